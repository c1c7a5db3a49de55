//! Identification: the parameters of ftsmc's rigid body that flight logs
//! determine, by linear least squares on the Newton–Euler equations, with
//! bootstrap intervals over flight segments.
//!
//! # Model (body frame forward-left-up, rotors numbered as ftsmc's)
//!
//! A command `u_i ∈ [0, 1]` asks for the rotor speed `u_i ω_max`; the rotor
//! follows it through a first-order lag of time constant τ, integrated
//! exactly under the zero-order hold of the logged commands:
//! `ū_i(t_{k+1}) = u_i(t_k) + (ū_i(t_k) − u_i(t_k)) e^{−Δt/τ}`, so
//! `ω_i = ω_max ū_i` and `T_i = k_f ω_i²` (ftsmc's rotor, `[vehicle]
//! thrust_coefficient`). With the accelerometer's specific force `f` and
//! the body velocity `v_B = Rᵀ v`:
//!
//! - vertical: `f_z = b₂ Σ ū_i² − c_z Σ ū_i w_{i,z}`,
//!   `b₂ = k_f ω_max² / m`, `c_z = k_z ω_max / m` (rotor axial drag), with
//!   `w_i = v_B + ω × r_i` the local airspeed of rotor `i` at `r_i`;
//! - horizontal: `f_{x,y} = −c_xy Σ ū_i w_{i,x,y}`, `c_xy = k_d ω_max / m`
//!   (rotor drag proportional to rotor speed, RotorPy's `k_d`, `k_z`);
//! - angular: with `α = Δω/Δt` over each sample step, the gyroscopic terms
//!   moved to the left (`ω × (Jω + h_r)`, with the base vehicle's J and
//!   rotor inertia) and `ū²` averaged over the step,
//!   `α_x + … = θ_x Σ r_{y,i} ū_i² + η_x M_x`,
//!   `α_y + … = −θ_y Σ r_{x,i} ū_i² + η_y M_y`,
//!   `α_z + … = −θ_z Σ s_i ū_i² + η_z M_z`,
//!   `θ_x = k_f ω_max² / J_x`, `θ_y = k_f ω_max² / J_y`,
//!   `θ_z = k_m ω_max² / J_z`; `M = Σ r_i × (−ū_i w_i)` (x, y from the
//!   axial, z from the in-plane components) are the moments of the rotor
//!   drag forces per unit coefficient, `η_{x,y} = k_z ω_max / J_{x,y}`,
//!   `η_z = k_d ω_max / J_z` (reported; ftsmc computes those moments from
//!   `k_d`, `k_z` itself).
//!
//! Each equation is linear in its coefficients for a given τ; τ is chosen
//! on a grid (`tau_step_s`) as the value that minimises the sum of the
//! unexplained variance fractions `1 − R²` of the vertical, roll and pitch
//! fits (separable least squares: Golub and Pereyra 1973). This is the
//! regression of Förster (2015, "System Identification of the Crazyflie 2.0
//! Nano Quadrocopter", ETH Zurich) — thrust quadratic in the PWM command,
//! torque over inertia from the rotor-force moments — done on flight data
//! instead of a thrust stand, as in Eschmann et al. (2024,
//! arXiv:2404.07837) for the motor delay.
//!
//! # What needs the mass
//!
//! A log measures accelerations, so it identifies forces and moments per
//! mass and per inertia: `b₂`, `c_z`, `c_xy`, `θ`, τ and the ratio
//! `J_x/J_y = θ_y/θ_x` need nothing else. With the mass `m` (`--mass`, else
//! the base vehicle's): `k_f = m b₂/ω_max²`, `J_x = m b₂/θ_x`,
//! `J_y = m b₂/θ_y`, `k_z = m c_z/ω_max`, `k_d = m c_xy/ω_max`. The yaw
//! moment coefficient needs `J_z` too, which no translational equation
//! gives: `k_m = θ_z J_z/ω_max²` with the base vehicle's `J_z`.
//!
//! # Intervals
//!
//! Each flight is cut into segments of `segment_s`; a bootstrap replicate
//! draws as many segments as there are, with replacement, and refits
//! everything (τ included); the interval is the 2.5–97.5 % percentile of
//! the replicates (Efron and Tibshirani 1993, ch. 13; segments rather than
//! samples keep the samples' correlation, Künsch 1989). The draws come from
//! `ChaCha8` seeded with `seed` (stream [`BOOTSTRAP_STREAM`]): the same
//! logs and seed give the same intervals.

