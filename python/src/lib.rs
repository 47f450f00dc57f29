//! `oeg._oeg`: the native half of the `oeg` Python package. It wraps the `oeg` and `oeg-eval` crates and holds
//! no logic of its own: arrays are checked and converted here, everything else is the crates' code. The
//! Python half (`python/oeg/`) turns results into dicts and DataFrames; `python/oeg/_oeg.pyi` types both.
//!
//! Long work (integrating, planning, running a scenario) runs with the GIL released.

use std::path::{Path, PathBuf};

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyFileNotFoundError, PyMemoryError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString};

create_exception!(
    _oeg,
    OegError,
    PyException,
    "A map, scenario or data file the testbed refused: the message names the file, the place and what was expected."
);

fn oeg_error(e: impl std::fmt::Display) -> PyErr {
    OegError::new_err(e.to_string())
}

/// The items of `values` in a vector allocated up front, or `MemoryError` (naming `name`) when the memory is not
/// there: a large array never aborts the interpreter.
fn collected<T>(name: &str, values: impl ExactSizeIterator<Item = T>) -> PyResult<Vec<T>> {
    let mut out = Vec::new();
    out.try_reserve_exact(values.len()).map_err(|_| {
        PyMemoryError::new_err(format!(
            "{name}: {} values of {} bytes do not fit in memory",
            values.len(),
            size_of::<T>()
        ))
    })?;
    out.extend(values);
    Ok(out)
}

/// Refuses a path that does not exist with `FileNotFoundError`, before the crates are asked.
fn existing(path: &Path) -> PyResult<()> {
    if path.exists() {
        Ok(())
    } else {
        Err(PyFileNotFoundError::new_err(format!(
            "{}: no such file or folder",
            path.display()
        )))
    }
}

/// A Python value as a TOML value in an override (`KEY=VALUE`), as the scenario files spell it.
fn toml_literal(key: &str, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if value.is_instance_of::<PyBool>() {
        Ok(value.extract::<bool>()?.to_string())
    } else if value.is_instance_of::<PyInt>() {
        Ok(value.extract::<i64>()?.to_string())
    } else if value.is_instance_of::<PyFloat>() {
        let v = value.extract::<f64>()?;
        if !v.is_finite() {
            return Err(PyValueError::new_err(format!(
                "{key}: {v} is not a finite number"
            )));
        }
        Ok(format!("{v:?}"))
    } else if value.is_instance_of::<PyString>() {
        Ok(serde_json::Value::String(value.extract::<String>()?).to_string())
    } else {
        Err(PyTypeError::new_err(format!(
            "{key}: expected a bool, int, float or str, got {}",
            value.get_type().name()?
        )))
    }
}

/// `--set` overrides from a dict of dotted keys, each under `prefix` when given (`robot`).
fn overrides_of(prefix: Option<&str>, table: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<String>> {
    let mut out = Vec::new();
    if let Some(table) = table {
        for (k, v) in table.iter() {
            let k = k.extract::<String>()?;
            let key = prefix.map_or_else(|| k.clone(), |p| format!("{p}.{k}"));
            out.push(format!("{key}={}", toml_literal(&key, &v)?));
        }
    }
    Ok(out)
}

/// The overrides of a map's `model` argument: a preset's name, or a dict in the scenario file's spelling
/// (`preset` and `traversability` of `[map]`, every other key of `[map.model]`).
fn model_overrides(model: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(model) = model else {
        return Ok(Vec::new());
    };
    if let Ok(name) = model.extract::<String>() {
        return Ok(vec![format!("map.preset={}", serde_json::Value::String(name))]);
    }
    let table = model.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err("model: expected a preset's name (str) or a dict of [map.model] keys")
    })?;
    let mut out = Vec::new();
    for (k, v) in table.iter() {
        let k = k.extract::<String>()?;
        let key = if k == "preset" || k == "traversability" {
            format!("map.{k}")
        } else {
            format!("map.model.{k}")
        };
        out.push(format!("{key}={}", toml_literal(&key, &v)?));
    }
    Ok(out)
}

