//! Safe output: write to a temporary file in the destination folder, then rename it into place,
//! so a failed or interrupted write never leaves a partial file or destroys an existing one.
//!
//! Every temporary file is registered while it exists, so a program that is interrupted (the
//! CLI's SIGINT/SIGTERM handler) can remove them all with [`remove_temp_files`] before it exits.
//! Only regular files are ever replaced: a directory, device, fifo or socket at the destination
//! is refused ([`check_output_kind`]) before any work and again just before the rename.

use crate::error::{Error, Result};
use std::fs::OpenOptions;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// The temporary files that exist now (created by [`temp_path_for`], not yet renamed or removed).
static TEMP_FILES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Numbers the temporary files of this process, so two made in the same instant differ.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

fn registry() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // A panic while the lock was held leaves a list that is still valid.
    TEMP_FILES.lock().unwrap_or_else(|e| e.into_inner())
}

/// Checks, before any work, that `dest` may be written as an output: [`check_output_kind`], and
/// its folder exists.
pub fn check_output(dest: &Path) -> Result<()> {
    check_output_kind(dest)?;
    let dir = output_dir(dest);
    if !dir.is_dir() {
        return Err(Error::invalid(format!(
            "{}: the output folder {} does not exist",
            dest.display(),
            dir.display()
        )));
    }
    Ok(())
}

/// Checks that `dest` is absent or a regular file. A directory (or a name ending in a
/// separator), a device such as /dev/null, a fifo or a socket is refused, so it is never replaced
/// by a regular file. The folder is not checked (a command may create it first).
pub fn check_output_kind(dest: &Path) -> Result<()> {
    let text = dest.as_os_str().to_string_lossy();
    let ends_in_separator = text.ends_with('/') || (cfg!(windows) && text.ends_with('\\'));
    if ends_in_separator || dest.file_name().is_none() {
        return Err(Error::invalid(if dest.is_dir() {
            format!("{} is a directory: give a file name", dest.display())
        } else {
            format!("{} names a folder: give a file name", dest.display())
        }));
    }
    match std::fs::metadata(dest) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(m) if m.is_dir() => Err(Error::invalid(format!(
            "{} is a directory: give a file name",
            dest.display()
        ))),
        Ok(_) => Err(Error::invalid(format!(
            "{} exists and is not a regular file (a device, fifo or socket): it is never replaced; \
             give the name of a new or regular file",
            dest.display()
        ))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => match output_dir(dest) {
            dir if dir.exists() && !dir.is_dir() => Err(Error::invalid(format!(
                "{}: the output folder {} is not a folder",
                dest.display(),
                dir.display()
            ))),
            _ => Err(Error::Io {
                path: dest.to_path_buf(),
                source: e,
            }),
        },
    }
}

/// The folder `dest` is written in ("." for a bare file name).
fn output_dir(dest: &Path) -> PathBuf {
    match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// True when `a` and `b` name the same file: the same device and inode (the same canonical path
/// off Unix) when both exist, which also catches links and different spellings; the same
/// canonical folder and file name when neither exists yet. A path that exists is never the same
/// as one that does not.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => same_node(a, &x, b, &y),
        (Err(_), Err(_)) => match (resolved(a), resolved(b)) {
            (Some(x), Some(y)) => x == y,
            _ => a == b,
        },
        _ => false,
    }
}

#[cfg(unix)]
fn same_node(_: &Path, x: &std::fs::Metadata, _: &Path, y: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    x.dev() == y.dev() && x.ino() == y.ino()
}

#[cfg(not(unix))]
fn same_node(a: &Path, _: &std::fs::Metadata, b: &Path, _: &std::fs::Metadata) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// A not-yet-existing path as its canonical folder plus its file name (None: no such folder).
fn resolved(p: &Path) -> Option<PathBuf> {
    let name = p.file_name()?;
    Some(output_dir(p).canonicalize().ok()?.join(name))
}

/// Creates a fresh, empty temporary file beside `dest` (keeping its extension: encoders choose
/// by it) and returns its path. The file is registered until [`rename_into_place`] or
/// [`discard_temp`] is called for it. Fails, naming `dest`, when `dest` is not a regular file
/// ([`check_output_kind`]), its folder does not exist, or no file can be created there.
pub fn temp_path_for(dest: &Path) -> Result<PathBuf> {
    check_output(dest)?;
    let dir = output_dir(dest);
    let name = dest
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let ext = dest
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    loop {
        let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{name}.{}-{n}.tmp{ext}", std::process::id()));
        // Created and registered under the lock, so an interrupt's clean-up sees every file.
        let mut files = registry();
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(_) => {
                files.push(tmp.clone());
                return Ok(tmp);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => {
                return Err(Error::invalid(format!(
                    "{}: cannot create a file in the folder {}: {e}",
                    dest.display(),
                    dir.display()
                )))
            }
        }
    }
}

fn unregister(tmp: &Path) {
    registry().retain(|p| p != tmp);
}

