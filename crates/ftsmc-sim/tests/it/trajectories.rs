//! Trajectories (`[reference] trajectory`): minimum snap continuity and
//! optimality, exact derivatives of every shape, feasibility, bad input, and
//! a closed-loop flight of the example figure-eight.

use ftsmc_sim::trajectory::feasibility::{self, VehicleLimits};
use ftsmc_sim::trajectory::{min_snap, FlatOutput, MinSnapSpec, Trajectory, TrajectorySpec};
use ftsmc_sim::Scenario;

fn min_snap_spec(waypoints: Vec<Vec<f64>>) -> MinSnapSpec {
    MinSnapSpec {
        waypoints,
        yaw: None,
        speed: Some(1.0),
        duration: None,
        times: None,
        start: 0.0,
        min_segment_time: 0.5,
    }
}

fn mission() -> Trajectory {
    let mut spec = min_snap_spec(vec![
        vec![0.0, 0.0, 1.0],
        vec![1.0, 0.5, 1.2],
        vec![2.0, -0.5, 1.5],
        vec![1.0, -1.5, 1.0],
        vec![0.0, 0.0, 1.0],
    ]);
    spec.yaw = Some(vec![0.0, 0.5, 1.0, 0.2, 0.0]);
    let t = Trajectory::new(TrajectorySpec::MinSnap(spec));
    t.check().expect("valid mission");
    t
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1.0)
}

#[test]
fn min_snap_is_continuous_to_snap_at_the_knots_and_rests_at_the_ends() {
    let t = mission();
    let plan = t.plan().unwrap();
    for i in 0..plan.times.len() - 2 {
        for o in 0..4 {
            let left = plan.segment_derivatives(i, o, 1.0);
            let right = plan.segment_derivatives(i + 1, o, 0.0);
            for m in 0..5 {
                assert!(
                    rel(left[m], right[m]) < 1e-9,
                    "knot {} output {o} derivative {m}: {left:?} vs {right:?}",
                    i + 1
                );
            }
        }
    }
    let last = plan.times.len() - 2;
    for o in 0..4 {
        let a = plan.segment_derivatives(0, o, 0.0);
        let b = plan.segment_derivatives(last, o, 1.0);
        for m in 1..4 {
            assert!(a[m].abs() < 1e-9 && b[m].abs() < 1e-9, "output {o} derivative {m}: {a:?} {b:?}");
        }
    }
    let start = t.sample(0.0);
    assert_eq!(start.pos, [0.0, 0.0, 1.0]);
    let w2 = t.sample(plan.times[2]);
    for (got, want) in w2.pos.iter().zip([2.0, -0.5, 1.5]) {
        assert!((got - want).abs() < 1e-12, "{:?}", w2.pos);
    }
    assert!((w2.yaw - 1.0).abs() < 1e-12);
}

#[test]
fn min_snap_times_follow_the_speed_rule() {
    let plan_of = |speed| {
        let mut s = min_snap_spec(vec![vec![0.0, 0.0, 1.0], vec![3.0, 4.0, 1.0], vec![3.0, 4.1, 1.0]]);
        s.speed = Some(speed);
        Trajectory::new(TrajectorySpec::MinSnap(s)).plan().unwrap().times.clone()
    };
    // 5 m at 2 m/s = 2.5 s; 0.1 m at 2 m/s = 0.05 s, raised to the 0.5 s minimum.
    assert_eq!(plan_of(2.0), vec![0.0, 2.5, 3.0]);
}

/// Central differences of `f` (samples of flat outputs) at `t`, step `h`.
fn check_derivatives(name: &str, f: &dyn Fn(f64) -> FlatOutput, times: &[f64]) {
    let h = 1e-4;
    for &t in times {
        let (m, p, c) = (f(t - h), f(t + h), f(t));
        let d = |a: f64, b: f64| (b - a) / (2.0 * h);
        for i in 0..3 {
            let pairs = [
                ("vel", d(m.pos[i], p.pos[i]), c.vel[i], c.acc[i]),
                ("acc", d(m.vel[i], p.vel[i]), c.acc[i], c.jerk[i]),
                ("jerk", d(m.acc[i], p.acc[i]), c.jerk[i], c.snap[i]),
            ];
            for (what, fd, exact, next) in pairs {
                let tol = 1e-6 * (1.0 + next.abs() + exact.abs()) + 1e-5 * next.abs();
                assert!((fd - exact).abs() < tol, "{name} {what}[{i}] at t = {t}: fd {fd} exact {exact}");
            }
            // Snap against the difference of jerk: the tolerance allows the
            // O(h²) term of the (unknown) fifth derivative.
            let fd = d(m.jerk[i], p.jerk[i]);
            assert!(
                (fd - c.snap[i]).abs() < 1e-4 * (1.0 + c.snap[i].abs()),
                "{name} snap[{i}] at t = {t}: fd {fd} exact {}",
                c.snap[i]
            );
        }
        let fd = d(m.yaw, p.yaw);
        assert!((fd - c.yaw_rate).abs() < 1e-6 * (1.0 + c.yaw_acc.abs()), "{name} yaw rate at {t}");
        let fd = d(m.yaw_rate, p.yaw_rate);
        assert!((fd - c.yaw_acc).abs() < 1e-5 * (1.0 + c.yaw_acc.abs()), "{name} yaw acc at {t}");
    }
}

