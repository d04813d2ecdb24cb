"""The Mitsuba 3 emitter (integrations/mitsuba3/specmap_envmap.py) against independent
references: Mitsuba's own RGB `envmap` on the map that was converted, colour-science's
CIEDE2000, the file's bands read by OpenEXR's binding, and `specmap render`'s ColorChecker spheres.

Maps are the bundled ones box-filtered to 128 x 64 (sunrise keeps a one-texel sun there), so
Mitsuba runs in seconds. Every test runs in scalar_spectral, and in llvm_ad_spectral where
Dr.Jit finds a working LLVM (DRJIT_LIBLLVM_PATH; tools/test.sh installs Debian's libllvm19)."""
import glob
import importlib
import os
import subprocess
import sys

import numpy as np
import OpenEXR
import pytest

import colour

from conftest import BIN, ROOT

PLUGIN_DIR = ROOT / "integrations" / "mitsuba3"
LLVM_CANDIDATES = ["/usr/lib/x86_64-linux-gnu/libLLVM.so.19*", "/usr/lib/llvm-19/lib/libLLVM.so*",
                   "/usr/lib/*/libLLVM-19.so"]
PROBE = ("import mitsuba as mi, drjit as dr; mi.set_variant('llvm_ad_spectral'); "
         "print(dr.sum(mi.Float([1, 2])))")


def _llvm_probe():
    """Why llvm_ad_spectral cannot run here, or None. A subprocess: a bad LLVM crashes."""
    paths = [os.environ.get("DRJIT_LIBLLVM_PATH")] if os.environ.get("DRJIT_LIBLLVM_PATH") \
        else [p for pat in LLVM_CANDIDATES for p in sorted(glob.glob(pat))] + [None]
    for path in paths:
        env = dict(os.environ, **({"DRJIT_LIBLLVM_PATH": path} if path else {}))
        try:
            p = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True,
                               text=True, timeout=120)
        except subprocess.TimeoutExpired:
            continue
        if p.returncode == 0 and "3" in p.stdout:
            if path:
                os.environ["DRJIT_LIBLLVM_PATH"] = path
            return None
    return "no working LLVM for Dr.Jit (install libllvm19, set DRJIT_LIBLLVM_PATH)"


LLVM_MISSING = _llvm_probe()
VARIANTS = ["scalar_spectral",
            pytest.param("llvm_ad_spectral",
                         marks=pytest.mark.skipif(LLVM_MISSING is not None,
                                                  reason=str(LLVM_MISSING)))]

import mitsuba as mi  # noqa: E402  (after DRJIT_LIBLLVM_PATH is settled)


@pytest.fixture(params=VARIANTS)
def plugin(request):
    """The emitter module, imported (again) after setting the variant: its class derives from
    that variant's mi.Emitter."""
    mi.set_variant(request.param)
    if str(PLUGIN_DIR) not in sys.path:
        sys.path.insert(0, str(PLUGIN_DIR))
    import specmap_envmap
    return importlib.reload(specmap_envmap)


# ----------------------------------------------------------------------------- maps

def write_rgb(path, rgb):
    """A float lat-long RGB EXR by OpenEXR's binding."""
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "envmap": OpenEXR.ENVMAP_LATLONG}
    with OpenEXR.File(header, {"RGB": np.ascontiguousarray(rgb, np.float32)}) as f:
        f.write(str(path))