/// The settings of `oeg map` for these overrides (one resolver, one set of errors).
fn settings(resolution_m: f64, overrides: &[String]) -> PyResult<oeg_eval::settings::MapJobSettings> {
    oeg_eval::settings::map_settings(resolution_m, overrides)
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A float array of shape `(n, cols)` (or `(n,)` when `cols` is `None`), `float32` or `float64`, as f64 rows.
fn float_rows(name: &str, array: &Bound<'_, PyAny>, cols: Option<usize>) -> PyResult<Vec<f64>> {
    let shape_error = |dtype: String, shape: Vec<usize>| {
        PyTypeError::new_err(format!(
            "{name}: expected a float32 or float64 numpy array of shape {}, got dtype {dtype} and shape {shape:?}",
            cols.map_or("(n,)".to_string(), |c| format!("(n, {c})"))
        ))
    };
    let ndim = cols.map_or(1, |_| 2);
    macro_rules! rows_of {
        ($t:ty) => {
            if let Ok(a) = array.cast::<numpy::PyArrayDyn<$t>>() {
                let shape = a.shape().to_vec();
                if shape.len() != ndim || cols.is_some_and(|c| shape[1] != c) {
                    return Err(shape_error(stringify!($t).replace("f", "float"), shape));
                }
                let ro = a.readonly();
                // A C-contiguous array is read in place; any other layout is copied once.
                return collected(name, ro.as_array().iter().map(|v| f64::from(*v)));
            }
        };
    }
    rows_of!(f64);
    rows_of!(f32);
    let (dtype, shape) = match array.cast::<numpy::PyUntypedArray>() {
        Ok(a) => (a.dtype().to_string(), a.shape().to_vec()),
        Err(_) => (array.get_type().name()?.to_string(), Vec::new()),
    };
    Err(shape_error(dtype, shape))
}

/// An optional per-ray array of `bool` of length `n`.
fn bool_column(name: &str, array: Option<&Bound<'_, PyAny>>, n: usize) -> PyResult<Vec<bool>> {
    let Some(array) = array else {
        return Ok(vec![false; n]);
    };
    let a = array.cast::<PyArray1<bool>>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name}: expected a numpy array of dtype bool and shape ({n},)"
        ))
    })?;
    let values: Vec<bool> = collected(name, a.readonly().as_array().iter().copied())?;
    if values.len() != n {
        return Err(PyValueError::new_err(format!(
            "{name}: {} values for {n} points",
            values.len()
        )));
    }
    Ok(values)
}

/// A scenario's overrides: a dict of dotted keys (values as Python scalars) or a list of `KEY=VALUE`
/// strings, as `--set` takes them.
fn scenario_overrides(overrides: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    match overrides.cast::<PyDict>() {
        Ok(table) => overrides_of(None, Some(table)),
        Err(_) => overrides.extract::<Vec<String>>().map_err(|_| {
            PyTypeError::new_err("overrides: expected a dict of dotted keys or a list of KEY=VALUE strings")
        }),
    }
}

/// A 3-vector of finite floats.
fn xyz(name: &str, value: &Bound<'_, PyAny>) -> PyResult<[f64; 3]> {
    let v: Vec<f64> = value
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("{name}: expected three floats (x, y, z) in metres")))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(PyValueError::new_err(format!(
            "{name}: expected three finite floats (x, y, z) in metres, got {v:?}"
        ))),
    }
}

/// `(x_min, x_max, y_min, y_max)` of a region, metres: `matplotlib.pyplot.imshow(extent=...)`.
fn extent(window: &oeg::GridWindow) -> Extent {
    let [x0, x1, y0, y1] = oeg_eval::navigation::external::extent_of(window);
    (x0, x1, y0, y1)
}

/// `(x_min, x_max, y_min, y_max)` in metres.
type Extent = (f64, f64, f64, f64);

/// A layer as a 2D array with its extent.
type Grid<'py, T> = (Bound<'py, PyArray2<T>>, Extent);

/// A 2D array of a raster's values: `num_y` rows from the min-y row, `num_x` columns.
fn grid<'py, T: numpy::Element>(
    py: Python<'py>,
    region: &oeg::CellRegion,
    values: Vec<T>,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let shape = (region.num_y as usize, region.num_x as usize);
    let array = Array2::from_shape_vec(shape, values).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(array.into_pyarray(py))
}

/// The Occupancy-Elevation Grid.
#[pyclass(name = "Map", module = "oeg._oeg")]
struct PyMap {
    map: oeg::Map,
    settings: oeg_eval::settings::MapJobSettings,
}

