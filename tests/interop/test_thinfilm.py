"""`specmap thinfilm` against Byrnes' tmm (an independent transfer-matrix implementation).

specmap folds the stack bottom-up with the Airy recursion; tmm multiplies 2x2 transfer matrices.
Both use n + ik with k > 0 absorbing and the same forward-wave branch, so R and T must agree to
rounding: the tolerance is 1e-9 absolute on R and T, for s and p separately, at 0, 30, 60, 85 and
89.9 degrees, on every wavelength of 380:780:10.
"""
import numpy as np
import pytest

import colour
import tmm

RANGE = "380:780:10"
ANGLES = [0.0, 30.0, 60.0, 85.0, 89.9]
TOL = 1e-9

# (name, --layers, --substrate, tmm n_list without the ambient, tmm thicknesses)
STACKS = [
    ("chrome oxide 270 nm (paper Fig. 6)", "2.7:270", "1.45", [2.7, 1.45], [270.0]),
    ("TiO2 150 nm (paper Fig. 7 left)", "2.3:150", "1.45", [2.3, 1.45], [150.0]),
    ("TiO2 350 nm (paper Fig. 7 right)", "2.3:350", "1.45", [2.3, 1.45], [350.0]),
    ("soap film in air", "1.33:400", "1.0", [1.33, 1.0], [400.0]),
    (
        "three layers on glass",
        "1.38:95,2.1:130,1.46:80",
        "1.52",
        [1.38, 2.1, 1.46, 1.52],
        [95.0, 130.0, 80.0],
    ),
    ("film on chrome", "1.38:100", "3.1+3.3i", [1.38, 3.1 + 3.3j], [100.0]),
    ("absorbing film on chrome", "2.0+0.3i:60", "3.1+3.3i", [2.0 + 0.3j, 3.1 + 3.3j], [60.0]),
]


def compare(out, pol, n_list, d_list, th0_deg, coherency=None):
    """Largest |R - R_tmm| and |T - T_tmm| over the output's wavelengths."""
    worst_r = worst_t = 0.0
    th0 = np.radians(th0_deg)
    for lam, r, t in zip(out["wavelengths_nm"], out["R"], out["T"]):
        if coherency is None:
            ref = tmm.coh_tmm(pol, n_list, d_list, th0, lam)
        else:
            ref = tmm.inc_tmm(pol, n_list, d_list, coherency, th0, lam)
        worst_r = max(worst_r, abs(r - ref["R"]))
        worst_t = max(worst_t, abs(t - ref["T"]))
    return worst_r, worst_t


@pytest.mark.parametrize("name,layers,substrate,n_list,d_list", STACKS, ids=[s[0] for s in STACKS])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_coherent_stacks_match_tmm(specmap, name, layers, substrate, n_list, d_list, pol):
    for angle in ANGLES:
        out = specmap(
            "thinfilm", "--layers", layers, "--substrate", substrate,
            "--angle", str(angle), "--pol", pol, "--range", RANGE,
        )
        assert out["incoherent_layers"] == []
        wr, wt = compare(out, pol, [1.0] + n_list, [np.inf] + d_list + [np.inf], angle)
        assert wr <= TOL and wt <= TOL, f"{name}, {pol}, {angle} deg: |dR| {wr:.2e}, |dT| {wt:.2e}"


@pytest.mark.parametrize("pol", ["s", "p"])
def test_total_internal_reflection_and_frustrated_tir_match_tmm(specmap, pol):
    # Glass ambient (1.5), an air gap, glass or air below: the critical angle is 41.8 degrees.
    for layers, substrate, n_list, d_list in [
        ("1.0:200", "1.5", [1.0, 1.5], [200.0]),
        ("1.0:50,2.0:100", "1.0", [1.0, 2.0, 1.0], [50.0, 100.0]),
    ]:
        for angle in [30.0, 45.0, 60.0, 89.9]:
            out = specmap(
                "thinfilm", "--ambient", "1.5", "--layers", layers, "--substrate", substrate,
                "--angle", str(angle), "--pol", pol, "--range", "380:780:50",
            )
            wr, wt = compare(out, pol, [1.5] + n_list, [np.inf] + d_list + [np.inf], angle)
            assert wr <= TOL and wt <= TOL, f"{layers} {angle}: |dR| {wr:.2e}, |dT| {wt:.2e}"


@pytest.mark.parametrize("pol", ["s", "p"])
def test_thick_layers_fall_back_to_tmm_incoherent(specmap, pol):
    """1 mm and 0.5 mm layers have fringes ~0.05 nm apart, far below the 10 nm step: specmap must
    flag them and agree with tmm's inc_tmm with those layers marked 'i'."""
    cases = [
        ("1.5:1000000", "1.0", [1.5, 1.0], [1e6], ["i", "i", "i"], [1]),
        (
            "2.0:100,1.5+0.00001i:1000000,1.38:80",
            "1.52",
            [2.0, 1.5 + 1e-5j, 1.38, 1.52],
            [100.0, 1e6, 80.0],
            ["i", "c", "i", "c", "i"],
            [2],
        ),
        ("1.5:500000,2.3:150", "1.45+0.01i", [1.5, 2.3, 1.45 + 0.01j], [5e5, 150.0],
         ["i", "i", "c", "i"], [1]),
    ]
    for layers, substrate, n_list, d_list, c_list, flagged in cases:
        for angle in [0.0, 60.0, 89.9]:
            out = specmap(
                "thinfilm", "--layers", layers, "--substrate", substrate,
                "--angle", str(angle), "--pol", pol, "--range", RANGE,
            )
            assert out["incoherent_layers"] == flagged
            wr, wt = compare(
                out, pol, [1.0] + n_list, [np.inf] + d_list + [np.inf], angle, c_list
            )
            assert wr <= TOL and wt <= TOL, f"{layers} {angle}: |dR| {wr:.2e}, |dT| {wt:.2e}"


def test_unpolarized_is_the_mean_and_the_colour_matches_colour_science(specmap):
    """The paper's chrome-oxide film, unpolarised at 30 degrees: R and T against tmm's
    unpolarized_RT, and the reflected colour under D65 against colour-science's sd_to_XYZ
    (Integration) of tmm's reflectance on 380:780:1."""
    out = specmap("thinfilm", "--layers", "2.7:270", "--substrate", "1.45", "--angle", "30")
    n_list, d_list = [1.0, 2.7, 1.45], [np.inf, 270.0, np.inf]
    lams = np.arange(380, 781, 1.0)
    ref = [tmm.unpolarized_RT(n_list, d_list, np.radians(30.0), lam) for lam in lams]
    assert np.allclose(out["wavelengths_nm"], lams)
    assert np.max(np.abs(np.array(out["R"]) - [x["R"] for x in ref])) <= TOL
    assert np.max(np.abs(np.array(out["T"]) - [x["T"] for x in ref])) <= TOL
    sd = colour.SpectralDistribution(dict(zip(lams, [x["R"] for x in ref])))
    xyz = colour.sd_to_XYZ(
        sd,
        colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"],
        colour.SDS_ILLUMINANTS["D65"],
        method="Integration",
        shape=colour.SpectralShape(380, 780, 1),
    )
    assert np.all(np.abs(np.array(out["XYZ"]) - xyz) <= 1e-6 * np.abs(xyz)), (out["XYZ"], xyz)
    srgb = colour.XYZ_to_sRGB(xyz / 100.0, apply_cctf_encoding=True)
    expected = np.round(np.clip(srgb, 0, 1) * 255).astype(int)
    assert np.all(np.abs(np.array(out["srgb8"]) - expected) <= 1), (out["srgb8"], expected)
