//! Open-loop validation: ftsmc's rigid body, started from a logged state
//! and driven by the logged motor commands, against what the log measured.
//!
//! For every start sample `k` in flight and every horizon of `n` sample
//! steps (one step, 0.1 s, 0.5 s by default), the plant is integrated
//! from the logged state `x_k` (position, velocity, attitude, body rates)
//! with the logged commands held over each step (`ω_cmd = u ω_max` through
//! the motor lag, [`crate::vehicle`]; `substeps` RK4 steps per log step,
//! rotor speeds held over each), the motors' state at `k` being the lag
//! run over the logged commands from the start of the log. Then:
//!
//! - **specific force** `f = F_body / m` (rotor thrust and drag; what an
//!   accelerometer measures) at `x̂_{k+n}` against the accelerometer at
//!   `k+n`; baseline (constant acceleration): the accelerometer at `k`;
//! - **angular acceleration** `(ω̂_{k+n} − ω̂_{k+n−1}) / Δt` over the last
//!   step against the logged `(ω_{k+n} − ω_{k+n−1}) / Δt`; baseline: the
//!   logged one over the step before `k`.
//!
//! Per axis: `R² = 1 − SSE/SST` (SST about the measured mean) and the RMS
//! residual, for the model and for the baseline. Intervals: 2.5–97.5 %
//! percentiles of a bootstrap over segments of `segment_s` pooled over the
//! flights (stream [`BOOTSTRAP_STREAM`] of `seed`).

use ftsmc_sim::actuators::Motors;
use ftsmc_sim::vehicle::rigid_body::{RigidBody, RigidBodyInput, RigidBodyState};
use rand::Rng;

use crate::error::IdentError;
use crate::lsq::{index_below, quantile};
use crate::series::Series;
use crate::vehicle::Vehicle;

/// ChaCha stream of the validation bootstrap.
pub const BOOTSTRAP_STREAM: u64 = 0x7A11;

/// Settings of [`validate`].
#[derive(Clone, Debug, PartialEq)]
pub struct ValidateOptions {
    /// Horizons, s; each becomes `max(1, round(h / Δt))` steps, Δt the
    /// log's median step (default `[0, 0.1, 0.5]`: 0 is one step).
    pub horizons_s: Vec<f64>,
    /// RK4 steps per log step (default 4).
    pub substeps: usize,
    /// A sample counts as flight when every rotor command is at least this.
    pub min_command: f64,
    /// Bootstrap segment, s (default 2).
    pub segment_s: f64,
    /// Bootstrap replicates (default 200).
    pub bootstrap: usize,
    /// Seed of the bootstrap (default 0).
    pub seed: u64,
    /// Command delay, log steps (default 0): the logged commands act this
    /// many samples later ([`crate::identify::IdentifyOptions::max_delay_steps`]).
    pub command_delay_steps: usize,
}

impl Default for ValidateOptions {
    fn default() -> Self {
        Self {
            horizons_s: vec![0.0, 0.1, 0.5],
            substeps: 4,
            min_command: 0.05,
            segment_s: 2.0,
            bootstrap: 200,
            seed: 0,
            command_delay_steps: 0,
        }
    }
}

/// What is compared.
pub const QUANTITIES: [&str; 2] = ["specific_force", "angular_acceleration"];
/// Axis names.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// One line of the table: one flight (or `all`), horizon, quantity, axis.
#[derive(Clone, Debug, PartialEq)]
pub struct ValidationRow {
    /// The log, or "all" for the flights pooled.
    pub flight: String,
    /// Horizon, s (steps × median Δt).
    pub horizon_s: f64,
    /// Horizon, log steps.
    pub steps: usize,
    /// "specific_force" (m/s²) or "angular_acceleration" (rad/s²).
    pub quantity: &'static str,
    /// "x", "y" or "z" (body).
    pub axis: &'static str,
    /// Samples compared.
    pub n: usize,
    /// Model R².
    pub r2: f64,
    /// Its interval (pooled rows only; NaN otherwise).
    pub r2_lo: f64,
    /// Upper end.
    pub r2_hi: f64,
    /// Model RMS residual.
    pub rms: f64,
    /// Its interval.
    pub rms_lo: f64,
    /// Upper end.
    pub rms_hi: f64,
    /// Constant-acceleration baseline R².
    pub baseline_r2: f64,
    /// Baseline RMS residual.
    pub baseline_rms: f64,
}

