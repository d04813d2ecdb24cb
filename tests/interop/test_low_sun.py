"""A sun below 4000 K against Mitsuba 3's sunsky (Hosek and Wilkie 2013's solar radiance, variant
scalar_spectral): specmap gives a low sun the spectrum of direct sunlight through the atmosphere
(`specmap::illuminant::low_sun`: the ASTM G173-03 extraterrestrial spectrum times Rayleigh,
aerosol and ozone transmittances at the air mass whose colour has the sun's CCT), where it gave a
black body before. This checks that the ColorChecker lit by specmap's low sun looks more like the
chart lit by Mitsuba's sun than under a black body of the same CCT does.

Each case is a clear sky made as tools/make_truth.py makes its `sky_*` scenes (128 x 64, the sun's
disk averaged into one pixel, a ColorChecker ground), written as an RGB map and converted by
`specmap convert --sun-spd match` (the sun pixel takes `natural(CCT)`, the low sun below 4000 K,
at the CCT specmap measures on the sun's pixel) over 380-720 nm: Mitsuba's spectral sunsky data
stop at 720 nm (NaN at exactly 720). The chart (Ohta's ColorChecker, 24 patches) is lit by
Mitsuba's sun, by the spectrum of specmap's sun pixel and by a Planckian radiator at the CCT
specmap reports, each chromatically adapted to D65 by CAT02 (von Kries) and compared with
CIEDE2000; the mean over the 24 patches is the score. The default conversion (the sun's own
colour: CIE daylight where it reaches, else the low sun modulated to the colour) is printed too.

    .venv/bin/python -m pytest tests/interop/test_low_sun.py -s    # prints the table
"""
import json
import math
import subprocess
import sys

import numpy as np
import OpenEXR
import pytest

import colour

from conftest import BIN, ROOT

sys.path.insert(0, str(ROOT / "tools"))
mi = pytest.importorskip("mitsuba")
import drjit as dr  # noqa: E402

import make_truth as mt  # noqa: E402

# Elevations (degrees) and turbidities where Mitsuba's sun is below 4000 K (1893-3499 K).
CASES = [(e, t) for t in (2, 4, 6) for e in (1, 3, 5, 7, 10)]
# The mean CIEDE2000 that specmap's low sun must stay under, for every case. Measured: 0.14-0.66,
# mean 0.35 (a Planckian of the same CCT: 0.42-1.32, mean 0.66); the worst is the reddest sun
# (1 degree, turbidity 2), and 1.0 is 1.5 x that: room for the CCT specmap measures on the pixel
# (the disk plus a little sky, within 15 K of the disk's own here), yet under the Planckian's
# worst.
MAX_MEAN_DE = 1.0

CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
D65_XY = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]


def mitsuba_sun(elevation_deg, turbidity, wl):
    """Mitsuba's sun alone (sky_scale = 0), its radiance averaged over the disk as make_truth
    does: rings of 6k directions at k/4 of the radius around the centre."""
    el, az = math.radians(elevation_deg), math.radians(mt.SUN_AZIMUTH_DEG)
    sun = np.array([math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el)])
    emitter = mi.load_dict({"type": "sunsky", "sun_direction": mt.to_mitsuba(sun),
                            "turbidity": float(turbidity), "sun_aperture": mt.SUN_APERTURE_DEG,
                            "sky_scale": 0.0})
    wl_eval = np.minimum(wl, mt.MITSUBA_MAX_NM - 1e-3)  # NaN at exactly 720 nm
    samples, weights = mt.sun_disk(sun)
    total = np.zeros(len(wl))
    si = dr.zeros(mi.SurfaceInteraction3f)
    for w, d in zip(weights, samples):
        si.wi = -mi.Vector3f(mt.to_mitsuba(d))
        for i in range(0, len(wl), 4):
            q = list(wl_eval[i:i + 4])
            n = len(q)
            si.wavelengths = mi.Spectrum(q + [q[-1]] * (4 - n))
            v = emitter.eval(si)
            total[i:i + n] += w * np.array([float(v[k]) for k in range(n)])
    assert (total > 0).all(), "the sun disk was missed"
    return total


def chart_lab(e, wl, rho, cmfs):
    """The chart under the light `e`: XYZ relative to the light's white (Y = 1), CAT02 to D65,
    CIELAB."""
    white = e @ cmfs / (e @ cmfs[:, 1])
    xyz = (rho * e) @ cmfs / (e @ cmfs[:, 1])
    adapted = colour.chromatic_adaptation(xyz, white, colour.xy_to_XYZ(D65_XY),
                                          method="Von Kries", transform="CAT02")
    return colour.XYZ_to_Lab(adapted, D65_XY)


