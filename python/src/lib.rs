//! `absorber._absorber`: the native half of the Python package `absorber`.
//!
//! Thin on purpose: every function loads the scene the way the command line does
//! (`absorber_sim::scene::Scene::load`, `Overrides::apply` for the overrides) and calls the same
//! library function as the command (`absorber_sim::simulate::run_in_memory`, `static_summary`,
//! `lowest_frequencies`, `sweep_in_memory`), so Python and the CLI give the same numbers. The
//! typed, documented API is `absorber/__init__.py`; errors become `absorber.AbsorberError`
//! (a `ValueError`) with the offending field in its `field` attribute.

mod fleet;

use absorber_sim::scene::{Overrides, Scene};
use absorber_sim::simulate;
use numpy::PyArray1;
use pyo3::create_exception;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

create_exception!(
    _absorber,
    AbsorberError,
    PyValueError,
    "A bad scene, parameter or option (`field` names it when there is one), or a run that failed."
);

/// The first `quoted` name in a message (`invalid value for `beam.modulus`: …`).
fn field_of(message: &str) -> Option<String> {
    let mut parts = message.split('`');
    parts.next()?;
    // A keyword argument is spelled `name=` in the messages; its field is `name`.
    parts
        .next()
        .map(|f| f.strip_suffix('=').unwrap_or(f).to_string())
}

/// An `AbsorberError` with its `field` attribute set from the message.
fn error(message: String) -> PyErr {
    let field = field_of(&message);
    let err = AbsorberError::new_err(message);
    Python::attach(|py| {
        let _ = err.value(py).setattr("field", field);
    });
    err
}

fn to_py(e: anyhow::Error) -> PyErr {
    error(format!("{e:#}"))
}

/// Deepest nesting of dicts and lists in a scene dictionary: a scene nests three levels
/// (`[[arm.heads]]`: a list of tables in a table); deeper is a mistake, and a structure that
/// holds itself would never end.
const MAX_SCENE_DEPTH: usize = 8;

/// Runs `f` (a computation of host-sim) on a worker thread while this thread, holding the GIL
/// between naps of 50 ms, checks Python's signals: Ctrl-C asks the computation to stop
/// ([`absorber_sim::interrupt`], read every 500 steps) and raises `KeyboardInterrupt` here once it
/// has (within a second), before any result reaches Python. The worker has the stack the
/// command line's threads have (the full solver's frames are large); a panic in it is an
/// `AbsorberError`, never an abort.
fn interruptible<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    absorber_sim::interrupt::reset();
    std::thread::scope(|scope| {
        let worker = std::thread::Builder::new()
            .name("absorber".into())
            .stack_size(64 << 20)
            .spawn_scoped(scope, f)
            .map_err(|e| error(format!("cannot start the computation's thread: {e}")))?;
        let mut signal = Ok(());
        while !worker.is_finished() {
            if signal.is_ok() {
                signal = py.check_signals();
                if signal.is_err() {
                    absorber_sim::interrupt::raise();
                }
            }
            py.detach(|| std::thread::sleep(std::time::Duration::from_millis(50)));
        }
        let value = py
            .detach(|| worker.join())
            .map_err(|_| error("internal error: the computation panicked".into()))?;
        signal?;
        Ok(value)
    })
}

/// A whole-number argument `key` of at least `min` (a negative one is named, not an
/// `OverflowError`).
fn whole(v: i64, key: &str, min: i64) -> PyResult<usize> {
    if v < min {
        return Err(error(format!(
            "invalid value for `{key}`: {v} (must be at least {min})"
        )));
    }
    usize::try_from(v).map_err(|_| error(format!("invalid value for `{key}`: {v} (too large)")))
}

