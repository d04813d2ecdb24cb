"""Ground-truth scenes of the kinds real users' HDRIs show (issue 41), for make_truth.py.

Small numpy ray casters in the style of truth_mixed.py, each returning (wavelengths, radiance
(HEIGHT, WIDTH, bands), params), 380-780 nm at 5 nm, 4 x 4 samples per pixel:

- `studio_led`, `studio_tungsten`, `studio_flash`: a photographic studio, a closed 8 x 4.5 x 10 m
  box (x in [-4, 4], y in [0, 4.5], z in [-5, 5]) seen from the subject's place (0, 1.6, 0). No
  sky. Walls and ceiling are black curtains (ColorChecker `black-2`, about 3%) with a band of the
  24 patches (8 coloured flats on each of the -x, +x and -z walls, 1.0-1.8 m high); the +z wall
  is a white cyclorama (`white-9.5`) curving into the floor through a quarter cylinder of radius
  1.5 m, its white running on over the floor to z = -1.5 m; the rest of the floor is grey
  concrete (`neutral-5`). Three softboxes face the subject: Lambertian 1 x 1.4 m rectangles,
  one-sided, with a gentle hot spot (`hot_spot`: 15% dimmer in the corners than at the centre,
  whose luminance is given), key (azimuth 140 degrees from +z towards +x, 35 degrees above the
  horizon, 3 m away horizontally, luminance 4000), fill (-130 degrees, 25 degrees, 3.2 m, 2000)
  and rim (35 degrees, 40 degrees, 2.5 m, 3000); their backs are black fabric. The lamps:
  - `studio_led`: `phosphor-led` (NIST CQS "Phosphor LED YAG": a blue pump at 465 nm and a broad
    YAG phosphor; CCT 6814 K, Duv +0.004 by Ohno 2013). It is the only measured daylight-white
    phosphor LED of spectra/light (phos-1..4 are NIST's modelled 3000 K spectra, 3-led/4-led
    are RGB mixes, luxeon-ww-2880 is 2880 K): no measured phosphor LED lies in 5000-6500 K,
    and this one, 300 K above, is the white of a "daylight" LED panel; the catalogue's nearest
    is LED-B5 (6598 K);
  - `studio_tungsten`: `incandescent` (NIST CQS "Incandescent", 2812 K; the same values as
    `60w-soft-white`): a measured filament, not a Planckian formula; the RGB is not balanced;
  - `studio_flash`: `kinoton-75p` (a xenon arc, 6343 K, tabulated at 2 nm: each 5 nm band is
    the mean of the piecewise-linear table over the band's +-2.5 nm) through a softbox diffuser
    of transmittance T(lambda) = 0.85 / (1 + exp(-(lambda - 405 nm) / 9 nm)) (a smooth,
    slightly UV-cutting white fabric: 0.14 at 390 nm, 0.31 at 400 nm, 0.72 at 420 nm, 0.85 above
    460 nm), so the flash is not a table by name (6244 K, Duv +0.005 after the diffuser).
  Direct light by the midpoint rule over each softbox (12 x 12 cells; the thin softboxes shade
  nothing), plus the integrating-sphere estimate of interreflection (the softboxes' flux over
  the room's area, times rho / (1 - rho), rho the area-weighted mean reflectance);
- `room_window_lamps`: a 5 x 2.7 x 6 m living room (truth_mixed.room: neutral-8 walls with the
  band of the 24 patches, a dark-skin wooden floor, a white-9.5 ceiling) seen from (0.3, 1.5,
  0.4), a 2 x 1.4 m window on its +z wall showing an overcast sky (CIE daylight 6500 K,
  luminance 3000) and three lamps with globe shades of `luxeon-ww-2880` warm-white phosphor
  LEDs (2880 K; Lambertian spheres of radius 0.1 m, luminance 5000): a pendant over the table
  and two floor lamps. The window gives about 82% of the emitters' luminous flux. The RGB is not
  white-balanced (unlike truth_mixed.room_incandescent_dusk);
- `street_dusk`: make_truth.py's street (12 m wide, 15 m facades, seven lamps on 7 m poles)
  with five `c100s54c` high-pressure sodium lamps (the coated 100 W lamp, 2236 K: the common
  street sodium, a measured table that is neither `hps` nor street_mixed's clear c100s54) and
  two `phosphor-led` street lamps (6814 K: the cool-white LED retrofits of the 2010s; no
  measured phosphor LED of spectra/light lies near 4000 K, and the other one, the 2880 K
  luxeon-ww-2880, is street_mixed's), under a twilight sky of CIE daylight 11000 K whose
  luminance goes smoothly from 20% of the road's luminance under a lamp at the zenith to 40% at
  the horizon (L = road (0.2 + 0.2 (1 - sin elevation))). The sky also lights the road and the
  facades (256 stratified cosine-weighted directions per point, escaping the canyon above the
  facades; no interreflection, as make_truth.street has none).
"""
import math

