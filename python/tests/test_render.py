"""specmap.render against the CLI built from the same tree: the image bit for bit what
``specmap render -o x.exr`` writes (read back with the OpenEXR package), the report what
``--json`` prints but for its timings; the errors as Python exceptions of their kind; and, where
a GPU adapter exists (Mesa's lavapipe will do), the GPU within the project's GPU/CPU tolerance
of the CPU (tests/render.rs: mean CIEDE2000 below 0.5, max below 2)."""

import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import specmap
from specmap._options import argv_of

# The fields of the report that measure time (they differ between any two runs).
TIMINGS = ("prepare_s", "render_s", "gpu_timing")

# The GPU/CPU agreement tests/render.rs states: mean CIEDE2000 below 0.5, max below 2.
MEAN_TOL = 0.5
MAX_TOL = 2.0


def read_exr(path):
    """(H, W, 3) float32 R, G, B of an EXR, as the file holds them."""
    openexr = pytest.importorskip("OpenEXR")
    with openexr.File(str(path), separate_channels=True) as f:
        channels = f.channels()
        return np.stack([channels[c].pixels for c in "RGB"], axis=-1)


def cli_render(cli, tmp_path, options):
    """`specmap render ARGS -o x.exr --json`: the image written and the report printed."""
    out = tmp_path / "cli.exr"
    report = cli("render", *argv_of(options), "-o", out, "--json")
    return read_exr(out), report


def without(report, *keys):
    return {k: v for k, v in report.items() if k not in keys}


def assert_same_bits(ours, theirs):
    assert ours.shape == theirs.shape
    assert ours.dtype == theirs.dtype == np.float32
    differ = ours.view(np.uint32) != theirs.view(np.uint32)
    assert not differ.any(), (
        f"{differ.sum()} of {differ.size} values differ, first at "
        f"{np.argwhere(differ)[0]}: {ours[differ][0]} against the CLI's {theirs[differ][0]}"
    )


# (scene, options) rendered by both; a small size keeps the CPU quick.
CASES = {
    "ball": ("ball", {}),
    "ball-sunrise": ("ball", {"env": "sunrise"}),
    "coated-ball-exposure": (
        "ball",
        {"film": "1.38:100,2.1:130", "substrate": "bk7", "exposure": -1.5, "step": 10},
    ),
    "cylinders-sunrise-orbit": (
        "cylinders",
        {"env": "sunrise", "orbit": (120, 15), "zoom": 1.5, "samples": 41},
    ),
    "chart-meyer": ("chart", {"quadrature": "meyer", "background": "flat"}),
}


@pytest.mark.parametrize("case", CASES)
def test_cpu_image_and_report_are_the_clis(case, cli, tmp_path, sunrise):
    scene, extra = CASES[case]
    options = {"scene": scene, "backend": "cpu", "size": "48x32", **extra}
    if options.get("env") == "sunrise":
        options["env"] = sunrise
    image, report = specmap.render(**options)
    exr, cli_report = cli_render(cli, tmp_path, options)
    assert image.shape == (32, 48, 3) and image.flags.c_contiguous
    assert np.isfinite(image).all() and image.max() > 0
    assert_same_bits(image, exr)
    assert "output" not in report
    assert cli_report["output"] == str(tmp_path / "cli.exr")
    assert without(report, *TIMINGS) == without(cli_report, *TIMINGS, "output")
    assert report["backend"] == "cpu" and report["adapter"] is None
    assert report["scene"] == scene and report["size"] == [48, 32]
    assert (report["env"] is not None) == ("env" in extra)


def test_exposure_scales_the_image_as_the_exr(tmp_path):
    plain, _ = specmap.render(backend="cpu", size=(24, 16), step=20)
    brighter, report = specmap.render(backend="cpu", size=(24, 16), step=20, exposure=2)
    assert report["exposure_ev"] == 2.0
    np.testing.assert_array_equal(brighter, plain * np.float32(4))


def test_options_become_the_clis_flags():
    argv = argv_of(
        {
            "scene": "chart",
            "max_nodes": 8,
            "no_cache": True,
            "json": False,
            "env": None,
            "orbit": (120, -15.5),
            "exposure": -0.5,
            "size": "64x48",
        }
    )
    assert argv == [
        "--scene=chart",
        "--max-nodes=8",
        "--no-cache",
        "--orbit=120,-15.5",
        "--exposure=-0.5",
        "--size=64x48",
    ]
    assert argv_of({"kd": np.float64(0.25), "samples": np.int64(9)}) == [
        "--kd=0.25",
        "--samples=9",
    ]
    with pytest.raises(ValueError, match="orbit"):
        argv_of({"orbit": {1, 2}})


def test_defaults_are_the_clis(cli, tmp_path):
    # No options but the backend: the preset's own size, 81 wavelengths, D65.
    image, report = specmap.render(backend="cpu", size=None)
    exr, cli_report = cli_render(cli, tmp_path, {"backend": "cpu"})
    assert_same_bits(image, exr)
    assert report["scene"] == "ball" and report["wavelengths"] == 81
    assert without(report, *TIMINGS) == without(cli_report, *TIMINGS, "output")


