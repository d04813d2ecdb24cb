//! The preview renderer against independent references: the GPU against the CPU, the film colour
//! at normal incidence against the thin-film module, closed forms of the Phong model, the
//! ColorChecker colours of `specmap color`, energy at grazing angles, and the loaders of the
//! three environment formats against one another.
//!
//! GPU tests need a wgpu adapter. Without one they print a notice and pass, unless
//! `SPECMAP_REQUIRE_GPU=1` (set by tools/test.sh, which installs Mesa's lavapipe), where a
//! missing adapter fails.

use specmap::colorimetry::{delta_e_2000, Cmfs, Lab, Observer, RgbSpace};
use specmap::render::prepare::Prepared;
use specmap::render::{
    compare, cpu, env, Environment, Image, Lighting, Object, Preset, Scene, Shape, Spectral,
    Surface, View,
};
use specmap::spectrum::{Interpolation, Rule, Tabulated, WavelengthGrid};
use specmap::thinfilm::{Coherence, Incidence, Index, Layer, Material, Polarization, Stack};

mod common;

/// One device for the whole test binary (lavapipe is slow to start).
use common::gpu;

fn spectral(step: f64) -> Spectral {
    Spectral::step(step).unwrap()
}

fn lab_of(rgb: [f64; 3]) -> Lab {
    let s = RgbSpace::SRGB;
    Lab::from_xyz(s.xyz_from_rgb(rgb), s.xyz_from_rgb([1.0; 3]))
}

fn px(img: &Image, x: usize, y: usize) -> [f64; 3] {
    img.get(x, y).map(|v| v as f64)
}

/// The stated tolerance of the GPU/CPU agreement: mean CIEDE2000 below 0.5, max below 2.
const MEAN_TOL: f64 = 0.5;
const MAX_TOL: f64 = 2.0;

#[test]
fn gpu_matches_cpu_on_every_preset() {
    let Some(gpu) = gpu() else { return };
    let sp = spectral(10.0);
    for preset in Preset::ALL {
        let (w, h) = preset.default_size();
        let (w, h) = (48 * w / h.max(w), 48 * h / h.max(w));
        let scene = preset.scene(w, h, "D65", None).unwrap();
        let p = Prepared::new(&scene, &sp).unwrap();
        let c = cpu::render(&p);
        let (g, _) = gpu.render(&p).unwrap();
        let cmp = compare(&c, &g, &RgbSpace::SRGB).unwrap();
        eprintln!("{}: {cmp:?}", preset.name());
        assert_eq!(cmp.non_finite, 0, "{}", preset.name());
        assert!(
            cmp.mean < MEAN_TOL && cmp.max < MAX_TOL,
            "{}: GPU vs CPU {cmp:?}",
            preset.name()
        );
    }
}

/// The sun and the map of a real environment, through every lookup the shader makes.
#[test]
fn gpu_matches_cpu_under_an_environment_map() {
    let Some(gpu) = gpu() else { return };
    let (lighting, report) = env::load(std::path::Path::new("envmaps/sunrise.exr"), "D65").unwrap();
    assert!(report.sun_irradiance.is_some(), "{report:?}");
    let sp = spectral(20.0);
    // The view's orbit turns every map lookup and the sun: both backends alike.
    let orbits = [None, Some((120.0, 20.0)), Some((-35.0, -60.0))];
    for (preset, orbit) in [Preset::Ball, Preset::TransparentBall]
        .into_iter()
        .flat_map(|p| orbits.map(|o| (p, o)))
    {
        let mut scene = preset.scene(40, 40, "D65", Some(lighting.clone())).unwrap();
        if let Some((yaw_deg, pitch_deg)) = orbit {
            scene.orbit(specmap::render::Orbit { yaw_deg, pitch_deg });
        }
        let p = Prepared::new(&scene, &sp).unwrap();
        let c = cpu::render(&p);
        let (g, _) = gpu.render(&p).unwrap();
        let cmp = compare(&c, &g, &RgbSpace::SRGB).unwrap();
        eprintln!(
            "{} under sunrise.exr, orbit {orbit:?}: {cmp:?}",
            preset.name()
        );
        assert!(cmp.mean < MEAN_TOL && cmp.max < MAX_TOL, "{cmp:?}");
    }
}

