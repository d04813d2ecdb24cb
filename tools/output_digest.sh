#!/usr/bin/env bash
# Converts the sample maps under a set of options, and renders the presets on the CPU (alone, under
# an RGB map and under a spectral map), and prints, per case, SHA-256 digests of the file
# written, decoded by OpenEXR's own library (its header's attributes, sorted, and its
# channels' pixels: the file's bytes differ from run to run, as the attributes' order does), and
# of a conversion's --json report without timings (floats to 9 digits: sums over pixels vary in
# their last bits with how the threads split the work). Run it before and after a refactor and
# diff the two outputs to show that every output is unchanged, bit for bit.
#   bash tools/output_digest.sh [SPECMAP_BINARY] > digest.txt
# PYTHON: an interpreter with the OpenEXR and numpy packages (default: the test suite's .venv).
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-target/release/specmap}"
python="${PYTHON:-.venv/bin/python}"
maps="${MAPS:-envmaps}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
# The header's attributes (sorted) and the channels' pixels of an OpenEXR file.
exr_digest() {
  "$python" -c '
import OpenEXR, sys, hashlib, numpy as np
f = OpenEXR.File(sys.argv[1])
head, pix = hashlib.sha256(), hashlib.sha256()
for part in f.parts:
    for k in sorted(part.header):
        head.update(f"{k}={part.header[k]!r}".encode())
    for name in sorted(part.channels):
        pix.update(name.encode())
        pix.update(np.ascontiguousarray(part.channels[name].pixels).tobytes())
print("header", head.hexdigest()[:16], "pixels", pix.hexdigest()[:16])' "$1"
}
cases=(
  "default|"
  "exact|--mode exact"
  "paper-one|--mode paper --lights one --light D65"
  "nonneg|--mode nonneg --light A"
  "lamp-FL11|--light FL11 --white light"
  "one-light|--lights one"
  "global|--reflectors global --sky light"
  "sun-match|--sun-spd match"
  "basis|--format basis"
  "basis-exact|--format basis --mode exact"
  "float-piz|--precision float --compression piz"
  "cube|--out-layout cube --size 64"
  "tolerance|--tolerance 1"
  "space|--space acescg --range 400:700:10"
  "flags-exact|--mode exact --light D65 --sun off"
  "flags-one|--lights one --light A --sun off"
  "flags-none|--mode nonneg --light FL2 --sun off --compression none"
)
for map in sunrise forest; do
  for c in "${cases[@]}"; do
    name="${c%%|*}"; args="${c#*|}"
    file="$out/$map-$name.exr"
    # shellcheck disable=SC2086
    "$bin" convert "$maps/$map.exr" -o "$file" $args --json 2>/dev/null >"$out/report.json"
    report=$(python3 -c '
import json, sys
r = json.load(open(sys.argv[1]))
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items()
                if not (k.startswith("seconds") or k in ("megapixels_per_second", "output"))}
    if isinstance(v, list):
        return [strip(x) for x in v]
    # Sums over pixels are reduced by however rayon split the work: their last bits vary.
    if isinstance(v, float):
        return float(f"{v:.9g}")
    return v
print(json.dumps(strip(r), sort_keys=True))' "$out/report.json" | sha256sum | cut -c1-16)
    printf '%-10s %-12s %s report %s\n' "$map" "$name" "$(exr_digest "$file")" "$report"
  done
done
# The renders: every preset on the CPU at 96x96, alone, under the RGB sunrise and under its
# spectral conversion (the renderer's two environment paths).
"$bin" convert "$maps/sunrise.exr" -o "$out/sunrise.spectral.exr" --quiet
for scene in ball transparent-ball cylinders chart checker-spheres; do
  for env in none rgb spectral; do
    case $env in
      none) args=() ;;
      rgb) args=(--env "$maps/sunrise.exr") ;;
      spectral) args=(--env "$out/sunrise.spectral.exr") ;;
    esac
    file="$out/render-$scene-$env.exr"
    "$bin" render --scene "$scene" --backend cpu --size 96x96 "${args[@]}" -o "$file" \
      >/dev/null 2>&1
    printf '%-16s %-9s %s\n' "$scene" "$env" "$(exr_digest "$file")"
  done
done