def read_channels(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return dict(f.header()), {k: v.pixels.copy() for k, v in f.channels().items()}


def downscaled(src, factor, gain=1.0):
    """The bundled map box-filtered by `factor` (area means: energy kept), times `gain`."""
    _, ch = read_channels(src)
    rgb = np.stack([ch[c] for c in "RGB"], -1).astype(np.float64)
    h, w, _ = rgb.shape
    return rgb.reshape(h // factor, factor, w // factor, factor, 3).mean((1, 3)) * gain


def upsampled(rgb):
    """x2 bilinear between texel centres (periodic in longitude, clamped in latitude): a map
    smooth at its texel scale, where Mitsuba's envmap interpolation is close to bilinear."""
    h, w, _ = rgb.shape
    xs = (np.arange(2 * w) + 0.5) / 2 - 0.5
    ys = np.clip((np.arange(2 * h) + 0.5) / 2 - 0.5, 0, h - 1)
    x0 = np.floor(xs).astype(int)
    y0 = np.minimum(np.floor(ys).astype(int), h - 2)
    fx, fy = (xs - x0)[None, :, None], (ys - y0)[:, None, None]
    rows = rgb[:, x0 % w] * (1 - fx) + rgb[:, (x0 + 1) % w] * fx
    return rows[y0] * (1 - fy) + rows[y0 + 1] * fy


def convert(src, dst, *args):
    p = subprocess.run([BIN, "convert", str(src), "-o", str(dst), "--quiet", *args],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return dst


@pytest.fixture(scope="session")
def maps(specmap, tmp_path_factory):
    """RGB inputs and their conversions. "sunrise" and "forest": the bundled maps box-filtered
    to 128 x 64 and made smooth at the texel scale (x2 bilinear, 256 x 128) for the comparisons
    with Mitsuba's envmap (which interpolates the upsampling model's spectrum and its scale
    separately: docs/mitsuba.md); sunrise is made 64 times brighter, so its half-float spectra
    need the EV scale. "sunrise-128": 128 x 64 unsmoothed, its sun found (one texel)."""
    d = tmp_path_factory.mktemp("mitsuba")
    out = {}
    for name, gain in (("sunrise", 64.0), ("forest", 1.0)):
        rgb = d / f"{name}.exr"
        write_rgb(rgb, upsampled(downscaled(ROOT / "envmaps" / f"{name}.exr", 8, gain)))
        out[name] = {"rgb": rgb,
                     "spectral": convert(rgb, d / f"{name}.spectral.exr"),
                     "basis": convert(rgb, d / f"{name}.basis.exr", "--format", "basis",
                                      "--precision", "float"),
                     "basis-half": convert(rgb, d / f"{name}.basis-half.exr", "--format",
                                           "basis")}
    rgb = d / "sunrise-128.exr"
    write_rgb(rgb, downscaled(ROOT / "envmaps" / "sunrise.exr", 8))
    out["sunrise-128"] = {"rgb": rgb, "spectral": convert(rgb, d / "sunrise-128.spectral.exr"),
                          "basis": convert(rgb, d / "sunrise-128.basis.exr", "--format",
                                           "basis")}
    return out


# ----------------------------------------------------------------------------- rendering

def film(w, h):
    return {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"},
            "pixel_format": "rgb"}


def render(plugin, scene, spp, seed=0):
    """Linear sRGB (h, w, 3) of a scene dict, the specmap emitters fitted to the scene."""
    return np.asarray(mi.render(plugin.load_dict(scene), spp=spp, seed=seed), np.float64)


def blocks(img, n):
    """Means over n x n pixel blocks."""
    h, w, _ = img.shape
    return img.reshape(h // n, n, w // n, n, 3).mean((1, 3))


def de2000(ref, test, white_y):
    """CIEDE2000 (colour-science) between linear sRGB arrays, both scaled so white_y is Y = 1."""
    def lab(rgb):
        xyz = colour.RGB_to_XYZ(rgb / white_y, "sRGB")
        return colour.XYZ_to_Lab(xyz, colour.CCS_ILLUMINANTS[
            "CIE 1931 2 Degree Standard Observer"]["D65"])
    return colour.delta_E(lab(ref), lab(test), method="CIE 2000")


def luminance(rgb):
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def envmap(path, kind):
    """Mitsuba's own envmap on the RGB file, or this emitter on a specmap file."""
    t = "envmap" if kind == "rgb" else "specmap_envmap"
    return {"type": t, "filename": str(path)}


# ----------------------------------------------------------------------------- (a) the map seen

# Mitsuba's envmap interpolates the upsampling model's spectrum and its scale separately, so
# near a bright texel (the sun) it loses energy that bilinear interpolation keeps: 0.8 % of the
# upper hemisphere of the smoothed sunrise, up to 1 % in a view (docs/mitsuba.md).
ENERGY_TOLERANCE = 0.02

VIEWS = [[0, 0, 1], [1, 0.1, 0], [-0.6, 0.15, -0.8], [0.3, -0.5, 0.4], [0.01, 1, 0]]


def camera_only(em, target):
    """A 90-degree camera at the origin looking at `target`, seeing only the environment."""
    return {"type": "scene", "env": em, "integrator": {"type": "direct"},
            "sensor": {"type": "perspective", "fov": 90, "film": film(48, 48),
                       "sampler": {"type": "ldsampler"},
                       "to_world": mi.ScalarTransform4f().look_at([0, 0, 0], target, [0, 1, 0])}}


@pytest.mark.parametrize("name,kind", [("sunrise", "spectral"), ("forest", "spectral"),
                                       ("sunrise", "basis")])
def test_map_seen_directly_matches_mitsubas_envmap(plugin, maps, name, kind):
    """Five views of the map (horizon, the sun's side, below, the zenith): this emitter on the
    conversion and Mitsuba's envmap on the RGB input agree in orientation and radiometric
    scale: CIEDE2000 of 8 x 8-pixel means below 0.5 on average (each view scaled to its brightest
    block), total luminance within ENERGY_TOLERANCE."""
    spec = maps[name][kind]
    header, _ = read_channels(spec)
    if name == "sunrise" and kind == "spectral":
        assert header.get("EV", 0) > 0, "the bright map should need the EV scale"
    des, ratios = [], []
    for target in VIEWS:
        ref = blocks(render(plugin, camera_only(envmap(maps[name]["rgb"], "rgb"), target), 16), 8)
        got = blocks(render(plugin, camera_only(envmap(spec, kind), target), 16), 8)
        des.append(de2000(ref, got, luminance(ref).max()))
        ratios.append(luminance(got).sum() / luminance(ref).sum())
    des = np.concatenate([d.ravel() for d in des])
    print(f"mean CIEDE2000 {des.mean():.3f} max {des.max():.3f}, "
          f"luminance ratios {np.round(ratios, 4)}")
    assert des.mean() < 0.5, (des.mean(), des.max())
    np.testing.assert_allclose(ratios, 1.0, atol=ENERGY_TOLERANCE)


def test_a_mirrored_map_fails_the_comparison(plugin, maps, tmp_path):
    """The comparison above can fail: the same map flipped left-right renders far from envmap."""
    _, ch = read_channels(maps["forest"]["rgb"])
    write_rgb(tmp_path / "flipped.exr", np.stack([ch[c] for c in "RGB"], -1)[:, ::-1])
    flipped = convert(tmp_path / "flipped.exr", tmp_path / "flipped.spectral.exr")
    ref = blocks(render(plugin, camera_only(envmap(maps["forest"]["rgb"], "rgb"), [1, 0.1, 0]),
                        8), 8)
    got = blocks(render(plugin, camera_only(envmap(flipped, "spectral"), [1, 0.1, 0]), 8), 8)
    assert de2000(ref, got, luminance(ref).max()).mean() > 2.0


# ----------------------------------------------------------------------------- (b) a white sphere

SPHERE_SPP = 64  # ldsampler: a power of four


def sphere_scene(em, camera_dir, integrator=None, reflectance=None):
    """A diffuse sphere of radius 1 at the origin, seen by an orthographic camera from
    `camera_dir` whose 24 x 24 pixels span the sphere's disk."""
    eye = np.asarray(camera_dir, float) * 5
    up = [0, 0, 1] if abs(camera_dir[1]) > 0.9 else [0, 1, 0]
    return {"type": "scene", "env": em,
            "integrator": integrator or {"type": "direct"},
            "ball": {"type": "sphere", "radius": 1.0,
                     "bsdf": {"type": "diffuse", "reflectance": reflectance or
                              {"type": "spectrum", "value": 0.8}}},
            "sensor": {"type": "orthographic", "film": film(24, 24),
                       "sampler": {"type": "ldsampler"},
                       "to_world": mi.ScalarTransform4f().look_at(eye.tolist(), [0, 0, 0], up)}}


def disk_mask(h, within=0.8):
    """Pixels of an h x h image of a disk (spanning the image) whose centres lie within
    `within` of its radius."""
    c = (np.arange(h) + 0.5 - h / 2) / (h / 2)
    return np.hypot(*np.meshgrid(c, c)) < within


def disk_regions(img, grid=3, within=0.8):
    """Mean colour of the disk's interior pixels in each cell of a grid x grid partition of
    the image, for the cells at least half inside."""
    h = img.shape[0]
    mask = disk_mask(h, within)
    n = h // grid
    out = []
    for i in range(grid):
        for j in range(grid):
            m = mask[i * n:(i + 1) * n, j * n:(j + 1) * n]
            if m.mean() >= 0.5:
                out.append(img[i * n:(i + 1) * n, j * n:(j + 1) * n][m].mean(0))
    return np.array(out)


@pytest.mark.parametrize("name", ["sunrise", "forest"])
def test_white_sphere_matches_mitsubas_envmap(plugin, maps, name):
    """A white (0.8) Lambertian sphere lit by the map, seen from four sides: this emitter
    (importance-sampled, MIS with the BSDF) and Mitsuba's envmap agree to CIEDE2000 < 0.5 over
    the means of 9 regions of the disk's interior, total luminance within ENERGY_TOLERANCE.
    Both renders use the same sample streams (common random numbers: the noise they share
    cancels)."""
    des, ratios = [], []
    for side in ([0, 0, 1], [1, 0, 0], [0, 0, -1], [-0.7, 0.3, 0.6]):
        ref = disk_regions(render(plugin, sphere_scene(envmap(maps[name]["rgb"], "rgb"), side),
                                  SPHERE_SPP))
        got = disk_regions(render(plugin, sphere_scene(envmap(maps[name]["spectral"], "spectral"),
                                                       side), SPHERE_SPP))
        des.append(de2000(ref, got, luminance(ref).max()))
        ratios.append(luminance(got).sum() / luminance(ref).sum())
    des = np.concatenate(des)
    print(f"mean CIEDE2000 {des.mean():.3f} max {des.max():.3f}, "
          f"luminance ratios {np.round(ratios, 4)}")
    assert des.mean() < 0.5, (des.mean(), des.max())
    np.testing.assert_allclose(ratios, 1.0, atol=ENERGY_TOLERANCE)


# ----------------------------------------------------------------------------- the readers

BANDS = [450.0, 550.0, 600.0, 700.0]  # on the 5 nm grid: no interpolation in wavelength


def specmap_directions(w, h):
    """Texel-centre directions of a w x h lat-long map in specmap's (OpenEXR's) convention."""
    y, x = np.mgrid[0:h, 0:w]
    lon = -2 * np.pi * ((x + 0.5) / w - 0.5)
    lat = np.pi / 2 - np.pi * (y + 0.5) / h
    return np.stack([np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)], -1)


def eval_at(emitter, dirs, wavelengths):
    """The emitter's radiance seen along `dirs` (n, 3) at four wavelengths: (n, 4)."""
    if dr_is_jit():
        si = mi.SurfaceInteraction3f()  # width 1, widened by the assignments
        si.wi = mi.Vector3f(*(-dirs.T.astype(np.float32)))
        si.wavelengths = mi.Spectrum(*[mi.Float(np.full(len(dirs), l, np.float32))
                                       for l in wavelengths])
        return np.array(emitter.eval(si)).reshape(4, -1).T
    out = []
    for d in dirs:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*(-d))
        si.wavelengths = mi.Spectrum(*wavelengths)
        out.append(list(emitter.eval(si)))
    return np.array(out)


def dr_is_jit():
    import drjit as dr
    return dr.is_jit_v(mi.Float)


def sample_texels(w, h, n=300, seed=3):
    """Texel indices (y, x) to check: all in JIT variants, `n` random ones in scalar."""
    y, x = np.mgrid[0:h, 0:w]
    idx = np.stack([y.ravel(), x.ravel()], 1)
    if dr_is_jit():
        return idx
    return idx[np.random.default_rng(seed).choice(len(idx), n, replace=False)]


def band_values(path, wavelengths):
    """The file's bands at `wavelengths` times 2^EV, read by OpenEXR's binding: (h, w, 4)."""
    header, ch = read_channels(path)
    scale = 2.0 ** float(header.get("EV", 0.0))
    return np.stack([ch[f"S0.{l:.6f}nm".replace(".", ",").replace("S0,", "S0.")]
                     for l in wavelengths], -1).astype(np.float64) * scale


def test_texel_centres_read_back_the_bands(plugin, maps):
    """rows=specmap: along specmap's texel-centre directions the emitter returns the file's
    bands (EV restored) times the radiometric factor, the sun texel included."""
    for path in (maps["sunrise-128"]["spectral"], maps["sunrise"]["spectral"]):
        em = mi.load_dict({"type": "specmap_envmap", "filename": str(path), "rows": "specmap"})
        want = band_values(path, BANDS)
        h, w = want.shape[:2]
        idx = sample_texels(w, h)
        dirs = specmap_directions(w, h)[idx[:, 0], idx[:, 1]]
        got = eval_at(em, dirs, BANDS) / plugin.radiometric_factor()
        # float32 directions land ~1e-4 texel off the centre: next to the sun that is 0.3 %
        np.testing.assert_allclose(got, want[idx[:, 0], idx[:, 1]], rtol=5e-3,
                                   atol=1e-6 * want.max())


def spectra_at(emitter, dirs, wavelengths):
    """The emitter's radiance along `dirs` at every wavelength (four at a time): (n, N)."""
    out = []
    for k in range(0, len(wavelengths), 4):
        group = list(wavelengths[k:k + 4])
        got = eval_at(emitter, dirs, group + [group[-1]] * (4 - len(group)))
        out.append(got[:, :len(group)])
    return np.concatenate(out, 1)


def rgb_of_spectra(spectra, wavelengths):
    """Linear sRGB of spectra with specmap's scale (Y = sum(L ybar) / sum(ybar)), by
    colour-science's CIE 1931 observer and sRGB matrix."""
    shape = colour.SpectralShape(wavelengths[0], wavelengths[-1], wavelengths[1] - wavelengths[0])
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape).values
    xyz = spectra @ cmfs / cmfs[:, 1].sum()
    return colour.XYZ_to_RGB(xyz, "sRGB")


def basis_version(path):
    """2 for a basis v2 file (specmap.basisVersion), else 1."""
    header, _ = read_channels(path)
    return int(header.get("specmap.basisVersion", 1))


def basis_emitter(path):
    return mi.load_dict({"type": "specmap_envmap", "filename": str(path), "rows": "specmap"})


def write_basis_v2(v1_path, dst, ev=3.0):
    """The same spectra as a basis v2 file (the format specified in issue 14): k00..k02 the v1
    coefficients, k03 the sun's weight with basis03 the sun's SPD, all divided by 2^EV."""
    header, ch = read_channels(v1_path)
    basis = [list(map(float, header[f"specmap.basis{j}"])) for j in range(3)]
    basis.append(list(map(float, header["specmap.sunSPD"])))
    coef = [ch[c].astype(np.float32) for c in ("c_R", "c_G", "c_B", "sun")]
    out = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
           "envmap": OpenEXR.ENVMAP_LATLONG, "specmap.basisVersion": 2, "specmap.basisK": 4,
           "specmap.basisSun": 3, "EV": float(ev),
           "specmap.wavelengths": list(map(float, header["specmap.wavelengths"]))}
    out.update({f"specmap.basis{j:02d}": b for j, b in enumerate(basis)})
    channels = {f"k{j:02d}": c / np.float32(2.0 ** ev) for j, c in enumerate(coef)}
    with OpenEXR.File(out, channels) as f:
        f.write(str(dst))
    return dst


