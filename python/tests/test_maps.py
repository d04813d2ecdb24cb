"""specmap.inspect, convert, read_spectral and upsample against the CLI (bit for bit where the
computation is the same), OpenEXR's own reader, colour-science's Fichet (2021) reader and
colour-science's colorimetry."""

import numpy as np
import OpenEXR
import pytest

import colour
import specmap

SHAPE = colour.SpectralShape(380, 780, 5)
TIMING = ("seconds_read", "seconds_analyse", "seconds_plan", "seconds_convert", "seconds_encode",
          "megapixels_per_second")


def read_openexr(path):
    """Channels by OpenEXR's own binding (before colour's reader loads OpenImageIO's copy)."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {name: c.pixels for name, c in f.channels().items()}


def bands_of(channels, wavelengths):
    names = {float(n[3:-2].replace(",", ".")): n for n in channels if n.startswith("S0.")}
    return np.stack([channels[names[w]] for w in wavelengths], -1)


def rgb_of(spectra, space="sRGB"):
    """Linear RGB of radiance spectra on SHAPE at specmap's scale Y = sum(L ybar) / sum(ybar),
    by colour-science's CMFs and primaries."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE).values
    xyz = spectra.astype(np.float64) @ cmfs / cmfs[:, 1].sum()
    cs = colour.RGB_COLOURSPACES[space]
    npm = colour.normalised_primary_matrix(cs.primaries, cs.whitepoint)
    return xyz @ np.linalg.inv(npm).T


def without(report, *keys):
    return {k: v for k, v in report.items() if k not in keys}


def test_convert_in_memory_is_the_cli_float_file_bit_for_bit(cli, sunrise, tmp_path):
    out = tmp_path / "s.exr"
    want = cli("convert", sunrise, "-o", out, "--precision", "float", "--quiet", "--json")
    got = specmap.convert(sunrise, precision="float")
    channels = read_openexr(out)
    np.testing.assert_array_equal(got["wavelengths"], want["wavelengths_nm"])
    np.testing.assert_array_equal(got["spectra"], bands_of(channels, got["wavelengths"]))
    for i, c in enumerate("RGB"):
        np.testing.assert_array_equal(got["rgb"][..., i], channels[c])
    np.testing.assert_array_equal(got["sun"], channels["sun"])
    assert got["sun"].sum() > 0, "sunrise has a sun"
    # The report is the CLI's but for the file (none written) and the timings.
    file_keys = ("output", "bytes", "wavelengths", "spectra", "rgb", "sun", "wavelengths_nm")
    assert without(got, *TIMING, *file_keys) == without(want, *TIMING, *file_keys)
    assert got["bytes"] == 0 and got["output"] == ""


def test_convert_to_a_file_writes_what_the_cli_writes(cli, forest, tmp_path):
    mine, theirs = tmp_path / "py.exr", tmp_path / "cli.exr"
    flags = ("--mode", "exact", "--light", "D65", "--compression", "piz")
    want = cli("convert", forest, "-o", theirs, *flags, "--quiet", "--json")
    got = specmap.convert(forest, mine, mode="exact", light="D65", compression="piz")
    assert without(got, *TIMING, "output") == without(want, *TIMING, "output")
    a, b = read_openexr(mine), read_openexr(theirs)
    assert a.keys() == b.keys()
    for name in a:
        np.testing.assert_array_equal(a[name], b[name])


def test_inspect_is_the_cli_json(cli, sunrise, tmp_path):
    want = cli("inspect", sunrise, "--light", "auto", "--json")
    got = specmap.inspect(sunrise, light="auto")
    assert got == want
    overlay = tmp_path / "lights.png"
    got = specmap.inspect(sunrise, overlay=overlay)
    assert overlay.stat().st_size > 0 and got["overlay"] is not None


def write_rgb(path, rgb):
    """An RGB OpenEXR by OpenEXR's own binding."""
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": np.ascontiguousarray(rgb, dtype=np.float32)}) as f:
        f.write(str(path))


@pytest.mark.parametrize("scale,precision", [(1.0, "float"), (1e6, "half")])
def test_read_spectral_agrees_with_colour_science(cli, tmp_path, scale, precision):
    # A map beyond half's range (65504) is written as half with an EV scale in its header.
    source, out = tmp_path / "bright.exr", tmp_path / "f.exr"
    write_rgb(source, np.random.default_rng(3).random((16, 32, 3)) * scale)
    cli("convert", source, "-o", out, "--precision", precision, "--sun", "off", "--quiet")
    wavelengths, spectra, rgb = specmap.read_spectral(out, with_rgb=True)
    channels = read_openexr(out)
    with OpenEXR.File(str(out)) as f:
        ev = float(f.header().get("EV", 0.0))
    assert (ev != 0.0) == (precision == "half")
    np.testing.assert_array_equal(rgb[..., 1], channels["G"] * np.float32(2.0**ev))
    w, image = colour.io.read_spectral_image_Fichet2021(str(out))["S0"]
    np.testing.assert_array_equal(wavelengths, w)
    # colour applies no EV scale: the file stores values / 2^EV.
    np.testing.assert_array_equal(spectra, (image * 2.0**ev).astype(np.float32))


def test_read_spectral_reads_a_file_colour_science_wrote(tmp_path):
    rng = np.random.default_rng(1)
    w = np.arange(400.0, 701.0, 50.0)
    image = rng.random((6, 12, len(w))).astype(np.float32)
    path = str(tmp_path / "colour.exr")
    colour.io.write_spectral_image_Fichet2021({"S0": (w, image)}, path)
    got_w, got = specmap.read_spectral(path)
    np.testing.assert_array_equal(got_w, w)
    np.testing.assert_array_equal(got, image)


