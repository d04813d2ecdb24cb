//! The batch's last two stages: decide what each input needs ([`plan`]), then convert those
//! that need it, `jobs` at a time, recording each ([`run`]).

use super::{Fingerprint, Item, Manifest, Record, Shard, Status};
use crate::envmap::convert::{convert, ConvertOptions, ConvertReport};
use crate::error::Result;
use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// What an input needs, and why.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "decision", content = "reason", rename_all = "lowercase")]
pub enum Decision {
    /// To convert, with the reason (e.g. "no output yet", "the input changed", "--force").
    Convert(String),
    /// Up to date: the manifest's record of the conversion that made the output.
    Skip(Box<Record>),
}

/// An input and its decision.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Planned {
    /// The input and its output name.
    pub item: Item,
    /// Whether it is converted or skipped, and why.
    pub decision: Decision,
}

/// Decides, for each item, whether its output in `out_dir` is up to date: it exists, has the
/// size the latest `converted` record of it says, and that record has these `settings` and the
/// input's current fingerprint. `force` converts everything.
pub fn plan(
    items: Vec<Item>,
    out_dir: &Path,
    settings: &str,
    records: &[Record],
    force: bool,
) -> Vec<Planned> {
    let mut latest: HashMap<&str, &Record> = HashMap::new();
    for r in records.iter().filter(|r| r.status == Status::Converted) {
        let newer = latest
            .get(r.output.as_str())
            .is_none_or(|old| old.finished_unix <= r.finished_unix);
        if newer {
            latest.insert(r.output.as_str(), r);
        }
    }
    items
        .into_iter()
        .map(|item| {
            let key = item.output.display().to_string();
            let decision = if force {
                Decision::Convert("--force".into())
            } else {
                decide(
                    &item,
                    &out_dir.join(&item.output),
                    settings,
                    latest.get(key.as_str()),
                )
            };
            Planned { item, decision }
        })
        .collect()
}

fn decide(item: &Item, output: &Path, settings: &str, record: Option<&&Record>) -> Decision {
    let size = match std::fs::metadata(output) {
        Ok(m) => m.len(),
        Err(_) => return Decision::Convert("no output yet".into()),
    };
    let Some(&r) = record else {
        return Decision::Convert("the output exists but no manifest records making it".into());
    };
    if r.bytes != Some(size) {
        return Decision::Convert(format!(
            "the output has {size} bytes, the manifest says {:?}: it was replaced",
            r.bytes
        ));
    }
    if r.settings != settings {
        return Decision::Convert(format!(
            "the settings changed (made with {}, now {settings})",
            r.settings
        ));
    }
    match r.fingerprint.as_ref().map(|f| f.matches(&item.input)) {
        Some(Ok(true)) => Decision::Skip(Box::new(r.clone())),
        Some(Ok(false)) | None => Decision::Convert("the input changed".into()),
        Some(Err(e)) => Decision::Convert(format!("the input cannot be read: {e}")),
    }
}

/// What the caller is told as the batch goes.
#[derive(Debug)]
pub enum Event<'a> {
    /// A conversion started.
    Started(&'a Item),
    /// Rows of a conversion done (done, total).
    Rows(&'a Item, usize, usize),
    /// An input finished: converted, skipped or failed.
    Finished(&'a Item, &'a Record),
}

/// What a batch did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Inputs planned: converted, skipped and failed together.
    pub inputs: usize,
    /// Inputs converted.
    pub converted: usize,
    /// Inputs skipped as up to date.
    pub skipped: usize,
    /// Inputs that failed (reading, converting or recording them).
    pub failed: usize,
    /// Bytes written by this run's conversions.
    pub bytes_written: u64,
    /// Wall-clock seconds of the whole run.
    pub seconds: f64,
    /// The path of the manifest this run appended to.
    pub manifest: String,
}

/// The error of a failed conversion with its causes, on one line.
fn error_chain(e: &crate::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        let more = s.to_string();
        if !text.contains(&more) {
            text = format!("{text}: {more}");
        }
        source = s.source();
    }
    text
}

/// The lights a conversion found: the report's `lights` array (kind, spectrum, CCT, share of the
/// energy, direction, reason of each).
fn lights(report: &ConvertReport) -> Option<serde_json::Value> {
    serde_json::to_value(&report.lights).ok()
}

fn now_unix() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// The run's fixed context: where, how, and the manifest.
struct Context<'a> {
    out_dir: &'a Path,
    opts: &'a ConvertOptions,
    settings: &'a str,
    shard: Option<Shard>,
    manifest: &'a Manifest,
}

