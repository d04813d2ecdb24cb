#!/usr/bin/env python3
"""Thin-film speed, specmap against tmm, in one run.

    .venv/bin/python tools/bench_thinfilm.py

Runs `cargo bench --bench thinfilm` (unpolarised R and T, 401 wavelengths x 90 angles, 1 and 3
layers, f64 and f32) and times tmm's `unpolarized_RT` on the same stacks (401 wavelengths x 10 of
those angles: tmm is slow), then prints evaluations per second and the ratios as markdown.
"""
import re
import subprocess
import time

import numpy as np
import tmm

STACKS = {
    "1 layer": ([1.0, 2.7, 1.45], [np.inf, 270.0, np.inf]),
    "3 layers": ([1.0, 1.38, 2.1, 1.46, 1.45], [np.inf, 95.0, 130.0, 80.0, np.inf]),
}


def specmap_rates():
    out = subprocess.run(
        ["cargo", "bench", "--bench", "thinfilm", "--", "--warm-up-time", "1",
         "--measurement-time", "4"],
        capture_output=True, text=True, check=True,
    ).stdout
    rates = {}
    name = None
    for line in out.splitlines():
        m = re.search(r"/(\d layers?, f\d\d)", line)
        if m:
            name = m.group(1)
        m = re.search(r"thrpt:\s+\[\S+ \S+ (\S+) (\S+)", line)
        if m and name:
            value, unit = float(m.group(1)), m.group(2)
            rates[name] = value * {"Kelem/s": 1e3, "Melem/s": 1e6, "Gelem/s": 1e9}[unit]
            name = None
    return rates


def tmm_rate(n_list, d_list):
    wavelengths = np.arange(380.0, 781.0, 1.0)
    angles = np.radians(np.arange(0, 90, 9))
    start = time.perf_counter()
    for lam in wavelengths:
        for th in angles:
            tmm.unpolarized_RT(n_list, d_list, th, lam)
    return len(wavelengths) * len(angles) / (time.perf_counter() - start)


def main():
    ours = specmap_rates()
    print("| stack | specmap f64 | specmap f32 | tmm 0.2.0 | f64 / tmm |")
    print("|---|---:|---:|---:|---:|")
    for name, (n, d) in STACKS.items():
        theirs = tmm_rate(n, d)
        f64, f32 = ours[f"{name}, f64"], ours[f"{name}, f32"]
        print(f"| {name} | {f64 / 1e6:.2f} M/s | {f32 / 1e6:.2f} M/s | {theirs / 1e3:.2f} k/s "
              f"| {f64 / theirs:.0f}x |")


if __name__ == "__main__":
    main()
