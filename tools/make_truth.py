#!/usr/bin/env python3
"""Ground-truth spectral environment maps for `specmap rendition` (issue 8, part 1).

Each scene is a lat-long map whose spectra are known, written twice under tests/data/truth/:

- `<scene>.spectral.exr`: the truth, in the spectral OpenEXR layout of Fichet, Pacanowski and
  Wilkie (JCGT 2021) exactly as specmap writes it: channels `S0.<nm>nm` (comma decimal separator),
  `spectralLayoutVersion` = 1.0, `emissiveUnits` = W.m^-2.sr^-1, `envmap` = latlong, R, G, B
  preview channels, half floats, ZIP; scene parameters in `truth.*` attributes;
- `<scene>.rgb.exr`: the RGB map a user would have of the same scene: the spectra above (after
  their rounding to half) integrated with the CIE 1931 2° observer, XYZ = sum(L xbar) / sum(ybar)
  (the luminance scale of specmap, pbrt-v4 and Mitsuba 3; sum(ybar) over 380-780 nm at 5 nm),
  then linear Rec.709 / sRGB primaries with the D65 white, no chromatic adaptation (a low sun
  stays orange); float, ZIP, `envmap` = latlong.

and `manifest.json` lists every scene with its parameters.

Scenes (128x64 lat-long, OpenEXR orientation: Y up, the centre column looks down +Z):

- `sky_e<elevation>_t<turbidity>`: Mitsuba 3's `sunsky` emitter (Hosek-Wilkie 2012 sky and 2013
  sun), variant `scalar_spectral`, at sun elevations 5, 20, 45 and 70 degrees and turbidities
  2, 4 and 6, sun azimuth 30 degrees from +Z towards +X. The sky (sun_scale = 0) is evaluated at
  every upper-hemisphere pixel centre. The sun (sky_scale = 0) is a disk of 0.5358 degrees
  (Mitsuba's default aperture), far smaller than a pixel (2.8 degrees): its radiance is averaged
  over 61 directions across the disk, times the disk's solid angle, and the resulting irradiance
  goes into the one pixel that contains the sun's direction (radiance = irradiance / the pixel's
  solid angle). The lower hemisphere is a ground of the 24 ColorChecker patches (8 sectors of
  longitude x 3 bands of latitude), Lambertian, lit by the map's own upper hemisphere:
  L = rho(lambda) E(lambda) / pi, with E the cosine-weighted sum over the upper pixels (sky and
  sun) with their exact solid angles. Mitsuba's ground albedo (a parameter of the sky model) is
  left at its default, 0.3.
- `interior_fl2`, `interior_fl11`: a 5 x 3 x 6 m room seen from (0.3, 1.5, 0.2), lit by three
  0.25 x 3 m strips of fluorescent tubes on the ceiling (CIE FL2 or FL11, Lambertian emitters);
  walls neutral-8 with a band of six ColorChecker patches each (all 24 around the room), a
  light-skin floor, a white-9.5 ceiling. Direct light by a midpoint rule over each strip (the
  room is convex: nothing is shadowed), plus interreflection by the integrating-sphere estimate
  (the tubes' flux over the room's area, times rho/(1 - rho) with rho(lambda) the room's mean
  reflectance: a uniform, wall-tinted irradiance). 4x4 samples per pixel.
- `street_hps`: a night street 12 m wide between facades (15 m high) with shop fronts of the 24
  ColorChecker patches, a neutral-3.5 road and neutral-6.5 pavements, lit by seven high-pressure
  sodium lamps (specmap's `hps`) on 7 m poles, 15 m apart, alternating sides, each a 0.3 m sphere
  that emits downwards only (inverse-square, cosine law, no occlusion: the street is convex), under
  a dark sky glowing with sodium light at 1% of the road's luminance. 4x4 samples per pixel.
- `office_mixed`, `office_warm_tubes`, `street_mixed`, `room_incandescent_dusk`,
  `yard_overcast`: scenes of several lights of different kinds (tools/truth_mixed.py, whose
  header describes them).
- `studio_led`, `studio_tungsten`, `studio_flash`, `room_window_lamps`, `street_dusk`: scenes of
  the kinds real users' HDRIs show (tools/truth_studio.py, whose header describes them): a
  photographic studio with no sky under phosphor LED, tungsten or xenon-flash softboxes, a living
  room with a daylight window and warm LED lamps, a dusk street of sodium and LED lamps under a
  bright twilight sky.

Wavelengths: 5 nm bands. Mitsuba's spectral sunsky data are tabulated at 320, 360, ..., 720 nm
and interpolated linearly between; it returns NaN at exactly 720 nm and 0 beyond. So the skies
cover 380-720 nm (69 bands; the 720 nm band is evaluated at 719.999 nm, on the last segment),
and no values are invented beyond: `specmap rendition` integrates on the wavelengths both maps
share, 380-720 nm for a sky. The interiors and the street cover 380-780 nm (81 bands): their
tables do. The RGB of a sky integrates the CMFs over 380-720 nm only (ybar beyond 720 nm holds
about 1e-4 of its integral).

Surfaces are the ColorChecker of Ohta (1997) (`spectra/reflectance/colorchecker-ohta.csv`, 380-780
nm at 5 nm, so no resampling or extrapolation), a different measurement of the chart from the
BabelColor average that `specmap rendition` lights as its test patches. Lights are specmap's
built-in tables (spectra/), exported from colour-science 0.4.7.

How to run it (from the repository root; mitsuba lives in its own, git-ignored venv so that the
interop-test venv, .venv, stays as CI builds it):

    python3 -m venv .venv-truth
    .venv-truth/bin/pip install mitsuba==3.9.1 colour-science==0.4.7 OpenEXR==3.5.3 numpy==2.4.6
    .venv-truth/bin/python tools/make_truth.py                 # every scene, about a minute
    .venv-truth/bin/python tools/make_truth.py --only street_hps interior_fl2

The interiors and the street need no mitsuba. The output is deterministic.
"""
import argparse
import csv
import json
import math
import pathlib
import sys

