"""`specmap.thinfilm` against Byrnes' tmm 0.2.0, an independent transfer-matrix implementation
(specmap folds the stack with the Airy recursion; tmm multiplies 2x2 matrices), element by
element over (thickness scale, angle, wavelength) grids: R and T agree to 1e-9 absolute for s, p
and unpolarised light, transparent and absorbing layers and substrates, 0 to 80 degrees. Also the
result's axes for each scalar/array combination, the CLI (`specmap thinfilm --json`) on one case,
and the errors."""

import numpy as np
import pytest
import tmm

import specmap

TOL = 1e-9
WAVELENGTHS = np.arange(380.0, 781.0, 20.0)
ANGLES = np.array([0.0, 30.0, 60.0, 70.0, 80.0])
SCALES = np.array([0.0, 0.5, 1.0, 1.7])


def tmm_rt(layers, substrate, lam, angle_deg, pol, ambient=1.0, scale=1.0):
    """R and T from tmm for one wavelength and angle; `layers` as (complex index, nm)."""
    n_list = [ambient] + [n for n, _ in layers] + [substrate]
    d_list = [np.inf] + [d * scale for _, d in layers] + [np.inf]
    th0 = np.radians(angle_deg)
    if pol == "u":
        out = tmm.unpolarized_RT(n_list, d_list, th0, lam)
    else:
        out = tmm.coh_tmm(pol, n_list, d_list, th0, lam)
    return out["R"], out["T"]


def tmm_grid(layers, substrate, pol, wavelengths=WAVELENGTHS, angles=ANGLES, scales=SCALES,
             ambient=1.0):
    """tmm's R and T on the (scale, angle, wavelength) grid, one call per element."""
    shape = (len(scales), len(angles), len(wavelengths))
    R, T = np.empty(shape), np.empty(shape)
    for i, s in enumerate(scales):
        for j, a in enumerate(angles):
            for k, lam in enumerate(wavelengths):
                R[i, j, k], T[i, j, k] = tmm_rt(layers, substrate, lam, a, pol, ambient, s)
    return R, T


# (name, layers as (index, nm) from the ambient side, substrate)
STACKS = [
    ("chrome oxide 270 nm on silica (1 layer)", [(2.7, 270.0)], 1.45),
    ("MgF2 + absorbing layer on chrome (2 layers)",
     [(1.38, 95.0), (2.0 + 0.3j, 60.0)], 3.1 + 3.3j),
    ("three layers on glass", [(1.38, 95.0), (2.1, 130.0), (1.46, 80.0)], 1.52),
    ("absorbing film on glass", [(1.9 + 0.8j, 25.0)], 1.52),
    ("bare chrome", [], 3.1 + 3.3j),
]


@pytest.mark.parametrize("name,layers,substrate", STACKS, ids=[s[0] for s in STACKS])
@pytest.mark.parametrize("pol", ["s", "p", "u"])
def test_matches_tmm_over_the_grid(name, layers, substrate, pol):
    R, T = specmap.thinfilm(layers, substrate, WAVELENGTHS, angles_deg=ANGLES,
                            thickness_scale=SCALES, pol=pol)
    assert R.shape == T.shape == (len(SCALES), len(ANGLES), len(WAVELENGTHS))
    assert R.dtype == T.dtype == np.float64
    R_ref, T_ref = tmm_grid(layers, substrate, pol)
    np.testing.assert_allclose(R, R_ref, rtol=0, atol=TOL)
    np.testing.assert_allclose(T, T_ref, rtol=0, atol=TOL)


@pytest.mark.parametrize("pol", ["s", "p", "u"])
def test_many_scales_match_tmm(pol):
    # From 8 scales each (angle, wavelength) is prepared once and swept over the scales: the
    # same numbers, in the same (scale, angle, wavelength) order.
    layers, substrate = [(1.38, 95.0), (2.0 + 0.3j, 60.0)], 3.1 + 3.3j
    scales = np.linspace(0.0, 2.0, 9)
    waves, angles = WAVELENGTHS[::3], np.array([0.0, 45.0, 70.0])
    R, T = specmap.thinfilm(layers, substrate, waves, angles_deg=angles, thickness_scale=scales,
                            pol=pol)
    R_ref, T_ref = tmm_grid(layers, substrate, pol, wavelengths=waves, angles=angles,
                            scales=scales)
    np.testing.assert_allclose(R, R_ref, rtol=0, atol=TOL)
    np.testing.assert_allclose(T, T_ref, rtol=0, atol=TOL)


