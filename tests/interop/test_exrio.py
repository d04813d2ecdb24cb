"""specmap's spectral OpenEXR output read by independent readers (OpenEXR's Python binding and
colour-science's Fichet 2021 channel parsing), and its RGB EXR input against OpenEXR's decoder.

The Rust side is `examples/write_spectral.rs`: pixel (x, y), band k of the wavelengths
382.5, 400, 450, ..., 700 nm holds 0.5 (x + 1) + 0.25 y + 0.125 k; the preview R = x, G = y, B = 1.
"""
import os
import pathlib
import re
import subprocess

import numpy as np
import pytest

import OpenEXR
from colour.io import fichet2021

ROOT = pathlib.Path(__file__).resolve().parents[2]
WAVELENGTHS = [382.5] + [400.0 + 50.0 * i for i in range(7)]
WIDTH, HEIGHT = 8, 5
COMPRESSIONS = ["none", "rle", "zip", "zips", "piz", "pxr24", "b44", "b44a"]


# tools/test.sh builds the examples before pytest and names the binary; by hand, cargo builds it.
WRITE_SPECTRAL = os.environ.get("SPECMAP_WRITE_SPECTRAL")


def example(*args):
    command = [WRITE_SPECTRAL] if WRITE_SPECTRAL else [
        "cargo", "run", "-q", "--example", "write_spectral", "--"]
    p = subprocess.run([*command, *map(str, args)], cwd=ROOT, capture_output=True, text=True)
    if p.returncode != 0:
        pytest.fail(f"write_spectral {' '.join(map(str, args))} exited {p.returncode}: {p.stderr}")
    return p.stdout


def expected_band(k):
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH]
    return 0.5 * (x + 1) + 0.25 * y + 0.125 * k


def fichet_wavelengths(channel_names):
    """colour-science's own emissive-channel parsing (Specification_Fichet2021)."""
    pattern = re.compile(rf"^(S[0-3])\.*{fichet2021.PATTERN_FICHET2021}$")
    found = {}
    for name in channel_names:
        m = pattern.match(name)
        if m is not None:
            assert m.group(1) == "S0"
            found[name] = fichet2021.match_groups_to_nm(m.group(2), m.group(4), m.group(5))
    return found


@pytest.mark.parametrize("precision", ["half", "float"])
@pytest.mark.parametrize("compression", COMPRESSIONS)
def test_openexr_reads_the_spectral_layout(tmp_path, precision, compression):
    out = tmp_path / f"s-{precision}-{compression}.exr"
    example(out, precision, compression)
    f = OpenEXR.File(str(out), separate_channels=True)
    header = f.header()
    assert header["spectralLayoutVersion"] == "1.0"
    assert header["emissiveUnits"] == "W.m^-2.sr^-1"
    assert header["envmap"] == OpenEXR.ENVMAP_LATLONG
    assert header["lineOrder"] == OpenEXR.INCREASING_Y
    assert header["mainLight"] == "D65"
    assert header["fitMode"] == "exact"
    assert float(np.asarray(header["fitScale"]).ravel()[0]) == 1.5
    assert list(header["fitWeights"]) == [0.25, 0.5, 2.0]

    channels = f.channels()
    names = set(channels)
    spectral = {"S0." + f"{wl:.6f}".replace(".", ",") + "nm" for wl in WAVELENGTHS}
    assert spectral == {n for n in names if n.startswith("S0.")}
    assert "S0.382,500000nm" in names and "S0.550,000000nm" in names
    assert {"R", "G", "B"} <= names
    parsed = fichet_wavelengths(names)
    assert sorted(parsed.values()) == WAVELENGTHS

    lossy = compression in ("b44", "b44a") and precision == "half"
    for name, wl in parsed.items():
        k = WAVELENGTHS.index(wl)
        pixels = channels[name].pixels
        assert pixels.dtype == (np.float16 if precision == "half" else np.float32)
        assert pixels.shape == (HEIGHT, WIDTH)
        if lossy:
            np.testing.assert_allclose(pixels, expected_band(k), rtol=0.05)
        else:
            np.testing.assert_array_equal(pixels.astype(np.float64), expected_band(k))
    if not lossy:
        y, x = np.mgrid[0:HEIGHT, 0:WIDTH]
        np.testing.assert_array_equal(channels["R"].pixels, x)
        np.testing.assert_array_equal(channels["G"].pixels, y)
        np.testing.assert_array_equal(channels["B"].pixels, np.ones_like(x))


@pytest.mark.parametrize("precision", ["half", "float"])
def test_colour_science_reader(tmp_path, precision):
    """colour-science's full reader (it needs OpenImageIO: skipped where that is missing)."""
    pytest.importorskip("OpenImageIO")
    out = tmp_path / "s.exr"
    example(out, precision, "piz")
    components, spec = fichet2021.read_spectral_image_Fichet2021(str(out), additional_data=True)
    assert spec.is_emissive and not spec.is_polarised and not spec.is_bispectral
    attributes = {a.name: a.value for a in spec.attributes}
    assert attributes["spectralLayoutVersion"] == "1.0"
    assert attributes["emissiveUnits"] == "W.m^-2.sr^-1"
    assert list(components) == ["S0"]
    wavelengths, values = components["S0"]
    order = np.argsort(wavelengths)
    np.testing.assert_array_equal(np.asarray(wavelengths)[order], WAVELENGTHS)
    for i, k in enumerate(order):
        np.testing.assert_array_equal(values[:, :, k], expected_band(i))


@pytest.mark.parametrize("name", ["forest.exr", "sunrise.exr"])
def test_read_rgb_matches_openexr(name):
    path = ROOT / "envmaps" / name
    width, height, *sums = example("--rgb-sums", path).split()
    f = OpenEXR.File(str(path), separate_channels=True)
    channels = f.channels()
    assert (int(width), int(height)) == (1024, 512)
    for value, c in zip(sums, "RGB"):
        pixels = channels[c].pixels
        assert pixels.shape == (512, 1024)
        assert float(value) == pytest.approx(pixels.astype(np.float64).sum(), rel=1e-12)
