//! # ftsmc-logs
//!
//! Real flight logs into one in-memory type, [`FlightLog`]: PX4 ULog files
//! (through the `yule_log` crate), NanoBench's Crazyflie/Vicon CSV files
//! and ftsmc's generic CSV schema (docs/logs.md). Every reader streams the
//! file, refuses files over [`LogLimits::max_file_bytes`] and anything but a
//! regular file, and reports a bad log as one [`LogError`] naming the file
//! and what is wrong — never a panic.
//!
//! ## Layout
//!
//! A module only uses modules on its own floor or below:
//!
//! ```text
//! floor 2  ulog.rs         ULog topics as columns (UlogStream, read_ulog) and their FlightLog
//!          nanobench.rs    NanoBench CSV (Ullah and Baca 2026) to FlightLog
//!          generic_csv.rs  the generic schema to FlightLog
//! floor 1  flight_log.rs   FlightLog, Frame, Motors and their checks
//!          table.rs        a CSV file of numbers as named columns
//! floor 0  error.rs        LogError
//!          source.rs       opening: regular files within a size limit, counted reads
//! ```
#![warn(missing_docs)]

pub mod error;
pub mod flight_log;
pub mod generic_csv;
pub mod nanobench;
pub mod source;
pub mod table;
pub mod ulog;

use std::path::Path;

pub use error::LogError;
pub use flight_log::{FlightLog, Frame, MotorUnit, Motors, Setpoint};
pub use source::LogLimits;

/// Reads a flight log of any supported kind, told apart by content: the
/// ULog magic, else a CSV header with NanoBench's columns, else one with
/// `time_s` (the generic schema).
pub fn read_log(path: &Path, limits: &LogLimits) -> Result<FlightLog, LogError> {
    let mut opened = source::open(path, limits)?;
    let mut head = [0u8; 7];
    let mut got = 0;
    while got < head.len() {
        use std::io::Read as _;
        match opened.reader.read(&mut head[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(opened.io_error(e)),
        }
    }
    drop(opened);
    if got == head.len() && head == ulog::MAGIC {
        return ulog::read_ulog_flight(path, limits);
    }
    let table = table::read_table(path, limits)?;
    if nanobench::is_nanobench(&table.names) {
        nanobench::flight_from_nanobench(&table)
    } else if generic_csv::is_generic(&table.names) {
        generic_csv::flight_from_generic(&table)
    } else {
        Err(LogError::Missing {
            file: table.file.clone(),
            what: "a known format".into(),
            found: format!(
                "not ULog (no magic), and the CSV header has neither NanoBench's {} nor the generic `time_s`",
                nanobench::SIGNATURE.join(", ")
            ),
        })
    }
}