import warnings

import numpy as np
import OpenEXR

warnings.filterwarnings("ignore", message=".*related API features are not available.*")
import colour  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
SPECTRA = ROOT / "spectra"
WIDTH, HEIGHT = 128, 64
STEP = 5.0
SKY_ELEVATIONS = (5, 20, 45, 70)
SKY_TURBIDITIES = (2, 4, 6)
SUN_AZIMUTH_DEG = 30.0
SUN_APERTURE_DEG = 0.5358  # Mitsuba's default: the sun disk's full angle
MITSUBA_MAX_NM = 720.0

CMFS_1931 = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
SRGB = colour.RGB_COLOURSPACES["sRGB"]
M_XYZ_TO_RGB = np.linalg.inv(colour.normalised_primary_matrix(SRGB.primaries, SRGB.whitepoint))
YBAR_SUM = CMFS_1931.copy().align(colour.SpectralShape(380, 780, 5)).values[:, 1].sum()


# ----------------------------------------------------------------------------------------------
# Tables


def read_table(path):
    """A specmap CSV table: wavelengths and {column: values}."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    names = rows[0][1:]
    data = np.array([[float(v) for v in r] for r in rows[1:]])
    return data[:, 0], {n: data[:, i + 1] for i, n in enumerate(names)}


def on_grid(wl_table, values, wl):
    """A 5 nm table restricted to the grid `wl` (the tables used here are all at 5 nm)."""
    idx = np.searchsorted(wl_table, wl)
    if not np.allclose(wl_table[idx], wl):
        raise SystemExit(f"table not sampled at {wl[0]}..{wl[-1]} nm every {STEP} nm")
    return values[idx]


def grid(end_nm):
    return np.arange(380.0, end_nm + STEP / 2, STEP)


PATCH_WL, PATCHES = read_table(SPECTRA / "reflectance" / "colorchecker-ohta.csv")
PATCH_NAMES = list(PATCHES)


def patch(name_or_index, wl):
    name = PATCH_NAMES[name_or_index] if isinstance(name_or_index, int) else name_or_index
    return on_grid(PATCH_WL, PATCHES[name], wl)


def light(kind, name, wl):
    w, cols = read_table(SPECTRA / kind / f"{name}.csv")
    return on_grid(w, cols[name], wl)


# ----------------------------------------------------------------------------------------------
# Lat-long geometry (OpenEXR orientation, pixel centres at (i + 0.5) / N, as specmap's src/envmap/layout/)


def latlong_dirs(w, h, ss=1):
    """Unit directions, shape (h, w, ss*ss, 3): ss x ss samples spread evenly over each pixel."""
    off = (np.arange(ss) + 0.5) / ss
    u = (np.arange(w)[None, :, None, None] + off[None, None, None, :]) / w
    v = (np.arange(h)[:, None, None, None] + off[None, None, :, None]) / h
    lon = -2.0 * np.pi * (u - 0.5)
    lat = -np.pi * (v - 0.5)
    lon, lat = np.broadcast_arrays(lon, lat)
    d = np.stack([np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)], -1)
    return d.reshape(h, w, ss * ss, 3)


def solid_angles(w, h):
    t = np.pi * np.arange(h + 1) / h
    band = 2.0 * np.pi / w * (np.cos(t[:-1]) - np.cos(t[1:]))
    return np.repeat(band[:, None], w, 1)


def pixel_of(d, w, h):
    lon = math.atan2(d[0], d[2])
    lat = math.asin(max(-1.0, min(1.0, d[1])))
    u = 0.5 - lon / (2.0 * math.pi)
    v = 0.5 - lat / math.pi
    return min(int(u * w), w - 1), min(int(v * h), h - 1)


def irradiance(radiance, normal):
    """E(lambda) = sum over pixels of L max(0, n . w) dOmega (radiance: (h, w, bands))."""
    h, w, _ = radiance.shape
    cosw = np.maximum(0.0, latlong_dirs(w, h)[:, :, 0, :] @ np.asarray(normal, float))
    return np.einsum("hw,hwb->b", cosw * solid_angles(w, h), radiance)


# ----------------------------------------------------------------------------------------------
# Output


def xyz_of(spectra, wl):
    """XYZ with specmap's luminance scale: sum(L xbar) / sum(ybar over 380-780 nm at 5 nm)."""
    cmfs = CMFS_1931.copy().align(colour.SpectralShape(wl[0], wl[-1], STEP)).values
    return spectra @ cmfs / YBAR_SUM


