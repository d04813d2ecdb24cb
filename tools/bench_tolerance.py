#!/usr/bin/env python3
"""Whether `render --tolerance` pays for itself: end-to-end wall time of one process per run.

Per case (preset x light x backend, 512x512 by default):
  uniform  `render --tolerance 0.5 --quadrature uniform` (the path --tolerance replaces)
  cold     `render --tolerance 0.5`, its cache folder empty (the plan decides: fit or not)
  warm     `render --tolerance 0.5`, the cache holding the scene's fit (made once beforehand by
           `render --tolerance 0.5 --quadrature scene`, whose time is reported as "fit")
each run REPEATS times (the median is reported, min and max in the JSON). Then turntables:
`render --turntable 36 --tolerance 0.5` (cold) against 36 runs of `render --orbit YAW,0
--tolerance 0.5 --quadrature uniform`, one per frame.

    python3 tools/bench_tolerance.py [--quick] [--repeats 3] [--out docs/bench/tolerance.md]

Needs a release build (cargo build --release). The GPU backend is whatever wgpu finds (lavapipe
where there is no GPU: apt-get install mesa-vulkan-drivers).
"""
import argparse
import json
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
BIN = ROOT / "target" / "release" / "specmap"
SUNRISE = str(ROOT / "envmaps" / "sunrise.exr")
PRESETS = ["ball", "transparent-ball", "cylinders", "chart", "checker-spheres"]
LIGHTS = ["D65", "A", "FL11", "sunrise.exr"]
TOLERANCE = "0.5"


def light_args(light):
    return ["--env", SUNRISE] if light == "sunrise.exr" else ["--light", light]


def cases(quick):
    if quick:
        return [("ball", "D65"), ("cylinders", "FL11")]
    out = []
    for p in PRESETS:
        for l in LIGHTS:
            # The chart compares D65, A and low-pressure sodium itself; --env lights one row.
            if p == "chart" and l in ("A", "FL11"):
                continue
            out.append((p, l))
    return out


def run(args, cache, tmp):
    """One `specmap render ARGS --json` with its cache in `cache`: (seconds, report). The cache
    is set by SPECMAP_CACHE_DIR, not XDG_CACHE_HOME: Mesa keeps its compiled shaders there, and an
    empty one would add lavapipe's shader compilation (about 2 s) to every run."""
    cmd = [str(BIN), "render", *args, "-o", str(tmp / "out.png"), "--json"]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True,
                       env={**os.environ, "SPECMAP_CACHE_DIR": str(cache)})
    s = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    return s, json.loads(p.stdout)


def timed(args, cache_for, repeats, tmp):
    """`run` REPEATS times, each with the cache `cache_for()` gives: min, median, max, report."""
    times, report = [], None
    for _ in range(repeats):
        s, report = run(args, cache_for(), tmp)
        times.append(s)
    return {"min": min(times), "median": statistics.median(times), "max": max(times)}, report


def case_row(preset, light, backend, size, repeats, tmp, fills):
    base = ["--scene", preset, "--size", size, "--backend", backend, *light_args(light),
            "--tolerance", TOLERANCE]
    empty = lambda: pathlib.Path(tempfile.mkdtemp(dir=tmp))
    uniform, ur = timed([*base, "--quadrature", "uniform"], empty, repeats, tmp)
    cold, cr = timed(base, empty, repeats, tmp)
    # The fit does not depend on the backend: made once per scene and light.
    if (preset, light) not in fills:
        filled = empty()
        fills[(preset, light)] = (filled, *run([*base, "--quadrature", "scene"], filled, tmp))
    filled, fit_s, fr = fills[(preset, light)]
    warm, wr = timed(base, lambda: filled, repeats, tmp)
    return {
        "preset": preset, "light": light, "backend": ur["backend"], "size": size,
        "uniform_nodes": ur["wavelengths"], "fitted_nodes": fr["wavelengths"],
        "fitted_kind": fr["quadrature"]["kind"],
        "uniform_s": uniform, "cold_s": cold, "warm_s": warm, "fit_s": fit_s,
        "cold_source": cr["quadrature_plan"]["source"],
        "cold_nodes": cr["wavelengths"],
        "warm_source": wr["quadrature_plan"]["source"],
        "cold_ratio": cold["median"] / uniform["median"],
        "warm_speedup": uniform["median"] / warm["median"],
        "image_max": (wr["quadrature_choice"].get("image") or {}).get("max_de2000"),
    }


