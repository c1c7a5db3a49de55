//! One list of built-in scenarios: `BUILT_IN_SCENARIOS` is what `ftsmc
//! list`, the unknown-scenario errors, `extends` and Python read, and
//! docs/scenarios.md must name every entry of it.

use ftsmc_sim::scenario::resolve::{built_in, built_in_names, built_in_names_joined};
use ftsmc_sim::scenario::{Scenario, BUILT_IN_SCENARIOS};

const DOC: &str = include_str!("../../../../docs/scenarios.md");

#[test]
fn docs_table_names_every_built_in_scenario_and_nothing_else() {
    let section = DOC.split("## Built-in scenarios").nth(1).expect("docs/scenarios.md has `## Built-in scenarios`");
    let section = section.split("\n## ").next().unwrap();
    let documented: Vec<&str> =
        section.lines().filter_map(|l| l.strip_prefix("| `")).filter_map(|l| l.split('`').next()).collect();
    let mut names: Vec<&str> = built_in_names().collect();
    let mut doc_sorted = documented.clone();
    names.sort_unstable();
    doc_sorted.sort_unstable();
    assert_eq!(doc_sorted, names, "docs/scenarios.md's table of built-in scenarios differs from BUILT_IN_SCENARIOS");
}

#[test]
fn every_built_in_name_resolves_loads_and_can_be_extended() {
    assert_eq!(built_in_names().count(), BUILT_IN_SCENARIOS.len());
    for name in built_in_names() {
        let (file, text) = built_in(name).unwrap_or_else(|| panic!("{name} does not resolve"));
        assert_eq!(built_in(&format!("{name}.toml")).map(|(f, _)| f), Some(file));
        Scenario::from_toml_str(text, file).unwrap_or_else(|e| panic!("{file}: {e}"));
        let child = format!("extends = \"{name}\"\nname = \"child\"\n");
        let s = Scenario::from_toml_str(&child, "child.toml").unwrap_or_else(|e| panic!("extends {name}: {e}"));
        assert_eq!(s.name, "child");
    }
}

/// The names an error message lists: `a-1/2` stands for `a-1, a-2`.
pub fn expand(list: &str) -> Vec<String> {
    let mut names = Vec::new();
    for group in list.split(", ") {
        let mut parts = group.split('/');
        let first = parts.next().unwrap();
        names.push(first.to_string());
        let stem = &first[..first.len() - 1];
        names.extend(parts.map(|last| format!("{stem}{last}")));
    }
    names
}

#[test]
fn the_short_list_of_error_messages_stands_for_every_name_in_order() {
    let joined = built_in_names_joined();
    assert_eq!(expand(&joined), built_in_names().collect::<Vec<_>>(), "{joined}");
    assert!(joined.contains("realistic-calm-1/2") && joined.contains("ftaftsmc-tuned-scenario-1,"), "{joined}");
    // With the CLI's `error: no scenario file `<40 chars>` …` around it, it fits its 300-character line.
    assert!(joined.chars().count() <= 200, "{} characters: {joined}", joined.chars().count());
}

#[test]
fn the_unknown_extends_error_lists_every_built_in_scenario() {
    let err = Scenario::from_toml_str("extends = \"no-such-scenario\"\nname = \"x\"\n", "mine.toml")
        .expect_err("an unknown extends target must be refused")
        .to_string();
    assert!(err.contains("mine.toml") && err.contains("no-such-scenario"), "{err}");
    let list = err.rsplit_once('(').expect("a list in parentheses").1.trim_end_matches(')');
    assert_eq!(expand(list), built_in_names().collect::<Vec<_>>(), "{err}");
}
