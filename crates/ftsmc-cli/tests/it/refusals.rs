//! Every hostile or nonsensical request is refused before any work: under a
//! time limit, with a non-zero exit code, a one-line `error:` message of at
//! most 300 characters naming the key or limit, and nothing written under
//! `--out`.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::scratch;

/// Longest time a refusal may take (they take milliseconds).
const TIME_LIMIT: Duration = Duration::from_secs(20);

/// Run `ftsmc args… --out <dir>/out/sub` in a fresh directory (with
/// `s.toml` = `scenario` when given) and check the refusal: in time,
/// non-zero exit, one `error:` line containing every `expected` string,
/// nothing under `<dir>/out`. Returns the message (the line without `error: `).
fn refused(test: &str, args: &[&str], scenario: Option<&str>, expected: &[&str]) -> String {
    let tmp = scratch(test);
    let dir = tmp.path();
    if let Some(text) = scenario {
        std::fs::write(dir.join("s.toml"), text).unwrap();
    }
    let out = dir.join("out").join("sub");
    let all: Vec<&str> = args.iter().copied().chain(["--out", out.to_str().unwrap()]).collect();
    let (status, err) = in_time(test, &all, dir);
    assert!(!status.success(), "{test}: must fail, got {status}; stderr: {err}");
    assert_eq!(status.code(), Some(1), "{test}: an error exit, not a crash/abort; stderr: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{test}: one line on stderr:\n{err}");
    // The documented bound on a message's first line: 300 characters.
    // `main` cuts a longer one to 300 ending in `…`: a cut line lost its end.
    let message = lines[0].strip_prefix("error: ").unwrap_or_else(|| panic!("{test}: not an error line: {err}"));
    assert!(message.chars().count() <= 300, "{test}: {} characters: {err}", message.chars().count());
    assert!(!message.ends_with('…'), "{test}: over 300 characters, cut by main: {err}");
    for e in expected {
        assert!(lines[0].contains(e), "{test}: `{e}` missing from: {err}");
    }
    let written: Vec<_> = std::fs::read_dir(dir.join("out")).map(|rd| rd.flatten().collect()).unwrap_or_default();
    assert!(written.is_empty(), "{test}: files written under --out: {written:?}");
    message.to_string()
}

/// Run `ftsmc args…` in `dir` (stdin empty): its exit status and stderr,
/// the child killed and the test failed if it runs past [`TIME_LIMIT`].
fn in_time(test: &str, args: &[&str], dir: &std::path::Path) -> (std::process::ExitStatus, String) {
    let stdout = std::fs::File::create(dir.join("stdout.txt")).unwrap();
    let stderr = std::fs::File::create(dir.join("stderr.txt")).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_ftsmc"))
        .args(args)
        .current_dir(dir)
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .spawn()
        .expect("binary runs");
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > TIME_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{test}: `ftsmc {}` still running after {TIME_LIMIT:?}: not refused", args.join(" "));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    (status, std::fs::read_to_string(dir.join("stderr.txt")).unwrap())
}

/// `ftsmc args…` refused by the argument parser before any work: in time,
/// clap's usage-error exit code 2, a first line `error: …` of at most 300
/// characters containing every `expected` string, nothing written.
fn usage_refused(test: &str, args: &[&str], expected: &[&str]) -> String {
    let tmp = scratch(test);
    let dir = tmp.path();
    let out = dir.join("out");
    let all: Vec<&str> = args.iter().copied().chain(["--out", out.to_str().unwrap()]).collect();
    let (status, err) = in_time(test, &all, dir);
    assert_eq!(status.code(), Some(2), "{test}: `ftsmc {}` must be a usage error; stderr: {err}", args.join(" "));
    let first = err.lines().next().unwrap_or("");
    let message = first.strip_prefix("error: ").unwrap_or_else(|| panic!("{test}: not an error line: {err}"));
    assert!(message.chars().count() <= 300, "{test}: {} characters: {err}", message.chars().count());
    for e in expected {
        assert!(first.contains(e), "{test}: `{e}` missing from the first line: {err}");
    }
    assert!(!out.exists(), "{test}: {} written", out.display());
    message.to_string()
}

