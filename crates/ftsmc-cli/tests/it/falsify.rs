//! `ftsmc falsify` and `ftsmc failure-probability` as a user runs them:
//! the worst case replays bit for bit with `ftsmc run`, the search is the
//! same on any thread count, bad budgets are refused.

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

use crate::common::scratch;

fn ftsmc(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).current_dir(cwd).output().expect("binary runs")
}

fn ok(out: &Output) -> String {
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// realistic-breeze-1 cut to 3 s, checked from 1.5 s: short flights.
const SHORT: &str = "extends = \"realistic-breeze-1\"\nname = \"short\"\nduration = 3.0\n\
[envelope]\nsettle_after = 1.5\nmax_position_error = 1.5\n\
[falsify]\nbudget = 12\ngusts = 1\ngust_onset = { low = 0.5, high = 2.5 }\n\
gust_length = { low = 0.3, high = 1.5 }\ngust_amplitude = { low = 0.0, high = 3.0 }\n\
gust_direction = { low = -180.0, high = 180.0 }\n";

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn the_worst_case_replays_with_ftsmc_run_and_the_search_ignores_the_thread_count() {
    let tmp = scratch("falsify");
    let dir = tmp.path();
    std::fs::write(dir.join("s.toml"), SHORT).unwrap();
    let stdout = ok(&ftsmc(&["falsify", "s.toml", "-c", "pid", "--threads", "1", "--out", "a", "--no-figures"], dir));
    assert!(stdout.contains("CMA-ES") && stdout.contains("random") && stdout.contains("first violation"), "{stdout}");
    ok(&ftsmc(&["falsify", "s.toml", "-c", "pid", "--threads", "3", "--out", "b", "--no-figures"], dir));
    let history = |d: &str| std::fs::read(dir.join(d).join("short/pid.history.csv")).unwrap();
    assert_eq!(history("a"), history("b"), "same flights and margins on 1 and 3 threads");
    let csv = String::from_utf8(history("a")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 12, "a header and 12 flights per method");

    let summary = json(&dir.join("a/short/pid.summary.json"));
    let margin = summary["worst"]["margin"].as_f64().unwrap();
    assert_eq!(summary["falsify"]["flights"], 12);
    assert_eq!(summary["random"]["flights"], 12);
    // `ftsmc run` of the written worst case: the same margin, bit for bit.
    ok(&ftsmc(&["run", "a/short/pid.worst.toml", "--out", "replay", "--no-figures"], dir));
    let run = json(&dir.join("replay/short-pid-worst/summary.json"));
    let replayed = run["scenarios"]["short-pid-worst"]["pid"]["margin"]["value"].as_f64().unwrap();
    assert_eq!(replayed.to_bits(), margin.to_bits(), "{replayed} vs {margin}");
}

#[test]
fn a_budget_of_zero_is_refused_before_flying() {
    let tmp = scratch("falsify-refuse");
    let dir = tmp.path();
    std::fs::write(dir.join("s.toml"), SHORT).unwrap();
    let out = ftsmc(&["falsify", "s.toml", "-c", "pid", "--budget", "0"], dir);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--budget 0"), "{err}");
    let bad = SHORT.replace("budget = 12", "budget = 0");
    std::fs::write(dir.join("bad.toml"), bad).unwrap();
    let err = String::from_utf8_lossy(&ftsmc(&["falsify", "bad.toml", "-c", "pid"], dir).stderr).into_owned();
    assert!(err.contains("bad.toml") && err.contains("falsify.budget") && err.contains("budget = 0"), "{err}");
    assert!(!dir.join("results").exists(), "nothing written");
    let out = ftsmc(&["failure-probability", "paper-scenario-1", "-c", "pid", "--budget", "100"], dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("[falsify]"), "{err}");
}

/// `--method splitting` on a tiny case: the result names the method, its
/// levels and reliability in the printout, the JSON and the CSV; the same
/// bits on 1 and 2 threads; work beyond `--max-flights` is refused before
/// any flight, naming the limit and how to raise it; a noise-driven
/// scenario defaults to plain Monte Carlo.
#[test]
fn splitting_failure_probability_on_a_tiny_case() {
    let tmp = scratch("failure-probability-splitting");
    let dir = tmp.path();
    std::fs::write(
        dir.join("s.toml"),
        SHORT
            .replace("duration = 3.0", "duration = 2.0")
            .replace("1.5\n[falsify]", "0.15\n[falsify]")
            .replace("settle_after = 1.5", "settle_after = 1.0"),
    )
    .unwrap();
    let args = |threads: &str, out: &str| {
        vec![
            "failure-probability",
            "s.toml",
            "-c",
            "pid",
            "--method",
            "splitting",
            "--particles",
            "4",
            "--repetitions",
            "5",
            "--max-flights",
            "200",
            "--threads",
            threads,
            "--out",
            out,
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>()
    };
    let run = |threads: &str, out: &str| {
        let a = args(threads, out);
        ok(&ftsmc(&a.iter().map(String::as_str).collect::<Vec<_>>(), dir))
    };
    let stdout = run("1", "a");
    assert!(stdout.contains("adaptive multilevel splitting") && stdout.contains("levels per repetition"), "{stdout}");
    assert!(stdout.contains("reliable") || stdout.contains("UNRELIABLE"), "{stdout}");
    run("2", "b");
    let summary = json(&dir.join("a/short/pid.failure-probability.json"));
    assert_eq!(summary["method"], "splitting");
    assert!(summary["reliable"].is_boolean() && summary["levels"].is_number(), "{summary}");
    assert_eq!(summary["splitting"]["repetitions"].as_array().unwrap().len(), 5);
    let flights = summary["flights"].as_u64().unwrap();
    assert!((20..=200).contains(&flights), "{flights}");
    let csv = |d: &str| std::fs::read_to_string(dir.join(d).join("short/pid.failure-probability.csv")).unwrap();
    assert!(
        csv("a").starts_with("method,p,lo,hi,confidence,flights,effective_sample_size,levels,reliable\nsplitting,"),
        "{}",
        csv("a")
    );
    assert_eq!(csv("a"), csv("b"), "same estimate on 1 and 2 threads");
    assert_eq!(summary["splitting"], json(&dir.join("b/short/pid.failure-probability.json"))["splitting"]);

    // 5 repetitions of 4 particles need 20 flights to start: refused at 19.
    let mut a = args("1", "c");
    a[11] = "19".into();
    let out = ftsmc(&a.iter().map(String::as_str).collect::<Vec<_>>(), dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--max-flights 19") && err.contains("--max-flights 20"), "{err}");
    assert!(!dir.join("c").exists(), "nothing written");
    // Plain and cross-entropy: --budget beyond --max-flights is refused too.
    let out = ftsmc(
        &[
            "failure-probability",
            "s.toml",
            "-c",
            "pid",
            "--method",
            "plain",
            "--budget",
            "300",
            "--max-flights",
            "100",
            "--out",
            "d",
        ],
        dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--max-flights 100") && err.contains("--max-flights 300"), "{err}");
    // The rung draws turbulence and sensor noise: plain Monte Carlo by
    // default (the only estimator whose interval held on a real rung).
    let out = ftsmc(
        &["failure-probability", "s.toml", "-c", "pid", "--budget", "300", "--max-flights", "100", "--out", "e"],
        dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--max-flights 300"), "the default is plain: {err}");
}
