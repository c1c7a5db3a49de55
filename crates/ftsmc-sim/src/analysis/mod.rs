//! Analyses built on flights: the fixed-time sweep ([`fixed_time`]) and gain
//! tuning ([`tuning`]).

pub mod fixed_time;
pub mod tuning;
