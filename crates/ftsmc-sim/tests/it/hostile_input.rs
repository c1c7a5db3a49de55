//! Hostile or nonsensical scenarios are refused at load time, before any
//! flight: cost above the limits, non-regular or huge files, names that are
//! not a plain file-name component, runs with no control period or no
//! controller, arrays of the wrong length, Monte Carlo distributions with
//! non-finite parameters or draws outside the physical ranges. Every error
//! names the key (or the limit) and echoes values briefly.

use std::path::PathBuf;
use std::sync::mpsc;
use std::time::Duration;

use ftsmc_sim::limits::{self, Limits};
use ftsmc_sim::scenario::{show, show_str, Scenario, ScenarioError, PAPER_SCENARIO_2};

use crate::common::scratch;

const BASE: &str = "name = \"t\"\nduration = 1.0\n";

fn parse(text: &str) -> Result<Scenario, ScenarioError> {
    Scenario::from_toml_str(text, "bad.toml")
}

/// The error message of `BASE + extra`, which must be rejected.
fn refused(extra: &str) -> String {
    let text = format!("{BASE}{extra}");
    let msg = parse(&text).map(|_| ()).expect_err(&format!("must be rejected:\n{text}")).to_string();
    assert!(msg.starts_with("bad.toml"), "error must name the file: {msg}");
    assert!(!msg.contains('\n'), "one line: {msg}");
    assert!(msg.len() < 400, "bounded: {msg}");
    msg
}

fn accepted(extra: &str) -> Scenario {
    parse(&format!("{BASE}{extra}")).unwrap_or_else(|e| panic!("{e}"))
}

/// Load `path` on another thread; the load must finish within 10 s
/// (a FIFO or `/dev/zero` used to block or grow forever).
fn load_with_timeout(path: PathBuf) -> Result<Scenario, String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(Scenario::from_file(&path).map_err(|e| e.to_string()));
    });
    rx.recv_timeout(Duration::from_secs(10)).expect("loading must not block or read without bound")
}

// ---- Refuse before working: cost limits --------------------------------

#[test]
fn steps_include_substeps() {
    let msg = refused("[simulation]\nsubsteps = 1000000000\n");
    assert!(msg.contains("max_steps") && msg.contains("substeps"), "{msg}");
    // ... and the limit can be raised explicitly.
    accepted("[simulation]\nsubsteps = 1000000000\n[limits]\nmax_steps = 1e13\n");
}

#[test]
fn a_fast_control_rate_counts_its_steps() {
    let msg = refused("[simulation]\ncontrol_rate = 1e9\nrecord_rate = 0.0\n");
    assert!(msg.contains("max_steps = 2e8") && msg.contains("1e9"), "{msg}");
}

#[test]
fn a_long_duration_is_refused_before_reserving_its_recording() {
    let text = "name = \"t\"\nduration = 1e6\n";
    let msg = parse(text).map(|_| ()).unwrap_err().to_string();
    assert!(msg.contains("max_steps"), "{msg}");
    // With the step limit raised, the recording (1e8 rows, ~48 GB) is still refused.
    let msg = parse(&format!("{text}[limits]\nmax_steps = 1e12\n")).map(|_| ()).unwrap_err().to_string();
    assert!(msg.contains("max_samples"), "{msg}");
}

#[test]
fn megahertz_recording_is_refused_by_rows_and_bytes() {
    let sim = "name = \"t\"\nduration = 1000.0\n[simulation]\ncontrol_rate = 1e6\nrecord_rate = 1e6\n";
    let msg = parse(sim).map(|_| ()).unwrap_err().to_string();
    assert!(msg.contains("max_steps"), "{msg}");
    let msg = parse(&format!("{sim}[limits]\nmax_steps = 1e12\n")).map(|_| ()).unwrap_err().to_string();
    assert!(msg.contains("max_samples"), "{msg}");
    // 10⁹ rows are above the hard bound of memory whatever max_samples says …
    let msg = parse(&format!("{sim}[limits]\nmax_steps = 1e12\nmax_samples = 1e12\n")).map(|_| ()).unwrap_err();
    assert!(msg.to_string().contains("hard bound") && msg.to_string().contains("max_samples"), "{msg}");
    // … and 10⁶ rows of three controllers' CSV are above max_output_bytes.
    let kilohertz = sim.replace("record_rate = 1e6", "record_rate = 1e3");
    let msg = parse(&format!("{kilohertz}[limits]\nmax_steps = 1e12\nmax_samples = 1e12\n")).map(|_| ()).unwrap_err();
    assert!(msg.to_string().contains("max_output_bytes"), "{msg}");
}