/// The ball's centre pixel looks at the film along its normal, in a uniform D65 light with no
/// sun and no pigment: its colour is the film's reflectance under D65, as `specmap thinfilm`
/// computes it with the thin-film module (f64, 1 nm... here on the render's own grid).
#[test]
fn film_colour_at_normal_incidence_matches_thinfilm_module() {
    for (layers, substrate, step) in [
        (vec![(2.7, 270.0)], 1.45, 5.0),
        (vec![(2.3, 350.0)], 1.45, 1.0),
        (vec![(1.38, 100.0), (2.1, 130.0)], 1.52, 10.0),
    ] {
        let sp = spectral(step);
        let mut scene = Preset::Ball.scene(33, 33, "D65", None).unwrap();
        scene.lightings[0].sun = None;
        let film = scene.objects[0].surface.film.as_mut().unwrap();
        film.layers = layers
            .iter()
            .map(|&(n, d)| Layer::new(Material::constant(Index::real(n).unwrap()), d).unwrap())
            .collect();
        film.substrate = Material::constant(Index::real(substrate).unwrap());
        let stack = Stack::new(
            film.ambient.clone(),
            film.layers.clone(),
            film.substrate.clone(),
        );
        scene.objects[0].surface.kd = 0.0;
        let resp = stack
            .response(
                &sp.grid,
                &Incidence::NORMAL,
                Polarization::Unpolarized,
                Coherence::Coherent,
            )
            .unwrap();
        let cmfs = Cmfs::new(Observer::Cie1931, &sp.grid).unwrap();
        let d65 = specmap::data::spectrum("D65")
            .unwrap()
            .data
            .resample(&sp.grid, Interpolation::LIGHT);
        let r = specmap::spectrum::Spectrum::new(sp.grid, resp.reflectance).unwrap();
        let xyz = cmfs.reflectance_xyz(&r, &d65, Rule::Riemann).unwrap();
        let want = RgbSpace::SRGB.rgb_from_xyz(xyz);
        let p = Prepared::new(&scene, &sp).unwrap();
        let c = cpu::render(&p);
        let got = px(&c, 16, 16);
        let de = delta_e_2000(lab_of(want), lab_of(got));
        assert!(de < 0.01, "CPU {layers:?}: {got:?} vs {want:?}: dE {de}");
        if let Some(gpu) = gpu() {
            let (g, _) = gpu.render(&p).unwrap();
            let got = px(&g, 16, 16);
            let de = delta_e_2000(lab_of(want), lab_of(got));
            assert!(de < 0.1, "GPU {layers:?}: {got:?} vs {want:?}: dE {de}");
        }
    }
}

fn sphere_scene(light: &str, surface: Surface, sun: bool) -> Scene {
    let lighting = Lighting::uniform(
        light,
        1.0,
        sun.then_some(specmap::render::Sun {
            direction: [0.0, 0.0, 1.0],
            irradiance: 1.0,
        }),
    )
    .unwrap();
    Scene {
        name: "test".into(),
        width: 31,
        height: 31,
        view: View {
            center: [0.0, 0.0],
            half_height: 1.1,
        },
        lightings: vec![lighting],
        objects: vec![Object {
            shape: Shape::Sphere {
                center: [0.0, 0.0, 0.0],
                radius: 1.0,
            },
            surface,
            lighting: 0,
            ramp: None,
            main: true,
        }],
        background: 0,
        backdrop: specmap::render::Backdrop::DEFAULT,
        orientation: specmap::render::IDENTITY,
        any_orientation: false,
    }
}

fn lambertian(albedo: f64) -> Surface {
    Surface {
        label: "grey".into(),
        diffuse: Some(Tabulated::new(vec![380.0, 780.0], vec![albedo, albedo]).unwrap()),
        kd: 1.0,
        ks: 0.0,
        shininess: 10.0,
        film: None,
        transparent: false,
    }
}

