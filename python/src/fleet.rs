//! Plain-data task functions of fleet studies (`absorber.fleet`): a scene (dict, TOML text,
//! path or built-in name), a seed and a duration in; numpy arrays and a summary out. The GIL is
//! released while the record runs, so threads of one process run records in parallel too.

use crate::{error, interruptible, load_scene, to_py};
use absorber_sim::fleet::{self, Absorber};
use absorber_sim::scene::Scene;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyString;

/// A scene from TOML text (a string with a newline or a `[section]`), or as `load_scene`.
fn scene_of(scene: &Bound<'_, PyAny>) -> PyResult<Scene> {
    if let Ok(s) = scene.cast::<PyString>() {
        let text: String = s.extract()?;
        if text.contains('\n') || text.trim_start().starts_with('[') {
            return Scene::from_toml(&text).map_err(|e| error(format!("scene text: {e:#}")));
        }
    }
    load_scene(scene)
}

/// One record: `(names, arrays, summary JSON, histogram)`.
#[pyfunction]
#[pyo3(signature = (scene, seed, duration, absorber="none", every=10))]
#[allow(clippy::type_complexity)]
pub fn fleet_record<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    seed: u64,
    duration: f64,
    absorber: &str,
    every: usize,
) -> PyResult<(
    Vec<&'static str>,
    Vec<Bound<'py, PyArray1<f64>>>,
    String,
    Bound<'py, PyArray1<u64>>,
)> {
    let s = scene_of(scene)?;
    let a = Absorber::from_name(absorber).map_err(to_py)?;
    let r = interruptible(py, || fleet::record(&s, seed, duration, a, every))?.map_err(to_py)?;
    let summary = serde_json::to_string(&r).map_err(|e| error(e.to_string()))?;
    let names = vec!["time", "root_stress", "tip_deflection"];
    let arrays = vec![
        PyArray1::from_vec(py, r.time),
        PyArray1::from_vec(py, r.root_stress),
        PyArray1::from_vec(py, r.tip_deflection),
    ];
    Ok((names, arrays, summary, PyArray1::from_vec(py, r.histogram)))
}

/// The reduced arm's lowest natural frequencies \[Hz\] with `absorber`.
#[pyfunction]
#[pyo3(signature = (scene, absorber="none"))]
pub fn fleet_frequencies<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    absorber: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let s = scene_of(scene)?;
    let a = Absorber::from_name(absorber).map_err(to_py)?;
    let f = interruptible(py, || fleet::frequencies(&s, a))?.map_err(to_py)?;
    Ok(PyArray1::from_vec(py, f))
}

/// Registers the functions and the histogram's bins.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("FLEET_RANGE_BIN", fleet::RANGE_BIN)?;
    m.add("FLEET_RANGE_BINS", fleet::RANGE_BINS)?;
    m.add_function(wrap_pyfunction!(fleet_record, m)?)?;
    m.add_function(wrap_pyfunction!(fleet_frequencies, m)?)?;
    Ok(())
}