fn run_refused(test: &str, extra: &str, expected: &[&str]) {
    let text = format!("name = \"t\"\nduration = 1.0\n{extra}");
    refused(test, &["run", "s.toml"], Some(&text), expected);
}

fn montecarlo_refused(test: &str, dist: &str, expected: &[&str]) {
    let text = format!("name = \"t\"\nduration = 1.0\n[payload]\nmass = 0.2\nstart = 0.0\n[montecarlo]\n{dist}\n");
    refused(test, &["montecarlo", "s.toml", "--runs", "2"], Some(&text), expected);
}

// ---- command-line values ------------------------------------------------

#[test]
fn runs_that_overflow_a_vector() {
    refused("runs-max", &["montecarlo", "paper-scenario-2", "--runs", "18446744073709551615"], None, &["max_flights"]);
}

#[test]
fn runs_that_exhaust_memory() {
    refused(
        "runs-1e12",
        &["montecarlo", "paper-scenario-2", "--runs", "1000000000000"],
        None,
        &["max_flights", "--limit"],
    );
}

#[test]
fn a_million_threads() {
    refused(
        "threads",
        &["montecarlo", "paper-scenario-2", "--runs", "1", "--threads", "1000000"],
        None,
        &["max_threads"],
    );
}

#[test]
fn per_decade_that_overflows() {
    refused("per-decade-max", &["fixed-time", "--per-decade", "18446744073709551615"], None, &["max_sweep_points"]);
}

#[test]
fn per_decade_that_never_ends() {
    refused("per-decade-1e8", &["fixed-time", "--per-decade", "100000000"], None, &["max_sweep_points"]);
}

#[test]
fn a_set_value_that_is_a_toml_fragment() {
    // `v = VALUE` read this as `name = "a"` and a second key, `seed`.
    refused(
        "set-fragment",
        &["run", "paper-scenario-1", "--set", "name=\"a\"\nseed = 4242"],
        None,
        &["--set name", "line break"],
    );
}

#[test]
fn an_unknown_limit_key() {
    refused("limit-key", &["run", "paper-scenario-1", "--limit", "max_stepz=1"], None, &["max_stepz"]);
}

// ---- scenario cost --------------------------------------------------------

#[test]
fn a_billion_substeps() {
    run_refused("substeps", "[simulation]\nsubsteps = 1000000000\n", &["max_steps", "substeps"]);
}

#[test]
fn a_gigahertz_control_rate() {
    run_refused("control-rate", "[simulation]\ncontrol_rate = 1e9\n", &["max_steps"]);
}

#[test]
fn a_million_seconds() {
    refused("duration-1e6", &["run", "s.toml"], Some("name = \"t\"\nduration = 1e6\n"), &["max_steps"]);
}

#[test]
fn megahertz_recording_for_1000_seconds() {
    let text = "name = \"t\"\nduration = 1000.0\n[simulation]\ncontrol_rate = 1e6\nrecord_rate = 1e6\n";
    refused("record-mhz", &["run", "s.toml"], Some(text), &["max_steps"]);
    // With the step limit raised explicitly, the recording itself is refused.
    refused("record-mhz-raised", &["run", "s.toml", "--limit", "max_steps=1e12"], Some(text), &["max_samples"]);
}

// ---- scenario files -------------------------------------------------------

#[test]
fn dev_zero() {
    refused("dev-zero", &["run", "/dev/zero"], None, &["/dev/zero", "regular file"]);
}

#[test]
fn a_fifo() {
    let tmp = scratch("fifo-holder");
    let dir = tmp.path();
    let fifo = dir.join("fifo.toml");
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
    refused("fifo", &["run", fifo.to_str().unwrap()], None, &["regular file"]);
}