import numpy as np

from make_truth import (FACADE_H, HEIGHT, LAMP_H, SPECTRA, STREET_HALF_W, WIDTH, box_hit, grid,
                        latlong_dirs, patch, read_table, street, street_hits, street_materials,
                        xyz_of)
from truth_mixed import (SS, around_normals, average_pixels, cosine_directions, daylight, lamp,
                         rect_gain, room)

# ----------------------------------------------------------------------------------------------
# The studio

STUDIO_LO, STUDIO_HI = np.array([-4.0, 0.0, -5.0]), np.array([4.0, 4.5, 5.0])
STUDIO_EYE = np.array([0.0, 1.6, 0.0])
COVE_R = 1.5                       # the cyclorama's cove: a quarter cylinder along x
COVE_Z = STUDIO_HI[2] - COVE_R     # its axis: y = COVE_R, z = COVE_Z
CYC_FLOOR_FROM_Z = -1.5            # the cyclorama's white runs over the floor from here to the cove
SOFTBOX_HALF = (0.5, 0.7)          # 1 m wide, 1.4 m high
# (name, azimuth from +z towards +x, elevation, horizontal distance, luminance)
SOFTBOXES = [("key", 140.0, 35.0, 3.0, 4000.0), ("fill", -130.0, 25.0, 3.2, 2000.0),
             ("rim", 35.0, 40.0, 2.5, 3000.0)]
CURTAIN, CYC, CONCRETE, FABRIC = "black-2", "white-9.5", "neutral-5", "black-2"
BAND = (1.0, 1.8)


def softbox_geometry():
    """(centre, half-axis a (horizontal), half-axis b, normal m towards the subject) per box."""
    boxes = []
    for _, az, el, dist, _ in SOFTBOXES:
        a_r, e_r = math.radians(az), math.radians(el)
        centre = STUDIO_EYE + np.array([dist * math.sin(a_r), dist * math.tan(e_r),
                                        dist * math.cos(a_r)])
        m = STUDIO_EYE - centre
        m /= np.linalg.norm(m)
        a = np.cross([0.0, 1.0, 0.0], m)
        a /= np.linalg.norm(a)
        b = np.cross(m, a)
        boxes.append((centre, a * SOFTBOX_HALF[0], b * SOFTBOX_HALF[1], m))
    return boxes


def studio_hit(dirs):
    """Where rays from the eye meet the studio's shell: points, normals (into the room) and a
    surface code (0 floor, 1 cove, 2 cyclorama wall, 3 ceiling, 4 the -x, +x, -z walls)."""
    p, face = box_hit(STUDIO_EYE, dirs, STUDIO_LO, STUDIO_HI)
    n = np.zeros_like(p)
    ax, side = face // 2, face % 2
    n[np.arange(len(p)), ax] = np.where(side == 1, -1.0, 1.0)
    code = np.select([face == 2, face == 5, face == 3], [0, 2, 3], 4)
    # A hit in the corner square behind the cove's arc is the cove (the arc's far root).
    behind = (p[:, 2] > COVE_Z) & (p[:, 1] < COVE_R) & \
        ((p[:, 1] - COVE_R) ** 2 + (p[:, 2] - COVE_Z) ** 2 > COVE_R ** 2)
    o = np.array([STUDIO_EYE[1] - COVE_R, STUDIO_EYE[2] - COVE_Z])
    d = dirs[behind][:, 1:]
    qa = (d * d).sum(-1)
    qb = d @ o
    qc = o @ o - COVE_R ** 2
    t = (-qb + np.sqrt(np.maximum(qb * qb - qa * qc, 0.0))) / qa
    q = STUDIO_EYE + t[:, None] * dirs[behind]
    p[behind] = q
    n[behind] = np.stack([np.zeros(len(q)), COVE_R - q[:, 1], COVE_Z - q[:, 2]], -1) / COVE_R
    code[behind] = 1
    return p, n, code


