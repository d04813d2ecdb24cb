"""How far Mitsuba 3's `envmap` interpolation is from bilinear, on an RGB lat-long map.

Mitsuba's spectral `envmap` stores per texel the sRGB model's coefficients of c / (2 max c) and
the scale f = 2 max c, and between texels multiplies the bilinear mean of the model's spectra by
the bilinear mean of f. In RGB that is (sum w c/f)(sum w f) instead of sum w c (the model's RGB
is linear in its spectrum). This script evaluates both at random directions of the upper
hemisphere and reports, over 16 x 8 regions of (u, v), the CIEDE2000 between their means and
the ratio of their total luminance. specmap_envmap interpolates bilinearly, so this is the part
of its difference from `envmap` that is envmap's.

    .venv/bin/python tools/mitsuba_interpolation.py envmaps/forest.exr --downscale 8 [--smooth]
"""
import argparse

import colour
import numpy as np
import OpenEXR


def read_rgb(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        return np.stack([ch[c].pixels for c in "RGB"], -1).astype(np.float64)


def downscale(rgb, k):
    h, w, _ = rgb.shape
    return rgb.reshape(h // k, k, w // k, k, 3).mean((1, 3))


def upsample2(rgb):
    """x2 bilinear between texel centres, as tests/interop/test_mitsuba.py smooths its maps."""
    h, w, _ = rgb.shape
    xs = (np.arange(2 * w) + 0.5) / 2 - 0.5
    ys = np.clip((np.arange(2 * h) + 0.5) / 2 - 0.5, 0, h - 1)
    x0, y0 = np.floor(xs).astype(int), np.minimum(np.floor(ys).astype(int), h - 2)
    fx, fy = (xs - x0)[None, :, None], (ys - y0)[:, None, None]
    rows = rgb[:, x0 % w] * (1 - fx) + rgb[:, (x0 + 1) % w] * fx
    return rows[y0] * (1 - fy) + rows[y0 + 1] * fy


def corners(rgb, u, v):
    """envmap's texel lookup: u texel-centred and periodic, v = y / (h - 1)."""
    h, w, _ = rgb.shape
    xf = u * w - 0.5
    x0 = np.floor(xf)
    fx = xf - x0
    x0 = x0.astype(int) % w
    yf = v * (h - 1)
    y0 = np.minimum(np.floor(yf), h - 2)
    fy = yf - y0
    y0 = y0.astype(int)
    return [(y0, x0, (1 - fx) * (1 - fy)), (y0, (x0 + 1) % w, fx * (1 - fy)),
            (y0 + 1, x0, (1 - fx) * fy), (y0 + 1, (x0 + 1) % w, fx * fy)]


def compare(rgb, n=400000, seed=0):
    rgb = np.maximum(rgb, 0.0)  # the model's coefficients stand for reflectances in [0, 1]
    rng = np.random.default_rng(seed)
    u, v = rng.random(n), rng.random(n) * 0.5
    c = corners(rgb, u, v)
    f = 2 * np.maximum(rgb.max(-1), 1e-8)
    bilinear = sum(w[:, None] * rgb[y, x] for y, x, w in c)
    shape = sum(w[:, None] * rgb[y, x] / f[y, x, None] for y, x, w in c)
    envmap = shape * sum(w * f[y, x] for y, x, w in c)[:, None]
    region = (np.floor(u * 16) + 16 * np.floor(v * 16)).astype(int)
    b = np.array([bilinear[region == k].mean(0) for k in range(128)])
    e = np.array([envmap[region == k].mean(0) for k in range(128)])
    lum = np.array([0.2126, 0.7152, 0.0722])
    white = (b @ lum).max()
    lab = [colour.XYZ_to_Lab(colour.RGB_to_XYZ(x / white, "sRGB")) for x in (b, e)]
    de = colour.delta_E(*lab, method="CIE 2000")
    return de.mean(), de.max(), (e @ lum).sum() / (b @ lum).sum()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("map")
    ap.add_argument("--downscale", type=int, default=1)
    ap.add_argument("--smooth", action="store_true", help="x2 bilinear upsampling first")
    a = ap.parse_args()
    rgb = downscale(read_rgb(a.map), a.downscale)
    if a.smooth:
        rgb = upsample2(rgb)
    mean, worst, ratio = compare(rgb)
    print(f"{a.map} {rgb.shape[1]}x{rgb.shape[0]}: CIEDE2000 envmap vs bilinear over 128 "
          f"regions of the upper hemisphere: mean {mean:.3f}, max {worst:.3f}; "
          f"luminance ratio {ratio:.4f}")


if __name__ == "__main__":
    main()