#[test]
fn px4_import_of_a_fifo() {
    // `px4 import` read its file with a blocking open: a FIFO hung it.
    let tmp = scratch("px4-fifo-holder");
    let fifo = tmp.path().join("fifo.params");
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
    let fifo = fifo.to_str().unwrap();
    refused("px4-fifo", &["px4", "import", fifo, "--scenario", "realistic-calm-1"], None, &[fifo, "regular file"]);
}

#[test]
fn a_scenario_importing_px4_params_from_a_fifo() {
    let tmp = scratch("px4-params-fifo-holder");
    let fifo = tmp.path().join("fifo.params");
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
    let text =
        format!("extends = \"realistic-calm-1\"\nname = \"p\"\n[pid]\npx4_params = {:?}\n", fifo.to_str().unwrap());
    refused(
        "px4-params-fifo",
        &["run", "s.toml", "-c", "pid"],
        Some(&text),
        &["px4_params", "fifo.params: not a regular file"],
    );
}

#[test]
fn px4_import_of_a_missing_file_says_the_cause_once() {
    let message = refused(
        "px4-missing",
        &["px4", "import", "missing.params", "--scenario", "realistic-calm-1"],
        None,
        &["missing.params"],
    );
    assert_eq!(message.matches("No such file or directory").count(), 1, "{message}");
}

#[test]
fn a_scenario_named_dot_dot() {
    refused("name", &["run", "s.toml"], Some("name = \"..\"\nduration = 1.0\n"), &["`name`"]);
}

// ---- meaningless runs -------------------------------------------------------

#[test]
fn a_duration_below_one_control_period() {
    refused("duration-tiny", &["run", "s.toml"], Some("name = \"t\"\nduration = 5e-324\n"), &["duration", "5e-324"]);
}

#[test]
fn no_controllers() {
    run_refused("no-controllers", "controllers = []\n", &["controllers"]);
}

#[test]
fn extra_array_elements() {
    run_refused(
        "extra-elements",
        "[initial_state]\nposition = [0.5, 0.25, 0.0, 99.0, \"junk\", [1]]\n",
        &["position", "invalid length 6"],
    );
}

#[test]
fn payload_against_the_true_plant() {
    run_refused(
        "payload",
        "[vehicle]\nmass = 0.3\n[payload]\nmass = -0.5\nstart = 0.0\n",
        &["payload.mass", "vehicle.mass"],
    );
}

#[test]
fn infinite_monte_carlo_bounds() {
    // A clamp of `inf` (or `nan`) used to be accepted; a uniform's bounds already were checked.
    montecarlo_refused(
        "mc-inf",
        "mass = { dist = \"normal\", mean = 0.74, std = 0.05, low = 0.5, high = inf }",
        &["montecarlo.mass.high"],
    );
    montecarlo_refused(
        "mc-nan",
        "mass = { dist = \"normal\", mean = 0.74, std = 0.05, low = nan, high = 1.0 }",
        &["montecarlo.mass.low"],
    );
}

#[test]
fn an_overflowing_uniform() {
    montecarlo_refused(
        "mc-overflow",
        "disturbance_phase = { dist = \"uniform\", low = -1.7e308, high = 1.7e308 }",
        &["montecarlo.disturbance_phase.high", "1.7e308"],
    );
}

#[test]
fn a_log_normal_with_infinite_draws() {
    montecarlo_refused(
        "mc-lognormal",
        "inertia_factor = { dist = \"log-normal\", mu = 1000.0, sigma = 0.1 }",
        &["montecarlo.inertia_factor.mu"],
    );
}

#[test]
fn a_negative_mass_draw() {
    montecarlo_refused("mc-mass", "mass = { dist = \"uniform\", low = -0.5, high = 1.0 }", &["`montecarlo.mass`"]);
}

