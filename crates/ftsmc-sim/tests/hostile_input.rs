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

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ftsmc-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
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
    let msg = parse(&format!("{sim}[limits]\nmax_steps = 1e12\nmax_samples = 1e12\n")).map(|_| ()).unwrap_err();
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
    let dir = temp_dir("fifo");
    let fifo = dir.join("s.toml");
    let ok = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success();
    assert!(ok, "mkfifo failed");
    let msg = load_with_timeout(fifo).map(|_| ()).unwrap_err();
    assert!(msg.contains("regular file"), "{msg}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_directory_is_refused() {
    let dir = temp_dir("dir");
    let msg = load_with_timeout(dir.clone()).map(|_| ()).unwrap_err();
    assert!(msg.contains("directory"), "{msg}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_above_the_size_limit_is_refused_unless_raised() {
    let dir = temp_dir("big");
    let path = dir.join("big.toml");
    let mut text = String::from(BASE);
    while text.len() <= 1024 * 1024 {
        text.push_str("# padding padding padding padding padding padding padding padding\n");
    }
    std::fs::write(&path, &text).unwrap();
    let msg = load_with_timeout(path.clone()).map(|_| ()).unwrap_err();
    assert!(msg.contains("max_scenario_bytes"), "{msg}");
    Scenario::from_file_with_limits(&path, &["max_scenario_bytes=2e6".into()]).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
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
    accepted("[ftaftsmc.mass_adaptation]\nenabled = true\nbeta1 = 0.8\nbeta2 = 0.01\nalpha_hat_bounds = [0.5, 2.0]\n");
    let s = accepted("[initial_state]\nposition = [0.5, 0.25, 0.0]\n[simulation]\nmetrics_window = [0.0, 1.0]\n");
    assert_eq!(s.initial_state.position, [0.5, 0.25, 0.0]);
}

#[test]
fn payload_is_checked_against_the_true_plant() {
    // Nominal mass 0.74, true mass 0.3: a payload of -0.5 makes the true mass negative.
    let msg = refused("[actual_plant]\nmass = 0.3\n[payload]\nmass = -0.5\nstart = 0.0\n");
    assert!(msg.contains("payload.mass") && msg.contains("actual_plant.mass"), "{msg}");
    accepted("[actual_plant]\nmass = 0.8\n[payload]\nmass = -0.5\nstart = 0.0\n");
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
        "[actual_plant]\nmass = 0.3\n{MC}payload_mass = {{ dist = \"uniform\", low = -0.5, high = 0.5 }}\n"
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
    accepted(&format!("{MC}mass = {{ dist = \"normal\", mean = 0.74, std = 0.1, low = 0.3 }}\n"));
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
