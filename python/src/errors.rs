//! specmap's errors as Python exceptions: a missing file is `FileNotFoundError`, another
//! operating-system failure `OSError`, everything the input or the arguments got wrong
//! (`Parse`, `NotFound`, `Invalid`, `Unsupported`, a flag the CLI's parser refuses)
//! `ValueError`. The message is specmap's own, as the CLI prints it.

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::PyErr;

/// A library error as the Python exception of its kind.
pub(crate) fn from_specmap(e: specmap::Error) -> PyErr {
    match &e {
        specmap::Error::Io { source, .. } => from_io(source.kind(), e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// An error of the CLI's code (anyhow): the kind of the first specmap or I/O error in its chain,
/// the message its whole chain (as the CLI prints it, "error: " left out).
pub(crate) fn from_anyhow(e: anyhow::Error) -> PyErr {
    let message = chain_text(&e);
    for cause in e.chain() {
        if let Some(specmap::Error::Io { source, .. }) = cause.downcast_ref::<specmap::Error>() {
            return from_io(source.kind(), message);
        }
        if let Some(io) = cause.downcast_ref::<std::io::Error>() {
            return from_io(io.kind(), message);
        }
    }
    PyValueError::new_err(message)
}

/// A clap parse error (an unknown option, a value out of its set) as `ValueError`, with clap's
/// message naming the flag and the values it takes.
pub(crate) fn from_clap(e: clap::Error) -> PyErr {
    PyValueError::new_err(e.render().to_string().trim().to_string())
}

fn from_io(kind: std::io::ErrorKind, message: String) -> PyErr {
    match kind {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// The error and its causes, each said once (a cause whose text an earlier one holds is left
/// out), joined by ": ".
fn chain_text(e: &anyhow::Error) -> String {
    let mut said: Vec<String> = Vec::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if !said.iter().any(|s| s.contains(&text)) {
            said.push(text);
        }
    }
    said.join(": ")
}

/// `Result<T, specmap::Error>` -> `PyResult<T>`.
pub(crate) trait OrPy<T> {
    /// The error as the Python exception of its kind.
    fn or_py(self) -> pyo3::PyResult<T>;
}

impl<T> OrPy<T> for specmap::Result<T> {
    fn or_py(self) -> pyo3::PyResult<T> {
        self.map_err(from_specmap)
    }
}

impl<T> OrPy<T> for anyhow::Result<T> {
    fn or_py(self) -> pyo3::PyResult<T> {
        self.map_err(from_anyhow)
    }
}