/// A Python value of a scene dictionary as TOML.
fn toml_value(v: &Bound<'_, PyAny>, key: &str, depth: usize) -> PyResult<toml::Value> {
    if depth > MAX_SCENE_DEPTH {
        return Err(error(format!(
            "invalid value for `{}`: the scene dictionary nests deeper than {MAX_SCENE_DEPTH} levels (allowed: at most {MAX_SCENE_DEPTH}; does it contain itself?)",
            key.split('.').take(MAX_SCENE_DEPTH).collect::<Vec<_>>().join(".")
        )));
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(toml::Value::Table(toml_table(d, key, depth + 1)?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let mut a = Vec::new();
        for x in v.try_iter()? {
            a.push(toml_value(&x?, key, depth + 1)?);
        }
        return Ok(toml::Value::Array(a));
    }
    if v.hasattr("__fspath__")? {
        return Ok(toml::Value::String(
            v.call_method0("__fspath__")?.extract()?,
        ));
    }
    Err(error(format!(
        "invalid value for `{key}`: a `{}` cannot go into a scene (allowed: numbers, strings, booleans, lists, dicts)",
        v.get_type().name()?
    )))
}

fn toml_table(d: &Bound<'_, PyDict>, prefix: &str, depth: usize) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let k: String = k
            .extract()
            .map_err(|_| PyTypeError::new_err("scene dictionary keys must be strings"))?;
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        t.insert(k, toml_value(&v, &path, depth)?);
    }
    Ok(t)
}

/// A scene from a built-in name, a TOML path (str or os.PathLike) or a dict of scene keys (the
/// TOML file's, unset keys at the paper's values).
fn load_scene(scene: &Bound<'_, PyAny>) -> PyResult<Scene> {
    if let Ok(d) = scene.cast::<PyDict>() {
        let text = toml::to_string(&toml_table(d, "", 1)?)
            .map_err(|e| error(format!("scene dictionary: {e}")))?;
        return Scene::from_toml(&text).map_err(to_py);
    }
    let spec: String = if scene.is_instance_of::<PyString>() {
        scene.extract()?
    } else if scene.hasattr("__fspath__")? {
        scene.call_method0("__fspath__")?.extract()?
    } else {
        return Err(PyTypeError::new_err(
            "scene must be a built-in name (\"paper\"), a path to a TOML file or a dict",
        ));
    };
    Scene::load(&spec).map_err(to_py)
}

fn parse_enum<E: clap::ValueEnum>(v: &Bound<'_, PyAny>, key: &str) -> PyResult<E> {
    let s: String = v
        .extract()
        .map_err(|_| error(format!("invalid value for `{key}`: not a string")))?;
    E::from_str(&s, true).map_err(|_| {
        let allowed: Vec<String> = E::value_variants()
            .iter()
            .filter_map(|x| x.to_possible_value().map(|p| p.get_name().to_string()))
            .collect();
        error(format!(
            "invalid value for `{key}`: {s:?} (allowed: {})",
            allowed.join(", ")
        ))
    })
}

fn number<T: for<'a, 'py> FromPyObject<'a, 'py>>(v: &Bound<'_, PyAny>, key: &str) -> PyResult<T> {
    v.extract::<T>().map_err(|_| {
        error(format!(
            "invalid value for `{key}`: {v} (not a number of the right kind)"
        ))
    })
}

/// The scene with the command line's overrides (`solver`, `kind`, `elements`, `precision`,
/// `frequency`, `amplitude`, `duration`, `step`), validated.
fn scene_with(scene: &Bound<'_, PyAny>, overrides: Option<&Bound<'_, PyDict>>) -> PyResult<Scene> {
    let s = load_scene(scene)?;
    let mut a = Overrides::default();
    if let Some(o) = overrides {
        for (k, v) in o.iter() {
            let k: String = k.extract()?;
            match k.as_str() {
                "solver" => a.solver = Some(parse_enum(&v, &k)?),
                "kind" => a.kind = Some(parse_enum(&v, &k)?),
                "precision" => a.precision = Some(parse_enum(&v, &k)?),
                "elements" => a.elements = Some(number(&v, &k)?),
                "frequency" => a.frequency = Some(number(&v, &k)?),
                "amplitude" => a.amplitude = Some(number(&v, &k)?),
                "duration" => a.duration = Some(number(&v, &k)?),
                "step" => a.step = Some(number(&v, &k)?),
                other => {
                    return Err(error(format!(
                        "invalid value for `{other}`: unknown override (allowed: solver, kind, elements, \
                         precision, frequency, amplitude, duration, step; other scene keys go in a scene dict)"
                    )))
                }
            }
        }
    }
    a.apply(s).map_err(to_py)
}

/// The scene's warnings (poorly resolved excitation), as the command line prints them.
fn warnings(s: &Scene) -> Vec<String> {
    s.warnings()
}

/// `run`: (column names, columns, summary JSON, warnings); with `ensemble` > 1 the columns are
/// member 0's and the summary's statistics are over the members (`run --ensemble`).
#[pyfunction]
#[pyo3(signature = (scene, overrides=None, transient=None, every=None, ensemble=1, seed=1))]
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    overrides: Option<&Bound<'py, PyDict>>,
    transient: Option<f64>,
    every: Option<i64>,
    ensemble: i64,
    seed: u64,
) -> PyResult<(
    Vec<&'static str>,
    Vec<Bound<'py, PyArray1<f64>>>,
    String,
    Vec<String>,
)> {
    let every = every.map(|n| whole(n, "every", 1)).transpose()?;
    let ensemble = whole(ensemble, "ensemble", 1)?;
    let s = scene_with(scene, overrides)?;
    let w = warnings(&s);
    let e = absorber_sim::ensemble::Ensemble::new(ensemble, seed).map_err(to_py)?;
    let (rows, summary) = interruptible(py, || {
        if e.is_ensemble() {
            simulate::run_ensemble_in_memory(&s, transient, every, e)
        } else {
            simulate::run_in_memory(&s, transient, every)
        }
    })?
    .map_err(to_py)?;
    let names = absorber_sim::run::csv_columns();
    let mut columns = vec![Vec::with_capacity(rows.len()); names.len()];
    for r in &rows {
        for (c, x) in columns.iter_mut().zip(r.values()) {
            c.push(x);
        }
    }
    let arrays = columns
        .into_iter()
        .map(|c| PyArray1::from_vec(py, c))
        .collect();
    Ok((names, arrays, summary.to_string(), w))
}

