//! Environment-map layouts: face order and orientation against OpenEXR's formulas, solid angles,
//! sampling, filtered resampling, layout detection.

use specmap::envmap::layout::{detect, EnvMap, Face, Layout, Orientation, Up};
use specmap::envmap::RgbImage;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------
// Transcriptions of OpenEXR's src/lib/OpenEXR/ImfEnvmap.cpp (AcademySoftwareFoundation/openexr,
// commit 41253757e6bbc8be5b0c4cafebe52f9b3e51a074), in f64, for a data window starting at (0, 0).
// ---------------------------------------------------------------------------------------------

/// `LatLongMap::direction(dataWindow, pixelPosition)` with max = (w - 1, h - 1).
fn exr_latlong_direction(w: usize, h: usize, px: f64, py: f64) -> [f64; 3] {
    let lat = if h > 1 {
        -PI * (py / (h - 1) as f64 - 0.5)
    } else {
        0.0
    };
    let lon = if w > 1 {
        -2.0 * PI * (px / (w - 1) as f64 - 0.5)
    } else {
        0.0
    };
    [lon.sin() * lat.cos(), lat.sin(), lon.cos() * lat.cos()]
}

/// `CubeMap::faceAndPixelPosition(direction, dataWindow, face, pif)`.
fn exr_face_and_pixel_position(d: [f64; 3], sof: usize) -> (usize, [f64; 2]) {
    let s = (sof - 1) as f64;
    let (ax, ay, az) = (d[0].abs(), d[1].abs(), d[2].abs());
    if ax >= ay && ax >= az {
        let pif = [(d[1] / ax + 1.0) / 2.0 * s, (d[2] / ax + 1.0) / 2.0 * s];
        (if d[0] > 0.0 { 0 } else { 1 }, pif)
    } else if ay >= az {
        let pif = [(d[0] / ay + 1.0) / 2.0 * s, (d[2] / ay + 1.0) / 2.0 * s];
        (if d[1] > 0.0 { 2 } else { 3 }, pif)
    } else {
        let pif = [(d[0] / az + 1.0) / 2.0 * s, (d[1] / az + 1.0) / 2.0 * s];
        (if d[2] > 0.0 { 4 } else { 5 }, pif)
    }
}

/// `CubeMap::pixelPosition(face, dataWindow, positionInFace)`.
fn exr_pixel_position(face: usize, sof: usize, pif: [f64; 2]) -> [f64; 2] {
    let (minx, miny) = (0.0, (face * sof) as f64);
    let (maxx, maxy) = (minx + sof as f64 - 1.0, miny + sof as f64 - 1.0);
    match face {
        0 => [minx + pif[1], maxy - pif[0]],
        1 => [maxx - pif[1], maxy - pif[0]],
        2 => [minx + pif[0], maxy - pif[1]],
        3 => [minx + pif[0], miny + pif[1]],
        4 => [maxx - pif[0], maxy - pif[1]],
        _ => [minx + pif[0], maxy - pif[1]],
    }
}

/// `CubeMap::direction(face, dataWindow, positionInFace)` (not normalised).
fn exr_cube_direction(face: usize, sof: usize, pif: [f64; 2]) -> [f64; 3] {
    let p = if sof > 1 {
        let s = (sof - 1) as f64;
        [pif[0] / s * 2.0 - 1.0, pif[1] / s * 2.0 - 1.0]
    } else {
        [0.0, 0.0]
    };
    match face {
        0 => [1.0, p[0], p[1]],
        1 => [-1.0, p[0], p[1]],
        2 => [p[0], 1.0, p[1]],
        3 => [p[0], -1.0, p[1]],
        4 => [p[0], p[1], 1.0],
        _ => [p[0], p[1], -1.0],
    }
}

// ---------------------------------------------------------------------------------------------

fn unit(d: [f64; 3]) -> [f64; 3] {
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    [d[0] / n, d[1] / n, d[2] / n]
}

fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (a, b) = (unit(a), unit(b));
    let c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let x = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt().atan2(c)
}

fn assert_dir(got: [f64; 3], want: [f64; 3], tol: f64, what: &str) {
    let a = angle(got, want);
    assert!(
        a <= tol,
        "{what}: got {got:?}, want {want:?} (off by {a:e} rad)"
    );
}

fn map_of(layout: Layout, size: usize) -> EnvMap {
    let (w, h) = layout.dimensions(size);
    EnvMap::new(layout, RgbImage::new(w, h)).unwrap()
}

