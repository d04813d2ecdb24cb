//! The batch's inputs: map files, folders (every `.exr` and `.hdr` below them) and text files
//! listing paths, each with the name its output gets under the output folder.

use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The output suffix of the spectral format: `sky.exr` -> `sky.spectral.exr`.
pub const OUTPUT_SUFFIX_SPECTRAL: &str = ".spectral.exr";
/// The output suffix of the basis format: `sky.exr` -> `sky.basis.exr`.
pub const OUTPUT_SUFFIX_BASIS: &str = ".basis.exr";

/// One map to convert.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Item {
    /// The map, as given (a folder's maps: the folder joined with the path below it).
    pub input: PathBuf,
    /// The output's path relative to the output folder: the input's name (a folder's maps keep
    /// the sub-folders below the folder given) with the extension replaced by the suffix.
    pub output: PathBuf,
}

/// The expanded inputs, sorted by output name, and how many paths were given more than once.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Expanded {
    /// The maps to convert, each once, sorted by output name.
    pub items: Vec<Item>,
    /// Inputs named more than once (e.g. a file and its folder): converted once.
    pub duplicates: usize,
}

/// Whether a path names a map by its extension (`.exr`, `.hdr`, any case).
fn is_map(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr") || e.eq_ignore_ascii_case("hdr"))
}

/// `rel` with its extension replaced by `suffix`.
fn output_name(rel: &Path, suffix: &str) -> PathBuf {
    let stem = rel.file_stem().unwrap_or(rel.as_os_str()).to_string_lossy();
    rel.with_file_name(format!("{stem}{suffix}"))
}

/// Expands `args` (map files, folders, lists of paths) into the maps to convert into
/// `out_dir`, with outputs named by `suffix`. The output folder is never searched for inputs
/// (its outputs would become inputs of the next run), nor are hidden files and folders (their
/// names start with '.': the temporary files of a run in progress). A path given as a map need
/// not exist: it is converted, and fails, as any other. Two different inputs whose outputs
/// would have the same name are refused, naming both.
pub fn expand(args: &[PathBuf], out_dir: &Path, suffix: &str) -> Result<Expanded> {
    let skip_dir = out_dir.canonicalize().ok();
    let mut found: Vec<Item> = Vec::new();
    for arg in args {
        expand_one(arg, None, skip_dir.as_deref(), suffix, &mut found)?;
    }
    let mut by_output: BTreeMap<PathBuf, Item> = BTreeMap::new();
    let mut seen = std::collections::HashSet::new();
    let mut duplicates = 0;
    for item in found {
        // The same file under two spellings (itself and through its folder) is one input.
        let key = item
            .input
            .canonicalize()
            .unwrap_or_else(|_| item.input.clone());
        if !seen.insert(key) {
            duplicates += 1;
            continue;
        }
        match by_output.get(&item.output) {
            None => {
                by_output.insert(item.output.clone(), item);
            }
            Some(first) => {
                return Err(Error::invalid(format!(
                    "{} and {} would both be written to {}: rename one, or convert them in \
                     separate batches",
                    first.input.display(),
                    item.input.display(),
                    out_dir.join(&item.output).display()
                )))
            }
        }
    }
    if by_output.is_empty() {
        return Err(Error::invalid(
            "no .exr or .hdr maps found in the inputs given",
        ));
    }
    Ok(Expanded {
        items: by_output.into_values().collect(),
        duplicates,
    })
}

/// Expands one path: `list` names the list file and line it came from (lists do not nest).
fn expand_one(
    path: &Path,
    list: Option<(&Path, usize)>,
    skip_dir: Option<&Path>,
    suffix: &str,
    found: &mut Vec<Item>,
) -> Result<()> {
    let whence = || match list {
        Some((file, line)) => format!("{} line {line}: ", file.display()),
        None => String::new(),
    };
    if path.is_dir() {
        return expand_folder(path, skip_dir, suffix, found);
    }
    if is_map(path) {
        let name = path.file_name().map(Path::new).unwrap_or(path);
        found.push(Item {
            input: path.to_path_buf(),
            output: output_name(name, suffix),
        });
        return Ok(());
    }
    if !path.exists() {
        return Err(Error::invalid(format!(
            "{}{}: no such file or folder",
            whence(),
            path.display()
        )));
    }
    if let Some((file, line)) = list {
        return Err(Error::invalid(format!(
            "{} line {line}: {} is neither an .exr or .hdr map nor a folder (lists do not nest)",
            file.display(),
            path.display()
        )));
    }
    expand_list(path, skip_dir, suffix, found)
}