def test_basis_v2_from_specmap_matches_its_spectral_conversion(plugin, maps):
    """specmap's own basis v2 output (--format basis, K spectra of the map's own, the sun's
    among them; float, and half with EV for the bright map) gives the spectra of the same
    map's spectral conversion to 1 % at every checked texel (the writer reports every pixel
    held to better than 1 %)."""
    for name, kind in (("sunrise-128", "basis"), ("sunrise", "basis"),
                       ("sunrise", "basis-half")):
        basis, spectral = maps[name][kind], maps[name]["spectral"]
        a, b = basis_emitter(basis), basis_emitter(spectral)
        assert a.kind == "basis-v2"
        idx = sample_texels(a.width, a.height, n=150)
        dirs = specmap_directions(a.width, a.height)[idx[:, 0], idx[:, 1]]
        wl = np.arange(380.0, 781.0, 20.0)
        got, want = spectra_at(a, dirs, wl), spectra_at(b, dirs, wl)
        peak = np.abs(want).max(1)
        lit = peak > 1e-3 * peak.max()
        rel = np.abs(got - want).max(1)[lit] / peak[lit]
        header, _ = read_channels(basis)
        if kind == "basis-half":
            assert header.get("EV", 0) > 0, "the bright map's half-float v2 should need EV"
        print(f"{name} {kind}: K = {header['specmap.basisK']}, EV = {header.get('EV', 0)}, "
              f"relative spectral difference median {np.median(rel):.2e} max {rel.max():.2e}")
        assert rel.max() < 0.01, (name, rel.max(), np.median(rel))