def test_auto_chooses_the_backend_the_cli_chooses(cli, tmp_path):
    options = {"size": "16x16", "step": 20}
    _, report = specmap.render(**options)
    _, cli_report = cli_render(cli, tmp_path, options)
    assert report["backend"] == cli_report["backend"]
    assert report["adapter"] == cli_report["adapter"]


# --- errors ---------------------------------------------------------------------------------


def test_unknown_option_is_a_value_error():
    with pytest.raises(ValueError, match="--colour"):
        specmap.render(backend="cpu", colour="red")


def test_bad_value_is_a_value_error_naming_the_flag():
    with pytest.raises(ValueError, match="--backend"):
        specmap.render(backend="quantum")
    with pytest.raises(ValueError, match="--size"):
        specmap.render(backend="cpu", size="big")
    with pytest.raises(ValueError, match="exposure"):
        specmap.render(backend="cpu", exposure=100)


def test_missing_env_is_file_not_found(tmp_path):
    missing = tmp_path / "nowhere.exr"
    with pytest.raises(FileNotFoundError, match="nowhere.exr"):
        specmap.render(backend="cpu", size="8x8", env=missing)


@pytest.mark.parametrize(
    "options, says",
    [
        ({"sweep": [4, 9]}, "--sweep"),
        ({"turntable": 3}, "--turntable"),
        ({"film": "2.7:100..400", "frames": 3}, "thickness range"),
    ],
)
def test_many_images_are_refused(options, says, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match=says):
        specmap.render(backend="cpu", size="8x8", **options)
    assert list(tmp_path.iterdir()) == []


def test_no_file_is_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    specmap.render(backend="cpu", size="8x8", step=20)
    with pytest.raises(ValueError, match="returned, not written"):
        specmap.render(backend="cpu", size="8x8", output=tmp_path / "x.exr")
    assert list(tmp_path.iterdir()) == []


# --- the GPU --------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def gpu_ready():
    """Skips without a GPU adapter, unless SPECMAP_REQUIRE_GPU=1 (as tools/test.sh sets)."""
    try:
        specmap.render(backend="gpu", size="4x4", step=100)
    except ValueError as e:
        if "--backend gpu" not in str(e) or os.environ.get("SPECMAP_REQUIRE_GPU") == "1":
            raise
        pytest.skip(f"no GPU adapter: {e}")


def ciede2000(a, b):
    """Per-pixel CIEDE2000 of linear sRGB images, CIELAB relative to RGB (1, 1, 1), as
    specmap::render::compare measures it."""
    colour = pytest.importorskip("colour")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", module="colour")
        m = colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ
        white = m @ np.ones(3)

        def lab(rgb):
            xyz = rgb.astype(np.float64) @ m.T / white
            f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
            x, y, z = f[..., 0], f[..., 1], f[..., 2]
            return np.stack([116 * y - 16, 500 * (x - y), 200 * (y - z)], axis=-1)

        return colour.difference.delta_E_CIE2000(lab(a), lab(b))


@pytest.mark.parametrize("env", [False, True])
def test_gpu_agrees_with_the_cpu(gpu_ready, env, sunrise):
    options = {"scene": "ball", "size": "40x40", "step": 10, "env": sunrise if env else None}
    cpu, cpu_report = specmap.render(backend="cpu", **options)
    gpu, report = specmap.render(backend="gpu", **options)
    assert report["backend"] == "gpu" and report["adapter"]["name"]
    assert report["gpu_timing"] is not None
    assert gpu.shape == cpu.shape == (40, 40, 3) and gpu.dtype == np.float32
    assert np.isfinite(gpu).all()
    de = ciede2000(cpu, gpu)
    assert de.mean() < MEAN_TOL and de.max() < MAX_TOL, (de.mean(), de.max())
    # The same wavelengths and report, but for the backend.
    same = without(report, *TIMINGS, "backend", "adapter")
    assert same == without(cpu_report, *TIMINGS, "backend", "adapter")


def test_gpu_without_a_runtime_dir_is_quiet(gpu_ready):
    # As the CLI's main does (cli::runtime_dir), a private XDG_RUNTIME_DIR keeps Mesa's Vulkan
    # layer from printing "XDG_RUNTIME_DIR is invalid or not set" when it probes for Wayland.
    env = {k: v for k, v in os.environ.items() if k != "XDG_RUNTIME_DIR"}
    env["PYTHONPATH"] = os.pathsep.join(
        [str(Path(specmap.__file__).parents[1]), env.get("PYTHONPATH", "")]
    )
    code = "import specmap; specmap.render(backend='gpu', size='4x4', step=100)"
    run = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    assert "XDG_RUNTIME_DIR" not in run.stderr, run.stderr