#[test]
fn limits_must_be_positive_numbers() {
    assert!(refused("[limits]\nmax_steps = -1.0\n").contains("limits.max_steps"));
    assert!(refused("[limits]\nmax_steps = nan\n").contains("limits.max_steps"));
    assert!(refused("[limits]\nmax_stepz = 1.0\n").contains("max_stepz"));
}

#[test]
fn batch_sweep_and_thread_requests_are_priced_without_overflow() {
    let s = accepted("");
    let l = Limits::default();
    for runs in [u64::MAX, 1_000_000_000_000] {
        let e = limits::check_batch(&s.flight_size(), runs, 3).unwrap_err();
        assert_eq!(e.key, "max_flights");
    }
    limits::check_batch(&s.flight_size(), 100, 3).unwrap();
    assert_eq!(limits::check_sweep(&l, limits::sweep_points(5, u64::MAX)).unwrap_err().key, "max_sweep_points");
    assert_eq!(limits::check_sweep(&l, limits::sweep_points(5, 100_000_000)).unwrap_err().key, "max_sweep_points");
    limits::check_sweep(&l, limits::sweep_points(5, 3)).unwrap();
    assert_eq!(limits::check_threads(&l, 1_000_000).unwrap_err().key, "max_threads");
    limits::check_threads(&l, 4).unwrap();
}

#[test]
fn paper_scenarios_are_far_below_every_limit() {
    for s in Scenario::paper_scenarios() {
        let cost = s.check_cost(3).unwrap();
        assert!(cost.integration_steps <= 5e4 && cost.samples <= 5001.0, "{cost:?}");
    }
}

// ---- Refuse before working: scenario files -----------------------------

#[test]
fn dev_zero_is_refused_without_reading_it() {
    let msg = load_with_timeout("/dev/zero".into()).map(|_| ()).unwrap_err();
    assert!(msg.contains("regular file"), "{msg}");
}

#[test]
fn a_fifo_is_refused_without_blocking() {
    let tmp = scratch("fifo");
    let dir = tmp.path();
    let fifo = dir.join("s.toml");
    let ok = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success();
    assert!(ok, "mkfifo failed");
    let msg = load_with_timeout(fifo).map(|_| ()).unwrap_err();
    assert!(msg.contains("regular file"), "{msg}");
}

#[test]
fn a_directory_is_refused() {
    let tmp = scratch("dir");
    let msg = load_with_timeout(tmp.path().to_path_buf()).map(|_| ()).unwrap_err();
    assert!(msg.contains("directory"), "{msg}");
}

#[test]
fn a_file_above_the_size_limit_is_refused_unless_raised() {
    let tmp = scratch("big");
    let dir = tmp.path();
    let path = dir.join("big.toml");
    let mut text = String::from(BASE);
    while text.len() <= 1024 * 1024 {
        text.push_str("# padding padding padding padding padding padding padding padding\n");
    }
    std::fs::write(&path, &text).unwrap();
    let msg = load_with_timeout(path.clone()).map(|_| ()).unwrap_err();
    assert!(msg.contains("max_scenario_bytes"), "{msg}");
    Scenario::from_file_with_limits(&path, &["max_scenario_bytes=2e6".into()]).unwrap();
}

#[test]
fn name_is_a_plain_file_name_component() {
    for bad in ["..", ".", ".hidden", "a/b", "a\\\\b", "a b", "tab\\there", "bell\\u0007", "", &"x".repeat(65)] {
        let text = format!("name = \"{bad}\"\nduration = 1.0\n");
        let msg = parse(&text).map(|_| ()).expect_err(bad).to_string();
        assert!(msg.contains("`name`"), "{bad}: {msg}");
        assert!(!msg.contains('\u{7}') && msg.len() < 300, "{msg}");
    }
    for good in ["paper-scenario-1", "run_2.v3", &"x".repeat(64)] {
        parse(&format!("name = \"{good}\"\nduration = 1.0\n")).unwrap();
    }
}