def studio_materials(p, code, wl):
    refl = np.tile(patch(CURTAIN, wl), (len(p), 1))
    cyc = (code == 1) | (code == 2) | ((code == 0) & (p[:, 2] >= CYC_FLOOR_FROM_Z))
    refl[(code == 0) & ~cyc] = patch(CONCRETE, wl)
    refl[cyc] = patch(CYC, wl)
    # 8 coloured flats on each curtain wall: -x (patches 0-7), +x (8-15), -z (16-23).
    walls = ((np.abs(p[:, 0] - STUDIO_LO[0]) < 1e-6, p[:, 2], STUDIO_LO[2], 10.0, 0),
             (np.abs(p[:, 0] - STUDIO_HI[0]) < 1e-6, p[:, 2], STUDIO_LO[2], 10.0, 8),
             (np.abs(p[:, 2] - STUDIO_LO[2]) < 1e-6, p[:, 0], STUDIO_LO[0], 8.0, 16))
    in_band = (code == 4) & (p[:, 1] >= BAND[0]) & (p[:, 1] <= BAND[1])
    for on, along, start, span, first in walls:
        m = in_band & on
        cell = np.clip(((along - start) / span * 8).astype(int), 0, 7)
        for c in range(8):
            refl[m & (cell == c)] = patch(first + c, wl)
    return refl


def studio_mean_reflectance(wl):
    """The area-weighted mean reflectance of the studio's shell, and its area."""
    s = STUDIO_HI - STUDIO_LO
    cove = s[0] * math.pi * COVE_R / 2
    cyc_wall = s[0] * (s[1] - COVE_R)
    cyc_floor = s[0] * (COVE_Z - CYC_FLOOR_FROM_Z)
    concrete = s[0] * (CYC_FLOOR_FROM_Z - STUDIO_LO[2])
    corner = COVE_R ** 2 * (1 - math.pi / 4)           # cut off each side wall by the cove
    band = (2 * s[2] + s[0]) * (BAND[1] - BAND[0])
    curtain = s[0] * s[2] + 2 * (s[1] * s[2] - corner) + s[0] * s[1] - band
    rho = ((cove + cyc_wall + cyc_floor) * patch(CYC, wl) + concrete * patch(CONCRETE, wl)
           + curtain * patch(CURTAIN, wl) + band * np.mean([patch(i, wl) for i in range(24)], 0))
    area = cove + cyc_wall + cyc_floor + concrete + curtain + band
    return rho / area, area


def hot_spot(ua, ub):
    """A softbox's luminance over its face relative to its centre's (ua, ub in [-1, 1]): a
    gentle hot spot, 15% dimmer in the corners, as real diffusers are (a perfectly uniform face
    would sit at the map's maximum in every pixel, which is how clipping looks)."""
    return 1.0 - 0.075 * (ua * ua + ub * ub)


def studio(wl, spd):
    """The studio lit by three softboxes of `spd` (at luminance 1), each at its luminance."""
    dirs = latlong_dirs(WIDTH, HEIGHT, SS).reshape(-1, 3)
    p, n, code = studio_hit(dirs)
    refl = studio_materials(p, code, wl)
    boxes = softbox_geometry()
    e = np.zeros((len(p), len(wl)))
    flux = np.zeros(len(wl))
    for (centre, a, b, m), (*_, lum) in zip(boxes, SOFTBOXES):
        e += rect_gain(p, n, centre, a, b, m, weight=hot_spot)[:, None] * (spd * lum)[None]
        mean_hot = 1.0 - 0.075 * 2 / 3   # hot_spot's mean over the face
        flux += math.pi * 4 * np.linalg.norm(a) * np.linalg.norm(b) * spd * lum * mean_hot
    rho, area = studio_mean_reflectance(wl)
    indirect = flux / area * rho / (1 - rho)
    radiance = refl * (e + indirect[None]) / math.pi
    # The softboxes in view: the front emits, the back is black fabric in the indirect light.
    t_shell = np.linalg.norm(p - STUDIO_EYE, axis=1)
    for (centre, a, b, m), (*_, lum) in zip(boxes, SOFTBOXES):
        dm = dirs @ m
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((centre - STUDIO_EYE) @ m) / dm
        q = STUDIO_EYE + np.where(np.isfinite(t), t, 0.0)[:, None] * dirs
        ua = ((q - centre) @ a) / (a @ a)
        ub = ((q - centre) @ b) / (b @ b)
        hit = (t > 0) & (t < t_shell) & (np.abs(ua) <= 1) & (np.abs(ub) <= 1)
        front = hit & (dm < 0)
        radiance[front] = hot_spot(ua[front], ub[front])[:, None] * (spd * lum)[None]
        radiance[hit & (dm >= 0)] = patch(FABRIC, wl) * indirect / math.pi
        t_shell = np.where(hit, t, t_shell)
    return average_pixels(radiance)


