#!/usr/bin/env python3
"""Conversion speed and memory, specmap against the same conversion in Python, in one run.

    .venv/bin/python tools/bench_convert.py [--big]

1. Throughput on envmaps/sunrise.exr and forest.exr (1024x512): `specmap convert` (release build,
   exact mode, D65, 380:780:5 = 81 bands + RGB, half, ZIP, sun off so both do the same work)
   against numpy + colour-science + OpenEXR doing the same: read, clamp, fit the exact-mode matrix,
   expand every pixel to 81 bands, write half/ZIP. Wall-clock seconds, best of 3.
2. With --big: an 8192x4096 input (sunrise upsampled 8x, half, ZIP) converted by specmap under
   /usr/bin/time: peak resident memory and throughput.
"""
import pathlib
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
import OpenEXR

import colour

ROOT = pathlib.Path(__file__).resolve().parent.parent
BIN = ROOT / "target" / "release" / "specmap"
SHAPE = colour.SpectralShape(380, 780, 5)
ARGS = ["--range", "380:780:5", "--precision", "half", "--compression", "zip", "--sun", "off",
        "--mode", "exact", "--light", "D65", "--quiet"]


def python_convert(src, dst):
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
    spectra = (rgb.reshape(-1, 3) @ w.T @ basis.T).astype(np.float16)
    h, wd = rgb.shape[:2]
    channels = {f"S0.{nm:.6f}".replace(".", ",", 1).replace("S0,", "S0.") + "nm":
                spectra[:, i].reshape(h, wd) for i, nm in enumerate(SHAPE.wavelengths)}
    for i, name in enumerate("RGB"):
        channels[name] = rgb[..., i].astype(np.float16)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as f:
        f.write(str(dst))


def best_of(n, f):
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=ROOT, check=True)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        print("| input | specmap | Python (numpy + colour-science + OpenEXR) | ratio |")
        print("|---|---:|---:|---:|")
        for name in ("sunrise", "forest"):
            src = ROOT / "envmaps" / f"{name}.exr"
            ours = best_of(3, lambda: subprocess.run(
                [BIN, "convert", src, "-o", tmp / "ours.exr", *ARGS], check=True))
            theirs = best_of(3, lambda: python_convert(src, tmp / "theirs.exr"))
            mpix = 1024 * 512 / 1e6
            print(f"| {name}.exr 1024x512 | {ours:.2f} s ({mpix / ours:.2f} Mpix/s) "
                  f"| {theirs:.2f} s ({mpix / theirs:.2f} Mpix/s) | {theirs / ours:.1f}x |")
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
