//! Batches of flights: Monte Carlo runs and their statistics ([`montecarlo`])
//! and the rows of `runs.csv` ([`runs_table`]).

pub mod montecarlo;
pub mod runs_table;
