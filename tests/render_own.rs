//! The preview lit by the spectra a map holds (src/render/own_spectra.rs): a spectral map projected onto
//! its own K spectra renders as the full N-band spectra do (CPU reference, no projection), on
//! both backends, whatever `--light` says; the basis form of a conversion renders as its
//! spectral form does.
//!
//! GPU checks run when an adapter exists and are required with `SPECMAP_REQUIRE_GPU=1`.

mod common;

use specmap::colorimetry::RgbSpace;
use specmap::envmap::convert::{convert, ConvertOptions, OutputFormat};
use specmap::envmap::files::Precision;
use specmap::render::own_spectra::{load_spectral, Spectra};
use specmap::render::prepare::Prepared;
use specmap::render::{compare, cpu, env, Backdrop, Image, Lighting, Preset, Spectral};
use std::path::Path;

use common::gpu;

/// The presets whose look depends most on the light's spectrum: a thin film (its colours come
/// from interference across the spectrum) and the ColorChecker spheres (24 reflectances).
const SCENES: [(Preset, usize, usize); 2] =
    [(Preset::Ball, 40, 40), (Preset::CheckerSpheres, 60, 40)];

fn render(preset: Preset, w: usize, h: usize, l: &Lighting, gpu: bool) -> Image {
    let scene = preset.scene(w, h, "D65", Some(l.clone())).unwrap();
    let p = Prepared::new(&scene, &Spectral::default()).unwrap();
    match gpu {
        false => cpu::render(&p),
        true => self::gpu().unwrap().render(&p).unwrap().0,
    }
}

fn converted(dir: &Path, input: &str, name: &str, opts: ConvertOptions) -> std::path::PathBuf {
    let out = dir.join(name);
    convert(input, &out, &opts, &|_, _| {}).unwrap();
    out
}

#[test]
fn own_spectra_render_as_the_full_spectra_do_on_both_backends() {
    let dir = tempfile::tempdir().unwrap();
    let maps = [
        // What `specmap convert MAP` writes: the faithful method, half floats.
        converted(
            dir.path(),
            "envmaps/sunrise.exr",
            "sunrise.exr",
            ConvertOptions::faithful(),
        ),
        converted(
            dir.path(),
            "envmaps/forest.exr",
            "forest.exr",
            ConvertOptions::faithful(),
        ),
        // A foreign file: truth data of a room lit by a window and fluorescent tubes, whose
        // spectra are spiky (tools/truth_mixed.py).
        "tests/data/truth/office_mixed.spectral.exr".into(),
        // The paper's exact mode, float.
        converted(
            dir.path(),
            "envmaps/sunrise.exr",
            "sunrise-exact.exr",
            ConvertOptions {
                precision: Precision::Float,
                ..ConvertOptions::default()
            },
        ),
    ];
    for map in &maps {
        let (own, report) = load_spectral(map, Spectra::Own).unwrap();
        let (full, _) = load_spectral(map, Spectra::Full).unwrap();
        let p = report.projection.as_ref().unwrap();
        eprintln!("{}: {}", map.display(), p.summary);
        assert!(p.keeps_colour && p.k <= 32, "{p:?}");
        for (preset, w, h) in SCENES {
            let reference = render(preset, w, h, &full, false);
            let mut backends = vec![("cpu", render(preset, w, h, &own, false))];
            if gpu().is_some() {
                backends.push(("gpu", render(preset, w, h, &own, true)));
            }
            for (name, img) in backends {
                let c = compare(&reference, &img, &RgbSpace::SRGB).unwrap();
                eprintln!("  {} {name}: {c:?}", preset.name());
                assert!(
                    c.mean < 0.05,
                    "{} {name} {}: {c:?}",
                    map.display(),
                    preset.name()
                );
            }
        }
    }
}