/// A smooth, positive radiance: constant + dipole + a few quadrupole terms (spherical harmonics
/// up to l = 2, distinct along every axis so that a mirrored or rotated face would show).
fn smooth(d: [f64; 3]) -> [f32; 3] {
    let [x, y, z] = d;
    let r = 1.0 + 0.5 * x + 0.3 * y - 0.2 * z + 0.4 * x * y + 0.3 * (3.0 * z * z - 1.0) / 2.0;
    let g = 1.2 - 0.4 * x + 0.35 * z + 0.25 * y * z;
    let b = 0.9 + 0.2 * y + 0.3 * x * z - 0.15 * (x * x - y * y);
    [r as f32, g as f32, b as f32]
}

fn filled(layout: Layout, size: usize, f: impl Fn([f64; 3]) -> [f32; 3]) -> EnvMap {
    let mut m = map_of(layout, size);
    for y in 0..m.image.height {
        for x in 0..m.image.width {
            if let Some(d) = m.direction(x, y) {
                m.image.set(x, y, f(d));
            }
        }
    }
    m
}

fn integral(m: &EnvMap) -> [f64; 3] {
    let mut s = [0.0; 3];
    for (_, _, _, sa, v) in m.pixels_with_directions() {
        for c in 0..3 {
            s[c] += sa * v[c] as f64;
        }
    }
    s
}

const CUBE_LIKE: [Layout; 5] = [
    Layout::Cube,
    Layout::HCross,
    Layout::VCross,
    Layout::HStrip,
    Layout::VStrip,
];

// ---------------------------------------------------------------------------------------------
// Orientation against OpenEXR.

#[test]
fn latlong_directions_are_openexrs() {
    for h in [1usize, 2, 3, 8, 33] {
        let m = map_of(Layout::LatLong, h);
        let w = 2 * h;
        for y in 0..h {
            for x in 0..w {
                // Our pixel centre (x + 0.5) / w is OpenEXR's position (x + 0.5) / w * (w - 1).
                let px = (x as f64 + 0.5) / w as f64 * (w - 1) as f64;
                let py = (y as f64 + 0.5) / h as f64 * (h - 1) as f64;
                let want = exr_latlong_direction(w, h, px, py);
                assert_dir(
                    m.direction(x, y).unwrap(),
                    want,
                    1e-12,
                    &format!("{w}x{h} ({x},{y})"),
                );
            }
        }
    }
}

#[test]
fn latlong_landmarks() {
    let m = map_of(Layout::LatLong, 64); // 128 x 64
    let half_px = PI / 64.0;
    // Centre column looks down +Z, a quarter from the left +X, three quarters -X, edges -Z.
    assert_dir(
        m.direction(64, 32).unwrap(),
        [0.0, 0.0, 1.0],
        half_px * 1.5,
        "centre",
    );
    assert_dir(
        m.direction(32, 32).unwrap(),
        [1.0, 0.0, 0.0],
        half_px * 1.5,
        "quarter",
    );
    assert_dir(
        m.direction(96, 32).unwrap(),
        [-1.0, 0.0, 0.0],
        half_px * 1.5,
        "3/4",
    );
    assert_dir(
        m.direction(0, 32).unwrap(),
        [0.0, 0.0, -1.0],
        half_px * 1.5,
        "left",
    );
    // Top row +Y, bottom row -Y.
    assert!(m.direction(10, 0).unwrap()[1] > (PI / 128.0).cos() - 1e-12);
    assert!(m.direction(10, 63).unwrap()[1] < -(PI / 128.0).cos() + 1e-12);
    // Longitude atan2(x, z) decreases to the right.
    let lon = |x| {
        let d = m.direction(x, 20).unwrap();
        d[0].atan2(d[2])
    };
    assert!(lon(65) < lon(64) && lon(64) < lon(63));
}

#[test]
fn cube_directions_are_openexrs() {
    for n in [1usize, 2, 3, 5, 16] {
        let m = map_of(Layout::Cube, n);
        for y in 0..6 * n {
            for x in 0..n {
                let d = m.direction(x, y).unwrap();
                let (face, pif) = exr_face_and_pixel_position(d, n);
                assert_eq!(face, y / n, "n={n} ({x},{y}): face order");
                let pos = exr_pixel_position(face, n, pif);
                // OpenEXR's position of our pixel centre: (i + 0.5) / n * (n - 1) in the face.
                let s = (n - 1) as f64 / n as f64;
                let want = [
                    (x as f64 + 0.5) * s,
                    (face * n) as f64 + ((y % n) as f64 + 0.5) * s,
                ];
                assert!(
                    (pos[0] - want[0]).abs() < 1e-9 && (pos[1] - want[1]).abs() < 1e-9,
                    "n={n} ({x},{y}): OpenEXR puts {d:?} at {pos:?}, expected {want:?}"
                );
                // And back: OpenEXR's direction of that position is ours.
                let back = exr_cube_direction(face, n, pif);
                assert_dir(d, back, 1e-12, "CubeMap::direction");
            }
        }
    }
}

