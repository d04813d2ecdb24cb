//! EXR/HDR input and streaming spectral EXR output: round trips checked with exr's own reader, bad input.

mod common;

use common::write_channels;
use exr::prelude::{
    f16, read_all_flat_layers_from_file, AnyChannel, AnyChannels, Encoding, FlatSamples, Image,
    Layer, LayerAttributes, SmallVec, WritableImage,
};
use specmap::envmap::files::{
    read_faces, read_rgb, read_spectral_info, read_spectral_rows, spectral_channel_name, AttrValue,
    ChannelSet, Compression, EnvmapAttr, Precision, SpectralLayout, SpectralWriter, FACE_NAMES,
    ZIP_DEFAULT_LEVEL, ZIP_MAX_LEVEL,
};
use specmap::envmap::RgbImage;
use std::path::{Path, PathBuf};

const ALL_COMPRESSIONS: [Compression; 8] = [
    Compression::None,
    Compression::Rle,
    Compression::Zip,
    Compression::Zips,
    Compression::Piz,
    Compression::Pxr24,
    Compression::B44,
    Compression::B44a,
];

fn envmap(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("envmaps")
        .join(name)
}

fn wavelengths() -> Vec<f64> {
    vec![380.0, 382.5, 500.0, 555.25, 700.0, 1000.0]
}

/// A smooth HDR test value for pixel (x, y), channel c.
fn value(x: usize, y: usize, c: usize) -> f32 {
    let t = (x as f32 * 0.37 + y as f32 * 0.21 + c as f32 * 0.9).sin();
    (1.0 + t) * 10f32.powf(c as f32 * 0.3 - 1.0)
}

fn layout(
    w: usize,
    h: usize,
    channels: ChannelSet,
    p: Precision,
    c: Compression,
) -> SpectralLayout {
    SpectralLayout {
        width: w,
        height: h,
        channels,
        precision: p,
        compression: c,
        envmap: None,
        ev: None,
        attributes: vec![],
        zip_level: ZIP_DEFAULT_LEVEL,
        unscaled: Vec::new(),
    }
}

/// Writes the test image in uneven row batches (1, 2, 3, ... rows at a time).
fn write_image(dest: &Path, layout: SpectralLayout) -> u64 {
    let (w, h) = (layout.width, layout.height);
    let n = layout.channels.names().len();
    let mut writer = SpectralWriter::create(dest, layout).unwrap();
    let mut y = 0;
    let mut batch = 1;
    while y < h {
        let rows = batch.min(h - y);
        let mut data = Vec::new();
        for yy in y..y + rows {
            for x in 0..w {
                for c in 0..n {
                    data.push(value(x, yy, c));
                }
            }
        }
        writer.write_rows(y, &data).unwrap();
        y += rows;
        batch += 1;
    }
    writer.finish().unwrap()
}

/// The allowed error on channel `c` of value `v`: half rounding, and for the lossy methods a
/// relative error (PXR24 on float: 15-bit mantissa) or, for B44 (4x4 blocks quantized in a
/// perceptual space), 10 % plus 2 % of the channel's range.
fn tolerance(p: Precision, c: Compression, ch: usize, v: f32) -> f32 {
    let stored = match p {
        Precision::Half => f16::from_f32(v).to_f32(),
        Precision::Float => v,
    };
    let rel = match (p, c) {
        (Precision::Half, Compression::B44 | Compression::B44a) => {
            return 0.1 * v.abs() + 0.04 * 10f32.powf(ch as f32 * 0.3 - 1.0);
        }
        (Precision::Float, Compression::Pxr24) => 1e-4,
        _ => 0.0,
    };
    (stored - v).abs() + rel * v.abs() + 1e-7
}

