"""specmap_envmap: a Mitsuba 3 environment emitter that reads specmap's spectral OpenEXR maps.

Mitsuba's own ``envmap`` reads RGB and upsamples it; this emitter reads the spectra that
``specmap convert`` wrote. Import the module after ``mi.set_variant(...)`` (a spectral variant:
``scalar_spectral``, ``llvm_ad_spectral``, ...); it registers the emitter type
``specmap_envmap``::

    import mitsuba as mi
    mi.set_variant("scalar_spectral")
    import specmap_envmap
    scene = specmap_envmap.load_dict({..., "sky": {"type": "specmap_envmap",
                                                   "filename": "map.spectral.exr"}})
    image = mi.render(scene, spp=64)

Parameters
----------
filename : str
    A spectral EXR from ``specmap convert`` (channels ``S0.<nm>nm``), a basis v2 EXR from
    ``specmap convert --format basis`` (``specmap.basisVersion`` = 2, channels
    ``k00 ... k{K-1}``), or a basis v1 EXR (channels ``c_R, c_G, c_B, sun``, what
    ``--format basis`` wrote before v2). Lat-long only.
scale : float
    Multiplies the radiance (default 1).
to_world : transform
    Emitter-to-world transform, as for ``envmap`` (default identity).
rows : str
    ``"mitsuba"`` (default): row y of an h-row map lies at polar angle pi y / (h - 1), as
    Mitsuba's ``envmap`` places it, so the two emitters are interchangeable. ``"specmap"``:
    row y's centre lies at pi (y + 0.5) / h, OpenEXR's and specmap's lat-long convention.

Orientation
-----------
With ``to_world`` the identity, a direction d = (x, y, z) looks at u = atan2(x, -z) / (2 pi)
(wrapped to [0, 1)) and polar angle acos(y), exactly as Mitsuba's ``envmap``: the map's centre
column looks down +Z, Y is up, a quarter of the width from the left looks at +X. That is
OpenEXR's (and specmap's) longitude, lon = -2 pi (u - 0.5); the two differ only in where rows
sit (``rows`` above): by at most half a texel of latitude.

Radiometric scale (derived from Mitsuba's source, ``include/mitsuba/core/spectrum.h``)
------------------------------------------------------------------------------------
* specmap writes relative radiance L_s with Y_s = sum(L_s ybar) / sum(ybar): an RGB pixel c of
  luminance Y(c) becomes a spectrum of luminance Y(c) and of c's XYZ.
* Mitsuba's film turns a spectrum into Y_mi = integral(L ybar) * MI_CIE_Y_NORMALIZATION, with
  MI_CIE_Y_NORMALIZATION = 1 / 106.7502594; its own ybar table integrates to 106.857, so a
  spectrum of specmap luminance Y renders at Y * 106.857 / 106.750.
* Mitsuba's ``envmap`` turns c into 2 max(c) S(lambda) D65(lambda) / 98.99741752
  (``srgb_model_eval`` times ``Texture::D65(1)``, MI_CIE_D65_NORMALIZATION), where the sRGB
  model's reflectance S reproduces c / (2 max c) under D65. Its luminance on the film is
  Y(c) * integral(D65n ybar) * MI_CIE_Y_NORMALIZATION = Y(c) * 0.99989.
* Equal luminance (and, the same argument for X and Z, equal colour) needs the factor
  k = integral(D65n ybar) / integral(ybar) = 106.739 / 106.857 = 0.99889, which
  :func:`radiometric_factor` computes at load time from Mitsuba's own ``cie1931_y`` and
  ``cie_d65``. The emitter returns k * scale * L_s.

Between texels the radiance is interpolated bilinearly. Mitsuba's ``envmap`` instead multiplies
the bilinear mean of its model's spectra by the bilinear mean of their scales, which next to a
bright texel (a sun) loses energy: on maps with sharp texel-to-texel contrast the two emitters
differ by that (docs/mitsuba.md, tools/mitsuba_interpolation.py).

Outside the file's wavelengths the radiance is 0 (as Mitsuba's ``regular`` spectrum). Mitsuba
gives a Python emitter no ``set_scene`` call: use :func:`load_dict` / :func:`load_file`, or call
:func:`fit_to_scene` after loading, so that shadow rays and emitted rays span the scene's
bounding sphere (before that a sphere of radius 1e4 about the origin is assumed).
"""
import array
import math
import re

