//! Closed-loop behaviour of FTAFTSMC on the paper's plant.

use ftsmc_core::cascade::{AttitudeDerivatives, Cascade, CascadeConfig, Controller, MassAdaptation};
use ftsmc_core::ftaftsmc::{reaching_law, FtaftsmcAxis};
use ftsmc_sim::registry;
use ftsmc_sim::run::{simulate, RunOptions};
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::signal::{Signal, Term};

fn paper_1() -> Scenario {
    Scenario::paper_scenarios().remove(0)
}

#[test]
fn scenario_1_settles_all_tracked_axes_within_5_s_with_printed_gains() {
    let s = paper_1();
    let run = registry::run("ftaftsmc", &s, RunOptions { record: false, ..Default::default() }).unwrap();
    assert!(run.exit.is_completed(), "{}", run.exit);
    let st = &run.metrics.settling_time;
    for (axis, t) in [("x", st.x), ("y", st.y), ("z", st.z), ("psi", st.psi)] {
        let t = t.unwrap_or_else(|| panic!("{axis} did not settle"));
        assert!(t < 5.0, "{axis} settles at {t} s");
    }
    println!(
        "scenario 1 FTAFTSMC ISE x {:.4} y {:.4} z {:.4} psi {:.4}",
        run.metrics.ise.x, run.metrics.ise.y, run.metrics.ise.z, run.metrics.ise.psi
    );
}

fn exact_model_scenario() -> Scenario {
    let mut s = paper_1();
    // Plant identical to the controller's model: no drag (the outer loop
    // treats drag as a disturbance), no rotor inertia (Ω̄ is known one tick late).
    s.plant.drag_translational = [0.0; 3];
    s.plant.drag_rotational = [0.0; 3];
    s.plant.rotor_inertia = 0.0;
    s.gains.ftaftsmc.mass_adaptation.enabled = false;
    s.reference.x = Signal::default();
    s.reference.y = Signal::default();
    s.reference.z = Signal { terms: vec![Term::Step { time: 0.0, height: 0.5 }], window: None };
    s.reference.psi = Signal { terms: vec![Term::Step { time: 0.0, height: 0.3 }], window: None };
    s.simulation.record_rate = s.simulation.control_rate;
    s.simulation.substeps = 4;
    s.duration = 3.0;
    s
}

#[test]
fn sliding_variable_obeys_the_reaching_law_when_the_model_is_exact() {
    // With exact cancellation, Ṡ = ϖ2 (Eq. 15) between control ticks up to
    // the zero-order-hold error O(dt).
    let s = exact_model_scenario();
    let run = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
    assert!(run.exit.is_completed());
    let dt = s.control_period();
    for (axis, gains) in [("z", s.gains.ftaftsmc.z), ("psi", s.gains.ftaftsmc.psi)] {
        let sv = run.recording.column(&format!("s_{axis}"));
        let dh = run.recording.column(&format!("delta_hat_{axis}"));
        let mut worst: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for k in 1..sv.len() - 1 {
            // δ̂ recorded after its update; ϖ2 used the value before it.
            let reaching = reaching_law(&gains, sv[k], dh[k - 1]);
            let fd = (sv[k + 1] - sv[k]) / dt;
            worst = worst.max((fd - reaching).abs());
            scale = scale.max(reaching.abs());
        }
        println!("{axis}: max |Ṡ − ϖ2| = {worst:.3e}, max |ϖ2| = {scale:.3e}");
        assert!(scale > 0.1, "{axis}: the test must exercise the reaching phase");
        assert!(worst < 0.03 * scale, "{axis}: max |Ṡ − ϖ2| = {worst} vs max |ϖ2| = {scale}");
    }
}

#[test]
fn sliding_variable_mismatch_shrinks_with_the_control_period() {
    // The residual of Ṡ = ϖ2 is the zero-order-hold error: halving dt halves it.
    let residual = |rate: f64| {
        let mut s = exact_model_scenario();
        s.simulation.control_rate = rate;
        s.simulation.record_rate = rate;
        s.duration = 1.0;
        let run = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
        let sv = run.recording.column("s_psi");
        let dh = run.recording.column("delta_hat_psi");
        let dt = 1.0 / rate;
        (1..sv.len() - 1)
            .map(|k| ((sv[k + 1] - sv[k]) / dt - reaching_law(&s.gains.ftaftsmc.psi, sv[k], dh[k - 1])).abs())
            .fold(0.0, f64::max)
    };
    let (coarse, fine) = (residual(1000.0), residual(4000.0));
    println!("residual 1 kHz {coarse:.3e}, 4 kHz {fine:.3e}");
    assert!(fine < 0.5 * coarse, "{fine} vs {coarse}");
}

fn hover_scenario(adapt: bool) -> Scenario {
    let mut s = paper_1();
    s.initial_state.position = [0.0, 0.0, 1.0];
    s.reference.x = Signal::default();
    s.reference.y = Signal::default();
    s.reference.z = Signal::constant(1.0);
    s.reference.psi = Signal::default();
    s.gains.ftaftsmc.mass_adaptation.enabled = adapt;
    s.duration = 5.0;
    s
}

