//! The `specmap` command line: parses flags into library objects, runs, maps errors to exit codes.

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    // Before any thread starts (it sets an environment variable).
    if args.may_use_gpu() {
        cli::runtime_dir::provide();
    }
    remove_temp_files_on_signals();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprint!("{}", error_text(&e));
            ExitCode::from(1)
        }
    }
}

/// The error and its causes, one a line, each said once: a cause whose text an earlier line
/// already holds (the library's "FILE: REASON" over the operating system's REASON) is left out.
fn error_text(e: &anyhow::Error) -> String {
    let mut said: Vec<String> = Vec::new();
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if said.iter().any(|s| s.contains(&text)) {
            continue;
        }
        if said.is_empty() {
            out += &format!("error: {text}\n");
        } else {
            out += &format!("  caused by: {text}\n");
        }
        said.push(text);
    }
    out
}

/// On SIGINT, SIGTERM or SIGHUP: remove the temporary files of the outputs being written (so an
/// interrupted run leaves nothing behind; finished outputs stay), say so, and exit with 128 +
/// the signal, as a shell reports a process killed by it.
#[cfg(unix)]
fn remove_temp_files_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = match signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("warning: cannot handle interrupts ({e}); an interrupted run may leave temporary files");
            return;
        }
    };
    let spawned = std::thread::Builder::new()
        .name("specmap signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                let removed = specmap::io::remove_temp_files();
                let name = signal_hook::low_level::signal_name(signal).unwrap_or("a signal");
                eprint!("{}", interrupted_text(name, &removed));
                std::process::exit(128 + signal);
            }
        });
    if let Err(e) = spawned {
        eprintln!(
            "warning: cannot handle interrupts ({e}); an interrupted run may leave temporary files"
        );
    }
}

#[cfg(not(unix))]
fn remove_temp_files_on_signals() {}

/// What an interrupted run says on its way out: the signal, and each temporary file removed
/// (the output it was becoming is left as it was: absent, or the previous file).
#[cfg_attr(not(unix), allow(dead_code))]
fn interrupted_text(signal: &str, removed: &[std::path::PathBuf]) -> String {
    // On a terminal the line may hold a progress bar (and the shell's ^C): start a new one.
    let mut out = if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        "\n".to_string()
    } else {
        String::new()
    };
    if removed.is_empty() {
        out += &format!("interrupted by {signal}: no output was being written\n");
    }
    for p in removed {
        out += &format!(
            "interrupted by {signal}: removed the unfinished output's temporary file {}; the \
             output is left as it was\n",
            p.display()
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::error_text;
    use anyhow::Context;

    #[test]
    fn each_cause_is_printed_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file (os error 2)");
        let lib = specmap::error::Error::Io {
            path: "x.exr".into(),
            source: io,
        };
        let e = Err::<(), _>(lib).context("converting x.exr").unwrap_err();
        let text = error_text(&e);
        assert_eq!(
            text,
            "error: converting x.exr\n  caused by: x.exr: No such file (os error 2)\n"
        );
        assert_eq!(text.matches("os error 2").count(), 1);
    }
}