def rgb_of(spectra, wl):
    return xyz_of(spectra, wl) @ M_XYZ_TO_RGB.T


def channel_name(nm):
    return "S0." + f"{nm:.6f}".replace(".", ",") + "nm"


def write_exr(path, channels, attrs):
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "envmap": OpenEXR.ENVMAP_LATLONG, **attrs}
    tmp = path.with_name(f".{path.name}.tmp.exr")
    with OpenEXR.File(header, channels) as f:
        f.write(str(tmp))
    tmp.replace(path)


def write_scene(out, name, wl, radiance, params):
    """Rounds the spectra to half, derives the RGB from the rounded spectra, writes both files.
    With `balance` in params (a table of spectra/light), the RGB map is white-balanced to that
    light: its RGB divided out, so that the light is (1, 1, 1)."""
    radiance = np.asarray(radiance, np.float64)
    if not np.isfinite(radiance).all() or radiance.min() < 0:
        raise SystemExit(f"{name}: non-finite or negative radiance")
    if radiance.max() >= 65504:
        raise SystemExit(f"{name}: radiance {radiance.max()} does not fit in half")
    half = radiance.astype(np.float16)
    rgb = rgb_of(half.astype(np.float64), wl)
    if "balance" in params:
        white = light("light", params["balance"], wl)
        white_rgb = rgb_of(white, wl) / xyz_of(white, wl)[1]
        rgb = rgb / white_rgb
    rgb = rgb.astype(np.float32)
    text = {f"truth.{k}": str(v) for k, v in params.items()}
    spectral = {channel_name(nm): np.ascontiguousarray(half[..., i]) for i, nm in enumerate(wl)}
    for i, c in enumerate("RGB"):
        spectral[c] = np.ascontiguousarray(rgb[..., i]).astype(np.float16)
    write_exr(out / f"{name}.spectral.exr", spectral,
              {"spectralLayoutVersion": "1.0", "emissiveUnits": "W.m^-2.sr^-1", **text})
    write_exr(out / f"{name}.rgb.exr",
              {c: np.ascontiguousarray(rgb[..., i]) for i, c in enumerate("RGB")}, text)
    e_up = irradiance(half.astype(np.float64), [0, 1, 0])
    xy = colour.XYZ_to_xy(xyz_of(e_up, wl))
    cct = [colour.temperature.xy_to_CCT(xy, method="McCamy 1992")]
    print(f"{name:<16} {wl[0]:.0f}-{wl[-1]:.0f} nm, {len(wl)} bands; E(up) xy "
          f"{xy[0]:.4f} {xy[1]:.4f}, CCT {cct[0]:.0f} K; max radiance {radiance.max():.4g}",
          flush=True)
    return {"name": name, "spectral": f"{name}.spectral.exr", "rgb": f"{name}.rgb.exr",
            "wavelengths_nm": [wl[0], wl[-1], STEP], "width": WIDTH, "height": HEIGHT,
            "irradiance_up_xy": [round(xy[0], 5), round(xy[1], 5)],
            "irradiance_up_cct_mccamy_K": round(float(cct[0]), 1), **params}


