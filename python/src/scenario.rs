//! Scenarios from Python: `run_scenario` (with a Python function as a closed loop's planner), a scenario's
//! `Truth` and `score`, another mapper's arrays judged against it.

use std::path::{Path, PathBuf};

use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::*;
use crate::{interruptible, oeg_error};

/// A Python function as a closed-loop run's planner: called with the map's layers over the region (a dict
/// of `(num_y, num_x)` arrays, and `extent`), the start and the goal; it returns a `(k, 2)` path, or `None`
/// for no path. Its exceptions are the run's `planner_failed` events.
struct PyPlanner(Py<PyAny>);

impl oeg_eval::navigation::PlannerCallback for PyPlanner {
    fn plan(&self, r: &oeg_eval::navigation::PlanRequest<'_>) -> Result<Option<Vec<(f64, f64)>>, String> {
        Python::attach(|py| {
            let call = || -> PyResult<Option<Vec<(f64, f64)>>> {
                let layers = PyDict::new(py);
                let codes = r.decisions.iter().map(|t| *t as u8).collect();
                layers.set_item("decisions", grid(py, &r.region, codes)?)?;
                for (kind, ..) in oeg::PLANNER_FLOAT_LAYERS {
                    let layer = r.map.layer(kind, r.region).map_err(oeg_error)?;
                    layers.set_item(kind.name(), grid(py, &r.region, layer.values)?)?;
                }
                let [x0, x1, y0, y1] = r.extent;
                layers.set_item("extent", (x0, x1, y0, y1))?;
                let path = self.0.call1(py, (layers, r.start, r.goal))?;
                let path = path.bind(py);
                if path.is_none() {
                    return Ok(None);
                }
                let flat = match float_rows("the planner's path", path, Some(2)) {
                    Ok(flat) => flat,
                    // A list of (x, y) pairs serves as well as an array.
                    Err(e) => match path.extract::<Vec<(f64, f64)>>() {
                        Ok(points) => return Ok(Some(points)),
                        Err(_) => return Err(e),
                    },
                };
                Ok(Some(flat.chunks(2).map(|p| (p[0], p[1])).collect()))
            };
            call().map_err(|e| e.to_string())
        })
    }
}

/// A run's metrics, its obstacles' rows, its failed expectations and its output folder.
type RunResult<'py> = (Bound<'py, PyAny>, Bound<'py, PyAny>, Vec<String>, String);

/// Runs a scenario as `oeg run` does; returns its metrics (a dict, as `metrics.json`), its obstacles' rows (as
/// `obstacles.csv`, a list of dicts), the failed expectations and the output folder.
#[pyfunction]
#[pyo3(signature = (path, overrides, out=None, seed=None, compare=None, planner=None))]
pub(crate) fn run_scenario<'py>(
    py: Python<'py>,
    path: PathBuf,
    overrides: &Bound<'_, PyAny>,
    out: Option<PathBuf>,
    seed: Option<u64>,
    compare: Option<String>,
    planner: Option<Py<PyAny>>,
) -> PyResult<RunResult<'py>> {
    existing(&path)?;
    let overrides = scenario_overrides(overrides)?;
    let compare = compare
        .map(|c| {
            c.parse::<oeg::MapPreset>()
                .map_err(|e| PyValueError::new_err(format!("compare: {e}")))
        })
        .transpose()?;
    let options = oeg_eval::pipeline::RunOptions {
        scenario: path,
        out_dir: out,
        seed,
        overrides,
        compare,
        planner_callback: planner.map(|f| {
            oeg_eval::navigation::SharedPlanner(std::sync::Arc::new(PyPlanner(f)) as std::sync::Arc<_>)
        }),
        ..Default::default()
    };
    let report = interruptible(py, |progress| {
        oeg_eval::pipeline::run_scenario(&options, progress)
    })?;
    let failed = report.failed.iter().map(ToString::to_string).collect();
    Ok((
        py_object(py, &report.metrics)?,
        py_object(py, &report.obstacles)?,
        failed,
        report.out_dir.display().to_string(),
    ))
}

/// A scenario's truth, as `oeg run` judges a map against it ([`oeg_eval::scoring::ScoringTruth`]).
#[pyclass(name = "Truth", module = "oeg._oeg", frozen)]
pub(crate) struct PyTruth {
    inner: oeg_eval::scoring::ScoringTruth,
}

#[pymethods]
impl PyTruth {
    /// The scenario's name.
    #[getter]
    fn scenario(&self) -> String {
        self.inner.scenario.name.clone()
    }

    /// Cell size, metres.
    #[getter]
    fn resolution_m(&self) -> f64 {
        self.inner.raster.window.resolution_m()
    }

    /// `(x_min, x_max, y_min, y_max)` of the region, metres.
    #[getter]
    fn extent(&self) -> Extent {
        extent(&self.inner.raster.window)
    }

