//! Chosen quadratures kept between runs: a scene's fit takes seconds to minutes, and the same
//! scene at the same tolerance chooses the same wavelengths every time.
//!
//! An entry is one JSON file, `<key>.json`, in the user's cache folder
//! (`$SPECMAP_CACHE_DIR/quadrature/`, else `$XDG_CACHE_HOME/specmap/quadrature/`, else
//! `~/.cache/specmap/quadrature/`). The key is a
//! BLAKE3 hash of everything that determines the choice (the caller hashes its scene; [`Key`]
//! adds specmap's version and the fit's options). An entry is written through a temporary file
//! and renamed, so two runs writing the same key at once leave one whole entry, never a torn
//! one. An entry that does not parse, was made by another version, holds another key or a
//! quadrature that [`super::Quadrature::new`] refuses is ignored with a note, never trusted.

use super::choose::{Family, Selection};
use super::fit::Options;
use crate::colorimetry::{Observer, RgbSpace};
use crate::error::Result;
use std::path::{Path, PathBuf};

/// The version of the entry's layout.
pub const FORMAT: u32 = 1;

/// specmap's version, part of every key and checked in every entry.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// A key: the hash of what determines a choice.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Key(String);

impl Key {
    /// The key of a choice among `family` at `opts` (tolerance, margin, node limits; not the
    /// deadline, which [`Entry::budget_s`] records) for `observer` and `space`, over a scene
    /// whose own hash is `scene` (everything about it that the choice reads).
    pub fn new(
        scene: &[u8],
        family: Family,
        opts: &Options,
        observer: Observer,
        space: RgbSpace,
    ) -> Key {
        let mut h = blake3::Hasher::new();
        h.update(format!("specmap {VERSION} format {FORMAT}\n").as_bytes());
        h.update(
            format!(
                "{family:?} tolerance {:?} margin {:?} max {} budget {:?} {observer:?} {space:?}\n",
                opts.tolerance, opts.margin, opts.max_nodes, opts.budget
            )
            .as_bytes(),
        );
        h.update(scene);
        Key(h.finalize().to_hex().to_string())
    }

    /// The key as lower-case hex (blake3).
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

/// One cached choice.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Entry {
    /// The entry's layout version ([`FORMAT`]).
    pub format: u32,
    /// The specmap version that wrote the entry ([`VERSION`]).
    pub specmap: String,
    /// The key the entry is stored under, as hex.
    pub key: String,
    /// The fit ran to its end (its time budget did not cut it short).
    pub complete: bool,
    /// The time budget it ran under, in seconds (None: none).
    pub budget_s: Option<f64>,
    /// What was chosen.
    pub selection: Selection,
}

/// What a lookup found.
#[derive(Debug)]
pub enum Lookup {
    /// A usable entry, from this file.
    Hit(Box<Selection>, PathBuf),
    /// No entry, or one that a longer fit may improve on (why).
    Miss(Option<String>),
    /// An entry that cannot be trusted, and why (a note for the user).
    Ignored(PathBuf, String),
}

/// A folder of entries.
#[derive(Debug, Clone)]
pub struct Cache {
    dir: PathBuf,
}

impl Cache {
    /// The user's cache folder for quadratures: `$SPECMAP_CACHE_DIR/quadrature` (specmap's
    /// caches alone elsewhere, leaving other programs' caches where they are), else
    /// `$XDG_CACHE_HOME/specmap/quadrature`, else `$HOME/.cache/specmap/quadrature`; None where
    /// no such variable is set.
    pub fn in_user_folder() -> Option<Cache> {
        let var = |k: &str| {
            std::env::var_os(k)
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
        };
        let base = var("SPECMAP_CACHE_DIR")
            .or_else(|| var("XDG_CACHE_HOME").map(|x| x.join("specmap")))
            .or_else(|| var("HOME").map(|h| h.join(".cache").join("specmap")))?;
        Some(Cache::at(base.join("quadrature")))
    }

    /// The entries in `dir`.
    pub fn at(dir: impl Into<PathBuf>) -> Cache {
        Cache { dir: dir.into() }
    }

    /// The folder the entries are in.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The file of `key`'s entry.
    pub fn file(&self, key: &Key) -> PathBuf {
        self.dir.join(format!("{}.json", key.0))
    }

