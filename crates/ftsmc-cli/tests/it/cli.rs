//! The `ftsmc` binary as a user runs it.

use std::path::Path;
use std::process::{Command, Output};

use crate::common::scratch;

fn ftsmc(args: &[&str], cwd: &Path) -> Output {
    // RUST_BACKTRACE=1: errors must stay one readable line even then.
    Command::new(env!("CARGO_BIN_EXE_ftsmc"))
        .args(args)
        .current_dir(cwd)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("binary runs")
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
    let tmp = scratch("reproduce");
    let dir = tmp.path();
    let args = [
        "reproduce",
        "--out",
        "res",
        "--no-figures",
        "--realistic-runs",
        "4",
        "--tuned-runs",
        "4",
        "--confidence",
        "0.9",
    ];
    let out = ftsmc(&args, dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("Table 3") && stdout.contains("0.2674"), "{stdout}");
    // --confidence reaches the ladder and the tuned table (text and JSON).
    assert!(stdout.contains("Success with its 90 % Wilson interval"), "{stdout}");
    assert!(stdout.contains("90 % intervals: rates Wilson score") && !stdout.contains("95 % interval"), "{stdout}");
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
    readme_sentences_match(&summary["table3"]);
    let csv = std::fs::read_to_string(dir.join("res/paper-scenario-1/ftaftsmc.csv")).unwrap();
    assert!(csv.starts_with("t,x,y,z,phi,theta,psi"));
    assert!(csv.lines().count() > 1000);
    assert!(no_files_with_suffix(dir, ".tmp"));
}

#[test]
fn a_bad_scenario_file_is_a_clear_error_not_a_panic() {
    let tmp = scratch("bad");
    let dir = tmp.path();
    let text = scenario_text("paper-scenario-1.toml").replacen("p = 0.1", "p = 1.2", 1);
    std::fs::write(dir.join("bad.toml"), text).unwrap();
    let out = ftsmc(&["run", "bad.toml", "--out", "res"], dir);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.toml") && err.contains("ftaftsmc.x.p") && err.contains("1.2"), "{err}");
    assert!(!err.contains("panicked") && !err.contains("backtrace"), "{err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(!dir.join("res").exists(), "a failed run must not leave output");

    std::fs::write(dir.join("typo.toml"), "name = \"t\"\nduration = 1.0\n[plant]\nmas = 1.0\n").unwrap();
    let out = ftsmc(&["run", "typo.toml"], dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("typo.toml") && err.contains("mas"), "{err}");

    let out = ftsmc(&["run", "missing.toml"], dir);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("missing.toml"));
    let out = ftsmc(&["run", "paper-scenario-1", "-c", "pidd"], dir);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("unknown controller `pidd`"));
}

#[test]
fn montecarlo_csv_is_byte_identical_across_thread_counts() {
    let tmp = scratch("mc");
    let dir = tmp.path();
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
            dir,
        );
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        // 4 runs × 3 controllers × 4 s at 1 kHz, none diverges: 48,000 steps.
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(said.contains("12 flights, 0.05 M control steps in "), "{said}");
        if cfg!(unix) {
            assert!(said.contains(" M steps flown per CPU-second"), "{said}");
        }
        // Which lanes and instruction set flew it.
        assert!(
            said.contains("; 4 lanes per thread, baseline)") || said.contains("; 4 lanes per thread, avx2+fma)"),
            "{said}"
        );
    }
    // `--out` is the parent: the batch goes to `<out>/<scenario name>/`.
    let one = std::fs::read(dir.join("mc1/paper-scenario-2/runs.csv")).unwrap();
    let two = std::fs::read(dir.join("mc2/paper-scenario-2/runs.csv")).unwrap();
    assert_eq!(one, two);
    let text = String::from_utf8(one).unwrap();
    assert_eq!(text.lines().count(), 1 + 4 * 3, "header + runs × controllers");
    assert!(text.lines().next().unwrap().starts_with("run,seed,controller,exit,diverged_at,mass,"));
    let summary = |d: &str| {
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(d).join("paper-scenario-2/summary.json")).unwrap())
                .unwrap();
        // The command lines differ (--threads, --out); everything else must not.
        v["provenance"].as_object_mut().unwrap().remove("command_line");
        v
    };
    assert_eq!(summary("mc1"), summary("mc2"));
}

