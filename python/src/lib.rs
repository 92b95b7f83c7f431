//! `imudrift._imudrift`: the compiled half of the Python package `imudrift` (python/imudrift/).
//! Thin: every number comes from the library crates the CLI uses; this crate converts numpy
//! arrays and Python arguments into their types and their errors into Python exceptions.

use pyo3::prelude::*;

/// The module `imudrift._imudrift`.
#[pymodule]
fn _imudrift(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
