//! Writes a small synthetic spectral OpenEXR (Fichet 2021 layout) with known values, for the interop tests.
//!
//! `cargo run --example write_spectral -- OUT.exr [half|float] [none|rle|zip|zips|piz|pxr24|b44|b44a]`
//!
//! `cargo run --example write_spectral -- --rgb-sums IN` prints `width height sumR sumG sumB`
//! of `read_rgb(IN)` instead (the interop test compares it with OpenEXR's Python binding).
//!
//! Pixel (x, y), band k (wavelengths 400, 450, ..., 700 nm, plus 382.5 nm as band 0):
//! value = 0.5 (x + 1) + 0.25 y + 0.125 k; preview R = x, G = y, B = 1. All exact in half.

use specmap::envmap::files::{
    AttrValue, ChannelSet, Compression, EnvmapAttr, Precision, SpectralLayout, SpectralWriter,
};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--rgb-sums") {
        let path = PathBuf::from(args.get(1).ok_or("--rgb-sums needs a file")?);
        let input = specmap::envmap::files::read_rgb(&path, None)?;
        let mut sums = [0.0f64; 3];
        for p in &input.image.pixels {
            for (s, v) in sums.iter_mut().zip(p) {
                *s += *v as f64;
            }
        }
        let img = &input.image;
        println!(
            "{} {} {:.17e} {:.17e} {:.17e}",
            img.width, img.height, sums[0], sums[1], sums[2]
        );
        return Ok(());
    }
    let out = PathBuf::from(
        args.first()
            .ok_or("usage: write_spectral OUT.exr [half|float] [compression]")?,
    );
    let precision = match args.get(1).map(String::as_str) {
        None | Some("half") => Precision::Half,
        Some("float") => Precision::Float,
        Some(p) => return Err(format!("unknown precision {p}").into()),
    };
    let compression = match args.get(2).map(String::as_str) {
        None | Some("zip") => Compression::Zip,
        Some("none") => Compression::None,
        Some("rle") => Compression::Rle,
        Some("zips") => Compression::Zips,
        Some("piz") => Compression::Piz,
        Some("pxr24") => Compression::Pxr24,
        Some("b44") => Compression::B44,
        Some("b44a") => Compression::B44a,
        Some(c) => return Err(format!("unknown compression {c}").into()),
    };
    let mut wavelengths = vec![382.5];
    wavelengths.extend((0..7).map(|i| 400.0 + 50.0 * i as f64));
    let (width, height) = (8usize, 5usize);
    let layout = SpectralLayout {
        width,
        height,
        channels: ChannelSet::Spectral {
            wavelengths_nm: wavelengths.clone(),
            preview_rgb: true,
        },
        precision,
        compression,
        envmap: Some(EnvmapAttr::LatLong),
        ev: None,
        zip_level: specmap::envmap::files::ZIP_DEFAULT_LEVEL,
        unscaled: Vec::new(),
        attributes: vec![
            ("mainLight".into(), AttrValue::Text("D65".into())),
            ("fitMode".into(), AttrValue::Text("exact".into())),
            ("fitScale".into(), AttrValue::F64(1.5)),
            ("fitWeights".into(), AttrValue::F32Vec(vec![0.25, 0.5, 2.0])),
        ],
    };
    let mut writer = SpectralWriter::create(&out, layout)?;
    for y in 0..height {
        let mut row = Vec::new();
        for x in 0..width {
            for k in 0..wavelengths.len() {
                row.push(0.5 * (x as f32 + 1.0) + 0.25 * y as f32 + 0.125 * k as f32);
            }
            row.extend([x as f32, y as f32, 1.0]);
        }
        writer.write_rows(y, &row)?;
    }
    let bytes = writer.finish()?;
    println!("{} {bytes} bytes", out.display());
    Ok(())
}