# ----------------------------------------------------------------------------------------------
# Clear skies (Mitsuba 3 sunsky)


def to_mitsuba(d):
    """OpenEXR world (Y up) -> the sunsky emitter's local frame (Z up): a rotation about X."""
    return [d[0], -d[2], d[1]]


def sun_disk(sun):
    """61 directions across the sun's disk (Mitsuba's aperture) around `sun`: its centre and rings
    of 6k directions at (k - 1/2)/4 of the radius, k = 1..4; and their weights (each ring's share
    of the disk's area), summing to 1."""
    half_ap = math.radians(SUN_APERTURE_DEG) / 2
    t1 = np.cross(sun, [0.0, 1.0, 0.0])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(sun, t1)
    samples, weights = [sun], [1.0]
    for k in range(1, 5):
        r = (k - 0.5) / 4 * half_ap
        for j in range(6 * k):
            phi = 2 * math.pi * (j + 0.5 * (k % 2)) / (6 * k)
            d = math.cos(r) * sun + math.sin(r) * (math.cos(phi) * t1 + math.sin(phi) * t2)
            samples.append(d)
            weights.append(2 * k - 1)  # ring area share
    weights = np.array(weights, float)
    return samples, weights / weights.sum()


def sky_scene(mi, dr, elevation_deg, turbidity):
    wl = grid(MITSUBA_MAX_NM)
    wl_eval = np.minimum(wl, MITSUBA_MAX_NM - 1e-3)  # NaN at exactly 720 nm
    el, az = math.radians(elevation_deg), math.radians(SUN_AZIMUTH_DEG)
    sun = np.array([math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el)])
    common = {"type": "sunsky", "sun_direction": to_mitsuba(sun), "turbidity": float(turbidity),
              "sun_aperture": SUN_APERTURE_DEG}
    sky = mi.load_dict({**common, "sun_scale": 0.0})
    sun_only = mi.load_dict({**common, "sky_scale": 0.0})
    quads = [wl_eval[i:i + 4] for i in range(0, len(wl_eval), 4)]

    def evaluate(emitter, d):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = -mi.Vector3f(to_mitsuba(d))
        out = []
        for q in quads:
            qq = list(q) + [q[-1]] * (4 - len(q))
            si.wavelengths = mi.Spectrum(qq)
            v = emitter.eval(si)
            out.extend(float(v[i]) for i in range(len(q)))
        return np.array(out)

    dirs = latlong_dirs(WIDTH, HEIGHT)[:, :, 0, :]
    omega = solid_angles(WIDTH, HEIGHT)
    radiance = np.zeros((HEIGHT, WIDTH, len(wl)))
    upper = HEIGHT // 2
    for y in range(upper):
        for x in range(WIDTH):
            radiance[y, x] = evaluate(sky, dirs[y, x])
    # The sun: average radiance over its disk (rings of 6k directions at k/4 of the radius),
    # times the disk's solid angle, into the pixel that holds its direction.
    samples, weights = sun_disk(sun)
    sun_l = sum(wt * evaluate(sun_only, d) for wt, d in zip(weights, samples))
    if not (sun_l > 0).all():
        raise SystemExit("the sun disk was missed: check the sun's sampling")
    omega_sun = 2 * math.pi * (1 - math.cos(math.radians(SUN_APERTURE_DEG) / 2))
    sx, sy = pixel_of(sun, WIDTH, HEIGHT)
    radiance[sy, sx] += sun_l * omega_sun / omega[sy, sx]
    # The ground: ColorChecker patches lit by the upper hemisphere.
    e_up = irradiance(radiance, [0, 1, 0])
    bands = np.array_split(np.arange(upper, HEIGHT), 3)
    sectors = np.array_split(np.arange(WIDTH), 8)
    for b, rows in enumerate(bands):
        for s, cols in enumerate(sectors):
            radiance[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1] = \
                patch(b * 8 + s, wl) * e_up / np.pi
    sun_pixel_dir = dirs[sy, sx]
    params = {
        "kind": "clear sky (Mitsuba 3 sunsky, Hosek-Wilkie) over a ColorChecker ground",
        "mitsuba": mi.__version__, "variant": "scalar_spectral",
        "sun_elevation_deg": elevation_deg, "sun_azimuth_deg": SUN_AZIMUTH_DEG,
        "turbidity": turbidity, "sun_aperture_deg": SUN_APERTURE_DEG, "ground_albedo": 0.3,
        "sun_pixel": [sx, sy],
        "sun_pixel_elevation_deg": round(math.degrees(math.asin(sun_pixel_dir[1])), 4),
        "right_light": "D65 (daylight)",
    }
    return wl, radiance, params


