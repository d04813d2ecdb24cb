//! The library's one error type: few kinds a caller can match, each naming what went wrong and
//! where: malformed input ([`Error::Parse`], the format kind), a name that does not resolve
//! ([`Error::NotFound`]), a value out of range or inconsistent ([`Error::Invalid`]), what
//! specmap does not do ([`Error::Unsupported`]), and a file that cannot be read or written
//! ([`Error::Io`]).
//!
//! ```
//! use specmap::Error;
//!
//! match specmap::data::spectrum("D66") {
//!     Err(Error::NotFound { suggestions, .. }) => assert!(suggestions.contains(&"D65".to_string())),
//!     other => panic!("expected NotFound, got {other:?}"),
//! }
//! ```

use std::path::PathBuf;

/// Everything the library can fail with. Messages name the file, line, column or value at fault.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Malformed input, the format kind: a CSV that is empty, has text where a number belongs,
    /// a NaN, wavelengths out of order, or a row with a missing column; an image file that is
    /// truncated, corrupt, or lacks the channels it needs.
    #[error("{}{}: {message}", .file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// The file at fault.
        file: PathBuf,
        /// Its line (1-based), for tables.
        line: Option<usize>,
        /// What is wrong, in words.
        message: String,
    },
    /// A name that does not resolve: an unknown table or column. `suggestions` holds the closest
    /// known names.
    #[error("{message}{}", suggest(.suggestions))]
    NotFound {
        /// What was looked for, and where.
        message: String,
        /// The closest known names.
        suggestions: Vec<String>,
    },
    /// An argument or value that is out of range or inconsistent (an empty wavelength range, a
    /// light with no energy in range, a step that does not divide the range...).
    #[error("{0}")]
    Invalid(String),
    /// Input that is well formed but asks for what specmap does not do: deep or subsampled
    /// OpenEXR data, an OpenEXR feature the reader lacks, a gain medium in a thin film.
    #[error("{}{message}", .file.as_ref().map(|f| format!("{}: ", f.display())).unwrap_or_default())]
    Unsupported {
        /// The file at fault, if a file is.
        file: Option<PathBuf>,
        /// What is not supported, in words.
        message: String,
    },
    /// A file that could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file read or written.
        path: PathBuf,
        /// What the operating system said.
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
    /// An [`Error::Invalid`] saying `message`.
    pub(crate) fn invalid(message: impl Into<String>) -> Self {
        Error::Invalid(message.into())
    }

    /// An [`Error::Unsupported`] of no file in particular.
    pub(crate) fn unsupported(message: impl Into<String>) -> Self {
        Error::Unsupported {
            file: None,
            message: message.into(),
        }
    }
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