#[test]
fn payload_draws_against_the_true_plant() {
    let text = "name = \"t\"\nduration = 1.0\n[vehicle]\nmass = 0.3\n[payload]\nmass = 0.2\nstart = 0.0\n\
                [montecarlo]\npayload_mass = { dist = \"uniform\", low = -0.5, high = 0.5 }\n";
    refused("mc-payload", &["montecarlo", "s.toml", "--runs", "2"], Some(text), &["montecarlo.payload_mass"]);
}

#[test]
fn limits_given_on_the_command_line_win_over_the_defaults() {
    // Paper scenario 1 is 2e4 steps: a lowered limit refuses it, naming the flag.
    refused("limit-lowered", &["run", "paper-scenario-1", "--limit", "max_steps=1000"], None, &["max_steps = 1000"]);
}

#[test]
fn reproduce_realistic_runs_are_priced() {
    refused(
        "realistic-runs",
        &["reproduce", "--no-figures", "--realistic-runs", "18446744073709551615"],
        None,
        &["--realistic-runs 18446744073709551615", "max_flights", "exceeds the limit"],
    );
    refused(
        "realistic-runs-limit",
        &["reproduce", "--no-figures", "--realistic-runs", "400000", "--limit", "max_flights=1e7"],
        None,
        &["max_output_bytes"],
    );
    refused(
        "reproduce-confidence",
        &["reproduce", "--no-figures", "--confidence", "1.5"],
        None,
        &["--confidence", "1.5"],
    );
    refused(
        "reproduce-worst-case",
        &["reproduce", "--no-figures", "--worst-case-budget", "5"],
        None,
        &["--worst-case-budget 5", "20"],
    );
}

#[test]
fn rigid_body_draws_outside_its_range() {
    let scenario = "extends = \"paper-scenario-1\"\nname = \"s\"\n[vehicle]\nmodel = \"rigid-body\"\n[montecarlo]\nmass = { dist = \"uniform\", low = 1e-9, high = 1.0 }\n";
    refused(
        "rigid-draws",
        &["montecarlo", "s.toml", "--runs", "2"],
        Some(scenario),
        &["s.toml", "montecarlo.mass", "draws in [1e-9, 1]", "rigid body", "mass = 1e-9"],
    );
}

#[test]
fn a_seed_of_2_pow_64_minus_1_writes_a_scenario_that_runs_again() {
    let tmp = scratch("big-seed");
    let dir = tmp.path();
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).current_dir(dir).output().unwrap();
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    };
    run(&[
        "montecarlo",
        "paper-scenario-2",
        "--runs",
        "8",
        "-c",
        "pid",
        "--seed",
        "18446744073709551615",
        "--out",
        "a",
        "--no-figures",
    ]);
    let toml = std::fs::read_to_string(dir.join("a/paper-scenario-2/scenario.toml")).unwrap();
    assert!(toml.contains("seed = \"18446744073709551615\""), "{toml}");
    run(&["montecarlo", "a/paper-scenario-2/scenario.toml", "--runs", "8", "--out", "b", "--no-figures"]);
    assert_eq!(
        std::fs::read(dir.join("a/paper-scenario-2/runs.csv")).unwrap(),
        std::fs::read(dir.join("b/paper-scenario-2/runs.csv")).unwrap()
    );
    // A row seed >= 2^63 from runs.csv flies again through `seed = "<row seed>"`.
    let csv = std::fs::read_to_string(dir.join("a/paper-scenario-2/runs.csv")).unwrap();
    let seeds: Vec<u64> = csv.lines().skip(1).map(|l| l.split(',').nth(1).unwrap().parse().unwrap()).collect();
    let big = *seeds.iter().find(|&&s| s >= 1 << 63).expect("a row seed >= 2^63 among 8");
    let text = format!("extends = \"paper-scenario-2\"\nname = \"row\"\nduration = 0.1\nseed = \"{big}\"\n");
    std::fs::write(dir.join("row.toml"), text).unwrap();
    run(&["run", "row.toml", "-c", "pid", "--out", "c", "--no-figures"]);
    let again = std::fs::read_to_string(dir.join("c/row/scenario.toml")).unwrap();
    assert!(again.contains(&format!("seed = \"{big}\"")), "{again}");
}

