// Spectral preview renderer, one invocation per pixel: the model of src/render/mod.rs, the same
// function as src/render/cpu.rs in f32. The film is the thin-film module's coherent recursion
// (src/thinfilm.rs, Film::coherent_rt, unpolarised) ported line by line.

struct Params {
    width: u32,
    height: u32,
    n_wl: u32,
    n_objects: u32,
    background: u32,
    // The quadrature: n_wl nodes (wavelengths at wl_offset) and their x, y, z weights over
    // sum w_y (at cmf_offset, n_wl each), so that XYZ = sum_i w_i I(lambda_i).
    cmf_offset: u32,
    wl_offset: u32,
    // HIDE_BACKGROUND: rays that miss are black.
    flags: u32,
    // Image centre x, y, world size of a pixel, tan(half the background's vertical fov).
    view: vec4<f32>,
    rgb0: vec4<f32>,
    rgb1: vec4<f32>,
    rgb2: vec4<f32>,
    // Camera to world for map lookups (Scene::orientation), rows.
    rot0: vec4<f32>,
    rot1: vec4<f32>,
    rot2: vec4<f32>,
}

struct Object {
    kind: u32,
    material: u32,
    lighting: u32,
    spec_map: u32,
    p0: vec4<f32>,
    p1: vec4<f32>,
    ramp: vec4<f32>,
    flags: vec4<u32>,
}

struct Material {
    flags: u32,
    n_layers: u32,
    diffuse_offset: u32,
    film_offset: u32,
    coef: vec4<f32>,
    thickness: array<vec4<f32>, 2>,
}

