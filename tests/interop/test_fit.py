"""specmap fit against an independent computation: colour-science for the colorimetry, numpy and
scipy for the linear algebra and the least-squares solve, colour-science's CIEDE2000 for the
round trip."""
import numpy as np
import pytest
from scipy.optimize import least_squares

import colour

SHAPE = colour.SpectralShape(380, 780, 1)
CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
CHECKER = colour.SDS_COLOURCHECKERS["BabelColor Average"]
BASIS = [CHECKER["red"], CHECKER["green"], CHECKER["blue"]]
LIGHTS = {
    "D65": colour.SDS_ILLUMINANTS["D65"],
    "A": colour.SDS_ILLUMINANTS["A"],
    "FL2": colour.SDS_ILLUMINANTS["FL2"],
    "FL11": colour.SDS_ILLUMINANTS["FL11"],
    "LED-B3": colour.SDS_ILLUMINANTS["LED-B3"],
    "hps": colour.SDS_LIGHT_SOURCES["HPS"],
    "lps": colour.SDS_LIGHT_SOURCES["LPS"],
}
SRGB = colour.RGB_COLOURSPACES["sRGB"]
RGB_TO_XYZ = colour.normalised_primary_matrix(SRGB.primaries, SRGB.whitepoint)
XYZ_TO_RGB = np.linalg.inv(RGB_TO_XYZ)


def system(light):
    """C (columns: RGB of each basis patch under the light, Eq. 10/11) and t (the light's RGB)."""
    sd = LIGHTS[light]
    cols = [
        XYZ_TO_RGB @ (colour.sd_to_XYZ(b, CMFS, sd, method="Integration", shape=SHAPE) / 100)
        for b in BASIS
    ]
    xyz_light = colour.sd_to_XYZ(sd, CMFS, method="Integration", shape=SHAPE)
    t = XYZ_TO_RGB @ (xyz_light / xyz_light[1])
    return np.column_stack(cols), t


def reference_weights(C, t, limit=100.0):
    """Least squares within the colour directions whose singular value is at least 1/limit of
    the largest (all of them for a well-conditioned C), by scipy's own solver."""
    u, s, vt = np.linalg.svd(C)
    V = vt[s * limit >= s[0]].T
    sol = least_squares(lambda z: C @ V @ z - t, V.T @ np.ones(3), xtol=1e-15, ftol=1e-15,
                        gtol=1e-15)
    return V @ sol.x, s[0] / s[-1], V.shape[1] < 3


def round_trip(C, W, t, light):
    """17^3 grid without black -> coefficients -> RGB of the SPD -> white balance -> CIEDE2000."""
    g = np.linspace(0, 1, 17)
    rgb = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)[1:]
    a = rgb @ W.T
    out = (a @ C.T) / t
    white = colour.XYZ_to_xy(RGB_TO_XYZ @ np.ones(3))
    lab_in = colour.XYZ_to_Lab(rgb @ RGB_TO_XYZ.T, white)
    lab_out = colour.XYZ_to_Lab(out @ RGB_TO_XYZ.T, white)
    de = np.sort(colour.delta_E(lab_in, lab_out, method="CIE 2000"))
    # Negative SPD: S(l) * sum_j a_j MCC_j(l) < 0 where the light has power.
    sd = LIGHTS[light].copy().align(SHAPE)
    mcc = np.stack([b.copy().align(SHAPE).values for b in BASIS], 1)
    lit = sd.values > 0
    vals = a @ mcc[lit].T
    neg = np.any(vals < -1e-12 * np.abs(a).max(1, keepdims=True), axis=1)
    return {
        "mean": de.mean(),
        "p95": np.percentile(de, 95, method="inverted_cdf"),
        "max": de.max(),
        "neg": neg.mean(),
    }