def write_basis_v1(dst, ev=2.0, sun=5e3, half=False, seed=5):
    """A basis v1 file to the --format basis layout of specmap before v2: random c_R, c_G, c_B
    (divided by 2^EV) on CIE daylight's S0, S1, S2 (colour-science), one texel's `sun` weight
    (unscaled) on D65. Returns the radiance it stands for (h, w, N) and the wavelengths."""
    from colour.colorimetry import SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES as D
    shape = colour.SpectralShape(380, 780, 5)
    wl = shape.wavelengths
    basis = np.stack([D[k].copy().align(shape).values for k in ("S0", "S1", "S2")]) / 100
    spd = colour.SDS_ILLUMINANTS["D65"].copy().align(shape).values / 100
    rng = np.random.default_rng(seed)
    c = rng.uniform(0.0, 3.0, (32, 64, 3)) * [1.0, 0.1, 0.1]
    weight = np.zeros((32, 64))
    weight[10, 20] = sun
    dtype = np.float16 if half else np.float32
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "envmap": OpenEXR.ENVMAP_LATLONG, "EV": float(ev),
              "specmap.wavelengths": [float(x) for x in wl],
              "specmap.sunSPD": [float(x) for x in spd]}
    header.update({f"specmap.basis{j}": [float(x) for x in basis[j]] for j in range(3)})
    channels = {n: (c[..., j] / 2 ** ev).astype(dtype) for j, n in enumerate(("c_R", "c_G", "c_B"))}
    channels["sun"] = weight.astype(dtype)
    with OpenEXR.File(header, channels) as f:
        f.write(str(dst))
    return c @ basis + weight[..., None] * spd, wl


