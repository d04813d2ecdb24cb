//! The `specmap` command line: parses flags into library objects, runs, maps errors to exit codes.

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
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
