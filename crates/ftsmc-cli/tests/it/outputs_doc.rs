//! Column dictionary: every CSV column and every JSON key that `reproduce`,
//! `run`, `montecarlo` (and its shards), `merge` and `fixed-time` write is named in docs/outputs.md,
//! so adding an output without documenting it fails here.
//!
//! The doc's notation generalises names: `<axis>` (x … psi), `<signal>`
//! (thrust … yaw_torque), `<scenario>`, `<controller>`, `<metric>` (a
//! runs.csv metric column) and `[]` for array elements; a name counts as
//! documented when it, or its generalised form, is the first cell of a
//! table row (`| \`name\` | unit | meaning |`), not merely mentioned.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

use crate::common::scratch;

const AXES: [&str; 6] = ["x", "y", "z", "phi", "theta", "psi"];
const SIGNALS: [&str; 4] = ["thrust", "roll_torque", "pitch_torque", "yaw_torque"];

fn ftsmc(args: &[&str], cwd: &Path) {
    let out = Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).current_dir(cwd).output().expect("binary runs");
    assert!(out.status.success(), "ftsmc {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// The names docs/outputs.md gives a table row of their own: the
/// backticked first cell of each row.
fn documented() -> BTreeSet<String> {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/outputs.md")).unwrap();
    doc.lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|rest| rest.split_once("` |").map(|(name, _)| name.to_string()))
        .collect()
}

/// `name` with a trailing `_<axis>` or `_<signal>` generalised.
fn generalised_column(name: &str) -> Option<String> {
    for s in SIGNALS {
        if let Some(prefix) = name.strip_suffix(&format!("_{s}")) {
            return Some(format!("{prefix}_<signal>"));
        }
    }
    for a in AXES {
        if let Some(prefix) = name.strip_suffix(&format!("_{a}")) {
            return Some(format!("{prefix}_<axis>"));
        }
    }
    None
}

fn column_documented(doc: &BTreeSet<String>, name: &str) -> bool {
    doc.contains(name) || generalised_column(name).is_some_and(|g| doc.contains(&g))
}

/// Headers of every `.csv` below `dir`, as (file, column).
fn csv_columns(dir: &Path, out: &mut Vec<(PathBuf, String)>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let p = entry.path();
        if p.is_dir() {
            csv_columns(&p, out);
        } else if p.extension().is_some_and(|e| e == "csv") {
            let text = std::fs::read_to_string(&p).unwrap();
            for name in text.lines().next().unwrap_or("").split(',') {
                out.push((p.clone(), name.to_string()));
            }
        }
    }
}

/// Dotted paths of every leaf of `v`, generalised: scenario and controller
/// levels, Monte Carlo metric names, axis and signal names, array elements.
fn key_paths(v: &Value, path: &mut Vec<String>, out: &mut BTreeSet<String>) {
    match v {
        Value::Object(map) => {
            for (k, child) in map {
                let depth = path.len();
                let seg = match (path.first().map(String::as_str), depth) {
                    (Some("scenarios"), 1) => "<scenario>".to_string(),
                    (Some("scenarios"), 2) | (Some("controllers"), 1) => "<controller>".to_string(),
                    (Some("controllers"), 3) if path[2] == "metrics" => "<metric>".to_string(),
                    (Some("table3"), 3) => "<controller>".to_string(),
                    _ if AXES.contains(&k.as_str()) => "<axis>".to_string(),
                    _ if SIGNALS.contains(&k.as_str()) => "<signal>".to_string(),
                    _ => k.clone(),
                };
                path.push(seg);
                key_paths(child, path, out);
                path.pop();
            }
        }
        Value::Array(items) if items.iter().any(|i| i.is_object() || i.is_array()) => {
            let last = path.pop().unwrap_or_default();
            path.push(format!("{last}[]"));
            for item in items {
                key_paths(item, path, out);
            }
            path.pop();
            path.push(last);
        }
        _ => {
            out.insert(path.join("."));
        }
    }
}

fn json_paths(file: &Path) -> BTreeSet<String> {
    let v: Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
    let mut out = BTreeSet::new();
    key_paths(&v, &mut Vec::new(), &mut out);
    out
}

