"""Quadratures checked independently: the nodes and weight triples specmap reports, applied by
numpy to colour-science's data (its lights interpolated linearly, its reflectances by Sprague
at 1 nm) and to tmm's films, against colour-science's CMFs at 1 nm by scipy's Simpson rule.

Every colour checked here besides the one asked for is one specmap did not fit: smooth
reflectances (edges and bumps, computed here) centred between the fitted and the held-out ones,
and the ball's film at angles between the fitted ones. A quadrature that misses its tolerance
on them fails the test.
"""
import numpy as np
import pytest
import scipy.integrate

import colour
import tmm
from test_fit import LIGHTS  # the lights of the table, as colour-science names them

CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
WL = np.arange(380, 781, dtype=float)
CMF = CMFS.copy().align(colour.SpectralShape(380, 780, 1)).values
TOL = 0.5
# Centres of smooth reflectances on neither specmap's fitted (420, 430, ...) nor its held-out
# (425, 435, ...) grid.
CENTRES = (437.0, 468.0, 493.0, 522.0, 557.0, 584.0, 611.0, 643.0, 673.0, 703.0)


def light_at(light, wl):
    return np.interp(wl, light.wavelengths, light.values)


def reflectance_1nm(sd):
    return sd.copy().align(colour.SpectralShape(380, 780, 1)).values


def reference_xyz(light, r):
    """XYZ at 1 nm by Simpson's rule, a white under the light at Y = 100."""
    s = light_at(light, WL)
    integ = lambda f: np.array([scipy.integrate.simpson(f * CMF[:, i], x=WL) for i in range(3)])
    return 100 * integ(s * r) / integ(s)[1]


def quadrature_xyz(q, light, r_at_nodes):
    nodes, w = np.array(q["nodes_nm"]), np.array(q["weights"])
    s = light_at(light, nodes)
    return 100 * (w * (s * r_at_nodes)[:, None]).sum(0) / (w[:, 1] * s).sum()


def de(a, b, white):
    xy = colour.XYZ_to_xy(white / 100)
    return float(colour.delta_E(colour.XYZ_to_Lab(a / 100, xy), colour.XYZ_to_Lab(b / 100, xy),
                                method="CIE 2000"))


def smooth(centre):
    """The family of smooth reflectances specmap fits (logistic edges 15 and 50 nm wide, up and
    down; Gaussian bumps 25, 50 and 100 nm wide), at 1 nm, centred at `centre`."""
    edge = lambda s: 1 / (1 + np.exp(-(WL - centre) / s))
    bump = lambda s: np.exp(-0.5 * ((WL - centre) / s) ** 2)
    shapes = [edge(15), 1 - edge(15), edge(50), 1 - edge(50), bump(25), bump(50), bump(100)]
    return [0.05 + 0.9 * f for f in shapes]


@pytest.mark.parametrize("name", list(LIGHTS))
def test_color_quadrature_holds_for_colours_it_did_not_fit(specmap, name):
    light = LIGHTS[name]
    out = specmap("color", "colorchecker:red", "--under", name, "--tolerance", str(TOL))
    q = out["quadrature"]
    assert out["wavelengths"] == len(q["nodes_nm"]) == len(q["weights"])
    white = reference_xyz(light, np.ones_like(WL))
    nodes = np.array(q["nodes_nm"])
    assert np.all(nodes == np.round(nodes)) or q["kind"] != "scene"
    idx = (nodes - 380).astype(int)
    worst = 0.0
    # The colour asked for: specmap's XYZ is the quadrature's, and within the tolerance.
    red = reflectance_1nm(colour.SDS_COLOURCHECKERS["BabelColor Average"]["red"])
    got = quadrature_xyz(q, light, red[idx]) if q["kind"] != "uniform" else np.array(out["XYZ"])
    assert np.allclose(got, out["XYZ"], rtol=1e-9, atol=1e-9)
    worst = max(worst, de(got, reference_xyz(light, red), white))
    # Smooth reflectances centred where specmap neither fitted nor held out.
    for r in [r for c in CENTRES for r in smooth(c)]:
        worst = max(worst, de(quadrature_xyz(q, light, r[idx]), reference_xyz(light, r), white))
    assert worst <= TOL, f"{name}: {q['kind']} {len(nodes)} nodes, largest CIEDE2000 {worst:.3f}"
    if q["kind"] == "scene":
        assert out["quadrature_choice"]["met"]