# ----------------------------------------------------------------------------------------------
# Interiors (fluorescent tubes) and a night street (sodium lamps): small numpy ray casters


def box_hit(origin, d, lo, hi):
    """Exit point of rays from inside an axis-aligned box: point, face index (axis*2 + side)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t_hi = (np.asarray(hi) - origin) / d
        t_lo = (np.asarray(lo) - origin) / d
    t = np.where(d > 0, t_hi, np.where(d < 0, t_lo, np.inf))
    axis = np.argmin(t, -1)
    tmin = np.take_along_axis(t, axis[..., None], -1)[..., 0]
    side = np.take_along_axis(d, axis[..., None], -1)[..., 0] > 0
    return origin + tmin[..., None] * d, axis * 2 + side


def interior_scene(tube):
    wl = grid(780.0)
    spd = light("illuminant", tube, wl)
    lo, hi = np.array([-2.5, 0.0, -3.0]), np.array([2.5, 3.0, 3.0])
    eye = np.array([0.3, 1.5, 0.2])
    strips = [(-1.2, 0.25), (0.0, 0.25), (1.2, 0.25)]  # (x centre, width), z in [-1.5, 1.5]
    strip_len = 3.0
    # Tube radiance: luminance 1000 (specmap's Y scale).
    tube_l = spd * 1000.0 / xyz_of(spd, wl)[1]
    ss = 4
    dirs = latlong_dirs(WIDTH, HEIGHT, ss).reshape(-1, 3)
    p, face = box_hit(eye, dirs, lo, hi)
    normals = np.zeros_like(p)
    ax, side = face // 2, face % 2
    normals[np.arange(len(p)), ax] = np.where(side == 1, -1.0, 1.0)  # facing into the room
    on_ceiling = face == 3
    in_strip = np.zeros(len(p), bool)
    for xc, wd in strips:
        in_strip |= on_ceiling & (np.abs(p[:, 0] - xc) <= wd / 2) & (np.abs(p[:, 2]) <= strip_len / 2)
    # Irradiance per unit tube radiance: midpoint rule over 4 x 60 cells per strip.
    src, area = [], []
    for xc, wd in strips:
        xs = xc + (np.arange(4) + 0.5) / 4 * wd - wd / 2
        zs = (np.arange(60) + 0.5) / 60 * strip_len - strip_len / 2
        gx, gz = np.meshgrid(xs, zs)
        src.append(np.stack([gx.ravel(), np.full(gx.size, hi[1]), gz.ravel()], -1))
        area.append(np.full(gx.size, wd / 4 * strip_len / 60))
    src, area = np.concatenate(src), np.concatenate(area)
    g = np.zeros(len(p))
    for i in range(0, len(p), 4096):
        q, n = p[i:i + 4096, None, :], normals[i:i + 4096, None, :]
        v = src[None] - q
        r2 = (v * v).sum(-1)
        r = np.sqrt(r2)
        cos_r = np.maximum(0.0, (v * n).sum(-1) / r)
        cos_e = np.maximum(0.0, v[..., 1] / r)  # emitter faces -Y: cos = (q - s) . (0,-1,0) / r
        g[i:i + 4096] = (cos_r * cos_e * area / r2).sum(-1)
    # Materials.
    refl = np.tile(patch("neutral-8", wl), (len(p), 1))
    refl[face == 2] = patch("light-skin", wl)       # floor (y = 0)
    refl[face == 3] = patch("white-9.5", wl)        # ceiling
    wall_order = [0, 1, 4, 5]                        # -x, +x, -z, +z walls
    for k, f in enumerate(wall_order):
        m = (face == f) & (p[:, 1] >= 1.0) & (p[:, 1] <= 1.8)
        along = p[:, 2] if f < 2 else p[:, 0]
        span = 6.0 if f < 2 else 5.0
        cell = np.clip(((along + span / 2) / span * 6).astype(int), 0, 5)
        for c in range(6):
            refl[m & (cell == c)] = patch(k * 6 + c, wl)
    # Interreflection, the integrating-sphere estimate for a closed room: the tubes' flux
    # (pi L A_strips per unit radiance) spread over the room's area A, times rho / (1 - rho) with
    # rho(lambda) the room's area-weighted mean reflectance, reaches every surface alike.
    areas = {"floor": 30.0, "ceiling": 30.0 - 3 * 0.25 * strip_len, "walls": 66.0 - 0.8 * 22.0,
             "patches": 0.8 * 22.0}
    rho = (areas["floor"] * patch("light-skin", wl) + areas["ceiling"] * patch("white-9.5", wl)
           + areas["walls"] * patch("neutral-8", wl)
           + areas["patches"] * np.mean([patch(i, wl) for i in range(24)], 0)) / sum(areas.values())
    strip_area = 3 * 0.25 * strip_len
    indirect = np.pi * strip_area / (sum(areas.values()) + strip_area) * rho / (1 - rho)
    radiance = refl * tube_l[None] * (g[:, None] + indirect[None]) / np.pi
    radiance[in_strip] = tube_l
    radiance = radiance.reshape(HEIGHT, WIDTH, ss * ss, len(wl)).mean(2)
    params = {"kind": f"room lit by {tube} fluorescent strips on the ceiling", "tube": tube,
              "tube_luminance": 1000.0, "right_light": tube}
    return wl, radiance, params


STREET_EYE = np.array([0.0, 1.6, 0.0])
STREET_HALF_W, FACADE_H, LAMP_H, LAMP_R = 6.0, 15.0, 7.0, 0.3
# Seven lamps on poles 15 m apart, alternating sides.
STREET_LAMPS = np.array([[4.5 if k % 2 == 0 else -4.5, LAMP_H, 15.0 * (k - 3)] for k in range(7)])


def street_hits(dirs):
    """Where rays from the eye meet the street: points, normals, what was hit (-1 the sky, 0 the
    road, 1 the facade at -x, 2 at +x, 3 a lamp) and which lamp (-1 for none)."""
    eye, half_w = STREET_EYE, STREET_HALF_W
    n_rays = len(dirs)
    t = np.full(n_rays, np.inf)
    kind = np.full(n_rays, -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_road = np.where(dirs[:, 1] < 0, -eye[1] / dirs[:, 1], np.inf)
        t_fx = np.where(dirs[:, 0] > 0, (half_w - eye[0]) / dirs[:, 0],
                        np.where(dirs[:, 0] < 0, (-half_w - eye[0]) / dirs[:, 0], np.inf))
    y_at_facade = eye[1] + t_fx * dirs[:, 1]
    t_fx = np.where((y_at_facade >= 0) & (y_at_facade <= FACADE_H), t_fx, np.inf)
    take = t_road < t
    t[take], kind[take] = t_road[take], 0
    take = t_fx < t
    t[take], kind[take] = t_fx[take], np.where(dirs[take, 0] < 0, 1, 2)
    lamp_id = np.full(n_rays, -1)
    for k, c in enumerate(STREET_LAMPS):
        oc = eye - c
        b = dirs @ oc
        disc = b * b - (oc @ oc - LAMP_R ** 2)
        tl = np.where(disc > 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
        take = (tl > 0) & (tl < t)
        t[take], kind[take], lamp_id[take] = tl[take], 3, k
    p = eye + np.where(np.isfinite(t), t, 0)[:, None] * dirs
    normals = np.zeros_like(p)
    normals[kind == 0] = [0, 1, 0]
    normals[kind == 1] = [1, 0, 0]
    normals[kind == 2] = [-1, 0, 0]
    return p, normals, kind, lamp_id


def street_materials(p, kind, wl):
    """A neutral-3.5 road with neutral-6.5 pavements, facades with shop fronts of the 24 patches."""
    refl = np.zeros((len(p), len(wl)))
    road = kind == 0
    refl[road] = patch("neutral-3.5", wl)
    refl[road & (np.abs(p[:, 0]) >= 4.0)] = patch("neutral-6.5", wl)
    for side, base in ((1, "light-skin"), (2, "neutral-6.5")):
        m = kind == side
        refl[m] = patch(base, wl)
        shop = m & (p[:, 1] >= 0.5) & (p[:, 1] <= 3.5)
        cell = (np.floor((p[:, 2] + 300.0) / 3.0).astype(int) + (12 if side == 2 else 0)) % 24
        for c in range(24):
            refl[shop & (cell == c)] = patch(c, wl)
    return refl


def street(wl, lamp_spds, sky_spd, sky_fraction):
    """A night street 12 m wide between facades, seven lamps on 7 m poles 15 m apart, alternating
    sides, each a 0.3 m sphere of intensity 2000 x its spectrum (each at luminance 1) emitting
    downwards only, under a sky of `sky_spd` (luminance 1) at `sky_fraction` of the road's
    luminance under a lamp. Radiance per pixel, 4 x 4 samples each."""
    lamps = STREET_LAMPS
    # Intensity so that the road under a lamp has illuminance-like luminance ~ 1.
    intensities = [spd * 2000.0 for spd in lamp_spds]
    ss = 4
    dirs = latlong_dirs(WIDTH, HEIGHT, ss).reshape(-1, 3)
    n_rays = len(dirs)
    p, normals, kind, lamp_id = street_hits(dirs)
    surf = (kind == 0) | (kind == 1) | (kind == 2)
    # The lamps' geometric factors, summed over the lamps of each spectrum (in lamp order).
    groups = []
    for c, i_spd in zip(lamps, intensities):
        v = c - p
        r2 = (v * v).sum(-1)
        r = np.sqrt(r2)
        cos_r = np.maximum(0.0, (v * normals).sum(-1) / r)
        # The lamp emits downwards only: it lights the points below it.
        g = np.where(surf & (v[:, 1] > 0), cos_r / r2, 0.0)
        same = next((grp for grp in groups if np.array_equal(grp[0], i_spd)), None)
        if same is None:
            groups.append([i_spd, np.zeros(n_rays)])
            same = groups[-1]
        same[1] += g
    refl = street_materials(p, kind, wl)
    radiance = sum(refl * i_spd[None] * (g / np.pi)[:, None] for i_spd, g in groups)
    for k in range(len(lamps)):
        radiance[(kind == 3) & (lamp_id == k)] = intensities[k] / (np.pi * LAMP_R ** 2)
    road_l = xyz_of(patch("neutral-3.5", wl) * intensities[0] * (1.0 / (LAMP_H ** 2)) / np.pi,
                    wl)[1]
    radiance[kind == -1] = sky_spd * sky_fraction * road_l
    return radiance.reshape(HEIGHT, WIDTH, ss * ss, len(wl)).mean(2)


def street_scene():
    """Seven of specmap's `hps` lamps under a dark sky glowing with their light at 1%."""
    wl = grid(780.0)
    spd = light("light", "hps", wl)
    spd = spd / xyz_of(spd, wl)[1]
    radiance = street(wl, [spd] * 7, spd, 0.01)
    params = {"kind": "night street lit by high-pressure sodium lamps", "lamp": "hps",
              "lamps": 7, "right_light": "hps (HPS)"}
    return wl, radiance, params