#[test]
fn hover_without_mass_adaptation_is_an_exact_equilibrium() {
    let s = hover_scenario(false);
    let run = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
    let m = &run.metrics;
    for v in [m.ise.x, m.ise.y, m.ise.z, m.ise.phi, m.ise.theta, m.ise.psi] {
        assert!(v < 1e-20, "{v}");
    }
    let mg = s.plant.mass * s.plant.gravity;
    for &u in run.recording.column("thrust") {
        assert!((u - mg).abs() < 1e-9, "thrust {u} vs m g {mg}");
    }
}

#[test]
fn hover_with_mass_adaptation_stays_close_despite_the_leakage_term() {
    // Eq. 44's leakage −β1β2 α̂ pulls α̂ below 1; S_z balances it, leaving a
    // small steady altitude bias. Zero error does not stay exactly zero.
    let s = hover_scenario(true);
    let run = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
    let z = run.recording.column("z");
    let bias = z.iter().map(|v| (v - 1.0).abs()).fold(0.0, f64::max);
    println!("hover altitude bias with mass adaptation: {bias:.3e} m");
    assert!(bias > 0.0 && bias < 1e-3, "{bias}");
    let thrust = run.recording.column("thrust");
    let mg = s.plant.mass * s.plant.gravity;
    assert!((thrust.last().unwrap() - mg).abs() < 1e-2 * mg);
}

#[test]
fn both_attitude_derivative_options_run_and_differ() {
    let mut s = paper_1();
    s.duration = 5.0;
    let filtered = registry::run("ftaftsmc", &s, RunOptions { record: false, ..Default::default() }).unwrap();
    s.cascade.attitude_derivatives = AttitudeDerivatives::Zero;
    let zero = registry::run("ftaftsmc", &s, RunOptions { record: false, ..Default::default() }).unwrap();
    assert!(filtered.exit.is_completed() && zero.exit.is_completed());
    assert_ne!(filtered.metrics.ise.x, zero.metrics.ise.x);
}

#[test]
fn a_diverging_flight_is_an_outcome_not_a_panic() {
    let mut s = paper_1();
    // Absurd disturbance: 200 rad/s² on roll from t = 0.5 s.
    s.disturbance.phi = Signal { terms: vec![Term::Constant { value: 2000.0 }], window: Some([0.5, 20.0]) };
    let run = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
    match run.exit {
        ftsmc_sim::ExitStatus::Diverged { time, .. } => assert!((0.5..20.0).contains(&time), "{time}"),
        other => panic!("expected divergence, got {other}"),
    }
    assert!(run.metrics.duration < 20.0);
}

#[test]
fn controller_runs_directly_without_the_registry() {
    let s = paper_1();
    let gains = s.gains.ftaftsmc.gains().to_array();
    let config = CascadeConfig { model: s.plant, settings: s.cascade, mass_adaptation: MassAdaptation::PAPER };
    let mut c = Cascade::new(config, gains.map(FtaftsmcAxis::new)).unwrap();
    let out = simulate(&s, &mut c, RunOptions { record: false, ..Default::default() });
    assert_eq!(c.name(), "ftaftsmc");
    assert!(out.exit.is_completed());
}

#[test]
fn each_baseline_settles_scenario_1_within_8_s_with_default_gains() {
    let s = paper_1();
    for name in ["ranftsmc", "tsm-sta"] {
        let run = registry::run(name, &s, RunOptions { record: false, ..Default::default() }).unwrap();
        assert!(run.exit.is_completed(), "{name}: {}", run.exit);
        let st = &run.metrics.settling_time;
        for (axis, t) in [("x", st.x), ("y", st.y), ("z", st.z), ("psi", st.psi)] {
            let t = t.unwrap_or_else(|| panic!("{name}: {axis} did not settle"));
            assert!(t < 8.0, "{name}: {axis} settles at {t} s");
        }
    }
}

#[test]
fn mass_adaptation_winds_up_on_a_large_descent_unless_projected() {
    // 10 m above the reference: the computed u1 is negative for a while and
    // Eq. 44 drives α̂ far from any physical mass ratio; the z loop's gain
    // grows with it and the sampled loop diverges. Projecting α̂ onto
    // [0.5, 3] (opt-in `alpha_hat_bounds`) keeps the flight.
    let mut s = paper_1();
    s.duration = 6.0;
    s.reference.x = Signal::default();
    s.reference.y = Signal::default();
    s.reference.z = Signal::default();
    s.reference.psi = Signal::default();
    s.initial_state.position = [0.0, 0.0, 10.0];
    let paper_law = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
    let peak = paper_law.recording.column("alpha_hat").iter().fold(0.0f64, |m, v| m.max(*v));
    println!("paper law: {}, peak α̂ {peak:.2}", paper_law.exit);
    assert!(peak > 10.0, "α̂ peaked at {peak}");
    assert!(!paper_law.exit.is_completed());

    s.gains.ftaftsmc.mass_adaptation.alpha_hat_bounds = Some([0.5, 3.0]);
    let projected = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
    assert!(projected.exit.is_completed(), "{}", projected.exit);
    assert!(projected.recording.column("alpha_hat").iter().all(|a| (0.5..=3.0).contains(a)));
    assert!(projected.metrics.settling_time.z.is_some_and(|t| t < 4.0), "{:?}", projected.metrics.settling_time.z);
}
