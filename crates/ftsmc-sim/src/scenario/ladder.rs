//! The wind ladder: the realistic scenarios `realistic-<level>-<n>`, one
//! vehicle (AscTec Hummingbird, PX4 mixer, motion capture + IMU) flying the
//! paper's scenario `n` (1: steps, 2: helix with payload and disturbances)
//! in ever stronger wind, `level` ∈ [`LEVELS`] (the presets of
//! [`crate::environment::wind::WindPreset`]). `calm` is the base file; the
//! other rungs extend it and change only `[wind]` and `[envelope]`, each
//! with an envelope argued for its conditions in the file.

/// The rungs, calmest first.
pub const LEVELS: [&str; 4] = ["calm", "breeze", "light", "moderate"];

/// `realistic-calm-1`: paper scenario 1 in still air (mocap room), 0.15 m envelope.
pub const REALISTIC_CALM_1: &str = include_str!("../../../../scenarios/realistic-calm-1.toml");
/// `realistic-calm-2`: paper scenario 2 in still air (mocap room), 0.15 m envelope.
pub const REALISTIC_CALM_2: &str = include_str!("../../../../scenarios/realistic-calm-2.toml");
/// `realistic-breeze-1`: scenario 1 in a 5-kt breeze, 0.3 m envelope.
pub const REALISTIC_BREEZE_1: &str = include_str!("../../../../scenarios/realistic-breeze-1.toml");
/// `realistic-breeze-2`: scenario 2 in a 5-kt breeze, 0.3 m envelope.
pub const REALISTIC_BREEZE_2: &str = include_str!("../../../../scenarios/realistic-breeze-2.toml");
/// `realistic-light-1`: scenario 1 in MIL-F-8785C light wind (15 kt), 0.5 m envelope.
pub const REALISTIC_LIGHT_1: &str = include_str!("../../../../scenarios/realistic-light-1.toml");
/// `realistic-light-2`: scenario 2 in MIL-F-8785C light wind (15 kt), 0.5 m envelope.
pub const REALISTIC_LIGHT_2: &str = include_str!("../../../../scenarios/realistic-light-2.toml");
/// `realistic-moderate-1`: scenario 1 in MIL-F-8785C moderate wind (30 kt), 1 m envelope.
pub const REALISTIC_MODERATE_1: &str = include_str!("../../../../scenarios/realistic-moderate-1.toml");
/// `realistic-moderate-2`: scenario 2 in MIL-F-8785C moderate wind (30 kt), 1 m envelope.
pub const REALISTIC_MODERATE_2: &str = include_str!("../../../../scenarios/realistic-moderate-2.toml");

/// The ladder's scenarios `(file name, TOML text)`, rung by rung, scenario
/// 1 before 2.
pub const LADDER: [(&str, &str); 8] = [
    ("realistic-calm-1.toml", REALISTIC_CALM_1),
    ("realistic-calm-2.toml", REALISTIC_CALM_2),
    ("realistic-breeze-1.toml", REALISTIC_BREEZE_1),
    ("realistic-breeze-2.toml", REALISTIC_BREEZE_2),
    ("realistic-light-1.toml", REALISTIC_LIGHT_1),
    ("realistic-light-2.toml", REALISTIC_LIGHT_2),
    ("realistic-moderate-1.toml", REALISTIC_MODERATE_1),
    ("realistic-moderate-2.toml", REALISTIC_MODERATE_2),
];