def test_upsample_is_the_colour_for_any_array_and_never_negative():
    rng = np.random.default_rng(7)
    rgb = rng.random((3, 50, 3)) * np.array([1.0, 0.8, 1.2]) + 1e-3
    wl, spectra = specmap.upsample(rgb)
    np.testing.assert_array_equal(wl, SHAPE.wavelengths)
    assert spectra.shape == (3, 50, 81) and spectra.dtype == np.float32
    assert spectra.min() >= 0.0
    np.testing.assert_allclose(rgb_of(spectra), rgb, rtol=2e-4, atol=1e-6)


@pytest.mark.parametrize("light", ["A", "FL11", "D65"])
def test_upsample_under_a_named_light_is_its_spd_for_its_own_colour(light):
    sd = specmap.spectrum(light, wavelengths=SHAPE.wavelengths)
    white = rgb_of(sd.values[None, :])[0]
    colours = np.array([white, white * 0.25, [0.3, 0.2, 0.1], [0.05, 0.1, 0.3]])
    wl, spectra = specmap.upsample(colours, light=light)
    assert spectra.min() >= 0.0
    np.testing.assert_allclose(rgb_of(spectra), colours, rtol=2e-4, atol=1e-6)
    # The light's own colour is the light's own SPD (scaled).
    ratio = spectra[0] / np.maximum(sd.values, 1e-12)
    np.testing.assert_allclose(ratio[sd.values > 1e-3 * sd.values.max()], ratio[40], rtol=1e-3)


def test_upsample_of_a_map_shaped_array_is_convert_of_the_file(sunrise):
    with OpenEXR.File(sunrise, separate_channels=True) as f:
        channels = f.channels()
        rgb = np.stack([channels[c].pixels for c in "RGB"], -1).astype(np.float32)
    # The converter's nearest spectra (colours no light of the map makes) and the negative
    # values it set to 0 (the CLI's report counts both) are said, not hidden.
    with pytest.warns(RuntimeWarning) as caught:
        wl, spectra = specmap.upsample(rgb)
    said = " ".join(str(w.message) for w in caught)
    assert "of 524288 colours" in said and "negative channel values were set to 0" in said
    want = specmap.convert(sunrise, precision="float")
    assert want["spectra"].shape == spectra.shape
    np.testing.assert_array_equal(wl, want["wavelengths"])
    np.testing.assert_array_equal(spectra, want["spectra"])


def test_upsample_in_another_space_and_on_another_grid():
    rgb = np.array([[0.5, 0.4, 0.3], [0.1, 0.6, 0.2]])
    wl, spectra = specmap.upsample(rgb, space="Rec2020", wavelengths=np.arange(400, 701, 10))
    np.testing.assert_array_equal(wl, np.arange(400, 701, 10))
    assert spectra.shape == (2, 31)
    shape = colour.SpectralShape(400, 700, 10)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape).values
    xyz = spectra.astype(np.float64) @ cmfs / cmfs[:, 1].sum()
    cs = colour.RGB_COLOURSPACES["ITU-R BT.2020"]
    npm = colour.normalised_primary_matrix(cs.primaries, cs.whitepoint)
    np.testing.assert_allclose(xyz, rgb @ npm.T, rtol=2e-4, atol=1e-6)


def test_an_impossible_colour_is_counted_and_warned():
    # Saturated red is no reflectance under a low-pressure sodium lamp (one line at 589 nm).
    with pytest.warns(RuntimeWarning, match="1 of 2 colours"):
        _, spectra = specmap.upsample([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]], light="lps")
    assert spectra.min() >= 0.0


def test_errors_are_python_exceptions_of_their_kind(sunrise, tmp_path):
    with pytest.raises(FileNotFoundError, match="no-such-map.exr"):
        specmap.convert(tmp_path / "no-such-map.exr")
    with pytest.raises(FileNotFoundError):
        specmap.read_spectral(tmp_path / "missing.exr")
    with pytest.raises(ValueError, match="precision"):
        specmap.convert(sunrise, precision="quad")
    with pytest.raises(ValueError, match="no_such_flag|no-such-flag"):
        specmap.inspect(sunrise, no_such_flag=1)
    with pytest.raises(ValueError, match="basis form"):
        specmap.convert(sunrise, format="basis")
    with pytest.raises(ValueError, match="last axis"):
        specmap.upsample(np.zeros((4, 4)))
    with pytest.raises(ValueError, match="finite"):
        specmap.upsample([[np.nan, 0.0, 0.0]])
    text = tmp_path / "text.exr"
    text.write_text("not an image")
    with pytest.raises(ValueError, match="text.exr"):
        specmap.read_spectral(text)
    with pytest.raises(ValueError, match="is the input"):
        specmap.convert(sunrise, sunrise)


def test_a_map_s_non_finite_and_negative_values_are_counted_not_hidden():
    rgb = np.full((8, 16, 3), 0.5, dtype=np.float32)
    rgb[0, 0, 0], rgb[1, 1, 1] = np.nan, np.inf
    rgb[2, 2] = -0.25  # no light at all: set to 0, where an out-of-gamut colour would be kept
    with pytest.warns(RuntimeWarning, match="2 NaN or infinite and 3 negative"):
        _, spectra = specmap.upsample(rgb)
    assert np.isfinite(spectra).all() and spectra.min() >= 0.0