def test_basis_v1_layout_reads_to_its_definition(plugin, tmp_path):
    """A v1 file written here (EV = 2 on c_R, c_G, c_B, the sun's weight unscaled): along
    specmap's texel centres the emitter gives c B + sun SPD, the sun texel included."""
    want, wl = write_basis_v1(tmp_path / "v1.exr")
    em = basis_emitter(tmp_path / "v1.exr")
    assert em.kind == "basis"
    h, w = want.shape[:2]
    idx = np.concatenate([sample_texels(w, h, n=100), [[10, 20]]])
    dirs = specmap_directions(w, h)[idx[:, 0], idx[:, 1]]
    bands = [450.0, 550.0, 600.0, 700.0]
    got = eval_at(em, dirs, bands) / plugin.radiometric_factor()
    cols = [int(np.argmin(np.abs(wl - b))) for b in bands]
    np.testing.assert_allclose(got, want[idx[:, 0], idx[:, 1]][:, cols], rtol=1e-5,
                               atol=1e-6 * want.max())


def test_a_v1_sun_that_overflowed_half_floats_is_refused(plugin, tmp_path):
    """specmap's v1 writer stored the sun channel unscaled by EV: a bright sun is inf in half
    floats. The emitter says so, and how to convert, rather than drawing no sun."""
    write_basis_v1(tmp_path / "v1.exr", sun=1e6, half=True)
    msg = load_error(tmp_path / "v1.exr")
    assert "v1.exr" in msg and "sun channel" in msg and "--precision float" in msg