#[test]
fn every_csv_column_and_json_key_is_in_docs_outputs_md() {
    let tmp = scratch("all");
    let dir = tmp.path();
    ftsmc(&["reproduce", "--no-figures", "--realistic-runs", "4", "--out", "repro"], dir);
    // A run that diverges (FTAFTSMC under a 1000 rad/s rotor limit tilts
    // over at 0.64 s) writes the divergence keys too.
    let scenario = Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(["scenario", "paper-scenario-1"]).output().unwrap();
    let text = String::from_utf8(scenario.stdout).unwrap();
    assert!(text.contains("\nduration = 20.0"), "scenario text changed; adjust this test");
    let text = text.replacen("\nduration = 20.0", "\nduration = 1.0", 1).replacen(
        "[simulation]\n",
        "[simulation]\nmax_rotor_speed = 1000.0\n",
        1,
    );
    std::fs::write(dir.join("diverging.toml"), text).unwrap();
    ftsmc(&["run", "diverging.toml", "--no-figures", "--out", "run"], dir);
    ftsmc(&["montecarlo", "paper-scenario-2", "--runs", "3", "--no-figures", "--out", "mc"], dir);
    ftsmc(&["montecarlo", "paper-scenario-2", "--runs", "3", "--shard", "1/1", "--no-figures", "--out", "shards"], dir);
    ftsmc(&["merge", "shards/paper-scenario-2-shard-1-of-1", "--no-figures", "--out", "merged"], dir);
    ftsmc(&["fixed-time", "--per-decade", "1", "--out", "ft"], dir);

    let doc = documented();
    let mut missing = BTreeSet::new();

    let mut columns = Vec::new();
    csv_columns(dir, &mut columns);
    let files: BTreeSet<String> =
        columns.iter().map(|(f, _)| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    for expected in ["ftaftsmc.csv", "ranftsmc.csv", "tsm-sta.csv", "runs.csv", "fixed-time.csv"] {
        assert!(files.contains(expected), "{expected} not written: {files:?}");
    }
    for (file, name) in &columns {
        if !column_documented(&doc, name) {
            missing.insert(format!("column `{name}` of {}", file.display()));
        }
    }

    let mut json_files = Vec::new();
    // `--out DIR` is the parent: montecarlo and fixed-time write `DIR/<scenario name>/`.
    for rel in [
        "repro/summary.json",
        "mc/paper-scenario-2/summary.json",
        "shards/paper-scenario-2-shard-1-of-1/summary.json",
        "merged/paper-scenario-2/summary.json",
        "ft/paper-scenario-1/fixed-time.json",
    ] {
        json_files.push(dir.join(rel));
    }
    let run_summary = std::fs::read_dir(dir.join("run")).unwrap().flatten().next().unwrap().path().join("summary.json");
    json_files.push(run_summary);
    let mut all_paths = BTreeSet::new();
    for file in &json_files {
        for path in json_paths(file) {
            if !doc.contains(&path) {
                missing.insert(format!("key `{path}` of {}", file.display()));
            }
            all_paths.insert(path);
        }
    }
    // The test must see what it claims to check.
    for p in [
        "scenarios.<scenario>.<controller>.exit_status.divergence.reason",
        "scenarios.<scenario>.<controller>.ise_window.<axis>",
        "table3.<axis>.ours.<controller>",
        "controllers.<controller>.metrics.<metric>.median",
        "channels[].bound",
        "shard.first_run",
        "provenance.merged_from[].provenance.scenario_sha256",
    ] {
        assert!(all_paths.contains(p), "{p} not produced: {all_paths:?}");
    }
    // Monte Carlo metric names are runs.csv columns, documented there.
    let mc: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("mc/paper-scenario-2/summary.json")).unwrap()).unwrap();
    for (_, c) in mc["controllers"].as_object().unwrap() {
        for metric in c["metrics"].as_object().unwrap().keys() {
            if !column_documented(&doc, metric) {
                missing.insert(format!("Monte Carlo metric `{metric}`"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "not documented in docs/outputs.md:\n{}",
        missing.into_iter().collect::<Vec<_>>().join("\n")
    );
}

#[test]
fn generalisation_keeps_undocumented_names_undocumented() {
    let doc = documented();
    assert!(column_documented(&doc, "delta_hat_theta"));
    assert!(column_documented(&doc, "control_energy_yaw_torque"));
    assert!(column_documented(&doc, "omega_3"));
    assert!(!column_documented(&doc, "est_x_0"));
    assert!(!column_documented(&doc, "omega_5"));
    assert!(!column_documented(&doc, "brand_new_x"));
    // Mentioned in prose only is not enough.
    assert!(!doc.contains("est_<axis>_0") && !doc.contains("<controller>"));
}

/// The rows of docs/outputs.md's `ftsmc tune` section: for each table row,
/// the backticked names of its first cell and the whole row's text.
fn tune_section_rows() -> Vec<(Vec<String>, String)> {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/outputs.md")).unwrap();
    let start = doc.find("## Tuning: `ftsmc tune`").expect("docs/outputs.md has a tune section");
    let section = &doc[start..];
    let end = section[3..].find("\n## ").map_or(section.len(), |e| e + 3);
    section[..end]
        .lines()
        .filter(|l| l.starts_with("| `"))
        .map(|l| {
            let first = l[1..].split(" | ").next().unwrap_or("");
            let names =
                first.split(", ").filter_map(|n| n.trim().strip_prefix('`')?.strip_suffix('`')).map(String::from);
            (names.collect(), l.to_string())
        })
        .collect()
}

#[test]
fn every_column_and_key_of_tune_is_in_docs_outputs_md() {
    let tmp = scratch("tune-doc");
    let dir = tmp.path();
    // A budget with a race (one screening draw, four final ones).
    let tiny = "extends = \"realistic-scenario-2\"\nname = \"tiny\"\nduration = 0.5\n\n[tune]\nruns = 2\n\
                population = 4\nvalidation_runs = 4\nrace = 2\nrace_runs = 1\nrace_final_runs = 4\n";
    std::fs::write(dir.join("tiny.toml"), tiny).unwrap();
    ftsmc(&["tune", "tiny.toml", "-c", "pid", "--budget", "150", "--no-figures", "--out", "t"], dir);
    let folder = dir.join("t").join("tiny");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("pid.summary.json")).unwrap()).unwrap();
    let rows = tune_section_rows();
    let names: BTreeSet<&str> = rows.iter().flat_map(|(n, _)| n.iter().map(String::as_str)).collect();
    let row_of = |name: &str| rows.iter().find(|(n, _)| n.iter().any(|x| x == name)).map(|(_, r)| r.as_str());
    let mut missing = Vec::new();

    // history.csv: every column, the searched parameters as `<parameter>`.
    let parameters: BTreeSet<String> = summary["best"]["parameters"].as_object().unwrap().keys().cloned().collect();
    assert!(!parameters.is_empty() && names.contains("<parameter>"));
    let history = std::fs::read_to_string(folder.join("pid.history.csv")).unwrap();
    let columns: Vec<&str> = history.lines().next().unwrap().split(',').collect();
    for c in &columns {
        if !names.contains(c) && !parameters.contains(*c) {
            missing.push(format!("history.csv column `{c}`"));
        }
    }
    // summary.json: every top-level key (a dotted row `best.cost` documents
    // `best`, a row `race[]` the array `race`).
    for key in summary.as_object().unwrap().keys() {
        let dotted = format!("{key}.");
        let array = format!("{key}[]");
        if !names.contains(key.as_str())
            && !names.contains(array.as_str())
            && !names.iter().any(|n| n.starts_with(&dotted))
        {
            missing.push(format!("summary.json key `{key}`"));
        }
    }
    // The fields of the arrays' entries, named in their row.
    for array in ["generations", "race"] {
        let row = row_of(&format!("{array}[]")).unwrap_or_else(|| panic!("no row for `{array}[]`"));
        let entries = summary[array].as_array().unwrap();
        assert!(!entries.is_empty(), "{array} is empty: the test must see its fields");
        for field in entries.iter().flat_map(|e| e.as_object().unwrap().keys()) {
            if !row.contains(&format!("`{field}`")) {
                missing.push(format!("summary.json `{array}[].{field}`"));
            }
        }
    }
    // Statistics objects are "the history.csv statistic columns, by name".
    let finalist = summary["race"].as_array().unwrap().iter().find(|r| !r["stats"].is_null()).expect("a finalist");
    for stats in [&summary["training"]["start"], &summary["held_out"]["tuned"], &finalist["screen_stats"]] {
        for field in stats.as_object().unwrap().keys() {
            if !columns.contains(&field.as_str()) {
                missing.push(format!("statistic `{field}` is not a history.csv column"));
            }
        }
    }
    missing.sort();
    missing.dedup();
    assert!(missing.is_empty(), "not documented in docs/outputs.md's tune section:\n{}", missing.join("\n"));
}
