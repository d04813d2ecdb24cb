"""`--tolerance` with uniform grids checked independently (`color --quadrature uniform`,
`convert`): the grid specmap chooses keeps every colour of the scene within the tolerance of a
1 nm Simpson reference, and every coarser candidate step does not. (The scene quadratures are
checked in test_quadrature.py.)

The reference side is numpy + colour-science: colour's datasets, its CMFs, its Sprague
interpolation for reflectances, linear interpolation for lights (the convention specmap follows,
as colour does for light sources), scipy's Simpson rule and colour's CIEDE2000.
"""
import numpy as np
import OpenEXR
import pytest
import scipy.integrate

import colour

CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
CHECKER = colour.SDS_COLOURCHECKERS["BabelColor Average"]
LIGHTS = {
    "D65": colour.SDS_ILLUMINANTS["D65"],
    "A": colour.SDS_ILLUMINANTS["A"],
    "FL2": colour.SDS_ILLUMINANTS["FL2"],
    "FL11": colour.SDS_ILLUMINANTS["FL11"],
    "LED-B3": colour.SDS_ILLUMINANTS["LED-B3"],
    "lps": colour.SDS_LIGHT_SOURCES["LPS"],
}
STEPS = [20, 10, 5, 4, 2, 1, 0.5]
TOL = 0.5


def sampled(step):
    """CMFs, light sampler and patch sampler on 380..780 at `step` nm."""
    wl = np.arange(380, 780 + step / 2, step, dtype=float)
    shape = colour.SpectralShape(380, 780, step)
    cmfs = CMFS.copy().align(shape)
    assert np.allclose(cmfs.wavelengths, wl)
    return wl, shape, cmfs.values


def reflectance_at(r, wl):
    """Sprague-interpolated at exactly `wl`: colour's align to a step that does not divide the
    table's own (10 nm to 4 nm) spreads the points over the table's range instead, so the
    reflectance is aligned to 1 nm (exact points) and read there."""
    fine = r.copy().align(colour.SpectralShape(380, 780, 1))
    return fine[wl]


def light_at(light, wl):
    return np.interp(wl, light.wavelengths, light.values)


def xyz(stimulus, cmfs, h, simpson):
    integrate = (lambda f: scipy.integrate.simpson(f, dx=h)) if simpson else (lambda f: f.sum() * h)
    return np.array([integrate(stimulus * cmfs[:, i]) for i in range(3)])


def max_error(light, reflectances, step):
    """Largest CIEDE2000 of the light and each reflectance under it, at `step` (Riemann) against
    1 nm Simpson; infinity when the grid misses the light."""
    worst = 0.0
    ref_wl, _, ref_cmfs = sampled(1)
    wl, _, cmfs = sampled(step)
    s_ref, s = light_at(light, ref_wl), light_at(light, wl)
    k_ref = 100 / xyz(s_ref, ref_cmfs, 1, True)[1]
    y = xyz(s, cmfs, step, False)[1]
    if y <= 0:
        return np.inf
    k = 100 / y
    white = k_ref * xyz(s_ref, ref_cmfs, 1, True)
    white_xy = colour.XYZ_to_xy(white / 100)
    for r in [None, *reflectances]:
        r_ref = 1 if r is None else reflectance_at(r, ref_wl)
        r_s = 1 if r is None else reflectance_at(r, wl)
        a = k_ref * xyz(s_ref * r_ref, ref_cmfs, 1, True)
        b = k * xyz(s * r_s, cmfs, step, False)
        lab_a = colour.XYZ_to_Lab(a / 100, white_xy)
        lab_b = colour.XYZ_to_Lab(b / 100, white_xy)
        worst = max(worst, float(colour.delta_E(lab_a, lab_b, method="CIE 2000")))
    return worst


def check_choice(step, light, reflectances):
    assert max_error(light, reflectances, step) <= TOL, f"chosen {step} nm exceeds {TOL}"
    for coarser in [s for s in STEPS if s > step]:
        assert max_error(light, reflectances, coarser) > TOL, f"{coarser} nm would do"


@pytest.mark.parametrize("name", list(LIGHTS))
def test_color_tolerance_of_a_light(specmap, name):
    out = specmap("color", name, "--tolerance", str(TOL), "--quadrature", "uniform")
    choice = out["grid_choice"]
    assert choice["met"] and choice["max_dE2000"] <= TOL
    assert out["range"] == choice["grid"]
    check_choice(choice["step_nm"], LIGHTS[name], [])


@pytest.mark.parametrize("name", ["D65", "FL2", "lps"])
def test_convert_tolerance_keeps_the_colorchecker_within_it(specmap, tmp_path, name):
    rng = np.random.default_rng(7)
    src, dst = tmp_path / "in.exr", tmp_path / "out.exr"
    rgb = rng.uniform(0.05, 2.0, (8, 16, 3)).astype(np.float32)
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                      {c: np.ascontiguousarray(rgb[..., i]) for i, c in enumerate("RGB")}) as f:
        f.write(str(src))
    out = specmap("convert", str(src), "-o", str(dst), "--light", name, "--sun", "off",
                  "--tolerance", str(TOL), "--quiet")
    choice = out["grid_choice"]
    step = choice["step_nm"]
    wl = np.array(out["wavelengths_nm"])
    assert np.allclose(np.diff(wl), step) and wl[0] == 380 and wl[-1] == 780
    with OpenEXR.File(str(dst), separate_channels=True) as f:
        bands = [c for c in f.channels() if c.startswith("S0.")]
    assert len(bands) == len(wl)
    check_choice(step, LIGHTS[name], [CHECKER[p] for p in CHECKER])


def test_spiky_lights_get_finer_grids(specmap):
    step = {n: specmap("color", n, "--tolerance", str(TOL), "--quadrature", "uniform")["grid_choice"]["step_nm"]
            for n in ("D65", "FL2", "lps")}
    assert step["FL2"] < step["D65"] and step["lps"] < step["D65"], step