# ----------------------------------------------------------------------------- clear errors

def load_error(path, **extra):
    """The message of the error loading `path` as a specmap_envmap."""
    with pytest.raises(Exception) as e:
        mi.load_dict({"type": "specmap_envmap", "filename": str(path), **extra})
    return str(e.value)


def test_a_file_of_neither_format_is_refused_by_name(plugin, maps):
    msg = load_error(maps["forest"]["rgb"])
    assert str(maps["forest"]["rgb"]) in msg
    assert "S0.<wavelength>nm" in msg and "c_R" in msg and "specmap.basisVersion" in msg


def test_a_v2_file_missing_a_basis_spectrum_is_refused(plugin, maps, tmp_path):
    v2 = maps["sunrise-128"]["basis"]
    if basis_version(v2) == 1:
        v2 = write_basis_v2(v2, tmp_path / "v2.exr")
    header, ch = read_channels(v2)
    del header["specmap.basis01"]
    keep = {k: v for k, v in header.items() if k.startswith("specmap.") or k == "EV"}
    keep.update({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage})
    with OpenEXR.File(keep, ch) as f:
        f.write(str(tmp_path / "broken.exr"))
    msg = load_error(tmp_path / "broken.exr")
    assert "broken.exr" in msg and "specmap.basis01" in msg and "missing" in msg


def test_a_cube_map_is_refused_with_the_command_that_fixes_it(plugin, maps, tmp_path):
    cube = convert(maps["sunrise-128"]["rgb"], tmp_path / "cube.exr", "--out-layout", "cube",
                   "--size", "16")
    msg = load_error(cube)
    assert "cube.exr" in msg and "--out-layout latlong" in msg


# ----------------------------------------------------------------------------- (c) ColorChecker

CHECKER_SIZE = (192, 128)  # specmap's render: pixel pitch 4 / 128 world units, sphere radius 0.4
CHECKER_SPP = 64
CHECKER_BIN = 2  # Mitsuba renders each 32 x 32-pixel sphere crop at 16 x 16 (2 x 2 bins)