#[test]
fn spectral_round_trip_every_compression_and_precision() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (37, 41);
    let wl = wavelengths();
    for p in [Precision::Half, Precision::Float] {
        for c in ALL_COMPRESSIONS {
            let path = dir.path().join(format!("s-{p:?}-{c:?}.exr"));
            let channels = ChannelSet::Spectral {
                wavelengths_nm: wl.clone(),
                preview_rgb: true,
            };
            let names = channels.names();
            let bytes = write_image(&path, layout(w, h, channels, p, c));
            assert_eq!(bytes, std::fs::metadata(&path).unwrap().len());

            // exr's own reader
            let image = read_all_flat_layers_from_file(&path).unwrap();
            let layer = &image.layer_data[0];
            assert_eq!(layer.size.0, w);
            assert_eq!(layer.size.1, h);
            assert_eq!(layer.encoding.compression, exr_compression(c));
            let attrs = &layer.attributes.other;
            let text = |k: &str| match attrs.get(&exr::prelude::Text::from(k)) {
                Some(exr::meta::attribute::AttributeValue::Text(t)) => t.to_string(),
                other => panic!("{k}: {other:?}"),
            };
            assert_eq!(text("spectralLayoutVersion"), "1.0");
            assert_eq!(text("emissiveUnits"), "W.m^-2.sr^-1");
            let mut found: Vec<String> = layer
                .channel_data
                .list
                .iter()
                .map(|ch| ch.name.to_string())
                .collect();
            let mut expected = names.clone();
            expected.sort();
            found.sort();
            assert_eq!(found, expected, "{p:?} {c:?}");
            for ch in &layer.channel_data.list {
                let ci = names
                    .iter()
                    .position(|n| *n == ch.name.to_string())
                    .unwrap();
                for (i, v) in ch.sample_data.values_as_f32().enumerate() {
                    let want = value(i % w, i / w, ci);
                    assert!(
                        (v - want).abs() <= tolerance(p, c, ci, want),
                        "{p:?} {c:?} {} pixel {i}: {v} vs {want}",
                        ch.name
                    );
                }
            }

            // our streaming reader: bands sorted by wavelength, then RGB
            let mut rows_seen = 0;
            let info = read_spectral_rows(&path, |y, row| {
                assert_eq!(y, rows_seen);
                rows_seen += 1;
                assert_eq!(row.len(), w * names.len());
                for x in 0..w {
                    for c2 in 0..names.len() {
                        let want = value(x, y, c2);
                        let v = row[x * names.len() + c2];
                        assert!((v - want).abs() <= tolerance(p, c, c2, want));
                    }
                }
            })
            .unwrap();
            assert_eq!(rows_seen, h);
            assert_eq!(info.wavelengths_nm, wl);
            assert!(info.has_rgb);
            assert_eq!((info.width, info.height), (w, h));
        }
    }
}

#[test]
fn every_zip_level_reads_back_and_higher_levels_are_smaller() {
    // Level 0 stores (each block raw, as OpenEXR does when compression does not help).
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40, 37);
    let set = || ChannelSet::Spectral {
        wavelengths_nm: wavelengths(),
        preview_rgb: true,
    };
    let mut sizes = vec![];
    for (c, level) in [
        (Compression::Zip, 0),
        (Compression::Zip, 1),
        (Compression::Zip, ZIP_DEFAULT_LEVEL),
        (Compression::Zip, ZIP_MAX_LEVEL),
        (Compression::Zips, 1),
    ] {
        let path = dir.path().join(format!("z{c:?}{level}.exr"));
        let mut l = layout(w, h, set(), Precision::Float, c);
        l.zip_level = level;
        sizes.push(write_image(&path, l));
        // The exr crate's reader (zune-inflate) gets every value back exactly.
        let image = read_all_flat_layers_from_file(&path).unwrap();
        for (k, ch) in image.layer_data[0].channel_data.list.iter().enumerate() {
            let FlatSamples::F32(v) = &ch.sample_data else {
                panic!("{k}: not f32")
            };
            let name = ch.name.to_string();
            let c = set().names().iter().position(|n| *n == name).unwrap();
            for (i, got) in v.iter().enumerate() {
                assert_eq!(
                    *got,
                    value(i % w, i / w, c),
                    "level {level}, {name}, sample {i}"
                );
            }
        }
    }
    assert!(
        sizes[0] > sizes[1] && sizes[1] >= sizes[2] && sizes[2] >= sizes[3],
        "{sizes:?}"
    );
}

fn exr_compression(c: Compression) -> exr::compression::Compression {
    use exr::compression::Compression as E;
    match c {
        Compression::None => E::Uncompressed,
        Compression::Rle => E::RLE,
        Compression::Zip => E::ZIP16,
        Compression::Zips => E::ZIP1,
        Compression::Piz => E::PIZ,
        Compression::Pxr24 => E::PXR24,
        Compression::B44 => E::B44,
        Compression::B44a => E::B44A,
    }
}