import drjit as dr
import mitsuba as mi
import numpy as np

PLUGIN = "specmap_envmap"
# Until fit_to_scene: a sphere that contains any scene of ordinary size.
DEFAULT_RADIUS = 1e4
SPECTRAL_CHANNEL = re.compile(r"^S0\.(\d+(?:[.,]\d*)?)nm$")
ROWS = ("mitsuba", "specmap")
EPSILON = 2.0 ** -24  # Dr.Jit's Epsilon<float>, as envmap uses


class SpecmapMapError(ValueError):
    """A file that this emitter cannot read as a specmap map (the message names the file)."""


# ----------------------------------------------------------------------------- file reading

def _open_exr(path):
    """Header and channels (name -> 2D float array) of an OpenEXR file's first part."""
    try:
        import OpenEXR
    except ImportError as e:
        raise SpecmapMapError(f"{path}: reading specmap maps needs OpenEXR's Python binding "
                              f"(pip install OpenEXR): {e}") from None
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            header = dict(f.header())
            channels = {k: np.asarray(v.pixels, dtype=np.float32) for k, v in f.channels().items()}
    except Exception as e:  # OpenEXR raises RuntimeError or OSError, depending on the fault
        raise SpecmapMapError(f"{path}: not a readable OpenEXR file: {e}") from None
    return header, channels


def _ev_scale(path, header):
    """2^EV from the ``EV`` attribute (1 without it): the factor that restores the values."""
    ev = header.get("EV", 0.0)
    try:
        ev = float(ev)
    except (TypeError, ValueError):
        raise SpecmapMapError(f"{path}: the EV attribute is {ev!r}, not a number") from None
    if not math.isfinite(ev) or abs(ev) > 126:
        raise SpecmapMapError(f"{path}: the EV attribute {ev} is out of range")
    return 2.0 ** ev


def _check_layout(path, header, width, height):
    """Refuses cube maps (and anything not lat-long) with the command that converts them."""
    envmap = str(header.get("envmap", "")).upper()
    if "CUBE" in envmap or (not envmap and height == 6 * width):
        raise SpecmapMapError(
            f"{path}: a cube map; this emitter reads lat-long maps only: convert it with "
            f"`specmap convert IN -o OUT --out-layout latlong`")
    if width < 2 or height < 2:
        raise SpecmapMapError(f"{path}: {width}x{height} is too small for an environment map")


def _floats(path, header, name, length=None):
    """A floatvector attribute as an array, checked for presence and length."""
    if name not in header:
        raise SpecmapMapError(f"{path}: attribute {name} is missing")
    v = np.asarray(header[name], dtype=np.float64).ravel()
    if length is not None and v.size != length:
        raise SpecmapMapError(f"{path}: attribute {name} has {v.size} values, expected {length}")
    if not np.all(np.isfinite(v)):
        raise SpecmapMapError(f"{path}: attribute {name} has a value that is not finite")
    return v


def _channel(path, channels, name):
    if name not in channels:
        raise SpecmapMapError(f"{path}: channel {name} is missing")
    return channels[name].astype(np.float64)


def _read_spectral(path, header, channels):
    """Fichet (2021) emissive channels S0.<nm>nm, times 2^EV (the sun mask is not a band)."""
    bands = sorted((float(m.group(1).replace(",", ".")), name)
                   for name in channels if (m := SPECTRAL_CHANNEL.match(name)))
    if len(bands) < 2:
        raise SpecmapMapError(f"{path}: a spectral map needs two S0.<wavelength>nm channels or "
                              f"more, it has {len(bands)}")
    wavelengths = np.array([b[0] for b in bands])
    cube = np.stack([channels[b[1]] for b in bands], -1).astype(np.float64)
    return wavelengths, cube * _ev_scale(path, header)


