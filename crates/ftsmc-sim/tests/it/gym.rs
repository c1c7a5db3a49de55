//! The reinforcement-learning environments (`ftsmc_sim::gym`): a seed
//! gives the same episode bits; a lane of a batch flies exactly as a lone
//! environment; next-step auto-reset; a scripted PD hovers in the
//! realistic scenario (sensors, wind, motors, ground) while doing nothing
//! falls and crashes; bad settings are refused by name.

use ftsmc_sim::gym::{ActionMode, Batch, GymSettings, GymSpec, Observe, StepResult, Task, ACTION_LEN, OBSERVATION_LEN};
use ftsmc_sim::scenario::resolve::built_in;
use ftsmc_sim::Scenario;

fn realistic() -> Scenario {
    let (file, text) = built_in("realistic-breeze-1").expect("built in");
    Scenario::from_toml_str(text, file).expect("valid")
}

fn hover(action: ActionMode, max_time: f64) -> GymSpec {
    let settings = GymSettings {
        task: Task::Hover { target: [0.0, 0.0, 1.0] },
        action,
        max_episode_time: Some(max_time),
        ..GymSettings::default()
    };
    GymSpec::new(realistic(), "realistic-breeze-1", settings).expect("valid spec")
}

/// A PD on the observation (thrust + body rates): the scripted baseline of
/// the Python example, in Rust.
fn pd(obs: &[f32], max_thrust: f64, mass: f64) -> [f64; ACTION_LEN] {
    let o: Vec<f64> = obs.iter().map(|&v| v as f64).collect();
    let (phi, theta) = (ftsmc_core::math::atan2(o[13], o[14]), -ftsmc_core::math::asin(o[12]));
    let g = 9.81;
    let ax = -2.0 * o[0] - 2.5 * o[3];
    let ay = -2.0 * o[1] - 2.5 * o[4];
    let az = -4.0 * o[2] - 3.0 * o[5];
    let thrust = mass * (g + az) / (o[14].max(0.5));
    let (theta_d, phi_d) = (ax / g, -ay / g);
    let p = 8.0 * (phi_d - phi) / 7.0;
    let q = 8.0 * (theta_d - theta) / 7.0;
    let r = -2.0 * ftsmc_core::math::atan2(o[7], o[6]) / 3.0;
    [2.0 * thrust / max_thrust - 1.0, p, q, r]
}

fn fly(spec: &GymSpec, seeds: &[u64], steps: usize, policy: &dyn Fn(&[f32]) -> [f64; ACTION_LEN]) -> Vec<StepResult> {
    let mut batch = Batch::new(spec.clone(), seeds);
    let mut out = StepResult::default();
    batch.reset(seeds, &mut out);
    let n = seeds.len();
    let mut results = vec![out.clone()];
    for k in 0..steps {
        let actions: Vec<f64> =
            (0..n).flat_map(|i| policy(&out.observation[i * OBSERVATION_LEN..][..OBSERVATION_LEN])).collect();
        let reset_seeds: Vec<u64> = (0..n as u64).map(|i| 1000 + 10 * k as u64 + i).collect();
        batch.step(&actions, &reset_seeds, &mut out);
        results.push(out.clone());
    }
    results
}

fn scale(spec: &GymSpec) -> (f64, f64) {
    let s = ftsmc_sim::gym::agent::ActionScale::of(&spec.scenario);
    (s.max_thrust, spec.scenario.rigid_body_params().mass)
}

#[test]
fn pd_hovers_and_zero_thrust_crashes() {
    let spec = hover(ActionMode::Ctbr, 5.0);
    let (tmax, mass) = scale(&spec);
    let run = fly(&spec, &[7], 500, &|o| pd(o, tmax, mass));
    let last = run.last().unwrap();
    let ended = run.iter().position(|r| r.truncated[0]).expect("truncated at 5 s");
    assert_eq!(ended, 500, "5 s at 100 Hz: the 500th step truncates");
    assert!(run.iter().all(|r| !r.terminated[0]), "the PD never crashes");
    assert_eq!(last.reason[0], "completed");
    // The breeze (2.5 m/s mean wind, σ_u = 0.5 m/s) moves it, but it stays near the point.
    let worst = run[200..].iter().flat_map(|r| r.observation[..3].iter().map(|v| v.abs())).fold(0.0f32, f32::max);
    assert!(worst < 0.5, "hover error up to {worst} m in the breeze");
    // Rotors idle: the vehicle falls from 1 m and hits the ground faster than 1 m/s.
    let fall = fly(&spec, &[7], 100, &|_| [-1.0, 0.0, 0.0, 0.0]);
    let k = fall.iter().position(|r| r.terminated[0]).expect("a crash");
    assert!(fall[k].reason[0].starts_with("crashed"), "{}", fall[k].reason[0]);
    assert!(fall[k].reward[0] < -5.0, "crash penalty");
}