// ---- Every accepted input gives a meaningful run -----------------------

#[test]
fn at_least_one_control_period() {
    let text = "name = \"t\"\nduration = 5e-324\n";
    let msg = parse(text).map(|_| ()).unwrap_err().to_string();
    assert!(msg.contains("`duration` = 5e-324") && msg.contains("control period"), "{msg}");
    let msg = parse("name = \"t\"\nduration = 0.0004\n").map(|_| ()).unwrap_err().to_string();
    assert!(msg.contains("control period"), "{msg}");
    parse("name = \"t\"\nduration = 0.001\n").unwrap();
}

#[test]
fn an_empty_controller_list_is_refused() {
    assert!(refused("controllers = []\n").contains("controllers"));
}

#[test]
fn arrays_of_the_wrong_length_are_refused() {
    let msg = refused("[initial_state]\nposition = [0.5, 0.25, 0.0, 99.0, \"junk\", [1]]\n");
    assert!(msg.contains("invalid length 6") && msg.contains("exactly 3"), "{msg}");
    let msg = refused("[initial_state]\nvelocity = [0.5]\n");
    assert!(msg.contains("invalid length 1"), "{msg}");
    refused("[initial_state]\nattitude = [0.0, 0.0, 0.0, 0.0]\n");
    refused("[initial_state]\nangular_rate = []\n");
    refused("[simulation]\nmetrics_window = [0.0, 1.0, 2.0]\n");
    refused("[reference.x]\nwindow = [0.0, 1.0, 2.0]\n");
    // Arrays of ftsmc-core structs: checked on the TOML tree.
    let msg = refused("[plant]\ninertia = [0.004, 0.004, 0.008, 5.0]\n");
    assert!(msg.contains("plant.inertia") && msg.contains("exactly 3"), "{msg}");
    let msg = refused(
        "[ftaftsmc.mass_adaptation]\nenabled = true\nbeta1 = 0.8\nbeta2 = 0.01\nalpha_hat_bounds = [0.5, 2.0, 3.0]\n",
    );
    assert!(msg.contains("ftaftsmc.mass_adaptation.alpha_hat_bounds") && msg.contains("exactly 2"), "{msg}");
    let msg = refused("[actual_plant]\ndrag_rotational = [0.0, 0.0]\n");
    assert!(msg.contains("drag_rotational") && msg.contains("invalid length 2"), "{msg}");
    let msg = refused("[actual_plant]\ndrag_translational = [0.0, 0.0, 0.0, 1.0]\n");
    assert!(msg.contains("actual_plant.drag_translational") && msg.contains("invalid length 4"), "{msg}");
    let msg = refused("[vehicle]\ndrag_translational = [0.0, 0.0, 0.0, 1.0]\n");
    assert!(msg.contains("vehicle.drag_translational") && msg.contains("invalid length 4"), "{msg}");
    let msg = refused("[vehicle]\nmodel = \"rigid-body\"\nparasitic_drag = [0.0, 0.0]\n");
    assert!(msg.contains("vehicle.parasitic_drag") && msg.contains("invalid length 2"), "{msg}");
    accepted("[ftaftsmc.mass_adaptation]\nenabled = true\nbeta1 = 0.8\nbeta2 = 0.01\nalpha_hat_bounds = [0.5, 2.0]\n");
    let s = accepted("[initial_state]\nposition = [0.5, 0.25, 0.0]\n[simulation]\nmetrics_window = [0.0, 1.0]\n");
    assert_eq!(s.initial_state.position, [0.5, 0.25, 0.0]);
}

#[test]
fn payload_is_checked_against_the_true_plant() {
    // Nominal mass 0.74, true mass 0.3: a payload of -0.5 makes the true mass negative.
    let msg = refused("[vehicle]\nmass = 0.3\n[payload]\nmass = -0.5\nstart = 0.0\n");
    assert!(msg.contains("payload.mass") && msg.contains("vehicle.mass"), "{msg}");
    accepted("[vehicle]\nmass = 0.8\n[payload]\nmass = -0.5\nstart = 0.0\n");
}

const MC: &str = "[payload]\nmass = 0.2\nstart = 0.0\n[montecarlo]\n";

