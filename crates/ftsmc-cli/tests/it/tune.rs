//! `ftsmc tune` end to end, with a tiny budget on a short realistic
//! scenario: the files it writes, that two controllers tuned into one
//! `--out` keep both results, and that the tuned file does not depend on
//! the thread count.

use std::path::Path;
use std::process::{Command, Output};

use tempfile::TempDir;

/// A 1.5 s realistic scenario 2 with 2 training flights per candidate, 4
/// candidates per generation and 3 held-out flights per gain set.
const TINY: &str = r#"extends = "realistic-scenario-2"
name = "tiny-tune"
duration = 1.5

[tune]
runs = 2
validation_runs = 3
population = 4
"#;

/// The start and 3 generations of 4 samples and their mean, the second and
/// third with the anchor beside them, 2 flights each.
const BUDGET: &str = "36";

fn ftsmc(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).current_dir(cwd).output().expect("binary runs")
}

fn ok(args: &[&str], cwd: &Path) {
    let out = ftsmc(args, cwd);
    assert!(out.status.success(), "ftsmc {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// A fresh scratch folder ([`crate::common::scratch`]) holding `tiny.toml`.
fn scratch(name: &str) -> TempDir {
    let d = crate::common::scratch(name);
    std::fs::write(d.path().join("tiny.toml"), TINY).unwrap();
    d
}

fn tune(dir: &Path, controller: &str, threads: &str, out: &str, figures: bool) {
    let mut args = vec!["tune", "tiny.toml", "-c", controller, "--budget", BUDGET, "--threads", threads, "--out", out];
    if !figures {
        args.push("--no-figures");
    }
    ok(&args, dir);
}

/// The tuned file without its `# Made by:` line (which names `--out` and
/// `--threads`): the gains and statistics must be equal.
fn tuned_without_command(path: &Path) -> String {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .filter(|l| !l.starts_with("# Made by:"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn two_controllers_tuned_into_one_folder_keep_both_results() {
    let tmp = scratch("two");
    let dir = tmp.path();
    tune(dir, "pid", "2", "out", true);
    tune(dir, "se3", "2", "out", false);
    let folder = dir.join("out/tiny-tune");
    for c in ["pid", "se3"] {
        for f in ["tuned.toml", "history.csv", "summary.json", "scenario.toml"] {
            assert!(folder.join(format!("{c}.{f}")).is_file(), "{c}.{f} missing after tuning pid then se3");
        }
        // `<sha256> <size> <path>` per file.
        let manifest = std::fs::read_to_string(folder.join(format!(".ftsmc-tune-{c}.manifest"))).unwrap();
        let listed: Vec<&str> = manifest.lines().map(|l| l.splitn(3, ' ').nth(2).unwrap_or("")).collect();
        assert!(listed.contains(&format!("{c}.tuned.toml").as_str()), "{c}'s manifest: {manifest}");
        assert!(listed.iter().all(|l| l.starts_with(&format!("{c}."))), "{c} owns only its files: {manifest}");
    }
    // PID's figure survives SE(3)'s tune without figures.
    assert!(folder.join("pid.convergence.svg").is_file() && folder.join("pid.convergence.png").is_file());
    assert!(!folder.join("se3.convergence.svg").exists());
    // Candidates are independent samples: points, with the search's mean
    // (each on its own generation's draws) as the one line (a dashed line
    // through the points read as a time series).
    let convergence = std::fs::read_to_string(folder.join("pid.convergence.svg")).unwrap();
    assert!(convergence.contains(r#"<g class="points">"#) && !convergence.contains("stroke-dasharray"));
    assert!(convergence.contains(">mean of the search</text>") && convergence.contains(">candidate</text>"));
    // Each tune writes its own page of the shared folder.
    for c in ["pid", "se3"] {
        let page = std::fs::read_to_string(folder.join(format!("{c}.report.html"))).unwrap();
        assert!(page.contains(&format!("{c}.tuned.toml")) && page.contains("<table>"), "{c}.report.html");
    }

    // Each tuned file is a scenario of its own controller that extends the input.
    let pid = std::fs::read_to_string(folder.join("pid.tuned.toml")).unwrap();
    assert!(pid.contains("controllers = [\"pid\"]") && pid.contains("tiny.toml"), "{pid}");
    let se3 = std::fs::read_to_string(folder.join("se3.tuned.toml")).unwrap();
    assert!(se3.contains("controllers = [\"se3\"]"), "{se3}");

    // History: one row per evaluated entry (the start, then 3 generations
    // of 4 samples and the mean, the second and third with the anchor),
    // the summary names the controller.
    let history = std::fs::read_to_string(folder.join("pid.history.csv")).unwrap();
    assert_eq!(history.lines().count(), 1 + 1 + 5 + 6 + 6, "{history}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("se3.summary.json")).unwrap()).unwrap();
    assert_eq!(summary["controller"], "se3");
    assert_eq!(summary["held_out"]["tuned"]["runs"], 3);

    // Re-tuning PID replaces PID's files and keeps SE(3)'s.
    let se3_before = std::fs::read(folder.join("se3.summary.json")).unwrap();
    tune(dir, "pid", "1", "out", false);
    assert_eq!(std::fs::read(folder.join("se3.summary.json")).unwrap(), se3_before);
    assert!(!folder.join("pid.convergence.svg").exists(), "pid's old figure is pid's to remove");
    assert!(folder.join("pid.tuned.toml").is_file());
}

#[test]
fn one_and_two_threads_give_the_same_tuned_file() {
    let tmp = scratch("threads");
    let dir = tmp.path();
    tune(dir, "ftaftsmc", "1", "one", false);
    tune(dir, "ftaftsmc", "2", "two", false);
    let one = tuned_without_command(&dir.join("one/tiny-tune/ftaftsmc.tuned.toml"));
    let two = tuned_without_command(&dir.join("two/tiny-tune/ftaftsmc.tuned.toml"));
    assert_eq!(one, two);
    let h1 = std::fs::read(dir.join("one/tiny-tune/ftaftsmc.history.csv")).unwrap();
    let h2 = std::fs::read(dir.join("two/tiny-tune/ftaftsmc.history.csv")).unwrap();
    assert_eq!(h1, h2, "history.csv differs between 1 and 2 threads");
}

/// A scenario path with a newline cannot add a key to the tuned file: the
/// command line is recorded as one comment line, the path as an escaped
/// TOML string, and flying the tuned file keeps the input's seed.
#[test]
fn a_path_with_a_newline_cannot_inject_a_key_into_the_tuned_file() {
    let tmp = scratch("inject");
    let dir = tmp.path();
    let evil = "x\nseed = 4242\n#.toml";
    std::fs::copy(dir.join("tiny.toml"), dir.join(evil)).unwrap();
    ok(&["tune", evil, "-c", "pid", "--budget", "12", "--threads", "1", "--out", "ti", "--no-figures"], dir);
    let tuned_path = dir.join("ti/tiny-tune/pid.tuned.toml");
    let text = std::fs::read_to_string(&tuned_path).unwrap();
    let made_by: Vec<&str> = text.lines().filter(|l| l.starts_with("# Made by:")).collect();
    assert_eq!(
        made_by,
        ["# Made by: ftsmc tune $'x\\nseed = 4242\\n#.toml' -c pid --budget 12 --threads 1 --out ti --no-figures"]
    );
    let table: toml::Table = toml::from_str(&text).unwrap();
    assert_ne!(table.get("seed").and_then(|v| v.as_integer()), Some(4242), "{text}");
    // It never extends a path (the evil one least of all): a built-in
    // scenario or nothing.
    if let Some(base) = table.get("extends") {
        let base = base.as_str().unwrap();
        assert!(ftsmc_sim::scenario::resolve::built_in(base).is_some() && !base.contains('/'), "{text}");
    }
    // Flying it: the seed is the input's, not 4242.
    ok(&["run", "ti/tiny-tune/pid.tuned.toml", "--out", "flown", "--no-figures"], dir);
    let flown = std::fs::read_to_string(dir.join("flown/tiny-tune-pid-tuned/scenario.toml")).unwrap();
    let flown: toml::Table = toml::from_str(&flown).unwrap();
    let input = std::fs::read_to_string(dir.join("ti/tiny-tune/pid.scenario.toml")).unwrap();
    let input: toml::Table = toml::from_str(&input).unwrap();
    assert_ne!(flown["seed"].as_integer(), Some(4242));
    assert_eq!(flown["seed"], input["seed"]);
}

#[test]
fn tune_refuses_seed_duration_and_unknown_extra_keys() {
    let d = scratch("tune-extra-keys");
    for key in ["seed", "duration", "no_such_key"] {
        let text = format!("{TINY}\n[[tune.extra]]\nkey = \"{key}\"\nlow = 1.0\nhigh = 100.0\n");
        std::fs::write(d.path().join("extra.toml"), text).unwrap();
        let out = ftsmc(&["tune", "extra.toml", "-c", "pid", "--budget", "5", "--out", "o"], d.path());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{key}: accepted");
        assert!(err.contains("extra.toml") && err.contains(&format!("\"{key}\"")), "{key}: {err}");
        assert!(!d.path().join("o").join("tiny-tune").exists(), "{key}: a result folder was written");
    }
}

/// The paper's plant with a tilt limit the start barely keeps (0.25 rad)
/// and TSM-STA's gains searched over factors 10⁻³ … 10³ with steps as wide
/// as that range: the one generation a budget of 8 flights pays for
/// diverges, so the tune finds nothing better than the start.
const CLIFF: &str = r#"extends = "paper-scenario-1"
name = "cliff"
duration = 4.0

[simulation]
max_tilt = 0.25

[tune]
runs = 1
validation_runs = 2
population = 6
sigma = 1.0

[tune.bounds]
time_xy = [0.001, 1000.0]
time_z = [0.001, 1000.0]
time_roll_pitch = [0.001, 1000.0]
time_yaw = [0.001, 1000.0]
k1_position = [0.001, 1000.0]
k2_position = [0.001, 1000.0]
k1_attitude = [0.001, 1000.0]
k2_attitude = [0.001, 1000.0]
command_filter = [0.001, 1000.0]
"#;

#[test]
fn a_tiny_budget_that_finds_nothing_warns_and_records_improved_false() {
    let d = scratch("tune-nothing");
    std::fs::write(d.path().join("cliff.toml"), CLIFF).unwrap();
    let out = ftsmc(
        &["tune", "cliff.toml", "-c", "tsm-sta", "--budget", "8", "--seed", "4", "--out", "o", "--no-figures"],
        d.path(),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("found nothing better than the start") && err.contains("--budget"), "{err}");
    let folder = d.path().join("o/cliff");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("tsm-sta.summary.json")).unwrap()).unwrap();
    assert_eq!(summary["improved"], false, "{summary}");
    // The flights actually flown (a candidate with invalid gains is charged but not flown).
    let flown = summary["training_flights"].as_u64().unwrap();
    assert!((1..=8).contains(&flown) && summary["race_flights"] == 0, "{summary}");
    let tuned = std::fs::read_to_string(folder.join("tsm-sta.tuned.toml")).unwrap();
    assert!(tuned.contains("# Improved: false"), "{tuned}");
    // The start's gains, unchanged: no gain key below the header.
    assert!(!tuned.lines().any(|l| l.starts_with("[tsm")), "{tuned}");
}

#[test]
fn tune_all_is_identical_with_one_and_two_threads() {
    let tmp = scratch("tune-all");
    let dir = tmp.path();
    for (threads, out) in [("1", "one"), ("2", "two")] {
        let args = ["tune", "tiny.toml", "-c", "all", "--budget", BUDGET, "--threads", threads, "--out", out];
        let o = ftsmc(&[&args[..], &["--no-figures"]].concat(), dir);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(stdout.contains("Paired verdicts") && stdout.contains("p (Holm)"), "{stdout}");
    }
    let read = |p: &str| std::fs::read_to_string(dir.join(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
    assert_eq!(read("one/tiny-tune/comparison.md"), read("two/tiny-tune/comparison.md"));
    assert_eq!(read("one/tiny-tune/comparison.json"), read("two/tiny-tune/comparison.json"));
    let md = read("one/tiny-tune/comparison.md");
    let json: serde_json::Value = serde_json::from_str(&read("one/tiny-tune/comparison.json")).unwrap();
    let names: Vec<&str> =
        json["controllers"].as_array().unwrap().iter().map(|c| c["controller"].as_str().unwrap()).collect();
    // `all` is every registered controller that declares tunable parameters.
    let expected: Vec<&str> = ftsmc_sim::registry::CONTROLLERS
        .iter()
        .map(|(n, _)| *n)
        .filter(|n| ftsmc_sim::controllers::tunable::parameters(n).is_ok_and(|p| !p.is_empty()))
        .collect();
    assert!(expected.len() >= 6 && !expected.contains(&"mellinger"), "{expected:?}");
    assert_eq!(names, expected);
    // Every pair on both metrics, on the same held-out draws.
    assert_eq!(json["verdicts"].as_array().unwrap().len(), names.len() * (names.len() - 1));
    assert!(md.contains("same 3 held-out draws"), "{md}");
    for c in &names {
        assert_eq!(
            tuned_without_command(&dir.join(format!("one/tiny-tune/{c}.tuned.toml"))),
            tuned_without_command(&dir.join(format!("two/tiny-tune/{c}.tuned.toml")))
        );
    }
}

/// A short realistic-calm-1 for the vehicle tests (a file of the user's).
const CALM: &str = r#"extends = "realistic-calm-1"
name = "calm-tune"
duration = 1.5

[tune]
runs = 2
validation_runs = 3
population = 4
"#;

/// `[plant]`, `[vehicle]` and `[actuators]` of a written scenario.toml.
fn vehicle_of(path: &Path) -> Vec<toml::Value> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let t: toml::Table = toml::from_str(&text).unwrap();
    ["plant", "vehicle", "actuators"].iter().map(|k| t[*k].clone()).collect()
}

/// The vehicle of `--set vehicle.preset=…` travels with the tuned file:
/// flying it flies that vehicle, also after its folder is moved; `px4
/// export` normalises on it; folders and names say which vehicle flew.
#[test]
fn a_tune_on_another_preset_writes_a_file_that_flies_that_preset_wherever_it_moves() {
    let tmp = scratch("preset");
    let dir = tmp.path();
    std::fs::write(dir.join("calm.toml"), CALM).unwrap();
    let set = ["--set", "vehicle.preset=crazyflie-2"];
    let mut args = vec!["tune", "calm.toml", "-c", "pid", "--budget", BUDGET, "--threads", "1", "--out", "ti"];
    args.extend(["--no-figures"].iter().chain(set.iter()));
    ok(&args, dir);
    // Named after the vehicle; the file extends the built-in scenario, not a path.
    let folder = dir.join("ti/calm-tune-crazyflie-2");
    let text = std::fs::read_to_string(folder.join("pid.tuned.toml")).unwrap();
    assert!(text.contains("extends = \"realistic-calm-1\"") && text.contains("preset = \"crazyflie-2\""), "{text}");
    assert!(text.contains("name = \"calm-tune-crazyflie-2-pid-tuned\""), "{text}");
    // Moved elsewhere (the user's calm.toml left behind), it still flies the Crazyflie.
    std::fs::create_dir_all(dir.join("moved/deeper")).unwrap();
    std::fs::rename(&folder, dir.join("moved/deeper/tuned")).unwrap();
    std::fs::remove_file(dir.join("calm.toml")).unwrap();
    let tuned = "moved/deeper/tuned/pid.tuned.toml";
    ok(&["run", tuned, "--out", "flown", "--no-figures"], dir);
    std::fs::write(dir.join("calm.toml"), CALM).unwrap();
    let mut own = vec!["run", "calm.toml", "-c", "pid", "--out", "own", "--no-figures"];
    own.extend(set);
    ok(&own, dir);
    assert_eq!(
        vehicle_of(&dir.join("flown/calm-tune-crazyflie-2-pid-tuned/scenario.toml")),
        vehicle_of(&dir.join("own/calm-tune-crazyflie-2/scenario.toml")),
        "the tuned file flies the vehicle it was tuned on"
    );
    // `px4 export` normalises on the Crazyflie, as the vehicle's own scenario does.
    let export = |args: &[&str]| {
        let out = ftsmc(args, dir);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8(out.stdout).unwrap();
        text.lines().find(|l| l.starts_with("# normalisation:")).unwrap().to_string()
    };
    assert_eq!(export(&["px4", "export", tuned]), export(&["px4", "export", "calm.toml", set[0], set[1]]));
}

/// `tune -c all` on a vehicle some controllers cannot fly from their
/// start: those are skipped (no file), the rest compared, one bottom line.
#[test]
fn tune_all_on_the_crazyflie_skips_unfit_starts_and_ends_with_a_bottom_line() {
    let tmp = scratch("all-cf");
    let dir = tmp.path();
    std::fs::write(dir.join("calm.toml"), CALM).unwrap();
    let out = ftsmc(
        &[
            "tune",
            "calm.toml",
            "-c",
            "pid,se3,ftaftsmc",
            "--budget",
            BUDGET,
            "--out",
            "ta",
            "--no-figures",
            "--set",
            "vehicle.preset=crazyflie-2",
        ],
        dir,
    );
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("skipped: ftaftsmc") && stderr.contains("its start gains fail all"), "{stderr}");
    let folder = dir.join("ta/calm-tune-crazyflie-2");
    assert!(!folder.join("ftaftsmc.tuned.toml").exists(), "no junk file for a start that never flies");
    assert!(folder.join("pid.tuned.toml").exists() && folder.join("se3.tuned.toml").exists());
    let bottom: Vec<&str> = stdout.lines().filter(|l| l.starts_with("Bottom line:")).collect();
    assert_eq!(bottom.len(), 1, "{stdout}");
    assert!(bottom[0].contains("McNemar") && bottom[0].contains("Wilcoxon"), "{}", bottom[0]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("comparison.json")).unwrap()).unwrap();
    assert_eq!(json["skipped"].as_array().unwrap().len(), 1);
}