def test_meyer_reproduces_its_gauss_construction(specmap):
    """Meyer's rule as specmap builds it: the 4-node Gauss rule of ybar on 380-780 nm
    (numpy's own eigen-decomposition of the Jacobi matrix from numpy's Stieltjes recurrence),
    with interpolatory weights for xbar, ybar, zbar."""
    out = specmap("color", "D65", "--quadrature", "meyer")
    q = out["quadrature"]
    t = (WL - 580) / 200
    m = scipy.integrate.simpson(np.eye(len(WL)), x=WL, axis=0) * CMF[:, 1]  # Simpson masses
    p_prev, p, alpha, beta, norm_prev = np.zeros_like(t), np.ones_like(t), [], [], 1.0
    for k in range(4):
        norm = (m * p * p).sum()
        alpha.append((m * t * p * p).sum() / norm)
        beta.append(norm / norm_prev if k else 0.0)
        p_prev, p, norm_prev = p, (t - alpha[-1]) * p - beta[-1] * p_prev, norm
    jac = np.diag(alpha) + np.diag(np.sqrt(beta[1:]), 1) + np.diag(np.sqrt(beta[1:]), -1)
    nodes = np.sort(np.linalg.eigvalsh(jac)) * 200 + 580
    assert np.allclose(q["nodes_nm"], nodes, atol=1e-6), (q["nodes_nm"], nodes)
    # Interpolatory: exact for cmf times any cubic.
    for k in range(4):
        f = ((WL - 580) / 200) ** k
        exact = [scipy.integrate.simpson(f * CMF[:, c], x=WL) for c in range(3)]
        got = (np.array(q["weights"]) * (((np.array(q["nodes_nm"]) - 580) / 200) ** k)[:, None]).sum(0)
        assert np.allclose(got, exact, rtol=1e-6, atol=1e-9), (k, got, exact)


def test_render_quadrature_integrates_the_ball_film_at_angles_it_did_not_fit(specmap, tmp_path):
    """The ball's chrome-oxide film (2.7, 270 nm on 1.45) under D65: tmm's reflectance at angles
    between the fitted ones, integrated with the render's quadrature, against colour-science at
    1 nm (CIELAB relative to the output white, as the render is compared)."""
    out = specmap("render", "--scene", "ball", "--size", "16x16", "--backend", "cpu",
                  "--tolerance", str(TOL), "--quadrature", "scene", "--no-cache",
                  "-o", str(tmp_path / "b.png"))
    q = out["quadrature"]
    assert q["kind"] == "scene" and out["wavelengths"] == len(q["nodes_nm"]) <= 8
    assert out["quadrature_choice"]["met"] and q["estimate_de2000"] <= TOL
    light = LIGHTS["D65"]
    white = 100 * colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
    nodes = np.array(q["nodes_nm"])

    def film(wl, deg):
        return np.array([tmm.unpolarized_RT([1.0, 2.7, 1.45], [np.inf, 270.0, np.inf],
                                            np.radians(deg), lam)["R"] for lam in wl])

    worst = 0.0
    for deg in (7.0, 21.0, 37.0, 52.0, 63.0, 74.0, 86.0):
        got = quadrature_xyz(q, light, film(nodes, deg))
        worst = max(worst, de(got, reference_xyz(light, film(WL, deg)), white))
    assert worst <= TOL, f"largest CIEDE2000 {worst:.3f} with {len(nodes)} nodes"