#[pymethods]
impl PyMap {
    #[new]
    #[pyo3(signature = (resolution_m, model=None, memory_limit_bytes=None))]
    fn new(
        resolution_m: f64,
        model: Option<&Bound<'_, PyAny>>,
        memory_limit_bytes: Option<u64>,
    ) -> PyResult<Self> {
        let settings = settings(resolution_m, &model_overrides(model)?)?;
        let config = oeg::MapConfig {
            resolution_m: settings.map.resolution_m,
            model: settings.map.model,
            memory_limit_bytes: memory_limit_bytes.unwrap_or(oeg::DEFAULT_MEMORY_LIMIT_BYTES),
        };
        let map = oeg::Map::new(config).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(Self { map, settings })
    }

    #[getter]
    fn resolution_m(&self) -> f64 {
        self.map.geometry().resolution_m()
    }

    #[getter]
    fn num_scans(&self) -> u64 {
        self.map.num_scans()
    }

    #[getter]
    fn model(&self) -> PyResult<String> {
        serde_json::to_string(&self.map.config().model).map_err(oeg_error)
    }

    #[pyo3(signature = (origin_xyz, points_xyz, no_return=None, range_variance_m2=None, sensor="laser"))]
    fn integrate(
        &mut self,
        py: Python<'_>,
        origin_xyz: &Bound<'_, PyAny>,
        points_xyz: &Bound<'_, PyAny>,
        no_return: Option<&Bound<'_, PyAny>>,
        range_variance_m2: Option<&Bound<'_, PyAny>>,
        sensor: &str,
    ) -> PyResult<(u64, u64, u64)> {
        let origin = xyz("origin_xyz", origin_xyz)?;
        let points = float_rows("points_xyz", points_xyz, Some(3))?;
        let n = points.len() / 3;
        let no_return = bool_column("no_return", no_return, n)?;
        let variances = match range_variance_m2 {
            Some(v) => Some(float_rows("range_variance_m2", v, None)?),
            None => None,
        };
        if let Some(v) = &variances
            && v.len() != n
        {
            return Err(PyValueError::new_err(format!(
                "range_variance_m2: {} values for {n} points",
                v.len()
            )));
        }
        let model = match sensor {
            "laser" => oeg_eval::settings::RangeModel::Laser.model(),
            "stereo" => oeg_eval::settings::RangeModel::Stereo.model(),
            other => {
                return Err(PyValueError::new_err(format!(
                    "sensor: expected \"laser\" or \"stereo\", got {other:?}"
                )));
            }
        };
        let o = nalgebra::Point3::new(origin[0], origin[1], origin[2]);
        let mut scan = oeg::Scan::new(o, model);
        scan.rays
            .try_reserve_exact(n)
            .map_err(|_| PyMemoryError::new_err(format!("points_xyz: {n} rays do not fit in memory")))?;
        for k in 0..n {
            let p = &points[3 * k..3 * k + 3];
            if !p.iter().all(|c| c.is_finite()) {
                return Err(PyValueError::new_err(format!(
                    "points_xyz: row {k} is not finite: {p:?}"
                )));
            }
            let offset = nalgebra::Vector3::new(
                (p[0] - origin[0]) as f32,
                (p[1] - origin[1]) as f32,
                (p[2] - origin[2]) as f32,
            );
            let mut ray = if no_return[k] {
                oeg::Ray::no_return(offset)
            } else {
                oeg::Ray::hit(offset)
            };
            if let Some(v) = &variances
                && !no_return[k]
            {
                if !(v[k].is_finite() && v[k] > 0.0) {
                    return Err(PyValueError::new_err(format!(
                        "range_variance_m2: row {k} is {}, expected a positive finite variance",
                        v[k]
                    )));
                }
                ray = ray.with_range_sigma_m(v[k].sqrt() as f32);
            }
            scan.rays.push(ray);
        }
        // Ctrl-C stops a long scan within RAYS_BETWEEN_STOP_CHECKS rays, the map as it was before it; a scan no
        // longer than that is integrated at once (Python sees the signal when it returns), without the worker
        // thread's cost.
        let map = &mut self.map;
        let integrated = if n <= oeg::RAYS_BETWEEN_STOP_CHECKS {
            py.detach(|| map.integrate(&scan))
        } else {
            interruptible(py, |progress| {
                Ok(map.integrate_unless(&scan, &|| progress.check_cancelled().is_err()))
            })?
        };
        let stats = integrated.map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok((stats.num_rays, stats.num_cell_visits, self.map.num_scans()))
    }