#[test]
fn cube_face_centres_and_corners() {
    // Odd size: each face has a centre pixel, which looks down the face's axis.
    for layout in CUBE_LIKE {
        let m = map_of(layout, 5);
        let mut seen = Vec::new();
        for y in 0..m.image.height {
            for x in 0..m.image.width {
                if x % 5 == 2 && y % 5 == 2 {
                    if let Some(d) = m.direction(x, y) {
                        seen.push(Face::of(d));
                        assert_dir(d, Face::of(d).axis(), 1e-12, layout.name());
                    }
                }
            }
        }
        assert_eq!(seen.len(), 6, "{layout:?}");
    }
    // The OpenEXR cube's faces, in order +X -X +Y -Y +Z -Z.
    let m = map_of(Layout::Cube, 5);
    for (i, f) in Face::ALL.iter().enumerate() {
        assert_dir(
            m.direction(2, 5 * i + 2).unwrap(),
            f.axis(),
            1e-12,
            f.name(),
        );
    }
    // Top-left and bottom-right pixel corners of +X, +Y, +Z (CubeMap::direction at pif (0,0)
    // / (sof-1, sof-1) through CubeMap::pixelPosition): +X top-left is (1, 1, -1), +Y top-left
    // (-1, 1, 1), +Z top-left (1, 1, 1).
    let n = 256;
    let m = map_of(Layout::Cube, n);
    let tol = 2.0 / n as f64;
    for (face, tl, br) in [
        (0, [1.0, 1.0, -1.0], [1.0, -1.0, 1.0]),
        (2, [-1.0, 1.0, 1.0], [1.0, 1.0, -1.0]),
        (4, [1.0, 1.0, 1.0], [-1.0, -1.0, 1.0]),
    ] {
        // The same corners from the transcription: which pif lands on the top-left pixel.
        let s = (n - 1) as f64;
        let exr_tl = (0..4)
            .map(|c| [(c & 1) as f64 * s, (c >> 1) as f64 * s])
            .find(|&pif| {
                let p = exr_pixel_position(face, n, pif);
                p[0] == 0.0 && p[1] == (face * n) as f64
            })
            .map(|pif| exr_cube_direction(face, n, pif))
            .unwrap();
        assert_dir(exr_tl, tl, 1e-12, "transcribed corner");
        assert_dir(m.direction(0, face * n).unwrap(), tl, tol, "top-left");
        assert_dir(
            m.direction(n - 1, face * n + n - 1).unwrap(),
            br,
            tol,
            "bottom-right",
        );
    }
}

/// The cross's cells: -X -Z +X +Z in the middle row, +Y above and -Y below -Z (cmft's
/// arrangement of OpenEXR's faces); strips in OpenEXR's face order.
#[test]
fn cross_and_strip_face_order() {
    let n = 3;
    let cells = |layout: Layout| -> Vec<(usize, usize, Face)> {
        let m = map_of(layout, n);
        let (cw, ch) = (m.image.width / n, m.image.height / n);
        let mut v = Vec::new();
        for r in 0..ch {
            for c in 0..cw {
                if let Some(d) = m.direction(c * n + 1, r * n + 1) {
                    v.push((c, r, Face::of(d)));
                }
            }
        }
        v
    };
    use Face::*;
    assert_eq!(
        cells(Layout::HCross),
        vec![
            (1, 0, PosY),
            (0, 1, NegX),
            (1, 1, NegZ),
            (2, 1, PosX),
            (3, 1, PosZ),
            (1, 2, NegY)
        ]
    );
    assert_eq!(
        cells(Layout::VCross),
        vec![
            (1, 0, PosY),
            (0, 1, NegX),
            (1, 1, NegZ),
            (2, 1, PosX),
            (1, 2, NegY),
            (1, 3, PosZ)
        ]
    );
    let order: Vec<Face> = cells(Layout::HStrip).iter().map(|c| c.2).collect();
    assert_eq!(order, Face::ALL.to_vec());
    let order: Vec<Face> = cells(Layout::VStrip).iter().map(|c| c.2).collect();
    assert_eq!(order, Face::ALL.to_vec());
    let order: Vec<Face> = cells(Layout::Cube).iter().map(|c| c.2).collect();
    assert_eq!(order, Face::ALL.to_vec());
}

/// Pixel (i, j) of face `f`'s cell in `m` (face size `n`).
fn face_pixel(m: &EnvMap, n: usize, f: Face, i: usize, j: usize) -> [f64; 3] {
    for r in 0..m.image.height / n {
        for c in 0..m.image.width / n {
            let centre = m.direction(c * n + n / 2, r * n + n / 2);
            if centre.is_some_and(|d| Face::of(d) == f) {
                return m.direction(c * n + i, r * n + j).unwrap();
            }
        }
    }
    panic!("no face {f:?}");
}

