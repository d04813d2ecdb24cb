#!/usr/bin/env python3
"""Conversion speed and memory, specmap against the same conversion in Python, in one run.

    .venv/bin/python tools/bench_convert.py [--sizes]

1. Throughput on envmaps/sunrise.exr and forest.exr (1024x512): `specmap convert` (release build,
   exact mode, D65, 380:780:5 = 81 bands + RGB + sun mask, half, ZIP, sun off so both do the same
   work; the flags decide every light, so specmap analyses no scene) against numpy +
   colour-science + OpenEXR doing the same: read, clamp, fit the exact-mode matrix, expand every
   pixel to 81 bands, write half/ZIP. The two outputs are checked to hold the same channels and
   values. Wall-clock seconds, best of 3; specmap on all cores and on one (--threads 1), with
   the stages its report times.
2. The compressions, on sunrise: ZIP, ZIPS, PIZ and none, specmap (all cores and one) and
   OpenEXR's Python binding writing the same spectra: seconds (best of 3) and file size.
3. The default conversion (the scene analysed), all cores and one.
4. With --sizes: sunrise upsampled to 2048x1024, 4096x2048 and 8192x4096 (half, ZIP), converted
   with ZIP and without compression under /usr/bin/time: wall time, peak resident memory,
   output size.
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


def specmap(src, dst, *extra, threads=None, args=ARGS):
    """Runs specmap convert on `threads` threads (None: all cores); its report, from --json."""
    t = ["--threads", str(threads)] if threads else []
    p = subprocess.run([BIN, "convert", src, "-o", dst, *args, *t, *extra, "--json"], check=True,
                       capture_output=True, text=True)
    return json.loads(p.stdout)


def stages(r):
    """Where the time went, from specmap's report: its stages' wall-clock seconds."""
    return (f"read {r['seconds_read']:.2f}, analyse {r['seconds_analyse']:.2f}, plan "
            f"{r['seconds_plan']:.2f}, write {r['seconds_convert']:.2f} (encoding "
            f"{r['seconds_encode']:.2f})")


def timed(cmd):
    """Runs cmd under /usr/bin/time: (wall seconds, peak resident MiB)."""
    p = subprocess.run(["/usr/bin/time", "-f", "%e %M", *map(str, cmd)], capture_output=True,
                       text=True, check=True)
    wall, rss = p.stderr.strip().splitlines()[-1].split()
    return float(wall), int(rss) / 1024


def throughput(tmp, cores):
    """The issue's conversion (exact, D65, sun off, half, ZIP) of the two sample maps: specmap on
    every core and on one, against the Python pipeline timed in the same run."""
    mpix = 1024 * 512 / 1e6
    print(f"| input, ZIP | specmap, {cores} threads | specmap, 1 thread | {cores} threads / 1 "
          "| Python (numpy + colour-science + OpenEXR) | specmap / Python | specmap's stages, "
          f"{cores} threads (s) |")
    print("|---|---:|---:|---:|---:|---:|---|")
    for name in ("sunrise", "forest"):
        src = ROOT / "envmaps" / f"{name}.exr"
        ours, report = best_of(3, lambda: specmap(src, tmp / "ours.exr"))
        ours_cpu = CPU_USED
        size = (tmp / "ours.exr").stat().st_size
        one, _ = best_of(3, lambda: specmap(src, tmp / "one.exr", threads=1))
        theirs, write = best_of(3, lambda: python_convert(src, tmp / "theirs.exr"))
        their_cpu = CPU_USED
        same_output(tmp / "ours.exr", tmp / "theirs.exr")
        print(f"| {name}.exr 1024x512 | {ours:.2f} s ({mpix / ours:.2f} Mpix/s; "
              f"{size / 1e6:.1f} MB; CPU {ours_cpu:.2f} s) | {one:.2f} s | {one / ours:.2f}x "
              f"| {theirs:.2f} s (OpenEXR write {write / theirs:.0%}; CPU {their_cpu:.2f} s) "
              f"| {theirs / ours:.1f}x | {stages(report)} |")


def compressions(tmp, cores):
    """Each compression of sunrise's conversion: specmap on every core and on one, and OpenEXR's
    Python binding writing the same spectra."""
    mpix = 1024 * 512 / 1e6
    print(f"\n| sunrise.exr | specmap, {cores} threads | specmap, 1 thread | {cores} threads / 1 "
          "| Python conversion (its OpenEXR write alone) | specmap / Python | specmap's stages, "
          f"{cores} threads (s) |")
    print("|---|---:|---:|---:|---:|---:|---|")
    src = ROOT / "envmaps" / "sunrise.exr"
    for c in COMPRESSIONS:
        ours, report = best_of(3, lambda: specmap(src, tmp / "ours.exr", "--compression", c))
        ours_cpu = CPU_USED
        size = (tmp / "ours.exr").stat().st_size
        one, _ = best_of(3, lambda: specmap(src, tmp / "one.exr", "--compression", c, threads=1))
        theirs, write = best_of(3, lambda: python_convert(src, tmp / "theirs.exr", c))
        same_output(tmp / "ours.exr", tmp / "theirs.exr")
        print(f"| {c.upper()}, {size / 1e6:.1f} MB | {ours:.2f} s ({mpix / ours:.2f} Mpix/s; CPU "
              f"{ours_cpu:.2f} s) | {one:.2f} s | {one / ours:.2f}x | {theirs:.2f} s "
              f"({write:.2f} s) | {theirs / ours:.1f}x | {stages(report)} |")


def default_flags(tmp, cores):
    """The default conversion (faithful, every light found, sun found): the scene analysed."""
    src = ROOT / "envmaps" / "sunrise.exr"
    ours, report = best_of(3, lambda: specmap(src, tmp / "ours.exr", args=["--quiet"]))
    one, _ = best_of(3, lambda: specmap(src, tmp / "one.exr", threads=1, args=["--quiet"]))
    print(f"\nDefault flags, sunrise.exr: {ours:.2f} s on {cores} threads, {one:.2f} s on 1 "
          f"({one / ours:.2f}x); stages on {cores}: {stages(report)}")


def sizes(tmp, cores):
    """Sunrise upsampled 1x, 2x, 4x and 8x (to 8192x4096, 33.5 Mpixel; half, ZIP): wall time and
    peak memory (/usr/bin/time), output size, for ZIP and no compression."""
    with OpenEXR.File(str(ROOT / "envmaps" / "sunrise.exr"), separate_channels=True) as f:
        ch = {c: v.pixels.astype(np.float32) for c, v in f.channels().items() if c in "RGB"}
    print(f"\n| size, {cores} threads | compression | wall | Mpix/s | peak memory | output "
          "| specmap's stages (s) |")
    print("|---|---|---:|---:|---:|---:|---|")
    for k in (1, 2, 4, 8):
        big = {c: np.kron(v, np.ones((k, k), np.float32)).astype(np.float16)
               for c, v in ch.items()}
        src = tmp / f"sunrise{k}x.exr"
        with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION,
                           "type": OpenEXR.scanlineimage}, big) as f:
            f.write(str(src))
        del big
        w, h = 1024 * k, 512 * k
        for c in ("zip", "none"):
            out = tmp / "big.spectral.exr"
            wall, rss = timed([BIN, "convert", src, "-o", out, *ARGS, "--compression", c])
            size = out.stat().st_size
            report = specmap(src, out, "--compression", c) if k < 8 else None
            out.unlink()
            print(f"| {w}x{h} | {c.upper()} | {wall:.2f} s | {w * h / 1e6 / wall:.2f} "
                  f"| {rss:.0f} MiB | {size / 1e9:.2f} GB "
                  f"| {stages(report) if report else 'one run (see wall)'} |")
        src.unlink()


def main():
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=ROOT, check=True)
    cores = os.cpu_count()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        throughput(tmp, cores)
        compressions(tmp, cores)
        default_flags(tmp, cores)
        if "--sizes" in sys.argv:
            sizes(tmp, cores)


if __name__ == "__main__":
    main()