    /// Whether the observability layers exist.
    #[getter]
    fn has_observability(&self) -> bool {
        self.inner.observability.is_some()
    }

    /// The robot's decision profile.
    #[getter]
    fn robot<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py_object(py, &self.inner.raster.profile)
    }

    /// The truth's layers as `(num_y, num_x)` arrays, row 0 the min-y row.
    fn layers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        use oeg_eval::judge::verdict::TruthClass;
        let t = &self.inner.raster;
        let region = t.window.region();
        let out = PyDict::new(py);
        let cells = &t.cells;
        let layers: [(&str, Vec<f32>); 4] = [
            ("elevation_m", cells.iter().map(|c| c.elevation_m).collect()),
            ("ground_m", cells.iter().map(|c| c.ground_m).collect()),
            ("step_m", cells.iter().map(|c| c.step_m).collect()),
            ("clearance_m", cells.iter().map(|c| c.structure_gap_m).collect()),
        ];
        for (name, values) in layers {
            out.set_item(name, grid(py, region, values)?)?;
        }
        out.set_item(
            "step_blocked",
            grid(py, region, t.cells.iter().map(|c| c.step_blocked).collect())?,
        )?;
        let classes: Vec<TruthClass> = (0..t.cells.len()).map(|k| TruthClass::of(t, k)).collect();
        out.set_item(
            "truly_blocked",
            grid(py, region, classes.iter().map(|c| c.is_blocked()).collect())?,
        )?;
        out.set_item(
            "truth_class",
            grid(py, region, classes.iter().map(|c| *c as u8).collect())?,
        )?;
        if let Some(o) = &self.inner.observability {
            out.set_item("observed_step", grid(py, region, o.step.clone())?)?;
            out.set_item("observed_clearance", grid(py, region, o.clearance.clone())?)?;
            out.set_item("observed_band_hit", grid(py, region, o.band_hit.clone())?)?;
        }
        Ok(out)
    }
}

/// The truth of a scenario; with `observability`, its scripted drive is simulated with its sensors.
#[pyfunction]
#[pyo3(signature = (path, overrides, seed=None, observability=true))]
pub(crate) fn truth(
    py: Python<'_>,
    path: PathBuf,
    overrides: &Bound<'_, PyAny>,
    seed: Option<u64>,
    observability: bool,
) -> PyResult<PyTruth> {
    existing(&path)?;
    let overrides = scenario_overrides(overrides)?;
    let options = oeg_eval::pipeline::RunOptions {
        scenario: path,
        seed,
        overrides,
        ..Default::default()
    };
    let inner = interruptible(py, |progress| {
        let loaded = oeg_eval::pipeline::load(&options)?;
        oeg_eval::scoring::ScoringTruth::of(&loaded, observability, progress)
    })?;
    Ok(PyTruth { inner })
}

/// Scores another mapper's arrays against `truth`; returns its metrics (a dict), the obstacles' rows and the
/// plan's rows (lists of dicts).
#[pyfunction]
#[pyo3(signature = (truth, decisions, origin, resolution_m, elevation=None, variance=None, occupancy=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn score<'py>(
    py: Python<'py>,
    truth: &PyTruth,
    decisions: &Bound<'_, PyAny>,
    origin: (f64, f64),
    resolution_m: f64,
    elevation: Option<&Bound<'_, PyAny>>,
    variance: Option<&Bound<'_, PyAny>>,
    occupancy: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let codes = decisions
        .cast::<PyArray2<i64>>()
        .map_err(|_| PyTypeError::new_err("decisions: expected a 2D int64 numpy array of decision codes"))?;
    let ro = codes.readonly();
    let (rows, cols) = (ro.shape()[0], ro.shape()[1]);
    let codes: Vec<i64> = collected("decisions", ro.as_array().iter().copied())?;
    let decisions = oeg_eval::judge::estimate::decisions_from_codes(&codes)
        .map_err(|e| PyValueError::new_err(format!("decisions: {e}")))?;
    let shape = (rows, cols);
    let elevation_m = float_grid("elevation", elevation, shape)?;
    let variance_m2 = float_grid("variance", variance, shape)?;
    let occupancy = float_grid("occupancy", occupancy, shape)?;
    let foreign = oeg_eval::judge::estimate::ForeignMap {
        origin_xy_m: [origin.0, origin.1],
        resolution_m,
        rows,
        cols,
        decisions,
        elevation_m,
        variance_m2,
        occupancy,
    };
    foreign
        .check(Path::new("the arrays"), [None; 3])
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let evaluation = py.detach(|| truth.inner.score(&foreign)).map_err(oeg_error)?;
    let geometry = *evaluation.estimate.window.geometry();
    let plan = oeg_eval::judge::plan_check::rows(&evaluation.plan, &geometry);
    Ok((
        py_object(py, &evaluation.metrics)?,
        py_object(py, &evaluation.obstacles)?,
        py_object(py, &plan)?,
    ))
}
