//! The errors of reading and writing image files, each naming the file.

use crate::error::Error;
use std::path::Path;

/// A file whose contents cannot be read as an image.
pub(crate) fn parse_err(path: &Path, message: impl Into<String>) -> Error {
    Error::Parse {
        file: path.to_path_buf(),
        line: None,
        message: message.into(),
    }
}

/// An error of the `exr` crate: a truncated file, an I/O error or a corrupt file.
pub(crate) fn exr_err(path: &Path, e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(source) => {
            if source.kind() == std::io::ErrorKind::UnexpectedEof {
                parse_err(path, "truncated OpenEXR file (unexpected end of file)")
            } else {
                Error::Io {
                    path: path.to_path_buf(),
                    source,
                }
            }
        }
        other => parse_err(
            path,
            format!("corrupt or unsupported OpenEXR file: {other}"),
        ),
    }
}

/// An I/O error on `path`.
pub(crate) fn io_err(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}