# ----------------------------------------------------------------------------------------------


def main():
    import truth_mixed  # noqa: F401  (the multi-light scenes; it imports this module's helpers)
    import truth_studio  # noqa: F401  (studios, a living room, a dusk street: issue 41)
    globals()["truth_mixed"] = truth_mixed
    globals()["truth_studio"] = truth_studio
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=pathlib.Path, default=ROOT / "tests" / "data" / "truth")
    ap.add_argument("--only", nargs="*", help="scene names to (re)generate")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    names = [f"sky_e{e:02d}_t{t}" for e in SKY_ELEVATIONS for t in SKY_TURBIDITIES]
    names += ["interior_fl2", "interior_fl11", "street_hps"]
    names += list(truth_mixed.SCENES)
    names += list(truth_studio.SCENES)
    wanted = args.only or names
    unknown = set(wanted) - set(names)
    if unknown:
        raise SystemExit(f"unknown scenes {sorted(unknown)}; known: {', '.join(names)}")
    manifest_path = args.out / "manifest.json"
    manifest = {}
    if manifest_path.exists():
        manifest = {s["name"]: s for s in json.loads(manifest_path.read_text())["scenes"]}
    mi = dr = None
    for name in names:
        if name not in wanted:
            continue
        if name.startswith("sky_"):
            if mi is None:
                import drjit as dr  # noqa: F811
                import mitsuba as mi  # noqa: F811
                mi.set_variant("scalar_spectral")
            e, t = int(name[5:7]), int(name.split("_t")[1])
            wl, radiance, params = sky_scene(mi, dr, e, t)
        elif name.startswith("interior_"):
            wl, radiance, params = interior_scene(name.split("_")[1].upper())
        elif name in truth_mixed.SCENES:
            wl, radiance, params = truth_mixed.SCENES[name]()
        elif name in truth_studio.SCENES:
            wl, radiance, params = truth_studio.SCENES[name]()
        else:
            wl, radiance, params = street_scene()
        manifest[name] = write_scene(args.out, name, wl, radiance, params)
    doc = {"generator": "tools/make_truth.py", "colour_science": colour.__version__,
           "scenes": [manifest[n] for n in names if n in manifest]}
    manifest_path.write_text(json.dumps(doc, indent=1) + "\n")
    total = sum(f.stat().st_size for f in args.out.glob("*.exr"))
    print(f"{len(doc['scenes'])} scenes in {args.out}, {total / 1e6:.2f} MB of EXR")


if __name__ == "__main__":
    sys.exit(main())
