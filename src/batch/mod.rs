//! Batch conversion of a library of maps: expand the inputs, plan what each needs, convert the
//! rest N at a time, and keep a manifest of what was done.
//!
//! The pipeline, each stage a value that can be printed:
//! 1. [`inputs::expand`]: files, folders (every `.exr` and `.hdr` below them) and text files
//!    listing paths become [`Item`]s, each with the output name it will get under the output
//!    folder; two inputs that would write the same output are refused before any work.
//! 2. [`Shard::select`]: a deterministic share of the items (`--shard I/N`), so that separate
//!    processes (GNU parallel, a Slurm job array) split a library between them.
//! 3. [`plan`]: for each item, [`Decision::Skip`] when its output exists and the manifest says it
//!    was made with the same settings ([`settings_hash`]) from the same input
//!    ([`Fingerprint`]), else [`Decision::Convert`] with the reason.
//! 4. [`run`]: converts the items to convert through [`crate::envmap::convert::convert`] (the
//!    same guarantees: a temporary file renamed into place), `jobs` at a time on rayon's one pool,
//!    appending a [`Record`] to the manifest as each finishes. A failed input is recorded and the
//!    others go on.

mod fingerprint;
mod inputs;
mod manifest;
mod run;
mod shard;

pub use fingerprint::{settings_hash, Fingerprint};
pub use inputs::{expand, Expanded, Item, OUTPUT_SUFFIX_BASIS, OUTPUT_SUFFIX_SPECTRAL};
pub use manifest::{manifest_name, Manifest, Record, Status, MANIFEST_PREFIX};
pub use run::{plan, run, Decision, Event, Planned, Summary};
pub use shard::Shard;
