//! The controller declarations (`src/controllers/`): every declared
//! controller builds from the default scenario and flies; names and section
//! keys are unique; every declared gain section is read, defaulted, written
//! and validated like the rest of a scenario; the docs list every controller.

use ftsmc_sim::analysis::fixed_time::{reaching_time_bound, sweep_channel, Sampling, SweepSettings};
use ftsmc_sim::controllers::{GainSections, DECLARED};
use ftsmc_sim::registry::{self, CONTROLLERS};
use ftsmc_sim::{ExitStatus, RunOptions, Scenario, ScenarioError};

const DEFAULT: &str = "name = \"registry\"\nduration = 1.0\n";

fn default_scenario() -> Scenario {
    Scenario::from_toml_str(DEFAULT, "default.toml").expect("the default scenario loads")
}

/// Fly `name` on `scenario`; assert it completes with a finite command at every recorded step.
fn flies(name: &str, scenario: &Scenario) {
    let run = registry::run(name, scenario, RunOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(run.exit, ExitStatus::Completed, "{name} on {}", scenario.name);
    assert_eq!(run.controller, name);
    assert!(run.steps >= 1000, "{name}: {} steps", run.steps);
    for column in ["thrust_cmd", "roll_torque_cmd", "pitch_torque_cmd", "yaw_torque_cmd"] {
        let values = run.recording.column(column);
        assert!(!values.is_empty(), "{name}: no `{column}` recorded");
        assert!(values.iter().all(|v| v.is_finite()), "{name}: non-finite `{column}`");
    }
}

#[test]
fn every_declared_controller_builds_from_the_default_scenario_and_flies_one_second() {
    let hover = default_scenario();
    let mut offset = hover.clone();
    offset.initial_state.position = [0.1, -0.1, 0.2];
    offset.initial_state.attitude[2] = 0.1;
    let mut rigid = Scenario::from_toml_str(&format!("{DEFAULT}[vehicle]\nmodel = \"rigid-body\"\n"), "rigid.toml")
        .expect("rigid-body default loads");
    rigid.initial_state = offset.initial_state;
    assert!(!DECLARED.is_empty());
    for d in DECLARED {
        registry::build(d.name, &hover).unwrap_or_else(|e| panic!("{} does not build: {e}", d.name));
        for scenario in [&hover, &offset, &rigid] {
            flies(d.name, scenario);
        }
    }
}

#[test]
fn names_labels_and_sections_are_unique_and_consistent() {
    let mut names: Vec<&str> = DECLARED.iter().map(|d| d.name).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), DECLARED.len(), "duplicate controller names in the list");
    let mut keys = GainSections::KEYS.to_vec();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), GainSections::KEYS.len(), "duplicate gain-section keys in the list");
    assert_eq!(CONTROLLERS.len(), DECLARED.len());
    for (d, (name, what)) in DECLARED.iter().zip(CONTROLLERS) {
        assert_eq!((d.name, d.description), (*name, *what));
        assert!(GainSections::KEYS.contains(&d.section), "{}: section `{}` not declared", d.name, d.section);
        assert!(!d.label.is_empty() && !d.description.is_empty(), "{}: empty label or description", d.name);
        assert_eq!(registry::label(d.name), d.label);
        assert!(registry::check_name(d.name).is_ok());
        let name_ok = d.name.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-');
        assert!(name_ok, "`{}`: names are lower-case kebab (file names, CLI)", d.name);
    }
    for key in GainSections::KEYS {
        assert!(DECLARED.iter().any(|d| d.section == *key), "section `{key}` is read by no controller");
    }
    for paper in registry::PAPER_CONTROLLERS {
        assert!(registry::check_name(paper).is_ok(), "{paper}");
    }
    let known = registry::check_name("no-such-controller").unwrap_err();
    assert_eq!(known, DECLARED.iter().map(|d| d.name).collect::<Vec<_>>().join(", "));
}

/// The default of section `key` as a TOML table.
fn section_defaults(key: &str) -> toml::Table {
    let all = toml::Table::try_from(GainSections::default()).expect("sections serialize");
    match all.get(key) {
        Some(toml::Value::Table(t)) => t.clone(),
        other => panic!("section `{key}` is not written as a table: {other:?}"),
    }
}

