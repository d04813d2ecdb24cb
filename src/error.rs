//! The library's one error type: few kinds, each naming what went wrong and where.

use std::path::PathBuf;

/// Everything the library can fail with. Messages name the file, line, column or value at fault.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Malformed tabular input: a CSV that is empty, has text where a number belongs, a NaN,
    /// wavelengths out of order, or a row with a missing column.
    #[error("{}{}: {message}", .file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        file: PathBuf,
        line: Option<usize>,
        message: String,
    },
    /// A name that does not resolve: an unknown table or column. `suggestions` holds the closest
    /// known names.
    #[error("{message}{}", suggest(.suggestions))]
    NotFound {
        message: String,
        suggestions: Vec<String>,
    },
    /// An argument or value that is out of range or inconsistent (an empty wavelength range, a
    /// light with no energy in range, a step that does not divide the range...).
    #[error("{0}")]
    Invalid(String),
    /// A file that could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

fn suggest(names: &[String]) -> String {
    if names.is_empty() {
        String::new()
    } else {
        format!(" (did you mean {}?)", names.join(", "))
    }
}

impl Error {
    pub(crate) fn invalid(message: impl Into<String>) -> Self {
        Error::Invalid(message.into())
    }
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