#[test]
fn same_seed_same_bits_and_lanes_fly_alone() {
    let spec = hover(ActionMode::Ctbr, 0.5);
    let (tmax, mass) = scale(&spec);
    let policy = |o: &[f32]| pd(o, tmax, mass);
    let a = fly(&spec, &[3, 4, 5], 70, &policy);
    let b = fly(&spec, &[3, 4, 5], 70, &policy);
    assert_eq!(a, b, "same seeds, same bits");
    // Lane 1 of the batch equals a lone environment seeded 4, auto-reset seeds included.
    let lone: Vec<StepResult> = {
        let mut batch = Batch::new(spec.clone(), &[4]);
        let mut out = StepResult::default();
        batch.reset(&[4], &mut out);
        let mut v = vec![out.clone()];
        for k in 0..70u64 {
            batch.step(&policy(&out.observation), &[1000 + 10 * k + 1], &mut out);
            v.push(out.clone());
        }
        v
    };
    for (x, y) in a.iter().zip(&lone) {
        assert_eq!(&x.observation[OBSERVATION_LEN..2 * OBSERVATION_LEN], &y.observation[..]);
        assert_eq!((x.reward[1], x.terminated[1], x.truncated[1]), (y.reward[0], y.terminated[0], y.truncated[0]));
    }
    // Another seed: other sensor noise and turbulence.
    assert_ne!(a[1].observation[..OBSERVATION_LEN], a[1].observation[OBSERVATION_LEN..2 * OBSERVATION_LEN]);
    // Large batches go through the thread pool: the bits stay.
    let seeds: Vec<u64> = (0..20).collect();
    let big = fly(&spec, &seeds, 5, &policy);
    let small = fly(&spec, &seeds[3..4], 5, &policy);
    for (x, y) in big.iter().zip(&small) {
        assert_eq!(&x.observation[3 * OBSERVATION_LEN..4 * OBSERVATION_LEN], &y.observation[..]);
    }
}

#[test]
fn next_step_autoreset() {
    // 0.5 s episodes: step 50 truncates, step 51 resets (reward 0, action ignored).
    let spec = hover(ActionMode::Ctbr, 0.5);
    let (tmax, mass) = scale(&spec);
    let run = fly(&spec, &[1], 52, &|o| pd(o, tmax, mass));
    assert!(run[50].truncated[0] && !run[50].reset[0]);
    assert!(run[51].reset[0] && !run[51].truncated[0] && !run[51].terminated[0]);
    assert_eq!(run[51].reward[0], 0.0);
    assert_eq!(run[51].time[0], 0.0);
    assert!(!run[52].reset[0] && run[52].time[0] > 0.0);
    // The new episode starts at the hover point again.
    assert!(run[51].observation[..3].iter().all(|v| v.abs() < 0.01), "{:?}", &run[51].observation[..3]);
}

#[test]
fn motors_at_hover_speed_hold_altitude_with_truth() {
    // All four rotors at the hover speed through the mixer and motors, truth
    // observed: the vehicle stays near 1 m for 1 s (only turbulence moves it).
    let settings = GymSettings {
        task: Task::Hover { target: [0.0, 0.0, 1.0] },
        action: ActionMode::Motors,
        observe: Observe::Truth,
        max_episode_time: Some(1.0),
        ..GymSettings::default()
    };
    let spec = GymSpec::new(realistic(), "realistic-breeze-1", settings).unwrap();
    let s = ftsmc_sim::gym::agent::ActionScale::of(&spec.scenario);
    let rb = spec.scenario.rigid_body_params();
    let hover = (rb.mass * rb.gravity / s.allocation[0].iter().sum::<f64>()).sqrt();
    let a = 2.0 * (hover - s.min_rotor_speed) / (s.max_rotor_speed - s.min_rotor_speed) - 1.0;
    let run = fly(&spec, &[2], 20, &|_| [a; 4]);
    let ez = run[20].observation[2];
    assert!(ez.abs() < 0.05, "altitude error after 0.2 s at hover speed: {ez}");
    // At full speed it climbs.
    let up = fly(&spec, &[2], 20, &|_| [1.0; 4]);
    assert!(up[20].observation[2] > 0.3, "{}", up[20].observation[2]);
}

#[test]
fn bad_settings_are_refused_by_name() {
    let bad = |settings: GymSettings| GymSpec::new(realistic(), "realistic-breeze-1", settings).unwrap_err();
    let e = bad(GymSettings { agent_rate: 300.0, ..GymSettings::default() });
    assert!(e.contains("agent_rate") && e.contains("300"), "{e}");
    let e = bad(GymSettings { max_episode_time: Some(-1.0), ..GymSettings::default() });
    assert!(e.contains("max_episode_time") && e.contains("-1"), "{e}");
    let mut settings = GymSettings::default();
    settings.reward.position = f64::NAN;
    let e = bad(settings);
    assert!(e.contains("reward.position") && e.contains("NaN"), "{e}");
    // `randomize` needs the scenario's `[montecarlo]` draws: paper scenario 1 has none.
    let (file, text) = built_in("paper-scenario-1").expect("built in");
    let plain = Scenario::from_toml_str(text, file).expect("valid");
    let e =
        GymSpec::new(plain, "paper-scenario-1", GymSettings { randomize: true, ..GymSettings::default() }).unwrap_err();
    assert!(e.contains("montecarlo"), "{e}");
}