def colorchecker():
    """specmap's built-in ColorChecker (spectra/reflectance/colorchecker.csv): wavelengths and
    the 24 patches' reflectances, in column order."""
    path = ROOT / "spectra" / "reflectance" / "colorchecker.csv"
    names = path.read_text().splitlines()[0].split(",")[1:]
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    return names, table[:, 0], table[:, 1:].T


def specmap_checker(env, out):
    """`specmap render --scene checker-spheres` of the map: linear sRGB (128, 192, 3)."""
    w, h = CHECKER_SIZE
    p = subprocess.run([BIN, "render", "--scene", "checker-spheres", "--env", str(env),
                        "--background", "none", "--backend", "cpu", "--size", f"{w}x{h}",
                        "-o", str(out)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    _, ch = read_channels(out)
    return np.stack([ch[c] for c in "RGB"], -1).astype(np.float64)


def one_sphere_scene(env, wavelengths, reflectance):
    """One Lambertian sphere of radius 0.4 at the origin under the map (rows in specmap's
    convention, the renderer's), framed as specmap frames each sphere: an orthographic camera
    down -Z spanning 1 x 1 world units (32 x 32 specmap pixels) about its centre."""
    pitch = 4.0 / CHECKER_SIZE[1]
    half = 16 * pitch
    n = 32 // CHECKER_BIN
    value = [(float(l), float(v)) for l, v in zip(wavelengths, reflectance)]
    return {"type": "scene",
            "env": {"type": "specmap_envmap", "filename": str(env), "rows": "specmap"},
            "integrator": {"type": "direct"},
            "ball": {"type": "sphere", "radius": 0.4,
                     "bsdf": {"type": "diffuse",
                              "reflectance": {"type": "spectrum", "value": value}}},
            "sensor": {"type": "orthographic", "film": film(n, n), "sampler": {"type": "ldsampler"},
                       "to_world": mi.ScalarTransform4f().look_at([0, 0, 10], [0, 0, 0], [0, 1, 0])
                       @ mi.ScalarTransform4f().scale([half, half, 1])}}


def crop_mean(img, within=0.8 * 0.4 / 0.5):
    """Mean colour of a square crop's pixels whose centres lie within 0.8 of the sphere's
    radius (the crop spans 1 world unit, the sphere's diameter is 0.8)."""
    return img[disk_mask(img.shape[0], within)].mean(0)


def test_colorchecker_spheres_match_specmaps_renderer(plugin, maps, tmp_path):
    """The 24 ColorChecker spheres under sunrise (its sun a texel here, a directional light in
    specmap's renderer): each sphere rendered alone in Mitsuba with this emitter, its interior
    mean (0.8 of the radius) against specmap's render of the same pixels; CIEDE2000 per patch,
    both scaled by the white patch's luminance in specmap's render, mean < 1.0."""
    env = maps["sunrise-128"]["spectral"]
    ref_img = specmap_checker(env, tmp_path / "checker.exr")
    names, _, _ = colorchecker()
    want = np.array([crop_mean(blocks(ref_img[32 * (k // 6):32 * (k // 6) + 32,
                                              32 * (k % 6):32 * (k % 6) + 32], CHECKER_BIN))
                     for k in range(24)])
    got = mitsuba_checker(plugin, env)
    white = luminance(want[names.index("white-9.5")])
    de = de2000(want, got, white)
    print("CIEDE2000 per patch", dict(zip(names, np.round(de, 2))), "mean", de.mean())
    assert de.mean() < 1.0, (de.mean(), de.max())


_CHECKER_CACHE = {}


def mitsuba_checker(plugin, env):
    """Mitsuba's 24 sphere means (linear sRGB), one sphere at a time, its reflectance changed
    through mi.traverse; cached per variant and map (two tests compare them)."""
    key = (mi.variant(), str(env))
    if key not in _CHECKER_CACHE:
        _, wl, patches = colorchecker()
        scene = plugin.load_dict(one_sphere_scene(env, wl, patches[0]))
        params = mi.traverse(scene)
        name = "ball.bsdf.reflectance.values"
        means = []
        for k, refl in enumerate(patches):
            params[name] = type(params[name])(refl.astype(np.float32))
            params.update()
            img = np.asarray(mi.render(scene, spp=CHECKER_SPP, seed=k), np.float64)
            means.append(crop_mean(img))
        _CHECKER_CACHE[key] = np.array(means)
    return _CHECKER_CACHE[key]


def integrated_checker(env):
    """The same 24 sphere means by direct numerical integration of the file (no Mitsuba): each
    pixel's normal n gets E(n, lambda) = sum over texels of L max(0, n.w) dOmega (specmap's
    lat-long convention), radiance rho E / pi, RGB by colour-science (specmap's Y scale)."""
    wl = np.arange(380.0, 781.0, 5.0)
    radiance = band_values(env, wl)
    h, w = radiance.shape[:2]
    dirs = specmap_directions(w, h).reshape(-1, 3)
    lat = np.pi / 2 - np.pi * np.arange(h + 1) / h
    omega = np.repeat(2 * np.pi / w * (np.sin(lat[:-1]) - np.sin(lat[1:])), w)
    n = 32 // CHECKER_BIN
    c = (np.arange(n) + 0.5 - n / 2) / n  # pixel centres in world units, the crop spans 1
    x, y = np.meshgrid(c, -c)
    inside = disk_mask(n, 0.8 * 0.4 / 0.5)
    normals = np.stack([x, y, np.sqrt(np.maximum(0.16 - x * x - y * y, 0))], -1)[inside] / 0.4
    irradiance = np.maximum(normals @ dirs.T, 0) @ (radiance.reshape(-1, wl.size) * omega[:, None])
    _, cc_wl, patches = colorchecker()
    means = []
    for refl in patches:
        rho = np.interp(wl, cc_wl, refl)
        means.append(rgb_of_spectra(irradiance * rho / np.pi, wl).mean(0))
    return np.array(means)


def test_colorchecker_spheres_match_numerical_integration(plugin, maps):
    """Mitsuba's one-sphere-at-a-time ColorChecker renders (the setup of the test above, sun
    included) against the numerical integral of the spectral file: CIEDE2000 per patch, scaled
    by the white patch, mean < 0.5. Runs whether or not specmap has the preset."""
    env = maps["sunrise-128"]["spectral"]
    names, _, _ = colorchecker()
    want = integrated_checker(env)
    got = mitsuba_checker(plugin, env)
    de = de2000(want, got, luminance(want[names.index("white-9.5")]))
    print("CIEDE2000 per patch", dict(zip(names, np.round(de, 2))), "mean", de.mean())
    assert de.mean() < 0.5, (de.mean(), de.max())


# ----------------------------------------------------------------------------- light tracing

def test_light_tracing_agrees_with_path_sampling(plugin, maps):
    """Mitsuba's particle tracer starts paths at the emitter (sample_ray, sample_wavelengths,
    the scene's bounding sphere from fit_to_scene): the white sphere's centre comes out as
    bright as the direct integrator makes it (emitter and BSDF sampling), within 4 %."""
    means = []
    for integrator, spp in (({"type": "direct"}, 64),
                            ({"type": "ptracer", "max_depth": 2, "hide_emitters": True}, 256)):
        scene = sphere_scene(envmap(maps["forest"]["spectral"], "spectral"), [0, 0, 1],
                             integrator)
        scene["sensor"] = {"type": "perspective", "fov": 12, "film": film(16, 16),
                           "to_world": mi.ScalarTransform4f().look_at([0, 0, 8], [0, 0, 0],
                                                                      [0, 1, 0])}
        img = render(plugin, scene, spp)
        means.append(luminance(img[disk_mask(16, 0.6)].mean(0)))
    assert means[1] == pytest.approx(means[0], rel=0.04), means


# ----------------------------------------------------------------------------- to_world

def test_to_world_turns_both_emitters_alike(plugin, maps):
    """The same to_world (a turn about Y and a tilt) given to envmap and this emitter: the map
    seen directly (eval) and a white sphere under it (sampling) still agree, CIEDE2000 < 0.5."""
    turn = mi.ScalarTransform4f().rotate([1, 0, 0], 30) @ mi.ScalarTransform4f().rotate(
        [0, 1, 0], 100)
    des = []
    for kind, path in (("rgb", maps["forest"]["rgb"]), ("spectral", maps["forest"]["spectral"])):
        em = dict(envmap(path, kind), to_world=turn)
        views = [blocks(render(plugin, camera_only(em, t), 16), 8) for t in VIEWS[:2]]
        ball = disk_regions(render(plugin, sphere_scene(em, [1, 0, 0]), SPHERE_SPP))
        des.append((views, ball))
    (ref_views, ref_ball), (got_views, got_ball) = des
    for ref, got in zip(ref_views + [ref_ball], got_views + [got_ball]):
        de = de2000(ref, got, luminance(ref).max())
        assert de.mean() < 0.5, (de.mean(), de.max())
