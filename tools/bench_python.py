#!/usr/bin/env python3
"""The Python package's speed against the pure-Python tools it replaces, as markdown table rows.

    cargo build --release -p specmap-python
    mkdir -p /tmp/bench_py/specmap && cp python/specmap/*.py /tmp/bench_py/specmap/
    cp target/release/lib_specmap.so /tmp/bench_py/specmap/_specmap.abi3.so
    PYTHONPATH=/tmp/bench_py .venv/bin/python tools/bench_python.py [--only thinfilm|upsample]

Use a release build: the dev profile of `python/dev.sh` is many times slower.

- thinfilm: `specmap.thinfilm` on 10^5 (thickness scale, angle) pairs x 81 wavelengths, one
  call, against tmm 0.2.0's `unpolarized_RT` called in a Python loop. tmm is timed on a random
  subset of the pairs (--tmm-pairs, 2000 by default) at all 81 wavelengths and its time
  extrapolated linearly to the whole grid (tmm's cost per call does not depend on the values);
  the subset's R and T are also checked against specmap's (printed on stderr).
- upsample: `specmap.upsample` of envmaps/sunrise.exr's pixels (1024x512, light="auto": the
  converter's scene analysis and spectra, in memory) against the release CLI converting the file
  (`--compression none`, end to end, and its report's read + spectra seconds), and the same
  array under D65 alone; colour-science's Mallett (2019) recovery (a product with its reflectance
  basis) on the same array as a speed reference, not a like-for-like result.
"""

import argparse
import os
import sys
import time

import numpy as np


def best_of(runs, f):
    """The shortest wall time of `runs` calls of f (after one warm-up call), and f's result."""
    out = f()
    best = float("inf")
    for _ in range(runs):
        start = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - start)
    return best, out


def bench_thinfilm(args):
    import specmap
    import tmm

    # Two layers on glass (MgF2 95 nm over TiO2 130 nm), unpolarised: a designer dragging the
    # coating's thickness (0.5x to 2x, 1000 steps) at 100 angles (0 to 79.2 degrees).
    layers = [(1.38, 95.0), (2.3, 130.0)]
    substrate = 1.52
    wavelengths = np.arange(380.0, 781.0, 5.0)
    scales = np.linspace(0.5, 2.0, 1000)
    angles = np.linspace(0.0, 79.2, 100)
    pairs = len(scales) * len(angles)
    assert len(wavelengths) == 81 and pairs == 100_000

    seconds, (R, T) = best_of(args.runs, lambda: specmap.thinfilm(
        layers, substrate, wavelengths, angles_deg=angles, thickness_scale=scales, pol="u"))
    assert R.shape == (len(scales), len(angles), len(wavelengths))

    rng = np.random.default_rng(1)
    picks = rng.choice(pairs, size=args.tmm_pairs, replace=False)
    worst = 0.0
    start = time.perf_counter()
    for p in picks:
        i, j = divmod(int(p), len(angles))
        d_list = [np.inf] + [d * scales[i] for _, d in layers] + [np.inf]
        n_list = [1.0] + [n for n, _ in layers] + [substrate]
        th0 = np.radians(angles[j])
        for k, lam in enumerate(wavelengths):
            ref = tmm.unpolarized_RT(n_list, d_list, th0, lam)
            worst = max(worst, abs(ref["R"] - R[i, j, k]), abs(ref["T"] - T[i, j, k]))
    sample = time.perf_counter() - start
    tmm_seconds = sample * pairs / args.tmm_pairs
    print(
        f"thinfilm: tmm took {sample:.1f} s for {args.tmm_pairs} random pairs x 81 wavelengths, "
        f"extrapolated x{pairs / args.tmm_pairs:g} to {tmm_seconds:.0f} s; largest |R - R_tmm|, "
        f"|T - T_tmm| there {worst:.1e}; {os.cpu_count()} CPUs",
        file=sys.stderr,
    )
    if worst > 1e-9:
        raise SystemExit(f"specmap and tmm disagree by {worst:.2e}")
    case = (
        "thinfilm: 2 layers, unpolarised, 10^5 (thickness, angle) pairs x 81 wavelengths "
        f"(tmm: {args.tmm_pairs} random pairs, extrapolated)"
    )
    return f"| {case} | {seconds:.3f} | {tmm_seconds:.0f} | {tmm_seconds / seconds:,.0f}x |"


