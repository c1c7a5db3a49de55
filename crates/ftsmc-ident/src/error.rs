//! Errors of identification and validation: each names the file (or
//! vehicle) and what is missing or wrong.

use ftsmc_logs::LogError;

/// What went wrong, with the file and the value involved.
#[derive(Debug, thiserror::Error)]
pub enum IdentError {
    /// The log could not be read.
    #[error(transparent)]
    Log(#[from] LogError),
    /// A channel the computation needs is not in the log.
    #[error("{file}: no {channel} in the log; {purpose} needs it")]
    MissingChannel {
        /// The log.
        file: String,
        /// The channel (e.g. "accelerometer").
        channel: &'static str,
        /// What needs it.
        purpose: &'static str,
    },
    /// The log's frames are not stated.
    #[error(
        "{file}: the log does not state its frames (a generic CSV needs a `# frame: zup-flu` or \
         `# frame: ned-frd` line before its header)"
    )]
    UnspecifiedFrame {
        /// The log.
        file: String,
    },
    /// Too little flight (motors on) to fit or validate.
    #[error("{what}: {found}, {needed} needed")]
    TooShort {
        /// The log(s) concerned.
        what: String,
        /// What was found (e.g. "3.1 s of flight in 1 segment").
        found: String,
        /// What is needed.
        needed: String,
    },
    /// The vehicle could not be loaded or lacks what is needed.
    #[error("vehicle {vehicle}: {message}")]
    Vehicle {
        /// The preset name or file.
        vehicle: String,
        /// What is wrong.
        message: String,
    },
    /// An option out of range.
    #[error("{option} = {value}: {expected}")]
    Option {
        /// The option's name.
        option: &'static str,
        /// The value given.
        value: String,
        /// What is expected.
        expected: &'static str,
    },
    /// The least-squares problem is singular: the flights do not excite
    /// what is fitted.
    #[error("{what}: the flights do not excite {channel} (singular least squares); fly with more motion")]
    Singular {
        /// The log(s).
        what: String,
        /// The channel fitted.
        channel: &'static str,
    },
}