def turntable_row(preset, light, backend, size, frames, tmp):
    base = ["--scene", preset, "--size", size, "--backend", backend, *light_args(light),
            "--tolerance", TOLERANCE]
    cache = pathlib.Path(tempfile.mkdtemp(dir=tmp))
    t_seq, r = run([*base, "--turntable", str(frames)], cache, tmp)
    t_each = 0.0
    for k in range(frames):
        yaw = f"{360.0 * k / frames},0"
        s, _ = run([*base, "--quadrature", "uniform", "--orbit", yaw], cache, tmp)
        t_each += s
    return {
        "preset": preset, "light": light, "backend": r["backend"], "size": size,
        "frames": frames, "turntable_s": t_seq, "uniform_renders_s": t_each,
        "speedup": t_each / t_seq, "nodes": r["wavelengths"],
        "source": r["quadrature_plan"]["source"],
        "fit_budget_s": r["quadrature_plan"]["fit_budget_s"],
    }


def markdown(rows, turns, machine):
    out = [f"Machine: {machine}. One process per run, wall time, median of the repeats.", "",
           "| case | backend | uniform (nodes) | cold: plan, nodes | cold / uniform | fitted "
           "nodes (fit s) | warm | uniform / warm | image max dE |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(
            f"| {r['preset']} under {r['light']} | {r['backend']} | {r['uniform_s']['median']:.2f} s "
            f"({r['uniform_nodes']}) | {r['cold_s']['median']:.2f} s: {r['cold_source']}, "
            f"{r['cold_nodes']} | {r['cold_ratio']:.2f}x | {r['fitted_nodes']} ({r['fit_s']:.1f}) | "
            f"{r['warm_s']['median']:.2f} s | {r['warm_speedup']:.1f}x | "
            + (f"{r['image_max']:.3f}" if r["image_max"] is not None else "-") + " |")
    if turns:
        out += ["", "| turntable | backend | frames | one run (nodes, plan) | separate uniform "
                "renders | speed-up |", "|---|---|---|---|---|---|"]
        for t in turns:
            out.append(
                f"| {t['preset']} under {t['light']} | {t['backend']} | {t['frames']} | "
                f"{t['turntable_s']:.1f} s ({t['nodes']}, {t['source']}) | "
                f"{t['uniform_renders_s']:.1f} s | {t['speedup']:.1f}x |")
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="two cases, one repeat, 8 frames")
    ap.add_argument("--backends", default="cpu,gpu")
    ap.add_argument("--size", default="512x512")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--frames", type=int, default=36)
    ap.add_argument("--turntables", default="ball:D65,cylinders:D65,checker-spheres:sunrise.exr")
    ap.add_argument("--cases", default=None, help="PRESET:LIGHT,... instead of every case")
    ap.add_argument("--out", default=None, help="markdown table (a .json beside it)")
    a = ap.parse_args()
    if not BIN.exists():
        sys.exit(f"{BIN} is missing: cargo build --release")
    repeats = 1 if a.quick else a.repeats
    frames = 8 if a.quick else a.frames
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="specmap-bench-tolerance-"))
    rows, turns, fills = [], [], {}
    try:
        for backend in a.backends.split(","):
            chosen = ([tuple(c.split(":")) for c in a.cases.split(",")] if a.cases
                      else cases(a.quick))
            for preset, light in chosen:
                r = case_row(preset, light, backend, a.size, repeats, tmp, fills)
                print(json.dumps(r), file=sys.stderr, flush=True)
                rows.append(r)
            for spec in a.turntables.split(",") if a.turntables else []:
                preset, light = spec.split(":")
                t = turntable_row(preset, light, backend, a.size, frames, tmp)
                print(json.dumps(t), file=sys.stderr, flush=True)
                turns.append(t)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    machine = subprocess.run(["nproc"], capture_output=True, text=True).stdout.strip() + " cores"
    table = markdown(rows, turns, machine)
    print(table)
    if a.out:
        out = pathlib.Path(a.out)
        out.write_text(table)
        out.with_suffix(".json").write_text(json.dumps({"cases": rows, "turntables": turns},
                                                       indent=1) + "\n")


if __name__ == "__main__":
    main()