def _read_basis_v1(path, header, channels):
    """``--format basis``: L = c_R B0 + c_G B1 + c_B B2 (times 2^EV) + sun * sunSPD.

    The writer divides c_R, c_G, c_B by 2^EV but stores the ``sun`` channel (the sun pixels'
    luminance, the weight of the sun's SPD) unscaled (the spectral writer's ``unscaled`` list), so only the
    three coefficients are multiplied back."""
    wavelengths = _floats(path, header, "specmap.wavelengths")
    n = wavelengths.size
    basis = np.stack([_floats(path, header, f"specmap.basis{j}", n) for j in range(3)])
    coef = np.stack([_channel(path, channels, c) for c in ("c_R", "c_G", "c_B")], -1)
    cube = (coef * _ev_scale(path, header)) @ basis
    if "sun" in channels and "specmap.sunSPD" in header:
        weight = channels["sun"].astype(np.float64)
        if not np.all(np.isfinite(weight)):
            raise SpecmapMapError(
                f"{path}: the sun channel holds values that are not finite (the basis writer "
                f"stores it without the EV scale, so a bright sun overflows half floats): "
                f"convert with --format basis --precision float")
        cube += weight[..., None] * _floats(path, header, "specmap.sunSPD", n)
    return wavelengths, cube


def _int_attr(path, header, name):
    if name not in header:
        raise SpecmapMapError(f"{path}: attribute {name} is missing")
    try:
        return int(header[name])
    except (TypeError, ValueError):
        raise SpecmapMapError(f"{path}: attribute {name} is {header[name]!r}, not an int") from None


def _read_basis_v2(path, header, channels):
    """Basis v2: L(lambda_i) = 2^EV sum_j k_j basis_j[i], K coefficients in channels kNN."""
    wavelengths = _floats(path, header, "specmap.wavelengths")
    n = wavelengths.size
    k = _int_attr(path, header, "specmap.basisK")
    if not 1 <= k <= 100:
        raise SpecmapMapError(f"{path}: specmap.basisK = {k}, expected 1 to 100")
    sun = _int_attr(path, header, "specmap.basisSun")
    if not -1 <= sun < k:
        raise SpecmapMapError(f"{path}: specmap.basisSun = {sun}, expected -1 to {k - 1}")
    basis = np.stack([_floats(path, header, f"specmap.basis{j:02d}", n) for j in range(k)])
    coef = np.stack([_channel(path, channels, f"k{j:02d}") for j in range(k)], -1)
    return wavelengths, (coef @ basis) * _ev_scale(path, header)


def read_map(path):
    """Reads a specmap map: (kind, wavelengths in nm (N,), absolute radiance (h, w, N) float64).

    kind is "spectral", "basis" (v1) or "basis-v2". Raises SpecmapMapError naming the file and
    what is missing for a file of neither format."""
    header, channels = _open_exr(path)
    if not channels:
        raise SpecmapMapError(f"{path}: the file has no channels")
    height, width = next(iter(channels.values())).shape[:2]
    _check_layout(path, header, width, height)
    if "specmap.basisVersion" in header:
        version = _int_attr(path, header, "specmap.basisVersion")
        if version != 2:
            raise SpecmapMapError(f"{path}: specmap.basisVersion {version} is not one this "
                                  f"emitter reads (2)")
        kind, (wl, cube) = "basis-v2", _read_basis_v2(path, header, channels)
    elif all(c in channels for c in ("c_R", "c_G", "c_B")):
        kind, (wl, cube) = "basis", _read_basis_v1(path, header, channels)
    elif any(SPECTRAL_CHANNEL.match(c) for c in channels):
        kind, (wl, cube) = "spectral", _read_spectral(path, header, channels)
    else:
        raise SpecmapMapError(
            f"{path}: neither a specmap spectral map (no S0.<wavelength>nm channels) nor a basis "
            f"map (no c_R, c_G, c_B channels, no specmap.basisVersion attribute); its channels "
            f"are {', '.join(sorted(channels))}")
    _check_grid(path, wl)
    bad = ~np.isfinite(cube)
    if bad.any():
        cube[bad] = 0.0  # as specmap's renderer: NaN and infinite values draw as black
    return kind, wl, cube


