"""Converted maps read by independent readers: colour-science's Fichet (2021) reader and
OpenEXR's own Python binding; their spectra integrated back by colour-science."""
import json
import pathlib
import subprocess

import numpy as np
import OpenEXR
import pytest

import colour

from conftest import BIN, ROOT

SHAPE = colour.SpectralShape(380, 780, 5)


def convert(tmp_path, name, *args, report=False):
    out = tmp_path / f"{name}.spectral.exr"
    p = subprocess.run([BIN, "convert", str(ROOT / "envmaps" / f"{name}.exr"), "-o", str(out),
                        "--quiet", "--json", *args], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return (out, json.loads(p.stdout)) if report else out


def read_openexr(path):
    """Header, channels and RGB preview by OpenEXR's binding. Call it before colour-science's
    Fichet reader: that loads OpenImageIO, whose bundled OpenEXR library then shadows the
    binding's in this process and custom header attributes go missing."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        header = dict(f.header())
        channels = dict(f.channels())
        preview = np.stack([channels[c].pixels for c in "RGB"], -1).astype(np.float64)
    return header, channels, preview


def rgb_from_spectra(spectra):
    """Linear sRGB of spectral radiance with specmap's scale: Y = sum(L ybar) / sum(ybar)."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE).values
    xyz = spectra @ cmfs / cmfs[:, 1].sum()
    cs = colour.RGB_COLOURSPACES["sRGB"]
    return xyz @ np.linalg.inv(colour.normalised_primary_matrix(cs.primaries, cs.whitepoint)).T


def test_forest_reads_back_with_colour_science_and_openexr(specmap, tmp_path):
    out, report = convert(tmp_path, "forest", "--precision", "float", report=True)
    header, channels, preview = read_openexr(out)
    wavelengths, image = colour.io.read_spectral_image_Fichet2021(str(out))["S0"]
    # No written spectrum is negative.
    assert image.min() >= 0.0
    np.testing.assert_array_equal(wavelengths, SHAPE.wavelengths)
    assert image.shape == (512, 1024, 81)
    assert header["spectralLayoutVersion"] == "1.0"
    assert header["emissiveUnits"] == "W.m^-2.sr^-1"
    assert "S0.550,000000nm" in channels
    assert str(header["envmap"]).endswith("LATLONG")
    # Every pixel's spectrum integrates back to its RGB preview (white-balanced by the main
    # light's RGB, stored in the header), but for those the report counts as inexact: colours
    # no non-negative spectrum under their light makes.
    back = rgb_from_spectra(image.reshape(-1, 81).astype(np.float64))
    back /= np.asarray(header["specmap.lightRGB"], dtype=np.float64)
    want = preview.reshape(-1, 3)
    lit = want.sum(1) > 1e-3
    rel = np.abs(back[lit] - want[lit]).max(1) / want[lit].max(1)
    inexact = report["spectra"]["nearest"] + report["spectra"]["clipped"]
    assert (rel > 1e-3).sum() <= inexact <= 0.001 * rel.size, (rel.max(), inexact)
    assert np.percentile(rel, 99.9) < 1e-4


def test_sunrise_sun_pixels_carry_their_own_daylight(specmap, tmp_path):
    """The default sun SPD: the CIE daylight-family member (S0, S1, S2) of the sun pixels' own
    colour, checked with colour-science's basis functions and colorimetry."""
    from colour.colorimetry import SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES as BASIS
    out = convert(tmp_path, "sunrise", "--precision", "float")
    _, channels, _ = read_openexr(out)
    mask = channels["sun"].pixels > 0.5
    rgb = np.stack([channels[c].pixels for c in "RGB"], -1)[mask].astype(float)
    _, image = colour.io.read_spectral_image_Fichet2021(str(out))["S0"]
    assert 1 <= mask.sum() <= 50
    basis = np.stack([BASIS[k].copy().align(SHAPE).values for k in ("S0", "S1", "S2")], 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE).values
    want = colour.XYZ_to_xy(colour.RGB_to_XYZ(rgb.sum(0), colour.RGB_COLOURSPACES["sRGB"],
                                              apply_cctf_decoding=False))
    for spectrum in image[mask]:
        c = np.linalg.lstsq(basis, spectrum, rcond=None)[0]
        assert np.abs(basis @ c - spectrum).max() < 1e-5 * spectrum.max()
        np.testing.assert_allclose(colour.XYZ_to_xy(spectrum @ cmfs), want, atol=1e-3)


def test_sunrise_sun_pixels_carry_d65_when_asked(specmap, tmp_path):
    out = convert(tmp_path, "sunrise", "--precision", "float", "--sun-spd", "D65")
    _, channels, _ = read_openexr(out)
    mask = channels["sun"].pixels > 0.5
    _, image = colour.io.read_spectral_image_Fichet2021(str(out))["S0"]
    assert 1 <= mask.sum() <= 50
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(SHAPE).values
    for spectrum in image[mask]:
        ratio = spectrum / d65
        np.testing.assert_allclose(ratio, ratio.mean(), rtol=1e-5)


def latlong_solid_angles(height, width):
    """Solid angle of each pixel of a lat-long map (bands between two latitudes)."""
    t = np.pi * np.arange(height + 1) / height
    band = 2 * np.pi / width * (np.cos(t[:-1]) - np.cos(t[1:]))
    return np.repeat(band[:, None], width, 1)


def floor_of(lum, omega):
    """The statistic's luminance floor, recomputed: 2^-13 of the 99th-percentile luminance by
    solid angle, the percentile rounded down to 1/16 octave (see src/envmap/roundtrip/stats.rs)."""
    order = np.argsort(lum, kind="stable")
    cum = np.cumsum(omega[order])
    p99 = lum[order][np.searchsorted(cum, 0.99 * cum[-1])]
    if p99 <= 0:
        return 0.0
    return 2.0 ** (np.floor(np.log2(p99) * 16) / 16 - 13)


def test_roundtrip_command_agrees_with_colour_science(specmap, tmp_path):
    """`specmap roundtrip` on a half-precision file: its statistics (mean, maximum and where it
    is, over the pixels at or above the luminance floor), recomputed in Python; and `convert`
    reports the same floor and maximum pixel for the same map."""
    out, report = convert(tmp_path, "forest", report=True)
    r = specmap("roundtrip", str(out))
    header, channels, preview = read_openexr(out)
    _, image = colour.io.read_spectral_image_Fichet2021(str(out))["S0"]
    back = rgb_from_spectra(image.reshape(-1, 81).astype(np.float64))
    back /= np.asarray(header["specmap.lightRGB"], dtype=np.float64)
    want = preview.reshape(-1, 3)
    cs = colour.RGB_COLOURSPACES["sRGB"]
    m = colour.normalised_primary_matrix(cs.primaries, cs.whitepoint)
    y = want @ m[1]
    omega = latlong_solid_angles(*preview.shape[:2]).reshape(-1)
    floor = floor_of(y, omega)
    assert r["floor"]["luminance"] == pytest.approx(floor, rel=1e-12)
    assert report["roundtrip_floor"]["luminance"] == pytest.approx(floor, rel=1e-3)
    lit = y >= floor
    white = colour.XYZ_to_xy(m @ np.ones(3))
    lab = lambda rgb: colour.XYZ_to_Lab((rgb / y[lit, None]) @ m.T, white)
    de = colour.delta_E(lab(want[lit]), lab(back[lit]), method="CIE 2000")
    w = y[lit] * omega[lit]
    assert r["all"]["pixels"] == lit.sum()
    assert r["all"]["max_de2000"] == pytest.approx(de.max(), rel=1e-3, abs=1e-4)
    assert r["all"]["weighted_mean_de2000"] == pytest.approx((de * w).sum() / w.sum(),
                                                             rel=1e-3, abs=1e-5)
    i = np.flatnonzero(lit)[np.argmax(de)]
    assert r["all"]["max_at"] == [int(i % preview.shape[1]), int(i // preview.shape[1])]
    assert r["all"]["max_luminance"] == pytest.approx(y[i], rel=1e-6)
    below = (y > 0) & ~lit
    assert r["all"]["below_floor"]["pixels"] == below.sum()
    assert r["all"]["black_pixels"] == (y <= 0).sum()
    # The conversion measured its spectra before half-float rounding: the same pixel is the
    # worst, by nearly the same amount.
    assert report["roundtrip"]["max_at"] == r["all"]["max_at"]
    assert report["roundtrip"]["max_de2000"] == pytest.approx(r["all"]["max_de2000"], abs=0.01)


def d50_srgb():
    """sRGB's primaries adapted to D50 by Bradford (as the ICC sRGB profile's colorants), by
    colour-science."""
    cs = colour.RGB_COLOURSPACES["sRGB"]
    d50 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D50"]
    xyz = colour.adaptation.chromatic_adaptation_VonKries(
        colour.xy_to_XYZ(cs.primaries), colour.xy_to_XYZ(cs.whitepoint), colour.xy_to_XYZ(d50),
        transform="Bradford")
    return colour.XYZ_to_xy(xyz), d50


def write_declared(path, primaries, white):
    """A 64 x 32 map of random colours with a `chromaticities` header, by OpenEXR's binding."""
    rng = np.random.default_rng(7)
    img = np.full((32, 64, 3), 0.5, np.float32)
    img[8:24] = rng.uniform(0.05, 1.0, (16, 64, 3)).astype(np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "chromaticities": tuple(float(v) for v in
                                      np.concatenate([np.ravel(primaries), white]))}
    with OpenEXR.File(header, {"RGB": img}) as f:
        f.write(str(path))
    return img


def xyz_from_spectra(path):
    """XYZ (Y = luminance) of every pixel's spectrum, by colour-science's reader and CMFs."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE).values
    _, image = colour.io.read_spectral_image_Fichet2021(str(path))["S0"]
    return image.reshape(-1, 81).astype(np.float64) @ cmfs / cmfs[:, 1].sum()


def run_convert(src, out, *args):
    p = subprocess.run([BIN, "convert", str(src), "-o", str(out), "--quiet", "--json",
                        "--precision", "float", *args], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def test_declared_chromaticities_are_honoured(tmp_path):
    """A map that declares D50-adapted sRGB: its spectra have the XYZ that colour-science's
    RGB_Colourspace of those primaries and white gives its RGB (no chromatic adaptation: a white
    pixel is D50), the output declares the same chromaticities, and `roundtrip` reads them."""
    primaries, white = d50_srgb()
    src = tmp_path / "d50.exr"
    rgb = write_declared(src, primaries, white).reshape(-1, 3).astype(np.float64)
    out = tmp_path / "d50.spectral.exr"
    report = run_convert(src, out)
    assert report["space"]["name"] == "declared"
    assert report["space"]["source"] == "file"
    assert report["space"]["white"].startswith("D50")
    with OpenEXR.File(str(out)) as f:
        declared = np.asarray(f.header()["chromaticities"], dtype=np.float64)
    np.testing.assert_allclose(declared, np.concatenate([np.ravel(primaries), white]), atol=1e-7)
    space = colour.RGB_Colourspace("D50 sRGB", primaries, white)
    want = rgb @ space.matrix_RGB_to_XYZ.T
    got = xyz_from_spectra(out)
    exact = report["spectra"]["nearest"] + report["spectra"]["clipped"] == 0
    assert exact, report["spectra"]
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-6)
    # Read as sRGB (what the attribute was ignored for), the same values are other colours.
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    assert np.abs(rgb @ srgb.matrix_RGB_to_XYZ.T - want).max() > 0.02
    r = json.loads(subprocess.run([BIN, "roundtrip", str(out), "--json"], capture_output=True,
                                  text=True).stdout)
    assert r["space"] == "declared"
    assert r["all"]["max_de2000"] < 1e-3, r["all"]


def test_space_overrides_the_declared_chromaticities_with_a_note(tmp_path):
    primaries, white = d50_srgb()
    src = tmp_path / "d50.exr"
    rgb = write_declared(src, primaries, white).reshape(-1, 3).astype(np.float64)
    out = tmp_path / "as-srgb.spectral.exr"
    report = run_convert(src, out, "--space", "srgb")
    assert report["space"]["name"] == "srgb" and report["space"]["source"] == "given"
    assert any("overrides the file's chromaticities" in n for n in report["notes"]), report["notes"]
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    m = colour.normalised_primary_matrix(srgb.primaries, srgb.whitepoint)
    np.testing.assert_allclose(xyz_from_spectra(out), rgb @ m.T, rtol=1e-4, atol=1e-6)


def test_acescg_chromaticities_name_acescg_and_its_white(tmp_path):
    """ACEScg declared by its AP1 primaries and ACES white (colour-science's): the report names
    the space and gives ACES white as RGB (1,1,1), not D65."""
    cs = colour.RGB_COLOURSPACES["ACEScg"]
    src = tmp_path / "acescg.exr"
    rgb = write_declared(src, cs.primaries, cs.whitepoint).reshape(-1, 3).astype(np.float64)
    out = tmp_path / "acescg.spectral.exr"
    report = run_convert(src, out)
    assert report["space"]["name"] == "acescg"
    x, y = cs.whitepoint
    assert report["space"]["white"] == f"ACES white (x {x:.5f}, y {y:.5f})"
    assert report["white"]["premise"] == "space"
    np.testing.assert_allclose(xyz_from_spectra(out), rgb @ cs.matrix_RGB_to_XYZ.T,
                               rtol=1e-4, atol=1e-6)
    text = subprocess.run([BIN, "convert", str(src), "-o", str(tmp_path / "t.exr")],
                          capture_output=True, text=True).stdout
    assert "RGB (1,1,1) is the space's white, ACES white (x 0.32168, y 0.33767)" in text, text
    assert "D65 white" not in text
