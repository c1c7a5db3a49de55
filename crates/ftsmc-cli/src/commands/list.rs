//! `ftsmc list`: the controllers, the built-in scenarios and the vehicle presets.

use anyhow::Result;
use ftsmc_sim::registry;
use ftsmc_sim::scenario::{Scenario, BUILT_IN_SCENARIOS};

/// Runs `ftsmc list`.
pub fn run() -> Result<()> {
    print!("{}", list_text()?);
    Ok(())
}

/// `ftsmc list`: every controller of the registry and every built-in
/// scenario (`BUILT_IN_SCENARIOS`), names in one aligned column.
fn list_text() -> Result<String> {
    let scenarios = BUILT_IN_SCENARIOS
        .iter()
        .map(|(file, text)| {
            let s = Scenario::from_toml_str(text, file)?;
            // A scenario with wind says it in a user's words, computed from its [wind].
            let description = match ftsmc_sim::scenario::ladder::rung_words(&s) {
                Some(words) => format!("{} — {words}", s.description),
                None => s.description,
            };
            Ok((file.trim_end_matches(".toml").to_string(), description))
        })
        .collect::<Result<Vec<_>>>()?;
    let width = registry::CONTROLLERS
        .iter()
        .map(|(name, _)| name.chars().count())
        .chain(scenarios.iter().map(|(name, _)| name.chars().count()))
        .max()
        .unwrap_or(0);
    let mut text = String::from("controllers (-c/--controllers):\n");
    for (name, what) in registry::CONTROLLERS {
        text.push_str(&format!("  {name:<width$}  {what}\n"));
    }
    text.push_str("built-in scenarios (ftsmc run NAME, ftsmc scenario NAME):\n");
    for (name, what) in &scenarios {
        text.push_str(&format!("  {name:<width$}  {what}\n"));
    }
    text.push_str("vehicle presets ([vehicle] preset = NAME, --set vehicle.preset=NAME; docs/vehicles.md):\n");
    for preset in ftsmc_sim::vehicle::VehiclePreset::ALL {
        text.push_str(&format!("  {:<width$}  {}\n", preset.name(), preset.description()));
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn list_names_every_built_in_scenario_and_vehicle_preset_in_one_aligned_column() {
        let text = list_text().unwrap();
        for (file, _) in BUILT_IN_SCENARIOS {
            assert!(text.contains(file.trim_end_matches(".toml")), "{file} missing:\n{text}");
        }
        let starts: Vec<usize> = text
            .lines()
            .filter(|l| l.starts_with("  "))
            .map(|l| {
                let name_end = 2 + l[2..].find(' ').unwrap();
                name_end + l[name_end..].chars().take_while(|c| *c == ' ').count()
            })
            .collect();
        let presets = ftsmc_sim::vehicle::VehiclePreset::ALL;
        assert_eq!(starts.len(), registry::CONTROLLERS.len() + BUILT_IN_SCENARIOS.len() + presets.len());
        for p in presets {
            assert!(
                text.lines().any(|l| l.trim_start().starts_with(p.name()) && l.ends_with(&p.description())),
                "{text}"
            );
        }
        for (name, what) in registry::CONTROLLERS {
            assert!(text.lines().any(|l| l.trim_start().starts_with(name) && l.ends_with(what)), "{name}:\n{text}");
        }
        assert!(starts.windows(2).all(|w| w[0] == w[1]), "descriptions not aligned:\n{text}");
    }
}