    #[pyo3(signature = (name, region=None))]
    fn layer<'py>(
        &self,
        py: Python<'py>,
        name: &str,
        region: Option<(f64, f64, f64, f64)>,
    ) -> PyResult<Grid<'py, f32>> {
        let kind = oeg::LayerKind::ALL
            .into_iter()
            .find(|k| k.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = oeg::LayerKind::ALL.iter().map(|k| k.name()).collect();
                PyValueError::new_err(format!("layer: expected one of {names:?}, got {name:?}"))
            })?;
        let region = self.region(region)?;
        let layer = self.map.layer(kind, region).map_err(oeg_error)?;
        Ok((
            grid(py, &region, layer.values)?,
            extent(&oeg::GridWindow::new(*self.map.geometry(), region)),
        ))
    }

    #[pyo3(signature = (robot=None, region=None))]
    fn traversability<'py>(
        &self,
        py: Python<'py>,
        robot: Option<&Bound<'_, PyDict>>,
        region: Option<(f64, f64, f64, f64)>,
    ) -> PyResult<Grid<'py, u8>> {
        let s = settings(
            self.settings.map.resolution_m,
            &overrides_of(Some("robot"), robot)?,
        )?;
        let region = self.region(region)?;
        let rule = self.settings.map.traversability;
        let classes = self
            .map
            .traversability_layer(region, &s.robot, rule)
            .map_err(oeg_error)?;
        let codes = classes.values.iter().map(|t| *t as u8).collect();
        Ok((
            grid(py, &region, codes)?,
            extent(&oeg::GridWindow::new(*self.map.geometry(), region)),
        ))
    }

    fn memory_bytes(&self) -> u64 {
        self.map.memory_bytes()
    }

    fn num_observed_cells(&self) -> u64 {
        self.map.num_observed_cells()
    }

    fn observed_extent(&self) -> Option<Extent> {
        self.map
            .observed_region()
            .map(|r| extent(&oeg::GridWindow::new(*self.map.geometry(), r)))
    }

    fn save(&self, path: PathBuf) -> PyResult<()> {
        oeg::save_map(&self.map, &path).map_err(oeg_error)
    }
}

impl PyMap {
    /// The cells of a region given in metres, or the observed region.
    fn region(&self, region: Option<(f64, f64, f64, f64)>) -> PyResult<oeg::CellRegion> {
        let g = self.map.geometry();
        match region {
            None => self.map.observed_region().ok_or_else(|| {
                PyValueError::new_err(
                    "the map has observed nothing yet: give a region (x_min, y_min, x_max, y_max)",
                )
            }),
            Some((x0, y0, x1, y1)) => {
                let lo = g.cell_of(x0, y0);
                let hi = g.cell_of(x1, y1);
                lo.zip(hi)
                    .and_then(|(lo, hi)| oeg::CellRegion::from_corners(lo, hi))
                    .ok_or_else(|| {
                        PyValueError::new_err(format!(
                            "region: expected finite (x_min, y_min, x_max, y_max) in metres with min <= max, got \
                             ({x0}, {y0}, {x1}, {y1})"
                        ))
                    })
            }
        }
    }
}

/// Loads a map file (`map.oeg`).
#[pyfunction]
#[pyo3(signature = (path, memory_limit_bytes=None))]
fn load(py: Python<'_>, path: PathBuf, memory_limit_bytes: Option<u64>) -> PyResult<PyMap> {
    existing(&path)?;
    let limit = memory_limit_bytes.unwrap_or(oeg::DEFAULT_MEMORY_LIMIT_BYTES);
    let map = py
        .detach(|| oeg::load_map_within(&path, limit))
        .map_err(oeg_error)?;
    let resolution_m = map.geometry().resolution_m();
    let mut settings = settings(resolution_m, &[])?;
    settings.map.model = map.config().model;
    Ok(PyMap { map, settings })
}

/// A scan as arrays: the origin `(3,)`, the points `(n, 3)` in the world frame (a no-return ray's point is
/// the origin plus its unit direction), and the no-return mask `(n,)`.
type ScanArrays<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<bool>>,
);