/// `static`: the summary JSON of `static --json`.
#[pyfunction]
#[pyo3(signature = (scene, overrides=None))]
fn static_summary(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<String> {
    let s = scene_with(scene, overrides)?;
    interruptible(py, || simulate::static_summary(&s))?
        .map(|v| v.to_string())
        .map_err(to_py)
}

/// `modes`: the lowest `count` natural frequencies \[Hz\].
#[pyfunction]
#[pyo3(signature = (scene, overrides=None, count=4))]
fn modes<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    overrides: Option<&Bound<'py, PyDict>>,
    count: i64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let count = whole(count, "count", 1)?;
    let s = scene_with(scene, overrides)?;
    let f = interruptible(py, || simulate::lowest_frequencies(&s, count))?.map_err(to_py)?;
    Ok(PyArray1::from_vec(py, f))
}

/// `sweep`: `{"points": [...], "locked": [...]}` as JSON: one object per frequency (`error`
/// set on a failed one), with `ensemble` > 1 every number of a point `{"mean", "sd", "min",
/// "max", "k"}` over the members; `locked` the same frequencies with the ball locked (one run
/// each, as the command's table, CSV and JSON; empty without a free ball).
#[pyfunction]
#[pyo3(signature = (scene, overrides=None, freqs=None, last=None, jobs=None, ensemble=1, seed=1))]
#[allow(clippy::too_many_arguments)]
fn sweep(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    overrides: Option<&Bound<'_, PyDict>>,
    freqs: Option<Vec<f64>>,
    last: Option<f64>,
    jobs: Option<i64>,
    ensemble: i64,
    seed: u64,
) -> PyResult<String> {
    if freqs.as_ref().is_some_and(Vec::is_empty) {
        return Err(error(
            "invalid value for `freqs`: [] (allowed: at least one frequency [Hz])".into(),
        ));
    }
    let jobs = jobs.map(|n| whole(n, "jobs", 1)).transpose()?;
    let ensemble = whole(ensemble, "ensemble", 1)?;
    let s = scene_with(scene, overrides)?;
    let e = absorber_sim::ensemble::Ensemble::new(ensemble, seed).map_err(to_py)?;
    let text = interruptible(py, || -> anyhow::Result<String> {
        let f = freqs.as_deref();
        let (points, locked) = if e.is_ensemble() {
            let (p, l) = simulate::sweep_ensemble_in_memory(&s, f, last, jobs, e)?;
            (serde_json::to_value(p)?, l)
        } else {
            let (p, l) = simulate::sweep_in_memory(&s, f, last, jobs)?;
            (serde_json::to_value(p)?, l)
        };
        Ok(serde_json::json!({ "points": points, "locked": locked }).to_string())
    })?
    .map_err(to_py)?;
    Ok(text)
}

/// The scene as TOML text (after the overrides): what a scene file for it would hold.
#[pyfunction]
#[pyo3(signature = (scene, overrides=None))]
fn scene_toml(scene: &Bound<'_, PyAny>, overrides: Option<&Bound<'_, PyDict>>) -> PyResult<String> {
    scene_with(scene, overrides)?.to_toml().map_err(to_py)
}

#[pymodule]
fn _absorber(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Messages name options as this package's keyword arguments (`transient=`, `last=`).
    absorber_sim::output::spell_options_for_python();
    m.add("AbsorberError", m.py().get_type::<AbsorberError>())?;
    m.add("CSV_COLUMNS", absorber_sim::run::csv_columns())?;
    m.add("SWEEP_COLUMNS", absorber_sim::sweep::csv_columns())?;
    m.add("BUILT_IN_SCENES", absorber_sim::scene::BUILT_IN.to_vec())?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(static_summary, m)?)?;
    m.add_function(wrap_pyfunction!(modes, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(scene_toml, m)?)?;
    fleet::register(m)?;
    Ok(())
}
