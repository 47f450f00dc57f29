//! Writing a job's outputs: every file atomically (temporary file, then rename), and every job's folder all
//! or nothing ([`Staged`]).

mod base64;
pub(crate) mod html;
mod markdown;
mod staged;

use std::path::Path;

use serde::Serialize;

use crate::error::{EvalError, Result};

pub(crate) use base64::base64;
pub(crate) use markdown::{markdown_rows, write_markdown_rows};
pub(crate) use staged::{OUTPUT_MARKER, Staged};

/// The unit a key's suffix names, as the outputs spell their keys (`..._m` metres, `..._m2` square metres,
/// `..._s` seconds, `..._deg` degrees, `..._cells` cells, ...); `None` for a key without one (fractions,
/// ratios, flags).
pub(crate) fn unit_of(key: &str) -> Option<&'static str> {
    const UNITS: [(&str, &str); 11] = [
        ("_m_per_sqrt_m", "m/\u{221a}m"),
        ("_deg_per_sqrt_m", "\u{b0}/\u{221a}m"),
        ("_m_s", "m/s"),
        ("_rays_per_s", "rays/s"),
        ("_s", "s"),
        ("_m2", "m\u{b2}"),
        ("_px", "px"),
        ("_deg", "\u{b0}"),
        ("_hz", "Hz"),
        ("_m", "m"),
        ("_cells", "cells"),
    ];
    UNITS
        .iter()
        .find(|(suffix, _)| key.ends_with(suffix))
        .map(|(_, unit)| *unit)
}

/// Creates the output folder (and its parents).
///
/// # Errors
/// [`EvalError::Io`] naming the folder.
pub(crate) fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| EvalError::Io {
        path: dir.to_path_buf(),
        source,
    })
}

/// Writes `value` as pretty JSON with a final newline.
///
/// # Errors
/// [`EvalError::Map`] wrapping the I/O error, naming the file.
pub(crate) fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|e| EvalError::Input {
        path: path.to_path_buf(),
        message: format!("cannot serialise: {e}"),
    })?;
    bytes.push(b'\n');
    Ok(oeg_files::write_atomically(path, &bytes)?)
}

/// Writes bytes (an image, a map).
///
/// # Errors
/// As [`write_json`].
pub(crate) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    Ok(oeg_files::write_atomically(path, bytes)?)
}

/// A row type of a CSV table: its columns, in the order its fields serialise. Each implementation is checked
/// by a test against the header `csv` derives from the struct ([`derived_header`]).
pub trait CsvRow: Serialize {
    /// The header.
    const COLUMNS: &'static [&'static str];
}

/// The project's one CSV writer: a header, then one record per row, in memory. The header is written even
/// when there are no rows, so an empty table still loads into pandas with its columns.
///
/// # Errors
/// A row whose fields do not serialise as one flat record, as text.
pub(crate) fn csv_bytes<T: Serialize>(
    columns: &[&str],
    rows: impl IntoIterator<Item = T>,
) -> std::result::Result<Vec<u8>, TableError> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    w.write_record(columns)?;
    for row in rows {
        w.serialize(row)?;
    }
    w.into_inner()
        .map_err(|e| TableError::Csv(csv::Error::from(e.into_error())))
}

