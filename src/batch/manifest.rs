//! The batch manifest: one JSON line per input as it finishes, appended to
//! `DIR/specmap-batch.jsonl` (`DIR/specmap-batch.shard-I-of-N.jsonl` for a shard, so that shards
//! writing to one folder at once, even from several hosts on a network file system, never
//! share a file). Every manifest of the folder is read to decide what is up to date.

use super::{Fingerprint, Shard};
use crate::error::{Error, Result};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The start of every manifest's file name.
pub const MANIFEST_PREFIX: &str = "specmap-batch";

/// The manifest file name of a run: one per shard.
pub fn manifest_name(shard: Option<Shard>) -> String {
    match shard {
        None => format!("{MANIFEST_PREFIX}.jsonl"),
        Some(s) => format!("{MANIFEST_PREFIX}.shard-{}-of-{}.jsonl", s.index, s.count),
    }
}

/// What became of an input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Converted by this run: its output was written.
    Converted,
    /// Its output was up to date.
    Skipped,
    /// Not converted: reading, converting or recording it failed (see [`Record::error`]).
    Failed,
}

/// One manifest line.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Record {
    /// The map, as given.
    pub input: String,
    /// The output, relative to the manifest's folder.
    pub output: String,
    /// What became of it.
    pub status: Status,
    /// Why it failed (the error and its causes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// [`super::settings_hash`] of the conversion.
    pub settings: String,
    /// The input read (None: it could not be read).
    pub fingerprint: Option<Fingerprint>,
    /// The lights the conversion found (its report's main light, sun and white premise).
    pub lights: Option<serde_json::Value>,
    /// Wall-clock seconds of the conversion (of the check, when skipped).
    pub seconds: f64,
    /// The output's size in bytes (None when failed).
    pub bytes: Option<u64>,
    /// The run's shard, as "I/N" (None: the run was not sharded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<String>,
    /// The version of specmap that wrote the line.
    pub specmap: String,
    /// When the line was written, in seconds since the Unix epoch.
    pub finished_unix: f64,
}

/// An open manifest: lines are appended whole, under a lock, so the jobs of one run never
/// interleave.
#[derive(Debug)]
pub struct Manifest {
    path: PathBuf,
    file: Mutex<std::fs::File>,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl Manifest {
    /// Opens (or creates) the manifest of `shard` in `dir` for appending. A last line left
    /// unfinished by a killed run is ended first, so the next record starts a line of its own.
    pub fn open(dir: &Path, shard: Option<Shard>) -> Result<Manifest> {
        let path = dir.join(manifest_name(shard));
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .append(true)
            .create(true)
            .open(&path)
            .map_err(io(&path))?;
        let len = file.metadata().map_err(io(&path))?.len();
        if len > 0 {
            let mut last = [0u8];
            file.seek(std::io::SeekFrom::Start(len - 1))
                .and_then(|_| file.read_exact(&mut last))
                .map_err(io(&path))?;
            if last[0] != b'\n' {
                file.write_all(b"\n").map_err(io(&path))?;
            }
        }
        Ok(Manifest {
            path,
            file: Mutex::new(file),
        })
    }

    /// The manifest file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends one record as one line, in one write.
    pub fn append(&self, record: &Record) -> Result<()> {
        let mut line = serde_json::to_string(record)
            .map_err(|e| Error::invalid(format!("{}: {e}", self.path.display())))?;
        line.push('\n');
        let mut file = self.file.lock().unwrap_or_else(|e| e.into_inner());
        file.write_all(line.as_bytes()).map_err(io(&self.path))
    }

    /// Every record of every manifest in `dir` (all shards), and the lines that are not records
    /// (one cut short by a killed run), each as "FILE line N".
    pub fn read_all(dir: &Path) -> Result<(Vec<Record>, Vec<String>)> {
        let mut records = Vec::new();
        let mut unreadable = Vec::new();
        let entries = match std::fs::read_dir(dir) {
            Ok(e) => e,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((records, unreadable)),
            Err(e) => return Err(io(dir)(e)),
        };
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .filter(|p| {
                p.file_name().is_some_and(|n| {
                    let n = n.to_string_lossy();
                    n.starts_with(MANIFEST_PREFIX) && n.ends_with(".jsonl")
                })
            })
            .collect();
        files.sort();
        for file in files {
            let text = std::fs::read_to_string(&file).map_err(io(&file))?;
            for (i, line) in text.lines().enumerate() {
                if line.trim().is_empty() {
                    continue;
                }
                match serde_json::from_str::<Record>(line) {
                    Ok(r) => records.push(r),
                    Err(_) => unreadable.push(format!("{} line {}", file.display(), i + 1)),
                }
            }
        }
        Ok((records, unreadable))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(output: &str, status: Status) -> Record {
        Record {
            input: format!("lib/{output}"),
            output: output.into(),
            status,
            error: None,
            settings: "s".into(),
            fingerprint: None,
            lights: None,
            seconds: 0.5,
            bytes: Some(3),
            shard: None,
            specmap: "0".into(),
            finished_unix: 1.0,
        }
    }

    #[test]
    fn records_of_every_shard_are_read_back_and_a_cut_line_is_named() {
        let d = tempfile::tempdir().unwrap();
        let a = Manifest::open(d.path(), None).unwrap();
        a.append(&record("a.exr", Status::Converted)).unwrap();
        let shard = Some(Shard { index: 1, count: 2 });
        let b = Manifest::open(d.path(), shard).unwrap();
        assert!(b.path().ends_with("specmap-batch.shard-1-of-2.jsonl"));
        b.append(&record("b.exr", Status::Failed)).unwrap();
        drop(b);
        // A run killed mid-line: the next run ends it and writes its own line after it.
        let path = d.path().join(manifest_name(shard));
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap();
        f.write_all(b"{\"input\": \"lib/c").unwrap();
        drop(f);
        let b = Manifest::open(d.path(), shard).unwrap();
        b.append(&record("c.exr", Status::Skipped)).unwrap();
        let (records, bad) = Manifest::read_all(d.path()).unwrap();
        let outputs: Vec<&str> = records.iter().map(|r| r.output.as_str()).collect();
        assert_eq!(outputs, ["a.exr", "b.exr", "c.exr"]);
        assert_eq!(records[1].status, Status::Failed);
        assert_eq!(bad.len(), 1);
        assert!(bad[0].ends_with("shard-1-of-2.jsonl line 2"), "{bad:?}");
    }
}