/// Closed form: a Lambertian sphere of albedo a in a uniform light L has radiance a L at every
/// pixel, whatever the normal; the background is L. With ks and no film the specular lobe in
/// the uniform light adds ks L.
#[test]
fn lambertian_sphere_in_uniform_light_is_albedo_times_light() {
    let sp = spectral(5.0);
    for light in ["A", "D65", "FL2"] {
        let cmfs = Cmfs::new(Observer::Cie1931, &sp.grid).unwrap();
        let s = specmap::data::spectrum(light)
            .unwrap()
            .data
            .resample(&sp.grid, Interpolation::LIGHT);
        let l = RgbSpace::SRGB.rgb_from_xyz(cmfs.light_xyz(&s, Rule::Riemann).unwrap());
        for (albedo, ks) in [(1.0, 0.0), (0.37, 0.0), (0.5, 0.25)] {
            let mut surf = lambertian(albedo);
            surf.ks = ks;
            let scene = sphere_scene(light, surf, false);
            let p = Prepared::new(&scene, &sp).unwrap();
            let mut images = vec![("cpu", cpu::render(&p), 1e-6)];
            if let Some(gpu) = gpu() {
                images.push(("gpu", gpu.render(&p).unwrap().0, 2e-5));
            }
            for (name, img, tol) in images {
                for y in 0..31 {
                    for x in 0..31 {
                        let inside = cpu::hit_pixel(&p, x, y).is_some();
                        let k = if inside { albedo + ks } else { 1.0 };
                        let got = px(&img, x, y);
                        for c in 0..3 {
                            assert!(
                                (got[c] - k * l[c]).abs() <= tol * 10.0 * l[c].abs().max(1.0),
                                "{name} {light} albedo {albedo} ks {ks} ({x},{y}): {got:?} vs {:?}",
                                l.map(|v| v * k)
                            );
                        }
                    }
                }
            }
        }
    }
}

/// Closed form with the sun: a Lambertian sphere lit by the sun from the camera's direction gets
/// `a (L + E cos / pi)` at every pixel, `cos = n_z`.
#[test]
fn lambertian_sphere_under_the_sun_follows_the_cosine() {
    let sp = spectral(10.0);
    let scene = sphere_scene("E", lambertian(0.8), true);
    let p = Prepared::new(&scene, &sp).unwrap();
    let img = cpu::render(&p);
    let cmfs = Cmfs::new(Observer::Cie1931, &sp.grid).unwrap();
    let e = specmap::data::spectrum("E")
        .unwrap()
        .data
        .resample(&sp.grid, Interpolation::LIGHT);
    let l = RgbSpace::SRGB.rgb_from_xyz(cmfs.light_xyz(&e, Rule::Riemann).unwrap());
    for (x, y) in [(15, 15), (20, 15), (15, 5), (26, 20)] {
        let [wx, wy] = cpu::pixel_position(&p, x, y);
        let nz = (1.0 - wx * wx - wy * wy).sqrt();
        let k = 0.8 * (1.0 + nz / std::f64::consts::PI);
        let got = px(&img, x, y);
        for c in 0..3 {
            assert!(
                (got[c] - k * l[c]).abs() < 1e-5,
                "({x},{y}) {got:?} vs {k} * {l:?}"
            );
        }
    }
}