def studio_params(what, lamp_name, right):
    lights = "; ".join(f"{n}: {lamp_name}, {az:g} deg azimuth, {el:g} deg up, luminance {lum:g}"
                       for n, az, el, _, lum in SOFTBOXES)
    return {"kind": f"photographic studio (black curtains, white cyclorama) lit by {what}",
            "lights": lights, "sky": "none", "right_light": right}


def studio_led():
    wl = grid(780.0)
    return wl, studio(wl, lamp("phosphor-led", wl)), studio_params(
        "three phosphor-led softboxes (6814 K)", "phosphor-led",
        "LED (the catalogue's LED-B5, 6598 K, is nearest)")


def studio_tungsten():
    wl = grid(780.0)
    return wl, studio(wl, lamp("incandescent", wl)), studio_params(
        "three tungsten softboxes (incandescent, 2812 K), RGB not balanced", "incandescent",
        "A (filament)")


DIFFUSER_EDGE_NM, DIFFUSER_WIDTH_NM, DIFFUSER_MAX = 405.0, 9.0, 0.85


def diffuser(wl):
    """The flash softbox's white fabric: smooth, slightly UV-cutting."""
    return DIFFUSER_MAX / (1 + np.exp(-(wl - DIFFUSER_EDGE_NM) / DIFFUSER_WIDTH_NM))


def band_mean(name, wl):
    """A table of spectra/light averaged over each 5 nm band (the mean of its piecewise-linear
    curve over [lambda - 2.5, lambda + 2.5] nm, clamped to the table's range)."""
    w, cols = read_table(SPECTRA / "light" / f"{name}.csv")
    fine = np.clip(wl[:, None] + np.linspace(-2.5, 2.5, 51)[None], w[0], w[-1])
    return np.interp(fine, w, cols[name]).mean(1)


def flash(wl):
    v = band_mean("kinoton-75p", wl) * diffuser(wl)
    return v / xyz_of(v, wl)[1]


def studio_flash():
    wl = grid(780.0)
    params = studio_params("three xenon flash softboxes (kinoton-75p through a diffuser)",
                           "kinoton-75p x diffuser", "D65 (xenon flash is near daylight)")
    params["diffuser"] = (f"T = {DIFFUSER_MAX} / (1 + exp(-(nm - {DIFFUSER_EDGE_NM:g}) / "
                          f"{DIFFUSER_WIDTH_NM:g}))")
    return wl, studio(wl, flash(wl)), params


# ----------------------------------------------------------------------------------------------
# A living room with a window and warm lamps

WINDOW_LUMINANCE, LAMP_LUMINANCE, LAMP_RADIUS = 3000.0, 5000.0, 0.1


def room_window_lamps():
    wl = grid(780.0)
    lo, hi = np.array([-2.5, 0.0, -3.0]), np.array([2.5, 2.7, 3.0])
    window_spd = daylight(6500.0, wl) * WINDOW_LUMINANCE
    window = ([0.5, 1.5, 3.0], [1.0, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, -1.0], window_spd)
    bulb = lamp("luxeon-ww-2880", wl) * LAMP_LUMINANCE
    bulbs = [([0.0, 2.0, -0.8], LAMP_RADIUS, bulb),     # pendant over the table
             ([-2.0, 1.6, 1.8], LAMP_RADIUS, bulb),     # floor lamps in two corners
             ([2.0, 1.6, -2.4], LAMP_RADIUS, bulb)]
    radiance = room(wl, lo, hi, np.array([0.3, 1.5, 0.4]), [window], bulbs, floor="dark-skin")
    window_flux = math.pi * 2.0 * 1.4 * WINDOW_LUMINANCE
    lamps_flux = 3 * 4 * math.pi ** 2 * LAMP_RADIUS ** 2 * LAMP_LUMINANCE
    return wl, radiance, {
        "kind": "living room: an overcast window (daylight 6500 K) and three luxeon-ww-2880 "
                "lamps (2880 K), RGB not balanced",
        "lights": f"window: daylight 6500 K, luminance {WINDOW_LUMINANCE:g}, 2 x 1.4 m; lamps: "
                  f"luxeon-ww-2880 x 3, spheres r {LAMP_RADIUS:g} m, luminance {LAMP_LUMINANCE:g}",
        "window_flux_share": round(window_flux / (window_flux + lamps_flux), 3),
        "right_light": "D65 (the window's daylight holds most of the energy; LED for the lamps)"}


