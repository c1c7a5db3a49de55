//! Analyses built on flights: the fixed-time sweep ([`fixed_time`]), gain
//! tuning ([`tuning`]) and missions with their tracking metrics ([`missions`]).

pub mod fixed_time;
pub mod missions;
pub mod tuning;
