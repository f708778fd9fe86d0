//! `zakai._zakai`: the PyO3 adapter under the `zakai` Python package — no maths here.
//!
//! Scenarios cross the boundary as JSON text (the same `ScenarioConfig` the CLI reads, so a
//! Python user's scenario file works in `zakai run` and in the playground), arrays as NumPy
//! `float64` arrays (one copy per call). Every error becomes an exception of
//! `zakai.errors` carrying the CLI's message; nothing panics into Python. The Pythonic surface
//! (docstrings, dataclasses, pandas) is `python/zakai/__init__.py`, over these functions.

use pyo3::prelude::*;

mod arrays;
mod errors;
mod fit;
mod runs;
mod stepping;

/// The compiled core of the `zakai` package (use `import zakai`).
#[pymodule]
fn _zakai(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(runs::presets, m)?)?;
    m.add_function(wrap_pyfunction!(runs::preset_json, m)?)?;
    m.add_function(wrap_pyfunction!(runs::catalogue_json, m)?)?;
    m.add_function(wrap_pyfunction!(runs::noise_kinds_json, m)?)?;
    m.add_function(wrap_pyfunction!(runs::check_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(runs::covering_domain, m)?)?;
    m.add_function(wrap_pyfunction!(runs::domain_from_data, m)?)?;
    m.add_function(wrap_pyfunction!(runs::refuse_coarse_prior_box, m)?)?;
    m.add_function(wrap_pyfunction!(runs::set_memory_cap, m)?)?;
    m.add_function(wrap_pyfunction!(runs::method_defaults_json, m)?)?;
    m.add_function(wrap_pyfunction!(runs::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(runs::run, m)?)?;
    m.add_function(wrap_pyfunction!(runs::filter_recorded, m)?)?;
    m.add_function(wrap_pyfunction!(runs::forecast_recorded, m)?)?;
    m.add_function(wrap_pyfunction!(runs::ljung_box, m)?)?;
    m.add_function(wrap_pyfunction!(runs::pit_uniformity, m)?)?;
    m.add_function(wrap_pyfunction!(runs::monte_carlo_json, m)?)?;
    m.add_function(wrap_pyfunction!(runs::run_json, m)?)?;
    m.add_function(wrap_pyfunction!(runs::monte_carlo_from_runs, m)?)?;
    m.add_function(wrap_pyfunction!(fit::log_likelihood, m)?)?;
    m.add_function(wrap_pyfunction!(fit::scenario_log_likelihood, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(fit::profile, m)?)?;
    m.add_function(wrap_pyfunction!(fit::sample, m)?)?;
    m.add_function(wrap_pyfunction!(fit::prior_density, m)?)?;
    m.add_class::<stepping::Stepper>()?;
    Ok(())
}