#[test]
fn help_names_the_commands() {
    let out = ftsmc(&["--help"], Path::new("."));
    let text = String::from_utf8_lossy(&out.stdout);
    for cmd in ["reproduce", "run", "fixed-time", "montecarlo", "tune-tsm-sta", "scenario", "list"] {
        assert!(text.contains(cmd), "{cmd} missing from --help:\n{text}");
    }
}

/// Scenario 1 with `max_rotor_speed = 1000` (FTAFTSMC diverges at 0.64 s),
/// shortened to 6 s (the others still pass the 5 s steady-state mark).
fn diverging_scenario() -> String {
    scenario_text("paper-scenario-1.toml").replacen("[simulation]", "[simulation]\nmax_rotor_speed = 1000", 1).replacen(
        "duration = 20.0",
        "duration = 6.0",
        1,
    )
}

#[test]
fn a_diverged_run_is_marked_in_the_table_and_the_json() {
    let tmp = scratch("diverged");
    let dir = tmp.path();
    let text = diverging_scenario();
    assert!(text.contains("max_rotor_speed = 1000") && text.contains("duration = 6.0"));
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let out = ftsmc(&["run", "s.toml", "--out", "res", "--no-figures"], dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<&str> = stdout.lines().filter(|l| l.starts_with("| FTAFTSMC")).collect();
    assert_eq!(rows.len(), 4, "ISE, IAE, settling, exit tables:\n{stdout}");
    assert!(
        rows.iter().all(|r| r.contains("| — ") && !r.contains("0.4862")),
        "no ISE number for a diverged run: {rows:?}"
    );
    assert!(rows[3].contains("diverged at 0.64 s"), "{}", rows[3]);
    assert!(stdout.contains("FTAFTSMC: diverged: tilt") && stdout.contains("0.639 s"), "{stdout}");
    let ok: Vec<&str> = stdout.lines().filter(|l| l.starts_with("| RANFTSMC")).collect();
    assert!(ok.iter().any(|l| l.contains("completed")) && ok.iter().all(|l| !l.contains('—')), "{ok:?}");

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("res/paper-scenario-1/summary.json")).unwrap()).unwrap();
    let ft = &summary["scenarios"]["paper-scenario-1"]["ftaftsmc"];
    assert_eq!(ft["completed"], false);
    assert!(ft["max_error_after"]["z"].is_null(), "{}", ft["max_error_after"]);
    let covered = ft["covered"].as_array().unwrap();
    assert_eq!(covered[0].as_f64(), Some(0.0));
    assert!((covered[1].as_f64().unwrap() - 0.639).abs() < 1e-9, "{covered:?}");
    assert!(ft["ise"]["x"].as_f64().unwrap() > 0.0, "the JSON keeps the numbers");
    let ran = &summary["scenarios"]["paper-scenario-1"]["ranftsmc"];
    assert_eq!(ran["completed"], true);
    assert!(ran["max_error_after"]["z"].is_number());
    assert!((ran["covered"][1].as_f64().unwrap() - 6.0).abs() < 1e-9, "{}", ran["covered"]);
}

