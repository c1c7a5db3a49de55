//! Batches of flights: Monte Carlo runs and their statistics ([`montecarlo`]).

pub mod montecarlo;
