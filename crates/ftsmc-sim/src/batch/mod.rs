//! Batches of flights: Monte Carlo runs and their statistics ([`montecarlo`]),
//! the rows of `runs.csv` ([`runs_table`]) and shards of a campaign that
//! several machines fly ([`shard`]), and how sure a batch is: intervals
//! and paired verdicts ([`verdicts`]), and contestants judged against
//! each other on the same draws ([`compare`]); and the refusal of gains
//! published for another vehicle that do not fly this one ([`gains_fit`]).

pub mod compare;
pub mod gains_fit;
pub mod montecarlo;
pub mod runs_table;
pub mod shard;
pub mod verdicts;