impl Context<'_> {
    fn record(&self, item: &Item, status: Status) -> Record {
        Record {
            input: item.input.display().to_string(),
            output: item.output.display().to_string(),
            status,
            error: None,
            settings: self.settings.to_string(),
            fingerprint: None,
            lights: None,
            seconds: 0.0,
            bytes: None,
            shard: self.shard.map(|s| s.to_string()),
            specmap: env!("CARGO_PKG_VERSION").to_string(),
            finished_unix: 0.0,
        }
    }

    /// Converts one item and returns its record (failed, with the error, when it failed).
    fn convert_one(&self, item: &Item, on: &(dyn Fn(Event) + Sync)) -> Record {
        let t0 = Instant::now();
        let mut record = self.record(item, Status::Failed);
        let output = self.out_dir.join(&item.output);
        let input = item.input.display().to_string();
        let done = Fingerprint::of(&item.input).and_then(|fp| {
            record.fingerprint = Some(fp);
            if let Some(dir) = output.parent() {
                std::fs::create_dir_all(dir).map_err(|source| crate::error::Error::Io {
                    path: dir.to_path_buf(),
                    source,
                })?;
            }
            convert(&input, &output, self.opts, &|d, t| {
                on(Event::Rows(item, d, t))
            })
        });
        match done {
            Ok(report) => {
                record.status = Status::Converted;
                record.bytes = Some(report.bytes);
                record.lights = lights(&report);
            }
            Err(e) => record.error = Some(error_chain(&e)),
        }
        record.seconds = t0.elapsed().as_secs_f64();
        record
    }

    /// Appends the record (a manifest that cannot be written fails the input) and tells.
    fn finish(&self, item: &Item, mut record: Record, on: &(dyn Fn(Event) + Sync)) -> Record {
        record.finished_unix = now_unix();
        if let Err(e) = self.manifest.append(&record) {
            record.status = Status::Failed;
            record.error = Some(format!("recording it: {}", error_chain(&e)));
        }
        on(Event::Finished(item, &record));
        record
    }
}

/// Records the skipped inputs, then converts the others `jobs` at a time into `out_dir`
/// (sub-folders created as needed), appending each record to `manifest` as it finishes. The
/// conversions share rayon's pool, so `jobs` overlaps their serial parts (reading, analysing)
/// without more threads than the pool's computing. A failed input is recorded and the others go
/// on.
#[allow(clippy::too_many_arguments)]
pub fn run(
    planned: &[Planned],
    out_dir: &Path,
    opts: &ConvertOptions,
    settings: &str,
    shard: Option<Shard>,
    jobs: usize,
    manifest: &Manifest,
    on: &(dyn Fn(Event) + Sync),
) -> Result<Summary> {
    let t0 = Instant::now();
    let cx = Context {
        out_dir,
        opts,
        settings,
        shard,
        manifest,
    };
    let summary = Mutex::new(Summary {
        inputs: planned.len(),
        manifest: manifest.path().display().to_string(),
        ..Summary::default()
    });
    let count = |r: &Record| {
        let mut s = summary.lock().unwrap_or_else(|e| e.into_inner());
        match r.status {
            Status::Converted => s.converted += 1,
            Status::Skipped => s.skipped += 1,
            Status::Failed => s.failed += 1,
        }
        if r.status == Status::Converted {
            s.bytes_written += r.bytes.unwrap_or(0);
        }
    };
    let mut todo = Vec::new();
    for p in planned {
        match &p.decision {
            Decision::Skip(made) => {
                let t = Instant::now();
                let mut r = cx.record(&p.item, Status::Skipped);
                r.fingerprint = made.fingerprint.clone();
                r.lights = made.lights.clone();
                r.bytes = made.bytes;
                r.seconds = t.elapsed().as_secs_f64();
                count(&cx.finish(&p.item, r, on));
            }
            Decision::Convert(_) => todo.push(&p.item),
        }
    }
    let next = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, todo.len().max(1)) {
            scope.spawn(|| {
                while let Some(&item) = todo.get(next.fetch_add(1, Ordering::Relaxed)) {
                    on(Event::Started(item));
                    let r = cx.convert_one(item, on);
                    count(&cx.finish(item, r, on));
                }
            });
        }
    });
    let mut s = summary.into_inner().unwrap_or_else(|e| e.into_inner());
    s.seconds = t0.elapsed().as_secs_f64();
    Ok(s)
}