fn scan_arrays<'py>(py: Python<'py>, scan: &oeg::Scan) -> PyResult<ScanArrays<'py>> {
    let o = scan.origin_in_world;
    let mut points = Vec::with_capacity(scan.rays.len() * 3);
    let mut no_return = Vec::with_capacity(scan.rays.len());
    for ray in &scan.rays {
        let d = ray.offset_in_world;
        let d = if ray.kind == oeg::RayKind::NoReturn {
            d.normalize()
        } else {
            d
        };
        points.extend([o.x + f64::from(d.x), o.y + f64::from(d.y), o.z + f64::from(d.z)]);
        no_return.push(ray.kind == oeg::RayKind::NoReturn);
    }
    let n = no_return.len();
    let points = Array2::from_shape_vec((n, 3), points).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((
        vec![o.x, o.y, o.z].into_pyarray(py),
        points.into_pyarray(py),
        no_return.into_pyarray(py),
    ))
}

/// Reads an OctoMap scan graph (`.graph`): one scan per node, at the node's pose.
#[pyfunction]
fn read_graph<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Vec<ScanArrays<'py>>> {
    existing(&path)?;
    let sensor = oeg::SensorModel::laser();
    let scans = py
        .detach(|| oeg::read_graph_scans(&path, sensor))
        .map_err(oeg_error)?;
    scans.iter().map(|s| scan_arrays(py, s)).collect()
}

/// Reads a PCD file as one scan; `settings` are `input.*` keys of `oeg map` (`pcd_frame`, `pcd_invalid`,
/// `pcd_sensor`).
#[pyfunction]
#[pyo3(signature = (path, origin_xyz=None, frame=None, invalid=None))]
fn read_pcd<'py>(
    py: Python<'py>,
    path: PathBuf,
    origin_xyz: Option<&Bound<'_, PyAny>>,
    frame: Option<&str>,
    invalid: Option<&str>,
) -> PyResult<ScanArrays<'py>> {
    existing(&path)?;
    let mut overrides = Vec::new();
    if let Some(f) = frame {
        overrides.push(format!("input.pcd_frame={}", serde_json::Value::String(f.into())));
    }
    if let Some(i) = invalid {
        overrides.push(format!(
            "input.pcd_invalid={}",
            serde_json::Value::String(i.into())
        ));
    }
    let s = settings(0.1, &overrides)?;
    let options = oeg::PcdOptions {
        frame: s.input.pcd_frame,
        invalid_points: s.input.pcd_invalid,
        sensor: s.input.pcd_sensor.model(),
    };
    let mut scan = py
        .detach(|| oeg::read_pcd_scan(&path, &options))
        .map_err(oeg_error)?;
    if let Some(o) = origin_xyz {
        let [x, y, z] = xyz("origin_xyz", o)?;
        scan.origin_in_world = nalgebra::Point3::new(x, y, z);
    }
    scan_arrays(py, &scan)
}

/// Plans on `map` from `start` to `goal` (x, y in metres); `None` when no path exists.
#[pyfunction]
#[pyo3(signature = (map, start, goal, settings=None))]
fn plan<'py>(
    py: Python<'py>,
    map: &PyMap,
    start: (f64, f64),
    goal: (f64, f64),
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
    let overrides = overrides_of(None, settings)?;
    let s =
        oeg_eval::settings::plan_settings(&overrides).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let name = Path::new("<map>");
    let m = &map.map;
    let planned = py
        .detach(|| {
            oeg_eval::jobs::plan::plan_on_map(
                m,
                name,
                (start, goal),
                &s.planner,
                &s.robot,
                s.map.traversability,
            )
        })
        .map_err(oeg_error)?;
    let Ok(p) = planned.plan else {
        return Ok(None);
    };
    let points = oeg_eval::judge::plan_check::polyline(&p, m.geometry());
    let n = points.len();
    let flat: Vec<f64> = points.into_iter().flat_map(|(x, y)| [x, y]).collect();
    let a = Array2::from_shape_vec((n, 2), flat).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(Some(a.into_pyarray(py)))
}

