"""`specmap rendition` recomputed independently: numpy for the irradiance (lat-long directions and
solid angles written out here), colour-science for the CMFs, the ColorChecker, CAT02
(`colour.chromatic_adaptation`), CIELAB and CIEDE2000 (`colour.delta_E`). Also checks that each
committed truth scene's RGB map is its spectra integrated with the CIE 1931 observer to linear
sRGB (Rec.709 primaries, D65 white)."""
import json
import subprocess

import numpy as np
import OpenEXR
import pytest

import colour

from conftest import BIN, ROOT

TRUTH = ROOT / "tests" / "data" / "truth"
CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
D65_XY = np.array([0.3127, 0.3290])
NORMALS = {"up": [0, 1, 0], "down": [0, -1, 0], "px": [1, 0, 0], "nx": [-1, 0, 0],
           "pz": [0, 0, 1], "nz": [0, 0, -1], "1:1:1": [1, 1, 1]}


def read_spectral(path):
    """Wavelengths and radiance (h, w, bands) of a Fichet-layout EXR, by OpenEXR's binding."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        channels = f.channels()
        bands = sorted((float(n[3:-2].replace(",", ".")), n) for n in channels
                       if n.startswith("S0.") and n.endswith("nm"))
        image = np.stack([channels[n].pixels for _, n in bands], -1).astype(np.float64)
        rgb = np.stack([channels[c].pixels for c in "RGB"], -1).astype(np.float64)
    return np.array([w for w, _ in bands]), image, rgb


def latlong(w, h):
    """OpenEXR lat-long pixel-centre directions and exact pixel solid angles."""
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    lon = -2 * np.pi * (u[None, :] - 0.5)
    lat = -np.pi * (v[:, None] - 0.5)
    d = np.stack(np.broadcast_arrays(np.sin(lon) * np.cos(lat), np.sin(lat),
                                     np.cos(lon) * np.cos(lat)), -1)
    t = np.pi * np.arange(h + 1) / h
    omega = np.repeat((2 * np.pi / w * (np.cos(t[:-1]) - np.cos(t[1:])))[:, None], w, 1)
    return d, omega


def irradiance(image, normal):
    h, w, _ = image.shape
    d, omega = latlong(w, h)
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    return np.einsum("hw,hwb->b", np.maximum(0, d @ n) * omega, image)


def rendition(truth, rec, normals):
    """What `specmap rendition` reports, computed here."""
    wt, it, _ = read_spectral(truth)
    wr, ir, _ = read_spectral(rec)
    lo, hi = max(wt[0], wr[0]), min(wt[-1], wr[-1])
    step = min(np.diff(wt).min(), np.diff(wr).min())
    shape = colour.SpectralShape(lo, hi, step)
    wl = shape.wavelengths
    cmfs = CMFS.copy().align(shape).values
    patches = colour.SDS_COLOURCHECKERS["BabelColor Average"]
    names = list(patches)
    rho = np.array([patches[n].copy().align(shape).values for n in names])
    d65 = colour.xy_to_XYZ(D65_XY)
    out = {}
    for name in normals:
        et = np.interp(wl, wt, irradiance(it, NORMALS[name]))
        er = np.interp(wl, wr, irradiance(ir, NORMALS[name]))

        def render(e):
            white = e @ cmfs / (e @ cmfs[:, 1])
            xyz = (rho * e) @ cmfs / (e @ cmfs[:, 1])
            return white, xyz

        (w_t, x_t), (w_r, x_r) = render(et), render(er)
        lab = lambda xyz, white: colour.XYZ_to_Lab(  # noqa: E731
            colour.chromatic_adaptation(xyz, white, d65, method="Von Kries", transform="CAT02"),
            D65_XY)
        de = colour.delta_E(lab(x_t, w_t), lab(x_r, w_r), method="CIE 2000")
        white_de = colour.delta_E(lab(w_t, w_t), lab(w_r, w_t), method="CIE 2000")
        # Patches in the chart's order, which is specmap's table's order too.
        out[name] = {"patches": de, "white": float(white_de),
                     "ratio": float((er @ cmfs[:, 1]) / (et @ cmfs[:, 1])),
                     "lab_t": lab(x_t, w_t), "white_xy": colour.XYZ_to_xy(w_t)}
    return wl, out


@pytest.fixture(scope="module")
def reconstruction(tmp_path_factory):
    """The default conversion of a committed sky's RGB map (float, so no EV scaling)."""
    out = tmp_path_factory.mktemp("rendition") / "sky.exr"
    p = subprocess.run([BIN, "convert", str(TRUTH / "sky_e20_t4.rgb.exr"), "-o", str(out),
                        "--precision", "float", "--quiet"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return out


def test_rendition_matches_an_independent_computation(specmap, reconstruction):
    truth = TRUTH / "sky_e20_t4.spectral.exr"
    normals = list(NORMALS)
    got = specmap("rendition", str(truth), str(reconstruction), "--normals=" + ",".join(normals))
    wl, want = rendition(truth, reconstruction, normals)
    assert got["wavelengths"]["start_nm"] == 380.0 and len(wl) == got["wavelengths"]["len"] == 69
    assert got["truth"]["range_nm"] == [380.0, 720.0]
    assert got["reconstructed"]["range_nm"] == [380.0, 780.0]
    des = []
    for n in got["normals"]:
        w = want[n["normal"]["name"]]
        np.testing.assert_allclose(n["truth_white"]["xy"], w["white_xy"], atol=1e-9)
        assert n["irradiance_ratio"] == pytest.approx(w["ratio"], rel=1e-9)
        assert n["white_de2000"] == pytest.approx(w["white"], abs=1e-7)
        for k, p in enumerate(n["patches"]):
            assert p["de2000"] == pytest.approx(w["patches"][k], abs=1e-7), p["patch"]
            np.testing.assert_allclose(p["truth_lab"], w["lab_t"][k], atol=1e-7)
            des.append(p["de2000"])
    assert got["mean_de2000"] == pytest.approx(np.mean(des), abs=1e-9)
    assert got["max_de2000"] == pytest.approx(np.max(des), abs=1e-9)
    assert got["mean_de2000"] > 0.05  # a reconstruction, not the truth: something to measure


def test_two_truths_under_different_lights(specmap):
    """Interior (FL2) against street (HPS): both on 380-780 nm, far apart, computed alike."""
    a, b = TRUTH / "interior_fl2.spectral.exr", TRUTH / "street_hps.spectral.exr"
    got = specmap("rendition", str(a), str(b))
    _, want = rendition(a, b, ["up", "px", "nx", "pz", "nz"])
    for n in got["normals"]:
        w = want[n["normal"]["name"]]
        assert n["white_de2000"] == pytest.approx(w["white"], abs=1e-7)
        for k, p in enumerate(n["patches"]):
            assert p["de2000"] == pytest.approx(w["patches"][k], abs=1e-7)
    assert got["white_mean_de2000"] > 10


@pytest.mark.parametrize("scene", json.loads((TRUTH / "manifest.json").read_text())["scenes"],
                         ids=lambda s: s["name"])
def test_truth_rgb_is_its_spectra_seen_by_the_cie_1931_observer(scene):
    wl, spectra, preview = read_spectral(TRUTH / scene["spectral"])
    shape = colour.SpectralShape(wl[0], wl[-1], wl[1] - wl[0])
    # Luminance scale of specmap, pbrt-v4 and Mitsuba 3: Y = sum(L ybar) / sum(ybar), the latter
    # over 380-780 nm at 5 nm whatever the scene's range.
    ybar_sum = CMFS.copy().align(colour.SpectralShape(380, 780, 5)).values[:, 1].sum()
    xyz = spectra.reshape(-1, len(wl)) @ CMFS.copy().align(shape).values / ybar_sum
    srgb = colour.RGB_COLOURSPACES["sRGB"]  # its matrix from the primaries, not the rounded one
    to_rgb = np.linalg.inv(colour.normalised_primary_matrix(srgb.primaries, srgb.whitepoint))
    rgb = xyz @ to_rgb.T
    if "balance" in scene:
        # White-balanced to a lamp: its RGB (at luminance 1) divided out.
        table = np.loadtxt(ROOT / "spectra" / "light" / f"{scene['balance']}.csv", delimiter=",",
                           skiprows=1)
        lamp = np.interp(wl, table[:, 0], table[:, 1])
        lamp_xyz = lamp @ CMFS.copy().align(shape).values
        rgb = rgb / (to_rgb @ (lamp_xyz / lamp_xyz[1]))
    with OpenEXR.File(str(TRUTH / scene["rgb"]), separate_channels=True) as f:
        channels = f.channels()
        user = np.stack([channels[c].pixels for c in "RGB"], -1).astype(np.float64)
    user = user.reshape(-1, 3)
    scale = np.abs(user).max()
    np.testing.assert_allclose(rgb, user, atol=2e-6 * scale, rtol=2e-6)
    np.testing.assert_allclose(preview.reshape(-1, 3), user, atol=1e-3 * scale, rtol=1e-3)