#[test]
fn fichet_channel_names() {
    assert_eq!(spectral_channel_name(550.0), "S0.550,000000nm");
    assert_eq!(spectral_channel_name(382.5), "S0.382,500000nm");
    let set = ChannelSet::Spectral {
        wavelengths_nm: vec![400.0, 700.0],
        preview_rgb: true,
    };
    assert_eq!(
        set.names(),
        ["S0.400,000000nm", "S0.700,000000nm", "R", "G", "B"]
    );
}

#[test]
fn custom_channels_round_trip_with_attributes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("basis.exr");
    let names: Vec<String> = ["c_R", "c_G", "c_B", "sun"].map(String::from).to_vec();
    for c in ALL_COMPRESSIONS {
        let mut l = layout(
            19,
            70,
            ChannelSet::Custom(names.clone()),
            Precision::Float,
            c,
        );
        l.envmap = Some(EnvmapAttr::Cube);
        l.attributes = vec![
            (
                "basisWavelengths".into(),
                AttrValue::F32Vec(vec![400.0, 500.0, 600.0]),
            ),
            ("mainLight".into(), AttrValue::Text("D65".into())),
            ("fitScale".into(), AttrValue::F64(0.125)),
        ];
        write_image(&path, l);
        let image = read_all_flat_layers_from_file(&path).unwrap();
        let layer = &image.layer_data[0];
        assert_eq!(
            layer.attributes.environment_map,
            Some(exr::meta::attribute::EnvironmentMap::Cube)
        );
        assert!(!layer
            .attributes
            .other
            .contains_key(&exr::prelude::Text::from("spectralLayoutVersion")));
        for ch in &layer.channel_data.list {
            let ci = names
                .iter()
                .position(|n| *n == ch.name.to_string())
                .unwrap();
            for (i, v) in ch.sample_data.values_as_f32().enumerate() {
                let want = value(i % 19, i / 19, ci);
                assert!((v - want).abs() <= tolerance(Precision::Float, c, ci, want));
            }
        }
    }
    // our reader refuses a file without spectral bands, naming its channels
    let err = read_spectral_rows(&path, |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("c_R") && err.contains("sun"), "{err}");
    // and read_rgb cannot find R, G, B
    let err = read_rgb(&path, None).unwrap_err().to_string();
    assert!(err.contains("basis.exr") && err.contains("c_G"), "{err}");
}

#[test]
fn attributes_and_envmap_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("attrs.exr");
    let mut l = layout(
        4,
        3,
        ChannelSet::Spectral {
            wavelengths_nm: vec![450.0, 550.0],
            preview_rgb: false,
        },
        Precision::Half,
        Compression::Zip,
    );
    l.envmap = Some(EnvmapAttr::LatLong);
    l.attributes = vec![
        ("w".into(), AttrValue::F32Vec(vec![1.0, 2.5])),
        ("mode".into(), AttrValue::Text("exact".into())),
        ("k".into(), AttrValue::F64(0.1)),
        ("n".into(), AttrValue::I32(7)),
    ];
    write_image(&path, l);
    let info = read_spectral_rows(&path, |_, row| assert_eq!(row.len(), 8)).unwrap();
    assert_eq!(read_spectral_info(&path).unwrap(), info);
    assert!(!info.has_rgb);
    assert_eq!(info.envmap, Some(EnvmapAttr::LatLong));
    let get = |k: &str| {
        info.attributes
            .iter()
            .find(|a| a.0 == k)
            .map(|a| a.1.clone())
    };
    assert_eq!(get("w"), Some(AttrValue::F32Vec(vec![1.0, 2.5])));
    assert_eq!(get("mode"), Some(AttrValue::Text("exact".into())));
    assert_eq!(get("k"), Some(AttrValue::F64(0.1)));
    assert_eq!(get("n"), Some(AttrValue::I32(7)));
    assert_eq!(
        get("spectralLayoutVersion"),
        Some(AttrValue::Text("1.0".into()))
    );
}

#[test]
fn half_overflow_is_an_error_naming_pixel_and_value() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sun.exr");
    let set = ChannelSet::Spectral {
        wavelengths_nm: vec![500.0, 600.0],
        preview_rgb: true,
    };
    let mut w = SpectralWriter::create(&path, layout(3, 2, set, Precision::Half, Compression::Zip))
        .unwrap();
    let mut row = vec![1.0f32; 15];
    row[2 * 5 + 1] = 70000.0; // pixel x=2, band 600 nm
    let err = w.write_rows(0, &row).unwrap_err().to_string();
    assert!(
        err.contains("(2, 0)") && err.contains("S0.600,000000nm") && err.contains("70000"),
        "{err}"
    );
    assert!(err.contains("65504"), "{err}");
    drop(w);
    assert!(!path.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "temporary file left"
    );
}

