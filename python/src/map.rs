//! The map from Python: `Map` (build, integrate, layers, decisions, save), `load`, the readers of scan
//! graphs and PCD files, and the planner.

use std::path::{Path, PathBuf};

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::{PyMemoryError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::*;
use crate::{interruptible, oeg_error};

/// The Occupancy-Elevation Grid.
#[pyclass(name = "Map", module = "oeg._oeg")]
pub(crate) struct PyMap {
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
    fn model<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py_object(py, &self.map.config().model)
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
pub(crate) fn load(py: Python<'_>, path: PathBuf, memory_limit_bytes: Option<u64>) -> PyResult<PyMap> {
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
pub(crate) fn read_graph<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Vec<ScanArrays<'py>>> {
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
pub(crate) fn read_pcd<'py>(
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
        points: s.input.pcd_points,
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
pub(crate) fn plan<'py>(
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