#[test]
fn monte_carlo_parameters_must_be_finite() {
    for (dist, key) in [
        ("mass = { dist = \"uniform\", low = 0.5, high = inf }", "montecarlo.mass.high"),
        ("mass = { dist = \"uniform\", low = -inf, high = 1.0 }", "montecarlo.mass.low"),
        ("drag_factor = { dist = \"normal\", mean = nan, std = 0.1 }", "montecarlo.drag_factor.mean"),
        (
            "drag_factor = { dist = \"normal\", mean = 1.0, std = 0.1, low = 0.0, high = inf }",
            "montecarlo.drag_factor.high",
        ),
        (
            "disturbance_phase = { dist = \"uniform\", low = -1.7e308, high = 1.7e308 }",
            "montecarlo.disturbance_phase.high",
        ),
        (
            "disturbance_amplitude = { dist = \"normal\", mean = 0.0, std = 1e307 }",
            "montecarlo.disturbance_amplitude.std",
        ),
        ("inertia_factor = { dist = \"log-normal\", mu = 1000.0, sigma = 0.1 }", "montecarlo.inertia_factor.mu"),
        ("inertia_factor = { dist = \"log-normal\", mu = 0.0, sigma = 30.0 }", "montecarlo.inertia_factor.mu"),
    ] {
        let msg = refused(&format!("{MC}{dist}\n"));
        assert!(msg.contains(&format!("`{key}`")), "{dist}: {msg}");
        assert!(!msg.contains("000000000000"), "abbreviated: {msg}");
    }
    // A finite `high` clamp makes a wide log-normal's draws finite.
    accepted(&format!(
        "{MC}inertia_factor = {{ dist = \"log-normal\", mu = 0.0, sigma = 30.0, low = 0.5, high = 2.0 }}\n"
    ));
}

#[test]
fn monte_carlo_draws_stay_in_the_physical_ranges() {
    for (dist, key) in [
        ("mass = { dist = \"uniform\", low = -0.1, high = 1.0 }", "montecarlo.mass"),
        ("mass = { dist = \"normal\", mean = 0.74, std = 0.1 }", "montecarlo.mass"),
        ("mass = { dist = \"normal\", mean = 0.74, std = 0.1, low = 0.0 }", "montecarlo.mass"),
        ("payload_mass = { dist = \"uniform\", low = -1.0, high = 0.5 }", "montecarlo.payload_mass"),
        ("inertia_factor = { dist = \"uniform\", low = 0.0, high = 2.0 }", "montecarlo.inertia_factor"),
        ("drag_factor = { dist = \"normal\", mean = 1.0, std = 0.5 }", "montecarlo.drag_factor"),
        (
            "initial_attitude_offset = { dist = \"uniform\", low = -2.0, high = 2.0 }",
            "montecarlo.initial_attitude_offset",
        ),
    ] {
        let msg = refused(&format!("{MC}{dist}\n"));
        assert!(msg.contains(&format!("`{key}`")), "{dist}: {msg}");
    }
    // Mass and payload draws together, against the true plant.
    let msg = refused(&format!(
        "[vehicle]\nmass = 0.3\n{MC}payload_mass = {{ dist = \"uniform\", low = -0.5, high = 0.5 }}\n"
    ));
    assert!(msg.contains("`montecarlo.payload_mass`"), "{msg}");
    let msg = refused(
        "[payload]\nmass = -0.5\nstart = 0.0\n[montecarlo]\nmass = { dist = \"uniform\", low = 0.4, high = 1.0 }\n",
    );
    assert!(msg.contains("`montecarlo.mass`"), "{msg}");
    // A payload distribution needs a payload to replace.
    let msg = refused("[montecarlo]\npayload_mass = { dist = \"uniform\", low = 0.0, high = 0.5 }\n");
    assert!(msg.contains("`montecarlo.payload_mass`") && msg.contains("[payload]"), "{msg}");
    // Clamped distributions inside the ranges are fine, and so is the shipped envelope.
    accepted(&format!("{MC}mass = {{ dist = \"normal\", mean = 0.74, std = 0.1, low = 0.3, high = 1.2 }}\n"));
    Scenario::from_toml_str(PAPER_SCENARIO_2, "paper-scenario-2.toml").unwrap();
}

// ---- Messages -----------------------------------------------------------