/// Under each light of the chart, the centre of each ColorChecker patch has the colour that
/// `specmap color colorchecker:<patch> --under <light>` computes (the library's
/// `Cmfs::reflectance_xyz`), on the render's grid.
#[test]
fn chart_patches_have_the_colours_of_specmap_color() {
    let sp = spectral(5.0);
    let scene = Preset::Chart.scene(768, 512, "D65", None).unwrap();
    let p = Prepared::new(&scene, &sp).unwrap();
    let cmfs = Cmfs::new(Observer::Cie1931, &sp.grid).unwrap();
    let cc = specmap::data::Table::builtin("colorchecker").unwrap();
    let mut checked = 0;
    for (i, o) in scene.objects.iter().enumerate() {
        let Some(patch) = o.surface.label.strip_prefix("colorchecker:") else {
            continue;
        };
        let Shape::Quad { center, .. } = o.shape else {
            continue;
        };
        let light = Preset::CHART_LIGHTS[o.lighting];
        let s = specmap::data::spectrum(light)
            .unwrap()
            .data
            .resample(&sp.grid, Interpolation::LIGHT);
        let r = cc
            .column(patch)
            .unwrap()
            .resample(&sp.grid, Interpolation::SMOOTH);
        let want =
            RgbSpace::SRGB.rgb_from_xyz(cmfs.reflectance_xyz(&r, &s, Rule::Riemann).unwrap());
        // The pixel at the patch centre.
        let v = p.params.view.map(|c| c as f64);
        let x = ((center[0] - v[0]) / v[2] + 384.0).floor() as usize;
        let y = ((v[1] - center[1]) / v[2] + 256.0).floor() as usize;
        let (hit, _) = cpu::hit_pixel(&p, x, y).unwrap();
        assert_eq!(hit, i);
        let one = single_pixel(&p, x, y);
        let de = delta_e_2000(lab_of(want), lab_of(one));
        assert!(
            de < 0.01,
            "{patch} under {light}: {one:?} vs {want:?} dE {de}"
        );
        checked += 1;
    }
    assert_eq!(checked, 72);
}

/// One pixel of a CPU render (a 1x1 crop of the frame around (x, y)).
fn single_pixel(p: &Prepared, x: usize, y: usize) -> [f64; 3] {
    let mut q = p.clone();
    let [wx, wy] = cpu::pixel_position(p, x, y);
    q.params.width = 1;
    q.params.height = 1;
    q.params.view[0] = wx as f32;
    q.params.view[1] = wy as f32;
    // The frame changed: so did which objects its one row can hit.
    q.rows = specmap::render::candidates::index(&q.objects, &q.params);
    px(&cpu::render(&q), 0, 0)
}

/// The metamer of the chart is the same colour as neutral 5 under D65 (1 nm) and not under A.
#[test]
fn chart_metamer_matches_under_d65_only() {
    let grid = WavelengthGrid::visible_1nm();
    let cmfs = Cmfs::new(Observer::Cie1931, &grid).unwrap();
    let cc = specmap::data::Table::builtin("colorchecker").unwrap();
    let grey = cc.column("neutral-5").unwrap();
    let m = specmap::render::presets::d65_metamer(&grey).unwrap();
    let de = |light: &str| {
        let s = specmap::data::spectrum(light)
            .unwrap()
            .data
            .resample(&grid, Interpolation::LIGHT);
        let white = cmfs.light_xyz(&s, Rule::Riemann).unwrap();
        let lab = |t: &Tabulated| {
            let r = t.resample(&grid, Interpolation::SMOOTH);
            Lab::from_xyz(cmfs.reflectance_xyz(&r, &s, Rule::Riemann).unwrap(), white)
        };
        delta_e_2000(lab(&grey), lab(&m))
    };
    assert!(de("D65") < 0.01, "{}", de("D65"));
    assert!(de("A") > 1.0, "{}", de("A"));
    assert!(m.values().iter().all(|&v| (0.0..=1.0).contains(&v)));
}

