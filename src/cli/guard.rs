//! The check every command makes before any work: no output is one of its inputs (inputs are
//! never overwritten) or another of its outputs, and every output may be written (absent, or a
//! regular file: never a directory, device, fifo or socket; in a folder that exists and takes
//! new files). No command creates the folder of a file output: a missing one is refused, named.
//! A command whose output is itself a folder (`demo -o`, `render --sweep-out`,
//! `batch --out-dir`) declares it ([`Guard::folder`]) and creates it itself.

use std::path::{Path, PathBuf};

/// What a command reads and writes, each with the flag that named it.
#[derive(Debug, Default)]
pub(crate) struct Guard {
    inputs: Vec<(String, PathBuf)>,
    outputs: Vec<(String, PathBuf)>,
    folders: Vec<(String, PathBuf)>,
}

impl Guard {
    pub(crate) fn new() -> Guard {
        Guard::default()
    }

    /// A file the command reads, with the flag that names it ("" for a positional argument).
    /// One that does not exist is skipped: reading it fails with its own message, and it cannot
    /// be overwritten.
    pub(crate) fn input(&mut self, what: &str, path: impl AsRef<Path>) -> &mut Guard {
        let path = path.as_ref();
        if path.is_file() {
            self.inputs.push((what.to_string(), path.to_path_buf()));
        }
        self
    }

    /// A spectrum or index argument: TABLE, TABLE:COLUMN, PATH, PATH:COLUMN, or
    /// INDEX:THICKNESS; whichever of the whole and the part before the last ':' is a file.
    pub(crate) fn spec(&mut self, what: &str, spec: &str) -> &mut Guard {
        self.input(what, spec);
        if let Some((head, _)) = spec.rsplit_once(':') {
            if !head.is_empty() {
                self.input(what, head);
            }
        }
        self
    }

    /// Several [`Guard::spec`] arguments, comma-separated (`--layers`, `--film`).
    pub(crate) fn spec_list(&mut self, what: &str, list: &str) -> &mut Guard {
        for part in list.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            self.spec(what, part);
        }
        self
    }

    /// A file the command writes.
    pub(crate) fn output(&mut self, what: &str, path: impl AsRef<Path>) -> &mut Guard {
        self.outputs
            .push((what.to_string(), path.as_ref().to_path_buf()));
        self
    }

    /// A folder the command writes its files into and creates itself when missing (`demo -o`,
    /// `render --sweep-out`, `batch --out-dir`), once the check and its own early checks pass:
    /// its files are not refused for a missing folder.
    pub(crate) fn folder(&mut self, what: &str, dir: impl AsRef<Path>) -> &mut Guard {
        self.folders
            .push((what.to_string(), dir.as_ref().to_path_buf()));
        self
    }

    /// Fails, naming both files, when an output is an input or another output, or naming the
    /// output when it cannot be replaced by a regular file. Nothing is written.
    pub(crate) fn check(&self) -> anyhow::Result<()> {
        for (what, dir) in &self.folders {
            if dir.exists() && !dir.is_dir() {
                anyhow::bail!("{what} {}: exists and is not a folder", dir.display());
            }
        }
        for (i, (what, out)) in self.outputs.iter().enumerate() {
            for (in_what, input) in &self.inputs {
                if specmap::io::same_file(out, input) {
                    let named = if in_what.is_empty() {
                        input.display().to_string()
                    } else {
                        format!("{in_what} {}", input.display())
                    };
                    anyhow::bail!(
                        "{what} {} is the input {named} (the same file): choose another name for \
                         the output (inputs are never overwritten)",
                        out.display(),
                    );
                }
            }
            for (other_what, other) in &self.outputs[..i] {
                if specmap::io::same_file(out, other) {
                    anyhow::bail!(
                        "{other_what} {} and {what} {} are the same file: give each output its \
                         own name",
                        other.display(),
                        out.display()
                    );
                }
            }
            specmap::io::check_output_kind(out)?;
            if let Some(dir) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
                if !dir.is_dir() && self.folders.iter().any(|(_, f)| f == dir) {
                    // The command creates it: nothing there to probe yet.
                    continue;
                }
                if !dir.is_dir() {
                    anyhow::bail!(
                        "{what} {}: the folder {} does not exist (no command creates the folder of an \
                         output file: create it first)",
                        out.display(),
                        dir.display()
                    );
                }
            }
            // A folder that exists but takes no new file fails now, not after the work.
            let probe = specmap::io::temp_path_for(out)?;
            specmap::io::discard_temp(&probe);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_output_that_is_an_input_is_refused_naming_both() {
        let d = tempfile::tempdir().unwrap();
        let csv = d.path().join("lamp.csv");
        std::fs::write(&csv, "wavelength_nm,v\n400,1\n").unwrap();
        let spelled = d.path().join(".").join("lamp.csv");
        let e = Guard::new()
            .spec("--light", &format!("{}:v", csv.display()))
            .output("--plot", &spelled)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("--plot") && e.contains("--light"), "{e}");
        assert!(e.contains(&csv.display().to_string()), "{e}");
        assert!(e.contains("inputs are never overwritten"), "{e}");
    }

    #[test]
    fn outputs_must_differ_from_each_other_but_not_from_missing_inputs() {
        let d = tempfile::tempdir().unwrap();
        let a = d.path().join("a.png");
        std::fs::create_dir(d.path().join("x")).unwrap();
        let e = Guard::new()
            .input("input", d.path().join("missing.exr"))
            .output("-o", &a)
            .output("--plot", d.path().join("x").join("b.png"))
            .check();
        assert!(e.is_ok(), "{e:?}");
        let e = Guard::new()
            .output("-o", &a)
            .output("--plot", &a)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("are the same file"), "{e}");
    }

    #[test]
    fn a_missing_output_folder_is_refused_naming_it_and_not_created() {
        let d = tempfile::tempdir().unwrap();
        let missing = d.path().join("new").join("folder");
        let e = Guard::new()
            .output("-o", missing.join("x.exr"))
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("-o "), "{e}");
        assert!(
            e.contains(&format!("the folder {} does not exist", missing.display())),
            "{e}"
        );
        assert!(!d.path().join("new").exists());
    }

    #[test]
    fn a_folder_the_command_creates_may_be_missing_but_not_a_file() {
        let d = tempfile::tempdir().unwrap();
        let dir = d.path().join("new").join("out");
        Guard::new()
            .folder("--out-dir", &dir)
            .output("--out-dir", dir.join("a.exr"))
            .check()
            .unwrap();
        assert!(!d.path().join("new").exists(), "the check creates nothing");
        let file = d.path().join("file");
        std::fs::write(&file, "x").unwrap();
        let e = Guard::new().folder("-o", &file).check().unwrap_err();
        assert!(e.to_string().contains("exists and is not a folder"), "{e}");
    }

    #[test]
    fn a_layer_list_names_its_index_tables() {
        let d = tempfile::tempdir().unwrap();
        let nk = d.path().join("nk.csv");
        std::fs::write(&nk, "wavelength_nm,n,k\n400,1.5,0\n").unwrap();
        let e = Guard::new()
            .spec_list("--layers", &format!("2.7:270, {}:100", nk.display()))
            .output("--plot", &nk)
            .check();
        assert!(e.is_err());
    }
}