#[test]
fn an_inf_limit_never_overflows() {
    // The check is off, but 5 × u64::MAX magnitudes are above the hard bound: an error, not a panic.
    refused(
        "inf-per-decade",
        &["fixed-time", "-c", "pid", "--per-decade", "18446744073709551615", "--limit", "max_sweep_points=inf"],
        None,
        &["hard bound", "max_sweep_points", "9.223372036854776e19"],
    );
}

// ---- limits off: the hard bounds still hold --------------------------------

/// Every limit switched off on the command line.
const LIMITS_OFF: [&str; 14] = [
    "--limit",
    "max_steps=inf",
    "--limit",
    "max_samples=inf",
    "--limit",
    "max_output_bytes=inf",
    "--limit",
    "max_flights=inf",
    "--limit",
    "max_sweep_points=inf",
    "--limit",
    "max_threads=inf",
    "--limit",
    "max_scenario_bytes=inf",
];

/// `args` with every limit off: refused by a hard bound of `key`.
fn refused_with_limits_off(test: &str, args: &[&str], scenario: Option<&str>, key: &str) {
    let all: Vec<&str> = args.iter().copied().chain(LIMITS_OFF).collect();
    refused(test, &all, scenario, &["hard bound", key, "even with"]);
}

#[test]
fn limits_off_matrix() {
    let mc = ["montecarlo", "paper-scenario-2", "--runs"];
    let runs_max = [&mc[..], &["18446744073709551615"]].concat();
    refused_with_limits_off("off-runs-max", &runs_max, None, "max_flights");
    let runs_1e12 = [&mc[..], &["1000000000000"]].concat();
    refused_with_limits_off("off-runs-1e12", &runs_1e12, None, "max_flights");
    let threads = [&mc[..], &["2", "--threads", "100000"]].concat();
    refused_with_limits_off("off-threads", &threads, None, "max_threads");
    refused_with_limits_off("off-per-decade", &["fixed-time", "--per-decade", "100000000"], None, "max_sweep_points");
    let endless = "name = \"t\"\nduration = 1e300\n";
    refused_with_limits_off("off-duration", &["run", "s.toml"], Some(endless), "max_steps");
    // 10¹¹ steps (under the step bound) recording every one: 10¹¹ rows do
    // not fit in any memory.
    let rows = "name = \"t\"\nduration = 1e7\n[simulation]\ncontrol_rate = 1e4\nrecord_rate = 1e4\n";
    refused_with_limits_off("off-rows", &["run", "s.toml"], Some(rows), "max_samples");
    let tune = ["tune", "paper-scenario-2", "-c", "pid", "--budget", "18446744073709551615"];
    refused_with_limits_off("off-tune-budget", &tune, None, "max_flights");
}

#[test]
fn twenty_thousand_gusts_are_priced() {
    // 20,000 gusts on a 10-minute flight: each is evaluated every step, like
    // a sine term, so the flight costs like 10⁸ × 626 steps.
    let gust = "{start=1,duration=1,amplitude=[1,0,0]},";
    let text = format!("name = \"t\"\nduration = 600.0\n[wind]\ngusts = [{}]\n", gust.repeat(20_000));
    refused("gusts", &["run", "s.toml"], Some(&text), &["max_steps", "terms"]);
}

#[test]
fn clap_names_the_flag_of_a_negative_number() {
    let tmp = scratch("negative-budget");
    for (args, flag) in [
        (&["tune", "paper-scenario-1", "-c", "pid", "--budget", "-1"][..], "--budget"),
        (&["montecarlo", "paper-scenario-1", "--runs", "-5"][..], "--runs"),
        (&["montecarlo", "paper-scenario-1", "--threads", "-2"][..], "--threads"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).current_dir(tmp.path()).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.lines().next().unwrap_or("").contains(flag), "{args:?}: {err}");
    }
}

