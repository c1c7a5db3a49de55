//! Shards of a Monte Carlo campaign: `K/N` is the K-th of N contiguous
//! blocks of run indices, so N machines (a Slurm job array, Dask tasks)
//! each fly one block and `ftsmc merge` puts the rows back in run order.
//!
//! Contiguous blocks rather than interleaved indices: a run's cost does not
//! depend on its index (its draws come from [`run_seed`](super::montecarlo::run_seed)
//! alone), so interleaving would balance nothing, while a block keeps each
//! shard's `runs.csv` a contiguous slice of the unsharded one (merging is
//! concatenation in shard order) and says at a glance which runs a shard
//! holds (`first_run`, `end_run`).

use std::fmt;
use std::ops::Range;
use std::str::FromStr;

/// Shard `index` of `count` (1-based, as written on the command line:
/// `--shard 2/8`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Shard {
    /// Which shard, 1 ..= `count`.
    pub index: u64,
    /// How many shards the campaign is split into (≥ 1).
    pub count: u64,
}

/// A `--shard` value that is not `K/N` with 1 ≤ K ≤ N, or a shard count
/// above the number of runs.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    /// Not of the form `K/N` with integers.
    #[error("shard `{0}` is not K/N (e.g. 2/8: the 2nd of 8 shards)")]
    Syntax(String),
    /// K or N out of range.
    #[error("shard `{text}`: need 1 <= K <= N (got K = {index}, N = {count})")]
    OutOfRange {
        /// The value as given.
        text: String,
        /// K.
        index: u64,
        /// N.
        count: u64,
    },
    /// More shards than runs: some shard would fly nothing.
    #[error(
        "shard {index}/{count}: {count} shards for {runs} runs, but every shard needs at least one run (use N <= runs)"
    )]
    MoreShardsThanRuns {
        /// K.
        index: u64,
        /// N.
        count: u64,
        /// Runs of the campaign.
        runs: u64,
    },
}

impl Shard {
    /// The whole campaign as one shard (`1/1`).
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// Shard `index` of `count`, checked (1 ≤ index ≤ count).
    pub fn new(index: u64, count: u64) -> Result<Self, ShardError> {
        if count == 0 || index == 0 || index > count {
            return Err(ShardError::OutOfRange { text: format!("{index}/{count}"), index, count });
        }
        Ok(Self { index, count })
    }

    /// Run indices of this shard in a campaign of `runs` runs: the block
    /// `[⌊(K−1)·runs/N⌋, ⌊K·runs/N⌋)`. The N blocks are disjoint, cover
    /// `0..runs` and differ in size by at most one run.
    pub fn range(&self, runs: u64) -> Result<Range<u64>, ShardError> {
        if self.count > runs {
            return Err(ShardError::MoreShardsThanRuns { index: self.index, count: self.count, runs });
        }
        let bound = |k: u64| (u128::from(k) * u128::from(runs) / u128::from(self.count)) as u64;
        Ok(bound(self.index - 1)..bound(self.index))
    }

    /// Folder name of this shard's results for scenario `name`:
    /// `<name>-shard-K-of-N`, K zero-padded to N's width so the folders sort
    /// in shard order.
    pub fn folder_name(&self, name: &str) -> String {
        let width = self.count.to_string().len();
        format!("{name}-shard-{:0width$}-of-{}", self.index, self.count)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = ShardError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let (k, n) = text.split_once('/').ok_or_else(|| ShardError::Syntax(text.to_string()))?;
        let parse = |s: &str| s.trim().parse::<u64>().map_err(|_| ShardError::Syntax(text.to_string()));
        let (index, count) = (parse(k)?, parse(n)?);
        Shard::new(index, count).map_err(|_| ShardError::OutOfRange { text: text.to_string(), index, count })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_run_once_in_blocks_of_nearly_equal_size() {
        for runs in [1u64, 2, 7, 10, 1000, 1001] {
            for count in 1..=runs.min(13) {
                let ranges: Vec<Range<u64>> =
                    (1..=count).map(|k| Shard::new(k, count).unwrap().range(runs).unwrap()).collect();
                assert_eq!(ranges[0].start, 0);
                assert_eq!(ranges.last().unwrap().end, runs);
                assert!(ranges.windows(2).all(|w| w[0].end == w[1].start), "{runs} {count}: {ranges:?}");
                let sizes: Vec<u64> = ranges.iter().map(|r| r.end - r.start).collect();
                assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1, "{sizes:?}");
                assert!(sizes.iter().all(|&s| s >= 1));
            }
        }
        let huge = Shard::new(3, 3).unwrap().range(u64::MAX).unwrap();
        assert_eq!(huge.end, u64::MAX);
    }

    #[test]
    fn bad_shards_are_refused_with_the_value() {
        assert_eq!("2/8".parse::<Shard>().unwrap(), Shard { index: 2, count: 8 });
        for bad in ["2", "a/3", "2/", "/3", "-1/3", "1.5/3"] {
            let e = bad.parse::<Shard>().unwrap_err();
            assert!(matches!(e, ShardError::Syntax(_)), "{bad}: {e}");
            assert!(e.to_string().contains(bad));
        }
        for bad in ["0/3", "4/3", "1/0"] {
            let e = bad.parse::<Shard>().unwrap_err().to_string();
            assert!(e.contains(bad) && e.contains("1 <= K <= N"), "{e}");
        }
        let e = Shard::new(1, 5).unwrap().range(3).unwrap_err().to_string();
        assert!(e.contains("5 shards for 3 runs"), "{e}");
        assert_eq!(Shard::new(7, 120).unwrap().folder_name("s"), "s-shard-007-of-120");
    }
}