/// Eq. 9 conserves energy: a lossless transparent film in a uniform light reflects R L and
/// transmits T L with R + T = 1, so every pixel is L, up to the grazing silhouette (cos -> 0,
/// R -> 1) and with no NaN. An opaque film ball never exceeds the light.
#[test]
fn films_conserve_energy_at_grazing_angles() {
    let sp = spectral(10.0);
    let mut scene = Preset::TransparentBall.scene(64, 32, "D65", None).unwrap();
    scene.lightings[0].environment = Environment::Uniform { radiance: 1.0 };
    scene.lightings[0].sun = None;
    let p = Prepared::new(&scene, &sp).unwrap();
    let mut images = vec![("cpu", cpu::render(&p), 1e-5)];
    if let Some(gpu) = gpu() {
        images.push(("gpu", gpu.render(&p).unwrap().0, 1e-3));
    }
    for (name, img, tol) in &images {
        let bg = img.get(0, 0);
        for (i, q) in img.pixels.iter().enumerate() {
            for c in 0..3 {
                assert!(q[c].is_finite(), "{name}: pixel {i} not finite");
                assert!(
                    (q[c] - bg[c]).abs() <= *tol as f32 * bg[c].abs().max(1.0),
                    "{name}: pixel {i} {q:?} vs background {bg:?}"
                );
            }
        }
    }
    // Opaque chrome-oxide ball on black plastic, uniform light, no sun: Y <= 1 everywhere.
    let mut scene = Preset::Ball.scene(41, 41, "D65", None).unwrap();
    scene.lightings[0].sun = None;
    let p = Prepared::new(&scene, &sp).unwrap();
    let mut images = vec![("cpu", cpu::render(&p))];
    if let Some(gpu) = gpu() {
        images.push(("gpu", gpu.render(&p).unwrap().0));
    }
    let m = RgbSpace::SRGB.to_xyz_matrix();
    for (name, img) in images {
        for q in &img.pixels {
            assert!(q.iter().all(|v| v.is_finite()), "{name}: NaN");
            let y: f64 = (0..3).map(|c| m[(1, c)] * q[c] as f64).sum();
            assert!(y <= 1.0 + 1e-4, "{name}: Y {y} > 1 ({q:?})");
        }
    }
}

/// In the paper's exact mode the three environment formats give one lighting: the RGB map
/// converted on the fly, and the basis EXR and the spectral EXR that `specmap convert` writes from
/// it (lit by their own spectra, which are the same ColorChecker spectra times D65, and the
/// sun's). The faithful method's spectra differ from the paper's by design; tests/render_own.rs
/// checks those against the full-spectral reference.
#[test]
fn basis_and_spectral_maps_light_the_scene_as_the_rgb_map_does() {
    use specmap::envmap::convert::{convert, ConvertOptions, OutputFormat};
    let dir = tempfile::tempdir().unwrap();
    let sp = spectral(10.0);
    let input = "envmaps/sunrise.exr";
    let (rgb, _) = env::load(std::path::Path::new(input), "D65").unwrap();
    let reference = {
        let scene = Preset::Ball.scene(32, 32, "D65", Some(rgb)).unwrap();
        cpu::render(&Prepared::new(&scene, &sp).unwrap())
    };
    for format in [OutputFormat::Basis, OutputFormat::Spectral] {
        let out = dir.path().join(format!("{format:?}.exr"));
        let opts = ConvertOptions {
            format,
            precision: specmap::envmap::files::Precision::Float,
            ..ConvertOptions::default()
        };
        convert(input, &out, &opts, &|_, _| {}).unwrap();
        let (l, report) = env::load(&out, "FL2").unwrap();
        eprintln!("{report:?}");
        assert!(!report.light_used);
        let scene = Preset::Ball.scene(32, 32, "D65", Some(l)).unwrap();
        let img = cpu::render(&Prepared::new(&scene, &sp).unwrap());
        let cmp = compare(&reference, &img, &RgbSpace::SRGB).unwrap();
        eprintln!("{format:?} vs rgb: {cmp:?}");
        assert!(cmp.mean < 0.5 && cmp.max < 2.0, "{format:?}: {cmp:?}");
    }
}

#[test]
fn invalid_scenes_are_errors() {
    let sp = spectral(10.0);
    let mut s = sphere_scene("D65", lambertian(0.5), false);
    s.objects[0].surface.transparent = true;
    assert!(Prepared::new(&s, &sp)
        .unwrap_err()
        .to_string()
        .contains("film"));
    let mut s = sphere_scene("D65", lambertian(0.5), false);
    s.objects[0].lighting = 3;
    assert!(Prepared::new(&s, &sp).is_err());
    let mut s = sphere_scene("D65", lambertian(0.5), false);
    s.width = 0;
    assert!(Prepared::new(&s, &sp).is_err());
    assert!(Spectral::samples(1).is_err());
    assert_eq!(Spectral::samples(81).unwrap().grid.step_nm(), 5.0);
}
