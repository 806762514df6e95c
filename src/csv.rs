//! The one reader of numeric tables in text: spectra, phase-function
//! tables, constituent grids and height fields.
//!
//! Format: `#` starts a comment (a whole line, or the rest of one); blank
//! lines are skipped; fields are separated by commas, or by white space on
//! a line without a comma. The first line with no numeric field is the
//! header (only before the first data row); every other line is a row,
//! all rows as wide as the first. Readers take the columns they use as
//! finite numbers ([`CsvTable::number`]); other columns (a source note)
//! may hold text. Every error is
//! [`Error::Data`]: the file, the 1-based line where there is one, the
//! scene field that named the file, and what is wrong.
//!
//! Hand-written rather than the `csv` crate: the tables are small, the
//! format is a subset, and the errors must carry the scene field.
//!
//! Not for: what the columns mean (each reader checks its own).

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// One data row.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// 1-based line in the file.
    pub line: usize,
    pub fields: Vec<String>,
}

/// A parsed table.
#[derive(Clone, Debug)]
pub struct CsvTable {
    path: PathBuf,
    field: String,
    /// Column names and their line, if the table has a header.
    pub header: Option<(usize, Vec<String>)>,
    pub rows: Vec<Row>,
}

/// Read and parse the table at `path`, named by the scene field `field`.
pub fn read(path: &Path, field: &str) -> Result<CsvTable> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, "read", e))?;
    parse(&text, path, field)
}

/// Parse `text`, reporting errors against `path` and `field`.
pub fn parse(text: &str, path: &Path, field: &str) -> Result<CsvTable> {
    let mut t = CsvTable {
        path: path.to_path_buf(),
        field: field.to_string(),
        header: None,
        rows: Vec::new(),
    };
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let fields: Vec<&str> = if content.contains(',') {
            content.split(',').map(str::trim).collect()
        } else {
            content.split_whitespace().collect()
        };
        // A header has no numeric field: a bad first data row such as
        // "4OO,0.1" still has a number, so it is reported, not skipped.
        if t.rows.is_empty()
            && t.header.is_none()
            && fields.iter().all(|f| f.parse::<f64>().is_err())
        {
            t.header = Some((line, fields.iter().map(|f| f.to_string()).collect()));
            continue;
        }
        if let Some(first) = t.rows.first() {
            if fields.len() != first.fields.len() {
                return Err(t.error(
                    Some(line),
                    format!(
                        "{} fields, but line {} has {} fields",
                        fields.len(),
                        first.line,
                        first.fields.len()
                    ),
                ));
            }
        }
        if fields.iter().any(|f| f.is_empty()) {
            return Err(t.error(Some(line), "empty field"));
        }
        t.rows.push(Row {
            line,
            fields: fields.iter().map(|f| f.to_string()).collect(),
        });
    }
    Ok(t)
}

impl CsvTable {
    /// An error about this file at `line` (or the file as a whole).
    pub fn error(&self, line: Option<usize>, what: impl Into<String>) -> Error {
        Error::data(&self.path, line, &self.field, what)
    }

    /// Fields per row (0 for a table without rows).
    pub fn width(&self) -> usize {
        self.rows.first().map_or(0, |r| r.fields.len())
    }

    /// Field `col` of `row` as a finite number.
    pub fn number(&self, row: &Row, col: usize) -> Result<f64> {
        let f = &row.fields[col];
        match f.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.error(Some(row.line), format!("'{f}' is not a finite number"))),
        }
    }

    /// Every field of `row` as a finite number.
    pub fn numbers(&self, row: &Row) -> Result<Vec<f64>> {
        (0..row.fields.len()).map(|c| self.number(row, c)).collect()
    }

    /// Require exactly `width` values per row, described as `what` in the
    /// error (e.g. "2 fields (nm,value)").
    pub fn expect_width(&self, width: usize, what: &str) -> Result<()> {
        match self.rows.first() {
            Some(r) if r.fields.len() != width => Err(self.error(
                Some(r.line),
                format!("expected {what}, found {}", r.fields.len()),
            )),
            _ => Ok(()),
        }
    }

    /// The index of column `name` in the header.
    pub fn column(&self, name: &str) -> Result<usize> {
        match &self.header {
            Some((line, names)) => names
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| self.error(Some(*line), format!("header has no column '{name}'"))),
            None => Err(self.error(
                self.rows.first().map(|r| r.line),
                "expected a header line naming the columns",
            )),
        }
    }

    /// Require the header to be exactly `names`.
    pub fn expect_header(&self, names: &[&str]) -> Result<()> {
        match &self.header {
            Some((_, h)) if h.iter().map(String::as_str).eq(names.iter().copied()) => Ok(()),
            Some((line, _)) => {
                Err(self.error(Some(*line), format!("header must be {}", names.join(","))))
            }
            None => Err(self.error(
                self.rows.first().map(|r| r.line),
                format!("expected the header {}", names.join(",")),
            )),
        }
    }
}

#[cfg(test)]
mod tests;