#[test]
fn every_section_rejects_an_unknown_key_by_name_at_its_top_and_in_its_first_sub_table() {
    for key in GainSections::KEYS {
        let text = format!("{DEFAULT}[{key}]\nno_such_gain = 1.0\n");
        let msg = Scenario::from_toml_str(&text, "typo.toml").unwrap_err().to_string();
        assert!(msg.contains("typo.toml") && msg.contains("no_such_gain"), "[{key}]: {msg}");
        assert!(msg.contains("line 4"), "[{key}]: the error points at the line: {msg}");
        let sub = section_defaults(key).into_iter().find(|(_, v)| v.is_table()).map(|(k, _)| k);
        if let Some(sub) = sub {
            let text = format!("{DEFAULT}[{key}.{sub}]\nno_such_gain = 1.0\n");
            let msg = Scenario::from_toml_str(&text, "typo.toml").unwrap_err().to_string();
            assert!(msg.contains("typo.toml") && msg.contains("no_such_gain"), "[{key}.{sub}]: {msg}");
        }
        let text = format!("{DEFAULT}{key} = 3\n");
        let msg = Scenario::from_toml_str(&text, "scalar.toml").unwrap_err().to_string();
        assert!(msg.contains("scalar.toml") && msg.contains("line 3"), "{key} = 3: {msg}");
    }
}

/// The dotted path and value of the first float in `table` (depth first).
fn first_float(table: &toml::Table, prefix: &str) -> Option<(String, f64)> {
    for (k, v) in table {
        let path = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
        match v {
            toml::Value::Float(x) => return Some((path, *x)),
            toml::Value::Table(t) => {
                if let Some(found) = first_float(t, &path) {
                    return Some(found);
                }
            }
            _ => {}
        }
    }
    None
}

#[test]
fn every_section_is_validated_with_the_dotted_key_and_the_writing_file() {
    for key in GainSections::KEYS {
        let (path, _) = first_float(&section_defaults(key), "").unwrap_or_else(|| panic!("[{key}] has no float"));
        let (table, leaf) =
            path.rsplit_once('.').map_or((key.to_string(), path.as_str()), |(t, l)| (format!("{key}.{t}"), l));
        let text = format!("{DEFAULT}[{table}]\n{leaf} = nan\n");
        match Scenario::from_toml_str(&text, "bad.toml") {
            Err(ScenarioError::Invalid { path: file, key: bad, value, .. }) => {
                assert_eq!(file, "bad.toml");
                assert_eq!(bad, format!("{key}.{path}"));
                assert_eq!(value, "NaN");
            }
            other => panic!("[{table}] {leaf} = nan: {other:?}"),
        }
    }
}

#[test]
fn sections_default_write_and_load_back_identically() {
    let defaults = default_scenario();
    assert_eq!(defaults.gains, GainSections::default());
    for scenario in std::iter::once(defaults).chain(Scenario::paper_scenarios()) {
        let text = scenario.to_toml().expect("writes");
        for key in GainSections::KEYS {
            assert!(text.contains(&format!("[{key}.")) || text.contains(&format!("[{key}]")), "[{key}] not written");
        }
        let back = Scenario::from_toml_str(&text, "written.toml").expect("loads back");
        assert_eq!(back, scenario, "{}: written and loaded back differs", scenario.name);
        assert_eq!(back.to_toml().unwrap(), text, "{}: writing is stable", scenario.name);
    }
}

#[test]
fn a_partial_section_keeps_the_other_defaults() {
    let (path, value) = first_float(&section_defaults("ftaftsmc"), "").expect("a float");
    let (table, leaf) = path.rsplit_once('.').expect("nested");
    let changed = value * 1.25;
    let text = format!("{DEFAULT}[ftaftsmc.{table}]\n{leaf} = {changed:?}\n");
    let s = Scenario::from_toml_str(&text, "partial.toml").unwrap();
    let written = toml::Table::try_from(&s.gains).unwrap();
    let mut want = toml::Table::try_from(GainSections::default()).unwrap();
    let mut t = want.get_mut("ftaftsmc").unwrap().as_table_mut().unwrap();
    for part in table.split('.') {
        t = t.get_mut(part).unwrap().as_table_mut().unwrap();
    }
    t.insert(leaf.to_string(), toml::Value::Float(changed));
    assert_eq!(written, want);
}

