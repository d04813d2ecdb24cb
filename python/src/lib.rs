//! The native module of the `specmap` Python package (`specmap._specmap`): the library's calls
//! with numpy arrays in and out, the GIL released while they work, and specmap's errors raised
//! as Python exceptions of their kind (see [`errors`]). `specmap/__init__.py` is the API users
//! call; it wraps these functions with keyword arguments, `colour` objects and docstrings.

// The command line's flag definitions and runs, compiled in as they are: `convert(...,
// precision="float")` is parsed by the same clap code as `specmap convert --precision float`,
// and `render` runs the CLI's own stages. Most of the CLI is unused here.
#[allow(dead_code, unreachable_pub, unused_imports)]
#[path = "../../src/cli/mod.rs"]
mod cli;

mod errors;
mod films;
mod maps;
mod render;
mod spectra;

use pyo3::prelude::*;

/// `argv` (a command's flags, as the Python wrappers build them) parsed by the CLI's own clap
/// definitions: `T` is a `Parser` flattening the command's args; a refused flag is a ValueError
/// with clap's message.
pub(crate) fn parse_flags<T: clap::Parser>(command: &str, argv: Vec<String>) -> PyResult<T> {
    T::try_parse_from(std::iter::once(command.to_string()).chain(argv)).map_err(errors::from_clap)
}

/// The native module: each function is documented where it is defined.
#[pymodule]
fn _specmap(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    spectra::register(m)?;
    films::register(m)?;
    maps::register(m)?;
    render::register(m)?;
    Ok(())
}