#[test]
fn a_spectral_maps_render_does_not_depend_on_light() {
    let dir = tempfile::tempdir().unwrap();
    let map = converted(
        dir.path(),
        "envmaps/sunrise.exr",
        "s.exr",
        ConvertOptions::faithful(),
    );
    let m = map.to_str().unwrap();
    let mut images = Vec::new();
    for light in ["D65", "FL2", "A"] {
        let out = dir.path().join(format!("{light}.exr"));
        let o = out.to_str().unwrap();
        let r = common::specmap(&[
            "render",
            "--scene",
            "ball",
            "--env",
            m,
            "--light",
            light,
            "--size",
            "32x32",
            "--backend",
            "cpu",
            "-o",
            o,
        ]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        images.push(
            exr::prelude::read_first_rgba_layer_from_file(
                &out,
                |res, _| vec![[0f32; 3]; res.width() * res.height()],
                |px: &mut Vec<[f32; 3]>, p, (r, g, b, _a): (f32, f32, f32, f32)| {
                    px[p.y() * 32 + p.x()] = [r, g, b]
                },
            )
            .unwrap()
            .layer_data
            .channel_data
            .pixels,
        );
    }
    assert!(images.iter().all(|i| i == &images[0]));
    // An RGB map has no spectra: there --light is the conversion's light and does matter.
    let (d65, r) = env::load(Path::new("envmaps/sunrise.exr"), "D65").unwrap();
    let (fl2, _) = env::load(Path::new("envmaps/sunrise.exr"), "FL2").unwrap();
    assert!(r.light_used);
    let (a, b) = (
        render(Preset::Ball, 24, 24, &d65, false),
        render(Preset::Ball, 24, 24, &fl2, false),
    );
    assert!(compare(&a, &b, &RgbSpace::SRGB).unwrap().mean > 0.5);
}

#[test]
fn the_background_is_the_map_seen_from_the_camera_or_black_when_hidden() {
    // A map whose every texel's colour is its direction's: the background shows a gradient
    // across the image, and --background none is black.
    let (l, _) = env::load(Path::new("envmaps/sunrise.exr"), "D65").unwrap();
    let mut scene = Preset::Ball.scene(64, 64, "D65", Some(l)).unwrap();
    scene.objects.clear();
    let img = cpu::render(&Prepared::new(&scene, &Spectral::default()).unwrap());
    let (top, bottom) = (img.pixels[2 * 64 + 32], img.pixels[61 * 64 + 32]);
    // sunrise.exr: blue sky above, dark ground below.
    assert!(top[2] > 2.0 * bottom[2], "{top:?} {bottom:?}");
    scene.backdrop = Backdrop::Hidden;
    let img = cpu::render(&Prepared::new(&scene, &Spectral::default()).unwrap());
    assert!(img.pixels.iter().all(|p| *p == [0.0; 3]));
    scene.backdrop = Backdrop::Flat;
    let img = cpu::render(&Prepared::new(&scene, &Spectral::default()).unwrap());
    assert!(img.pixels.iter().all(|p| *p == img.pixels[0]));
}

#[test]
fn the_basis_form_renders_as_the_spectral_form_and_keeps_the_sun() {
    let dir = tempfile::tempdir().unwrap();
    for (name, base) in [
        ("faithful", ConvertOptions::faithful()),
        ("exact", ConvertOptions::default()),
    ] {
        let opts = |format| ConvertOptions {
            format,
            precision: Precision::Float,
            ..base.clone()
        };
        let sp = converted(
            dir.path(),
            "envmaps/sunrise.exr",
            &format!("{name}-s.exr"),
            opts(OutputFormat::Spectral),
        );
        let ba = converted(
            dir.path(),
            "envmaps/sunrise.exr",
            &format!("{name}-b.exr"),
            opts(OutputFormat::Basis),
        );
        let (ls, _) = load_spectral(&sp, Spectra::Full).unwrap();
        let (lb, rb) = env::load(&ba, "FL2").unwrap();
        eprintln!("{name}: {rb:?}");
        assert_eq!(rb.kind, "basis-k");
        assert!(!rb.light_used);
        let (ss, bs) = (ls.sun.expect("a sun"), lb.sun.expect("a sun"));
        assert!((ss.irradiance - bs.irradiance).abs() < 1e-3 * ss.irradiance);
        for (preset, w, h) in SCENES {
            let a = render(preset, w, h, &ls, false);
            let b = render(preset, w, h, &lb, false);
            let c = compare(&a, &b, &RgbSpace::SRGB).unwrap();
            eprintln!("  {} {name}: {c:?}", preset.name());
            assert!(c.mean < 0.01, "{name} {}: {c:?}", preset.name());
        }
    }
}

#[test]
fn a_basis_map_converted_with_sun_spd_a_is_lit_by_an_a_sun() {
    use specmap::envmap::convert::SunSpd;
    use specmap::render::LightSpectra;
    let dir = tempfile::tempdir().unwrap();
    let out = converted(
        dir.path(),
        "envmaps/sunrise.exr",
        "a.exr",
        ConvertOptions {
            format: OutputFormat::Basis,
            sun_spd: Some(SunSpd::Light("A".into())),
            ..ConvertOptions::faithful()
        },
    );
    let (l, r) = env::load(&out, "D65").unwrap();
    assert!(l.sun.is_some(), "{r:?}");
    let LightSpectra::Own { sun_spd, .. } = &l.spectra else {
        panic!("a basis map is lit by its own spectra")
    };
    // Illuminant A's shape (the table, independent of the conversion), normalised at 560 nm.
    let a = specmap::data::spectrum("A").unwrap().data;
    let at = |t: &specmap::spectrum::Tabulated, nm: f64| {
        let i = t.wavelengths_nm().iter().position(|&w| w == nm).unwrap();
        t.values()[i]
    };
    for nm in [400.0, 450.0, 500.0, 600.0, 650.0, 700.0] {
        let want = at(&a, nm) / at(&a, 560.0);
        let got = at(sun_spd, nm) / at(sun_spd, 560.0);
        assert!(
            (got - want).abs() < 2e-3 * want,
            "{nm} nm: {got} vs A's {want}"
        );
    }
}

#[test]
fn a_version_1_basis_file_is_lit_by_the_spectra_its_header_stores() {
    use exr::meta::attribute::{AttributeValue, Text};
    use specmap::render::LightSpectra;
    // A 16 x 8 lat-long of version 1 (c_R, c_G, c_B, sun; the spectra in the header), written
    // with the exr crate: made-up spectra that no light by name has.
    let (w, h) = (16, 8);
    let wl: Vec<f32> = (0..9).map(|i| 380.0 + 50.0 * i as f32).collect();
    let b: Vec<Vec<f32>> = (0..4)
        .map(|j| {
            (0..9)
                .map(|i| 0.1 + ((i * (j + 1)) % 5) as f32 * 0.2)
                .collect()
        })
        .collect();
    let floats = |v: &[f32]| AttributeValue::Custom {
        kind: Text::from("floatvector"),
        bytes: v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    };
    let mut attrs = exr::meta::header::LayerAttributes::default();
    let mut put = |k: &str, v: AttributeValue| {
        attrs.other.insert(Text::from(k), v);
    };
    put("specmap.light", AttributeValue::Text(Text::from("D65")));
    put("specmap.wavelengths", floats(&wl));
    for (j, bj) in b.iter().take(3).enumerate() {
        put(&format!("specmap.basis{j}"), floats(bj));
    }
    put("specmap.sunSPD", floats(&b[3]));
    let sun_at = 2 * w + 5;
    let mut sun = vec![0f32; w * h];
    sun[sun_at] = 40.0;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("v1.exr");
    common::write_channels_with(
        &path,
        w,
        h,
        vec![
            ("c_R", vec![0.5; w * h]),
            ("c_G", vec![0.25; w * h]),
            ("c_B", vec![0.125; w * h]),
            ("sun", sun),
        ],
        attrs,
    );
    let (l, r) = env::load(&path, "FL2").unwrap();
    assert_eq!((r.kind, r.light_used), ("basis", false));
    let LightSpectra::Own {
        spectra, sun_spd, ..
    } = &l.spectra
    else {
        panic!("{r:?}")
    };
    for (j, s) in spectra.iter().take(3).chain([sun_spd]).enumerate() {
        let want: Vec<f64> = b[j].iter().map(|&v| v as f64).collect();
        assert_eq!(s.values(), &want[..], "spectrum {j}");
    }
    // The sun: the pixel's value times its solid angle, towards its direction.
    let s = l.sun.expect("the sun channel's pixel");
    let omega = env::solid_angle(w, h, 2);
    assert!(
        (s.irradiance - 40.0 * omega).abs() < 1e-5 * s.irradiance,
        "{s:?}"
    );
    let d = env::direction(w, h, 5, 2);
    assert!((0..3).map(|k| d[k] * s.direction[k]).sum::<f64>() > 1.0 - 1e-9);
}