def cct_of(e, cmfs):
    uv = colour.xy_to_UCS_uv(colour.XYZ_to_xy(e @ cmfs))
    return colour.temperature.uv_to_CCT_Ohno2013(uv)


def sun_pixel_spectrum(path, sx, sy, wl):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = dict(f.channels())
    return np.array([float(ch[mt.channel_name(nm)].pixels[sy, sx]) for nm in wl])


def convert(src, out, *args):
    p = subprocess.run([BIN, "convert", str(src), "-o", str(out), "--range", "380:720:5",
                        "--precision", "float", "--quiet", "--json", *args],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


@pytest.fixture(scope="module")
def comparison(tmp_path_factory):
    mi.set_variant("scalar_spectral")
    tmp = tmp_path_factory.mktemp("low_sun")
    wl = mt.grid(mt.MITSUBA_MAX_NM)
    cmfs = CMFS.copy().align(colour.SpectralShape(wl[0], wl[-1], mt.STEP)).values
    rho = np.array([mt.patch(i, wl) for i in range(24)])
    rows = []
    for e, t in CASES:
        _, radiance, params = mt.sky_scene(mi, dr, e, t)
        sx, sy = params["sun_pixel"]
        rgb = mt.rgb_of(radiance, wl).astype(np.float32)
        src = tmp / f"sky_e{e:02d}_t{t}.rgb.exr"
        mt.write_exr(src, {c: np.ascontiguousarray(rgb[..., i]) for i, c in enumerate("RGB")},
                     {})
        match = convert(src, tmp / "match.exr", "--sun-spd", "match")
        default = convert(src, tmp / "default.exr")
        assert match["sun"]["found"], (e, t, match["sun"]["reason"])
        k = match["sun"]["cct_K"]
        ref = mitsuba_sun(e, t, wl)
        ours = sun_pixel_spectrum(tmp / "match.exr", sx, sy, wl)
        own = sun_pixel_spectrum(tmp / "default.exr", sx, sy, wl)
        planck = colour.colorimetry.planck_law(wl * 1e-9, k)
        lab_ref = chart_lab(ref, wl, rho, cmfs)
        score = {name: float(np.mean(colour.delta_E(lab_ref, chart_lab(s, wl, rho, cmfs),
                                                     method="CIE 2000")))
                 for name, s in (("low_sun", ours), ("planck", planck), ("default", own))}
        rows.append({"elevation": e, "turbidity": t, "mitsuba_cct": cct_of(ref, cmfs),
                     "specmap_cct": k, "label": match["sun_spd"], **score})
    print("\nelev  T  Mitsuba CCT, Duv   specmap CCT  label            "
          "mean dE00: low sun  Planckian  default")
    for r in rows:
        c, duv = r["mitsuba_cct"]
        print(f"{r['elevation']:4d}  {r['turbidity']}  {c:7.0f} K {duv:+.4f}  "
              f"{r['specmap_cct']:7.0f} K  {r['label']:<15}  {r['low_sun']:17.3f}  "
              f"{r['planck']:9.3f}  {r['default']:7.3f}")
    mean = {k: np.mean([r[k] for r in rows]) for k in ("low_sun", "planck", "default")}
    print(f"{'mean over the cases':>68}  {mean['low_sun']:.3f}  {mean['planck']:9.3f}  "
          f"{mean['default']:7.3f}")
    return rows


def test_mitsuba_suns_are_below_4000_k_and_specmap_names_its_low_sun(comparison):
    for r in comparison:
        assert r["mitsuba_cct"][0] < 4000 and r["specmap_cct"] < 4000, r
        assert r["label"] == f"low sun {r['specmap_cct']:.0f} K", r
        # specmap measures the CCT on the sun's pixel (the disk plus a little sky): close to the
        # disk's own.
        assert abs(r["specmap_cct"] - r["mitsuba_cct"][0]) < 0.03 * r["mitsuba_cct"][0], r


def test_low_sun_renders_the_chart_closer_to_mitsuba_than_a_planckian(comparison):
    for r in comparison:
        assert r["low_sun"] < r["planck"], r
        assert r["low_sun"] < MAX_MEAN_DE, r
