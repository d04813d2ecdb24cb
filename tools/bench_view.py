#!/usr/bin/env python3
"""Frames per second of `specmap view`: the scenes under envmaps/sunrise.exr, 81 uniform
wavelengths against the fitted set (--tolerance 0.5), on the GPU adapter (lavapipe where no GPU)
and on the CPU backend, at the sizes given. Each case replays a script in the window (under
the DISPLAY given, e.g. Xvfb) and reads the frame times `--json` reports: the fitted case waits
for the fit, then renders FRAMES frames on its nodes; the fit's time is reported beside.

    python3 tools/bench_view.py [--sizes 512x512,1024x1024] [--frames 10] [--out docs/bench/view.md]

Needs a release build (cargo build --release) and a display (DISPLAY=:99 with Xvfb :99).
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
BIN = ROOT / "target" / "release" / "specmap"


def run_case(scene, size, backend, fitted, frames, tmp):
    steps = []
    if fitted:
        steps.append({"wait": "quadrature"})
    steps.append({"frames": frames})
    script = tmp / "steps.json"
    script.write_text(json.dumps(steps))
    cmd = [str(BIN), "view", "--scene", scene, "--env", str(ROOT / "envmaps" / "sunrise.exr"),
           "--size", size, "--backend", backend, "--script", str(script), "--json"]
    cmd += ["--tolerance", "0.5"] if fitted else ["--samples", "81"]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=1800)
    if out.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{out.stderr}")
    r = json.loads(out.stdout)
    last = r["frames"][-frames:]
    ms = statistics.median(f["ms"] for f in last)
    fit = r["fits"][-1] if r["fits"] else None
    return {
        "scene": scene, "size": size, "backend": r["backend"], "fitted": fitted,
        "nodes": last[-1]["nodes"], "median_ms": ms, "fps": 1000.0 / ms,
        "first_frame_ms": r["first_frame_ms"],
        "fit_s": fit["seconds"] if fit else None,
        "estimate": fit["estimate_de2000"] if fit else None,
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="512x512")
    ap.add_argument("--scenes", default="ball,cylinders,checker-spheres")
    ap.add_argument("--backends", default="gpu,cpu")
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    if not os.environ.get("DISPLAY"):
        sys.exit("no DISPLAY: start Xvfb (Xvfb :99 &) and set DISPLAY=:99")
    rows = []
    with tempfile.TemporaryDirectory() as t:
        tmp = pathlib.Path(t)
        for size in a.sizes.split(","):
            for backend in a.backends.split(","):
                for scene in a.scenes.split(","):
                    for fitted in (False, True):
                        r = run_case(scene, size, backend, fitted, a.frames, tmp)
                        print(json.dumps(r), file=sys.stderr, flush=True)
                        rows.append(r)
    lines = ["| scene | size | backend | wavelengths | frame (median ms) | frames/s | fit (s) | estimate |",
             "|---|---|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        kind = f"{r['nodes']} fitted" if r["fitted"] else f"{r['nodes']} uniform"
        fit = f"{r['fit_s']:.0f}" if r["fit_s"] is not None else ""
        est = f"{r['estimate']:.3f}" if r["estimate"] is not None else ""
        lines.append(f"| {r['scene']} | {r['size']} | {r['backend']} | {kind} | "
                     f"{r['median_ms']:.0f} | {r['fps']:.1f} | {fit} | {est} |")
    table = "\n".join(lines) + "\n"
    print(table)
    if a.out:
        pathlib.Path(a.out).write_text(table)
        (pathlib.Path(a.out).with_suffix(".json")).write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
