//! `specmap batch`: a library of maps converted into one folder: resumable, shardable across
//! processes and hosts, N files at once.

use super::convert::ConvertOptionArgs;
use super::outln;
use anyhow::Context;
use clap::Args;
use specmap::batch::{self, Decision, Event, Manifest, Planned, Record, Shard, Status, Summary};
use specmap::envmap::convert::{ConvertOptions, OutputFormat};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

pub(crate) const AFTER_HELP: &str = "\
Examples:
  specmap batch ~/hdri --out-dir ~/hdri-spectral            # every .exr/.hdr below ~/hdri
  specmap batch list.txt --out-dir out --jobs 2 --light auto
  specmap batch ~/hdri --out-dir out --dry-run              # what each map needs, and why
  parallel specmap batch ~/hdri --out-dir out --threads 1 --shard {}/4 ::: 0 1 2 3
  sbatch --array=0-15 integrations/slurm/specmap-batch.sbatch ~/hdri out

Every convert option applies to every map. A second run converts only what is missing or out
of date (other settings, a changed input); out/specmap-batch*.jsonl records every input.";

#[derive(Debug, Args)]
pub(crate) struct BatchArgs {
    /// Maps (.exr, .hdr), folders (every map below them, sub-folders kept in the output names)
    /// or text files listing such paths, one a line, relative to the list's own folder.
    #[arg(required = true, value_name = "INPUT")]
    inputs: Vec<PathBuf>,
    /// The output folder, created if missing: MAP.exr becomes DIR/MAP.spectral.exr
    /// (DIR/MAP.basis.exr with --format basis); DIR/specmap-batch.jsonl records each input.
    #[arg(long, value_name = "DIR")]
    out_dir: PathBuf,
    /// Convert share I of N of the inputs (I from 0 to N-1; every N-th map in name order), for
    /// N processes given the same inputs: each writes its own manifest, none collide.
    #[arg(long, value_name = "I/N")]
    shard: Option<Shard>,
    /// Convert N maps at once (they share one pool of --threads threads: no oversubscription;
    /// each holds its map and a batch of rows in memory).
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u16).range(1..))]
    jobs: u16,
    /// Threads computing and compressing (default: every core); 1 per process when GNU parallel
    /// runs one shard per core.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    threads: Option<u16>,
    /// Convert every input, even those whose output is up to date.
    #[arg(long)]
    force: bool,
    /// Print what each input needs and why; convert nothing.
    #[arg(long)]
    dry_run: bool,
    #[command(flatten)]
    options: ConvertOptionArgs,
    /// Print nothing but errors (no progress bar, no line per map, no summary).
    #[arg(long)]
    quiet: bool,
    /// The summary as JSON on stdout.
    #[arg(long)]
    json: bool,
}

/// `specmap batch`: the options and folder checked, the inputs planned against the manifest;
/// then the plan printed (`--dry-run`), or every map converted and the run summed up.
pub(crate) fn run(a: BatchArgs) -> anyhow::Result<()> {
    let opts = prepare(&a)?;
    let work = plan_work(&a, &opts)?;
    if a.dry_run {
        super::emit(&dry_run_text(&work));
        return Ok(());
    }
    let manifest = Manifest::open(&a.out_dir, a.shard)?;
    let log = Log::new(work.planned.len(), a.quiet, &a.out_dir);
    let summary = batch::run(
        &work.planned,
        &a.out_dir,
        &opts,
        &work.settings,
        a.shard,
        a.jobs as usize,
        &manifest,
        &|e| log.event(e),
    )?;
    log.finish();
    if a.json {
        super::emit(&(serde_json::to_string_pretty(&summary)? + "\n"));
    } else if !a.quiet {
        super::emit(&summary_text(&work.scope, &summary));
    }
    if summary.failed > 0 {
        anyhow::bail!(
            "{} of {} inputs failed (each error is above and in {})",
            summary.failed,
            summary.inputs,
            summary.manifest
        );
    }
    Ok(())
}

/// The conversion's options, checked with `--threads`' pool started and the output folder made.
fn prepare(a: &BatchArgs) -> anyhow::Result<ConvertOptions> {
    if a.options.faces() {
        anyhow::bail!(
            "--in-layout faces: a batch converts one-file maps; convert six-face maps with \
             `specmap convert PATTERN -o OUT.exr --in-layout faces`"
        );
    }
    let opts = a.options.to_options()?;
    if let Some(n) = a.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .context("--threads: starting the thread pool")?;
    }
    let mut guard = super::guard::Guard::new();
    if let Some(p) = a.options.fit_file() {
        guard.input("--fit", p);
    }
    guard.folder("--out-dir", &a.out_dir).check()?;
    std::fs::create_dir_all(&a.out_dir)
        .with_context(|| format!("--out-dir {}: creating the folder", a.out_dir.display()))?;
    Ok(opts)
}

/// What this run does, before it does it.
struct Work {
    /// Each input of this shard, and whether it is converted or skipped.
    planned: Vec<Planned>,
    /// The hash of the conversion's settings.
    settings: String,
    /// How many inputs, in words (the shard, the duplicates).
    scope: String,
}

