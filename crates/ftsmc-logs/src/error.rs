//! The one error type of every reader: each variant names the file and what
//! is wrong with it (the field, row or byte offset, and the value found), so
//! that a bad log is reported in one line and never panics.

/// Why a flight log could not be read. `file` is the path as given.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The file could not be opened or its metadata read.
    #[error("{file}: cannot open: {source}")]
    Open {
        /// The path.
        file: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A read failed for another reason than the end of the file.
    #[error("{file}: cannot read: {source}")]
    Read {
        /// The path.
        file: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A directory, FIFO, socket or device: only regular files are read, so
    /// that a reader never blocks on a pipe nor reads `/dev/zero` forever.
    #[error("{file} is {kind}, not a regular file")]
    NotRegularFile {
        /// The path.
        file: String,
        /// "a directory" or "a FIFO, socket or device".
        kind: &'static str,
    },
    /// Larger than [`crate::LogLimits::max_file_bytes`] (or it grew past the
    /// limit while being read).
    #[error(
        "{file}: {size} bytes or more, over the limit of {limit} bytes \
         (raise LogLimits::max_file_bytes to read it)"
    )]
    TooLarge {
        /// The path.
        file: String,
        /// The size seen, bytes (a lower bound when the file grew).
        size: u64,
        /// The limit, bytes.
        limit: u64,
    },
    /// The file does not start with the ULog magic `ULog` 01 12 35.
    #[error(
        "{file}: not a ULog file: it starts with {found}, a ULog file with 55 4c 6f 67 01 12 35 (\"ULog\" 01 12 35)"
    )]
    BadMagic {
        /// The path.
        file: String,
        /// The first bytes, in hexadecimal.
        found: String,
    },
    /// The file ends inside a message (or inside the 16-byte header).
    #[error("{file}: truncated: the file ends inside a message (after byte {offset})")]
    Truncated {
        /// The path.
        file: String,
        /// Bytes read before the end was met.
        offset: u64,
    },
    /// The bytes are not valid for the format: a message or definition that
    /// does not parse, a nested type that refers to itself, and so on.
    #[error("{file}: malformed {format} (near byte {offset}): {detail}")]
    Malformed {
        /// The path.
        file: String,
        /// "ULog", "CSV", …
        format: &'static str,
        /// Bytes read when the fault was found.
        offset: u64,
        /// What is wrong.
        detail: String,
    },
    /// Something the log must hold is absent: a topic, a CSV column, rows.
    #[error("{file}: missing {what}; {found}")]
    Missing {
        /// The path.
        file: String,
        /// What was looked for (`topic vehicle_attitude`, `column t`).
        what: String,
        /// What the file has instead.
        found: String,
    },
    /// A time stamp is not after the one before it.
    #[error("{file}: {channel}: time does not increase at sample {index}: {previous} s, then {next} s")]
    NonMonotonicTime {
        /// The path.
        file: String,
        /// The topic or column whose time it is.
        channel: String,
        /// Index of the offending sample (0-based).
        index: usize,
        /// The time before, s.
        previous: f64,
        /// The time at `index`, s.
        next: f64,
    },
    /// A value the flight log uses is NaN or infinite.
    #[error("{file}: {field}: value {value} at sample {index} (t = {time} s) is not finite")]
    NotFinite {
        /// The path.
        file: String,
        /// The field (`vehicle_local_position.vx`, column `px`).
        field: String,
        /// Index of the sample (0-based).
        index: usize,
        /// Its time, s.
        time: f64,
        /// The value.
        value: f64,
    },
    /// A CSV cell that is not a number.
    #[error("{file}: line {line}, column `{column}`: `{value}` is not a number")]
    NotANumber {
        /// The path.
        file: String,
        /// 1-based line of the file.
        line: u64,
        /// The column's header.
        column: String,
        /// The cell, as written (cut to 40 characters).
        value: String,
    },
}
