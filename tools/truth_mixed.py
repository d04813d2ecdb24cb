"""Ground-truth scenes with several lights of different kinds (issue 13), for make_truth.py.

Small numpy ray casters in the style of make_truth.py's interior and street, each returning
(wavelengths, radiance (HEIGHT, WIDTH, bands), params):

- `office_mixed`: a 6 x 3 x 5 m office with a 3 x 1.5 m window on its -x wall showing an
  overcast sky (CIE daylight 7000 K, luminance 1500) and two strips of f32t8-tl841 triphosphor
  tubes (4100 K, a measured lamp the converter does not match against; luminance 3000) on the
  ceiling towards +x: the walls by the window are lit mostly by daylight, those under the tubes
  mostly by them;
- `office_warm_tubes`: the same office with 3500 K f32t8-tl835 tubes and a 6000 K window (the
  tubes' white is the halophosphate FL3's, within a just noticeable difference, and no
  triphosphor table's);
- `street_mixed`: make_truth.py's street with six c100s54 high-pressure sodium lamps (a
  measured 100 W lamp, not the converter's `hps`) and one luxeon-ww-2880 warm-white LED lamp
  under a dim blue-hour sky (CIE daylight 9000 K at 2% of the road's luminance);
- `room_incandescent_dusk`: a 4 x 2.7 x 5 m room lit by three 60w-soft-white incandescent bulbs
  with a 2 x 1.4 m window on its +z wall showing a dusk sky (CIE daylight 12000 K, luminance
  25); its RGB map is white-balanced to the bulbs (their RGB divided out, so they are (1,1,1));
- `yard_overcast`: a 10 x 10 m courtyard with 8 m walls under a CIE overcast sky (daylight
  6500 K, zenith luminance 2000, L = Lz (1 + 2 sin elevation) / 3), the sun hidden behind a
  wall but shining through a gap onto a 2 x 2 m patch of yellow wall (CIE daylight 5500 K,
  30000 lux at 45 degrees): the brightest region of the map is a sunlit reflector, not a light.

Surfaces are the Ohta ColorChecker (neutral walls with bands of the 24 patches); lighting is
direct (midpoint rules over each emitter, the sky by 256 stratified directions per point) plus,
in the closed rooms, the integrating-sphere estimate of interreflection (each emitter's flux
over the room's area, times rho / (1 - rho)). 4 x 4 samples per pixel.
"""
import math

import numpy as np

import colour

from make_truth import (HEIGHT, WIDTH, box_hit, grid, latlong_dirs, light, patch, street, xyz_of)

SS = 4


def daylight(cct, wl):
    """CIE daylight of correlated colour temperature `cct` (colour-science), at luminance 1."""
    xy = colour.temperature.CCT_to_xy_CIE_D(cct * 1.4388 / 1.4380)
    sd = colour.sd_CIE_illuminant_D_series(xy).copy().align(colour.SpectralShape(380, 780, 5))
    v = np.interp(wl, sd.wavelengths, sd.values)
    return v / xyz_of(v, wl)[1]


def lamp(name, wl):
    """A measured lamp of spectra/light at luminance 1."""
    v = light("light", name, wl)
    return v / xyz_of(v, wl)[1]


def rect_gain(p, n, centre, a, b, m, cells=(12, 12), weight=None):
    """Per unit radiance of a Lambertian rectangle (centre, half-axes a, b, emitting towards
    m): the irradiance at points p with normals n, by the midpoint rule. `weight(u, v)` (u, v in
    [-1, 1] along a and b) scales the radiance over the face (None: uniform)."""
    us = ((np.arange(cells[0]) + 0.5) / cells[0]) * 2 - 1
    vs = ((np.arange(cells[1]) + 0.5) / cells[1]) * 2 - 1
    src = (np.asarray(centre)[None, None] + us[:, None, None] * np.asarray(a)
           + vs[None, :, None] * np.asarray(b)).reshape(-1, 3)
    area = 4 * np.linalg.norm(a) * np.linalg.norm(b) / src.shape[0]
    if weight is not None:
        area = area * weight(us[:, None], vs[None, :]).reshape(-1)
    g = np.zeros(len(p))
    for i in range(0, len(p), 2048):
        q, nn = p[i:i + 2048, None, :], n[i:i + 2048, None, :]
        v = src[None] - q
        r2 = (v * v).sum(-1)
        r = np.sqrt(r2)
        cos_r = np.maximum(0.0, (v * nn).sum(-1) / r)
        cos_e = np.maximum(0.0, -(v @ np.asarray(m)) / r)
        g[i:i + 2048] = (cos_r * cos_e * area / r2).sum(-1)
    return g


