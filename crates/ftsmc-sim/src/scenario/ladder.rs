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

/// A rung in a user's words, computed from its scenario's `[wind]`
/// ([`crate::environment::wind::WindParams::in_words`]): its level (the
/// wind preset's name, else `custom`), then the mean wind in m/s at its
/// altitude with its Beaufort force and the turbulence intensity, e.g.
/// `light: 7.4 m/s mean wind at 5 m (Beaufort 5, fresh breeze), light
/// turbulence (MIL-F-8785C, W₂₀ 15 kt, σ_u 1.50 m/s)`. `None` for a
/// scenario without `[wind]`.
pub fn rung_words(scenario: &super::Scenario) -> Option<String> {
    let wind = scenario.wind.as_ref()?;
    Some(format!("{}: {}", level(wind), wind.in_words()))
}

/// [`rung_words`] short enough for a figure title
/// ([`crate::environment::wind::WindParams::in_short_words`]), e.g.
/// `light: 7.4 m/s mean wind at 5 m, light turbulence`.
pub fn rung_title(scenario: &super::Scenario) -> Option<String> {
    let wind = scenario.wind.as_ref()?;
    Some(format!("{}: {}", level(wind), wind.in_short_words()))
}

/// The rung's level: its wind preset's name, else `custom`.
fn level(wind: &crate::environment::wind::WindParams) -> &'static str {
    wind.preset.map_or("custom", |p| match p {
        crate::environment::wind::WindPreset::Calm => "calm",
        crate::environment::wind::WindPreset::Breeze => "breeze",
        crate::environment::wind::WindPreset::Light => "light",
        crate::environment::wind::WindPreset::Moderate => "moderate",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_rung_names_its_level_and_its_wind_from_its_file() {
        for (file, text) in LADDER {
            let s = super::super::Scenario::from_toml_str(text, file).unwrap();
            let words = rung_words(&s).expect("every rung has [wind]");
            let level = file.trim_start_matches("realistic-").split('-').next().unwrap();
            assert!(words.starts_with(&format!("{level}: ")), "{file}: {words}");
            let expected = match level {
                "calm" => "still air",
                "breeze" => "2.5 m/s mean wind at 5 m (Beaufort 2, light breeze)",
                "light" => "7.4 m/s mean wind at 5 m (Beaufort 5, fresh breeze), light turbulence",
                _ => "14.8 m/s mean wind at 5 m (Beaufort 7, near gale), moderate turbulence",
            };
            assert!(words.contains(expected), "{file}: {words}");
            let title = rung_title(&s).unwrap();
            assert!(title.starts_with(&format!("{level}: ")) && title.len() < words.len(), "{title}");
        }
    }
}
