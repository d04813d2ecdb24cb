#!/usr/bin/env python3
"""Conversion speed and memory, specmap against the same conversion in Python, in one run.

    .venv/bin/python tools/bench_convert.py [--big]

1. Throughput on envmaps/sunrise.exr and forest.exr (1024x512): `specmap convert` (release build,
   exact mode, D65, 380:780:5 = 81 bands + RGB + sun mask, half, ZIP, sun off so both do the same
   work) against numpy + colour-science + OpenEXR doing the same: read, clamp, fit the exact-mode
   matrix, expand every pixel to 81 bands, write half/ZIP. The two outputs are checked to hold the
   same channels and values. Wall-clock seconds, best of 3; specmap on all cores and on one
   (RAYON_NUM_THREADS=1), and with --zip-level 1.
2. The compressions, on sunrise: ZIP, ZIPS, PIZ and none, specmap and OpenEXR's Python binding
   writing the same spectra: seconds (best of 3) and file size.
3. With --big: an 8192x4096 input (sunrise upsampled 8x, half, ZIP) converted by specmap under
   /usr/bin/time: peak resident memory and throughput.
"""
import json
import os
import pathlib
import re
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
import OpenEXR

import colour

ROOT = pathlib.Path(__file__).resolve().parent.parent
BIN = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "release" / "specmap"
SHAPE = colour.SpectralShape(380, 780, 5)
ARGS = ["--range", "380:780:5", "--precision", "half", "--sun", "off",
        "--mode", "exact", "--light", "D65", "--quiet"]


COMPRESSIONS = {"zip": OpenEXR.ZIP_COMPRESSION, "zips": OpenEXR.ZIPS_COMPRESSION,
                "piz": OpenEXR.PIZ_COMPRESSION, "none": OpenEXR.NO_COMPRESSION}


def python_convert(src, dst, compression="zip"):
    with OpenEXR.File(str(src), separate_channels=True) as f:
        ch = f.channels()
        rgb = np.stack([ch[c].pixels.astype(np.float32) for c in "RGB"], -1)
    rgb = np.nan_to_num(rgb, nan=0.0, posinf=0.0, neginf=0.0).clip(0, None)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE).values
    light = colour.SDS_ILLUMINANTS["D65"].copy().align(SHAPE).values
    checker = colour.SDS_COLOURCHECKERS["BabelColor Average"]
    mcc = np.stack([checker[p].copy().align(SHAPE).values for p in ("red", "green", "blue")], 1)
    cs = colour.RGB_COLOURSPACES["sRGB"]
    to_rgb = np.linalg.inv(colour.normalised_primary_matrix(cs.primaries, cs.whitepoint))
    y_norm = cmfs[:, 1].sum()
    light = light / (light @ cmfs[:, 1] / y_norm)          # Y(light) = 1
    basis = mcc * light[:, None]                           # 81 x 3
    c = to_rgb @ (cmfs.T @ basis / y_norm)                 # RGB of each basis spectrum
    t = to_rgb @ (cmfs.T @ light / y_norm)                 # RGB of the light
    w = np.linalg.inv(c) @ np.diag(t)                      # exact mode
    # One contiguous (bands, pixels) array: OpenEXR's binding wants each channel contiguous.
    spectra = (basis @ w @ rgb.reshape(-1, 3).T).astype(np.float16)
    h, wd = rgb.shape[:2]
    channels = {"S0." + f"{nm:.6f}".replace(".", ",") + "nm": spectra[i].reshape(h, wd)
                for i, nm in enumerate(SHAPE.wavelengths)}
    for i, name in enumerate("RGB"):
        channels[name] = np.ascontiguousarray(rgb[..., i]).astype(np.float16)
    channels["sun"] = np.zeros((h, wd), np.float16)        # specmap writes the (empty) sun mask
    header = {"compression": COMPRESSIONS[compression], "type": OpenEXR.scanlineimage}
    t0 = time.perf_counter()
    with OpenEXR.File(header, channels) as f:
        f.write(str(dst))
    return time.perf_counter() - t0


def same_output(ours, theirs):
    """Both conversions wrote the same channels and values (specmap may scale by 2^-EV)."""
    with OpenEXR.File(str(ours), separate_channels=True) as f:
        a = {c: v.pixels.astype(np.float32) for c, v in f.channels().items()}
        scale = 2.0 ** float(f.header().get("EV", 0.0))
    with OpenEXR.File(str(theirs), separate_channels=True) as f:
        b = {c: v.pixels.astype(np.float32) for c, v in f.channels().items()}
    assert sorted(a) == sorted(b), (sorted(set(a) ^ set(b)))
    for c in a:
        if c.startswith("S0."):
            x, y = a[c] * scale, b[c]
            assert np.allclose(x, y, rtol=2e-3, atol=1e-3 * y.max()), (c, np.abs(x - y).max())


