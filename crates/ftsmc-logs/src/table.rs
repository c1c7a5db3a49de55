//! CSV files of numbers with a header line, read as a stream into named
//! `f64` columns: the common part of the NanoBench and generic CSV readers.
//!
//! Lines starting with `#` are comments; every record must have as many
//! fields as the header; every cell must parse as an `f64` (`nan` and `inf`
//! parse, and are refused later where a value is used).

use std::path::Path;

use crate::error::LogError;
use crate::source::{self, LogLimits};

/// A CSV file as columns.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The path as given.
    pub file: String,
    /// The header's names, trimmed.
    pub names: Vec<String>,
    /// One column per name.
    pub columns: Vec<Vec<f64>>,
    /// The `# key: value` comment lines before the header, trimmed.
    pub comments: Vec<String>,
}

impl Table {
    /// The column called `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names.iter().position(|n| n == name).map(|i| &self.columns[i][..])
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// The columns called `names`, or a `Missing` error listing the absent
    /// ones (`group` says what they are for).
    pub fn require(&self, names: &[&str], group: &str) -> Result<Vec<&[f64]>, LogError> {
        let missing: Vec<&str> = names.iter().copied().filter(|n| self.column(n).is_none()).collect();
        if !missing.is_empty() {
            return Err(LogError::Missing {
                file: self.file.clone(),
                what: format!("column(s) {} ({group})", missing.join(", ")),
                found: format!("the header has {}", abbreviate(&self.names)),
            });
        }
        Ok(names.iter().map(|n| self.column(n).unwrap_or(&[])).collect())
    }
}

fn abbreviate(names: &[String]) -> String {
    if names.len() <= 12 {
        names.join(", ")
    } else {
        format!("{}, … ({} columns)", names[..12].join(", "), names.len())
    }
}

/// Reads the CSV file `path` (a regular file within `limits`).
pub fn read_table(path: &Path, limits: &LogLimits) -> Result<Table, LogError> {
    let mut opened = source::open(path, limits)?;
    let file = opened.file.clone();
    // Comment lines before the header are kept (the generic schema's
    // `# frame: …`); the csv crate's own comment handling would drop them.
    let mut comments = Vec::new();
    let mut first_line = 1u64;
    loop {
        use std::io::{BufRead as _, Read as _};
        let first = match opened.reader.fill_buf() {
            Ok(buf) => buf.first().copied(),
            Err(e) => return Err(opened.io_error(e)),
        };
        if first != Some(b'#') {
            break;
        }
        let mut line = Vec::new();
        let mut limited = (&mut opened.reader).take(4096);
        limited.read_until(b'\n', &mut line).map_err(|e| opened.io_error(e))?;
        if line.last() != Some(&b'\n') {
            return Err(LogError::Malformed {
                file,
                format: "CSV",
                offset: opened.offset.get(),
                detail: format!("comment line {first_line} is longer than 4096 bytes or not ended"),
            });
        }
        comments.push(String::from_utf8_lossy(&line[1..]).trim().to_string());
        first_line += 1;
    }
    let mut reader = csv::ReaderBuilder::new().has_headers(true).comment(Some(b'#')).from_reader(&mut opened.reader);
    let csv_error = |e: csv::Error, offset: u64| -> LogError {
        let line = e.position().map_or(0, |p| p.line()) + first_line - 1;
        match e.into_kind() {
            csv::ErrorKind::Io(io) => {
                if io.kind() == std::io::ErrorKind::UnexpectedEof {
                    LogError::Truncated { file: file.clone(), offset }
                } else if io.get_ref().is_some_and(|x| x.is::<source::GrewPastLimit>()) {
                    LogError::TooLarge { file: file.clone(), size: offset, limit: limits.max_file_bytes }
                } else {
                    LogError::Read { file: file.clone(), source: io }
                }
            }
            csv::ErrorKind::UnequalLengths { expected_len, len, .. } => LogError::Malformed {
                file: file.clone(),
                format: "CSV",
                offset,
                detail: format!("line {line} has {len} fields, the header {expected_len}"),
            },
            csv::ErrorKind::Utf8 { .. } => LogError::Malformed {
                file: file.clone(),
                format: "CSV",
                offset,
                detail: format!("line {line} is not UTF-8"),
            },
            other => LogError::Malformed { file: file.clone(), format: "CSV", offset, detail: format!("{other:?}") },
        }
    };
    let names: Vec<String> = match reader.headers() {
        Ok(h) => h.iter().map(|n| n.trim().to_string()).collect(),
        Err(e) => return Err(csv_error(e, opened.offset.get())),
    };
    if names.iter().all(String::is_empty) {
        return Err(LogError::Missing { file, what: "a header line".into(), found: "the file is empty".into() });
    }
    let mut columns = vec![Vec::new(); names.len()];
    let mut record = csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => return Err(csv_error(e, opened.offset.get())),
        }
        let line = record.position().map_or(0, |p| p.line()) + first_line - 1;
        for ((cell, column), name) in record.iter().zip(&mut columns).zip(&names) {
            let value = cell.trim().parse::<f64>().map_err(|_| LogError::NotANumber {
                file: file.clone(),
                line,
                column: name.clone(),
                value: cell.chars().take(40).collect(),
            })?;
            column.push(value);
        }
    }
    Ok(Table { file, names, columns, comments })
}