/// Every map below a folder, in name order, named by its path below the folder.
fn expand_folder(
    dir: &Path,
    skip_dir: Option<&Path>,
    suffix: &str,
    found: &mut Vec<Item>,
) -> Result<()> {
    let walk = walkdir::WalkDir::new(dir)
        .follow_links(true)
        .sort_by_file_name()
        .into_iter()
        .filter_entry(|e| {
            let hidden = e.depth() > 0 && e.file_name().to_string_lossy().starts_with('.');
            let is_out = e.file_type().is_dir()
                && skip_dir.is_some_and(|s| e.path().canonicalize().is_ok_and(|p| p == s));
            !hidden && !is_out
        });
    for entry in walk {
        let entry = entry.map_err(|e| {
            Error::invalid(format!("{}: cannot list the folder: {e}", dir.display()))
        })?;
        if entry.file_type().is_file() && is_map(entry.path()) {
            let rel = entry.path().strip_prefix(dir).unwrap_or(entry.path());
            found.push(Item {
                input: entry.path().to_path_buf(),
                output: output_name(rel, suffix),
            });
        }
    }
    Ok(())
}

/// A text file of paths, one a line, relative to the list's own folder; blank lines and lines
/// starting with '#' are skipped.
fn expand_list(
    file: &Path,
    skip_dir: Option<&Path>,
    suffix: &str,
    found: &mut Vec<Item>,
) -> Result<()> {
    let bytes = std::fs::read(file).map_err(|source| Error::Io {
        path: file.to_path_buf(),
        source,
    })?;
    let text = match std::str::from_utf8(&bytes) {
        Ok(t) if !t.contains('\0') => t,
        _ => {
            return Err(Error::invalid(format!(
                "{}: not an .exr or .hdr map, a folder, or a text file listing paths",
                file.display()
            )))
        }
    };
    let base = file.parent().unwrap_or(Path::new(""));
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let path = base.join(line);
        expand_one(&path, Some((file, i + 1)), skip_dir, suffix, found)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(p: &Path) {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, b"x").unwrap();
    }

    fn outputs(e: &Expanded) -> Vec<String> {
        e.items
            .iter()
            .map(|i| i.output.display().to_string())
            .collect()
    }

    #[test]
    fn folders_give_their_maps_below_them_but_not_the_output_folder_nor_hidden_files() {
        let d = tempfile::tempdir().unwrap();
        let lib = d.path().join("lib");
        for f in [
            "a.exr",
            "sub/b.HDR",
            "notes.txt",
            ".a.exr.123-0.tmp.exr",
            "out/a.spectral.exr",
        ] {
            touch(&lib.join(f));
        }
        let e = expand(
            std::slice::from_ref(&lib),
            &lib.join("out"),
            OUTPUT_SUFFIX_SPECTRAL,
        )
        .unwrap();
        assert_eq!(outputs(&e), ["a.spectral.exr", "sub/b.spectral.exr"]);
        assert_eq!(e.items[1].input, lib.join("sub/b.HDR"));
        assert_eq!(e.duplicates, 0);
    }

    #[test]
    fn a_list_names_paths_relative_to_itself_and_a_bad_line_is_named() {
        let d = tempfile::tempdir().unwrap();
        touch(&d.path().join("maps/a.exr"));
        touch(&d.path().join("maps/more/c.exr"));
        let list = d.path().join("maps/list.txt");
        std::fs::write(&list, "# the library\na.exr\n\nmore\nmissing.hdr\n").unwrap();
        let out = d.path().join("out");
        let e = expand(std::slice::from_ref(&list), &out, OUTPUT_SUFFIX_BASIS).unwrap();
        assert_eq!(
            outputs(&e),
            ["a.basis.exr", "c.basis.exr", "missing.basis.exr"]
        );
        std::fs::write(&list, "a.exr\nnotes.md\n").unwrap();
        touch(&d.path().join("maps/notes.md"));
        let err = expand(std::slice::from_ref(&list), &out, OUTPUT_SUFFIX_BASIS)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("list.txt line 2") && err.contains("notes.md"),
            "{err}"
        );
        std::fs::write(&list, "a.exr\nnowhere\n").unwrap();
        let err = expand(&[list], &out, OUTPUT_SUFFIX_BASIS)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("line 2") && err.contains("no such file"),
            "{err}"
        );
    }

    #[test]
    fn two_inputs_of_one_output_name_are_refused_and_the_same_one_twice_is_counted() {
        let d = tempfile::tempdir().unwrap();
        let (a, b) = (d.path().join("x/sky.exr"), d.path().join("y/sky.hdr"));
        touch(&a);
        touch(&b);
        let out = d.path().join("out");
        let err = expand(&[a.clone(), b.clone()], &out, OUTPUT_SUFFIX_SPECTRAL)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("x/sky.exr") && err.contains("y/sky.hdr"),
            "{err}"
        );
        // Itself, through its folder, and spelled another way: one input, named as first given.
        let spelled = d.path().join("x/../x/sky.exr");
        let e = expand(
            &[a.clone(), d.path().join("x"), spelled],
            &out,
            OUTPUT_SUFFIX_SPECTRAL,
        )
        .unwrap();
        assert_eq!(e.items.len(), 1);
        assert_eq!(e.items[0].input, a);
        assert_eq!(e.duplicates, 2);
        let binary = d.path().join("image.png");
        std::fs::write(&binary, [0x89, b'P', b'N', b'G', 0, 0]).unwrap();
        let err = expand(&[binary], &out, OUTPUT_SUFFIX_SPECTRAL)
            .unwrap_err()
            .to_string();
        assert!(err.contains("text file listing paths"), "{err}");
    }
}