def cosine_directions(seed):
    """256 stratified cosine-weighted directions about +z (16 x 16 jittered strata, the jitter
    drawn with numpy's generator from `seed`), as an array (256, 3)."""
    rng = np.random.default_rng(seed)
    u = (np.arange(16)[:, None] + rng.random((16, 16))) / 16
    v = (np.arange(16)[None, :] + rng.random((16, 16))) / 16
    r, phi = np.sqrt(u.ravel()), 2 * np.pi * v.ravel()
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - r * r)], -1)


def around_normals(local, nn):
    """The directions `local` (about +z) turned about each normal of `nn`: (len(nn), n, 3)."""
    helper = np.where(np.abs(nn[:, 1:2]) < 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    t1 = np.cross(nn, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(nn, t1)
    return (local[None, :, 0:1] * t1[:, None] + local[None, :, 1:2] * t2[:, None]
            + local[None, :, 2:3] * nn[:, None])


def in_rect(p, centre, a, b):
    """Points p inside the rectangle: on its plane, within its half-axes."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = p - np.asarray(centre)
    m = np.cross(a, b)
    on_plane = np.abs(d @ (m / np.linalg.norm(m))) < 1e-6
    ua = (d @ a) / (a @ a)
    ub = (d @ b) / (b @ b)
    return on_plane & (np.abs(ua) <= 1) & (np.abs(ub) <= 1)


def face_normals(p, face):
    n = np.zeros_like(p)
    ax, side = face // 2, face % 2
    n[np.arange(len(p)), ax] = np.where(side == 1, -1.0, 1.0)  # facing into the room
    return n


def room_materials(p, face, lo, hi, wl, floor="light-skin", walls="neutral-8",
                   ceiling="white-9.5", band=(1.0, 1.8)):
    """Neutral walls with a band of the 24 patches around the room, a floor and a ceiling."""
    refl = np.tile(patch(walls, wl), (len(p), 1))
    refl[face == 2] = patch(floor, wl)
    refl[face == 3] = patch(ceiling, wl)
    spans = hi - lo
    for k, f in enumerate([0, 1, 4, 5]):
        m = (face == f) & (p[:, 1] >= band[0]) & (p[:, 1] <= band[1])
        along, span, start = ((p[:, 2], spans[2], lo[2]) if f < 2 else (p[:, 0], spans[0], lo[0]))
        cell = np.clip(((along - start) / span * 6).astype(int), 0, 5)
        for c in range(6):
            refl[m & (cell == c)] = patch(k * 6 + c, wl)
    return refl


def mean_reflectance(lo, hi, wl, floor="light-skin", walls="neutral-8", ceiling="white-9.5",
                     band=(1.0, 1.8)):
    s = hi - lo
    a_floor = s[0] * s[2]
    a_walls = 2 * (s[0] + s[2]) * s[1]
    a_band = 2 * (s[0] + s[2]) * (band[1] - band[0])
    rho = (a_floor * (patch(floor, wl) + patch(ceiling, wl)) + (a_walls - a_band) * patch(walls, wl)
           + a_band * np.mean([patch(i, wl) for i in range(24)], 0)) / (2 * a_floor + a_walls)
    return rho, 2 * a_floor + a_walls


def average_pixels(radiance):
    return radiance.reshape(HEIGHT, WIDTH, SS * SS, -1).mean(2)


def room(wl, lo, hi, eye, rects, bulbs, **materials):
    """A closed room lit by Lambertian rectangles on its surfaces ((centre, a, b, normal,
    radiance spectrum)) and spherical bulbs ((centre, radius, radiance spectrum)): radiance per
    supersample ray."""
    dirs = latlong_dirs(WIDTH, HEIGHT, SS).reshape(-1, 3)
    p, face = box_hit(eye, dirs, lo, hi)
    n = face_normals(p, face)
    refl = room_materials(p, face, lo, hi, wl, **materials)
    e = np.zeros((len(p), len(wl)))
    flux = np.zeros(len(wl))
    for centre, a, b, m, spd in rects:
        e += rect_gain(p, n, centre, a, b, m)[:, None] * spd[None]
        flux += math.pi * 4 * np.linalg.norm(a) * np.linalg.norm(b) * spd
    for centre, r, spd in bulbs:
        v = np.asarray(centre) - p
        d2 = (v * v).sum(-1)
        cos_r = np.maximum(0.0, (v * n).sum(-1) / np.sqrt(d2))
        intensity = math.pi * r * r * spd  # a Lambertian sphere: the same in every direction
        e += (cos_r / d2)[:, None] * intensity[None]
        flux += 4 * math.pi * math.pi * r * r * spd
    rho, area = mean_reflectance(lo, hi, wl, **materials)
    e += (flux / area * rho / (1 - rho))[None]
    radiance = refl * e / math.pi
    for centre, a, b, m, spd in rects:
        radiance[in_rect(p, centre, a, b)] = spd
    for centre, r, spd in bulbs:
        oc = eye - np.asarray(centre)
        bq = dirs @ oc
        disc = bq * bq - (oc @ oc - r * r)
        radiance[(disc > 0) & (-bq - np.sqrt(np.maximum(disc, 0)) > 0)] = spd
    return average_pixels(radiance)


def office(tube_name, window_k):
    """A 6 x 3 x 5 m office: a window of daylight `window_k` on its -x wall, two strips of
    `tube_name` tubes on the ceiling towards +x."""
    wl = grid(780.0)
    lo, hi = np.array([-3.0, 0.0, -2.5]), np.array([3.0, 3.0, 2.5])
    window = ([-3.0, 1.65, 0.0], [0.0, 0.75, 0.0], [0.0, 0.0, 1.5], [1.0, 0.0, 0.0],
              daylight(window_k, wl) * 1500.0)
    tube = lamp(tube_name, wl) * 3000.0
    tubes = [([x, 3.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.0, 1.5], [0.0, -1.0, 0.0], tube)
             for x in (0.5, 2.0)]
    return wl, room(wl, lo, hi, np.array([0.5, 1.5, 0.3]), [window] + tubes, [])


def office_mixed():
    wl, radiance = office("f32t8-tl841", 7000.0)
    return wl, radiance, {
        "kind": "office with an overcast window (daylight 7000 K) and f32t8-tl841 tubes",
        "lights": "window: daylight 7000 K; ceiling: f32t8-tl841 x 2",
        "right_light": "daylight for the window, fluorescent (triphosphor 4100 K) for the tubes"}


def office_warm_tubes():
    """office_mixed with 3500 K tubes (f32t8-tl835) and a 6000 K window: a tube whose white is a
    legacy halophosphate table's (FL3) and no triphosphor table's."""
    wl, radiance = office("f32t8-tl835", 6000.0)
    return wl, radiance, {
        "kind": "office with a daylight window (6000 K) and f32t8-tl835 tubes",
        "lights": "window: daylight 6000 K; ceiling: f32t8-tl835 x 2",
        "right_light": "daylight for the window, fluorescent (triphosphor 3500 K) for the tubes"}


def room_incandescent_dusk():
    wl = grid(780.0)
    lo, hi = np.array([-2.0, 0.0, -2.5]), np.array([2.0, 2.7, 2.5])
    bulb = lamp("60w-soft-white", wl) * 10000.0
    bulbs = [([x, 2.3, z], 0.06, bulb) for x, z in ((-1.0, -1.2), (1.0, -1.2), (0.0, 1.2))]
    window = ([0.0, 1.5, 2.5], [1.0, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, -1.0],
              daylight(12000.0, wl) * 25.0)
    radiance = room(wl, lo, hi, np.array([0.2, 1.4, -0.3]), [window], bulbs,
                    walls="neutral-6.5", floor="dark-skin")
    return wl, radiance, {
        "kind": "room lit by three 60w-soft-white bulbs, a dusk window (daylight 12000 K)",
        "balance": "60w-soft-white", "right_light": "A (--light A --white light)"}


def street_mixed():
    """make_truth.py's street: six c100s54 sodium lamps and one luxeon-ww-2880 LED lamp (15 m
    ahead on the right) under a blue-hour sky at 2% of the road's luminance."""
    wl = grid(780.0)
    spds = [lamp("c100s54", wl)] * 7
    spds[4] = lamp("luxeon-ww-2880", wl)
    radiance = street(wl, spds, daylight(9000.0, wl), 0.02)
    return wl, radiance, {
        "kind": "night street: six c100s54 sodium lamps, one luxeon-ww-2880 LED, blue-hour sky",
        "lamps": 7, "right_light": "sodium for six lamps, LED for one, daylight for the sky"}


def yard_overcast():
    wl = grid(780.0)
    lo, hi = np.array([-5.0, 0.0, -5.0]), np.array([5.0, 8.0, 5.0])
    eye = np.array([0.0, 1.6, 0.0])
    sky_spd = daylight(6500.0, wl)
    zenith = 2000.0
    dirs = latlong_dirs(WIDTH, HEIGHT, SS).reshape(-1, 3)
    p, face = box_hit(eye, dirs, lo, hi)
    sky = face == 3  # the open top
    n = face_normals(p, face)
    refl = np.tile(patch("neutral-6.5", wl), (len(p), 1))
    refl[face == 2] = patch("neutral-5", wl)
    band = (face != 2) & (face != 3) & (p[:, 1] >= 0.5) & (p[:, 1] <= 2.0)
    along = np.where(face < 2, p[:, 2], p[:, 0])
    order = np.select([face == 0, face == 1, face == 4], [0, 1, 2], 3)
    cell = order * 6 + np.clip(((along + 5.0) / 10.0 * 6).astype(int), 0, 5)
    for c in range(24):
        refl[band & (cell == c)] = patch(c, wl)
    # Sky light through the opening: 256 stratified cosine-weighted directions per point.
    local = cosine_directions(13)
    e_sky = np.zeros(len(p))
    for i in range(0, len(p), 1024):
        q, nn = p[i:i + 1024], n[i:i + 1024]
        w = around_normals(local, nn)
        with np.errstate(divide="ignore", invalid="ignore"):
            tt = (hi[1] - q[:, None, 1]) / w[..., 1]
        x = q[:, None, 0] + tt * w[..., 0]
        z = q[:, None, 2] + tt * w[..., 2]
        out = (w[..., 1] > 0) & (np.abs(x) <= 5) & (np.abs(z) <= 5)
        lum = zenith * (1 + 2 * np.clip(w[..., 1], 0, 1)) / 3
        e_sky[i:i + 1024] = np.pi * np.where(out, lum, 0.0).mean(1)
    radiance = refl * (e_sky[:, None] * sky_spd[None]) / np.pi
    # The sun through a gap: 30000 lux at 45 degrees on a 2 x 2 m yellow patch of the +x wall.
    patch_centre, a, b = [5.0, 4.0, -1.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]
    lit = (face == 1) & in_rect(p, patch_centre, a, b)
    sun_spd = daylight(5500.0, wl) * 30000.0 * math.cos(math.radians(45))
    refl[lit] = patch("yellow", wl)
    radiance[lit] = refl[lit] * (e_sky[lit, None] * sky_spd[None] + sun_spd[None]) / np.pi
    elev = np.clip(dirs[sky, 1], 0, 1)
    radiance[sky] = sky_spd[None] * (zenith * (1 + 2 * elev) / 3)[:, None]
    return wl, average_pixels(radiance), {
        "kind": "overcast courtyard (daylight 6500 K) with a small sunlit yellow wall",
        "right_light": "daylight (the sky); the sunlit wall is a reflector"}


SCENES = {
    "office_mixed": office_mixed,
    "office_warm_tubes": office_warm_tubes,
    "street_mixed": street_mixed,
    "room_incandescent_dusk": room_incandescent_dusk,
    "yard_overcast": yard_overcast,
}