#[test]
fn long_values_are_abbreviated() {
    assert_eq!(show(1e308), "1e308");
    assert_eq!(show(5e-324), "5e-324");
    assert_eq!(show(0.74), "0.74");
    assert_eq!(show(-3.0), "-3");
    assert!(show_str(&"a".repeat(1000)).chars().count() <= 40);
    let msg = refused("[simulation]\nmax_position_error = -1e308\n");
    assert!(msg.contains("-1e308") && msg.len() < 200, "{msg}");
    let long_name = format!("name = \"{}\"\nduration = 1.0\n", "y".repeat(500));
    let msg = parse(&long_name).map(|_| ()).unwrap_err().to_string();
    assert!(msg.len() < 300, "{msg}");
}

// ---- The rigid body's valid range: refused at load, or stopped with a reason ----

const RIGID: &str = "extends = \"paper-scenario-1\"\nname = \"t\"\nduration = 1.0\n[vehicle]\nmodel = \"rigid-body\"\n";

fn rigid(extra: &str) -> Result<Scenario, String> {
    Scenario::from_toml_str(&format!("{RIGID}{extra}"), "rigid.toml").map_err(|e| e.to_string())
}

#[test]
fn monte_carlo_draws_outside_the_rigid_bodys_range_are_refused_at_load() {
    // Each passes the plant's own checks (mass > 0, factor > 0) but not the rigid body's.
    for (dist, key, field) in [
        ("mass = { dist = \"uniform\", low = 1e-9, high = 1.0 }", "montecarlo.mass", "mass = 1e-9"),
        ("mass = { dist = \"uniform\", low = 0.5, high = 2e6 }", "montecarlo.mass", "mass = 2e6"),
        ("inertia_factor = { dist = \"uniform\", low = 0.5, high = 1e12 }", "montecarlo.inertia_factor", "inertia"),
    ] {
        let msg = rigid(&format!("[montecarlo]\n{dist}\n")).expect_err(dist);
        assert!(msg.starts_with("rigid.toml") && msg.contains(&format!("`{key}`")), "{dist}: {msg}");
        assert!(msg.contains("draws in [") && msg.contains(field) && msg.contains("rigid body"), "{dist}: {msg}");
    }
    // The payload adds to the drawn mass.
    let msg = rigid(
        "[payload]\nmass = 0.5\nstart = 0.0\n[montecarlo]\nmass = { dist = \"uniform\", low = 0.5, high = 999999.8 }\n",
    )
    .unwrap_err();
    assert!(msg.contains("`montecarlo.mass`") && msg.contains("mass = 1.0000003e6"), "{msg}");
    // Draws the rigid body refuses for its own range are legal on the paper
    // plant (within a factor 3 of its 0.74 kg, the band of every vehicle).
    Scenario::from_toml_str(
        "extends = \"paper-scenario-1\"\nname = \"t\"\n[montecarlo]\nmass = { dist = \"uniform\", low = 0.3, high = 2.0 }\n",
        "paper.toml",
    )
    .unwrap();
    rigid("[montecarlo]\nmass = { dist = \"uniform\", low = 0.6, high = 0.9 }\n").unwrap();
}

#[test]
fn a_payload_outside_the_rigid_bodys_range_is_refused_at_load() {
    let msg = rigid("[payload]\nmass = 2e6\nstart = 0.5\n").unwrap_err();
    assert!(msg.starts_with("rigid.toml") && msg.contains("`payload.mass`") && msg.contains("2e6"), "{msg}");
    assert!(msg.contains("1e-6 <= mass <= 1e6"), "{msg}");
    // A rigid body built from a plant outside its range is refused too.
    let msg = rigid("[plant]\nmass = 1e-7\n").unwrap_err();
    assert!(msg.contains("mass") && msg.contains("1e-7"), "{msg}");
}

