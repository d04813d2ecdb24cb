//! Embeds every table under spectra/<kind>/*.csv in the binary, so specmap works from any folder.

use std::fmt::Write as _;
use std::path::Path;

fn main() {
    // Read at run time: env!() would bake in the checkout the build script was compiled in,
    // and cargo reuses a compiled build script across checkouts that share a target folder.
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let root = Path::new(&manifest).join("spectra");
    println!("cargo:rerun-if-changed={}", root.display());
    let mut entries = Vec::new();
    for kind in ["cmf", "illuminant", "light", "reflectance", "basis"] {
        let dir = root.join(kind);
        println!("cargo:rerun-if-changed={}", dir.display());
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.expect("readable spectra entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "csv"))
            .collect();
        files.sort();
        for path in files {
            let name = path.file_stem().unwrap().to_string_lossy().into_owned();
            entries.push((kind, name, path));
        }
    }
    let mut code = String::from("pub(crate) static BUILTIN: &[(&str, &str, &str)] = &[\n");
    for (kind, name, path) in &entries {
        writeln!(
            code,
            "    ({kind:?}, {name:?}, include_str!({:?})),",
            path.display().to_string()
        )
        .unwrap();
    }
    code.push_str("];\n");
    let out = Path::new(&std::env::var("OUT_DIR").unwrap()).join("builtin_tables.rs");
    std::fs::write(out, code).unwrap();
}