/// Runs `work` on a thread of its own with the GIL released, while this thread checks Python's signals every
/// 50 ms: on Ctrl-C the work is cancelled at its next step ([`oeg_eval::progress::Progress::cancel`]) and the
/// call raises `KeyboardInterrupt` once it has stopped.
fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(&oeg_eval::progress::Progress) -> oeg_eval::error::Result<T> + Send,
) -> PyResult<T> {
    let progress = oeg_eval::progress::Progress::hidden();
    let (result, interrupt) = py.detach(|| {
        std::thread::scope(|scope| {
            // The worker says when it is done, so a short call returns at once; signals are checked every 50 ms
            // while it runs.
            let (done, finished) = std::sync::mpsc::channel::<()>();
            let progress = &progress;
            let worker = scope.spawn(move || {
                let result = work(progress);
                let _ = done.send(());
                result
            });
            let mut interrupt = None;
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
                finished.recv_timeout(std::time::Duration::from_millis(50))
            {
                if interrupt.is_none()
                    && let Err(e) = Python::attach(|py| py.check_signals())
                {
                    progress.cancel();
                    interrupt = Some(e);
                }
            }
            (worker.join(), interrupt)
        })
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    match result {
        Ok(r) => r.map_err(oeg_error),
        Err(_) => Err(OegError::new_err(
            "the work panicked: this is a bug, please report it",
        )),
    }
}

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

/// Runs a scenario as `oeg run` does; returns `metrics.json` and `obstacles.csv` as text, and the output folder.
#[pyfunction]
#[pyo3(signature = (path, overrides, out=None, seed=None, compare=None, planner=None))]
fn run_scenario(
    py: Python<'_>,
    path: PathBuf,
    overrides: &Bound<'_, PyAny>,
    out: Option<PathBuf>,
    seed: Option<u64>,
    compare: Option<String>,
    planner: Option<Py<PyAny>>,
) -> PyResult<(String, String, Vec<String>, String)> {
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
    let metrics = serde_json::to_string(&report.metrics).map_err(oeg_error)?;
    let obstacles = oeg::read_text(&report.out_dir.join("obstacles.csv")).map_err(oeg_error)?;
    let failed = report.failed.iter().map(ToString::to_string).collect();
    Ok((metrics, obstacles, failed, report.out_dir.display().to_string()))
}

/// A scenario's truth, as `oeg run` judges a map against it ([`oeg_eval::scoring::ScoringTruth`]).
#[pyclass(name = "Truth", module = "oeg._oeg", frozen)]
struct PyTruth {
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

    /// The robot's decision profile as JSON.
    #[getter]
    fn robot(&self) -> PyResult<String> {
        serde_json::to_string(&self.inner.raster.profile).map_err(oeg_error)
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
fn truth(
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

/// A 2D float64 array of `shape` as its values, or `None`.
fn float_grid(
    name: &str,
    array: Option<&Bound<'_, PyAny>>,
    shape: (usize, usize),
) -> PyResult<Option<Vec<f64>>> {
    let Some(array) = array else { return Ok(None) };
    let a = array
        .cast::<PyArray2<f64>>()
        .map_err(|_| PyTypeError::new_err(format!("{name}: expected a 2D float64 numpy array")))?;
    let ro = a.readonly();
    let got = (ro.shape()[0], ro.shape()[1]);
    if got != shape {
        return Err(PyValueError::new_err(format!(
            "{name}: shape {got:?}, expected the decisions' shape {shape:?}"
        )));
    }
    Ok(Some(collected(name, ro.as_array().iter().copied())?))
}

/// Scores another mapper's arrays against `truth`; returns `metrics.json`, the obstacles and the plan
/// rows as JSON.
#[pyfunction]
#[pyo3(signature = (truth, decisions, origin, resolution_m, elevation=None, variance=None, occupancy=None))]
#[allow(clippy::too_many_arguments)]
fn score(
    py: Python<'_>,
    truth: &PyTruth,
    decisions: &Bound<'_, PyAny>,
    origin: (f64, f64),
    resolution_m: f64,
    elevation: Option<&Bound<'_, PyAny>>,
    variance: Option<&Bound<'_, PyAny>>,
    occupancy: Option<&Bound<'_, PyAny>>,
) -> PyResult<(String, String, String)> {
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
        serde_json::to_string(&evaluation.metrics).map_err(oeg_error)?,
        serde_json::to_string(&evaluation.obstacles).map_err(oeg_error)?,
        serde_json::to_string(&plan).map_err(oeg_error)?,
    ))
}

/// The native module.
#[pymodule]
fn _oeg(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMap>()?;
    m.add_class::<PyTruth>()?;
    m.add("OegError", m.py().get_type::<OegError>())?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(read_graph, m)?)?;
    m.add_function(wrap_pyfunction!(read_pcd, m)?)?;
    m.add_function(wrap_pyfunction!(plan, m)?)?;
    m.add_function(wrap_pyfunction!(run_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(truth, m)?)?;
    m.add_function(wrap_pyfunction!(score, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