#[test]
fn ev_scale_keeps_a_bright_sun_in_half() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ev.exr");
    let set = ChannelSet::Spectral {
        wavelengths_nm: vec![500.0],
        preview_rgb: false,
    };
    let mut l = layout(2, 1, set, Precision::Half, Compression::Piz);
    l.ev = Some(4.0);
    let mut w = SpectralWriter::create(&path, l).unwrap();
    w.write_rows(0, &[1.0e6, 0.5]).unwrap();
    w.finish().unwrap();
    let mut got = vec![];
    let info = read_spectral_rows(&path, |_, row| got.extend_from_slice(row)).unwrap();
    assert_eq!(info.ev, Some(4.0));
    assert!((got[0] - 1.0e6).abs() / 1.0e6 < 1e-3, "{got:?}");
    assert_eq!(got[1], 0.5);
    // exr's reader sees the stored (scaled) values and the EV attribute
    let image = read_all_flat_layers_from_file(&path).unwrap();
    let stored: Vec<f32> = image.layer_data[0].channel_data.list[0]
        .sample_data
        .values_as_f32()
        .collect();
    assert!((stored[0] - 62500.0).abs() < 64.0, "{stored:?}");
}

#[test]
fn writer_misuse_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.exr");
    let set = || ChannelSet::Custom(vec!["a".into(), "b".into()]);
    let mut w = SpectralWriter::create(
        &path,
        layout(2, 4, set(), Precision::Float, Compression::Zip),
    )
    .unwrap();
    assert!(w
        .write_rows(1, &[0.0; 4])
        .unwrap_err()
        .to_string()
        .contains("expected row 0"));
    assert!(w
        .write_rows(0, &[0.0; 3])
        .unwrap_err()
        .to_string()
        .contains("whole number"));
    assert!(w
        .write_rows(0, &[f32::NAN; 4])
        .unwrap_err()
        .to_string()
        .contains("not finite"));
    assert!(w
        .write_rows(0, &[0.0; 20])
        .unwrap_err()
        .to_string()
        .contains("exceed"));
    w.write_rows(0, &[0.0; 4]).unwrap();
    let err = w.finish().unwrap_err().to_string();
    assert!(err.contains("1 of 4 rows"), "{err}");
    assert!(!path.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "temporary file left"
    );

    let dup = ChannelSet::Custom(vec!["a".into(), "a".into()]);
    let err = SpectralWriter::create(&path, layout(2, 2, dup, Precision::Half, Compression::Zip))
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("appears twice"), "{err}");
    let mut l = layout(2, 2, set(), Precision::Half, Compression::Zip);
    l.attributes = vec![("EV".into(), AttrValue::F64(1.0))];
    assert!(SpectralWriter::create(&path, l).is_err());
    let mut l = layout(2, 2, set(), Precision::Half, Compression::Zip);
    l.attributes = vec![("owner".into(), AttrValue::Text("x".into()))];
    let err = SpectralWriter::create(&path, l).err().unwrap().to_string();
    assert!(err.contains("owner"), "{err}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

// ---------------------------------------------------------------------------------------------
// Input

fn sums(img: &RgbImage) -> [f64; 3] {
    let mut s = [0.0f64; 3];
    for p in &img.pixels {
        for k in 0..3 {
            s[k] += p[k] as f64;
        }
    }
    s
}

#[test]
fn sample_maps_read_like_exr_reader() {
    for name in ["forest.exr", "sunrise.exr"] {
        let path = envmap(name);
        let input = read_rgb(&path, None).unwrap();
        assert_eq!(
            (input.image.width, input.image.height),
            (1024, 512),
            "{name}"
        );
        assert!(
            input.description.starts_with("OpenEXR, "),
            "{}",
            input.description
        );
        let image = read_all_flat_layers_from_file(&path).unwrap();
        let layer = &image.layer_data[0];
        let mut want = [0.0f64; 3];
        for (k, n) in ["R", "G", "B"].iter().enumerate() {
            let ch = layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name.to_string() == *n)
                .unwrap();
            want[k] = ch.sample_data.values_as_f32().map(|v| v as f64).sum();
        }
        assert_eq!(sums(&input.image), want, "{name}");
    }
}