#[test]
fn an_inertia_variation_leaving_the_range_stops_the_run_with_a_reason() {
    use ftsmc_sim::{registry, run::Divergence, ExitStatus, RunOptions};
    // Inertia × (1 - 2) < 0 from t = 0.5 s: the run must not go on with the old inertia.
    let s =
        rigid("[inertia_variation]\nwindow = [0.5, 1.0]\nterms = [{ type = \"constant\", value = -2.0 }]\n").unwrap();
    let out = registry::run("pid", &s, RunOptions::default()).unwrap();
    match out.exit {
        ExitStatus::Diverged { divergence: Divergence::RigidBodyOutOfRange { inertia_scale, .. }, time } => {
            assert!((time - 0.5).abs() < 2e-3 && inertia_scale < 0.0, "{}", out.exit);
        }
        other => panic!("must stop with a reason, got {other}"),
    }
    assert!(out.exit.to_string().contains("rigid body out of its valid range"), "{}", out.exit);
    // The recorded inertia is the one flown: every row before the stop.
    let t = out.recording.column("t");
    assert!(t.last().is_some_and(|&t| t < 0.5), "no row after the stop");
}

#[test]
fn an_unvalidated_invalid_rigid_body_stops_at_once_instead_of_panicking() {
    use ftsmc_sim::{registry, run::Divergence, ExitStatus, RunOptions};
    let mut s = rigid("").unwrap();
    s.vehicle.mass = Some(1e-9); // below the rigid body's range, set behind validation's back
    let out = registry::run("pid", &s, RunOptions::default()).unwrap();
    assert!(
        matches!(out.exit, ExitStatus::Diverged { divergence: Divergence::RigidBodyOutOfRange { .. }, time } if time == 0.0),
        "{}",
        out.exit
    );
}

#[test]
fn extends_of_a_file_that_is_not_a_scenario_names_it_without_quoting_it() {
    let tmp = scratch("extends-secret");
    let dir = tmp.path();
    let secret = "root:SECRET-HASH:19000:0:99999:7:::";
    std::fs::write(dir.join("system-file"), format!("{secret}\nother line\n")).unwrap();
    std::fs::write(dir.join("mine.toml"), "extends = \"system-file\"\nname = \"t\"\n").unwrap();
    let msg = Scenario::from_file(&dir.join("mine.toml")).map(|_| ()).unwrap_err().to_string();
    // The folder's own path (random name, any temp dir such as /root/tmp) is
    // not the file's content: leave it out of the quoting check.
    let msg = msg.replace(&dir.display().to_string(), "<dir>");
    assert!(!msg.contains("SECRET") && !msg.contains("root"), "content quoted: {msg}");
    assert!(msg.contains("system-file") && msg.contains("not a scenario file") && msg.contains("line 1"), "{msg}");
    assert!(msg.contains("mine.toml"), "names the extending file: {msg}");
}

#[test]
fn every_u64_seed_round_trips_through_scenario_toml() {
    for seed in [0, 1, (1u64 << 63) - 1, 1u64 << 63, u64::MAX] {
        let mut s = parse(BASE).unwrap();
        s.seed = seed;
        let text = s.to_toml().unwrap();
        let back = Scenario::from_toml_str(&text, "scenario.toml").unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert_eq!(back.seed, seed);
        assert_eq!(back, s);
        if seed >= 1 << 63 {
            assert!(text.contains(&format!("seed = \"{seed}\"")), "{text}");
        } else {
            assert!(text.contains(&format!("seed = {seed}\n")), "{text}");
        }
    }
    // By hand: a decimal or hex string; a negative or malformed seed is refused naming the key.
    assert_eq!(accepted("seed = \"0xffffffffffffffff\"\n").seed, u64::MAX);
    assert_eq!(accepted("seed = \"9223372036854775808\"\n").seed, 1 << 63);
    for bad in ["seed = -1\n", "seed = \"18446744073709551616\"\n", "seed = \"twelve\"\n"] {
        let msg = refused(bad);
        assert!(msg.contains("seed"), "{bad}: {msg}");
    }
}

#[test]
fn monte_carlo_row_seeds_load_back() {
    use ftsmc_sim::batch::montecarlo::{run_seed, MonteCarloSpec};
    // Find row seeds >= 2^63 of a batch with master seed u64::MAX and load each as a scenario seed.
    let base = parse(BASE).unwrap();
    let spec = MonteCarloSpec::default();
    let mut big = 0;
    for index in 0..16 {
        let (s, seed, _) = spec.sample(&base, u64::MAX, index);
        assert_eq!(seed, run_seed(u64::MAX, index));
        let back = Scenario::from_toml_str(&s.to_toml().unwrap(), "row.toml").unwrap();
        assert_eq!(back.seed, seed);
        big += usize::from(seed >= 1 << 63);
    }
    assert!(big > 0, "no row seed >= 2^63 in 16 rows");
}

