//! rigport in Python (the `rigport` package, module `rigport._rigport`): PyO3 bindings
//! over the pipeline and model crates, one abi3 wheel for CPython 3.9 and later.
//!
//! Bindings only: every call goes to `rigport_pipeline` (the functions the CLI calls, so
//! results are the CLI's) and reads `rigport_model` data; values are converted at this
//! edge (`options`), errors and warnings become Python's (`errors`). Work runs with
//! the GIL released, and evaluated frames reach numpy without a copy (`frames`).

mod asset;
mod commands;
mod errors;
mod frames;
mod options;
mod report;

use pyo3::prelude::*;

/// The extension module; `rigport/__init__.py` re-exports it.
#[pymodule]
fn _rigport(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    // As the CLI does first: large buffers (frames, meshes) reuse freed memory.
    rigport_pipeline::memory::raise_malloc_mmap_threshold();
    m.add_function(wrap_pyfunction!(asset::open, m)?)?;
    m.add_class::<asset::Asset>()?;
    m.add_class::<asset::Mesh>()?;
    m.add_class::<asset::Clip>()?;
    m.add_class::<frames::Frames>()?;
    m.add_class::<report::Report>()?;
    m.add("RigportError", py.get_type::<errors::RigportError>())?;
    m.add("InputError", py.get_type::<errors::InputError>())?;
    m.add("UsageError", py.get_type::<errors::UsageError>())?;
    m.add("OutputError", py.get_type::<errors::OutputError>())?;
    m.add("RigportWarning", py.get_type::<errors::RigportWarning>())?;
    commands::register(m)?;
    Ok(())
}
