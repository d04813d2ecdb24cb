"""specmap.spectrum / Spectrum / xyz / fit against independent references: the CSV tables in
spectra/, the CLI built from the same tree, and colour-science's interpolators and
integration (never outputs captured from this package)."""

import csv
import json
import os
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest

import specmap

ROOT = Path(__file__).resolve().parents[2]
SPECTRA = ROOT / "spectra"

OBSERVERS = {
    "CIE 1931": "CIE 1931 2 Degree Standard Observer",
    "CIE 1964": "CIE 1964 10 Degree Standard Observer",
}


@pytest.fixture(scope="module")
def colour():
    """colour-science, its import-time and alignment warnings silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mod = pytest.importorskip("colour")
    return mod


@pytest.fixture(autouse=True)
def _quiet_colour():
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", module="colour")
        warnings.filterwarnings("ignore", message=".*Aligning.*")
        yield


def read_csv(path):
    """A spectral CSV as (header, wavelengths, {column: values}), read with the csv module."""
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and r[0].strip()]
    header = [h for h in rows[0] if h.strip()]
    data = [[float(x) for x in r[: len(header)]] for r in rows[1:]]
    a = np.array(data, dtype=np.float64)
    return header, a[:, 0], {h: a[:, i] for i, h in enumerate(header) if i > 0}


def data_show(cli, name, *extra):
    return json.loads(cli("data", "show", name, "--format", "json", *extra))


# --- spectrum -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name", ["D65", "A", "FL2", "FL3.7", "LED-B1", "lps", "hps", "colorchecker:red", "cie1931:y"]
)
def test_spectrum_equals_cli_data_show(cli, name):
    shown = data_show(cli, name)
    s = specmap.spectrum(name)
    (column, values), = shown["columns"].items()
    assert s.wavelengths.dtype == np.float64 and s.values.dtype == np.float64
    assert s.wavelengths.tolist() == shown["wavelengths_nm"]
    assert s.values.tolist() == values
    assert s.kind == shown["kind"]
    assert len(s) == len(values)
    assert s.name == (name if ":" not in name else f"{shown['name']}:{column}")


@pytest.mark.parametrize(
    "path, column",
    [
        ("illuminant/FL2.csv", "FL2"),
        ("illuminant/D65.csv", "D65"),
        ("light/lps.csv", "lps"),
        ("reflectance/colorchecker.csv", "blue"),
        ("cmf/cie1964.csv", "z"),
    ],
)
def test_spectrum_equals_the_csv_tables(path, column):
    _, w, cols = read_csv(SPECTRA / path)
    table = Path(path).stem
    builtin = specmap.spectrum(table if len(cols) == 1 else f"{table}:{column}")
    assert np.array_equal(builtin.wavelengths, w)
    assert np.array_equal(builtin.values, cols[column])
    # The same file by path (str and pathlib.Path): the values as tabulated, no kind.
    by_path = str(SPECTRA / path) + ("" if len(cols) == 1 else f":{column}")
    for src in (by_path, Path(by_path)) if len(cols) == 1 else (by_path,):
        s = specmap.spectrum(src)
        assert np.array_equal(s.wavelengths, w) and np.array_equal(s.values, cols[column])
        assert s.kind is None


def test_spectrum_repr_array_and_kinds():
    d65 = specmap.spectrum("d65")  # case-insensitive
    assert repr(d65) == "Spectrum('D65', kind='illuminant', 300..780 nm, 97 samples)"
    assert np.asarray(d65) is not None and np.array_equal(np.asarray(d65), d65.values)
    assert np.array_equal(np.asarray(d65, dtype=np.float32), d65.values.astype(np.float32))
    assert d65.is_light and specmap.spectrum("lps").is_light
    assert not specmap.spectrum("colorchecker:red").is_light
    s = specmap.Spectrum("mine", [400, 500], [1, 2])
    assert s.wavelengths.dtype == np.float64 and s.kind is None
    with pytest.raises(ValueError):
        specmap.Spectrum("bad", [400, 500, 600], [1, 2])
    with pytest.raises(ValueError):
        specmap.Spectrum("bad", [500, 400], [1, 2])


# --- resampling -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name, interp",
    [
        ("FL2", None),  # a light: linear
        ("colorchecker:red", None),  # a reflectance: Sprague (CIE 167)
        ("FL2", "cie167"),
        ("colorchecker:red", "linear"),
        ("cie1931:x", None),
        ("lps", None),
    ],
)
def test_resampled_equals_cli_data_show_range(cli, name, interp):
    extra = ["--range", "371:803:1.5"] + (["--interp", interp] if interp else [])
    shown = data_show(cli, name, *extra)
    (values,) = shown["columns"].values()
    s = specmap.spectrum(name, wavelengths=shown["wavelengths_nm"], interpolation=interp)
    assert s.wavelengths.tolist() == shown["wavelengths_nm"]
    assert s.values.tolist() == values
    assert s.kind == shown["kind"] and s.name == specmap.spectrum(name).name


def test_linear_resampling_equals_colour_linear_interpolator(colour):
    fl2 = specmap.spectrum("FL2")  # an illuminant: linear by default
    rng = np.random.default_rng(1)
    at = np.sort(rng.uniform(fl2.wavelengths[0], fl2.wavelengths[-1], 300))
    ours = specmap.spectrum("FL2", wavelengths=at).values
    theirs = colour.LinearInterpolator(fl2.wavelengths, fl2.values)(at)
    np.testing.assert_allclose(ours, theirs, rtol=1e-13, atol=1e-13)
    # Outside the table the end values are held (colour's Constant extrapolation).
    out = specmap.spectrum("FL2", wavelengths=[100.0, 1000.0]).values
    assert out.tolist() == [fl2.values[0], fl2.values[-1]]


@pytest.mark.parametrize("name", ["colorchecker:red", "colorchecker:cyan", "cie1964:y", "D65"])
def test_cie167_resampling_equals_colour_sprague_interpolator(colour, name):
    s = specmap.spectrum(name)
    assert len(s) >= 6 and np.ptp(np.diff(s.wavelengths)) < 1e-9  # uniform: Sprague
    rng = np.random.default_rng(2)
    at = np.sort(rng.uniform(s.wavelengths[0], s.wavelengths[-1], 400))
    ours = specmap.spectrum(name, wavelengths=at, interpolation="cie167").values
    theirs = colour.SpragueInterpolator(s.wavelengths, s.values)(at)
    np.testing.assert_allclose(ours, theirs, rtol=1e-11, atol=1e-12 * np.abs(s.values).max())


def test_cie167_on_uneven_samples_is_a_not_a_knot_spline():
    interpolate = pytest.importorskip("scipy.interpolate")
    w = np.array([380.0, 400, 430, 445, 470, 520, 560, 600, 640, 700, 780])
    v = np.sin(w / 60.0) + 2.0
    uneven = specmap.Spectrum("uneven", w, v)
    at = np.linspace(380.0, 780.0, 97)
    ours = specmap.spectrum(uneven, wavelengths=at).values  # kind None: cie167
    theirs = interpolate.CubicSpline(w, v, bc_type="not-a-knot")(at)
    np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-12)


def test_resample_method_and_bad_interpolation():
    red = specmap.spectrum("colorchecker:red")
    at = np.arange(400.0, 701.0, 7.0)
    assert np.array_equal(
        red.resample(at).values, specmap.spectrum("colorchecker:red", wavelengths=at).values
    )
    with pytest.raises(ValueError, match="linear"):
        specmap.spectrum("D65", wavelengths=at, interpolation="cubic")
    with pytest.raises(ValueError, match="increase"):
        specmap.spectrum("D65", wavelengths=at[::-1])


# --- colour round trip ----------------------------------------------------------------------


@pytest.mark.parametrize("name", ["FL2", "colorchecker:red", "lps"])
def test_to_colour_round_trip(colour, name):
    s = specmap.spectrum(name)
    sd = s.to_colour()
    assert isinstance(sd, colour.SpectralDistribution)
    assert sd.name == s.name
    assert np.array_equal(sd.wavelengths, s.wavelengths) and np.array_equal(sd.values, s.values)
    back = specmap.spectrum(sd)
    assert np.array_equal(back.wavelengths, s.wavelengths)
    assert np.array_equal(back.values, s.values)
    assert back.name == s.name and back.kind is None
    # A light goes to colour with its linear interpolator, and comes back resampled the same.
    assert (sd.interpolator is colour.LinearInterpolator) == s.is_light
    at = np.arange(372.5, 790.0, 2.5)
    assert np.array_equal(
        specmap.spectrum(sd, wavelengths=at).values, specmap.spectrum(name, wavelengths=at).values
    )
    # colour resamples it as specmap does, inside the table's range.
    inside = at[(at >= s.wavelengths[0]) & (at <= s.wavelengths[-1])]
    np.testing.assert_allclose(
        sd.copy()[inside], specmap.spectrum(s, wavelengths=inside).values, rtol=1e-11, atol=1e-13
    )


def test_spectrum_of_colour_objects_keeps_values(colour):
    a = colour.SDS_ILLUMINANTS["A"]  # colour's own A: 100 at 560 nm, not renormalised
    s = specmap.spectrum(a)
    assert s.name == a.name and s.kind is None
    assert np.array_equal(s.values, a.values) and np.array_equal(s.wavelengths, a.wavelengths)
    sd = colour.SpectralDistribution({400: 0.25, 500: 0.5, 600: 0.125})
    assert specmap.spectrum(sd).values.tolist() == [0.25, 0.5, 0.125]
    s.values[0] = -1.0  # a copy, not a view of colour's array
    assert a.values[0] != -1.0


# --- xyz ------------------------------------------------------------------------------------


def colour_cmfs(colour, observer, wl):
    cmfs = colour.MSDS_CMFS[OBSERVERS[observer]]
    idx = np.searchsorted(cmfs.wavelengths, wl)
    assert np.array_equal(cmfs.wavelengths[idx], wl)
    return colour.MultiSpectralDistributions(cmfs.values[idx], wl)


@pytest.mark.parametrize("observer", ["CIE 1931", "CIE 1964"])
@pytest.mark.parametrize("illuminant", ["D65", "A"])
@pytest.mark.parametrize("step", [5.0, 1.0])
def test_xyz_of_reflectances_equals_colour_integration(colour, observer, illuminant, step):
    wl = np.arange(380.0, 780.0 + step / 2, step)
    shape = colour.SpectralShape(380, 780, step)
    patches = ["red", "green", "blue", "yellow", "magenta", "cyan"]
    r = np.stack(
        [specmap.spectrum(f"colorchecker:{p}", wavelengths=wl).values for p in patches]
    ).reshape(2, 3, len(wl))
    light = specmap.spectrum(illuminant, wavelengths=wl)
    cmfs = colour_cmfs(colour, observer, wl)
    theirs = colour.sd_to_XYZ(
        r, cmfs, light.to_colour(), method="Integration", shape=shape
    )
    ours = specmap.xyz(r, wl, light=light.values, observer=observer)
    assert ours.shape == (2, 3, 3) and ours.dtype == np.float64
    np.testing.assert_allclose(ours, theirs, rtol=1e-12)
    # 1-D: one spectrum -> (3,)
    one = specmap.xyz(r[1, 2], wl, light=light.values, observer=observer)
    assert one.shape == (3,)
    np.testing.assert_allclose(one, theirs[1, 2], rtol=1e-12)
    # The light as a name, a Spectrum or a colour SD: resampled onto wl, the same XYZ.
    for form in (illuminant, specmap.spectrum(illuminant), specmap.spectrum(illuminant).to_colour()):
        np.testing.assert_array_equal(specmap.xyz(r, wl, light=form, observer=observer), ours)
    # A light's own SD (colour's default Sprague interpolator) is resampled linearly all the
    # same, as fit() resamples its light.
    raw = specmap.spectrum(illuminant)
    linear = colour.LinearInterpolator(raw.wavelengths, raw.values)(wl)
    np.testing.assert_allclose(
        specmap.xyz(r, wl, light=colour.SpectralDistribution(raw.values, raw.wavelengths),
                    observer=observer),
        specmap.xyz(r, wl, light=linear, observer=observer), rtol=1e-13,
    )
    # Eq. 11: a perfect white has Y = 100.
    np.testing.assert_allclose(
        specmap.xyz(np.ones(len(wl)), wl, light=illuminant, observer=observer)[1], 100.0,
        rtol=1e-13,
    )


@pytest.mark.parametrize("observer", ["CIE 1931", "CIE 1964"])
def test_xyz_of_lights_with_k_equals_colour(colour, observer):
    wl = np.arange(380.0, 781.0, 5.0)
    shape = colour.SpectralShape(380, 780, 5)
    lights = np.stack(
        [specmap.spectrum(n, wavelengths=wl).values for n in ["FL2", "A", "lps", "D65", "FL11", "E"]]
    ).reshape(2, 3, len(wl))
    cmfs = colour_cmfs(colour, observer, wl)
    ones = colour.sd_ones(shape)
    # colour divides by 100 when k is given ("as percentage"); specmap's Y is k * integral.
    theirs = 100 * colour.sd_to_XYZ(
        lights, cmfs, ones, k=683.002, method="Integration", shape=shape
    )
    ours = specmap.xyz(lights, wl, k=683.002, observer=observer)
    assert ours.shape == (2, 3, 3)
    np.testing.assert_allclose(ours, theirs, rtol=1e-12)
    np.testing.assert_allclose(
        specmap.xyz(lights[0, 0], wl, k=683.002, observer=observer), theirs[0, 0], rtol=1e-12
    )
    # k defaults to 1.
    np.testing.assert_allclose(
        specmap.xyz(lights, wl, observer=observer), theirs / 683.002, rtol=1e-12
    )


def test_xyz_errors():
    wl = np.arange(380.0, 781.0, 5.0)
    r = np.full((4, len(wl)), 0.5)
    uneven = wl.copy()
    uneven[10] += 1.0
    with pytest.raises(ValueError, match="uniformly spaced"):
        specmap.xyz(r, uneven, light="D65")
    with pytest.raises(ValueError, match="last axis"):
        specmap.xyz(r[:, :-1], wl, light="D65")
    with pytest.raises(ValueError, match="last axis"):
        specmap.xyz(r.T, wl)
    with pytest.raises(ValueError):
        specmap.xyz(r, wl, light=np.ones(len(wl) - 1))
    with pytest.raises(ValueError):
        specmap.xyz(r, wl, light="D65", k=683.002)
    with pytest.raises(ValueError, match="observer"):
        specmap.xyz(r, wl, observer="CIE 2015")
    with pytest.raises(ValueError, match="rule"):
        specmap.xyz(r, wl, rule="gauss")
    with pytest.raises(ValueError, match="did you mean"):
        specmap.xyz(r, wl, light="D66")


# --- fit ------------------------------------------------------------------------------------


def srgb_npm(colour):
    """sRGB's RGB -> XYZ matrix derived from its primaries and D65's xy."""
    cs = colour.RGB_COLOURSPACES["sRGB"]
    return colour.normalised_primary_matrix(cs.primaries, cs.whitepoint)


@pytest.fixture(scope="module")
def fl2_exact():
    return specmap.fit("FL2", mode="exact")


def test_fit_equals_cli(cli, fl2_exact):
    f = fl2_exact
    report = cli("fit", "--light", "FL2", "--mode", "exact", "--json")
    assert f.weights.tolist() == report["weights"]
    assert f.roundtrip == report["roundtrip"]
    assert f.matrix.tolist() == report["matrix"]
    assert f.light_rgb.tolist() == report["light_rgb"]
    assert f.report == report
    assert (f.light, f.mode, f.space, f.observer, f.rule) == (
        "FL2", "exact", "srgb", "cie1931", "riemann"
    )
    assert f.basis_names == ("colorchecker:red", "colorchecker:green", "colorchecker:blue")
    assert f.condition_number == report["condition_number"] and f.regularized is False
    assert f.pixel is None and f.lost_information is None


def test_fit_file_equals_cli(cli, tmp_path, fl2_exact):
    out = tmp_path / "fit.json"
    cli("fit", "--light", "FL2", "--mode", "exact", "-o", out)
    written = json.loads(out.read_text())
    assert fl2_exact.data == written
    assert fl2_exact.basis.tolist() == written["basis_reflectance"]
    assert fl2_exact.light_spd.tolist() == written["light_spd"]
    mine = tmp_path / "mine.json"
    fl2_exact.save(mine)
    assert json.loads(mine.read_text()) == written


def test_fit_grid_and_spectra(fl2_exact):
    f = fl2_exact
    wl = np.arange(380.0, 781.0, 1.0)
    assert np.array_equal(f.wavelengths, wl)
    assert f.basis.shape == (3, len(wl)) and f.weights.shape == (3,) and f.matrix.shape == (3, 3)
    # The light linear, the basis by CIE 167, both from the tables.
    np.testing.assert_allclose(f.light_spd, specmap.spectrum("FL2", wavelengths=wl).values,
                               rtol=1e-14, atol=1e-14)
    for row, patch in zip(f.basis, ["red", "green", "blue"]):
        np.testing.assert_allclose(
            row, specmap.spectrum(f"colorchecker:{patch}", wavelengths=wl).values,
            rtol=1e-13, atol=1e-15,
        )
    np.testing.assert_allclose(
        f.weighted_basis, f.weights[:, None] * f.basis * f.light_spd, rtol=0, atol=0
    )


def test_fit_round_trip_is_really_exact(colour, fl2_exact):
    f = fl2_exact
    wl, s = f.wavelengths, f.light_spd
    white = specmap.xyz(np.ones(len(wl)), wl, light=s)
    # The paper's weights: w @ basis under the light has the light's colour (Eq. 10/11).
    np.testing.assert_allclose(specmap.xyz(f.weights @ f.basis, wl, light=s), white, rtol=1e-12)
    np.testing.assert_allclose(f.weighted_basis.sum(axis=0) / s, f.weights @ f.basis, rtol=1e-12)
    # light_rgb is the light's sRGB at Y = 1.
    to_rgb = np.linalg.inv(srgb_npm(colour))
    np.testing.assert_allclose(to_rgb @ (white / 100), f.light_rgb, rtol=1e-9)
    # Exact mode: a = W rgb, the spectrum's RGB white-balanced to the light is rgb again.
    rng = np.random.default_rng(3)
    rgb = np.vstack([np.eye(3), rng.uniform(0, 1, (20, 3))])
    refl = (rgb @ f.matrix.T) @ f.basis  # (23, N): sum_j a_j MCC_j
    back = (specmap.xyz(refl, wl, light=s) / 100) @ to_rgb.T / f.light_rgb
    np.testing.assert_allclose(back, rgb, atol=1e-9)
    # ... and not so in paper mode (W = diag(w)): only white comes back.
    paper = specmap.fit("FL2")
    assert np.array_equal(paper.weights, f.weights)
    assert np.array_equal(paper.matrix, np.diag(paper.weights))
    p = (specmap.xyz((rgb @ paper.matrix.T) @ paper.basis, wl, light=s) / 100) @ to_rgb.T
    assert np.abs(p / paper.light_rgb - rgb).max() > 1e-3
    np.testing.assert_allclose(
        to_rgb @ (specmap.xyz(paper.weights @ paper.basis, wl, light=s) / 100) / paper.light_rgb,
        [1.0, 1.0, 1.0], rtol=1e-9,
    )


def test_fit_options_equal_cli(cli):
    f = specmap.fit(
        "D65", mode="nonneg", space="display-p3", wavelengths=range(380, 781, 5),
        observer="CIE 1964", rule="simpson", rgb=[1.0, 0.5, 0.2],
    )
    report = cli(
        "fit", "--light", "D65", "--mode", "nonneg", "--space", "display-p3", "--range",
        "380:780:5", "--observer", "cie1964", "--rule", "simpson", "--rgb", "1,0.5,0.2", "--json",
    )
    assert f.report == report
    assert f.pixel == report["pixel"] and f.pixel is not None
    assert np.array_equal(f.wavelengths, np.arange(380.0, 781.0, 5.0))
    # The grid as an array and as text mean the same.
    for grid in (np.arange(380.0, 781.0, 5.0), "380:780:5"):
        assert specmap.fit("D65", wavelengths=grid).report == cli(
            "fit", "--light", "D65", "--range", "380:780:5", "--json"
        )


def test_fit_of_a_spectrum_equals_fit_of_the_name(colour, tmp_path, monkeypatch, fl2_exact):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    by_spectrum = specmap.fit(specmap.spectrum("FL2"), mode="exact")
    by_sd = specmap.fit(specmap.spectrum("FL2").to_colour(), mode="exact")
    for f in (by_spectrum, by_sd):
        assert f.light == "FL2"
        assert np.array_equal(f.weights, fl2_exact.weights)
        assert np.array_equal(f.matrix, fl2_exact.matrix)
        assert f.roundtrip == fl2_exact.roundtrip
    basis = [specmap.spectrum(f"colorchecker:{p}").to_colour() for p in ("red", "green", "blue")]
    with_basis = specmap.fit("FL2", mode="exact", basis=basis)
    assert np.array_equal(with_basis.weights, fl2_exact.weights)
    assert list(tmp_path.iterdir()) == []  # the temporary CSVs are gone


def test_fit_of_a_spectrum_keeps_every_digit(tmp_path):
    rng = np.random.default_rng(4)
    wl = np.arange(360.0, 831.0, 2.5)
    lamp = specmap.Spectrum("my lamp", wl, 1.0 + rng.uniform(0, 1, len(wl)) ** 3)
    path = tmp_path / "lamp.csv"
    with open(path, "w") as f:
        f.write("wavelength_nm,spd\n")
        f.writelines(f"{w!r},{v!r}\n" for w, v in zip(wl.tolist(), lamp.values.tolist()))
    by_file = specmap.fit(path, mode="exact")
    by_spectrum = specmap.fit(lamp, mode="exact")
    assert by_spectrum.light == "my_lamp" and by_file.light == "lamp"
    assert np.array_equal(by_spectrum.light_spd, by_file.light_spd)
    assert np.array_equal(by_spectrum.weights, by_file.weights)
    assert np.array_equal(by_spectrum.matrix, by_file.matrix)
    np.testing.assert_allclose(
        by_file.light_spd, specmap.spectrum(lamp, wavelengths=by_file.wavelengths,
                                            interpolation="linear").values, rtol=1e-14
    )


def test_fit_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        specmap.fit(str(tmp_path / "missing.csv"))
    with pytest.raises(FileNotFoundError):
        specmap.fit(tmp_path / "missing")
    with pytest.raises(ValueError, match="did you mean"):
        specmap.fit("D66")
    with pytest.raises(ValueError):
        specmap.fit("D65", mode="exactly")
    with pytest.raises(ValueError):
        specmap.fit("D65", space="adobe")
    with pytest.raises(ValueError, match="three"):
        specmap.fit("D65", basis=["colorchecker:red"])
    with pytest.raises(ValueError, match="uniformly spaced"):
        specmap.fit("D65", wavelengths=[380.0, 400.0, 410.0])


# --- spectrum errors ------------------------------------------------------------------------


def test_missing_csv_is_file_not_found(tmp_path):
    for missing in (str(tmp_path / "missing.csv"), tmp_path / "missing.csv", tmp_path / "lamp",
                    "missing.csv"):
        with pytest.raises(FileNotFoundError):
            specmap.spectrum(missing)


def test_unknown_names_are_value_errors_with_suggestions():
    with pytest.raises(ValueError, match=r"no built-in table named 'D66'.*did you mean.*D65"):
        specmap.spectrum("D66")
    with pytest.raises(ValueError, match=r"no column 'redd'.*did you mean red"):
        specmap.spectrum("colorchecker:redd")
    with pytest.raises(ValueError, match="name one"):
        specmap.spectrum("colorchecker")
    with pytest.raises(TypeError):
        specmap.spectrum(42)  # type: ignore[arg-type]


def test_a_bad_csv_is_a_value_error(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("wavelength_nm,x\n400,1\n500,oops\n")
    with pytest.raises(ValueError):
        specmap.spectrum(bad)