def bench_upsample(args):
    """specmap.upsample of the 1024x512 sunrise map (light="auto": the converter's scene
    analysis and faithful spectra, in memory) against the CLI converting the same file, and
    colour-science's Mallett (2019) reflectance recovery on the same array as a speed reference
    only (a reflectance basis, no lights: not the same result)."""
    import json
    import subprocess
    import tempfile

    import OpenEXR
    import specmap
    from colour.recovery import MSDS_BASIS_FUNCTIONS_sRGB_MALLETT2019 as mallett

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    source = os.path.join(root, "envmaps", "sunrise.exr")
    cli = os.environ.get("SPECMAP_BIN", os.path.join(root, "target", "release", "specmap"))
    with OpenEXR.File(source, separate_channels=True) as f:
        channels = f.channels()
        rgb = np.stack([channels[c].pixels for c in "RGB"], -1).astype(np.float32)
    assert rgb.shape == (512, 1024, 3)

    # numpy first: rayon's threads spin for a while after specmap's calls, and would slow it.
    basis = mallett.values.T.astype(np.float32)
    mallett_seconds, _ = best_of(args.runs, lambda: rgb.reshape(-1, 3) @ basis)
    seconds, (wavelengths, spectra) = best_of(args.runs, lambda: specmap.upsample(rgb))
    assert spectra.shape == (512, 1024, 81)
    colours, _ = best_of(args.runs, lambda: specmap.upsample(rgb, light="D65"))

    def convert():
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "s.exr")
            p = subprocess.run([cli, "convert", source, "-o", out, "--compression", "none",
                                "--quiet", "--json"], check=True, capture_output=True, text=True)
            return json.loads(p.stdout)

    cli_seconds, _ = best_of(args.runs, convert)
    in_memory, _ = best_of(args.runs, lambda: specmap.convert(source))
    print(
        f"upsample: CLI convert --compression none {cli_seconds:.3f} s end to end; "
        f"specmap.convert(path) in memory {in_memory:.3f} s; specmap.upsample {seconds:.3f} s; "
        f"under D65 without the scene analysis {colours:.3f} s; colour's Mallett (2019) basis "
        f"product on the same array {mallett_seconds:.3f} s; {os.cpu_count()} CPUs",
        file=sys.stderr,
    )
    rows = [
        ("upsample of the 1024x512 map's array (light auto) vs `specmap convert "
         "--compression none`, end to end", seconds, cli_seconds),
        ("convert(path) in memory vs the same CLI run", in_memory, cli_seconds),
        ("upsample of the same colours under D65 (no scene analysis) vs the same CLI run",
         colours, cli_seconds),
        ("upsample (light auto) vs colour's Mallett (2019) recovery on the same array (a "
         "reflectance basis product: a speed reference, not the same result)", seconds,
         mallett_seconds),
    ]
    return "\n".join(
        f"| {case} | {mine:.3f} | {ref:.3f} | {ref / mine:.2f}x |" for case, mine, ref in rows
    )


BENCHES = {"thinfilm": bench_thinfilm, "upsample": bench_upsample}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--only", choices=sorted(BENCHES), help="run this benchmark only")
    parser.add_argument("--runs", type=int, default=3,
                        help="specmap's time is the best of this many runs (default 3)")
    parser.add_argument("--tmm-pairs", type=int, default=2000,
                        help="(thickness, angle) pairs tmm is timed on (default 2000)")
    args = parser.parse_args()
    names = [args.only] if args.only else list(BENCHES)
    print("| case | specmap (s) | reference (s) | speed-up |")
    print("|---|---:|---:|---:|")
    for name in names:
        try:
            print(BENCHES[name](args), flush=True)
        except NotImplementedError as e:
            if args.only:
                raise
            print(f"{name}: skipped, {e}", file=sys.stderr)


if __name__ == "__main__":
    main()
