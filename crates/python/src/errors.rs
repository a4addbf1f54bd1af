//! rigport's errors and warnings as Python sees them: [`PipelineError`] becomes
//! `rigport.InputError` (with `path`, `line`, `location`), `rigport.UsageError` or
//! `rigport.OutputError` (with `path`), the exit codes 1, 2 and 3 of the CLI; warnings go
//! through Python's `warnings` module as `rigport.RigportWarning` (with `code`, `name`).

use std::sync::Mutex;

use pyo3::exceptions::{PyException, PyUserWarning};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rigport_model::Warning;
use rigport_pipeline::PipelineError;
use rigport_pipeline::progress::{Denied, Progress};

pyo3::create_exception!(
    rigport,
    RigportError,
    PyException,
    "The base of rigport's errors; `str(e)` is the message the CLI prints."
);
pyo3::create_exception!(
    rigport,
    InputError,
    RigportError,
    "An input cannot be read or does not make what was asked (the CLI's exit code 1). \
     `path` (str or None) is the file, `line` (int or None) its 1-based line, `location` \
     (str or None) the place as printed (`walk.bvh:12:5`, `a.gltf: at /skins/0`)."
);
pyo3::create_exception!(
    rigport,
    UsageError,
    RigportError,
    "The request cannot be carried out as given: an option's value, an output extension \
     rigport does not write, an output that is one of the inputs (the CLI's exit code 2)."
);
pyo3::create_exception!(
    rigport,
    OutputError,
    RigportError,
    "An output cannot be written (the CLI's exit code 3); `path` is the output."
);
pyo3::create_exception!(
    rigport,
    RigportWarning,
    PyUserWarning,
    "Something lossy or repaired (dropped influences, renormalized weights, ...); `code` is \
     its stable code (`W001`...) and `name` its kebab-case name, as the CLI prints them."
);

/// A `rigport.UsageError` with `message`.
pub fn usage(message: impl Into<String>) -> PyErr {
    UsageError::new_err(message.into())
}

/// `err` as the Python exception of its class, its message the CLI's (causes joined by
/// `: `), with the attributes of its class set.
pub fn to_py(py: Python<'_>, err: &PipelineError) -> PyErr {
    let message = rigport_pipeline::chain(err);
    if err.is_usage() {
        UsageError::new_err(message)
    } else if let PipelineError::Output { path, .. } = err {
        let e = OutputError::new_err(message);
        set(py, &e, "path", path.as_str());
        e
    } else {
        let e = InputError::new_err(message);
        let location = match err {
            PipelineError::Import(e) => Some(&*e.location),
            PipelineError::Json(e) => Some(&*e.location),
            _ => None,
        };
        set(
            py,
            &e,
            "path",
            location.map(|l| l.path.display().to_string()),
        );
        set(py, &e, "line", location.and_then(|l| l.line));
        set(py, &e, "location", location.map(|l| l.to_string()));
        e
    }
}

/// Sets attribute `name` of the exception `e` (an attribute the class documents).
fn set<'py, T: IntoPyObject<'py>>(py: Python<'py>, e: &PyErr, name: &str, value: T) {
    // Setting an attribute of a fresh exception instance cannot fail but for memory.
    let _ = e.value(py).setattr(name, value);
}

/// The [`Progress`] of a Python call: warnings go to Python's `warnings` module (a filter
/// that turns them into errors refuses them, and nothing is written: the CLI's
/// deny-warnings), notes are kept for the caller, steps are not shown.
#[derive(Default)]
pub struct PyProgress {
    /// The exception a warning filter raised, re-raised when the call returns.
    raised: Mutex<Option<PyErr>>,
    /// The warnings already given to Python (by `open`), not given again by a write.
    shown: Vec<String>,
    /// The notes (`N001`) met.
    pub notes: Mutex<Vec<String>>,
}

impl PyProgress {
    /// A progress that does not repeat `shown` (warnings given to Python before).
    pub fn after(shown: &[Warning]) -> Self {
        Self {
            shown: shown.iter().map(Warning::labelled).collect(),
            ..Self::default()
        }
    }

    /// `err` as a Python exception: the one a warning filter raised if it refused the
    /// warnings, else [`to_py`].
    pub fn error(&self, py: Python<'_>, err: &PipelineError) -> PyErr {
        if let PipelineError::Denied(_) = err {
            if let Some(raised) = self.raised.lock().ok().and_then(|mut r| r.take()) {
                return raised;
            }
        }
        to_py(py, err)
    }
}

impl Progress for PyProgress {
    fn warnings(&self, warnings: &[Warning]) -> Result<(), Denied> {
        let fresh: Vec<&Warning> = warnings
            .iter()
            .filter(|w| !self.shown.contains(&w.labelled()))
            .collect();
        if let Ok(mut notes) = self.notes.lock() {
            notes.extend(fresh.iter().filter(|w| w.is_note()).map(|w| w.labelled()));
        }
        let fresh: Vec<&Warning> = fresh.into_iter().filter(|w| !w.is_note()).collect();
        if fresh.is_empty() {
            return Ok(());
        }
        Python::attach(|py| match warn(py, &fresh) {
            Ok(()) => Ok(()),
            Err(e) => {
                if let Ok(mut raised) = self.raised.lock() {
                    *raised = Some(e);
                }
                Err(Denied { count: fresh.len() })
            }
        })
    }
}

/// Gives `warnings` to Python's `warnings.warn`, each a `rigport.RigportWarning` with its
/// code and name.
///
/// # Errors
/// A warning filter turned one into an exception.
pub fn warn(py: Python<'_>, warnings: &[&Warning]) -> PyResult<()> {
    let module = py.import("warnings")?;
    for w in warnings {
        let instance = py.get_type::<RigportWarning>().call1((w.labelled(),))?;
        instance.setattr("code", w.code())?;
        instance.setattr("name", w.name())?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("stacklevel", 2)?;
        module.call_method("warn", (instance,), Some(&kwargs))?;
    }
    Ok(())
}