#[test]
fn montecarlo_marks_diverged_rows_and_leaves_after_t_metrics_empty() {
    let tmp = scratch("mc-diverged");
    let dir = tmp.path();
    std::fs::write(dir.join("s.toml"), diverging_scenario().replacen("duration = 6.0", "duration = 2.0", 1)).unwrap();
    let out = ftsmc(&["montecarlo", "s.toml", "--runs", "2", "--out", "mc", "--no-figures"], dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    // The headline table (with intervals) first, then the ISE table.
    let rows: Vec<&str> = stdout.lines().filter(|l| l.starts_with("| FTAFTSMC")).collect();
    assert_eq!(rows.len(), 3, "{stdout}");
    assert!(rows[0].contains("| 0.0 % [") && rows[0].contains("| — "), "{}", rows[0]);
    assert!(rows[1].contains("— (all 2 diverged)"), "{}", rows[1]);
    let csv = std::fs::read_to_string(dir.join("mc/paper-scenario-1/runs.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        // 2 s < steady_state_after = 5 s: never reached, so empty, not 0.
        assert_eq!(f[col("max_error_after_z")], "", "{line}");
        let diverged = f[col("controller")] == "ftaftsmc";
        assert_eq!(f[col("completed")], if diverged { "false" } else { "true" }, "{line}");
        assert_eq!(f[col("duration")].parse::<f64>().unwrap(), if diverged { 0.639 } else { 2.0 }, "{line}");
    }
}

#[test]
fn an_io_error_names_its_cause_once() {
    let tmp = scratch("io");
    let dir = tmp.path();
    std::fs::create_dir_all(dir.join("adir.toml")).unwrap();
    let out = ftsmc(&["run", "adir.toml", "--out", "res"], dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("adir.toml"), "{err}");
    assert!(err.matches("os error").count() <= 1, "cause repeated: {err}");
    assert!(err.matches("directory").count() <= 1, "cause repeated: {err}");
}

#[test]
fn a_deeply_nested_file_gives_one_short_error_line() {
    let tmp = scratch("nested");
    let dir = tmp.path();
    std::fs::write(dir.join("deep.toml"), format!("a = {}\n", "[".repeat(10_000))).unwrap();
    std::fs::write(dir.join("long.toml"), format!("name = \"{}\n", "x".repeat(300_000))).unwrap();
    for file in ["deep.toml", "long.toml"] {
        let out = ftsmc(&["run", file, "--out", "res"], dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert_eq!(err.lines().count(), 1, "{file}: one line, got {} bytes", err.len());
        assert!(err.chars().count() <= 320, "{file}: {} chars", err.chars().count());
        assert!(err.starts_with("error: ") && err.contains(file) && err.contains("line 1, column"), "{err}");
    }
}

#[test]
fn a_realistic_run_reports_success_and_rotor_demand() {
    // Paper scenario 1 on the rigid body with 0-350 rad/s rotors, motor lag,
    // ground and envelope: TSM-STA flies it inside the envelope without
    // saturating; FTAFTSMC asks for far more than the rotors give and tilts over.
    let tmp = scratch("realistic");
    let dir = tmp.path();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/realism/rigid-body-scenario-1.toml");
    let out = ftsmc(&["run", root.to_str().unwrap(), "-c", "tsm-sta,ftaftsmc", "--no-figures", "--out", "res"], dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let row = |label: &str| {
        stdout
            .lines()
            .find(|l| l.starts_with(&format!("| {label}")) && l.contains('%'))
            .unwrap_or_else(|| panic!("no rotor row for {label}: {stdout}"))
            .to_string()
    };
    assert!(stdout.contains("peak ω demand (rad/s)"), "{stdout}");
    let tsm = row("TSM-STA");
    assert!(tsm.contains("| yes ") && tsm.contains("0.0 %"), "{tsm}");
    let ft = row("FTAFTSMC");
    assert!(ft.contains("| no ") && ft.contains("diverged at"), "{ft}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("res/rigid-body-scenario-1/summary.json")).unwrap())
            .unwrap();
    let run = &summary["scenarios"]["rigid-body-scenario-1"];
    assert_eq!(run["tsm-sta"]["success"], true);
    assert_eq!(run["ftaftsmc"]["success"], false);
    // The demand is what the law asked for before the 350 rad/s limit.
    assert!(run["ftaftsmc"]["peak_rotor_speed_demand"].as_f64().unwrap() > 350.0);
    assert!(stdout.lines().all(|l| l.chars().count() <= 120), "a line is wider than 120 columns");
}

/// The README's comparative sentences about the paper's scenario 1 say
/// what `reproduce` computes (its Table 3 record `t3`): "FTAFTSMC has the
/// lowest ISE on x, y, z and ψ", "its z ISE is N % below both baselines",
/// and the ours/paper ratios of every Table 3 cell.
fn readme_sentences_match(t3: &serde_json::Value) {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    let text = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    let ise = |axis: &str, c: &str| t3[axis]["ours"][c].as_f64().unwrap_or_else(|| panic!("{axis} {c}: {t3}"));
    let paper = |axis: &str, c: &str| t3[axis]["paper"][c].as_f64().unwrap();
    assert!(text.contains("FTAFTSMC has the lowest ISE on x, y, z and ψ in scenario 1"), "README sentence moved");
    for axis in ["x", "y", "z", "psi"] {
        let f = ise(axis, "ftaftsmc");
        assert!(f < ise(axis, "ranftsmc") && f < ise(axis, "tsm-sta"), "README: lowest {axis} ISE, reproduce: {t3}");
    }
    let below = 100.0 * (1.0 - ise("z", "ftaftsmc") / ise("z", "ranftsmc").min(ise("z", "tsm-sta")));
    assert!(
        text.contains(&format!("its z ISE is {below:.0} % below both baselines")),
        "README's z reduction, reproduce: {below:.2} %"
    );
    for (c, shown) in [("ranftsmc", "RANFTSMC"), ("tsm-sta", "TSM-STA"), ("ftaftsmc", "FTAFTSMC")] {
        let r = |axis: &str| ise(axis, c) / paper(axis, c);
        let sentence = format!("{shown} x {:.1}, y {:.1}, z {:.1}, ψ {:.1}", r("x"), r("y"), r("z"), r("psi"));
        assert!(text.contains(&sentence), "README's Table 3 ratios: reproduce gives `{sentence}`");
    }
}

#[test]
fn reproduce_prints_the_papers_part_before_the_beyond_part_starts() {
    // One pipe for stdout and stderr keeps their order: Table 3 and the
    // verdicts must be on screen before the beyond part (and its minutes of
    // Monte Carlo) starts, not after it.
    let tmp = scratch("order");
    let dir = tmp.path();
    let exe = env!("CARGO_BIN_EXE_ftsmc");
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("exec '{exe}' reproduce --out res --no-figures --realistic-runs 2 2>&1"))
        .current_dir(dir)
        .output()
        .expect("sh runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let at = |needle: &str| text.find(needle).unwrap_or_else(|| panic!("no {needle:?} in:\n{text}"));
    let table3 = at("Table 3");
    let verdict = at("Headline");
    let beyond_starts = at("beyond the paper:");
    let monte_carlo = at("the wind ladder, 2 runs");
    assert!(table3 < beyond_starts && verdict < beyond_starts, "paper part after the beyond part started:\n{text}");
    assert!(verdict < monte_carlo, "{text}");
}

/// `--set KEY=VALUE` changes the scenario as Python's `with_overrides`
/// does, and the written scenario.toml records it: flying that file again
/// is the same scenario.
#[test]
fn set_changes_the_scenario_and_the_written_file_records_it() {
    let tmp = scratch("set");
    let dir = tmp.path();
    let out = ftsmc(
        &[
            "run",
            "realistic-calm-1",
            "--set",
            "vehicle.preset=crazyflie-2",
            "--set",
            "duration=2.0",
            "-c",
            "se3",
            "--no-figures",
            "--out",
            "out",
        ],
        dir,
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // The folder is named after the vehicle that flew.
    let written = dir.join("out/realistic-calm-1-crazyflie-2/scenario.toml");
    let text = std::fs::read_to_string(&written).unwrap();
    assert!(text.contains("preset = \"crazyflie-2\""), "{text}");
    let again = ftsmc_sim::Scenario::from_file(&written).unwrap();
    let (file, calm) = ftsmc_sim::scenario::resolve::built_in("realistic-calm-1").unwrap();
    let calm = ftsmc_sim::Scenario::from_toml_str(calm, file).unwrap();
    let sets = [
        ("vehicle.preset".to_string(), toml::Value::String("crazyflie-2".into())),
        ("duration".to_string(), toml::Value::Float(2.0)),
    ];
    let mut expected = calm.with_overrides(&sets).unwrap().scenario;
    expected.controllers = vec!["se3".into()];
    assert_eq!(again, expected);
    assert_eq!(again.plant.mass, 0.03);
    // A malformed --set is one clear line.
    let bad = ftsmc(&["run", "paper-scenario-1", "--set", "duration", "--out", "out"], dir);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("KEY=VALUE"), "{err}");
}

#[test]
fn px4_export_then_import_writes_a_pid_section_that_flies() {
    let tmp = scratch("px4");
    let dir = tmp.path();
    let out = ftsmc(&["px4", "export", "realistic-scenario-1", "-o", "hb.params"], dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let params = std::fs::read_to_string(dir.join("hb.params")).unwrap();
    assert!(params.contains("1\t1\tMC_ROLLRATE_P\t0.15\t9\n"), "{params}");
    // Never over an existing file.
    let again = ftsmc(&["px4", "export", "realistic-scenario-1", "-o", "hb.params"], dir);
    assert!(!again.status.success() && String::from_utf8_lossy(&again.stderr).contains("never overwritten"));
    let out = ftsmc(&["px4", "import", "hb.params", "--scenario", "realistic-scenario-1", "-o", "pid.toml"], dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // The section appended to a scenario loads: `ftsmc px4 export` of it gives the same file body.
    let pid = std::fs::read_to_string(dir.join("pid.toml")).unwrap();
    std::fs::write(dir.join("s.toml"), format!("extends = \"realistic-scenario-1\"\n{pid}")).unwrap();
    let out = ftsmc(&["px4", "export", "s.toml"], dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let body = |t: &str| t.lines().filter(|l| !l.starts_with('#')).map(str::to_owned).collect::<Vec<_>>();
    assert_eq!(body(&String::from_utf8_lossy(&out.stdout)), body(&params));
    // A bad line: one error line naming file, line and parameter.
    std::fs::write(dir.join("bad.params"), "1\t1\tMC_YAW_P\tx\t9\n").unwrap();
    let out = ftsmc(&["px4", "import", "bad.params", "--scenario", "realistic-scenario-1"], dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("bad.params, line 1") && err.contains("MC_YAW_P"), "{err}");
}

/// PX4's Gazebo X500 airframe (`tests/data/4001_gz_x500.params`): import
/// flies its rotor layout and idle speed, normalises the gains on that
/// layout, and lists what it reads but does not fly; `[pid] px4_params` of
/// the file on a vehicle of another layout is refused naming the remedy.
#[test]
fn px4_import_of_the_gz_x500_airframe_flies_its_layout_and_idle() {
    let tmp = scratch("px4-airframe");
    let dir = tmp.path();
    let params = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/4001_gz_x500.params");
    std::fs::copy(&params, dir.join("x500.params")).unwrap();
    let out = ftsmc(&["px4", "import", "x500.params", "--scenario", "realistic-calm-1", "-o", "x500.toml"], dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    for wanted in [
        "CA_ROTOR0_CT = 6.5",
        "CA_ROTOR0_KM = 0.05",
        "SIM_GZ_EC_*",
        "MPC_THR_HOVER",
        "CA_AIRFRAME",
        "not realistic-calm-1's vehicle",
    ] {
        assert!(err.contains(wanted), "stderr lacks {wanted}: {err}");
    }
    let text = std::fs::read_to_string(dir.join("x500.toml")).unwrap();
    assert!(text.contains("# not flown: CA_ROTOR0_CT = 6.5"), "{text}");
    // The sections fly: a file extending the X500 preset with them.
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "extends = \"realistic-calm-1\"\nname = \"gz-x500\"\n{}",
            text.replace("[vehicle]\n", "[vehicle]\npreset = \"px4-x500\"\n")
        ),
    )
    .unwrap();
    let s = ftsmc_sim::scenario::Scenario::from_file(&dir.join("s.toml")).unwrap();
    let rb = s.rigid_body_params();
    assert_eq!(rb.custom_positions, Some([[0.13, -0.22], [-0.13, 0.20], [0.13, 0.22], [-0.13, -0.20]]));
    assert_eq!(rb.spin.map(|s| s.sign()), [1.0, 1.0, -1.0, -1.0]);
    let a = s.actuators.unwrap();
    assert_eq!((a.min_rotor_speed, a.max_rotor_speed), (150.0, 1000.0));
    // The gains were normalised on that layout: export gives MC_ROLLRATE_P back.
    let out = ftsmc(&["px4", "export", "s.toml"], dir);
    let exported = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && exported.contains("1\t1\tMC_ROLLRATE_P\t0.15\t9\n"), "{exported}");
    // Flying the file's gains directly on the square preset is refused.
    std::fs::write(
        dir.join("direct.toml"),
        "extends = \"realistic-calm-1\"\nname = \"d\"\n[vehicle]\npreset = \"px4-x500\"\n[pid]\npx4_params = \"x500.params\"\n",
    )
    .unwrap();
    let e = ftsmc_sim::scenario::Scenario::from_file(&dir.join("direct.toml")).unwrap_err().to_string();
    assert!(
        e.contains("px4_params") && e.contains("set [vehicle] rotor_positions") && e.contains("(0.13, -0.22)"),
        "{e}"
    );
    assert!(e.contains("(0.174, 0.174)"), "{e}");
}

/// `[plant]`, `[vehicle]` and `[actuators]` of a scenario file ftsmc wrote.
fn vehicle_sections(path: &Path) -> Vec<toml::Value> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let t: toml::Table = toml::from_str(&text).unwrap();
    ["plant", "vehicle", "actuators"].iter().map(|k| t[*k].clone()).collect()
}

/// Every writer given `--set vehicle.preset=crazyflie-2` writes files that
/// hold the Crazyflie (the same sections as a file naming the preset),
/// into a folder named after it.
#[test]
fn every_writer_keeps_a_vehicle_set_on_the_command_line() {
    let tmp = scratch("writers-vehicle");
    let dir = tmp.path();
    std::fs::write(
        dir.join("cf.toml"),
        "extends = \"realistic-calm-1\"\nname = \"cf-file\"\nduration = 1.5\n[vehicle]\npreset = \"crazyflie-2\"\n",
    )
    .unwrap();
    let run = |args: &[&str]| {
        let out = ftsmc(args, dir);
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    };
    run(&["run", "cf.toml", "-c", "pid", "--out", "own", "--no-figures"]);
    let own = vehicle_sections(&dir.join("own/cf-file/scenario.toml"));
    let set = ["--set", "vehicle.preset=crazyflie-2", "--set", "duration=1.5"];
    let writers: [(&[&str], &str); 4] = [
        (&["run", "realistic-calm-1", "-c", "pid", "--out", "w", "--no-figures"], "scenario.toml"),
        (
            &["montecarlo", "realistic-calm-1", "-c", "pid", "--runs", "2", "--out", "w", "--no-figures"],
            "scenario.toml",
        ),
        (
            &["compare", "realistic-calm-1", "-c", "pid,se3", "--runs", "2", "--out", "w", "--no-figures"],
            "scenario.toml",
        ),
        (
            &["falsify", "realistic-calm-1", "-c", "pid", "--budget", "12", "--out", "w", "--no-figures"],
            "pid.worst.toml",
        ),
    ];
    for (args, file) in writers {
        let _ = std::fs::remove_dir_all(dir.join("w"));
        let mut all = args.to_vec();
        all.extend(set);
        run(&all);
        let written = dir.join("w/realistic-calm-1-crazyflie-2").join(file);
        assert_eq!(vehicle_sections(&written), own, "{args:?}: {}", written.display());
    }
}