    /// The entry of `key`, for a run that may fit for `budget_s` seconds (None: as long as it
    /// takes). An entry cut short by its budget serves a run with no more time than it had.
    pub fn get(&self, key: &Key, budget_s: Option<f64>) -> Lookup {
        let file = self.file(key);
        let text = match std::fs::read_to_string(&file) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Lookup::Miss(None),
            Err(e) => return Lookup::Ignored(file, format!("cannot be read: {e}")),
        };
        let entry: Entry = match serde_json::from_str(&text) {
            Ok(e) => e,
            Err(e) => return Lookup::Ignored(file, format!("is not a cache entry: {e}")),
        };
        if let Some(why) = entry.foreign(key) {
            return Lookup::Ignored(file, why);
        }
        let more_time = match (budget_s, entry.budget_s) {
            _ if entry.complete => false,
            (None, _) | (_, None) => true,
            (Some(now), Some(then)) => now > then,
        };
        if more_time {
            let then = entry.budget_s.map_or("?".into(), |b| format!("{b:.1}"));
            return Lookup::Miss(Some(format!(
                "the cached fit was cut short at {then} s; this run may fit longer"
            )));
        }
        let mut selection = entry.selection;
        selection.from_cache = Some(file.clone());
        Lookup::Hit(Box::new(selection), file)
    }

    /// Stores `selection` under `key`, made within `budget_s` seconds (cut short or not), and
    /// returns its file.
    pub fn put(
        &self,
        key: &Key,
        selection: &Selection,
        budget_s: Option<f64>,
        complete: bool,
    ) -> Result<PathBuf> {
        std::fs::create_dir_all(&self.dir).map_err(|source| crate::error::Error::Io {
            path: self.dir.clone(),
            source,
        })?;
        let entry = Entry {
            format: FORMAT,
            specmap: VERSION.to_string(),
            key: key.0.clone(),
            complete,
            budget_s,
            selection: Selection {
                from_cache: None,
                ..selection.clone()
            },
        };
        let file = self.file(key);
        let text = serde_json::to_string_pretty(&entry)
            .map_err(|e| crate::error::Error::invalid(format!("a cache entry: {e}")))?;
        crate::io::write_atomic(&file, text.as_bytes())?;
        Ok(file)
    }
}

