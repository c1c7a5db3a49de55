//! The saturation remedies of `ftsmc_core::cascade` in
//! scenario files: the defaults serialise without the new keys (so nothing
//! written today changes) and re-load equal; the keys load from a
//! scenario's `[cascade]` table, and bad thrust limits are refused with an
//! error naming the file, the key and the value.

use ftsmc_core::cascade::CascadeSettings;
use ftsmc_sim::scenario::{Scenario, PAPER_SCENARIO_1};

#[test]
fn default_settings_serialise_without_the_remedy_keys_and_reload_equal() {
    let text = toml::to_string(&CascadeSettings::default()).unwrap();
    assert!(!text.contains("thrust_limits") && !text.contains("freeze_adaptation"), "{text}");
    assert_eq!(toml::from_str::<CascadeSettings>(&text).unwrap(), CascadeSettings::default());

    let on = CascadeSettings {
        thrust_limits: Some([0.5, 28.0]),
        freeze_adaptation_on_saturation: true,
        ..CascadeSettings::default()
    };
    let text = toml::to_string(&on).unwrap();
    assert!(text.contains("thrust_limits") && text.contains("freeze_adaptation_on_saturation = true"), "{text}");
    assert_eq!(toml::from_str::<CascadeSettings>(&text).unwrap(), on);
}

fn with_cascade_keys(keys: &str) -> String {
    let text = PAPER_SCENARIO_1.replacen("[cascade]\n", &format!("[cascade]\n{keys}\n"), 1);
    assert_ne!(text, PAPER_SCENARIO_1, "the paper scenario has a [cascade] table");
    text
}

#[test]
fn scenario_files_take_the_remedies_and_validate_them() {
    assert_eq!(
        Scenario::from_toml_str(PAPER_SCENARIO_1, "s.toml").unwrap().cascade,
        CascadeSettings { max_tilt: 0.6, ..CascadeSettings::default() }
    );
    let s = Scenario::from_toml_str(
        &with_cascade_keys("thrust_limits = [0.0, 28.0]\nfreeze_adaptation_on_saturation = true"),
        "s.toml",
    )
    .unwrap();
    assert_eq!(s.cascade.thrust_limits, Some([0.0, 28.0]));
    assert!(s.cascade.freeze_adaptation_on_saturation);

    for (keys, field, value) in [
        ("thrust_limits = [5.0, 1.0]", "thrust_limits[1]", "1"),
        ("thrust_limits = [-1.0, 10.0]", "thrust_limits[0]", "-1"),
    ] {
        let err = Scenario::from_toml_str(&with_cascade_keys(keys), "bad.toml").unwrap_err().to_string();
        assert!(err.starts_with("bad.toml") && err.contains(field) && err.contains(value), "{err}");
    }
}