fn shape(kind: &str, extra: &str) -> Trajectory {
    let text = format!("type = \"{kind}\"\nperiod = 6.0\nlaps = 2.0\nramp = 1.5\n{extra}");
    let spec: TrajectorySpec = toml::from_str(&text).unwrap_or_else(|e| panic!("{kind}: {e}"));
    let t = Trajectory::new(spec);
    t.check().unwrap_or_else(|e| panic!("{kind}: {e:?}"));
    t
}

fn every_shape() -> Vec<(&'static str, Trajectory)> {
    vec![
        ("hover", shape("hover", "")),
        ("circle", shape("circle", "radius = 1.2")),
        ("oval", shape("oval", "amplitude = [1.5, 0.7]")),
        ("figure-eight", shape("figure-eight", "amplitude = [1.0, 0.5]")),
        (
            "lissajous",
            shape("lissajous", "amplitude = [1.0, 0.8, 0.3]\nfrequencies = [1.0, 2.0, 3.0]\nphases = [0.3, 0.0, 1.0]"),
        ),
        ("helix", shape("helix", "radius = 1.0\nclimb = 0.4")),
        ("star", shape("star", "radius = 1.0\npoints = 5\ndepth = 0.4")),
        ("trefoil", shape("trefoil", "radius = 1.0\nheight = 0.3")),
        ("ramp", shape("ramp", "amplitude = [1.0, 0.5, 0.5]")),
    ]
}

#[test]
fn every_shape_and_min_snap_have_exact_derivatives() {
    // Inside the start ramp, at full speed, in the stop ramp, and in segments.
    let times = [0.3, 1.0, 1.49, 2.2, 5.0, 9.7, 12.6, 13.2];
    for (name, t) in every_shape() {
        check_derivatives(name, &|s| t.sample(s), &times);
    }
    let m = mission();
    let knots = m.plan().unwrap().times.clone();
    let inside: Vec<f64> = knots.windows(2).flat_map(|w| [0.3 * w[0] + 0.7 * w[1], 0.5 * (w[0] + w[1])]).collect();
    check_derivatives("min-snap", &|s| m.sample(s), &inside);
    // A stretched trajectory: derivatives scale by k^-m.
    let mut slow = mission();
    slow.set_stretch(1.7);
    check_derivatives("min-snap stretched", &|s| slow.sample(s), &inside);
}

#[test]
fn shapes_start_and_stop_at_rest_and_the_circle_has_its_radius() {
    for (name, t) in every_shape() {
        let end = t.end().unwrap();
        for s in [t.sample(0.0), t.sample(end), t.sample(end + 3.0)] {
            let moving = s.vel.iter().chain(&s.acc).chain(&s.jerk).chain(&s.snap).any(|v| v.abs() > 1e-9);
            assert!(!moving, "{name}: {s:?}");
        }
    }
    let circle = shape("circle", "radius = 1.2");
    for t in [2.0, 4.4, 7.9] {
        let p = circle.sample(t).pos;
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        assert!((r - 1.2).abs() < 1e-12, "{r}");
        assert!((p[2] - 1.0).abs() < 1e-15);
    }
}

#[test]
fn min_snap_is_the_minimum_of_the_snap_cost() {
    let t = mission();
    let plan = t.plan().unwrap();
    let (_, h) = min_snap::matrices();
    let base: f64 = (0..3).map(|o| plan.cost(o)).sum();
    // Perturb each free derivative of each interior knot alone: the cost rises
    // (quadratically: the gradient vanishes at the optimum).
    for knot in 1..plan.times.len() - 1 {
        for order in 0..3 {
            for o in 0..3 {
                for eps in [1e-3, -1e-3] {
                    let mut kd = plan.knot_derivatives.clone();
                    kd[knot][o][order] += eps;
                    let cost = |kd: &Vec<[[f64; 3]; 4]>| -> f64 {
                        (0..plan.times.len() - 1)
                            .map(|i| {
                                let p0 = plan.segment_derivatives(i, o, 0.0)[0];
                                let p1 = plan.segment_derivatives(i, o, 1.0)[0];
                                let (a, b) = (kd[i][o], kd[i + 1][o]);
                                let d = [p0, a[0], a[1], a[2], p1, b[0], b[1], b[2]];
                                min_snap::segment_cost(&h, plan.times[i + 1] - plan.times[i], &d)
                            })
                            .sum::<f64>()
                    };
                    let unperturbed = cost(&plan.knot_derivatives);
                    let perturbed = cost(&kd);
                    assert!(
                        perturbed > unperturbed,
                        "knot {knot} order {order} axis {o}: {perturbed} <= {unperturbed}"
                    );
                    // Quadratic growth: the first-order change is below the second-order one.
                    assert!((perturbed - unperturbed) < 1e-2 * base.max(1.0), "{perturbed} vs {unperturbed}");
                }
            }
        }
    }
}