def test_thousands_of_scales_at_one_angle_and_wavelength():
    # More scales than one parallel task takes (2048): every one in its place.
    layers, substrate = [(2.3, 150.0), (1.46, 80.0)], 1.52
    scales = np.linspace(0.0, 3.0, 5001)
    R, T = specmap.thinfilm(layers, substrate, 610.0, angles_deg=35.0, thickness_scale=scales,
                            pol="u")
    assert R.shape == T.shape == (5001,)
    for i in range(0, 5001, 97):
        r, t = tmm_rt(layers, substrate, 610.0, 35.0, "u", scale=scales[i])
        assert abs(R[i] - r) < TOL and abs(T[i] - t) < TOL, i


@pytest.mark.parametrize("pol", ["s", "p", "u"])
def test_total_internal_reflection_matches_tmm(pol):
    # Glass ambient, an air gap, glass below: beyond 41.8 degrees the gap is evanescent and
    # transmission is frustrated TIR.
    layers, substrate = [(1.0, 200.0)], 1.5
    angles = np.array([0.0, 30.0, 45.0, 60.0, 75.0])
    scales = np.array([0.25, 1.0])
    R, T = specmap.thinfilm(layers, substrate, WAVELENGTHS, angles_deg=angles,
                            thickness_scale=scales, pol=pol, ambient=1.5)
    R_ref, T_ref = tmm_grid(layers, substrate, pol, angles=angles, scales=scales, ambient=1.5)
    np.testing.assert_allclose(R, R_ref, rtol=0, atol=TOL)
    np.testing.assert_allclose(T, T_ref, rtol=0, atol=TOL)


def test_named_material_is_its_dispersion():
    # N-BK7, Schott's Sellmeier coefficients (lambda in micrometres), written out here.
    def bk7(lam_nm):
        l2 = (lam_nm / 1000.0) ** 2
        b = (1.03961212, 0.231792344, 1.01046945)
        c = (0.00600069867, 0.0200179144, 103.560653)
        return np.sqrt(1 + sum(bi * l2 / (l2 - ci) for bi, ci in zip(b, c)))

    angles = np.array([0.0, 65.0])
    R, T = specmap.thinfilm([(1.38, 99.6)], "bk7", WAVELENGTHS, angles_deg=angles, pol="u")
    for j, a in enumerate(angles):
        for k, lam in enumerate(WAVELENGTHS):
            r, t = tmm_rt([(1.38, 99.6)], bk7(lam), lam, a, "u")
            assert abs(R[j, k] - r) < TOL and abs(T[j, k] - t) < TOL, (a, lam)
    # And as a layer's index, as the CLI writes one for the substrate.
    R2, _ = specmap.thinfilm([("bk7", 80.0)], "3.1+3.3i", 500.0, pol="s")
    r, _ = tmm_rt([(bk7(500.0), 80.0)], 3.1 + 3.3j, 500.0, 0.0, "s")
    assert abs(R2 - r) < TOL


def test_absorption_sign_convention():
    # n + 1j*k with k > 0 absorbs, as in tmm: a lossless stack conserves power, an absorbing
    # layer takes some, and k < 0 (gain) is refused.
    R, T = specmap.thinfilm([(2.3, 150.0)], 1.45, WAVELENGTHS, angles_deg=ANGLES)
    np.testing.assert_allclose(R + T, 1.0, rtol=0, atol=1e-12)
    R, T = specmap.thinfilm([(2.3 + 0.2j, 150.0)], 1.45, WAVELENGTHS, angles_deg=ANGLES)
    assert np.all(1.0 - R - T > 1e-3)
    with pytest.raises(ValueError, match="gain"):
        specmap.thinfilm([(2.3 - 0.2j, 150.0)], 1.45, WAVELENGTHS)


