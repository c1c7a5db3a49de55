//! # ftsmc-core
//!
//! The control laws of *Robust Fixed Time Adaptive Terminal Sliding Mode
//! Control of a QUAUV Under Time Varying Disturbances and Payload* (FTAFTSMC)
//! and its two comparison controllers, as a `no_std` library: no I/O, no
//! allocation, no simulation plumbing.
//!
//! - [`ftaftsmc`]: the fixed-time sliding surface, reaching and adaptive laws (Eq. 5–17).
//! - [`cascade`]: the outer/inner cascade with mass adaptation (Eq. 18–20, 44, 52, 56–58).
//! - [`allocation`]: rotor allocation (Eq. 2).
//! - [`rotor_layout`]: any planar four-rotor layout, its effectiveness and PX4's normalisation of it.
//! - [`model`]: physical parameters (Table 2, corrected), state, reference, command.
//! - [`law`]: the [`law::AxisLaw`] interface all cascaded sliding-mode laws implement.
//! - [`measured`]: the measurement a controller receives (Euler state, and quaternion and body rates when known).
//! - [`kinematics`]: Z-Y-X Euler angles, quaternions, rotation matrices and their rates.
//! - [`pid`]: the PX4 multicopter cascade (P/PID position, quaternion P attitude, PID rates).
//! - [`se3`]: Lee, Leok & McClamroch 2010 geometric control on SE(3).
//! - [`crazyflie_pid`]: the Crazyflie firmware's PID cascade and power distribution (16-bit motor commands).
//! - [`mellinger`]: the Crazyflie firmware's Mellinger controller.
//! - [`estimate`]: state estimators from onboard sensors (Mahony complementary filter, 15-state error-state Kalman filter).
//!
//! Every transcendental function, with or without the default `std`
//! feature, is the pure-Rust `libm` crate's ([`math`]): the same bits on
//! every CPU. `std` only links the standard library for the simulator.
#![cfg_attr(not(feature = "std"), no_std)]
#![warn(missing_docs)]

pub mod allocation;
pub mod cascade;
pub mod controller;
pub mod crazyflie_pid;
pub mod elementary;
pub mod estimate;
pub mod ftaftsmc;
pub mod kinematics;
pub mod lanes;
pub mod lanes_math;
pub mod law;
pub mod math;
pub mod measured;
pub mod mellinger;
pub mod model;
pub mod pid;
pub mod ranftsmc;
pub mod rotor_layout;
pub mod se3;
mod setpoint;
pub mod tsm_sta;

pub use cascade::{Cascade, CascadeConfig, CascadeSettings, MassAdaptation};
pub use controller::{check_input, update_checked, Controller, InvalidInput, SlidingTelemetry, Telemetry};
pub use ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};
pub use law::{AxisLaw, GainError};
pub use measured::{BodyAttitude, Measurement};
pub use model::{Command, QuadState, QuadrotorParams, Reference};
pub use pid::{PidController, PidGains};
pub use se3::{Se3Controller, Se3Gains};