@pytest.mark.parametrize("light", list(LIGHTS))
@pytest.mark.parametrize("mode", ["paper", "exact"])
def test_fit_matches_independent_computation(specmap, light, mode):
    out = specmap("fit", "--light", light, "--mode", mode)
    C, t = system(light)
    w, cond, reduced = reference_weights(C, t)
    np.testing.assert_allclose(out["light_rgb"], t, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(out["weights"], w, rtol=1e-7, err_msg="weights")
    assert out["condition_number"] == pytest.approx(cond, rel=1e-5)
    assert out["regularized"] == reduced
    # argmin and the closed form agree to 1e-8 (the criterion).
    assert out["argmin"]["max_abs_difference"] < 1e-8
    np.testing.assert_allclose(out["argmin"]["weights"], out["weights"], rtol=0, atol=1e-8)
    if mode == "paper":
        W = np.diag(w)
    else:
        u, s, vt = np.linalg.svd(C)
        keep = s * 100 >= s[0]
        W = (vt[keep].T @ np.diag(1 / s[keep]) @ u[:, keep].T) @ np.diag(t)
    np.testing.assert_allclose(out["matrix"], W, rtol=1e-6, atol=1e-9, err_msg="matrix")
    ref = round_trip(C, W, t, light)
    rt = out["roundtrip"]
    assert rt["colours"] == 17**3 - 1
    for ours, theirs in [("mean_dE2000", "mean"), ("p95_dE2000", "p95"), ("max_dE2000", "max")]:
        assert rt[ours] == pytest.approx(ref[theirs], rel=1e-5, abs=1e-7), ours
    assert rt["negative_fraction"] == pytest.approx(ref["neg"], abs=1.5 / 4912)
    if mode == "exact" and not reduced:
        assert rt["max_dE2000"] < 1e-3


def test_lps_is_finite_flagged_and_explained(specmap):
    out = specmap("fit", "--light", "lps")
    assert out["regularized"] is True
    assert all(np.isfinite(out["weights"])) and max(abs(w) for w in out["weights"]) < 1000
    assert "only brightness survives" in out["lost_information"]


@pytest.mark.parametrize("light", ["D65", "FL2", "hps"])
def test_nonneg_is_optimal_against_scipy_slsqp(specmap, light):
    """For colours whose exact SPD goes negative, specmap's non-negative solution is at least as
    good (CIEDE2000) as scipy's SLSQP on the same constrained problem from several starts, and its
    SPD is non-negative; inside the cone it is the exact solution."""
    from scipy.optimize import minimize

    C, t = system(light)
    sd = LIGHTS[light].copy().align(SHAPE)
    mcc = np.stack([b.copy().align(SHAPE).values for b in BASIS], 1)[sd.values > 0]
    white = colour.XYZ_to_xy(RGB_TO_XYZ @ np.ones(3))
    W = np.linalg.inv(C) @ np.diag(t)
    for rgb in ([1, 0, 0], [0, 0, 1], [0, 1, 1], [1, 0, 1], [0.9, 0.9, 0.1], [0.6, 0.5, 0.4]):
        rgb = np.asarray(rgb, float)
        out = specmap("fit", "--light", light, "--mode", "nonneg", "--rgb",
                      ",".join(map(str, rgb)))["pixel"]
        assert out["min_spd"] >= -1e-12
        lab_in = colour.XYZ_to_Lab(RGB_TO_XYZ @ rgb, white)

        def de(a):
            return colour.delta_E(lab_in, colour.XYZ_to_Lab(RGB_TO_XYZ @ ((C @ a) / t), white),
                                  method="CIE 2000")

        exact = W @ rgb
        if np.all(mcc @ exact >= 0):
            np.testing.assert_allclose(out["coefficients"], exact, rtol=1e-9, atol=1e-12)
            continue
        best = np.inf
        for start in (np.clip(exact, 0, None), np.full(3, 0.5), W @ np.full(3, rgb.mean())):
            r = minimize(de, start, method="SLSQP",
                         constraints=[{"type": "ineq", "fun": lambda a: mcc @ a}],
                         options={"ftol": 1e-12, "maxiter": 500})
            if r.success and np.all(mcc @ r.x >= -1e-9):
                best = min(best, de(r.x))
        assert np.isfinite(best)
        assert out["dE2000"] == pytest.approx(de(np.asarray(out["coefficients"])), abs=1e-9)
        assert out["dE2000"] <= best + 2e-3, f"{light} {rgb}: ours {out['dE2000']} vs SLSQP {best}"
