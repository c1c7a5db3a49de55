//! All integration tests of this crate in one test binary: one link of the
//! crate (built at opt-level 2 by `[profile.test]`) instead of one per file.
//!
//! A new test file goes here as a module: put it in tests/it/ (with its
//! `.proptest-regressions` file, if any, beside it) and add `mod name;` below;
//! shared helpers are `crate::common` (tests/common/). Keep a test in its own
//! tests/<name>.rs binary only when it needs its process alone (a
//! `#[global_allocator]`, `std::env::set_var`, rayon's global pool).

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/source.rs"]
mod source;

mod actuators;
mod builtin_scenarios;
mod cascade_remedies;
mod closed_loop;
mod crazyflie_firmware;
mod custom_layout;
mod docs_numbers;
mod falsify;
mod gym;
mod hostile_input;
mod import_cycles;
mod ladder;
mod lanes;
mod layout;
mod lean_agreement;
mod margin;
mod mixer_px4;
mod mixer_px4_sequential;
mod montecarlo;
mod paper_values;
mod practitioners;
mod px4_params;
mod realism;
mod realistic_montecarlo;
mod recording_csv;
mod registry;
mod rigid_body;
mod rigid_body_rescale;
mod run_loop;
mod scenario_2;
mod scenario_ergonomics;
mod scenario_files;
mod sensor_pipeline;
mod sensor_stages;
mod sensors;
mod sensors_body;
mod sensors_imu;
mod splitting;
mod splitting_flights;
mod stats;
mod stream_csv;
mod telemetry_split;
mod tilt_names;
mod trajectories;
mod true_vehicle;
mod tune;
mod tune_mission;
mod tuning;
mod vehicle_presets;
mod verdicts;
mod wind;
mod wind_ladder;