use ftsmc_sim::vehicle::RigidBodyParams;
use rand::Rng;

use crate::error::IdentError;
use crate::lsq::{index_below, quantile, Normal};
use crate::series::{world_to_body, Series};
use crate::vehicle::Vehicle;

/// ChaCha stream of the bootstrap draws.
pub const BOOTSTRAP_STREAM: u64 = 0x1DE7;

/// Settings of [`identify`].
#[derive(Clone, Debug, PartialEq)]
pub struct IdentifyOptions {
    /// Mass, kg (default: the base vehicle's).
    pub mass_kg: Option<f64>,
    /// Length of a bootstrap segment, s (default 2).
    pub segment_s: f64,
    /// Bootstrap replicates (default 200; 0: no intervals).
    pub bootstrap: usize,
    /// Seed of the bootstrap draws (default 0).
    pub seed: u64,
    /// Largest motor time constant tried, s (default 0.2).
    pub tau_max_s: f64,
    /// Step of the τ grid, s (default 0.002).
    pub tau_step_s: f64,
    /// A sample counts as flight when every rotor command is at least this
    /// (0–1, default 0.05).
    pub min_command: f64,
    /// Largest command delay tried, log steps (default 0): the commands are
    /// shifted later by 0…this many samples before the lag, a transport
    /// delay of the log's timing (the motor values logged before they act,
    /// the IMU's filters) that the vehicle file cannot hold; `ftsmc
    /// validate --command-delay` applies it.
    pub max_delay_steps: usize,
}

impl Default for IdentifyOptions {
    fn default() -> Self {
        Self {
            mass_kg: None,
            segment_s: 2.0,
            bootstrap: 200,
            seed: 0,
            tau_max_s: 0.2,
            tau_step_s: 0.002,
            min_command: 0.05,
            max_delay_steps: 0,
        }
    }
}

/// One identified quantity with its bootstrap interval.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// Name (`tau`, `thrust_coefficient`, …).
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// The fit on all segments.
    pub value: f64,
    /// 2.5 % bootstrap percentile (NaN without bootstrap).
    pub lo: f64,
    /// 97.5 % bootstrap percentile.
    pub hi: f64,
    /// What it rests on: "log", "log + mass" or "log + mass + base J_z".
    pub basis: &'static str,
    /// The base vehicle's value, where it has one (NaN otherwise).
    pub base: f64,
}

/// A thrust map fitted at the chosen τ (the vertical equation).
#[derive(Clone, Debug, PartialEq)]
pub struct ThrustMap {
    /// Which form.
    pub name: &'static str,
    /// Per-rotor thrust at full command, linear term `a₁` of
    /// `T = a₁ ū + a₂ ū²`, N (0 for the pure quadratic).
    pub linear_n: f64,
    /// Quadratic term `a₂`, N.
    pub quadratic_n: f64,
    /// R² of the vertical specific force.
    pub r2: f64,
}

