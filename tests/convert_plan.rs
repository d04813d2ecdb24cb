//! The conversion's plan is what is written: `inspect` prints the whole plan (the file's form,
//! precision, EV, compression and header attributes included), and `convert` writes exactly
//! that. The files are read back with the `exr` crate, not with specmap's reader.

use serde_json::Value;
use specmap::envmap::convert::{convert, inspect, ConvertOptions, OutputFormat};
use specmap::envmap::files::Precision;
use std::path::Path;

/// The header attributes of an OpenEXR file whose names start with `specmap.`, as the `exr`
/// crate reads them, in JSON (text as strings, float vectors as arrays).
fn specmap_attributes(path: &Path) -> serde_json::Map<String, Value> {
    use exr::meta::attribute::AttributeValue as A;
    let meta = exr::meta::MetaData::read_from_file(path, false).unwrap();
    let header = &meta.headers[0];
    let mut out = serde_json::Map::new();
    for (name, value) in header.own_attributes.other.iter() {
        let name = name.to_string();
        if !name.starts_with("specmap.") {
            continue;
        }
        let v = match value {
            A::Text(t) => Value::from(t.to_string()),
            A::I32(i) => Value::from(*i),
            A::F32(f) => Value::from(*f),
            A::F64(f) => Value::from(*f),
            A::Custom { kind, bytes } if kind == "floatvector" => Value::from(
                bytes
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect::<Vec<f32>>(),
            ),
            other => panic!("{name}: an attribute of an unexpected type {other:?}"),
        };
        out.insert(name, v);
    }
    out
}

#[test]
fn inspect_prints_the_plan_convert_writes() {
    let dir = tempfile::tempdir().unwrap();
    let input = "envmaps/sunrise.exr";
    let opts = ConvertOptions::faithful();
    let planned = serde_json::to_value(inspect(input, &opts).unwrap()).unwrap();
    let file = &planned["plan"]["file"];
    let out = dir.path().join("sunrise.spectral.exr");
    let report = convert(input, &out, &opts, &|_, _| {}).unwrap();

    // The form, precision, EV and compression the plan printed are the file's.
    assert_eq!(file["output"]["form"], "spectral", "{file}");
    let precision = &file["output"]["precision"];
    assert_eq!(precision["precision"], "half", "{precision}");
    assert_eq!(report.precision, "half");
    assert_eq!(precision["ev"].as_f64(), report.ev, "{precision}");
    assert_eq!(
        precision["below_half"].as_u64(),
        Some(report.below_half as u64)
    );
    assert_eq!(file["compression"], report.compression.as_str());
    assert_eq!(file["path"], Value::Null, "inspect writes nothing");
    // The plan prints its fit: the report's weights.
    let weights: Vec<f64> = serde_json::from_value(planned["plan"]["fit"]["weights"].clone())
        .expect("the plan's fit has weights");
    assert_eq!(weights, report.weights.to_vec());

    // Every specmap attribute the plan printed is in the file, with its value.
    let planned_attributes = file["attributes"].as_object().expect("attributes").clone();
    let written = specmap_attributes(&out);
    let planned_specmap: serde_json::Map<String, Value> = planned_attributes
        .into_iter()
        .filter(|(k, _)| k.starts_with("specmap."))
        .collect();
    assert_eq!(
        planned_specmap.keys().collect::<Vec<_>>(),
        written.keys().collect::<Vec<_>>()
    );
    for (name, value) in &planned_specmap {
        assert_eq!(value, &written[name], "{name}");
    }
}

#[test]
fn the_basis_form_keeps_the_spectral_form_s_attributes_and_no_version_1_ones() {
    let dir = tempfile::tempdir().unwrap();
    // The paper's exact mode: the mode whose version-1 sun spectrum leaked into version-2 files.
    let base = ConvertOptions {
        precision: Precision::Float,
        size: Some(32),
        ..ConvertOptions::default()
    };
    let mut headers = Vec::new();
    for format in [OutputFormat::Spectral, OutputFormat::Basis] {
        let out = dir.path().join(format!("{format:?}.exr"));
        let opts = ConvertOptions {
            format,
            ..base.clone()
        };
        convert("envmaps/sunrise.exr", &out, &opts, &|_, _| {}).unwrap();
        headers.push(specmap_attributes(&out));
    }
    let (spectral, basis) = (&headers[0], &headers[1]);
    // The fit's own names for its three reflectances stay (a filter on "specmap.basis" dropped
    // them), as does every other attribute of the spectral form.
    assert_eq!(
        basis["specmap.basis"],
        "colorchecker:red,colorchecker:green,colorchecker:blue"
    );
    for (name, value) in spectral {
        assert_eq!(basis.get(name), Some(value), "{name}");
    }
    // What is added is the basis form's own: its version, K, wavelengths, spectra and the sun's
    // index.
    let k = basis["specmap.basisK"].as_i64().unwrap();
    for name in basis.keys().filter(|n| !spectral.contains_key(*n)) {
        let own = [
            "specmap.basisVersion",
            "specmap.basisK",
            "specmap.basisSun",
            "specmap.wavelengths",
        ]
        .contains(&name.as_str())
            || (0..k).any(|j| *name == format!("specmap.basis{j:02}"));
        assert!(
            own,
            "{name} is neither the spectral form's nor the basis form's"
        );
    }
    assert!(!basis.contains_key("specmap.sunSPD"));
}