def test_thickness_scale_multiplies_every_layer():
    layers = [(1.38, 95.0), (2.1, 130.0)]
    R, T = specmap.thinfilm(layers, 1.52, WAVELENGTHS, angles_deg=45.0,
                            thickness_scale=[0.0, 2.0])
    R2, T2 = specmap.thinfilm([(1.38, 190.0), (2.1, 260.0)], 1.52, WAVELENGTHS, angles_deg=45.0)
    np.testing.assert_allclose(R[1], R2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(T[1], T2, rtol=0, atol=1e-12)
    R0, T0 = specmap.thinfilm([], 1.52, WAVELENGTHS, angles_deg=45.0)
    np.testing.assert_allclose(R[0], R0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(T[0], T0, rtol=0, atol=1e-12)


def test_bare_substrate_is_fresnel():
    # 4% from glass of 1.5 at normal incidence, whatever the wavelength.
    R, T = specmap.thinfilm([], 1.5, WAVELENGTHS)
    np.testing.assert_allclose(R, 0.04, rtol=0, atol=1e-15)
    np.testing.assert_allclose(T, 0.96, rtol=0, atol=1e-15)


KINDS = ["scalar", "array"]


@pytest.mark.parametrize("scale_kind", ["none", "scalar", "array"])
@pytest.mark.parametrize("angle_kind", KINDS)
@pytest.mark.parametrize("wavelength_kind", KINDS)
def test_axes_only_for_arrays(scale_kind, angle_kind, wavelength_kind):
    layers, substrate = [(1.38, 95.0), (2.0 + 0.3j, 60.0)], 3.1 + 3.3j
    scales = {"none": None, "scalar": 1.3, "array": np.array([0.5, 1.3, 2.0])}[scale_kind]
    angles = {"scalar": 60.0, "array": [0.0, 60.0, 75.0]}[angle_kind]
    waves = {"scalar": 540.0, "array": np.linspace(400.0, 700.0, 7)}[wavelength_kind]
    R, T = specmap.thinfilm(layers, substrate, waves, angles_deg=angles,
                            thickness_scale=scales, pol="p")
    shape = tuple(
        n for n, kind in [(3, scale_kind), (3, angle_kind), (7, wavelength_kind)]
        if kind == "array"
    )
    assert isinstance(R, np.ndarray) and isinstance(T, np.ndarray)
    assert R.shape == T.shape == shape
    # The element at scale 1.3, 60 degrees, 550 nm (index 3 of the wavelengths), against tmm.
    pick = tuple(
        i for i, kind in [(1, scale_kind), (1, angle_kind), (3, wavelength_kind)]
        if kind == "array"
    )
    lam = 540.0 if wavelength_kind == "scalar" else 550.0
    scale = 1.0 if scale_kind == "none" else 1.3
    r, t = tmm_rt(layers, substrate, lam, 60.0, "p", scale=scale)
    assert abs(R[pick] - r) < TOL and abs(T[pick] - t) < TOL


def test_empty_axes():
    R, T = specmap.thinfilm([(1.38, 95.0)], 1.52, np.array([]), angles_deg=[0.0, 10.0])
    assert R.shape == T.shape == (2, 0)


def test_agrees_with_the_cli(cli):
    out = cli("thinfilm", "--layers", "1.38:95,2.0+0.3i:60", "--substrate", "3.1+3.3i",
              "--angle", "60", "--pol", "p", "--range", "380:780:10", "--coherence", "coherent",
              "--json")
    R, T = specmap.thinfilm([(1.38, 95.0), (2.0 + 0.3j, 60.0)], 3.1 + 3.3j,
                            np.array(out["wavelengths_nm"]), angles_deg=60.0, pol="p")
    assert len(out["R"]) == len(R) == 41
    np.testing.assert_allclose(R, out["R"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(T, out["T"], rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(layers=[(1.5, -10.0)]), "layer 1.*negative"),
        (dict(layers=[(1.5, np.nan)]), "layer 1.*not finite"),
        (dict(layers=[(1.5 - 0.1j, 10.0)]), "layer 1.*gain"),
        (dict(substrate=1.5 - 0.1j), "substrate.*gain"),
        (dict(layers=[("unobtainium", 10.0)]), "layer 1.*unobtainium"),
        (dict(layers=[(1.5,)]), "layer 1.*pair"),
        (dict(layers=[([1.5, 1.6], 10.0)]), "layer 1.*not a refractive index"),
        (dict(angles_deg=90.0), r"\[0, 90\)"),
        (dict(angles_deg=[0.0, -1.0]), r"\[0, 90\)"),
        (dict(angles_deg=np.nan), r"\[0, 90\)"),
        (dict(wavelengths=[500.0, 0.0]), "wavelength 0 nm.*positive"),
        (dict(wavelengths=[500.0, np.nan]), "(?i)wavelength nan nm.*positive"),
        (dict(wavelengths=np.ones((2, 2)) * 500), "1-D"),
        (dict(angles_deg=np.zeros((2, 1))), "1-D"),
        (dict(thickness_scale=[1.0, -0.5]), "thickness_scale"),
        (dict(thickness_scale=np.inf), "thickness_scale"),
        (dict(thickness_scale=[1.0, 1e30]), "thickness_scale 1e30.*at most 1e20"),
        (dict(pol="x"), "pol"),
        (dict(ambient=1.0 + 0.1j), "ambient.*transparent"),
    ],
)
def test_bad_input_is_a_value_error(kwargs, match):
    args = dict(layers=[(1.38, 95.0)], substrate=1.52, wavelengths=[450.0, 550.0])
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        specmap.thinfilm(**args)