#[derive(Clone, Copy, Default)]
struct Acc {
    n: f64,
    y: f64,
    yy: f64,
    sse: f64,
    sse_base: f64,
}

impl Acc {
    fn push(&mut self, measured: f64, predicted: f64, baseline: f64) {
        self.n += 1.0;
        self.y += measured;
        self.yy += measured * measured;
        self.sse += (measured - predicted) * (measured - predicted);
        self.sse_base += (measured - baseline) * (measured - baseline);
    }
    fn add(&mut self, o: &Acc, w: f64) {
        self.n += w * o.n;
        self.y += w * o.y;
        self.yy += w * o.yy;
        self.sse += w * o.sse;
        self.sse_base += w * o.sse_base;
    }
    fn sst(&self) -> f64 {
        self.yy - self.y * self.y / self.n
    }
    fn r2(&self) -> f64 {
        1.0 - self.sse / self.sst()
    }
    fn rms(&self) -> f64 {
        (self.sse / self.n).sqrt()
    }
    fn r2_base(&self) -> f64 {
        1.0 - self.sse_base / self.sst()
    }
    fn rms_base(&self) -> f64 {
        (self.sse_base / self.n).sqrt()
    }
}

/// The logged state at sample `k` as ftsmc's rigid-body state.
pub fn state_at(s: &Series, k: usize) -> RigidBodyState {
    let mut x = [0.0; 13];
    x[0..3].copy_from_slice(&s.position_m[k]);
    x[3..6].copy_from_slice(&s.velocity_m_s[k]);
    x[6..10].copy_from_slice(&s.attitude_wxyz[k]);
    x[10..13].copy_from_slice(&s.body_rates_rad_s[k]);
    x
}

/// Rotor speeds at every sample: the motors run over the logged commands
/// (`ω_cmd = u ω_max`) from `ω = u_0 ω_max` at the first sample,
/// `substeps` per step.
pub fn motor_speeds(s: &Series, vehicle: &Vehicle, substeps: usize) -> Vec<[f64; 4]> {
    let w_max = vehicle.max_rotor_speed();
    let mut motors = Motors::new(&vehicle.actuators, s.commands[0].map(|u| u * w_max));
    let mut out = Vec::with_capacity(s.len());
    out.push(motors.speeds());
    for k in 0..s.len() - 1 {
        let cmd = s.commands[k].map(|u| u * w_max);
        let h = (s.time_s[k + 1] - s.time_s[k]) / substeps as f64;
        for _ in 0..substeps {
            motors.advance(&cmd, h);
        }
        out.push(motors.speeds());
    }
    out
}

/// One log step from `x` with `motors` and command `u`: `substeps` RK4
/// steps, rotor speeds held over each, then the motors advanced.
pub fn step(
    body: &RigidBody,
    motors: &mut Motors,
    x: &RigidBodyState,
    u: &[f64; 4],
    w_max: f64,
    dt: f64,
    substeps: usize,
) -> RigidBodyState {
    let cmd = u.map(|c| c * w_max);
    let h = dt / substeps as f64;
    let mut x = *x;
    for _ in 0..substeps {
        let input = RigidBodyInput { rotor_speeds: motors.speeds(), ..Default::default() };
        x = body.step(&x, &input, h);
        motors.advance(&cmd, h);
    }
    x
}