impl Entry {
    /// Why an entry read for `key` is not to be trusted, if it is not.
    fn foreign(&self, key: &Key) -> Option<String> {
        if self.format != FORMAT || self.specmap != VERSION {
            return Some(format!(
                "was made by specmap {} (format {}), not {VERSION} (format {FORMAT})",
                self.specmap, self.format
            ));
        }
        if self.key != key.0 {
            return Some(format!("holds the entry of another key ({})", self.key));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::choose;

    /// A real choice: `color`'s stimuli for the red patch under FL2.
    fn selection() -> Selection {
        let (fit, held_out) = choose::red_under_fl2();
        let scene = choose::own_light(&fit, &held_out);
        choose::select(&scene, Family::Scene, &Options::new(1.0).unwrap()).unwrap()
    }

    fn key(scene: &[u8], tolerance: f64) -> Key {
        let opts = Options::new(tolerance).unwrap();
        Key::new(
            scene,
            Family::Scene,
            &opts,
            Observer::Cie1931,
            RgbSpace::SRGB,
        )
    }

    #[test]
    fn an_entry_reads_back_as_the_choice_it_stored() {
        let dir = tempfile::tempdir().unwrap();
        let cache = Cache::at(dir.path().join("q"));
        let k = key(b"scene", 1.0);
        assert!(matches!(cache.get(&k, None), Lookup::Miss(None)));
        let s = selection();
        let file = cache.put(&k, &s, None, true).unwrap();
        assert_eq!(file, cache.file(&k));
        let Lookup::Hit(back, at) = cache.get(&k, None) else {
            panic!("no hit")
        };
        assert_eq!(at, file);
        assert_eq!(back.quadrature, s.quadrature);
        assert_eq!(back.reason, s.reason);
        assert_eq!(back.estimate_de2000, s.estimate_de2000);
        // Another scene, tolerance or observer is another key.
        assert_ne!(key(b"scene 2", 1.0), k);
        assert_ne!(key(b"scene", 0.5), k);
        let opts = Options::new(1.0).unwrap();
        let other = Key::new(
            b"scene",
            Family::Scene,
            &opts,
            Observer::Cie1964,
            RgbSpace::SRGB,
        );
        assert_ne!(other, k);
    }

    /// A grid that misses a lamp's line errs without bound; JSON writes that as null, and it
    /// reads back as infinite (the chart under low-pressure sodium at 20 nm).
    #[test]
    fn an_error_without_bound_reads_back_as_infinite() {
        let dir = tempfile::tempdir().unwrap();
        let cache = Cache::at(dir.path());
        let k = key(b"scene", 1.0);
        let mut s = selection();
        s.uniform.tried[0].max = f64::INFINITY;
        cache.put(&k, &s, None, true).unwrap();
        let Lookup::Hit(back, _) = cache.get(&k, None) else {
            panic!("not read back")
        };
        assert_eq!(back.uniform.tried[0].max, f64::INFINITY);
    }

    #[test]
    fn a_corrupt_or_foreign_entry_is_ignored_with_a_note() {
        let dir = tempfile::tempdir().unwrap();
        let cache = Cache::at(dir.path());
        let k = key(b"scene", 1.0);
        std::fs::write(cache.file(&k), "{ torn").unwrap();
        let Lookup::Ignored(_, why) = cache.get(&k, None) else {
            panic!("a torn entry was trusted")
        };
        assert!(why.contains("not a cache entry"), "{why}");
        // Another key's entry under this key's name.
        let other = key(b"other", 1.0);
        let file = cache.put(&other, &selection(), None, true).unwrap();
        std::fs::rename(file, cache.file(&k)).unwrap();
        let Lookup::Ignored(_, why) = cache.get(&k, None) else {
            panic!("a foreign entry was trusted")
        };
        assert!(why.contains("another key"), "{why}");
        // Another version's entry.
        let text = std::fs::read_to_string(cache.file(&k)).unwrap();
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["key"] = k.as_str().into();
        v["specmap"] = "0.0.1".into();
        std::fs::write(cache.file(&k), v.to_string()).unwrap();
        let Lookup::Ignored(_, why) = cache.get(&k, None) else {
            panic!("another version's entry was trusted")
        };
        assert!(why.contains("specmap 0.0.1"), "{why}");
        // A quadrature whose nodes do not increase.
        v["specmap"] = VERSION.into();
        v["selection"]["quadrature"]["nodes_nm"][0] = 900.0.into();
        std::fs::write(cache.file(&k), v.to_string()).unwrap();
        assert!(matches!(cache.get(&k, None), Lookup::Ignored(..)));
    }

    #[test]
    fn a_fit_cut_short_serves_only_runs_with_no_more_time() {
        let dir = tempfile::tempdir().unwrap();
        let cache = Cache::at(dir.path());
        let k = key(b"scene", 1.0);
        cache.put(&k, &selection(), Some(2.0), false).unwrap();
        assert!(matches!(cache.get(&k, Some(1.5)), Lookup::Hit(..)));
        assert!(matches!(cache.get(&k, Some(2.0)), Lookup::Hit(..)));
        assert!(matches!(cache.get(&k, Some(5.0)), Lookup::Miss(Some(_))));
        assert!(matches!(cache.get(&k, None), Lookup::Miss(Some(_))));
        // A complete fit serves every run.
        cache.put(&k, &selection(), Some(2.0), true).unwrap();
        assert!(matches!(cache.get(&k, None), Lookup::Hit(..)));
    }

    #[test]
    fn writers_at_once_leave_one_whole_entry() {
        let dir = tempfile::tempdir().unwrap();
        let cache = Cache::at(dir.path());
        let k = key(b"scene", 1.0);
        let s = selection();
        std::thread::scope(|t| {
            for _ in 0..8 {
                t.spawn(|| {
                    for _ in 0..10 {
                        cache.put(&k, &s, None, true).unwrap();
                    }
                });
            }
            for _ in 0..50 {
                assert!(!matches!(cache.get(&k, None), Lookup::Ignored(..)));
            }
        });
        assert!(matches!(cache.get(&k, None), Lookup::Hit(..)));
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "temporary files left: {names:?}");
    }
}
