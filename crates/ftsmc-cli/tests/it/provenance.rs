//! Provenance round trip: a result folder's `scenario.toml` is the scenario
//! exactly as flown, so flying it again gives byte-identical results, and
//! `summary.json` says which program, commit, command and scenario made it.

use std::path::Path;
use std::process::Command;

use ftsmc_sim::scenario::{Scenario, BUILT_IN_SCENARIOS};
use serde_json::Value;

use crate::common::scratch;

fn ftsmc(args: &[&str], cwd: &Path) {
    let out = Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).current_dir(cwd).output().expect("binary runs");
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Every file name in `dir` (not recursive), sorted.
fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.path().is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The provenance every result records; returns it without `command_line`.
fn check_provenance(summary: &Value, folder: &Path) -> Value {
    let mut p = summary["provenance"].clone();
    assert_eq!(p["ftsmc_version"], env!("CARGO_PKG_VERSION"));
    let commit = p["git_commit"].as_str().unwrap();
    assert!(
        commit == "unknown" || (commit.len() >= 40 && commit[..40].chars().all(|c| c.is_ascii_hexdigit())),
        "{commit}"
    );
    assert!(p["command_line"].as_array().unwrap().len() >= 2);
    let file = folder.join(p["scenario_file"].as_str().unwrap());
    let bytes = std::fs::read(&file).unwrap();
    assert_eq!(p["scenario_sha256"].as_str().unwrap().len(), 64);
    let text = String::from_utf8(bytes).unwrap();
    let scenario = Scenario::from_toml_str(&text, "scenario.toml").unwrap();
    assert_eq!(p["seed"].as_u64(), Some(scenario.seed));
    p.as_object_mut().unwrap().remove("command_line");
    p
}

#[test]
fn every_built_in_scenario_survives_a_toml_round_trip() {
    for (file, text) in BUILT_IN_SCENARIOS {
        let s = Scenario::from_toml_str(text, file).unwrap();
        let written = toml::to_string(&s).unwrap();
        let back = Scenario::from_toml_str(&written, "scenario.toml").unwrap();
        assert_eq!(back, s, "{file}");
        assert_eq!(toml::to_string(&back).unwrap(), written, "{file}: writing is stable");
    }
}

#[test]
fn rerunning_a_written_scenario_gives_byte_identical_results() {
    let tmp = scratch("run");
    let dir = tmp.path();
    ftsmc(&["run", "paper-scenario-2", "--out", "A", "--no-figures"], dir);
    let a = dir.join("A/paper-scenario-2");
    ftsmc(&["run", a.join("scenario.toml").to_str().unwrap(), "--out", "B", "--no-figures"], dir);
    // The scenario's `name` decides the sub-folder.
    let b = dir.join("B/paper-scenario-2");
    assert_eq!(files(&a), files(&b));
    // summary.json differs in its provenance, and so does its SHA-256 in
    // the manifest; every other line of the manifest is the same.
    for f in files(&a) {
        if f == ".ftsmc-run.manifest" {
            let lines = |p: &Path| -> Vec<String> {
                std::fs::read_to_string(p)
                    .unwrap()
                    .lines()
                    .filter(|l| !l.ends_with(" summary.json") && !l.ends_with(" report.html"))
                    .map(String::from)
                    .collect()
            };
            assert_eq!(lines(&a.join(&f)), lines(&b.join(&f)), "the manifests differ");
        } else if f != "summary.json" && f != "report.html" {
            // summary.json and report.html (which shows it) hold the command line.
            assert!(std::fs::read(a.join(&f)).unwrap() == std::fs::read(b.join(&f)).unwrap(), "{f} differs");
        }
    }
    assert!(files(&a).iter().filter(|f| f.ends_with(".csv")).count() == 3, "{:?}", files(&a));
    let (mut sa, mut sb) = (json(&a.join("summary.json")), json(&b.join("summary.json")));
    assert_eq!(check_provenance(&sa, &a), check_provenance(&sb, &b), "same scenario hash, seed, version");
    sa.as_object_mut().unwrap().remove("provenance");
    sb.as_object_mut().unwrap().remove("provenance");
    assert_eq!(sa, sb, "metrics identical");
}

#[test]
fn rerunning_a_monte_carlo_scenario_gives_an_identical_runs_csv() {
    let tmp = scratch("mc");
    let dir = tmp.path();
    // A short copy, with a master seed and controllers given on the command
    // line: the written scenario must carry both.
    let text = BUILT_IN_SCENARIOS[1].1.replacen("duration = 50.0", "duration = 2.0", 1);
    assert!(text.contains("duration = 2.0"));
    std::fs::write(dir.join("short.toml"), text).unwrap();
    let args = ["--runs", "3", "--no-figures", "--threads", "2"];
    let mut first = vec!["montecarlo", "short.toml", "--seed", "11", "-c", "ftaftsmc,ranftsmc", "--out", "A"];
    first.extend(args);
    ftsmc(&first, dir);
    let a = dir.join("A/paper-scenario-2");
    let scenario = a.join("scenario.toml");
    let mut second = vec!["montecarlo", scenario.to_str().unwrap(), "--out", "B"];
    second.extend(args);
    ftsmc(&second, dir);
    let b = dir.join("B/paper-scenario-2");
    let runs_a = std::fs::read(a.join("runs.csv")).unwrap();
    assert!(runs_a == std::fs::read(b.join("runs.csv")).unwrap(), "runs.csv differs");
    assert_eq!(String::from_utf8(runs_a).unwrap().lines().count(), 1 + 3 * 2);
    let (sa, sb) = (json(&a.join("summary.json")), json(&b.join("summary.json")));
    assert_eq!(sa["master_seed"], 11);
    assert_eq!(check_provenance(&sa, &a), check_provenance(&sb, &b));
    assert_eq!(sa["controllers"], sb["controllers"]);
}

#[test]
fn reproduce_and_fixed_time_record_their_scenarios() {
    let tmp = scratch("reproduce");
    let dir = tmp.path();
    ftsmc(&["reproduce", "--out", "res", "--no-figures", "--realistic-runs", "4"], dir);
    let summary = json(&dir.join("res/summary.json"));
    let list = summary["provenance"]["scenarios"].as_array().unwrap();
    assert!(list.len() >= 2);
    for entry in list {
        let text = std::fs::read_to_string(dir.join("res").join(entry["scenario_file"].as_str().unwrap())).unwrap();
        let s = Scenario::from_toml_str(&text, "scenario.toml").unwrap();
        assert_eq!(entry["seed"].as_u64(), Some(s.seed));
    }
    for name in ["paper-scenario-1", "paper-scenario-2"] {
        assert!(dir.join("res").join(name).join("scenario.toml").is_file(), "{name}");
    }

    ftsmc(&["fixed-time", "-c", "ftaftsmc", "--per-decade", "1", "--out", "ft"], dir);
    let folder = dir.join("ft/paper-scenario-1");
    check_provenance(&json(&folder.join("fixed-time.json")), &folder);
}