/// Specific force (body frame, m/s²) of the plant at `x` with rotor speeds `w`.
pub fn specific_force(body: &RigidBody, x: &RigidBodyState, w: &[f64; 4]) -> [f64; 3] {
    let wrench = body.body_wrench(x, &RigidBodyInput { rotor_speeds: *w, ..Default::default() });
    let m = body.params().mass;
    wrench.force.map(|f| f / m)
}

/// The validation table of `logs` on `vehicle`: every flight, then the
/// flights pooled with intervals (module docs).
pub fn validate(
    logs: &[Series],
    vehicle: &Vehicle,
    options: &ValidateOptions,
) -> Result<Vec<ValidationRow>, IdentError> {
    if options.substeps == 0 || options.substeps > 1000 {
        return Err(IdentError::Option {
            option: "substeps",
            value: options.substeps.to_string(),
            expected: "1 to 1000",
        });
    }
    if options.segment_s.is_nan() || options.segment_s <= 0.0 {
        return Err(IdentError::Option {
            option: "segment_s",
            value: options.segment_s.to_string(),
            expected: "a positive duration in s",
        });
    }
    if let Some(h) = options.horizons_s.iter().find(|h| !(**h >= 0.0 && **h <= 10.0)) {
        return Err(IdentError::Option {
            option: "horizon",
            value: h.to_string(),
            expected: "a horizon from 0 to 10 s",
        });
    }
    let body = RigidBody::new(vehicle.body)
        .map_err(|e| IdentError::Vehicle { vehicle: vehicle.name.clone(), message: e.to_string() })?;
    let w_max = vehicle.max_rotor_speed();
    let mut table = Vec::new();
    // segments[h][segment] = per quantity/axis accumulators
    let mut seg_accs: Vec<Vec<[[Acc; 3]; 2]>> = vec![Vec::new(); options.horizons_s.len()];
    let mut steps_of = vec![0usize; options.horizons_s.len()];
    let mut dt_of = vec![0.0; options.horizons_s.len()];
    let delayed: Vec<Series> = logs.iter().map(|s| crate::identify::delay(s, options.command_delay_steps)).collect();
    for s in &delayed {
        if s.len() < 3 {
            return Err(IdentError::TooShort {
                what: s.source.clone(),
                found: format!("{} samples", s.len()),
                needed: "3".into(),
            });
        }
        let mut dts: Vec<f64> = s.time_s.windows(2).map(|w| w[1] - w[0]).collect();
        dts.sort_by(f64::total_cmp);
        let dt_med = dts[dts.len() / 2];
        let speeds = motor_speeds(s, vehicle, options.substeps);
        for (hi, &h) in options.horizons_s.iter().enumerate() {
            let n_steps = ((h / dt_med).round() as usize).max(1);
            steps_of[hi] = n_steps;
            dt_of[hi] = n_steps as f64 * dt_med;
            let mut flight = [[Acc::default(); 3]; 2];
            let mut bins = std::collections::BTreeMap::new();
            let first_seg = seg_accs[hi].len();
            for k in 1..s.len().saturating_sub(n_steps) {
                if !(k - 1..=k + n_steps).all(|j| s.flying(j, options.min_command)) {
                    continue;
                }
                let mut x = state_at(s, k);
                let mut motors = Motors::new(&vehicle.actuators, speeds[k]);
                let mut prev_rates = s.body_rates_rad_s[k];
                for j in k..k + n_steps {
                    prev_rates = [x[10], x[11], x[12]];
                    x = step(
                        &body,
                        &mut motors,
                        &x,
                        &s.commands[j],
                        w_max,
                        s.time_s[j + 1] - s.time_s[j],
                        options.substeps,
                    );
                }
                let end = k + n_steps;
                let f_pred = specific_force(&body, &x, &motors.speeds());
                let dt_last = s.time_s[end] - s.time_s[end - 1];
                let dt_before = s.time_s[k] - s.time_s[k - 1];
                let bin = (s.time_s[k] / options.segment_s).floor() as i64;
                let seg = *bins.entry(bin).or_insert_with(|| {
                    seg_accs[hi].push([[Acc::default(); 3]; 2]);
                    seg_accs[hi].len() - 1
                });
                debug_assert!(seg >= first_seg);
                for a in 0..3 {
                    let f_meas = s.specific_force_m_s2[end][a];
                    let f_base = s.specific_force_m_s2[k][a];
                    let al_meas = (s.body_rates_rad_s[end][a] - s.body_rates_rad_s[end - 1][a]) / dt_last;
                    let al_pred = ([x[10], x[11], x[12]][a] - prev_rates[a]) / dt_last;
                    let al_base = (s.body_rates_rad_s[k][a] - s.body_rates_rad_s[k - 1][a]) / dt_before;
                    flight[0][a].push(f_meas, f_pred[a], f_base);
                    flight[1][a].push(al_meas, al_pred, al_base);
                    seg_accs[hi][seg][0][a].push(f_meas, f_pred[a], f_base);
                    seg_accs[hi][seg][1][a].push(al_meas, al_pred, al_base);
                }
            }
            if flight[0][0].n == 0.0 {
                return Err(IdentError::TooShort {
                    what: s.source.clone(),
                    found: "no sample in flight with a full horizon".into(),
                    needed: format!("{n_steps} steps with every rotor command ≥ {}", options.min_command),
                });
            }
            for q in 0..2 {
                for a in 0..3 {
                    let acc = &flight[q][a];
                    table.push(row(&s.source, dt_of[hi], n_steps, q, a, acc, [f64::NAN; 4]));
                }
            }
        }
    }
    // Pooled, with bootstrap intervals over segments.
    let mut rng = ftsmc_sim::rng::chacha_stream(options.seed, BOOTSTRAP_STREAM);
    for hi in 0..options.horizons_s.len() {
        let segs = &seg_accs[hi];
        let mut total = [[Acc::default(); 3]; 2];
        for sg in segs {
            for q in 0..2 {
                for a in 0..3 {
                    total[q][a].add(&sg[q][a], 1.0);
                }
            }
        }
        let mut reps: Vec<[[(f64, f64); 3]; 2]> = Vec::new();
        for _ in 0..options.bootstrap {
            let mut w = vec![0.0; segs.len()];
            for _ in 0..segs.len() {
                w[index_below(rng.next_u64(), segs.len())] += 1.0;
            }
            let mut t = [[Acc::default(); 3]; 2];
            for (sg, &wi) in segs.iter().zip(&w) {
                for q in 0..2 {
                    for a in 0..3 {
                        t[q][a].add(&sg[q][a], wi);
                    }
                }
            }
            reps.push(core::array::from_fn(|q| core::array::from_fn(|a| (t[q][a].r2(), t[q][a].rms()))));
        }
        for q in 0..2 {
            for a in 0..3 {
                let r2s: Vec<f64> = reps.iter().map(|r| r[q][a].0).collect();
                let rmss: Vec<f64> = reps.iter().map(|r| r[q][a].1).collect();
                let ci = [quantile(&r2s, 0.025), quantile(&r2s, 0.975), quantile(&rmss, 0.025), quantile(&rmss, 0.975)];
                table.push(row("all", dt_of[hi], steps_of[hi], q, a, &total[q][a], ci));
            }
        }
    }
    Ok(table)
}

fn row(flight: &str, horizon_s: f64, steps: usize, q: usize, a: usize, acc: &Acc, ci: [f64; 4]) -> ValidationRow {
    ValidationRow {
        flight: flight.to_string(),
        horizon_s,
        steps,
        quantity: QUANTITIES[q],
        axis: AXES[a],
        n: acc.n as usize,
        r2: acc.r2(),
        r2_lo: ci[0],
        r2_hi: ci[1],
        rms: acc.rms(),
        rms_lo: ci[2],
        rms_hi: ci[3],
        baseline_r2: acc.r2_base(),
        baseline_rms: acc.rms_base(),
    }
}