// ---- Limits: `inf` means no limit, never an overflow; signal terms are priced ----

const NO_LIMITS: &str = "[limits]\nmax_steps = inf\nmax_samples = inf\nmax_output_bytes = inf\n";

#[test]
fn an_inf_limit_lifts_the_check_without_overflow_and_the_run_can_be_cancelled() {
    use ftsmc_sim::{registry, ExitStatus, RunOptions};
    use std::sync::atomic::{AtomicBool, Ordering};
    // 1e300 s at 1 kHz: refused by default, and with `inf` by the hard bound on steps.
    let endless = "extends = \"paper-scenario-1\"\nname = \"t\"\nduration = 1e300\n";
    let msg = Scenario::from_toml_str(endless, "inf.toml").unwrap_err().to_string();
    assert!(msg.contains("max_steps"), "{msg}");
    let msg = Scenario::from_toml_str(&format!("{endless}{NO_LIMITS}"), "inf.toml").unwrap_err().to_string();
    assert!(msg.contains("max_steps") && msg.contains("hard bound"), "{msg}");
    // 1e7 s (1e10 steps, 1e6 rows at 0.1 Hz): refused by default, accepted with `inf`.
    let huge = "extends = \"paper-scenario-1\"\nname = \"t\"\nduration = 1e7\n[simulation]\nrecord_rate = 0.1\n";
    let msg = Scenario::from_toml_str(huge, "inf.toml").unwrap_err().to_string();
    assert!(msg.contains("max_steps"), "{msg}");
    let text = format!("{huge}{NO_LIMITS}");
    let s = Scenario::from_toml_str(&text, "inf.toml").unwrap();
    for (controller, extra) in [("pid", ""), ("ftaftsmc", "[vehicle]\nmodel = \"rigid-body\"\n")] {
        let s = if extra.is_empty() {
            s.clone()
        } else {
            Scenario::from_toml_str(&format!("{text}{extra}"), "inf.toml").unwrap()
        };
        let cancel = AtomicBool::new(false);
        let started = std::time::Instant::now();
        let out = std::thread::scope(|scope| {
            scope.spawn(|| {
                std::thread::sleep(Duration::from_millis(200));
                cancel.store(true, Ordering::Relaxed);
            });
            registry::run(controller, &s, RunOptions { cancel: Some(&cancel), ..Default::default() }).unwrap()
        });
        assert!(started.elapsed() < Duration::from_secs(5), "{controller}: took {:?}", started.elapsed());
        let ExitStatus::Interrupted { time } = out.exit else { panic!("{controller}: {}", out.exit) };
        assert!(time > 0.0 && out.exit.to_string().starts_with("interrupted at t = "), "{}", out.exit);
        assert_eq!(out.recording.column("t").last().copied().map(|t| t < time), Some(true));
    }
}

#[test]
fn a_cancelled_batch_stops_and_returns_no_partial_rows() {
    use ftsmc_sim::batch::montecarlo::{run_batch, BatchOptions, MonteCarloSpec, INTERRUPTED};
    use std::sync::atomic::AtomicBool;
    let s = Scenario::from_toml_str(PAPER_SCENARIO_2, "paper-scenario-2.toml").unwrap();
    let cancel = AtomicBool::new(true);
    let started = std::time::Instant::now();
    let r = run_batch(
        &s,
        &MonteCarloSpec::default(),
        &["pid".into()],
        BatchOptions { cancel: Some(&cancel), ..BatchOptions::new(100_000, 1) },
    );
    assert_eq!(r.unwrap_err(), INTERRUPTED);
    assert!(started.elapsed() < Duration::from_secs(5), "{:?}", started.elapsed());
}

#[test]
fn signal_terms_are_priced_into_the_step_limit() {
    // ~1 MiB of sine terms on a 1000 s flight: thousands of term evaluations per step.
    let terms: Vec<String> =
        (0..20_000).map(|i| format!("{{ type = \"sine\", amplitude = 1e-6, omega = {}.0 }}", i % 7 + 1)).collect();
    let many = format!("[disturbance.x]\nterms = [{}]\n", terms.join(", "));
    let long =
        |extra: &str| Scenario::from_toml_str(&format!("name = \"t\"\nduration = 1000.0\n{many}{extra}"), "t.toml");
    let msg = long("").unwrap_err().to_string();
    assert!(msg.contains("max_steps") && msg.contains("signal terms") && msg.contains("20000 terms"), "{msg}");
    // Without the terms the same flight is fine; so are the terms on a short
    // flight, or with the limit lifted.
    Scenario::from_toml_str("name = \"t\"\nduration = 1000.0\n", "t.toml").unwrap();
    accepted(&many);
    long("[limits]\nmax_steps = inf\n").unwrap();
}

