//! What `ftsmc identify` and `ftsmc validate` share: the logs, the output
//! folder, the bootstrap and its seed (one flattened clap group, declared
//! once), and reading the logs as series.

use std::path::PathBuf;

use anyhow::Result;
use ftsmc_ident::series::Series;

/// Arguments every log command takes.
#[derive(clap::Args)]
pub struct LogArgs {
    /// Flight logs: PX4 ULog, NanoBench CSV or the generic CSV (docs/logs.md).
    #[arg(required = true)]
    pub logs: Vec<PathBuf>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Bootstrap replicates over flight segments (the intervals).
    #[arg(long, default_value_t = 200)]
    pub bootstrap: usize,
    /// Seed of the bootstrap.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

impl LogArgs {
    /// Reads every log as a [`Series`] for `purpose` (named in errors).
    pub fn read_series(&self, purpose: &'static str) -> Result<Vec<Series>> {
        Ok(Series::read_all(&self.logs, purpose)?)
    }
}