def cpu_seconds():
    """CPU seconds (user + system) of this process and its finished children, all threads."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def best_of(n, f):
    """The fastest of n runs of f: (seconds, f's result in that run); CPU_USED holds that run's
    CPU seconds (which a machine shared with other work inflates far less than wall time)."""
    global CPU_USED
    runs = []
    for _ in range(n):
        t0, c0 = time.perf_counter(), cpu_seconds()
        r = f()
        runs.append((time.perf_counter() - t0, r, cpu_seconds() - c0))
    wall, r, CPU_USED = min(runs, key=lambda t: t[0])
    return wall, r


CPU_USED = 0.0


def specmap(src, dst, *extra, threads=None):
    """Runs specmap convert (its report, from --json)."""
    env = dict(os.environ, **({"RAYON_NUM_THREADS": str(threads)} if threads else {}))
    p = subprocess.run([BIN, "convert", src, "-o", dst, *ARGS, *extra, "--json"], check=True,
                       capture_output=True, text=True, env=env)
    return json.loads(p.stdout)


def main():
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=ROOT, check=True)
    cores = os.cpu_count()
    mpix = 1024 * 512 / 1e6
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        print(f"| input | specmap, {cores} threads | specmap, 1 thread | specmap, --zip-level 1 "
              "| Python (numpy + colour-science + OpenEXR) | ratio | ratio, 1 thread |")
        print("|---|---:|---:|---:|---:|---:|---:|")
        for name in ("sunrise", "forest"):
            src = ROOT / "envmaps" / f"{name}.exr"
            ours, _ = best_of(3, lambda: specmap(src, tmp / "ours.exr"))
            ours_cpu = CPU_USED
            size = (tmp / "ours.exr").stat().st_size
            one, _ = best_of(3, lambda: specmap(src, tmp / "one.exr", threads=1))
            fast, _ = best_of(3, lambda: specmap(src, tmp / "fast.exr", "--zip-level", "1"))
            fast_size = (tmp / "fast.exr").stat().st_size
            theirs, write = best_of(3, lambda: python_convert(src, tmp / "theirs.exr"))
            their_cpu = CPU_USED
            their_size = (tmp / "theirs.exr").stat().st_size
            same_output(tmp / "ours.exr", tmp / "theirs.exr")
            same_output(tmp / "fast.exr", tmp / "theirs.exr")
            print(f"| {name}.exr 1024x512 | {ours:.2f} s ({mpix / ours:.2f} Mpix/s; "
                  f"{size / 1e6:.1f} MB; CPU {ours_cpu:.2f} s) | {one:.2f} s "
                  f"| {fast:.2f} s ({fast_size / 1e6:.1f} MB) | {theirs:.2f} s ({mpix / theirs:.2f} "
                  f"Mpix/s; OpenEXR write {write / theirs:.0%}; {their_size / 1e6:.1f} MB; CPU "
                  f"{their_cpu:.2f} s) "
                  f"| {theirs / ours:.1f}x | {theirs / one:.1f}x |")
        print(f"\n| sunrise.exr, compression | specmap, {cores} threads | OpenEXR's Python binding "
              "(whole Python conversion; its write alone) | ratio |")
        print("|---|---:|---:|---:|")
        src = ROOT / "envmaps" / "sunrise.exr"
        for c in COMPRESSIONS:
            ours, _ = best_of(3, lambda: specmap(src, tmp / "ours.exr", "--compression", c))
            ours_cpu = CPU_USED
            size = (tmp / "ours.exr").stat().st_size
            theirs, write = best_of(3, lambda: python_convert(src, tmp / "theirs.exr", c))
            their_cpu = CPU_USED
            their_size = (tmp / "theirs.exr").stat().st_size
            same_output(tmp / "ours.exr", tmp / "theirs.exr")
            print(f"| {c.upper()} | {ours:.2f} s ({mpix / ours:.2f} Mpix/s; CPU {ours_cpu:.2f} s), "
                  f"{size / 1e6:.1f} MB | {theirs:.2f} s (write {write:.2f} s; CPU "
                  f"{their_cpu:.2f} s), {their_size / 1e6:.1f} MB | {theirs / ours:.1f}x |")
        if "--big" in sys.argv:
            with OpenEXR.File(str(ROOT / "envmaps" / "sunrise.exr"), separate_channels=True) as f:
                ch = f.channels()
                big = {c: np.kron(ch[c].pixels, np.ones((8, 8), np.float32)).astype(np.float16)
                       for c in "RGB"}
            src = tmp / "big.exr"
            with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION,
                               "type": OpenEXR.scanlineimage}, big) as f:
                f.write(str(src))
            del big
            p = subprocess.run(["/usr/bin/time", "-v", BIN, "convert", src, "-o", tmp / "big.spectral.exr",
                                *ARGS], capture_output=True, text=True, check=True)
            rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1))
            wall = re.search(r"Elapsed \(wall clock\) time.*: (\S+)", p.stderr).group(1)
            parts = [float(x) for x in wall.split(":")]
            secs = sum(v * 60 ** i for i, v in enumerate(reversed(parts)))
            size = (tmp / "big.spectral.exr").stat().st_size
            print(f"\n8192x4096 -> 81 bands half ZIP: peak RSS {rss / 1024:.0f} MiB, {secs:.1f} s "
                  f"({8192 * 4096 / 1e6 / secs:.2f} Mpix/s), output {size / 1e9:.2f} GB")


if __name__ == "__main__":
    main()
