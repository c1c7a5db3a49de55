//! The `ftsmc` binary as a user runs it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn ftsmc(args: &[&str], cwd: &Path) -> Output {
    // RUST_BACKTRACE=1: errors must stay one readable line even then.
    Command::new(env!("CARGO_BIN_EXE_ftsmc"))
        .args(args)
        .current_dir(cwd)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ftsmc-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn scenario_text(name: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    std::fs::read_to_string(root.join(name)).unwrap()
}

fn no_files_with_suffix(dir: &Path, suffix: &str) -> bool {
    std::fs::read_dir(dir).map_or(true, |rd| {
        rd.flatten().all(|e| {
            let p = e.path();
            if p.is_dir() {
                no_files_with_suffix(&p, suffix)
            } else {
                !p.to_string_lossy().ends_with(suffix)
            }
        })
    })
}

#[test]
fn reproduce_from_any_directory_writes_table_json_and_csv() {
    let dir = temp_dir("reproduce");
    let out = ftsmc(&["reproduce", "--out", "res", "--no-figures"], &dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("Table 3") && stdout.contains("0.2674"), "{stdout}");
    assert!(stdout.contains("Headline") && (stdout.contains("**confirmed**") || stdout.contains("**not confirmed**")));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("res/summary.json")).unwrap()).unwrap();
    for c in ["ftaftsmc", "ranftsmc", "tsm-sta"] {
        let run = &summary["scenarios"]["paper-scenario-1"][c];
        for axis in ["x", "y", "z", "psi"] {
            assert!(run["ise"][axis].as_f64().unwrap() > 0.0, "{c} {axis}");
        }
        assert_eq!(run["exit"], "completed");
        assert!(summary["scenarios"]["paper-scenario-2"][c]["iae"]["z"].is_number());
    }
    let csv = std::fs::read_to_string(dir.join("res/paper-scenario-1/ftaftsmc.csv")).unwrap();
    assert!(csv.starts_with("t,x,y,z,phi,theta,psi"));
    assert!(csv.lines().count() > 1000);
    assert!(no_files_with_suffix(&dir, ".tmp"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_bad_scenario_file_is_a_clear_error_not_a_panic() {
    let dir = temp_dir("bad");
    let text = scenario_text("paper-scenario-1.toml").replacen("p = 0.1", "p = 1.2", 1);
    std::fs::write(dir.join("bad.toml"), text).unwrap();
    let out = ftsmc(&["run", "bad.toml", "--out", "res"], &dir);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.toml") && err.contains("ftaftsmc.x.p") && err.contains("1.2"), "{err}");
    assert!(!err.contains("panicked") && !err.contains("backtrace"), "{err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(!dir.join("res").exists(), "a failed run must not leave output");

    std::fs::write(dir.join("typo.toml"), "name = \"t\"\nduration = 1.0\n[plant]\nmas = 1.0\n").unwrap();
    let out = ftsmc(&["run", "typo.toml"], &dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("typo.toml") && err.contains("mas"), "{err}");

    let out = ftsmc(&["run", "missing.toml"], &dir);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("missing.toml"));
    let out = ftsmc(&["run", "paper-scenario-1", "-c", "pid"], &dir);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("unknown controller `pid`"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn montecarlo_csv_is_byte_identical_across_thread_counts() {
    let dir = temp_dir("mc");
    let text = scenario_text("paper-scenario-2.toml").replace("duration = 50.0", "duration = 4.0");
    std::fs::write(dir.join("short.toml"), text).unwrap();
    for threads in ["1", "2"] {
        let out = ftsmc(
            &[
                "montecarlo",
                "short.toml",
                "--runs",
                "4",
                "--seed",
                "9",
                "--threads",
                threads,
                "--out",
                &format!("mc{threads}"),
                "--no-figures",
            ],
            &dir,
        );
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let one = std::fs::read(dir.join("mc1/runs.csv")).unwrap();
    let two = std::fs::read(dir.join("mc2/runs.csv")).unwrap();
    assert_eq!(one, two);
    let text = String::from_utf8(one).unwrap();
    assert_eq!(text.lines().count(), 1 + 4 * 3, "header + runs × controllers");
    assert!(text.lines().next().unwrap().starts_with("run,seed,controller,exit,diverged_at,mass,"));
    let s1 = std::fs::read(dir.join("mc1/summary.json")).unwrap();
    assert_eq!(s1, std::fs::read(dir.join("mc2/summary.json")).unwrap());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn help_names_the_commands() {
    let out = ftsmc(&["--help"], Path::new("."));
    let text = String::from_utf8_lossy(&out.stdout);
    for cmd in ["reproduce", "run", "fixed-time", "montecarlo", "tune-tsm-sta", "scenario", "list"] {
        assert!(text.contains(cmd), "{cmd} missing from --help:\n{text}");
    }
}