def _check_grid(path, wavelengths):
    """The bands must be evenly spaced and increasing (as specmap writes them)."""
    if wavelengths.size < 2:
        raise SpecmapMapError(f"{path}: needs two wavelengths or more, has {wavelengths.size}")
    step = np.diff(wavelengths)
    if step.min() <= 0 or step.max() - step.min() > 1e-4 * step.mean():
        raise SpecmapMapError(f"{path}: the wavelengths are not evenly spaced and increasing "
                              f"({wavelengths[0]}-{wavelengths[-1]} nm, {wavelengths.size} "
                              f"values); this emitter needs a uniform grid")


# ------------------------------------------------------------------------ radiometry helpers

def _mitsuba_tables(step=0.1):
    """Mitsuba's ybar and normalised D65 on a fine grid over 360-830 nm (their tables are
    piecewise linear at 5 nm, so the trapezoid rule on this grid is exact to rounding)."""
    lam = np.arange(360.0, 830.0 + step / 2, step)
    if dr.is_jit_v(mi.Float):
        y = mi.cie1931_y(mi.Float(lam)).numpy().astype(np.float64)
        d = mi.cie_d65(mi.Float(lam)).numpy().astype(np.float64)
    else:
        y = np.array([mi.cie1931_y(float(x)) for x in lam])
        d = np.array([mi.cie_d65(float(x)) for x in lam])
    return lam, y, d


def radiometric_factor():
    """k = integral(D65n ybar) / integral(ybar) with Mitsuba's tables (see the module's
    docstring): the factor that gives a specmap spectrum the luminance Mitsuba's ``envmap``
    gives the RGB it came from."""
    lam, y, d = _mitsuba_tables()
    return float(np.trapezoid(d * y, lam) / np.trapezoid(y, lam))


def _luminance(wavelengths, cube):
    """Each texel's luminance (any positive multiple does for a sampling density)."""
    ybar = np.array([mi.cie1931_y(float(x)) for x in wavelengths]) if not dr.is_jit_v(mi.Float) \
        else mi.cie1931_y(mi.Float(wavelengths)).numpy().astype(np.float64)
    return np.maximum(cube @ ybar, 0.0)


def _is_jit():
    return dr.is_jit_v(mi.Float)


def _zeros(cls):
    """A zero-initialised Mitsuba record (scalar variants construct it directly)."""
    return dr.zeros(cls) if _is_jit() else cls()


def _warp_grid(lum, rows):
    """The luminance sampling grid, as Mitsuba's ``envmap`` builds it: W + 1 columns at
    u = (x + 0.5) / W (the last repeats the first), rows at v = r / (R - 1), each times
    sin(pi v). With ``rows="specmap"`` the R = h + 1 grid rows lie between texel rows and take
    the texture's value there (the mean of the two rows around them)."""
    grid = np.concatenate([lum, lum[:, :1]], 1)
    if rows == "specmap":
        grid = np.concatenate([grid[:1], 0.5 * (grid[1:] + grid[:-1]), grid[-1:]], 0)
    theta = np.linspace(0.0, math.pi, grid.shape[0])
    grid = grid * np.sin(theta)[:, None]
    if not np.any(grid > 0):
        grid = np.ones_like(grid)  # a black map: sample uniformly (every weight is 0)
    return grid.astype(np.float32)