fn load(extra: &str) -> Result<ftsmc_sim::scenario::resolve::Loaded, String> {
    let text = format!("name = \"t\"\nduration = 10.0\n{extra}");
    Scenario::from_toml_str_with_warnings(&text, "t.toml", &[]).map_err(|e| e.to_string())
}

#[test]
fn bad_input_is_refused_naming_the_key_index_and_value() {
    let cases = [
        (
            "[reference]\ntrajectory = { type = \"min-snap\", waypoints = [[0, 0, 1], [1, 0, 1], [1, 0, 1]], speed = 1.0 }",
            "reference.trajectory.waypoints[2]",
        ),
        (
            "[reference]\ntrajectory = { type = \"min-snap\", waypoints = [[0, 0, 1], [1, 0, 1], [2, 0, 1]], times = [0.0, 2.0, 2.0] }",
            "reference.trajectory.times[2]",
        ),
        ("[reference]\ntrajectory = { type = \"min-snap\", waypoints = [[0, 0, 1], [1, nan, 1]], speed = 1.0 }", "reference.trajectory.waypoints[1][1]"),
        ("[reference]\ntrajectory = { type = \"min-snap\", waypoints = [[0, 0, 1], [1, 0, 1]], speed = 0.0 }", "reference.trajectory.speed"),
        ("[reference]\ntrajectory = { type = \"min-snap\", waypoints = [[0, 0, 1], [1, 0, 1]], speed = -1.0 }", "reference.trajectory.speed"),
        ("[reference]\ntrajectory = { type = \"min-snap\", waypoints = [[0, 0, 1], [1, 0, 1]] }", "reference.trajectory.speed"),
        ("[reference]\ntrajectory = { type = \"min-snap\", waypoints = [[0, 0, 1], [1, 0]], speed = 1.0 }", "reference.trajectory.waypoints[1]"),
        ("[reference]\ntrajectory = { type = \"min-snap\", waypoints = [[0, 0, 1], [1, 0, 1]], speed = 1.0, yaw = [0.0] }", "reference.trajectory.yaw"),
        ("[reference]\ntrajectory = { type = \"circle\", radius = 0.0 }", "reference.trajectory.radius"),
        ("[reference]\ntrajectory = { type = \"circle\", period = inf }", "reference.trajectory.period"),
        ("[reference]\ntrajectory = { type = \"circle\", points = 5 }", "reference.trajectory.points"),
        ("[reference]\ntrajectory = { type = \"hover\" }\nx = 1.0", "reference.x"),
        ("[reference]\ntime_scale = \"fit\"", "reference.time_scale"),
    ];
    for (text, key) in cases {
        let e = load(text).err().unwrap_or_else(|| panic!("accepted: {text}"));
        assert!(e.contains(&format!("`{key}`")), "{text}\n→ {e}");
    }
}

#[test]
fn a_million_waypoints_are_refused_at_once_with_the_limit() {
    let waypoints: Vec<Vec<f64>> = (0..1_000_000).map(|i| vec![i as f64, 0.0, 1.0]).collect();
    let start = std::time::Instant::now();
    let t = Trajectory::new(TrajectorySpec::MinSnap(min_snap_spec(waypoints)));
    let (key, value, expected) = t.check().unwrap_err();
    assert!(start.elapsed().as_secs_f64() < 1.0, "{:?}", start.elapsed());
    assert_eq!(key, "waypoints");
    assert_eq!(value, "1000000 waypoints");
    assert!(expected.contains("10000") && expected.contains("split"), "{expected}");
    // At the limit it is solved (banded, linear in the count).
    let waypoints: Vec<Vec<f64>> = (0..10_000).map(|i| vec![(i % 2) as f64, i as f64 * 0.1, 1.0]).collect();
    let t = Trajectory::new(TrajectorySpec::MinSnap(min_snap_spec(waypoints)));
    t.check().expect("10^4 waypoints solve");
}

