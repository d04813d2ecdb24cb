//! What a batch compares to decide that an output is up to date: a hash of the conversion's
//! settings and a fingerprint of its input (size, modification time, BLAKE3 of the contents).

use crate::envmap::convert::{input_files, ConvertOptions};
use crate::error::{Error, Result};
use std::path::Path;

/// A map's identity: its size and contents (BLAKE3), and the modification time that lets a
/// later run trust an unchanged file without reading it (as make and git's index do).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Fingerprint {
    /// The file's size in bytes.
    pub bytes: u64,
    /// Nanoseconds since the Unix epoch (None where the file system keeps no time).
    pub modified_ns: Option<i64>,
    /// BLAKE3 hash of the contents, in lowercase hex (64 digits).
    pub blake3: String,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn modified_ns(m: &std::fs::Metadata) -> Option<i64> {
    let t = m.modified().ok()?;
    let d = t.duration_since(std::time::UNIX_EPOCH).ok()?;
    i64::try_from(d.as_nanos()).ok()
}

fn blake3_of(path: &Path) -> Result<String> {
    let mut h = blake3::Hasher::new();
    h.update_reader(std::fs::File::open(path).map_err(io(path))?)
        .map_err(io(path))?;
    Ok(h.finalize().to_hex().to_string())
}

impl Fingerprint {
    /// Reads the file.
    pub fn of(path: &Path) -> Result<Fingerprint> {
        let m = std::fs::metadata(path).map_err(io(path))?;
        Ok(Fingerprint {
            bytes: m.len(),
            modified_ns: modified_ns(&m),
            blake3: blake3_of(path)?,
        })
    }

    /// Whether `path` still holds what was fingerprinted: a different size is a change; the same
    /// size and modification time are taken as the same file without reading it; otherwise
    /// (a copy, a touched file) the contents decide.
    pub fn matches(&self, path: &Path) -> Result<bool> {
        let m = std::fs::metadata(path).map_err(io(path))?;
        if m.len() != self.bytes {
            return Ok(false);
        }
        if self.modified_ns.is_some() && modified_ns(&m) == self.modified_ns {
            return Ok(true);
        }
        Ok(blake3_of(path)? == self.blake3)
    }
}

/// A short hash of everything that decides a conversion's output: every option (printed in
/// full, so an option added later takes part without being listed here), the contents of the
/// light files they name, and specmap's version.
pub fn settings_hash(opts: &ConvertOptions) -> Result<String> {
    let mut h = blake3::Hasher::new();
    h.update(format!("specmap {}\n{opts:?}\n", env!("CARGO_PKG_VERSION")).as_bytes());
    for file in input_files("", opts) {
        h.update(file.display().to_string().as_bytes());
        h.update(blake3_of(&file)?.as_bytes());
    }
    Ok(h.finalize().to_hex()[..16].to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envmap::convert::LightSpec;

    #[test]
    fn the_settings_hash_follows_every_option_and_the_lights_contents() {
        let base = settings_hash(&ConvertOptions::faithful()).unwrap();
        assert_eq!(base, settings_hash(&ConvertOptions::faithful()).unwrap());
        let level = ConvertOptions {
            zip_level: 1,
            ..ConvertOptions::faithful()
        };
        assert_ne!(base, settings_hash(&level).unwrap());
        let d = tempfile::tempdir().unwrap();
        let lamp = d.path().join("lamp.csv");
        std::fs::write(&lamp, "wavelength_nm,v\n400,1\n700,1\n").unwrap();
        let with_lamp = ConvertOptions {
            light: LightSpec::Named(lamp.display().to_string()),
            ..ConvertOptions::faithful()
        };
        let before = settings_hash(&with_lamp).unwrap();
        std::fs::write(&lamp, "wavelength_nm,v\n400,1\n700,2\n").unwrap();
        assert_ne!(before, settings_hash(&with_lamp).unwrap());
    }

    #[test]
    fn a_fingerprint_sees_a_change_of_contents_even_at_the_same_size_and_time() {
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("a.exr");
        std::fs::write(&f, b"abcd").unwrap();
        let fp = Fingerprint::of(&f).unwrap();
        assert!(fp.matches(&f).unwrap());
        // The same size, another time: the contents decide.
        let other_time = Fingerprint {
            modified_ns: Some(1),
            ..fp.clone()
        };
        assert!(other_time.matches(&f).unwrap());
        std::fs::write(&f, b"abce").unwrap();
        let stale = Fingerprint {
            modified_ns: Some(1),
            ..fp.clone()
        };
        assert!(!stale.matches(&f).unwrap());
        std::fs::write(&f, b"abcde").unwrap();
        assert!(!fp.matches(&f).unwrap());
    }
}