// ---- messages that fit their line ----------------------------------------

#[test]
fn an_unknown_falsify_parameter_fits_the_line_with_its_remedy() {
    // serde listed all 15 [falsify] keys: 307 characters, cut before the end.
    let text = "extends = \"realistic-calm-1\"\nname = \"f\"\n[falsify]\nwind_sped = { low = 0.0, high = 1.0 }\n";
    refused(
        "falsify-key",
        &["falsify", "s.toml", "-c", "pid"],
        Some(text),
        &["`wind_sped`", "did you mean `wind_speed`?"],
    );
}

#[test]
fn an_unknown_set_key_fits_the_line_with_its_remedy() {
    refused(
        "set-key",
        &["run", "paper-scenario-1", "--set", "durtion=5"],
        None,
        &["`durtion`", "did you mean `duration`?"],
    );
    refused(
        "set-key-far",
        &["run", "paper-scenario-1", "--set", "nosuch.key=1"],
        None,
        &["`nosuch`", "docs/scenarios.md"],
    );
}

// ---- contradictory or empty flags ------------------------------------------

#[test]
fn contradictory_flags_are_refused_naming_both() {
    let compare = ["compare", "paper-scenario-1", "-c", "pid,se3"];
    let cases: &[(&[&str], &str, &str)] = &[
        (&["--runs", "4", "--until-decided"], "--runs", "--until-decided"),
        (&["--runs", "4", "--max-runs", "10"], "--runs", "--max-runs"),
        (&["--batch", "10", "--runs", "4"], "--batch", "--runs"),
    ];
    for (i, (extra, a, b)) in cases.iter().enumerate() {
        let args: Vec<&str> = compare.iter().chain(extra.iter()).copied().collect();
        usage_refused(&format!("conflict-compare-{i}"), &args, &[a, b]);
    }
    // --max-runs and --batch mean something only with --until-decided.
    for flag in ["--max-runs", "--batch"] {
        let args: Vec<&str> = compare.iter().copied().chain([flag, "10"]).collect();
        refused(&format!("requires{flag}"), &args, None, &[flag, "needs --until-decided"]);
    }
    // The figure style is meaningless without figures, on every command with --no-figures.
    for command in [
        &["run", "paper-scenario-1"][..],
        &["reproduce"],
        &["montecarlo", "paper-scenario-1"],
        &["falsify", "realistic-calm-1", "-c", "pid"],
        &["compare", "paper-scenario-1", "-c", "pid"],
        &["merge", "a"],
        &["tune", "paper-scenario-1", "-c", "pid"],
    ] {
        let args: Vec<&str> = command.iter().copied().chain(["--no-figures", "--style", "paper"]).collect();
        usage_refused(&format!("style-{}", command[0]), &args, &["--no-figures", "--style"]);
    }
}

#[test]
fn empty_controller_lists_are_refused_on_every_command() {
    for command in [
        &["run", "paper-scenario-1"][..],
        &["fixed-time"],
        &["montecarlo", "paper-scenario-1"],
        &["compare", "paper-scenario-1"],
        &["tune", "paper-scenario-1"],
        &["falsify", "realistic-calm-1"],
        &["failure-probability", "realistic-calm-1"],
    ] {
        for (i, list) in ["", ",", " , "].into_iter().enumerate() {
            let args: Vec<&str> = command.iter().copied().chain(["-c", list]).collect();
            usage_refused(&format!("empty-c-{}-{i}", command[0]), &args, &["--controller", "no controller named"]);
        }
    }
}

#[test]
fn compare_without_controllers_names_the_flag() {
    refused("compare-no-c", &["compare", "paper-scenario-1"], None, &["-c/--controllers"]);
}
