//! The basis form (version 2, src/envmap/convert/basis_form.rs) holds the spectra of the spectral form of
//! the same conversion: every pixel rebuilt from the header's K spectra and its K coefficients,
//! against the spectral file's own bands.

use specmap::envmap::convert::{convert, ConvertOptions, OutputFormat};
use specmap::envmap::files::{self, AttrValue, Precision};
use std::path::Path;

/// The basis file's coefficients (per pixel) and spectra, from the file itself.
fn read_basis(path: &Path) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, Option<usize>) {
    let image = exr::prelude::read_first_flat_layer_from_file(path).unwrap();
    let layer = &image.layer_data;
    let attr = |name: &str| {
        layer
            .attributes
            .other
            .iter()
            .find(|(n, _)| **n == *name)
            .and_then(|(_, v)| files::attr_from_exr(v))
            .unwrap_or_else(|| panic!("no attribute {name}"))
    };
    let AttrValue::I32(k) = attr("specmap.basisK") else {
        panic!("specmap.basisK is not an int")
    };
    assert!(matches!(attr("specmap.basisVersion"), AttrValue::I32(2)));
    let spectra: Vec<Vec<f64>> = (0..k)
        .map(|j| match attr(&format!("specmap.basis{j:02}")) {
            AttrValue::F32Vec(v) => v.iter().map(|&x| x as f64).collect(),
            _ => panic!("basis{j:02} is not a float vector"),
        })
        .collect();
    let ev = match layer
        .attributes
        .other
        .iter()
        .find(|(n, _)| **n == *"EV")
        .and_then(|(_, v)| files::attr_from_exr(v))
    {
        Some(AttrValue::F32(e)) => e as f64,
        _ => 0.0,
    };
    let coef: Vec<Vec<f64>> = (0..k)
        .map(|j| {
            let name = format!("k{j:02}");
            let c = layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name.to_string() == name)
                .unwrap_or_else(|| panic!("no channel {name}"));
            c.sample_data
                .values_as_f32()
                .map(|v| v as f64 * ev.exp2())
                .collect()
        })
        .collect();
    let sun = match attr("specmap.basisSun") {
        AttrValue::I32(i) if i >= 0 => Some(i as usize),
        _ => None,
    };
    (coef, spectra, sun)
}

/// Per pixel `|rebuilt - bands| / |bands|` over the spectral file.
fn residuals(spectral: &Path, basis: &Path) -> Vec<f64> {
    let (coef, spectra, _) = read_basis(basis);
    let info = files::read_spectral_info(spectral).unwrap();
    let (w, n) = (info.width, info.wavelengths_nm.len());
    let mut out = vec![0.0; info.width * info.height];
    files::read_spectral_rows(spectral, |y, row| {
        let per = row.len() / w;
        for x in 0..w {
            let i = y * w + x;
            let (mut r2, mut s2) = (0.0, 0.0);
            for b in 0..n {
                let v = row[x * per + b] as f64;
                let rebuilt: f64 = (0..spectra.len()).map(|j| coef[j][i] * spectra[j][b]).sum();
                r2 += (rebuilt - v).powi(2);
                s2 += v * v;
            }
            out[i] = if s2 > 0.0 {
                (r2 / s2).sqrt()
            } else {
                r2.sqrt()
            };
        }
    })
    .unwrap();
    out
}

#[test]
fn every_pixel_of_the_basis_form_rebuilds_its_spectrum() {
    let dir = tempfile::tempdir().unwrap();
    for (name, base) in [
        ("exact", ConvertOptions::default()),
        ("faithful", ConvertOptions::faithful()),
    ] {
        let mut reports = Vec::new();
        for format in [OutputFormat::Spectral, OutputFormat::Basis] {
            let out = dir.path().join(format!("{name}-{format:?}.exr"));
            let opts = ConvertOptions {
                format,
                precision: Precision::Float,
                ..base.clone()
            };
            reports.push((
                out.clone(),
                convert("envmaps/sunrise.exr", &out, &opts, &|_, _| {}).unwrap(),
            ));
        }
        let (spectral, basis) = (&reports[0].0, &reports[1].0);
        let stats = reports[1]
            .1
            .basis
            .clone()
            .expect("the basis form's statistics");
        let (_, spectra, sun) = read_basis(basis);
        assert_eq!(spectra.len(), stats.k);
        assert!(sun.is_some(), "sunrise.exr has a sun");
        let r = residuals(spectral, basis);
        let worst = r.iter().cloned().fold(0.0, f64::max);
        let over = r.iter().filter(|&&v| v > 0.01).count();
        eprintln!(
            "{name}: K {}, worst {worst:.2e}, {over} over 1%: {stats:?}",
            stats.k
        );
        // The report says what the file holds.
        assert!(
            (worst - stats.max_residual).abs() < 1e-4 + 1e-3 * worst,
            "{worst} {stats:?}"
        );
        assert_eq!(over, stats.pixels_over_1_percent);
        if name == "exact" {
            // The paper's exact mode: three ColorChecker spectra times the light, and the sun.
            assert!(stats.k <= 5 && worst < 1e-4, "{stats:?}");
        } else {
            // The faithful method: its few hundred Bernstein and nearest spectra lie outside;
            // every other pixel is held.
            assert!(stats.k <= 32 && over * 1000 < r.len(), "{stats:?}");
        }
    }
}
