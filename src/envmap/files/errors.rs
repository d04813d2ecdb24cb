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

/// A file that is well formed but holds what the readers do not read (deep or subsampled data,
/// an OpenEXR feature the `exr` crate lacks).
pub(crate) fn unsupported_err(path: &Path, message: impl Into<String>) -> Error {
    Error::Unsupported {
        file: Some(path.to_path_buf()),
        message: message.into(),
    }
}

/// An error of the `exr` crate: a truncated file, an I/O error, a feature it does not read, or a
/// corrupt file.
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
        exr::error::Error::NotSupported(what) => unsupported_err(
            path,
            format!(
                "corrupt or unsupported OpenEXR file: {}",
                exr::error::Error::NotSupported(what)
            ),
        ),
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
