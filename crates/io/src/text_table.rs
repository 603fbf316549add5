//! Whitespace-separated numeric tables (relations, trajectories): one parser with line-numbered
//! errors so both file types fail the same clear way.

use crate::carmen::ReadError;
use crate::input::{open_input, TextLines};
use std::path::Path;

/// One parsed row: the raw first field (timestamps are kept as written) and all fields as numbers.
pub struct Row<'a> {
    pub first_text: &'a str,
    pub values: Vec<f64>,
}

/// Reads a file (gzip recognised by content) into rows of exactly `columns` finite numbers.
/// Blank lines and `#` comments are passed over.
pub fn read_rows(
    path: &Path,
    columns: usize,
    visit: impl FnMut(Row) -> Result<(), ReadError>,
) -> Result<(), ReadError> {
    read_rows_and_comments(path, columns, visit, |_| Ok(()))
}

/// [`read_rows`], handing each `#` comment (its text after the `#`) to `comment`, whose error is
/// reported at the comment's line.
pub fn read_rows_and_comments(
    path: &Path,
    columns: usize,
    mut visit: impl FnMut(Row) -> Result<(), ReadError>,
    mut comment: impl FnMut(&str) -> Result<(), String>,
) -> Result<(), ReadError> {
    let input = open_input(path)?;
    let mut lines = TextLines::new(input.reader, &input.name);
    while let Some((line_no, line)) = lines.next_line()? {
        let err = |message: String| ReadError {
            file: input.name.clone(),
            line: line_no,
            message,
        };
        let trimmed = line.trim();
        if let Some(text) = trimmed.strip_prefix('#') {
            comment(text).map_err(err)?;
            continue;
        }
        if trimmed.is_empty() {
            continue;
        }
        let fields: Vec<&str> = trimmed.split_ascii_whitespace().collect();
        if fields.len() != columns {
            return Err(err(format!(
                "expected {columns} fields, found {}",
                fields.len()
            )));
        }
        let mut values = Vec::with_capacity(columns);
        for (k, f) in fields.iter().enumerate() {
            match f.parse::<f64>() {
                Ok(v) if v.is_finite() => values.push(v),
                _ => {
                    return Err(err(format!(
                        "field {} is not a finite number: {f:?}",
                        k + 1
                    )))
                }
            }
        }
        visit(Row {
            first_text: fields[0],
            values,
        })?;
    }
    Ok(())
}