/// A scenario on the ground (`z0 = 0`, ground at 0) whose `[montecarlo]`
/// draws `dist` as the initial position offset.
fn on_the_ground(dist: &str) -> String {
    format!("extends = \"realistic-calm-1\"\nname = \"drawn\"\n\n[montecarlo]\ninitial_position_offset = {dist}\n")
}

#[test]
fn draws_below_the_ground_are_refused_like_a_file() {
    // A single file starting below the ground is refused …
    let below = "extends = \"realistic-calm-1\"\nname = \"below\"\n\n[initial_state]\nposition = [0.0, 0.0, -0.5]\n";
    assert!(Scenario::from_toml_str(below, "below.toml").is_err());
    // … and so is a draw that could start there: the key, its range and the bound.
    let err = Scenario::from_toml_str(&on_the_ground("{ dist = \"uniform\", low = -1.0, high = 1.0 }"), "mc.toml")
        .unwrap_err()
        .to_string();
    for part in ["mc.toml", "montecarlo.initial_position_offset", "draws in [-1, 1]", "ground.height = 0", "z = 0 + -1"]
    {
        assert!(err.contains(part), "`{part}` missing from: {err}");
    }
    assert!(err.lines().next().unwrap().len() <= 300, "{err}");
    // An unbounded normal reaches below the ground too: refused, unless clamped.
    let normal = on_the_ground("{ dist = \"normal\", mean = 0.5, std = 0.1 }");
    assert!(Scenario::from_toml_str(&normal, "mc.toml").unwrap_err().to_string().contains("initial_position_offset"));
    let clamped = on_the_ground("{ dist = \"normal\", mean = 0.5, std = 0.1, low = 0.0 }");
    Scenario::from_toml_str(&clamped, "mc.toml").unwrap();
    Scenario::from_toml_str(&on_the_ground("{ dist = \"uniform\", low = 0.0, high = 1.0 }"), "mc.toml").unwrap();
}

#[test]
fn disturbance_factors_that_overflow_are_refused() {
    let text = "extends = \"paper-scenario-1\"\nname = \"big\"\n\n[disturbance.x]\nterms = [{ type = \"sine\", amplitude = 10.0, omega = 1.0 }]\n\n[montecarlo]\ndisturbance_amplitude = { dist = \"uniform\", low = 1.0, high = 1e308 }\n";
    let err = Scenario::from_toml_str(text, "big.toml").unwrap_err().to_string();
    assert!(err.contains("montecarlo.disturbance_amplitude") && err.contains("1e308"), "{err}");
}

#[test]
fn a_completed_flight_never_reports_an_infinite_metric() {
    use ftsmc_sim::{registry, run::Divergence, ExitStatus, RunOptions};
    // 1e200 m above its reference with the divergence check moved out of
    // the way: the state stays finite for the two control periods, but
    // e² = 1e400 overflows ISE z.
    let text = "extends = \"paper-scenario-1\"\nname = \"far\"\nduration = 0.002\n\n[simulation]\nmax_position_error = 1e300\n\n[initial_state]\nposition = [0.0, 0.0, 1e200]\n";
    let s = Scenario::from_toml_str(text, "far.toml").unwrap();
    let out = registry::run("pid", &s, RunOptions::default()).unwrap();
    assert!(!out.exit.is_completed(), "completed with ISE z = {}", out.metrics.ise.z);
    match out.exit {
        ExitStatus::Diverged { divergence: Divergence::NonFiniteMetric, time } => {
            assert!(time > 0.0 && out.exit.to_string().contains("metric"), "{}", out.exit);
        }
        other => panic!("expected a metric overflow, got {other}"),
    }
    assert!(!out.success() && out.metrics.first_non_finite().as_deref() == Some("ise_z"));
}