/// A table that cannot be written or read as CSV: a row that is not one flat record, or bytes that are not
/// CSV (the caller names the file).
#[derive(Debug, thiserror::Error)]
pub(crate) enum TableError {
    /// From the CSV writer or reader.
    #[error("{0}")]
    Csv(#[from] csv::Error),
}

/// [`csv_bytes`] of [`CsvRow`]s, with their [`CsvRow::COLUMNS`].
///
/// # Errors
/// As [`csv_bytes`].
pub(crate) fn csv_table<'a, T: CsvRow + 'a>(
    rows: impl IntoIterator<Item = &'a T>,
) -> std::result::Result<Vec<u8>, TableError> {
    csv_bytes(T::COLUMNS, rows)
}

/// Writes a table to `path` atomically: [`csv_bytes`], an error naming the file.
///
/// # Errors
/// [`EvalError::Input`] naming the file for a row that is not one flat record, and a failed write.
pub(crate) fn write_csv<T: Serialize>(
    path: &Path,
    columns: &[&str],
    rows: impl IntoIterator<Item = T>,
) -> Result<()> {
    let bytes = csv_bytes(columns, rows).map_err(|e| EvalError::Input {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    write_bytes(path, &bytes)
}

/// [`write_csv`] of [`CsvRow`]s, with their [`CsvRow::COLUMNS`].
///
/// # Errors
/// As [`write_csv`].
pub(crate) fn write_table<'a, T: CsvRow + 'a>(
    path: &Path,
    rows: impl IntoIterator<Item = &'a T>,
) -> Result<()> {
    write_csv(path, T::COLUMNS, rows)
}

/// The header `csv` derives from a struct row's field names (for the tests of [`CsvRow::COLUMNS`]).
#[cfg(test)]
pub(crate) fn derived_header<T: Serialize>(row: &T) -> Vec<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    if w.serialize(row).is_err() {
        return Vec::new();
    }
    let bytes = w.into_inner().unwrap_or_default();
    let text = String::from_utf8_lossy(&bytes);
    text.lines()
        .next()
        .map(|l| l.split(',').map(str::to_string).collect())
        .unwrap_or_default()
}

/// A coordinate rounded to the micrometre for CSV files: cell centres such as `1180.5 * 0.1` print as
/// `118.05`, not `118.05000000000001`.
pub(crate) fn round_m(v_m: f64) -> f64 {
    (v_m * 1e6).round() / 1e6
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check<T: CsvRow>(row: &T) {
        let columns: Vec<String> = T::COLUMNS.iter().map(|c| (*c).to_string()).collect();
        assert_eq!(columns, derived_header(row), "{}", std::any::type_name::<T>());
        let empty = csv_table::<T>(&[]).expect("csv");
        assert_eq!(
            String::from_utf8(empty).expect("utf8"),
            format!("{}\n", T::COLUMNS.join(","))
        );
    }

    #[test]
    fn every_report_tables_columns_are_its_fields_in_order_and_an_empty_table_keeps_its_header() {
        check(&sim::physics::PhysicsSample {
            time_s: 0.0,
            x_m: 0.0,
            y_m: 0.0,
            z_m: 0.0,
            yaw_deg: 0.0,
            roll_deg: 0.0,
            pitch_deg: 0.0,
            commanded_speed_m_s: 0.0,
            commanded_turn_rate_deg_s: 0.0,
            speed_m_s: 0.0,
            turn_rate_deg_s: 0.0,
            slip_left: 0.0,
            slip_right: 0.0,
            path_error_m: None,
        });
        check(&crate::jobs::suite::SuiteRow {
            scenario: "s".into(),
            file: "f".into(),
            status: "error".into(),
            safety: String::new(),
            coverage: None,
            elevation_rmse_m: None,
            unsafe_step_cells: None,
            overcautious_step_cells: None,
            unsafe_clearance_cells: None,
            overcautious_clearance_cells: None,
            plan_length_ratio: None,
            plan_unsafe_cells: None,
            unsafe_observable_cells: None,
            blind_cells: None,
            nav_reached: None,
            nav_contacts: None,
            nav_contacts_observable: None,
            wall_time_s: 1.0,
            problems: String::new(),
        });
        check(&crate::report::ComparisonRow {
            model: "paper".into(),
            unsafe_cells: 1,
            overcautious_cells: 2,
            uncertain_cells: 3,
            plan_found: true,
            plan_unsafe_cells: 0,
            plan_length_ratio: Some(1.0),
            elevation_within_2sigma: 0.9,
            elevation_rmse_m: 0.01,
        });
        check(&crate::judge::obstacles::ObstacleDecision {
            index: 0,
            name: "curb".into(),
            kind: "box".into(),
            height_m: 0.03,
            sensor_returns: Some(12),
            num_cells: 1,
            num_observed_cells: 1,
            true_blocked_cells: 0,
            mapped_blocked_cells: 0,
            uncertain_cells: 0,
            unsafe_cells: 0,
            blind_cells: 0,
            overcautious_cells: 0,
            true_elevation_mean_m: Some(0.03),
            mapped_elevation_mean_m: None,
            true_decision: "passable",
            mapped_decision: "passable",
            decision: "right",
            decision_right: true,
        });
        check(&crate::jobs::sweep::report::SummaryRow {
            axis: "a".into(),
            value: "v".into(),
            line: "all".into(),
            metric: "m".into(),
            interval: "wilson",
            n: 1,
            mean: Some(0.5),
            std: None,
            ci95_low: None,
            ci95_high: None,
        });
    }

    #[test]
    fn every_run_tables_columns_are_its_fields_in_order_and_an_empty_table_keeps_its_header() {
        check(&crate::judge::plan_check::PlanRow {
            path: "map",
            step: 0,
            x_m: 0.0,
            y_m: 0.0,
            unsafe_cell: false,
            blind_cell: false,
        });
        check(&sim::observability::BlindBandRow {
            range_m: 1.0,
            rays_in_band: 2,
            largest_gap_m: 0.1,
            gap_from_m: 0.2,
            gap_to_m: 0.3,
        });
        check(&crate::navigation::record::Event {
            time_s: 1.0,
            kind: crate::navigation::record::EventKind::Contact,
            x_m: 0.0,
            y_m: 0.0,
            yaw_deg: 0.0,
            obstacle: "wall".into(),
            distance_m: Some(0.0),
            observable: None,
            mapped_as: String::new(),
            closed_by: String::new(),
            message: "m".into(),
        });
        check(&crate::navigation::record::TrajectoryRow {
            time_s: 0.1,
            true_x_m: 0.0,
            true_y_m: 0.0,
            true_yaw_deg: 0.0,
            estimated_x_m: 0.0,
            estimated_y_m: 0.0,
            estimated_yaw_deg: 0.0,
            speed_m_s: 0.4,
            turn_rate_deg_s: 0.0,
            planner_state: "following",
            plan: Some(0),
        });
        check(&crate::navigation::record::PlanPointRow {
            plan: 0,
            time_s: 0.0,
            step: 0,
            x_m: 0.0,
            y_m: 0.0,
        });
        check(&crate::test_support::wrong_cell());
    }
}
