#!/usr/bin/env python3
"""Colour rendition of `specmap convert` against the ground-truth scenes, as a markdown table.

    cargo build && python3 tools/rendition_table.py [SCENE-SUBSTRING...] [--config NAME=FLAGS]...

For each scene of tests/data/truth/manifest.json and each configuration: `specmap convert
<scene>.rgb.exr -o X.exr <flags> --quiet --json`, then `specmap rendition <scene>.spectral.exr
X.exr --json`. `--config NAME=FLAGS` adds (or replaces) a column (NAME without `=`); `--only
NAME,...` (or NAME;NAME;... when a name holds a comma) keeps only those columns. Each cell: mean / max rendition CIEDE2000 / mean white CIEDE2000 (over the normals
up, +x, -x, +z, -z). `{light}` in a configuration's flags is the scene's right light (D65 for the
skies, FL2, FL11, hps). The binary: $SPECMAP_BIN, else $CARGO_TARGET_DIR/debug/specmap, else
target/debug/specmap. Only the standard library is needed.
"""
import json
import os
import pathlib
import shlex
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = pathlib.Path(__file__).resolve().parent.parent
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
BIN = os.environ.get("SPECMAP_BIN", str(TARGET / "debug" / "specmap"))
TRUTH = ROOT / "tests" / "data" / "truth"

RIGHT = {"interior_fl2": "FL2", "interior_fl11": "FL11", "street_hps": "hps",
         # The scenes of several lights: the light of the most energy (the tubes, the sodium
         # lamps, the bulbs as A), or daylight.
         "office_mixed": "FL11", "office_warm_tubes": "FL11", "street_mixed": "hps", "room_incandescent_dusk": "A",
         "yard_overcast": "D65",
         # Issue 41's scenes: the catalogue's nearest to the softboxes' phosphor-led (6814 K) is
         # LED-B5 (6598 K); tungsten is A; a xenon flash and the living room's window are
         # daylight; the dusk street's light is mostly sodium.
         "studio_led": "LED-B5", "studio_tungsten": "A", "studio_flash": "D65",
         "room_window_lamps": "D65", "street_dusk": "hps"}
# paper/exact/nonneg keep the paper's sun (D65), sky (the light's basis) and, with a named light,
# its white premise (RGB (1,1,1) is the main light), so these are the methods as they were.
CONFIGS = [
    ("paper's method, right light", "--mode paper --light {light}"),
    ("exact, D65 carrier", "--mode exact --light D65"),
    ("one light, right light", "--lights one --light {light}"),
    ("one light, auto", "--lights one"),
    ("default", ""),
]


def run(args):
    p = subprocess.run([BIN, *args], capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"specmap {' '.join(args)}: {p.stderr}")
    return p.stdout


def measure(tmp, scene, label, flags):
    flags = shlex.split(flags.format(light=RIGHT.get(scene, "D65")))
    out = pathlib.Path(tmp) / f"{scene}-{abs(hash(label))}.exr"
    conv = json.loads(run(["convert", str(TRUTH / f"{scene}.rgb.exr"), "-o", str(out), *flags,
                           "--quiet", "--json"]))
    r = json.loads(run(["rendition", str(TRUTH / f"{scene}.spectral.exr"), str(out), "--json"]))
    out.unlink()
    sp = conv.get("spectra", {})
    return dict(mean=r["mean_de2000"], max=r["max_de2000"], white=r["white_mean_de2000"],
                white_max=r["white_max_de2000"], light=conv["light"],
                premise=conv.get("white", {}).get("premise", "light"),
                negative=sp.get("negative", 0), pixels=conv["output_size"][0] *
                conv["output_size"][1], roundtrip=conv["roundtrip"]["max_de2000"])


def main():
    args, configs = [], list(CONFIGS)
    argv = sys.argv[1:]
    while argv:
        a = argv.pop(0)
        if a == "--config":
            name, _, flags = argv.pop(0).partition("=")
            configs = [c for c in configs if c[0] != name] + [(name, flags)]
        elif a == "--only":
            keep = argv.pop(0).split(";") if ";" in argv[0] else argv.pop(0).split(",")
            configs = [c for c in configs if c[0] in keep]
        else:
            args.append(a)
    scenes = [s["name"] for s in json.loads((TRUTH / "manifest.json").read_text())["scenes"]]
    if args:
        scenes = [s for s in scenes if any(a in s for a in args)]
    jobs = [(s, label, flags) for s in scenes for label, flags in configs]
    with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(2) as pool:
        results = dict(zip([(s, l) for s, l, _ in jobs],
                           pool.map(lambda j: measure(tmp, *j), jobs)))
    for (s, l), v in results.items():
        print(f"{s:14s} {l:22s} {v['mean']:.3f} {v['max']:.3f} {v['white']:.3f} "
              f"{v['light']}/{v['premise']} negative {v['negative']}/{v['pixels']} "
              f"roundtrip max {v['roundtrip']:.2e}", file=sys.stderr)
    labels = [c[0] for c in configs]
    print("| scene | " + " | ".join(labels) + " |")
    print("|---|" + "---:|" * len(labels))
    cell = lambda v: "%.2f / %.2f / %.2f" % (v["mean"], v["max"], v["white"])
    skies = [s for s in scenes if s.startswith("sky_")]
    for scene in scenes:
        print(f"| {scene} | " + " | ".join(cell(results[(scene, l)]) for l in labels) + " |")
    if len(skies) > 1:
        def agg(l, key, f):
            return f(results[(s, l)][key] for s in skies)
        print(f"| {len(skies)} skies: mean of means / worst max / worst white | " + " | ".join(
            "%.2f / %.2f / %.2f" % (agg(l, "mean", lambda v: sum(v) / len(skies)),
                                    agg(l, "max", max), agg(l, "white", max))
            for l in labels) + " |")
        print(f"| {len(skies)} skies: worst mean | " + " | ".join(
            "%.2f" % agg(l, "mean", max) for l in labels) + " |")
    print("\nFlags: " + "; ".join(f"{l}: `{f or '(none)'}`" for l, f in configs))


if __name__ == "__main__":
    main()
