//! Tables as Markdown, for pages generated from a job's outputs (the README's status table, `docs/results/`):
//! the same rows as the job's CSV file, numbers rounded for reading, columns that vary from run to run (wall
//! times) left out so that the page is the same bytes whenever the same inputs are run.

use std::path::Path;

use super::{CsvRow, TableError, csv_table, write_bytes};
use crate::error::{EvalError, Result};

/// A CSV table (header first, as [`super::csv_bytes`] writes it) as a Markdown table, without the columns
/// named in `drop`. Whole numbers stay as they are, other numbers get 3 decimals, empty fields read `-`.
///
/// # Errors
/// [`TableError`] when the bytes are not CSV.
pub(super) fn markdown_table(csv: &[u8], drop: &[&str]) -> std::result::Result<String, TableError> {
    let mut reader = csv::ReaderBuilder::new().has_headers(true).from_reader(csv);
    let header = reader.headers()?.clone();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&k| !drop.contains(&&header[k]))
        .collect();
    let row = |cells: Vec<String>| format!("| {} |\n", cells.join(" | "));
    let mut out = row(keep.iter().map(|&k| header[k].to_string()).collect());
    out.push_str(&row(keep.iter().map(|_| "---".to_string()).collect()));
    for record in reader.records() {
        let record = record?;
        out.push_str(&row(keep
            .iter()
            .map(|&k| cell(record.get(k).unwrap_or_default()))
            .collect()));
    }
    Ok(out)
}

/// One field as it reads in the page.
fn cell(field: &str) -> String {
    if field.is_empty() {
        return "-".into();
    }
    if field.bytes().all(|b| b.is_ascii_digit() || b == b'-') {
        return field.to_string();
    }
    match field.parse::<f64>() {
        Ok(v) if v.is_finite() => format!("{v:.3}"),
        _ => field.replace('|', "\\|"),
    }
}

/// [`markdown_table`] of [`CsvRow`]s: the same rows as their CSV file, without the columns in `drop`.
///
/// # Errors
/// As [`markdown_table`], and a row that is not one flat record.
pub(crate) fn markdown_rows<'a, T: CsvRow + 'a>(
    rows: impl IntoIterator<Item = &'a T>,
    drop: &[&str],
) -> std::result::Result<String, TableError> {
    markdown_table(&csv_table(rows)?, drop)
}

/// Writes [`markdown_rows`] to `path` atomically, beside the rows' CSV file.
///
/// # Errors
/// [`EvalError::Input`] naming the file for a row that is not one flat record, and a failed write.
pub(crate) fn write_markdown_rows<'a, T: CsvRow + 'a>(
    path: &Path,
    rows: impl IntoIterator<Item = &'a T>,
    drop: &[&str],
) -> Result<()> {
    let text = markdown_rows(rows, drop).map_err(|e| EvalError::Input {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    write_bytes(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_csv_table_reads_as_markdown_without_the_dropped_columns() {
        let csv = b"model,unsafe_cells,ratio,wall_time_s,note\npaper,847,1.0276100921264315,2.5,\nrobust,245,,3.1,a|b\n";
        let md = markdown_table(csv, &["wall_time_s"]).expect("csv");
        assert_eq!(
            md,
            "| model | unsafe_cells | ratio | note |\n| --- | --- | --- | --- |\n| paper | 847 | 1.028 | - |\n\
             | robust | 245 | - | a\\|b |\n"
        );
    }
}