/// Removes a temporary file from [`temp_path_for`] (a write that failed or was abandoned).
pub fn discard_temp(tmp: &Path) {
    let _ = std::fs::remove_file(tmp);
    unregister(tmp);
}

/// Renames `tmp` to `dest` (atomic on one filesystem); removes `tmp` if that fails. Refuses, and
/// removes `tmp`, when `dest` has become something other than a regular file meanwhile.
pub fn rename_into_place(tmp: &Path, dest: &Path) -> Result<()> {
    if let Err(e) = check_output_kind(dest) {
        discard_temp(tmp);
        return Err(e);
    }
    let renamed = std::fs::rename(tmp, dest);
    match renamed {
        Ok(()) => {
            unregister(tmp);
            Ok(())
        }
        Err(source) => {
            discard_temp(tmp);
            Err(Error::Io {
                path: dest.to_path_buf(),
                source,
            })
        }
    }
}

/// Writes `bytes` to `dest` through a temporary file.
pub fn write_atomic(dest: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temp_path_for(dest)?;
    std::fs::write(&tmp, bytes).map_err(|source| {
        discard_temp(&tmp);
        Error::Io {
            path: dest.to_path_buf(),
            source,
        }
    })?;
    rename_into_place(&tmp, dest)
}

/// Removes every registered temporary file, for a program about to exit on a signal, and
/// returns the ones it removed (to be named in the exit message). The registry stays locked
/// afterwards, so no thread can create another one before the exit: call it only right before
/// ending the process.
pub fn remove_temp_files() -> Vec<PathBuf> {
    let mut files = registry();
    let removed = files
        .drain(..)
        .filter(|p| std::fs::remove_file(p).is_ok())
        .collect();
    std::mem::forget(files);
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn listing(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn write_atomic_replaces_a_regular_file_and_leaves_no_temp() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.txt");
        std::fs::write(&p, "old").unwrap();
        write_atomic(&p, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        assert_eq!(listing(d.path()), ["a.txt"]);
    }

    #[test]
    fn a_directory_is_refused_by_name() {
        let d = tempfile::tempdir().unwrap();
        let sub = d.path().join("o");
        std::fs::create_dir(&sub).unwrap();
        for dest in [sub.clone(), PathBuf::from(format!("{}/", sub.display()))] {
            let e = write_atomic(&dest, b"x").unwrap_err().to_string();
            assert!(e.contains("is a directory: give a file name"), "{e}");
            assert!(e.contains(&sub.display().to_string()), "{e}");
        }
        assert!(sub.is_dir());
        assert_eq!(listing(d.path()), ["o"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_never_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let d = tempfile::tempdir().unwrap();
        let fifo = d.path().join("pipe.exr");
        let ok = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(ok.success());
        let e = write_atomic(&fifo, b"x").unwrap_err().to_string();
        assert!(e.contains("exists and is not a regular file"), "{e}");
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
        assert_eq!(listing(d.path()), ["pipe.exr"]);
    }

    #[test]
    fn an_unwritable_folder_is_reported_with_the_output_name() {
        let d = tempfile::tempdir().unwrap();
        let dest = d.path().join("missing").join("x.exr");
        let e = temp_path_for(&dest).unwrap_err().to_string();
        assert!(e.starts_with(&dest.display().to_string()), "{e}");
        assert!(!e.contains(".x.exr."), "no temporary name: {e}");
    }

    #[test]
    fn temp_files_are_registered_until_renamed_or_discarded() {
        let d = tempfile::tempdir().unwrap();
        let a = temp_path_for(&d.path().join("a.png")).unwrap();
        let b = temp_path_for(&d.path().join("a.png")).unwrap();
        assert_ne!(a, b);
        assert!(a.is_file() && b.is_file());
        assert!(a.file_name().unwrap().to_string_lossy().ends_with(".png"));
        assert!(registry().contains(&a) && registry().contains(&b));
        rename_into_place(&a, &d.path().join("a.png")).unwrap();
        discard_temp(&b);
        assert!(!registry().contains(&a) && !registry().contains(&b));
        assert_eq!(listing(d.path()), ["a.png"]);
    }

    #[test]
    fn same_file_sees_through_spellings_and_links() {
        let d = tempfile::tempdir().unwrap();
        let a = d.path().join("a.csv");
        std::fs::write(&a, "x").unwrap();
        let sub = d.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        assert!(same_file(&a, &sub.join("..").join("a.csv")));
        std::fs::hard_link(&a, d.path().join("h.csv")).unwrap();
        assert!(same_file(&a, &d.path().join("h.csv")));
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&a, d.path().join("l.csv")).unwrap();
            assert!(same_file(&a, &d.path().join("l.csv")));
        }
        assert!(!same_file(&a, &d.path().join("new.csv")));
        assert!(same_file(
            &d.path().join("new.csv"),
            &sub.join("..").join("new.csv")
        ));
        assert!(!same_file(&d.path().join("new.csv"), &sub.join("new.csv")));
    }
}