#[test]
fn feasibility_refuses_with_the_first_violation_and_fit_stretches() {
    // The Hummingbird of realistic-calm-1 (4 k_f ω_max² = 24.0 N, 0.716 kg) on a
    // figure-eight of 2 s per lap: about 10 m/s² sideways, beyond the 0.6 rad
    // tilt demand limit.
    let fast = "extends = \"realistic-calm-1\"\n[initial_state]\nposition = [0.0, 0.0, 1.0]\n[reference]\n\
                trajectory = { type = \"figure-eight\", center = [0.0, 0.0, 1.0], amplitude = [1.0, 0.5], period = 2.0, laps = 2, ramp = 1.0 }\n";
    let Err(e) = load(fast) else { panic!("a 2 s figure-eight was accepted") };
    eprintln!("refusal: {e}");
    assert!(e.contains("`reference.trajectory`") && e.contains("needs tilt") && e.contains("limit 0.6"), "{e}");
    let fitted = load(&format!("{fast}time_scale = \"fit\"\n")).expect("fitted");
    let k = fitted.scenario.reference.trajectory.as_ref().unwrap().stretch();
    assert!(k > 1.0 && k < 10.0, "{k}");
    assert!(fitted.warnings.iter().any(|w| w.contains("stretched by")), "{:?}", fitted.warnings);
    // Smallest: 1 % less stretch fails.
    let s = &fitted.scenario;
    let mut less = s.reference.trajectory.clone().unwrap();
    less.set_stretch(k * 0.99);
    assert!(feasibility::check(&less, &s.trajectory_limits(), s.duration).is_err());
    // Thrust: a vertical sprint beyond 24 N.
    let limits =
        VehicleLimits { mass: 0.716, gravity: 9.81, max_thrust: Some(24.0), max_tilt: 0.6, max_body_rate: None };
    let mut spec = min_snap_spec(vec![vec![0.0, 0.0, 1.0], vec![0.0, 0.0, 3.0]]);
    spec.speed = None;
    spec.duration = Some(0.6);
    let up = Trajectory::new(TrajectorySpec::MinSnap(spec));
    let v = feasibility::check(&up, &limits, 10.0).unwrap_err();
    assert_eq!(v.quantity, "thrust");
    assert_eq!(v.limit, 24.0);
    assert!(v.time > 0.0 && v.time < 0.4, "{v:?}");
    let k = feasibility::fit(&up, &limits, 10.0).unwrap();
    assert!(k > 1.0, "{k}");
}

#[test]
fn a_trajectory_replaces_the_base_files_steps_and_round_trips() {
    let loaded = load(
        "extends = \"paper-scenario-1\"\n[reference]\ntrajectory = { type = \"hover\", center = [0.5, 0.0, 1.0] }\n",
    )
    .expect("loads");
    let s = &loaded.scenario;
    assert!(s.reference.x.is_zero() && s.reference.psi.is_zero());
    let r = ftsmc_sim::run::reference_at(s, 3.0);
    assert_eq!(r.position, [0.5, 0.0, 1.0]);
    let text = s.to_toml().unwrap();
    let again = Scenario::from_toml_str(&text, "again.toml").unwrap();
    assert_eq!(&again, s);
    assert!(again.reference.same_bits(&s.reference));
}

/// The example figure-eight, flown by the PID/PX4 cascade on the calm rung
/// (Hummingbird rigid body, PX4 mixer, mocap + IMU, still air). Measured
/// when written: largest error after the 5 s steady-state start (after the
/// 2 s ramp) x 0.101 m, y 0.185 m, z 0.012 m; RMS over the whole run x
/// 0.064 m, y 0.113 m, z 0.011 m. The bounds leave room for model changes
/// but fail a controller that does not follow the figure (its 1 m and
/// 0.5 m half-widths).
#[test]
fn the_example_figure_eight_is_flown() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/examples/figure-eight.toml");
    let s = Scenario::from_file(&path).expect("example loads");
    let out =
        ftsmc_sim::registry::run("pid", &s, ftsmc_sim::RunOptions { record: false, ..Default::default() }).unwrap();
    assert!(out.exit.is_completed(), "{:?}", out.exit);
    let m = &out.metrics;
    eprintln!(
        "figure-eight pid: rms {:?} max after {:?}",
        [m.rms.x, m.rms.y, m.rms.z],
        [m.max_error_after.x, m.max_error_after.y, m.max_error_after.z]
    );
    for (e, bound) in [(m.max_error_after.x, 0.25), (m.max_error_after.y, 0.3), (m.max_error_after.z, 0.05)] {
        assert!(e.unwrap() < bound, "{e:?} >= {bound}");
    }
    assert!(m.rms.x < 0.15 && m.rms.y < 0.2 && m.rms.z < 0.05, "{:?}", m.rms);
}
