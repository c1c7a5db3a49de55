//! Batches of flights: Monte Carlo runs and their statistics ([`montecarlo`]),
//! the rows of `runs.csv` ([`runs_table`]) and shards of a campaign that
//! several machines fly ([`shard`]), and how sure a batch is: intervals
//! and paired verdicts ([`verdicts`]), and contestants judged against
//! each other on the same draws ([`compare`]).

pub mod compare;
pub mod montecarlo;
pub mod runs_table;
pub mod shard;
pub mod verdicts;