class SpecmapEnvmap(mi.Emitter):
    """Environment emitter of a specmap spectral or basis EXR (see the module's docstring)."""

    def __init__(self, props):
        super().__init__(props)
        if not mi.is_spectral:
            raise RuntimeError(f"{PLUGIN} needs a spectral variant (e.g. scalar_spectral), not "
                               f"{mi.variant()}")
        if not props.has_property("filename"):
            raise SpecmapMapError(f"{PLUGIN}: the filename parameter is missing")
        name = str(props["filename"])
        self.filename = str(mi.Thread.thread().file_resolver().resolve(name))
        self.scale = float(props.get("scale", 1.0))
        self.rows = str(props.get("rows", "mitsuba"))
        if self.rows not in ROWS:
            raise ValueError(f"{PLUGIN}: rows = {self.rows!r}, expected one of {ROWS}")
        to_world = props.get("to_world", mi.ScalarTransform4f())  # double precision
        self._to_world = mi.Transform4f(np.array(to_world.matrix, dtype=np.float32))
        self._to_local = self._to_world.inverse()
        self.kind, wavelengths, cube = read_map(self.filename)
        self._load(wavelengths, cube)
        self.set_bounds(None)
        self.m_flags = mi.EmitterFlags.Infinite | mi.EmitterFlags.SpatiallyVarying

    def _load(self, wavelengths, cube):
        """Keeps the radiance (times the radiometric factor) flat, and builds the warp."""
        self.height, self.width, self.bands = cube.shape
        self.lambda0 = float(wavelengths[0])
        self.step = float((wavelengths[-1] - wavelengths[0]) / (wavelengths.size - 1))
        self.factor = radiometric_factor()
        flat = (cube * self.factor).astype(np.float32).ravel()
        # Scalar variants index it from Python: a compact array of float32 (4 bytes a value).
        self._data = mi.Float(flat) if _is_jit() else array.array("f", flat.tobytes())
        self._warp = mi.Hierarchical2D0(_warp_grid(_luminance(wavelengths, cube), self.rows))
        self._half_texel = 0.5 / self.width

    def set_bounds(self, bbox):
        """The scene's bounding sphere, as ``envmap``'s ``set_scene`` takes it (None: the
        default sphere of radius DEFAULT_RADIUS about the origin)."""
        if bbox is None:
            center, radius = [0.0, 0.0, 0.0], DEFAULT_RADIUS
        elif bbox.valid():
            sphere = bbox.bounding_sphere()
            eps = float(mi.math.RayEpsilon)
            center, radius = sphere.center, max(eps, float(sphere.radius) * (1 + eps))
        else:
            center, radius = [0.0, 0.0, 0.0], float(mi.math.RayEpsilon)
        self._center = mi.Point3f(center)
        self._radius = mi.Float(radius)

    # ------------------------------------------------------------------ texture lookups

    def _fetch(self, index, active):
        if _is_jit():
            return dr.gather(mi.Float, self._data, index, active)
        return self._data[int(index)]

    def _corners(self, uv):
        """The four texels around uv and their bilinear weights: periodic in u with texel
        centres at (x + 0.5) / w, rows at the ``rows`` convention, clamped in v."""
        w, h = self.width, self.height
        u = uv.x - dr.floor(uv.x)
        v = dr.clip(uv.y, 0.0, 1.0)
        xf = u * w - 0.5
        x0f = dr.floor(xf)
        fx = xf - x0f
        x0 = mi.Int32(x0f)
        x0 = dr.select(x0 < 0, x0 + w, x0)
        x1 = dr.select(x0 + 1 >= w, x0 + 1 - w, x0 + 1)
        yf = v * (h - 1) if self.rows == "mitsuba" else dr.clip(v * h - 0.5, 0.0, h - 1.0)
        y0f = dr.minimum(dr.floor(yf), h - 2.0)
        fy = yf - y0f
        r0 = mi.Int32(y0f) * w
        r1 = r0 + w
        return [(r0 + x0, (1 - fx) * (1 - fy)), (r0 + x1, fx * (1 - fy)),
                (r1 + x0, (1 - fx) * fy), (r1 + x1, fx * fy)]

    def _eval_spectrum(self, uv, wavelengths, active):
        """Radiance at texture coordinates uv and the query's wavelengths: bilinear in space,
        linear in wavelength between the file's bands, 0 outside them."""
        if not _is_jit():
            if not active:
                return mi.UnpolarizedSpectrum(0.0)
            return mi.UnpolarizedSpectrum(self._eval_scalar(uv.x, uv.y, wavelengths)) * self.scale
        corners = self._corners(uv)
        n = self.bands
        lanes = []
        for i in range(dr.size_v(mi.Spectrum)):
            t = (wavelengths[i] - self.lambda0) / self.step
            inside = active & (t >= 0.0) & (t <= n - 1.0)
            b0f = dr.clip(dr.floor(t), 0.0, n - 2.0)
            ft = t - b0f
            b0 = mi.UInt32(b0f)
            acc = 0.0
            for texel, weight in corners:
                base = mi.UInt32(texel) * n + b0
                a, b = self._fetch(base, inside), self._fetch(base + 1, inside)
                acc = acc + weight * ((1.0 - ft) * a + ft * b)
            lanes.append(dr.select(inside, acc, 0.0))
        return mi.UnpolarizedSpectrum(lanes) * self.scale

    def _eval_scalar(self, u, v, wavelengths):
        """_eval_spectrum's arithmetic on Python floats (scalar variants call the emitter once
        per query, where Dr.Jit's dispatch on scalars costs more than the arithmetic)."""
        w, h, n = self.width, self.height, self.bands
        xf = (u - math.floor(u)) * w - 0.5
        x0 = math.floor(xf)
        fx = xf - x0
        x0, x1 = x0 % w, (x0 + 1) % w
        v = min(max(v, 0.0), 1.0)
        yf = v * (h - 1) if self.rows == "mitsuba" else min(max(v * h - 0.5, 0.0), h - 1.0)
        y0 = min(math.floor(yf), h - 2)
        fy = yf - y0
        r0, r1 = y0 * w, (y0 + 1) * w
        corners = ((r0 + x0, (1 - fx) * (1 - fy)), (r0 + x1, fx * (1 - fy)),
                   (r1 + x0, (1 - fx) * fy), (r1 + x1, fx * fy))
        data, out = self._data, []
        for lam in wavelengths:
            t = (lam - self.lambda0) / self.step
            if not 0.0 <= t <= n - 1.0:
                out.append(0.0)
                continue
            b0 = min(int(t), n - 2)
            ft = t - b0
            acc = 0.0
            for texel, weight in corners:
                i = texel * n + b0
                acc += weight * ((1.0 - ft) * data[i] + ft * data[i + 1])
            out.append(acc)
        return out

    # ------------------------------------------------------------------ mappings

    @staticmethod
    def _uv_to_direction(uv):
        """Local direction of uv and 1 / sin(theta) (Mitsuba ``envmap``'s mapping)."""
        sin_t, cos_t = dr.sincos(uv.y * dr.pi)
        sin_p, cos_p = dr.sincos(uv.x * 2.0 * dr.pi)
        inv_sin = dr.rcp(dr.maximum(sin_t, EPSILON))
        return mi.Vector3f(sin_p * sin_t, cos_t, -cos_p * sin_t), inv_sin

    @staticmethod
    def _direction_to_uv(d):
        return mi.Point2f(dr.atan2(d.x, -d.z) * dr.inv_two_pi, dr.safe_acos(d.y) * dr.inv_pi)

    def _emitter_ptr(self):
        return mi.EmitterPtr(self) if _is_jit() else self

    # ------------------------------------------------------------------ Emitter interface

    def eval(self, si, active=True):
        uv = self._direction_to_uv(self._to_local @ (-si.wi))
        return self._eval_spectrum(uv, si.wavelengths, active)

    def _sample_uv(self, sample, active):
        """A texture coordinate sampled by luminance, and its density per unit solid angle."""
        uv, pdf = self._warp.sample(sample, active=active)
        uv = mi.Point2f(uv.x + self._half_texel, uv.y)
        d, inv_sin = self._uv_to_direction(uv)
        return uv, d, pdf * inv_sin * (1.0 / (2.0 * dr.pi * dr.pi))

    def sample_direction(self, it, sample, active=True):
        uv, d, pdf = self._sample_uv(sample, active)
        active = active & (pdf > 0.0)
        radius = dr.maximum(self._radius, dr.norm(it.p - self._center))
        dist = 2.0 * radius
        d = self._to_world @ d
        ds = _zeros(mi.DirectionSample3f)
        ds.p = it.p + d * dist
        ds.n = -d
        ds.uv = uv
        ds.time = it.time
        ds.pdf = dr.select(active, pdf, 0.0)
        ds.delta = False
        ds.emitter = self._emitter_ptr()
        ds.d = d
        ds.dist = dist
        value = self._eval_spectrum(uv, it.wavelengths, active)
        weight = dr.select(active, value / dr.select(active, pdf, 1.0), 0.0)
        return ds, weight

    def pdf_direction(self, it, ds, active=True):
        d = self._to_local @ ds.d
        uv = self._direction_to_uv(d)
        uv = mi.Point2f(uv.x - self._half_texel, uv.y)
        uv = uv - dr.floor(uv)
        inv_sin = dr.rsqrt(dr.maximum(d.x * d.x + d.z * d.z,
                                           dr.square(EPSILON)))
        return self._warp.eval(uv, active=active) * inv_sin * (1.0 / (2.0 * dr.pi * dr.pi))

    def eval_direction(self, it, ds, active=True):
        return self._eval_spectrum(ds.uv, it.wavelengths, active)

    def sample_wavelengths(self, si, sample, active=True):
        """Wavelengths by Mitsuba's RGB importance spectrum; weight = radiance / pdf."""
        wavelengths, weight = mi.sample_rgb_spectrum(mi.sample_shifted(sample))
        return wavelengths, weight * self._eval_spectrum(si.uv, wavelengths, active)

    def pdf_wavelengths(self, wavelengths, active=True):
        return mi.pdf_rgb_spectrum(wavelengths)

    def sample_ray(self, time, sample1, sample2, sample3, active=True):
        """A ray from the bounding sphere's disk towards the scene (``envmap``'s sample_ray)."""
        offset = mi.warp.square_to_uniform_disk_concentric(sample2)
        uv, d, pdf = self._sample_uv(sample3, active)
        active = active & (pdf > 0.0)
        d_global = self._to_world @ (-d)
        perpendicular = mi.Frame3f(d).to_world(mi.Vector3f(offset.x, offset.y, 0.0))
        origin = self._center + (perpendicular - d_global) * self._radius
        si = _zeros(mi.SurfaceInteraction3f)
        si.t, si.time, si.p, si.uv = 0.0, time, origin, uv
        wavelengths, weight = self.sample_wavelengths(si, sample1, active)
        ray = mi.Ray3f(origin, d_global, time, wavelengths)
        weight = weight * (dr.pi * dr.square(self._radius) / dr.select(active, pdf, 1.0))
        return ray, dr.select(active, weight, 0.0)

    def sample_position(self, time, sample, active=True):
        if _is_jit():
            return _zeros(mi.PositionSample3f), dr.nan
        raise NotImplementedError(f"{PLUGIN}: sample_position (an infinite emitter)")

    def pdf_position(self, ps, active=True):
        return mi.Float(0.0)

    def bbox(self):
        return mi.ScalarBoundingBox3f()  # invalid: the emitter occupies no region of space

    def to_string(self):
        return (f"SpecmapEnvmap[filename={self.filename!r}, kind={self.kind}, "
                f"res={self.width}x{self.height}, bands={self.bands} "
                f"({self.lambda0:g}-{self.lambda0 + self.step * (self.bands - 1):g} nm), "
                f"scale={self.scale}, rows={self.rows}, factor={self.factor:.6f}]")


# ------------------------------------------------------------------------ scene helpers

def fit_to_scene(scene):
    """Gives every specmap_envmap of a loaded scene the scene's bounding sphere (what Mitsuba's
    ``set_scene`` does for ``envmap``, which it cannot do for a Python emitter). Returns scene."""
    for emitter in scene.emitters():
        if isinstance(emitter, SpecmapEnvmap):
            emitter.set_bounds(scene.bbox())
    return scene


def load_dict(scene_dict, **kwargs):
    """mi.load_dict, then :func:`fit_to_scene`."""
    return fit_to_scene(mi.load_dict(scene_dict, **kwargs))


def load_file(path, **kwargs):
    """mi.load_file, then :func:`fit_to_scene`."""
    return fit_to_scene(mi.load_file(str(path), **kwargs))


mi.register_emitter(PLUGIN, lambda props: SpecmapEnvmap(props))
