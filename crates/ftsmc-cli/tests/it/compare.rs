//! `ftsmc compare`: contestants are controllers or files; a file made for
//! another vehicle is refused (naming the keys) before any flight unless
//! `--allow-other-vehicle`; a short comparison writes its folder with
//! intervals and verdicts.

use std::path::Path;
use std::process::Command;

use crate::common::scratch;

fn ftsmc(args: &[&str], cwd: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).current_dir(cwd).output().expect("binary runs")
}

fn repo() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn unknown_contestants_and_other_vehicles_are_refused_before_flying() {
    let tmp = scratch("refuse");
    let out = ftsmc(&["compare", "realistic-calm-1", "-c", "pid,no-such-thing", "--out", "o"], tmp.path());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("unknown contestant `no-such-thing`") && err.contains("pid"), "{err}");

    // Gains tuned for the paper's plant, offered to the realistic vehicle.
    let file = repo().join("scenarios/tuned/paper-scenario-1-pid.toml");
    let file = file.to_str().unwrap();
    let out = ftsmc(&["compare", "realistic-calm-1", "-c", &format!("se3,{file}"), "--out", "o"], tmp.path());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("vehicle differs") && err.contains("--allow-other-vehicle"), "{err}");
    assert!(err.contains("vehicle.") || err.contains("plant.") || err.contains("actuators"), "{err}");
    // The remedy is on the first line, within its 300 characters.
    let first = err.lines().next().unwrap();
    assert!(first.chars().count() <= 300 && first.contains("--allow-other-vehicle"), "{first}");

    // A Crazyflie file offered to the Hummingbird: the remedy names its preset.
    std::fs::write(
        tmp.path().join("cf.toml"),
        "extends = \"realistic-calm-1\"\nname = \"cf\"\n[vehicle]\npreset = \"crazyflie-2\"\n",
    )
    .unwrap();
    let out = ftsmc(&["compare", "realistic-calm-1", "-c", "pid,cf.toml", "--out", "o"], tmp.path());
    let err = String::from_utf8_lossy(&out.stderr);
    let first = err.lines().next().unwrap();
    assert!(!out.status.success());
    assert!(first.chars().count() <= 300 && first.contains("`--set vehicle.preset=crazyflie-2`"), "{first}");
    assert!(!tmp.path().join("o").exists(), "nothing written for a refused comparison");
}

#[test]
fn a_short_comparison_writes_intervals_and_verdicts() {
    let tmp = scratch("short");
    let out = ftsmc(
        &["compare", "paper-scenario-1", "-c", "pid,se3", "--runs", "3", "--confidence", "0.9", "--out", "o"],
        tmp.path(),
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let dir = tmp.path().join("o/paper-scenario-1");
    for f in ["runs.csv", "summary.json", "report.md", "report.html", "scenario.toml", "forest.svg", "forest.png"] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["confidence"], 0.9);
    assert_eq!(s["verdicts"].as_array().unwrap().len(), 2);
    for c in s["contestants"].as_object().unwrap().values() {
        let r = &c["intervals"]["success_rate"];
        let (lo, e, hi) = (r["lo"].as_f64().unwrap(), r["estimate"].as_f64().unwrap(), r["hi"].as_f64().unwrap());
        assert!(lo <= e && e <= hi, "{r}");
    }
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("90 % intervals") && report.contains("Verdict matrix"), "{report}");
    // The page holds the same tables and the forest plot, and links the data.
    let page = std::fs::read_to_string(dir.join("report.html")).unwrap();
    for part in ["Verdict matrix", "<table>", "<svg", "href=\"runs.csv\"", "href=\"summary.json\""] {
        assert!(page.contains(part), "report.html lacks {part}");
    }
}

/// A tuned file is labelled by what it is, not by its file name.
#[test]
fn a_tuned_file_is_labelled_as_tuned_gains_of_its_scenario() {
    let tmp = scratch("label");
    let file = repo().join("scenarios/tuned/realistic-calm-1-pid.toml");
    let file = file.to_str().unwrap();
    let out = ftsmc(
        &["compare", "realistic-calm-1", "-c", &format!("pid,{file}"), "--runs", "2", "--no-figures", "--out", "o"],
        tmp.path(),
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("o/realistic-calm-1/summary.json")).unwrap())
            .unwrap();
    let names: Vec<&String> = s["contestants"].as_object().unwrap().keys().collect();
    assert!(names.iter().any(|n| n.as_str() == "pid (tuned, hummingbird, calm-1)"), "{names:?}");
}

/// `--min-effect` judges every verdict against a practical margin too; a
/// bad margin is refused naming itself.
#[test]
fn min_effect_adds_practical_verdicts_and_refuses_bad_margins() {
    let tmp = scratch("min-effect");
    let args = ["compare", "paper-scenario-1", "-c", "pid,se3", "--runs", "3", "--no-figures", "--out", "o"];
    let mut with = args.to_vec();
    with.extend(["--min-effect", "rms=0.001", "--min-effect", "success=0.05"]);
    let out = ftsmc(&with, tmp.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let dir = tmp.path().join("o/paper-scenario-1");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["min_effect"]["rms"], 0.001);
    assert_eq!(s["practical"].as_array().unwrap().len(), s["verdicts"].as_array().unwrap().len());
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("practical verdict") && report.contains("two one-sided tests"), "{report}");
    let mut bad = args.to_vec();
    bad.extend(["--min-effect", "tilt=0.1"]);
    let out = ftsmc(&bad, tmp.path());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--min-effect tilt=0.1: unknown metric"), "{err}");
}