/// Every face of the crosses and strips is OpenEXR's face image (pixel (i, j) looks where the
/// cube's pixel (i, j) of that face looks), except the vertical cross's +Z, turned 180°.
#[test]
fn every_face_has_openexrs_orientation() {
    let n = 4;
    let cube = map_of(Layout::Cube, n);
    for layout in [
        Layout::HCross,
        Layout::VCross,
        Layout::HStrip,
        Layout::VStrip,
    ] {
        let m = map_of(layout, n);
        for f in Face::ALL {
            let turned = f == Face::PosZ && layout == Layout::VCross;
            for j in 0..n {
                for i in 0..n {
                    let (ci, cj) = if turned {
                        (n - 1 - i, n - 1 - j)
                    } else {
                        (i, j)
                    };
                    assert_dir(
                        face_pixel(&m, n, f, i, j),
                        face_pixel(&cube, n, f, ci, cj),
                        1e-12,
                        &format!("{layout:?} {} ({i},{j})", f.name()),
                    );
                }
            }
        }
    }
}

/// A vertical strip holds the same pixels as OpenEXR's cube, so both read every pixel as the
/// same direction and give the same value in every direction.
#[test]
fn a_vertical_strip_is_openexrs_cube() {
    let n = 8;
    let cube = filled(Layout::Cube, n, smooth);
    let strip = EnvMap::new(Layout::VStrip, cube.image.clone()).unwrap();
    for y in 0..6 * n {
        for x in 0..n {
            assert_eq!(strip.direction(x, y), cube.direction(x, y), "({x},{y})");
        }
    }
    for k in 0..500 {
        let t = k as f64 * 0.37;
        let d = [
            t.sin() * (1.3 * t).cos(),
            (0.7 * t).cos(),
            t.cos() * (2.1 * t).sin(),
        ];
        assert_eq!(strip.sample(d), cube.sample(d), "{d:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// Transcriptions of cmft's src/cmft/cubemaputils.h and src/cmft/image.cpp (dariomanesku/cmft,
// commit cad5f31bac66fd05987d667af62311c444df6d46): its face frame, cross cells and lat-long.
// ---------------------------------------------------------------------------------------------

/// `s_faceUvVectors`: for cmft's faces +x, -x, +y, -y, +z, -z, the directions of u (right),
/// v (down) and the face's centre.
const CMFT_FACE_UV: [[[f64; 3]; 3]; 6] = [
    [[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]],
    [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [-1.0, 0.0, 0.0]],
    [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
    [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, -1.0, 0.0]],
    [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
    [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
];

/// `texelCoordToVec(u, v, face)` for u, v in [-1, 1] (not normalised).
fn cmft_texel_to_vec(u: f64, v: f64, face: usize) -> [f64; 3] {
    let [uu, vv, c] = CMFT_FACE_UV[face];
    [0, 1, 2].map(|k| u * uu[k] + v * vv[k] + c[k])
}

/// The cell (column, row) of each cmft face in `imageCubemapFromCross`'s `faceOffsets`, and
/// whether the face is flipped in x and y (the vertical cross's -z).
fn cmft_cross_cell(face: usize, vertical: bool) -> (usize, usize, bool) {
    match (face, vertical) {
        (0, _) => (2, 1, false),
        (1, _) => (0, 1, false),
        (2, _) => (1, 0, false),
        (3, _) => (1, 2, false),
        (4, _) => (1, 1, false),
        (_, false) => (3, 1, false),
        (_, true) => (1, 3, true),
    }
}

/// Every pixel of a cross cmft reads as cmft's direction c, its cmft face and its position in
/// that face (the face's own pixel, after cmft's flip).
fn cmft_cross_pixels(n: usize, vertical: bool) -> Vec<(usize, usize, [f64; 3])> {
    let mut v = Vec::new();
    for face in 0..6 {
        let (col, row, flip) = cmft_cross_cell(face, vertical);
        for j in 0..n {
            for i in 0..n {
                let (fi, fj) = if flip { (n - 1 - i, n - 1 - j) } else { (i, j) };
                let u = 2.0 * (fi as f64 + 0.5) / n as f64 - 1.0;
                let w = 2.0 * (fj as f64 + 0.5) / n as f64 - 1.0;
                v.push((col * n + i, row * n + j, cmft_texel_to_vec(u, w, face)));
            }
        }
    }
    v
}

/// cmft's crosses, read in OpenEXR's right-handed world: cmft's frame is left-handed (the
/// OpenGL cube-map convention), and with z negated each of its face images is OpenEXR's. Every
/// pixel then looks where cmft's own reading says, and the unused cells are the same.
#[test]
fn crosses_match_cmft_with_z_negated() {
    let n = 6;
    for (layout, vertical) in [(Layout::HCross, false), (Layout::VCross, true)] {
        let m = map_of(layout, n);
        let pixels = cmft_cross_pixels(n, vertical);
        for &(x, y, c) in &pixels {
            let want = [c[0], c[1], -c[2]];
            let got = m
                .direction(x, y)
                .unwrap_or_else(|| panic!("{layout:?} ({x},{y}) unused"));
            assert_dir(got, want, 1e-12, &format!("{layout:?} ({x},{y})"));
        }
        let used = (0..m.image.height)
            .flat_map(|y| (0..m.image.width).map(move |x| (x, y)))
            .filter(|&(x, y)| m.direction(x, y).is_some())
            .count();
        assert_eq!(used, pixels.len(), "{layout:?}");
    }
}

/// cmft's `latLongFromVec`: its lat-long position (u, v) in [0, 1] of a direction.
fn cmft_latlong_from_vec(d: [f64; 3]) -> [f64; 2] {
    let d = unit(d);
    let phi = d[2].atan2(-d[0]);
    [(PI + phi) / (2.0 * PI), d[1].acos() / PI]
}

/// A cross that cmft makes from a lat-long (`imageCubemapFromLatLong`, then the cross) holds, in
/// each pixel, the lat-long's value at `latLongFromVec` of cmft's direction; cmft's lat-long is
/// a quarter turn from OpenEXR's, so read with `--rotation 90` the cross looks where the
/// lat-long does (OpenEXR's `LatLongMap::latLong`, continuous).
#[test]
fn a_cross_cmft_made_from_a_latlong_reads_back_with_a_quarter_turn() {
    let n = 6;
    let turn = Orientation {
        up: Up::Y,
        rotation_deg: 90.0,
    };
    for (layout, vertical) in [(Layout::HCross, false), (Layout::VCross, true)] {
        let m = map_of(layout, n);
        for (x, y, c) in cmft_cross_pixels(n, vertical) {
            let [cu, cv] = cmft_latlong_from_vec(c);
            let w = turn.to_world(m.direction(x, y).unwrap());
            let lon = w[0].atan2(w[2]);
            let lat = w[1].atan2((w[0] * w[0] + w[2] * w[2]).sqrt());
            let (u, v) = (0.5 - lon / (2.0 * PI), 0.5 - lat / PI);
            let du = (u - cu).rem_euclid(1.0);
            assert!(
                du.min(1.0 - du) < 1e-9,
                "{layout:?} ({x},{y}): u {u} vs cmft {cu}"
            );
            assert!(
                (v - cv).abs() < 1e-9,
                "{layout:?} ({x},{y}): v {v} vs cmft {cv}"
            );
        }
    }
}

/// Neighbouring pixels across the edges of a cross's cells point to neighbouring directions.
#[test]
fn crosses_are_seamless() {
    let n = 32;
    let step = PI / 2.0 / n as f64 * 1.5;
    for layout in [Layout::HCross, Layout::VCross] {
        let m = map_of(layout, n);
        let (w, h) = (m.image.width, m.image.height);
        let mut edges = 0;
        for y in 0..h {
            for x in 0..w {
                let Some(a) = m.direction(x, y) else { continue };
                for (dx, dy) in [(1, 0), (0, 1)] {
                    let (x2, y2) = (x + dx, y + dy);
                    let Some(b) = m.direction(x2, y2) else {
                        continue;
                    };
                    let crosses = (x2 / n != x / n) || (y2 / n != y / n);
                    if crosses {
                        edges += 1;
                    }
                    assert!(
                        angle(a, b) < step,
                        "{layout:?} ({x},{y})-({x2},{y2}): {a:?} vs {b:?}"
                    );
                }
            }
        }
        // 5 shared edges of n pixel pairs each.
        assert_eq!(edges, 5 * n, "{layout:?}");
    }
    // The middle row turns as the lat-long does, seen from inside: right of -Z is +X.
    let m = map_of(Layout::HCross, n);
    let d = m.direction(2 * n + n / 2, n + n / 2).unwrap();
    assert_dir(d, [1.0, 0.0, 0.0], step, "right of -Z");
}

// ---------------------------------------------------------------------------------------------
// Solid angles, sampling, resampling.

#[test]
fn solid_angles_sum_to_four_pi() {
    for layout in Layout::ALL {
        for size in [1usize, 2, 3, 7, 16, 64] {
            let m = map_of(layout, size);
            let mut sum = 0.0;
            for y in 0..m.image.height {
                for x in 0..m.image.width {
                    let sa = m.solid_angle(x, y);
                    assert!(sa >= 0.0);
                    if m.direction(x, y).is_none() {
                        assert_eq!(sa, 0.0);
                    }
                    sum += sa;
                }
            }
            assert!(
                (sum - 4.0 * PI).abs() < 1e-9,
                "{layout:?} size {size}: {sum}"
            );
        }
    }
    // Closed forms: a 1x1 cube face is 4pi/6; a lat-long's top row is a cap of height
    // 1 - cos(pi/h), split in 2h.
    let m = map_of(Layout::Cube, 1);
    assert!((m.solid_angle(0, 3) - 4.0 * PI / 6.0).abs() < 1e-12);
    let m = map_of(Layout::LatLong, 10);
    let want = 2.0 * PI * (1.0 - (PI / 10.0).cos()) / 20.0;
    assert!((m.solid_angle(7, 0) - want).abs() < 1e-15);
}

#[test]
fn sample_at_pixel_centres_returns_the_pixel() {
    for layout in Layout::ALL {
        for size in [1usize, 2, 3, 8] {
            let mut m = map_of(layout, size);
            let w = m.image.width;
            for (i, p) in m.image.pixels.iter_mut().enumerate() {
                *p = [i as f32, (i % w) as f32, 1000.0 - i as f32];
            }
            for y in 0..m.image.height {
                for x in 0..w {
                    if let Some(d) = m.direction(x, y) {
                        let got = m.sample(d);
                        let want = m.image.get(x, y);
                        for c in 0..3 {
                            assert!(
                                (got[c] - want[c]).abs() < 1e-3,
                                "{layout:?} size {size} ({x},{y}): {got:?} vs {want:?}"
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn sample_wraps_in_longitude_and_is_panic_free() {
    let mut m = map_of(Layout::LatLong, 4); // 8 x 4
    m.image.set(0, 1, [1.0; 3]);
    m.image.set(7, 1, [3.0; 3]);
    // Half-way between the first and last column centres: the -Z seam.
    // Row 1's latitude is pi/8; longitude pi is the -Z seam between the first and last columns.
    let lat = PI / 8.0;
    let mid = [0.0, lat.sin(), -lat.cos()];
    assert!((m.sample(mid)[0] - 2.0).abs() < 1e-5, "{:?}", m.sample(mid));
    for layout in Layout::ALL {
        let m = map_of(layout, 1);
        for d in [
            [0.0, 0.0, 0.0],
            [f64::NAN, 0.0, 1.0],
            [0.0, 1e-300, 0.0],
            [1.0, 1.0, 1.0],
            [-0.0, -1.0, -0.0],
        ] {
            let _ = m.sample(d);
        }
    }
}

#[test]
fn resample_round_trips_within_filtering_error() {
    // Source 128 x 64 lat-long of a smooth function; through each layout at face size 32 and
    // back. The function's second derivatives are below 2, and the filters (bilinear + a box of
    // one destination pixel, about 0.05 rad at face size 32) blur a quadratic by at most
    // |f''| * width^2 / 8 per pass, a few 1e-3; 0.02 leaves room for three passes. A wrong face
    // order or a mirrored face gives errors of order 1.
    let src = filled(Layout::LatLong, 64, smooth);
    for layout in Layout::ALL {
        let mid = src.resample(layout, 32);
        assert_eq!(mid.layout, layout);
        assert_eq!((mid.image.width, mid.image.height), layout.dimensions(32));
        // The intermediate map is the function itself.
        for (x, y, d, _, v) in mid.pixels_with_directions() {
            let want = smooth(d);
            for c in 0..3 {
                assert!(
                    (v[c] - want[c]).abs() < 0.02,
                    "{layout:?} ({x},{y}): {v:?} vs {want:?}"
                );
            }
        }
        let back = mid.resample(Layout::LatLong, 64);
        // The polar rows get a looser bound: a box filter over a polar pixel averages a sector
        // whose centroid lies a third of a pixel off the pixel's centre direction (about 1e-2
        // rad at height 32, times a gradient up to 1, on each of the two passes).
        let (mut worst, mut worst_polar) = (0.0f32, 0.0f32);
        for (i, (a, b)) in back
            .image
            .pixels
            .iter()
            .zip(src.image.pixels.iter())
            .enumerate()
        {
            let y = i / back.image.width;
            let polar = y == 0 || y + 1 == back.image.height;
            for c in 0..3 {
                let e = (a[c] - b[c]).abs();
                if polar {
                    worst_polar = worst_polar.max(e);
                } else {
                    worst = worst.max(e);
                }
            }
        }
        eprintln!("latlong -> {layout:?} -> latlong: max error {worst}, polar rows {worst_polar}");
        assert!(worst < 0.02, "latlong -> {layout:?} -> latlong: {worst}");
        assert!(
            worst_polar < 0.05,
            "latlong -> {layout:?} -> latlong (poles): {worst_polar}"
        );
    }
}

#[test]
fn resample_preserves_the_integral() {
    let src = filled(Layout::LatLong, 64, smooth);
    let want = integral(&src);
    for layout in Layout::ALL {
        for size in [8usize, 31, 100] {
            let got = integral(&src.resample(layout, size));
            for c in 0..3 {
                let rel = (got[c] - want[c]).abs() / want[c];
                assert!(rel < 1e-3, "{layout:?} {size}: {got:?} vs {want:?}");
            }
        }
    }
    // And from a cube, down to a small lat-long.
    let cube = filled(Layout::Cube, 48, smooth);
    let want = integral(&cube);
    let got = integral(&cube.resample(Layout::LatLong, 16));
    for c in 0..3 {
        assert!((got[c] - want[c]).abs() / want[c] < 1e-3);
    }
}

#[test]
fn resample_tiny_maps() {
    for from in Layout::ALL {
        for to in Layout::ALL {
            for (a, b) in [(1usize, 1usize), (1, 3), (2, 1), (0, 0)] {
                let src = filled(from, a.max(1), smooth);
                let dst = src.resample(to, b);
                assert_eq!((dst.image.width, dst.image.height), to.dimensions(b.max(1)));
                assert!(dst
                    .image
                    .pixels
                    .iter()
                    .all(|p| p.iter().all(|c| c.is_finite())));
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Detection and validation.

#[test]
fn detect_by_aspect_ratio() {
    assert_eq!(detect(2048, 1024, None).unwrap(), Layout::LatLong);
    assert_eq!(detect(2, 1, None).unwrap(), Layout::LatLong);
    assert_eq!(detect(512, 3072, None).unwrap(), Layout::Cube);
    assert_eq!(detect(1, 6, None).unwrap(), Layout::Cube);
    assert_eq!(detect(3072, 512, None).unwrap(), Layout::HStrip);
    assert_eq!(detect(2048, 1536, None).unwrap(), Layout::HCross);
    assert_eq!(detect(1536, 2048, None).unwrap(), Layout::VCross);
    for (w, h) in [(1000, 1000), (2049, 1024), (0, 0), (5, 0), (4, 4), (10, 7)] {
        let e = detect(w, h, None).unwrap_err().to_string();
        assert!(e.contains("--in-layout"), "{e}");
        assert!(e.contains(&format!("{w}x{h}")), "{e}");
    }
}

#[test]
fn detect_attribute_wins_but_is_checked() {
    assert_eq!(
        detect(512, 3072, Some(Layout::VStrip)).unwrap(),
        Layout::VStrip
    );
    assert_eq!(
        detect(2048, 1024, Some(Layout::LatLong)).unwrap(),
        Layout::LatLong
    );
    let e = detect(2048, 1000, Some(Layout::LatLong))
        .unwrap_err()
        .to_string();
    assert!(e.contains("lat-long must be 2:1, got 2048x1000"), "{e}");
    assert!(detect(2048, 1024, Some(Layout::Cube)).is_err());
    assert!(detect(400, 300, Some(Layout::VCross)).is_err());
}

#[test]
fn new_validates_dimensions() {
    let e = EnvMap::new(Layout::LatLong, RgbImage::new(100, 30))
        .unwrap_err()
        .to_string();
    assert_eq!(e, "lat-long must be 2:1, got 100x30");
    for layout in Layout::ALL {
        let (w, h) = layout.dimensions(4);
        assert!(EnvMap::new(layout, RgbImage::new(w, h)).is_ok());
        assert!(EnvMap::new(layout, RgbImage::new(w + 1, h)).is_err());
        assert!(EnvMap::new(layout, RgbImage::new(0, 0)).is_err());
        let mut bad = RgbImage::new(w, h);
        bad.pixels.pop();
        assert!(EnvMap::new(layout, bad).is_err());
    }
    assert_eq!(map_of(Layout::HCross, 7).face_size(), 7);
    assert_eq!(map_of(Layout::LatLong, 7).face_size(), 7);
    assert_eq!(map_of(Layout::VStrip, 5).face_size(), 5);
}

#[test]
fn from_faces_stacks_in_order_and_names_bad_faces() {
    let faces: [RgbImage; 6] = std::array::from_fn(|i| {
        let mut f = RgbImage::new(2, 2);
        f.pixels.iter_mut().for_each(|p| *p = [i as f32; 3]);
        f
    });
    let m = EnvMap::from_faces(faces.clone()).unwrap();
    assert_eq!(m.layout, Layout::Cube);
    assert_eq!((m.image.width, m.image.height), (2, 12));
    for (i, f) in Face::ALL.iter().enumerate() {
        assert_eq!(m.sample(f.axis()), [i as f32; 3], "{}", f.name());
    }
    let mut bad = faces.clone();
    bad[2] = RgbImage::new(2, 3);
    let e = EnvMap::from_faces(bad).unwrap_err().to_string();
    assert!(e.contains("+Y") && e.contains("2x3"), "{e}");
    let mut bad = faces;
    bad[5] = RgbImage::new(3, 3);
    let e = EnvMap::from_faces(bad).unwrap_err().to_string();
    assert!(e.contains("-Z") && e.contains("3x3"), "{e}");
}

#[test]
fn layout_names_serialise_lowercase() {
    assert_eq!(
        serde_json::to_string(&Layout::LatLong).unwrap(),
        "\"latlong\""
    );
    assert_eq!(
        serde_json::from_str::<Layout>("\"hcross\"").unwrap(),
        Layout::HCross
    );
    for l in Layout::ALL {
        assert_eq!(
            serde_json::to_string(&l).unwrap(),
            format!("\"{}\"", l.name())
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Orientation.

#[test]
fn orientation_round_trips_and_z_up() {
    let dirs = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.3, -0.5, 0.81],
        [-0.7, 0.1, -0.2],
    ];
    for up in [Up::Y, Up::Z] {
        for rot in [0.0, 30.0, 90.0, -135.0, 400.0] {
            let o = Orientation {
                up,
                rotation_deg: rot,
            };
            for d in dirs {
                let back = o.to_map(o.to_world(d));
                let back2 = o.to_world(o.to_map(d));
                for i in 0..3 {
                    assert!((back[i] - d[i]).abs() < 1e-12);
                    assert!((back2[i] - d[i]).abs() < 1e-12);
                }
            }
        }
    }
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-12);
    let z_up = Orientation {
        up: Up::Z,
        rotation_deg: 0.0,
    };
    assert!(close(z_up.to_world([0.0, 0.0, 1.0]), [0.0, 1.0, 0.0]));
    assert!(close(z_up.to_world([1.0, 0.0, 0.0]), [1.0, 0.0, 0.0]));
    // Right-handed: map +Y (Z up) becomes world -Z.
    assert!(close(z_up.to_world([0.0, 1.0, 0.0]), [0.0, 0.0, -1.0]));
    assert_eq!(
        Orientation::default().to_world([0.1, 0.2, 0.3]),
        [0.1, 0.2, 0.3]
    );
    // A quarter turn about the up axis takes +Z to +X and keeps up.
    let turn = Orientation {
        up: Up::Y,
        rotation_deg: 90.0,
    };
    assert!(close(turn.to_world([0.0, 0.0, 1.0]), [1.0, 0.0, 0.0]));
    assert!(close(turn.to_world([0.0, 1.0, 0.0]), [0.0, 1.0, 0.0]));
}

#[test]
fn oriented_resampling_puts_map_directions_where_the_orientation_says() {
    // A smooth function in map space, resampled with an orientation: each world direction d
    // must get the map's value at to_map(d), within the filtering error of the test above.
    // A sign error in the rotation or the Z-up swap gives errors of order 1.
    let src = filled(Layout::LatLong, 64, smooth);
    for (up, rot) in [(Up::Y, 90.0), (Up::Y, -30.0), (Up::Z, 0.0), (Up::Z, 135.0)] {
        let o = Orientation {
            up,
            rotation_deg: rot,
        };
        for layout in [Layout::LatLong, Layout::Cube] {
            let out = src.resample_oriented(layout, 32, &o);
            let mut worst = 0f32;
            for (_, y, d, _, v) in out.pixels_with_directions() {
                if layout == Layout::LatLong && (y == 0 || y + 1 == out.image.height) {
                    continue; // polar rows: see the test above
                }
                let want = smooth(o.to_map(d));
                for c in 0..3 {
                    worst = worst.max((v[c] - want[c]).abs());
                }
            }
            assert!(worst < 0.02, "{up:?} {rot}: {layout:?} off by {worst}");
        }
    }
    // The identity changes nothing.
    let same = src.resample_oriented(Layout::LatLong, 64, &Orientation::default());
    let plain = src.resample(Layout::LatLong, 64);
    assert_eq!(same.image.pixels, plain.image.pixels);
}

/// Throughput on the largest map (not a timed assertion; run with
/// `cargo test --release --test layout -- --ignored --nocapture`).
#[test]
#[ignore]
fn resample_large_map_throughput() {
    let src = filled(Layout::LatLong, 4096, smooth);
    let t = std::time::Instant::now();
    let cube = src.resample(Layout::Cube, 2048);
    let t1 = t.elapsed();
    let back = cube.resample(Layout::LatLong, 4096);
    let t2 = t.elapsed() - t1;
    eprintln!(
        "8192x4096 lat-long -> 2048 cube: {:.2} s; back: {:.2} s ({} threads)",
        t1.as_secs_f64(),
        t2.as_secs_f64(),
        rayon::current_num_threads()
    );
    assert_eq!(back.image.pixels.len(), src.image.pixels.len());
}