struct Lighting {
    spectra: u32,
    diffuse_map: u32,
    background_map: u32,
    has_sun: u32,
    sun: vec4<f32>,
    // Groups of four coefficients per texel, offset of the sun's SPD.
    shape: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> spectra: array<f32>;
@group(0) @binding(2) var<storage, read> objects: array<Object>;
@group(0) @binding(3) var<storage, read> materials: array<Material>;
@group(0) @binding(4) var<storage, read> lightings: array<Lighting>;
@group(0) @binding(5) var<storage, read> maps: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read> texels: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> out_rgb: array<vec4<f32>>;
// Per pixel row and band of BAND pixels, the objects it can hit (candidates.rs): height * bands + 1
// offsets, then object indices.
@group(0) @binding(8) var<storage, read> rows: array<u32>;

const PI: f32 = 3.14159265358979;
const TWO_PI: f32 = 6.28318530717959;
const SPHERE: u32 = 0u;
const CYLINDER_X: u32 = 1u;
const QUAD: u32 = 2u;
const TRANSPARENT: u32 = 1u;
const HAS_FILM: u32 = 2u;
const HAS_DIFFUSE: u32 = 4u;
const HIDE_BACKGROUND: u32 = 1u;
// The most groups of four coefficients a texel holds (prepare.rs: MAX_GROUPS).
const MAX_GROUPS: u32 = 8u;
// Pixels per band of the object index (candidates.rs: BAND).
const BAND: u32 = 8u;

// ---- environment maps (latlong.rs: sample) ---------------------------------------------------

// The four texels around a direction and their bilinear weights.
struct Taps {
    idx: vec4<u32>,
    wt: vec4<f32>,
}

fn taps(map: u32, dir: vec3<f32>) -> Taps {
    let m = maps[map];
    let w = m.y;
    let h = m.z;
    var t: Taps;
    // A uniform lighting's maps are one texel: no direction to look up (latlong.rs: bilinear).
    if (w * h == 1u) {
        t.idx = vec4<u32>(0u, 0u, 0u, 0u);
        t.wt = vec4<f32>(1.0, 0.0, 0.0, 0.0);
        return t;
    }
    let wd = vec3<f32>(dot(params.rot0.xyz, dir), dot(params.rot1.xyz, dir), dot(params.rot2.xyz, dir));
    let u = 0.5 - atan2(wd.x, wd.z) / TWO_PI;
    let v = acos(clamp(wd.y, -1.0, 1.0)) / PI;
    let fx = u * f32(w) - 0.5;
    let fy = clamp(v * f32(h) - 0.5, 0.0, f32(h - 1u));
    let x0f = floor(fx);
    let tx = fx - x0f;
    let y0f = floor(fy);
    let ty = fy - y0f;
    let wi = i32(w);
    let x0 = u32(((i32(x0f) % wi) + wi) % wi);
    let x1 = (x0 + 1u) % w;
    let y0 = u32(y0f);
    let y1 = min(y0 + 1u, h - 1u);
    t.idx = vec4<u32>(y0 * w + x0, y0 * w + x1, y1 * w + x0, y1 * w + x1);
    t.wt = vec4<f32>((1.0 - tx) * (1.0 - ty), tx * (1.0 - ty), (1.0 - tx) * ty, tx * ty);
    return t;
}

// Group g of the map's coefficients in the direction of `t`.
fn sample_group(map: u32, t: Taps, g: u32) -> vec4<f32> {
    let m = maps[map];
    let off = m.x;
    let groups = m.w;
    return texels[off + t.idx.x * groups + g] * t.wt.x + texels[off + t.idx.y * groups + g] * t.wt.y
        + texels[off + t.idx.z * groups + g] * t.wt.z + texels[off + t.idx.w * groups + g] * t.wt.w;
}

// ---- complex arithmetic ----------------------------------------------------------------------

fn cmul(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}

fn cdiv(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    let d = b.x * b.x + b.y * b.y;
    return vec2<f32>((a.x * b.x + a.y * b.y) / d, (a.y * b.x - a.x * b.y) / d);
}

fn norm2(a: vec2<f32>) -> f32 {
    return a.x * a.x + a.y * a.y;
}

// sqrt on the forward branch: Im >= 0, and Re >= 0 when Im = 0 (thinfilm.rs: forward_sqrt).
fn forward_sqrt(z: vec2<f32>) -> vec2<f32> {
    let m = length(z);
    if (m == 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    var a: f32;
    var b: f32;
    if (z.x >= 0.0) {
        a = sqrt((m + z.x) / 2.0);
        b = z.y / (2.0 * a);
    } else {
        b = sqrt((m - z.x) / 2.0);
        a = z.y / (2.0 * b);
    }
    if (b < 0.0 || (b == 0.0 && a < 0.0)) {
        return vec2<f32>(-a, -b);
    }
    return vec2<f32>(a, b);
}

// ---- thin film (thinfilm.rs) -----------------------------------------------------------------

struct Medium {
    n: vec2<f32>,
    n2: vec2<f32>,
    q: vec2<f32>,
}

fn film_index(mat: Material, m: u32, i: u32) -> vec2<f32> {
    let nw = params.n_wl;
    let base = mat.film_offset + 2u * m * nw + i;
    return vec2<f32>(spectra[base], spectra[base + nw]);
}

// Medium m (0 = ambient) seen with xi^2 given by g = (n0^2, q0^2).
fn medium(mat: Material, m: u32, i: u32, cos0: f32) -> Medium {
    let n = film_index(mat, m, i);
    let n2 = cmul(n, n);
    if (m == 0u) {
        return Medium(n, n2, vec2<f32>(n.x * cos0, 0.0));
    }
    let n0 = film_index(mat, 0u, i).x;
    let q0 = n0 * cos0;
    let z = vec2<f32>(n2.x - n0 * n0 + q0 * q0, n2.y);
    return Medium(n, n2, forward_sqrt(z));
}

struct Amp {
    r: vec2<f32>,
    t: vec2<f32>,
}

fn fresnel(p_wave: bool, a: Medium, b: Medium) -> Amp {
    if (all(a.n == b.n)) {
        return Amp(vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0));
    }
    if (!p_wave) {
        let den = a.q + b.q;
        return Amp(cdiv(a.q - b.q, den), cdiv(a.q * 2.0, den));
    }
    let x = cmul(b.n2, a.q);
    let y = cmul(a.n2, b.q);
    let den = x + y;
    return Amp(cdiv(x - y, den), cdiv(cmul(cmul(a.n, b.n), a.q) * 2.0, den));
}

fn propagate(q: vec2<f32>, d_over_lambda: f32) -> vec2<f32> {
    let cycles = q.x * d_over_lambda;
    let frac = cycles - round(cycles);
    let ph = TWO_PI * frac;
    let decay = exp(-(TWO_PI * q.y * d_over_lambda));
    return vec2<f32>(decay * cos(ph), decay * sin(ph));
}

fn flux(p_wave: bool, m: Medium) -> f32 {
    if (!p_wave) {
        return m.q.x;
    }
    return cmul(m.n2, vec2<f32>(m.q.x, -m.q.y)).x / norm2(m.n);
}

fn layer_thickness(mat: Material, k: u32) -> f32 {
    return mat.thickness[k / 4u][k % 4u];
}

// Unpolarised (R, T) of the material's film at wavelength index i, cos of the angle in the
// ambient, thicknesses times scale.
fn film_rt(mat: Material, i: u32, cos0: f32, scale: f32) -> vec2<f32> {
    if (cos0 == 0.0) {
        return vec2<f32>(1.0, 0.0);
    }
    let lambda = spectra[params.wl_offset + i];
    let last = mat.n_layers + 1u;
    let sub = medium(mat, last, i, cos0);
    var j = last - 1u;
    var here = medium(mat, j, i, cos0);
    let one = vec2<f32>(1.0, 0.0);
    let s0 = fresnel(false, here, sub);
    let p0 = fresnel(true, here, sub);
    var rs = s0.r;
    var ts = s0.t;
    var rp = p0.r;
    var tp = p0.t;
    loop {
        if (j == 0u) {
            break;
        }
        let above = medium(mat, j - 1u, i, cos0);
        let e1 = propagate(here.q, layer_thickness(mat, j - 1u) * scale / lambda);
        let e2 = cmul(e1, e1);
        let sa = fresnel(false, above, here);
        let xs = cmul(rs, e2);
        let dens = one + cmul(sa.r, xs);
        rs = cdiv(sa.r + xs, dens);
        ts = cdiv(cmul(cmul(sa.t, ts), e1), dens);
        let pa = fresnel(true, above, here);
        let xp = cmul(rp, e2);
        let denp = one + cmul(pa.r, xp);
        rp = cdiv(pa.r + xp, denp);
        tp = cdiv(cmul(cmul(pa.t, tp), e1), denp);
        here = above;
        j = j - 1u;
    }
    var t_s = 0.0;
    let fs = flux(false, here);
    if (fs > 0.0) {
        t_s = norm2(ts) * flux(false, sub) / fs;
    }
    var t_p = 0.0;
    let fp = flux(true, here);
    if (fp > 0.0) {
        t_p = norm2(tp) * flux(true, sub) / fp;
    }
    return vec2<f32>(0.5 * (norm2(rs) + norm2(rp)), 0.5 * (t_s + t_p));
}

// ---- shading ---------------------------------------------------------------------------------

fn lobe(c: f32, n: f32) -> f32 {
    if (c > 0.0) {
        return pow(c, n);
    }
    return 0.0;
}

fn light_spectrum(off: u32, j: u32, i: u32) -> f32 {
    return spectra[off + j * params.n_wl + i];
}

// Coefficients sampled in one direction, all groups.
struct Coeffs {
    g: array<vec4<f32>, MAX_GROUPS>,
}

fn sample_all(map: u32, dir: vec3<f32>, groups: u32) -> Coeffs {
    let t = taps(map, dir);
    var c: Coeffs;
    for (var g = 0u; g < groups; g = g + 1u) {
        c.g[g] = sample_group(map, t, g);
    }
    return c;
}

fn expand(c: Coeffs, groups: u32, off: u32, i: u32) -> f32 {
    var l = 0.0;
    for (var g = 0u; g < groups; g = g + 1u) {
        let j = 4u * g;
        let s = vec4<f32>(light_spectrum(off, j, i), light_spectrum(off, j + 1u, i),
            light_spectrum(off, j + 2u, i), light_spectrum(off, j + 3u, i));
        l = l + dot(c.g[g], s);
    }
    return l;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = gid.y;
    if (x >= params.width || y >= params.height) {
        return;
    }
    let nw = params.n_wl;
    let px = params.view.x + (f32(x) + 0.5 - 0.5 * f32(params.width)) * params.view.z;
    let py = params.view.y - (f32(y) + 0.5 - 0.5 * f32(params.height)) * params.view.z;
    // The background's direction (cpu.rs: background_direction).
    let t = params.view.w;
    let bu = (f32(x) + 0.5 - 0.5 * f32(params.width)) / (0.5 * f32(params.height)) * t;
    let bv = -(f32(y) + 0.5 - 0.5 * f32(params.height)) / (0.5 * f32(params.height)) * t;
    let d = normalize(vec3<f32>(bu, bv, -1.0));

    // Nearest hit (cpu.rs: hit).
    var best = -1;
    var best_z = -3.4e38;
    var n = vec3<f32>(0.0, 0.0, 1.0);
    let tile = y * ((params.width + BAND - 1u) / BAND) + x / BAND;
    for (var r = rows[tile]; r < rows[tile + 1u]; r = r + 1u) {
        let k = rows[r];
        let o = objects[k];
        var found = false;
        var z = 0.0;
        var nn = vec3<f32>(0.0, 0.0, 1.0);
        if (o.kind == SPHERE) {
            let dx = px - o.p0.x;
            let dy = py - o.p0.y;
            let r = o.p0.w;
            let q = r * r - dx * dx - dy * dy;
            if (q >= 0.0) {
                let s = sqrt(q);
                found = true;
                z = o.p0.z + s;
                nn = vec3<f32>(dx / r, dy / r, s / r);
            }
        } else if (o.kind == CYLINDER_X) {
            let dy = py - o.p0.y;
            let r = o.p0.w;
            let q = r * r - dy * dy;
            if (abs(px - o.p0.x) <= o.p1.x && q >= 0.0) {
                let s = sqrt(q);
                found = true;
                z = o.p0.z + s;
                nn = vec3<f32>(0.0, dy / r, s / r);
            }
        } else if (o.kind == QUAD) {
            if (abs(px - o.p0.x) <= o.p1.x && abs(py - o.p0.y) <= o.p1.y) {
                found = true;
                z = o.p0.z;
            }
        }
        if (found && z > best_z) {
            best_z = z;
            best = i32(k);
            n = nn;
        }
    }

    var xyz = vec3<f32>(0.0, 0.0, 0.0);
    if (best < 0 && (params.flags & HIDE_BACKGROUND) == 0u) {
        let lt = lightings[params.background];
        let groups = lt.shape.x;
        let c = sample_all(lt.background_map, d, groups);
        for (var i = 0u; i < nw; i = i + 1u) {
            let l = expand(c, groups, lt.spectra, i);
            xyz = xyz + l * vec3<f32>(spectra[params.cmf_offset + i],
                spectra[params.cmf_offset + nw + i], spectra[params.cmf_offset + 2u * nw + i]);
        }
    } else if (best >= 0) {
        n = normalize(n);
        let o = objects[u32(best)];
        let mat = materials[o.material];
        let lt = lightings[o.lighting];
        let cos_v = clamp(n.z, 0.0, 1.0);
        let rv = vec3<f32>(2.0 * n.z * n.x, 2.0 * n.z * n.y, 2.0 * n.z * n.z - 1.0);
        let kd = mat.coef.x;
        let ks = mat.coef.y;
        let shininess = mat.coef.z;
        let transparent = (mat.flags & TRANSPARENT) != 0u;
        let has_film = (mat.flags & HAS_FILM) != 0u;
        let has_diffuse = (mat.flags & HAS_DIFFUSE) != 0u;
        let groups = lt.shape.x;
        let sun_spd = lt.shape.y;
        // A matte surface (no film, ks = 0) reflects nothing specularly (cpu.rs: specular).
        let specular = has_film || ks != 0.0;
        let cd = sample_all(lt.diffuse_map, n, groups);
        var cs: Coeffs;
        if (specular) {
            cs = sample_all(o.spec_map, rv, groups);
        }
        var ct: Coeffs;
        if (transparent) {
            ct = sample_all(lt.background_map, d, groups);
        }
        var sun_d = 0.0;
        var sun_s = 0.0;
        if (lt.has_sun != 0u) {
            let l = lt.sun.xyz;
            sun_d = lt.sun.w * max(dot(n, l), 0.0) / PI;
            if (specular) {
                sun_s = lt.sun.w * (shininess + 1.0) / TWO_PI * lobe(dot(rv, l), shininess);
            }
        }
        var scale = 1.0;
        if (o.flags.x != 0u) {
            var t = 0.0;
            if (o.ramp.y != o.ramp.x) {
                t = clamp((px - o.ramp.x) / (o.ramp.y - o.ramp.x), 0.0, 1.0);
            }
            scale = o.ramp.z + (o.ramp.w - o.ramp.z) * t;
        }
        for (var i = 0u; i < nw; i = i + 1u) {
            let e = spectra[sun_spd + i];
            let ld = expand(cd, groups, lt.spectra, i) + sun_d * e;
            var ls = 0.0;
            if (specular) {
                ls = expand(cs, groups, lt.spectra, i) + sun_s * e;
            }
            var fr = ks;
            var ft = 1.0;
            if (has_film) {
                let rt = film_rt(mat, i, cos_v, scale);
                fr = rt.x;
                ft = rt.y;
            }
            var l = 0.0;
            if (transparent) {
                l = fr * ls + ft * expand(ct, groups, lt.spectra, i);
            } else {
                var rd = 0.0;
                if (has_diffuse) {
                    rd = spectra[mat.diffuse_offset + i];
                }
                l = kd * rd * ft * ld + fr * ls;
            }
            xyz = xyz + l * vec3<f32>(spectra[params.cmf_offset + i],
                spectra[params.cmf_offset + nw + i], spectra[params.cmf_offset + 2u * nw + i]);
        }
    }
    let rgb = vec3<f32>(dot(params.rgb0.xyz, xyz), dot(params.rgb1.xyz, xyz), dot(params.rgb2.xyz, xyz));
    out_rgb[y * params.width + x] = vec4<f32>(rgb, 1.0);
}