#[test]
fn layers_luminance_and_case() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("layers.exr");
    let ramp = |o: f32| (0..6).map(|i| i as f32 + o).collect::<Vec<f32>>();
    write_channels(
        &p,
        3,
        2,
        vec![
            ("diffuse.R", ramp(0.0)),
            ("diffuse.G", ramp(10.0)),
            ("diffuse.B", ramp(20.0)),
            ("r", ramp(100.0)),
            ("g", ramp(200.0)),
            ("b", ramp(300.0)),
        ],
    );
    let base = read_rgb(&p, None).unwrap();
    assert_eq!(base.image.get(1, 1), [104.0, 204.0, 304.0]);
    let diffuse = read_rgb(&p, Some("Diffuse")).unwrap();
    assert_eq!(diffuse.image.get(2, 0), [2.0, 12.0, 22.0]);
    assert!(
        diffuse.description.contains("diffuse.R"),
        "{}",
        diffuse.description
    );
    let err = read_rgb(&p, Some("specular")).unwrap_err().to_string();
    assert!(
        err.contains("layers.exr") && err.contains("specular.R") && err.contains("diffuse.G"),
        "{err}"
    );

    let y = dir.path().join("y.exr");
    write_channels(&y, 3, 2, vec![("Y", ramp(0.5))]);
    let grey = read_rgb(&y, None).unwrap();
    assert_eq!(grey.image.get(0, 1), [3.5, 3.5, 3.5]);
    assert!(grey.description.contains("grey"), "{}", grey.description);

    let a = dir.path().join("alpha-only.exr");
    write_channels(&a, 3, 2, vec![("A", ramp(0.0)), ("Z", ramp(0.0))]);
    let err = read_rgb(&a, None).unwrap_err().to_string();
    assert!(
        err.contains("alpha-only.exr") && err.contains("A, Z"),
        "{err}"
    );
}

#[test]
fn radiance_hdr_by_magic_not_extension() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("map.exr"); // wrong extension on purpose
    let pixels: Vec<image::Rgb<f32>> = (0..8).map(|i| image::Rgb([i as f32, 0.5, 2.0])).collect();
    let file = std::fs::File::create(&p).unwrap();
    image::codecs::hdr::HdrEncoder::new(file)
        .encode(&pixels, 4, 2)
        .unwrap();
    let input = read_rgb(&p, None).unwrap();
    assert_eq!((input.image.width, input.image.height), (4, 2));
    assert_eq!(input.image.get(3, 1), [7.0, 0.5, 2.0]);
    assert!(input.description.contains("Radiance"));
    assert_eq!(input.envmap, None);
}

#[test]
fn bad_input_has_clear_messages() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.exr");
    let err = read_rgb(&missing, None).unwrap_err().to_string();
    assert!(err.contains("nope.exr"), "{err}");

    let text = dir.path().join("notes.exr");
    std::fs::write(&text, "hello, not an image").unwrap();
    let err = read_rgb(&text, None).unwrap_err().to_string();
    assert!(
        err.contains("notes.exr") && err.contains("not an OpenEXR"),
        "{err}"
    );

    let empty = dir.path().join("empty.hdr");
    std::fs::write(&empty, "").unwrap();
    assert!(read_rgb(&empty, None)
        .unwrap_err()
        .to_string()
        .contains("empty.hdr"));

    let original = std::fs::read(envmap("forest.exr")).unwrap();
    for keep in [8, 200, original.len() / 2, original.len() - 100] {
        let t = dir.path().join(format!("truncated-{keep}.exr"));
        std::fs::write(&t, &original[..keep]).unwrap();
        let err = read_rgb(&t, None).unwrap_err().to_string();
        assert!(
            err.contains(&format!("truncated-{keep}.exr")),
            "{keep}: {err}"
        );
    }
    // flipped bytes in the header, in the offset table, in the pixel data
    let header_end = original.windows(2).position(|w| w == [0, 0]).unwrap_or(100);
    for at in [
        4,
        20,
        header_end / 2,
        original.len() / 3,
        original.len() / 2,
    ] {
        let mut bytes = original.clone();
        for b in &mut bytes[at..(at + 16).min(original.len())] {
            *b ^= 0xA5;
        }
        let c = dir.path().join(format!("corrupt-{at}.exr"));
        std::fs::write(&c, &bytes).unwrap();
        match read_rgb(&c, None) {
            Err(e) => assert!(e.to_string().contains(&format!("corrupt-{at}.exr")), "{e}"),
            // flipped bits inside compressed pixels may still decode; they must not panic
            Ok(img) => assert_eq!(img.image.pixels.len(), 1024 * 512),
        }
    }
}