#[test]
fn the_sweep_and_the_bound_dispatch_through_the_declarations() {
    let scenario = default_scenario();
    let settings = SweepSettings { magnitudes: vec![0.1], t_max: 1.0, ..SweepSettings::default() };
    for d in DECLARED {
        match sweep_channel(d.name, &scenario, 2, &settings, Sampling::Sampled) {
            Ok(times) => {
                assert_eq!(times.len(), 2, "{}: both signs", d.name);
                assert!(times.iter().all(|t| t.diverged_at.is_none()), "{}", d.name);
            }
            Err(e) => assert!(e.contains(d.name) && e.contains("no per-axis"), "{}: {e}", d.name),
        }
    }
    assert!(sweep_channel("no-such-controller", &scenario, 2, &settings, Sampling::Sampled).is_err());
    let bound = reaching_time_bound("ftaftsmc", &scenario, 2).expect("FTAFTSMC has the Eq. 38 bound");
    assert_eq!(Some(bound), reaching_time_bound("ftaftsmc-no-mass", &scenario, 2));
    assert_eq!(bound, scenario.gains.ftaftsmc.z.reaching_time_bound());
    assert_eq!(reaching_time_bound("ranftsmc", &scenario, 2), None);
}

#[test]
fn the_docs_list_every_controller_and_section() {
    let docs = |file: &str| {
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(file))
            .unwrap_or_else(|e| panic!("{file}: {e}"))
    };
    let controllers = docs("docs/controllers.md");
    let scenarios = docs("docs/scenarios.md");
    for d in DECLARED {
        assert!(controllers.contains(&format!("`{}`", d.name)), "docs/controllers.md does not list `{}`", d.name);
    }
    for key in GainSections::KEYS {
        assert!(scenarios.contains(&format!("[{key}")), "docs/scenarios.md does not document `[{key}]`");
    }
    assert!(controllers.contains("## Adding a controller"));
}

/// Every controller's declaration names what `ftsmc tune` may change
/// (possibly nothing, declared as `tune_param::none`): unique non-empty
/// names with a line of documentation, factor bounds around the start 1,
/// and factor 1 leaves the default gains bit for bit; `tunable_controllers`
/// is exactly the controllers with at least one parameter.
#[test]
fn every_declaration_declares_its_tunables() {
    use ftsmc_sim::controllers::tunable::{self, TuneTarget};
    let scenario = default_scenario();
    let mut with_any = Vec::new();
    for d in DECLARED {
        let params = tunable::parameters(d.name).unwrap_or_else(|e| panic!("{}: {e}", d.name));
        assert_eq!(params.len(), (d.tune_parameters)().len(), "{}", d.name);
        let mut names: Vec<&str> = params.iter().map(|p| p.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), params.len(), "{}: duplicate tunable names", d.name);
        for p in &params {
            assert!(!p.name.is_empty() && !p.doc.is_empty(), "{}: {} undocumented", d.name, p.name);
            assert!(0.0 < p.low && p.low <= 1.0 && 1.0 <= p.high, "{}.{}: [{}, {}]", d.name, p.name, p.low, p.high);
            let (mut gains, mut cascade) = (scenario.gains.clone(), scenario.cascade);
            (p.apply)(&mut TuneTarget { gains: &mut gains, cascade: &mut cascade }, 1.0);
            assert!(
                gains == scenario.gains && cascade == scenario.cascade,
                "{}.{}: factor 1 changes gains",
                d.name,
                p.name
            );
        }
        if !params.is_empty() {
            with_any.push(d.name);
        }
    }
    assert_eq!(registry::tunable_controllers(), with_any);
    assert_eq!(with_any, ["ftaftsmc", "ftaftsmc-no-mass", "ranftsmc", "tsm-sta", "pid", "se3"]);
    assert!(tunable::parameters("no-such-controller").is_err());
}