/// The result of [`identify`].
#[derive(Clone, Debug, PartialEq)]
pub struct Identification {
    /// The logs, as given.
    pub flights: Vec<String>,
    /// The base vehicle.
    pub base: Vehicle,
    /// Mass used for the mass-dependent values, kg.
    pub mass_kg: f64,
    /// Where the mass came from ("--mass" or the base vehicle).
    pub mass_source: String,
    /// Rows (sample steps in flight) fitted.
    pub rows: usize,
    /// Segments the bootstrap draws from.
    pub segments: usize,
    /// Bootstrap replicates that solved (of those asked for).
    pub replicates: usize,
    /// Every estimate (mass-free first).
    pub estimates: Vec<Estimate>,
    /// R² of each fitted equation at the chosen τ: `f_z`, `f_xy`, `alpha_x`, `alpha_y`, `alpha_z`.
    pub r2: Vec<(&'static str, f64)>,
    /// Thrust maps compared: pure quadratic (ftsmc's rotor), with a linear
    /// term, and both with the command scaled by `V / V_ref` (battery).
    pub thrust_maps: Vec<ThrustMap>,
    /// Mean battery voltage of the fitted rows, V (NaN when not logged).
    pub battery_ref_v: f64,
    /// The seed of the bootstrap.
    pub seed: u64,
}

impl Identification {
    /// The estimate named `name`.
    pub fn get(&self, name: &str) -> Option<&Estimate> {
        self.estimates.iter().find(|e| e.name == name)
    }
}

#[derive(Clone, Copy, Default)]
struct Sums {
    z: Normal<3>,
    zv: Normal<3>,
    xy: Normal<1>,
    ang: [Normal<2>; 3],
}

impl Sums {
    fn add_scaled(&mut self, o: &Sums, w: f64) {
        self.z.add_scaled(&o.z, w);
        self.zv.add_scaled(&o.zv, w);
        self.xy.add_scaled(&o.xy, w);
        for a in 0..3 {
            self.ang[a].add_scaled(&o.ang[a], w);
        }
    }
}

/// `s` with its commands shifted `d` samples later (`u'_k = u_{k−d}`, the
/// first command held before).
pub fn delay(s: &Series, d: usize) -> Series {
    let mut out = s.clone();
    for k in 0..s.len() {
        out.commands[k] = s.commands[k.saturating_sub(d)];
    }
    out
}

/// Lagged commands `ū` of a series for time constant `tau` (module docs):
/// `ū(t_0) = u(t_0)`, then the exact first-order response to the held command.
pub fn lagged_commands(s: &Series, tau: f64, scale: Option<&[f64]>) -> Vec<[f64; 4]> {
    let n = s.len();
    let cmd = |k: usize| {
        let f = scale.map_or(1.0, |v| v[k]);
        s.commands[k].map(|u| u * f)
    };
    let mut out = Vec::with_capacity(n);
    let mut y = cmd(0);
    out.push(y);
    for k in 1..n {
        let u = cmd(k - 1);
        let dt = s.time_s[k] - s.time_s[k - 1];
        let a = if tau > 0.0 { ftsmc_core::math::exp(-dt / tau) } else { 0.0 };
        y = core::array::from_fn(|i| u[i] + (y[i] - u[i]) * a);
        out.push(y);
    }
    out
}

/// Identifies the parameters of the module docs from `logs` against the
/// `base` vehicle (its layout, ω_max, rotor inertia and J for the
/// gyroscopic terms, and its mass unless `options.mass_kg`).
pub fn identify(logs: &[Series], base: &Vehicle, options: &IdentifyOptions) -> Result<Identification, IdentError> {
    check_options(options)?;
    let what = || logs.iter().map(|s| s.source.as_str()).collect::<Vec<_>>().join(", ");
    if logs.is_empty() {
        return Err(IdentError::TooShort { what: "identify".into(), found: "no log".into(), needed: "one".into() });
    }
    let body = &base.body;
    let w_max = base.max_rotor_speed();
    let mass = options.mass_kg.unwrap_or(body.mass);
    let mass_source =
        if options.mass_kg.is_some() { "--mass".to_string() } else { format!("{} (base vehicle)", base.name) };
    // Flying rows k (k-1, k, k+1 flying) and their segment.
    let mut rows: Vec<Vec<(usize, usize)>> = Vec::new();
    let mut segments = 0usize;
    for s in logs {
        let mut r = Vec::new();
        let mut seg_of_bin = std::collections::BTreeMap::new();
        for k in 1..s.len().saturating_sub(1) {
            if s.flying(k - 1, options.min_command)
                && s.flying(k, options.min_command)
                && s.flying(k + 1, options.min_command)
            {
                let bin = (s.time_s[k] / options.segment_s).floor() as i64;
                let seg = *seg_of_bin.entry(bin).or_insert_with(|| {
                    segments += 1;
                    segments - 1
                });
                r.push((k, seg));
            }
        }
        rows.push(r);
    }
    let n_rows: usize = rows.iter().map(Vec::len).sum();
    if segments < 4 {
        return Err(IdentError::TooShort {
            what: what(),
            found: format!("{n_rows} sample steps of flight in {segments} segment(s) of {} s", options.segment_s),
            needed: format!(
                "at least 4 segments of flight (every rotor command ≥ {}) for the fit and its bootstrap",
                options.min_command
            ),
        });
    }
    let with_battery = logs.iter().all(|s| s.battery_v.is_some());
    let battery_ref_v = if with_battery {
        let (mut sum, mut n) = (0.0, 0.0);
        for (s, r) in logs.iter().zip(&rows) {
            for &(k, _) in r {
                sum += s.battery_v.as_ref().unwrap()[k];
                n += 1.0;
            }
        }
        sum / n
    } else {
        f64::NAN
    };
    let positions = body.rotor_positions();
    let spin = body.spin.map(|s| s.sign());
    let inertia = [body.inertia[0][0], body.inertia[1][1], body.inertia[2][2]];
    let n_tau = (options.tau_max_s / options.tau_step_s).round() as usize + 1;
    // The grid: every delay (steps) with every τ.
    let grid: Vec<(usize, f64)> = (0..=options.max_delay_steps)
        .flat_map(|d| (0..n_tau).map(move |i| (d, i as f64 * options.tau_step_s)))
        .collect();
    let taus: Vec<f64> = grid.iter().map(|g| g.1).collect();
    let delayed: Vec<Vec<Series>> =
        (0..=options.max_delay_steps).map(|d| logs.iter().map(|s| delay(s, d)).collect()).collect();
    // sums[grid point][segment]
    let mut sums = vec![vec![Sums::default(); segments]; grid.len()];
    for (ti, &(d, tau)) in grid.iter().enumerate() {
        for (s, r) in delayed[d].iter().zip(&rows) {
            let lag = lagged_commands(s, tau, None);
            let scale: Option<Vec<f64>> = s.battery_v.as_ref().map(|v| v.iter().map(|x| x / battery_ref_v).collect());
            let lag_v = scale.as_ref().map(|sc| lagged_commands(s, tau, Some(sc)));
            for &(k, seg) in r {
                let acc = &mut sums[ti][seg];
                push_rows(
                    acc,
                    s,
                    k,
                    &lag,
                    lag_v.as_deref(),
                    &s.commands,
                    tau,
                    &positions,
                    &spin,
                    &inertia,
                    body,
                    w_max,
                );
            }
        }
    }
    let ones = vec![1.0; segments];
    let point = fit_all(&sums, &ones, &taus)
        .ok_or_else(|| IdentError::Singular { what: what(), channel: "the thrust, roll or pitch equations" })?;
    let mut replicates: Vec<[f64; N_PARAMS]> = Vec::new();
    let mut replicate_grid: Vec<usize> = Vec::new();
    let mut rng = ftsmc_sim::rng::chacha_stream(options.seed, BOOTSTRAP_STREAM);
    for _ in 0..options.bootstrap {
        let mut w = vec![0.0; segments];
        for _ in 0..segments {
            w[index_below(rng.next_u64(), segments)] += 1.0;
        }
        if let Some(f) = fit_all(&sums, &w, &taus) {
            replicates.push(f.params);
            replicate_grid.push(f.tau_index);
        }
    }
    // Derived values of a parameter vector.
    let derived = |p: &[f64; N_PARAMS]| -> [f64; N_DERIVED] {
        let [_, b2, cz, cxy, tx, ty, tz, ..] = *p;
        let kf = mass * b2 / (w_max * w_max);
        [
            ty / tx,
            kf,
            mass * b2 / tx,
            mass * b2 / ty,
            tz * inertia[2] / (w_max * w_max),
            mass * cxy / w_max,
            mass * cz / w_max,
        ]
    };
    let mut estimates = Vec::new();
    let base_params = base_parameter_values(body, w_max, base.time_constant());
    for (i, (name, unit)) in PARAM_NAMES.iter().enumerate() {
        let col: Vec<f64> = replicates.iter().map(|p| p[i]).collect();
        estimates.push(estimate(name, unit, point.params[i], &col, "log", base_params[i]));
    }
    widen_by_grid(&mut estimates[0], options.tau_step_s);
    let delay_of = |ti: usize| grid[ti].0 as f64;
    let delay_reps: Vec<f64> = replicate_grid.iter().map(|&ti| delay_of(ti)).collect();
    estimates.push(estimate("command_delay_steps", "log steps", delay_of(point.tau_index), &delay_reps, "log", 0.0));
    let d_point = derived(&point.params);
    let d_reps: Vec<[f64; N_DERIVED]> = replicates.iter().map(derived).collect();
    let base_derived = [
        inertia[0] / inertia[1],
        body.thrust_coefficient,
        inertia[0],
        inertia[1],
        body.moment_coefficient,
        body.rotor_drag_xy,
        body.rotor_drag_z,
    ];
    for (i, (name, unit, basis)) in DERIVED_NAMES.iter().enumerate() {
        let col: Vec<f64> = d_reps.iter().map(|p| p[i]).collect();
        estimates.push(estimate(name, unit, d_point[i], &col, basis, base_derived[i]));
    }
    // Thrust maps at the chosen τ.
    let total = total_at(&sums[point.tau_index], &ones);
    let mut thrust_maps = Vec::new();
    let per_rotor = mass; // b (m/s² per rotor at full command) × m = N
    for (name, normal, cols) in [
        ("quadratic (ftsmc rotor)", &total.z, &[0usize, 1][..]),
        ("linear + quadratic", &total.z, &[0, 1, 2][..]),
        ("quadratic, command x V/V_ref", &total.zv, &[0, 1][..]),
        ("linear + quadratic, command x V/V_ref", &total.zv, &[0, 1, 2][..]),
    ] {
        if normal.n == 0.0 {
            continue;
        }
        if let Some(f) = normal.solve(cols) {
            thrust_maps.push(ThrustMap {
                name,
                linear_n: per_rotor * f.beta[2],
                quadratic_n: per_rotor * f.beta[0],
                r2: f.r2(),
            });
        }
    }
    Ok(Identification {
        flights: logs.iter().map(|s| s.source.clone()).collect(),
        base: base.clone(),
        mass_kg: mass,
        mass_source,
        rows: n_rows,
        segments,
        replicates: replicates.len(),
        estimates,
        r2: point.r2.to_vec(),
        thrust_maps,
        battery_ref_v,
        seed: options.seed,
    })
}

fn check_options(o: &IdentifyOptions) -> Result<(), IdentError> {
    let bad = |option, value: f64, expected| Err(IdentError::Option { option, value: value.to_string(), expected });
    if let Some(m) = o.mass_kg {
        if !(m > 0.0 && m.is_finite()) {
            return bad("mass", m, "a positive mass in kg");
        }
    }
    if !(o.segment_s > 0.0 && o.segment_s.is_finite()) {
        return bad("segment_s", o.segment_s, "a positive duration in s");
    }
    if !(o.tau_step_s > 0.0 && o.tau_max_s >= 0.0 && o.tau_max_s / o.tau_step_s <= 10_000.0) {
        return bad("tau_step_s", o.tau_step_s, "a positive step with at most 10,000 steps up to tau_max_s");
    }
    if o.max_delay_steps > 100 {
        return Err(IdentError::Option {
            option: "max_delay_steps",
            value: o.max_delay_steps.to_string(),
            expected: "at most 100 log steps",
        });
    }
    if !(0.0..1.0).contains(&o.min_command) {
        return bad("min_command", o.min_command, "a command in [0, 1)");
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn push_rows(
    acc: &mut Sums,
    s: &Series,
    k: usize,
    lag: &[[f64; 4]],
    lag_v: Option<&[[f64; 4]]>,
    held: &[[f64; 4]],
    tau: f64,
    positions: &[[f64; 3]; 4],
    spin: &[f64; 4],
    inertia: &[f64; 3],
    body: &RigidBodyParams,
    w_max: f64,
) {
    let q = &s.attitude_wxyz[k];
    let vb = world_to_body(q, &s.velocity_m_s[k]);
    let f = s.specific_force_m_s2[k];
    let (w0, w1) = (s.body_rates_rad_s[k], s.body_rates_rad_s[k + 1]);
    let wk = w0;
    let y = lag[k];
    let s2: f64 = y.iter().map(|u| u * u).sum();
    let s1: f64 = y.iter().sum();
    // Each rotor's local airspeed v_B + ω × r_i (rotors in the plane z_B = 0).
    let local = |i: usize, w: &[f64; 3]| {
        let r = positions[i];
        [vb[0] - w[2] * r[1], vb[1] + w[2] * r[0], vb[2] + w[0] * r[1] - w[1] * r[0]]
    };
    let drag_cols = |u: &[f64; 4], w: &[f64; 3]| -> [f64; 3] {
        let mut c = [0.0; 3];
        for i in 0..4 {
            let v = local(i, w);
            for a in 0..3 {
                c[a] -= u[i] * v[a];
            }
        }
        c
    };
    let dk = drag_cols(&y, &wk);
    acc.z.push(&[s2, dk[2], s1], f[2]);
    if let Some(lv) = lag_v {
        let yv = lv[k];
        let s1v: f64 = yv.iter().sum();
        let s2v: f64 = yv.iter().map(|u| u * u).sum();
        acc.zv.push(&[s2v, drag_cols(&yv, &wk)[2], s1v], f[2]);
    }
    acc.xy.push(&[dk[0]], f[0]);
    acc.xy.push(&[dk[1]], f[1]);
    let dt = s.time_s[k + 1] - s.time_s[k];
    let wm: [f64; 3] = core::array::from_fn(|a| 0.5 * (w0[a] + w1[a]));
    // Means of ū and ū² over the step under the exact lag response
    // ū(t) = u + (ū_k − u) e^{−t/τ} to the held command u = u_k (scaled by
    // the battery when `lag` is): m₁ = (τ/Δt)(1 − e^{−Δt/τ}),
    // m₂ = (τ/2Δt)(1 − e^{−2Δt/τ}).
    let u_held = held[k];
    let (m1, m2) = if tau > 0.0 {
        let a = ftsmc_core::math::exp(-dt / tau);
        (tau / dt * (1.0 - a), tau / (2.0 * dt) * (1.0 - a * a))
    } else {
        (0.0, 0.0)
    };
    let ym: [f64; 4] = core::array::from_fn(|i| u_held[i] + (y[i] - u_held[i]) * m1);
    let ym2: [f64; 4] = core::array::from_fn(|i| {
        let (u, e) = (u_held[i], y[i] - u_held[i]);
        u * u + 2.0 * u * e * m1 + e * e * m2
    });
    let hz = body.rotor_inertia * w_max * (0..4).map(|i| spin[i] * ym[i]).sum::<f64>();
    let jw = [inertia[0] * wm[0], inertia[1] * wm[1], inertia[2] * wm[2] + hz];
    let gyro = [wm[1] * jw[2] - wm[2] * jw[1], wm[2] * jw[0] - wm[0] * jw[2], wm[0] * jw[1] - wm[1] * jw[0]];
    let x = [
        (0..4).map(|i| positions[i][1] * ym2[i]).sum::<f64>(),
        -(0..4).map(|i| positions[i][0] * ym2[i]).sum::<f64>(),
        -(0..4).map(|i| spin[i] * ym2[i]).sum::<f64>(),
    ];
    // Moments of the rotor drag forces −k ω_i (local airspeed), per unit
    // coefficient: r_i × (−ū_i [k_d v_x, k_d v_y, k_z v_z]).
    let mut moment = [0.0; 3];
    for i in 0..4 {
        let v = local(i, &wm);
        let r = positions[i];
        moment[0] -= ym[i] * r[1] * v[2];
        moment[1] += ym[i] * r[0] * v[2];
        moment[2] -= ym[i] * (r[0] * v[1] - r[1] * v[0]);
    }
    for a in 0..3 {
        let alpha = (w1[a] - w0[a]) / dt;
        acc.ang[a].push(&[x[a], moment[a]], alpha + gyro[a] / inertia[a]);
    }
}

const N_PARAMS: usize = 10;
const PARAM_NAMES: [(&str, &str); N_PARAMS] = [
    ("tau", "s"),
    ("thrust_per_mass_full_command", "m/s^2 per rotor"),
    ("axial_drag_per_mass", "1/s per unit command sum"),
    ("rotor_drag_per_mass", "1/s per unit command sum"),
    ("roll_moment_over_inertia", "1/(m s^2)"),
    ("pitch_moment_over_inertia", "1/(m s^2)"),
    ("yaw_moment_over_inertia", "1/s^2"),
    ("roll_drag_moment_over_inertia", "1/(m s)"),
    ("pitch_drag_moment_over_inertia", "1/(m s)"),
    ("yaw_drag_moment_over_inertia", "1/(m s)"),
];
const N_DERIVED: usize = 7;
const DERIVED_NAMES: [(&str, &str, &str); N_DERIVED] = [
    ("inertia_ratio_x_over_y", "-", "log"),
    ("thrust_coefficient", "N s^2/rad^2", "log + mass"),
    ("inertia_x", "kg m^2", "log + mass"),
    ("inertia_y", "kg m^2", "log + mass"),
    ("moment_coefficient", "N m s^2/rad^2", "log + base J_z"),
    ("rotor_drag_xy", "N s^2/(m rad)", "log + mass"),
    ("rotor_drag_z", "N s^2/(m rad)", "log + mass"),
];

/// The base vehicle's values of the mass-free parameters (NaN where the
/// model has no such term), for the comparison column.
fn base_parameter_values(b: &RigidBodyParams, w_max: f64, tau: f64) -> [f64; N_PARAMS] {
    let w2 = w_max * w_max;
    [
        tau,
        b.thrust_coefficient * w2 / b.mass,
        b.rotor_drag_z * w_max / b.mass,
        b.rotor_drag_xy * w_max / b.mass,
        b.thrust_coefficient * w2 / b.inertia[0][0],
        b.thrust_coefficient * w2 / b.inertia[1][1],
        b.moment_coefficient * w2 / b.inertia[2][2],
        b.rotor_drag_z * w_max / b.inertia[0][0],
        b.rotor_drag_z * w_max / b.inertia[1][1],
        b.rotor_drag_xy * w_max / b.inertia[2][2],
    ]
}

fn estimate(
    name: &'static str,
    unit: &'static str,
    value: f64,
    reps: &[f64],
    basis: &'static str,
    base: f64,
) -> Estimate {
    Estimate { name, unit, value, lo: quantile(reps, 0.025), hi: quantile(reps, 0.975), basis, base }
}

/// The τ estimate's interval widened by half a grid step each side: the
/// grid's resolution is part of its uncertainty.
fn widen_by_grid(e: &mut Estimate, step: f64) {
    e.lo -= 0.5 * step;
    e.hi += 0.5 * step;
}

struct PointFit {
    tau_index: usize,
    params: [f64; N_PARAMS],
    r2: [(&'static str, f64); 5],
}

fn total_at(per_segment: &[Sums], w: &[f64]) -> Sums {
    let mut t = Sums::default();
    for (s, &wi) in per_segment.iter().zip(w) {
        if wi != 0.0 {
            t.add_scaled(s, wi);
        }
    }
    t
}

/// The fit of every equation for segment weights `w`, τ chosen on the grid.
fn fit_all(sums: &[Vec<Sums>], w: &[f64], taus: &[f64]) -> Option<PointFit> {
    let mut best: Option<(f64, usize)> = None;
    for (ti, per_segment) in sums.iter().enumerate() {
        let t = total_at(per_segment, w);
        let (Some(z), Some(x), Some(y)) = (t.z.solve(&[0, 1]), t.ang[0].solve(&[0, 1]), t.ang[1].solve(&[0, 1])) else {
            continue;
        };
        let score = (1.0 - z.r2()) + (1.0 - x.r2()) + (1.0 - y.r2());
        if score.is_finite() && best.is_none_or(|(b, _)| score < b) {
            best = Some((score, ti));
        }
    }
    let (_, ti) = best?;
    let t = total_at(&sums[ti], w);
    let z = t.z.solve(&[0, 1])?;
    let xy = t.xy.solve(&[0])?;
    let ang: Vec<_> = (0..3).map(|a| t.ang[a].solve(&[0, 1])).collect::<Option<Vec<_>>>()?;
    let params = [
        taus[ti],
        z.beta[0],
        z.beta[1],
        xy.beta[0],
        ang[0].beta[0],
        ang[1].beta[0],
        ang[2].beta[0],
        ang[0].beta[1],
        ang[1].beta[1],
        ang[2].beta[1],
    ];
    let r2 = [
        ("f_z", z.r2()),
        ("f_xy", xy.r2()),
        ("alpha_x", ang[0].r2()),
        ("alpha_y", ang[1].r2()),
        ("alpha_z", ang[2].r2()),
    ];
    Some(PointFit { tau_index: ti, params, r2 })
}

impl Identification {
    /// A vehicle file the simulator accepts (a scenario layer: `name`,
    /// `duration` and the vehicle sections): the base vehicle (its preset
    /// named in `[vehicle]`, or its file through `extends`, given as
    /// `base_path` when it is a file) with the identified mass, inertia
    /// `J_x`, `J_y`, thrust and moment coefficients, rotor drags and motor
    /// time constant; every value's interval and the flights in the header.
    /// `J_z`, the layout, `ω_max` and the rotor inertia stay the base's.
    pub fn vehicle_toml(&self, base_path: Option<&str>) -> String {
        let v = |name: &str| self.get(name).map_or(f64::NAN, |e| e.value);
        let mut out = String::new();
        out.push_str("# Vehicle identified by `ftsmc identify` (ftsmc-ident; docs/validation.md) from:\n");
        for f in &self.flights {
            out.push_str(&format!("#   {f}\n"));
        }
        out.push_str(&format!(
            "# on the base vehicle {} (layout, max rotor speed, rotor inertia, J_z), mass {} kg from {}.\n",
            self.base.name, self.mass_kg, self.mass_source
        ));
        out.push_str(&format!(
            "# {} sample steps in {} segments; 95 % intervals: percentiles of {} bootstrap replicates over segments (seed {}).\n",
            self.rows, self.segments, self.replicates, self.seed
        ));
        out.push_str("#\n# name                            value          [2.5 %, 97.5 %]            unit   basis (base vehicle)\n");
        for e in &self.estimates {
            out.push_str(&format!(
                "# {:<31} {:<14.6e} [{:.6e}, {:.6e}] {} ; {} (base {:.6e})\n",
                e.name, e.value, e.lo, e.hi, e.unit, e.basis, e.base
            ));
        }
        out.push_str("#\n# R² of the fitted equations:");
        for (name, r2) in &self.r2 {
            out.push_str(&format!(" {name} {r2:.4}"));
        }
        out.push_str(
            "\n# Thrust maps per rotor, T = a1 u + a2 u² (u the 0–1 command; only the first is written below):\n",
        );
        for m in &self.thrust_maps {
            out.push_str(&format!(
                "#   {:<38} a1 = {:.6e} N, a2 = {:.6e} N, R² {:.4}\n",
                m.name, m.linear_n, m.quadratic_n, m.r2
            ));
        }
        if self.battery_ref_v.is_finite() {
            out.push_str(&format!(
                "#   (V_ref = {:.4} V, the mean battery voltage of the fitted samples)\n",
                self.battery_ref_v
            ));
        }
        out.push_str("# The drag moments are reported only: ftsmc makes them from its rotor drags. A negative\n# rotor drag fit is written as 0 (ftsmc's drags are non-negative).\n");
        if let Some(d) = self.get("command_delay_steps") {
            out.push_str(&format!(
                "# Command delay {} log step(s) (a property of the log's timing, not of the vehicle):\n#   validate with `ftsmc validate LOG --vehicle THIS_FILE --command-delay {}`.\n",
                d.value, d.value
            ));
        }
        if let Some(p) = base_path {
            out.push_str(&format!("extends = {}\n", toml::Value::String(p.to_string())));
        }
        out.push_str("name = \"identified\"\n");
        out.push_str(&format!(
            "description = {}\n",
            toml::Value::String(format!("{} identified from {} flight log(s)", self.base.name, self.flights.len()))
        ));
        out.push_str("duration = 10.0\n");
        let inertia = [v("inertia_x"), v("inertia_y"), self.base.body.inertia[2][2]];
        let inertia_text = format!("[{:e}, {:e}, {:e}]", inertia[0], inertia[1], inertia[2]);
        out.push_str("\n[plant]\n");
        out.push_str(&format!("mass = {:e}\n", self.mass_kg));
        out.push_str(&format!("inertia = {inertia_text}\n"));
        out.push_str(&format!("lift_coefficient = {:e}\n", v("thrust_coefficient")));
        out.push_str(&format!("yaw_drag_coefficient = {:e}\n", v("moment_coefficient")));
        out.push_str("\n[vehicle]\n");
        if base_path.is_none() {
            if let Some(p) = self.base.preset {
                out.push_str(&format!("preset = \"{}\"\n", p.name()));
            }
        }
        out.push_str("model = \"rigid-body\"\n");
        out.push_str(&format!("mass = {:e}\n", self.mass_kg));
        out.push_str(&format!("inertia = {inertia_text}\n"));
        out.push_str(&format!("thrust_coefficient = {:e}\n", v("thrust_coefficient")));
        out.push_str(&format!("moment_coefficient = {:e}\n", v("moment_coefficient")));
        out.push_str(&format!("rotor_drag_xy = {:e}\n", v("rotor_drag_xy").max(0.0)));
        out.push_str(&format!("rotor_drag_z = {:e}\n", v("rotor_drag_z").max(0.0)));
        out.push_str("\n[actuators]\n");
        out.push_str(&format!("max_rotor_speed = {:e}\n", self.base.max_rotor_speed()));
        out.push_str(&format!("min_rotor_speed = {:e}\n", self.base.actuators.min_rotor_speed));
        out.push_str(&format!("time_constant_up = {:e}\n", v("tau")));
        out.push_str(&format!("time_constant_down = {:e}\n", v("tau")));
        out
    }
}