#[test]
fn six_face_files() {
    let dir = tempfile::tempdir().unwrap();
    for (i, face) in FACE_NAMES.iter().enumerate() {
        let name = if i == 3 {
            "sky_-y.exr".to_string()
        } else {
            format!("sky_{face}.exr")
        };
        write_channels(
            &dir.path().join(name),
            2,
            2,
            vec![
                ("R", vec![i as f32; 4]),
                ("G", vec![0.0; 4]),
                ("B", vec![1.0; 4]),
            ],
        );
    }
    let pattern = dir.path().join("sky_{face}.exr");
    let faces = read_faces(pattern.to_str().unwrap(), None).unwrap();
    for (i, f) in faces.iter().enumerate() {
        assert_eq!(f.get(1, 1), [i as f32, 0.0, 1.0]);
    }
    std::fs::remove_file(dir.path().join("sky_pz.exr")).unwrap();
    let err = read_faces(pattern.to_str().unwrap(), None)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("sky_pz.exr") && err.contains("sky_+z.exr"),
        "{err}"
    );
    assert!(read_faces("no-placeholder.exr", None).is_err());
}

#[test]
fn multi_part_uses_the_first_part_with_rgb_or_the_named_one() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("parts.exr");
    let part = |name: &str, chans: Vec<(&str, f32)>| {
        let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = chans
            .into_iter()
            .map(|(n, v)| AnyChannel::new(n, FlatSamples::F32(vec![v; 4])))
            .collect();
        Layer::new(
            (2, 2),
            LayerAttributes::named(name),
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(list),
        )
    };
    let layers: SmallVec<[_; 2]> = SmallVec::from_vec(vec![
        part("depth", vec![("Z", 9.0)]),
        part("beauty", vec![("R", 1.0), ("G", 2.0), ("B", 3.0)]),
        part("diffuse", vec![("R", 4.0), ("G", 5.0), ("B", 6.0)]),
    ]);
    Image::from_layers(
        exr::prelude::ImageAttributes::new(exr::prelude::IntegerBounds::from_dimensions((2, 2))),
        layers,
    )
    .write()
    .to_file(&p)
    .unwrap();
    let first = read_rgb(&p, None).unwrap();
    assert_eq!(first.image.get(0, 0), [1.0, 2.0, 3.0]);
    assert!(
        first.description.contains("part 1 of 3"),
        "{}",
        first.description
    );
    let named = read_rgb(&p, Some("DIFFUSE")).unwrap();
    assert_eq!(named.image.get(1, 1), [4.0, 5.0, 6.0]);
    let err = read_rgb(&p, Some("specular")).unwrap_err().to_string();
    assert!(err.contains("part 0: Z"), "{err}");
}

#[test]
fn envmap_attribute_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("cube.exr");
    let rgb = ChannelSet::Custom(vec!["R".into(), "G".into(), "B".into()]);
    let mut l = layout(4, 24, rgb, Precision::Half, Compression::Piz);
    l.envmap = Some(EnvmapAttr::Cube);
    write_image(&p, l);
    let input = read_rgb(&p, None).unwrap();
    assert_eq!(input.envmap, Some(EnvmapAttr::Cube));
    assert_eq!((input.image.width, input.image.height), (4, 24));
    assert_eq!(
        input.image.get(3, 5)[1],
        f16::from_f32(value(3, 5, 1)).to_f32()
    );
    assert_eq!(input.description, "OpenEXR, PIZ, half, channels R,G,B");
    let plain = read_rgb(&envmap("forest.exr"), None).unwrap();
    assert_eq!(plain.envmap, None);
}