# ----------------------------------------------------------------------------------------------
# A dusk street: make_truth.street's lamps under a bright twilight sky that lights the street

SKY_ZENITH, SKY_HORIZON = 0.2, 0.4   # of the road's luminance under a lamp


def sky_profile(up):
    """The sky's luminance, in units of the road's, at the direction's sine of elevation `up`."""
    return SKY_ZENITH + (SKY_HORIZON - SKY_ZENITH) * (1 - np.clip(up, 0.0, 1.0))


def street_sky(wl, sky_spd, road_l):
    """What the twilight sky adds to make_truth.street (whose own sky is set to 0): the sky's
    pixels, and the road and facades lit by it, on street()'s ray cast and materials."""
    dirs = latlong_dirs(WIDTH, HEIGHT, SS).reshape(-1, 3)
    p, n, kind, _ = street_hits(dirs)
    refl = street_materials(p, kind, wl)
    half_w, facade_h = STREET_HALF_W, FACADE_H
    # Sky irradiance (per unit of the road's luminance): 256 stratified cosine-weighted
    # directions per surface point; a direction sees the sky if it leaves the canyon above the
    # facades (the street runs on without end along z).
    local = cosine_directions(41)
    surf = np.flatnonzero((kind >= 0) & (kind <= 2))
    e_sky = np.zeros(len(p))
    for i in range(0, len(surf), 1024):
        idx = surf[i:i + 1024]
        q, nn = p[idx], n[idx]
        w = around_normals(local, nn)
        with np.errstate(divide="ignore", invalid="ignore"):
            tw = np.where(w[..., 0] > 0, (half_w - q[:, None, 0]) / w[..., 0],
                          np.where(w[..., 0] < 0, (-half_w - q[:, None, 0]) / w[..., 0], np.inf))
        y_out = q[:, None, 1] + np.where(np.isfinite(tw), tw, 0.0) * w[..., 1]
        sees = (w[..., 1] > 0) & (~np.isfinite(tw) | (y_out > facade_h))
        e_sky[idx] = np.pi * np.where(sees, sky_profile(w[..., 1]), 0.0).mean(1)
    radiance = refl * (e_sky[:, None] * sky_spd[None]) * road_l / np.pi
    sky = kind == -1
    radiance[sky] = sky_spd[None] * (road_l * sky_profile(dirs[sky, 1]))[:, None]
    return average_pixels(radiance)


LED_POLES = (2, 5)   # make_truth.street's lamps 2 (15 m behind, +x) and 5 (30 m ahead, -x)


def street_dusk():
    wl = grid(780.0)
    sodium = lamp("c100s54c", wl)
    spds = [sodium] * 7
    for k in LED_POLES:
        spds[k] = lamp("phosphor-led", wl)
    radiance = street(wl, spds, sodium, 0.0)
    road_l = xyz_of(patch("neutral-3.5", wl) * sodium * 2000.0 / LAMP_H ** 2 / np.pi, wl)[1]
    radiance = radiance + street_sky(wl, daylight(11000.0, wl), road_l)
    return wl, radiance, {
        "kind": "dusk street: five c100s54c sodium lamps, two phosphor-led LED lamps, a "
                "twilight sky (daylight 11000 K) at 20-40% of the road's luminance",
        "lamps": 7, "lights": "c100s54c x 5 (2236 K), phosphor-led x 2 (6814 K, poles "
                              f"{LED_POLES[0]} and {LED_POLES[1]}), sky daylight 11000 K",
        "sky_fraction": f"{SKY_ZENITH:g} at the zenith to {SKY_HORIZON:g} at the horizon",
        "right_light": "sodium for five lamps, LED for two, daylight for the sky"}


SCENES = {
    "studio_led": studio_led,
    "studio_tungsten": studio_tungsten,
    "studio_flash": studio_flash,
    "room_window_lamps": room_window_lamps,
    "street_dusk": street_dusk,
}