/// The inputs expanded, this shard's kept, and each planned against the manifest's records.
fn plan_work(a: &BatchArgs, opts: &ConvertOptions) -> anyhow::Result<Work> {
    let suffix = match opts.format {
        OutputFormat::Spectral => batch::OUTPUT_SUFFIX_SPECTRAL,
        OutputFormat::Basis => batch::OUTPUT_SUFFIX_BASIS,
    };
    let expanded = batch::expand(&a.inputs, &a.out_dir, suffix)?;
    let found = expanded.items.len();
    let items = match a.shard {
        Some(s) => s.select(expanded.items),
        None => expanded.items,
    };
    let settings = batch::settings_hash(opts)?;
    let (records, unreadable) = Manifest::read_all(&a.out_dir)?;
    for line in &unreadable {
        eprintln!("warning: {line} is not a manifest record (a run cut short?): ignored");
    }
    let planned = batch::plan(items, &a.out_dir, &settings, &records, a.force);
    let scope = match a.shard {
        Some(s) => format!("{} inputs (shard {s} of {found})", planned.len()),
        None => format!("{} inputs", planned.len()),
    };
    let scope = if expanded.duplicates > 0 {
        format!(
            "{scope}; {} named more than once, converted once",
            expanded.duplicates
        )
    } else {
        scope
    };
    Ok(Work {
        planned,
        settings,
        scope,
    })
}

/// `--dry-run`: what each map needs and why, then the scope and settings.
fn dry_run_text(work: &Work) -> String {
    let mut out = String::new();
    for p in &work.planned {
        let what = match &p.decision {
            Decision::Convert(why) => format!("convert  ({why})"),
            Decision::Skip(_) => "skip     (up to date)".into(),
        };
        outln!(
            out,
            "{what}  {} -> {}",
            p.item.input.display(),
            p.item.output.display()
        );
    }
    outln!(
        out,
        "batch --dry-run: {}, settings {}",
        work.scope,
        work.settings
    );
    out
}

/// The run's one-line summary.
fn summary_text(scope: &str, summary: &Summary) -> String {
    let mut out = String::new();
    outln!(
        out,
        "batch: {scope}: {} converted, {} skipped, {} failed; {:.1} MB written in {:.1} s; \
         manifest {}",
        summary.converted,
        summary.skipped,
        summary.failed,
        summary.bytes_written as f64 / 1e6,
        summary.seconds,
        summary.manifest
    );
    out
}

/// The progress bar over files (and bytes written) on a terminal, a line per map otherwise;
/// failures are always printed.
struct Log<'a> {
    bar: Option<indicatif::ProgressBar>,
    quiet: bool,
    out_dir: &'a Path,
    bytes: std::sync::atomic::AtomicU64,
}

impl<'a> Log<'a> {
    fn new(files: usize, quiet: bool, out_dir: &'a Path) -> Log<'a> {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let b = indicatif::ProgressBar::new(files as u64);
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "batch [{bar:30}] {pos}/{len} maps, {msg} written, {elapsed} (eta {eta})",
                )
                .expect("a valid template")
                .progress_chars("=> "),
            );
            b.set_message("0 B");
            b
        });
        Log {
            bar,
            quiet,
            out_dir,
            bytes: Default::default(),
        }
    }

    fn line(&self, text: String) {
        match &self.bar {
            Some(b) => b.println(text),
            None => eprintln!("{text}"),
        }
    }

    fn event(&self, e: Event) {
        let Event::Finished(item, r) = e else {
            return;
        };
        if let Some(b) = &self.bar {
            let add = match r.status {
                Status::Converted => r.bytes.unwrap_or(0),
                _ => 0,
            };
            let total = self
                .bytes
                .fetch_add(add, std::sync::atomic::Ordering::Relaxed)
                + add;
            b.set_message(indicatif::HumanBytes(total).to_string());
            b.inc(1);
        }
        let output = self.out_dir.join(&item.output);
        match r.status {
            Status::Failed => self.line(format!(
                "error: {}: {}",
                item.input.display(),
                r.error.as_deref().unwrap_or("failed")
            )),
            _ if self.quiet => {}
            Status::Converted => self.line(format!(
                "converted {} -> {} ({:.1} s, {:.1} MB; {})",
                item.input.display(),
                output.display(),
                r.seconds,
                r.bytes.unwrap_or(0) as f64 / 1e6,
                lights_text(r)
            )),
            Status::Skipped => self.line(format!(
                "skipped   {}: {} is up to date",
                item.input.display(),
                output.display()
            )),
        }
    }

    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// "light D65, sun found" from a record's lights.
fn lights_text(r: &Record) -> String {
    let Some(l) = &r.lights else {
        return String::new();
    };
    let light = l.get("light").and_then(|v| v.as_str()).unwrap_or("?");
    let found = l.get("sun").and_then(|s| s.get("found"));
    let sun = match found.and_then(|f| f.as_str()) {
        Some("true") => "sun found",
        _ => "no sun",
    };
    format!("light {light}, {sun}")
}