/// Not a timed test: `cargo test --release --test files -- --ignored --nocapture` under
/// `/usr/bin/time -v` shows the writer's resident memory on an 8192x4096, 81-band half image.
#[test]
#[ignore]
fn stream_a_large_image() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.exr");
    let (w, h) = (8192, 4096);
    let wl: Vec<f64> = (0..81).map(|i| 380.0 + 5.0 * i as f64).collect();
    let set = ChannelSet::Spectral {
        wavelengths_nm: wl,
        preview_rgb: true,
    };
    let n = set.names().len();
    let start = std::time::Instant::now();
    let mut writer =
        SpectralWriter::create(&path, layout(w, h, set, Precision::Half, Compression::Zip))
            .unwrap();
    let mut rows = vec![0f32; 16 * w * n];
    for y0 in (0..h).step_by(16) {
        for (i, v) in rows.iter_mut().enumerate() {
            *v = ((i + y0 * w * n) % 977) as f32 * 0.01;
        }
        writer.write_rows(y0, &rows).unwrap();
    }
    let bytes = writer.finish().unwrap();
    eprintln!("{bytes} bytes in {:.1} s", start.elapsed().as_secs_f64());
    let start = std::time::Instant::now();
    let mut count = 0;
    let info = read_spectral_rows(&path, |y, row| {
        assert_eq!(y, count);
        assert_eq!(row.len(), w * n);
        count += 1;
    })
    .unwrap();
    assert_eq!((count, info.wavelengths_nm.len()), (h, 81));
    eprintln!("read back in {:.1} s", start.elapsed().as_secs_f64());
}

#[test]
fn tiled_spectral_files_read_like_scan_lines() {
    // Spectral EXRs from other tools may be tiled: written here by the exr crate with tiles that
    // do not divide the image (partial tiles at the right and bottom), in no particular order.
    use exr::prelude::{Blocks, LineOrder, Vec2};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tiled.exr");
    let (w, h) = (70, 45);
    let wl = wavelengths();
    let mut channels: Vec<(String, Vec<f32>)> = wl
        .iter()
        .enumerate()
        .map(|(c, &l)| {
            let v = (0..w * h).map(|i| value(i % w, i / w, c)).collect();
            (spectral_channel_name(l), v)
        })
        .collect();
    for (k, name) in ["R", "G", "B"].iter().enumerate() {
        channels.push((
            name.to_string(),
            (0..w * h).map(|i| (i * 3 + k) as f32).collect(),
        ));
    }
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .into_iter()
        .map(|(n, v)| AnyChannel::new(n.as_str(), FlatSamples::F32(v)))
        .collect();
    let encoding = Encoding {
        compression: exr::compression::Compression::ZIP16,
        blocks: Blocks::Tiles(Vec2(16, 16)),
        line_order: LineOrder::Unspecified,
    };
    let mut attrs = LayerAttributes::default();
    attrs.other.insert(
        "spectralLayoutVersion".into(),
        exr::meta::attribute::AttributeValue::Text("1.0".into()),
    );
    let layer = Layer::new((w, h), attrs, encoding, AnyChannels::sort(list));
    Image::from_layer(layer).write().to_file(&path).unwrap();

    let mut seen = vec![false; h];
    let mut next = 0;
    let info = read_spectral_rows(&path, |y, row| {
        assert_eq!(y, next, "rows in order");
        next += 1;
        seen[y] = true;
        let per_pixel = wl.len() + 3;
        assert_eq!(row.len(), w * per_pixel);
        for x in 0..w {
            for c in 0..wl.len() {
                assert_eq!(row[x * per_pixel + c], value(x, y, c), "({x},{y}) band {c}");
            }
            for k in 0..3 {
                assert_eq!(
                    row[x * per_pixel + wl.len() + k],
                    ((y * w + x) * 3 + k) as f32
                );
            }
        }
    })
    .unwrap();
    assert!(seen.iter().all(|&s| s));
    assert_eq!((info.width, info.height), (w, h));
}

#[test]
fn read_errors_have_kinds_a_caller_can_match() {
    use specmap::Error;
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.exr");
    assert!(matches!(
        specmap::envmap::files::read_rgb(&missing, None),
        Err(Error::Io { .. })
    ));
    let text = dir.path().join("text.exr");
    std::fs::write(&text, "R,G,B\n1,2,3\n").unwrap();
    assert!(matches!(
        specmap::envmap::files::read_rgb(&text, None),
        Err(Error::Parse { .. })
    ));
    let bytes = std::fs::read("envmaps/sunrise.exr").unwrap();
    let cut = dir.path().join("cut.exr");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    match specmap::envmap::files::read_rgb(&cut, None) {
        Err(Error::Parse { file, message, .. }) => {
            assert_eq!(file, cut);
            assert!(
                message.contains("truncated") || message.contains("corrupt"),
                "{message}"
            );
        }
        other => panic!("a truncated file is a Parse error, not {other:?}"),
    }
}
