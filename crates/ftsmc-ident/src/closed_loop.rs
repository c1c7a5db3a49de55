//! Closed-loop validation: the log's reference flown in ftsmc by the log's
//! controller, and the simulated tracking error set beside the real one.
//!
//! For each flight:
//!
//! 1. **Span.** Takeoff is the first sample with every rotor command at
//!    least `min_command`, landing the last. The simulation starts at
//!    takeoff from the logged state there (position, velocity, attitude,
//!    gyro), the rotors at rest, every controller state reset (as the
//!    firmware resets its PIDs while the motors are off), and runs to
//!    landing. Until the rotors lift it, the vehicle rests where it was
//!    logged (a ground contact: below the logged takeoff height the state
//!    is held at the logged pose with no velocity).
//! 2. **Loop.** The controller ([`LogController`]: the Crazyflie firmware's
//!    PID cascade or Mellinger controller, `ftsmc_core::crazyflie_pid`,
//!    `ftsmc_core::mellinger`, with the firmware's default gains) runs at the
//!    firmware's 500 Hz on the simulated state, with the logged set-point held
//!    from its latest sample (Mellinger: velocity and acceleration
//!    feed-forward from central differences of the held set-point, which a
//!    log of positions does not carry). Its uncapped motor commands pass
//!    through the firmware's battery compensation with the logged voltage
//!    low-passed as the firmware does (`b = 0.01` per 1 kHz tick) when the
//!    log has the voltage and `battery_compensation` is on, then the cap;
//!    `ω_cmd = (m/65535) ω_max` drives ftsmc's motors (lag) and rigid body
//!    (RK4, `substeps` per control period) — the map under which
//!    [`crate::validate`] flies the logged commands.
//! 3. **Error.** Over the tracking window — from the first to the last
//!    sample between takeoff and landing whose set-point height is at
//!    least 90 % of the flight's highest (the climb and the descent left
//!    out) — the RMS of `‖p − p_sp‖` for the logged position (real) and the
//!    simulated one at the control tick nearest each log sample (sim).
//!
//! Over flights ([`table`]), per trajectory and speed (the file name
//! without its `_repN`) and all together: mean real RMS, mean simulated
//! RMS, and the paired difference (sim − real) with its 95 % Student t
//! interval over the flights (`ftsmc_sim::stats::mean`; infinite with one
//! flight).

use ftsmc_core::crazyflie_pid::{
    battery_compensated, power_cap, CrazyfliePid, CrazyfliePidGains, FirmwareState, ATTITUDE_RATE_HZ, PWM_MAX,
};
use ftsmc_core::mellinger::{Mellinger, MellingerGains};
use ftsmc_core::model::{QuadrotorParams, Reference};
use ftsmc_sim::actuators::Motors;
use ftsmc_sim::vehicle::rigid_body::{RigidBody, RigidBodyInput, RigidBodyState};

use crate::error::IdentError;
use crate::series::{MotorOrder, Series};
use crate::validate::{specific_force, state_at};
use crate::vehicle::Vehicle;

/// The controller a log was flown with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogController {
    /// The Crazyflie firmware's PID cascade (`crazyflie-pid`).
    CrazyfliePid,
    /// The Crazyflie firmware's Mellinger controller (`mellinger`).
    Mellinger,
}

impl LogController {
    /// The registry names (`ftsmc list`), in this order.
    pub const NAMES: [&'static str; 2] = ["crazyflie-pid", "mellinger"];

    /// By registry name.
    pub fn from_name(name: &str) -> Result<Self, IdentError> {
        match name {
            "crazyflie-pid" => Ok(Self::CrazyfliePid),
            "mellinger" => Ok(Self::Mellinger),
            _ => Err(IdentError::Option {
                option: "controller",
                value: name.to_string(),
                expected: "crazyflie-pid or mellinger (the controllers closed-loop validation flies)",
            }),
        }
    }

    /// The registry name.
    pub fn name(self) -> &'static str {
        match self {
            Self::CrazyfliePid => Self::NAMES[0],
            Self::Mellinger => Self::NAMES[1],
        }
    }
}

/// Settings of [`fly_log`].
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedLoopOptions {
    /// The log's controller (default the firmware's PID cascade, the
    /// Crazyflie's default controller).
    pub controller: LogController,
    /// RK4 steps per control period (default 1: 2 ms).
    pub substeps: usize,
    /// A sample counts as flight when every rotor command is at least this
    /// (default 0.05).
    pub min_command: f64,
    /// Apply the firmware's battery compensation with the logged voltage
    /// (default true; no effect on a log without voltage).
    pub battery_compensation: bool,
}

impl Default for ClosedLoopOptions {
    fn default() -> Self {
        Self { controller: LogController::CrazyfliePid, substeps: 1, min_command: 0.05, battery_compensation: true }
    }
}

/// One flight flown in ftsmc beside the log.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedLoopFlight {
    /// The log.
    pub source: String,
    /// Trajectory and speed: the file name without directory, extension and `_repN`.
    pub group: String,
    /// Time of each log sample of the tracking window, s since the log's start.
    pub time_s: Vec<f64>,
    /// The set-point at those samples, m.
    pub setpoint_m: Vec<[f64; 3]>,
    /// The logged position, m.
    pub real_m: Vec<[f64; 3]>,
    /// The simulated position, m.
    pub sim_m: Vec<[f64; 3]>,
    /// The logged rotor commands (0–1, ftsmc's rotor order) over the window.
    pub real_commands: Vec<[f64; 4]>,
    /// The simulated rotor commands (after compensation and cap, 0–1).
    pub sim_commands: Vec<[f64; 4]>,
    /// RMS of `‖p − p_sp‖` of the log over the window, m.
    pub real_rms_m: f64,
    /// The same of the simulation, m.
    pub sim_rms_m: f64,
    /// The simulation left the arena (non-finite state or more than 100 m
    /// from the set-point) at this time, s; `None` when it flew the span.
    pub diverged_at_s: Option<f64>,
}

/// The simulated flight at every control tick, for [`fly`]'s callers.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Tick times, s (the log's clock).
    pub time_s: Vec<f64>,
    /// Rigid-body state at each tick.
    pub state: Vec<RigidBodyState>,
    /// Rotor commands 0–1 (ftsmc's rotor order) applied from each tick.
    pub commands: Vec<[f64; 4]>,
    /// Specific force (body, m/s²) at each tick.
    pub specific_force: Vec<[f64; 3]>,
    /// Set to the time of divergence when the flight left the arena.
    pub diverged_at_s: Option<f64>,
}

/// The Crazyflie's controllers behind one interface.
enum Flown {
    Pid(Box<CrazyfliePid>),
    Mellinger(Box<Mellinger>),
}

impl Flown {
    fn step(&mut self, s: &FirmwareState, r: &Reference, dt: f64) -> [f64; 4] {
        match self {
            Flown::Pid(c) => {
                c.step(s, r, dt);
                c.uncapped()
            }
            Flown::Mellinger(c) => {
                c.step(s, r, dt);
                c.uncapped()
            }
        }
    }
    fn idle(&self) -> f64 {
        match self {
            Flown::Pid(c) => c.gains().motors.idle_thrust,
            Flown::Mellinger(c) => c.gains().motors.idle_thrust,
        }
    }
}

/// The controller's nominal model from the vehicle (mass, inertia, thrust
/// and moment coefficients, arm length).
fn nominal(vehicle: &Vehicle) -> QuadrotorParams {
    let b = vehicle.body;
    QuadrotorParams {
        mass: b.mass,
        gravity: b.gravity,
        inertia: [b.inertia[0][0], b.inertia[1][1], b.inertia[2][2]],
        lift_coefficient: b.thrust_coefficient,
        yaw_drag_coefficient: b.moment_coefficient,
        arm_length: b.arm_length,
        ..QuadrotorParams::default()
    }
}

fn controller(vehicle: &Vehicle, which: LogController) -> Result<Flown, IdentError> {
    let err = |e: ftsmc_core::GainError| IdentError::Vehicle { vehicle: vehicle.name.clone(), message: e.to_string() };
    let model = nominal(vehicle);
    Ok(match which {
        LogController::CrazyfliePid => {
            let mut g = CrazyfliePidGains::default();
            g.motors.max_rotor_speed = vehicle.max_rotor_speed();
            Flown::Pid(Box::new(CrazyfliePid::new(model, g).map_err(err)?))
        }
        LogController::Mellinger => {
            let mut g = MellingerGains::default();
            g.motors.max_rotor_speed = vehicle.max_rotor_speed();
            Flown::Mellinger(Box::new(Mellinger::new(model, g).map_err(err)?))
        }
    })
}

/// What the closed loop is flown against: set-point samples on a clock,
/// with the battery voltage when known.
#[derive(Clone, Debug, PartialEq)]
pub struct SetpointTrack<'a> {
    /// Sample times, s, strictly increasing.
    pub time_s: &'a [f64],
    /// Position set-point, m (world).
    pub position_m: &'a [[f64; 3]],
    /// Yaw set-point, rad.
    pub yaw_rad: &'a [f64],
    /// Battery voltage, V, when logged.
    pub battery_v: Option<&'a [f64]>,
}

impl SetpointTrack<'_> {
    /// Index of the latest sample at or before `t` (the first if none).
    fn index_at(&self, t: f64) -> usize {
        self.time_s.partition_point(|&x| x <= t).saturating_sub(1)
    }

    /// The held set-point at `t`, with velocity and acceleration from
    /// central differences of the samples around it (zero at the ends).
    fn reference_at(&self, t: f64, feed_forward: bool) -> Reference {
        let k = self.index_at(t);
        let mut r = Reference { position: self.position_m[k], yaw: self.yaw_rad[k], ..Reference::default() };
        let n = self.time_s.len();
        if feed_forward && k >= 1 && k + 1 < n {
            let (t0, t1, t2) = (self.time_s[k - 1], self.time_s[k], self.time_s[k + 1]);
            let (p0, p1, p2) = (self.position_m[k - 1], self.position_m[k], self.position_m[k + 1]);
            for i in 0..3 {
                let v01 = (p1[i] - p0[i]) / (t1 - t0);
                let v12 = (p2[i] - p1[i]) / (t2 - t1);
                r.velocity[i] = (p2[i] - p0[i]) / (t2 - t0);
                r.acceleration[i] = 2.0 * (v12 - v01) / (t2 - t0);
            }
        }
        r
    }
}

/// Fly `track` from `initial` (rigid-body state at `track.time_s[0]`, the
/// rotors at rest) to its last sample with `which` on `vehicle` (module
/// docs, steps 1–2); ground at the initial height.
pub fn fly(
    vehicle: &Vehicle,
    which: LogController,
    initial: &RigidBodyState,
    track: &SetpointTrack<'_>,
    options: &ClosedLoopOptions,
) -> Result<Trajectory, IdentError> {
    if options.substeps == 0 || options.substeps > 1000 {
        return Err(IdentError::Option {
            option: "substeps",
            value: options.substeps.to_string(),
            expected: "1 to 1000",
        });
    }
    let body = RigidBody::new(vehicle.body)
        .map_err(|e| IdentError::Vehicle { vehicle: vehicle.name.clone(), message: e.to_string() })?;
    let mut c = controller(vehicle, which)?;
    let w_max = vehicle.max_rotor_speed();
    let order = MotorOrder::Crazyflie.log_index();
    let h = 1.0 / ATTITUDE_RATE_HZ;
    let t0 = track.time_s[0];
    let t_end = *track.time_s.last().unwrap_or(&t0);
    let ticks = ((t_end - t0) / h).floor() as usize + 1;
    let mut motors = Motors::new(&vehicle.actuators, [0.0; 4]);
    let mut x = *initial;
    let ground = initial[2];
    // The firmware's low-passed supply voltage: b = 0.01 per 1 kHz tick,
    // two ticks per control period; it has run since boot, so it starts
    // at the first logged voltage.
    let decay = 1.0 - (1.0 - 0.01f64) * (1.0 - 0.01);
    let mut supply = track.battery_v.map(|v| v[0]);
    let mut out = Trajectory {
        time_s: Vec::with_capacity(ticks),
        state: Vec::with_capacity(ticks),
        commands: Vec::with_capacity(ticks),
        specific_force: Vec::with_capacity(ticks),
        diverged_at_s: None,
    };
    for n in 0..ticks {
        let t = t0 + n as f64 * h;
        let reference = track.reference_at(t, which == LogController::Mellinger);
        let s = FirmwareState {
            position: [x[0], x[1], x[2]],
            velocity: [x[3], x[4], x[5]],
            quaternion: [x[6], x[7], x[8], x[9]],
            body_rates: [x[10], x[11], x[12]],
        };
        let uncapped = c.step(&s, &reference, h);
        let compensated = match (options.battery_compensation, track.battery_v, supply.as_mut()) {
            (true, Some(v), Some(f)) => {
                *f += decay * (v[track.index_at(t)] - *f);
                uncapped.map(|m| battery_compensated(m, *f))
            }
            _ => uncapped,
        };
        let pwm = power_cap(compensated, c.idle());
        let u: [f64; 4] = core::array::from_fn(|i| pwm[order[i]] / PWM_MAX);
        out.time_s.push(t);
        out.state.push(x);
        out.commands.push(u);
        out.specific_force.push(specific_force(&body, &x, &motors.speeds()));
        let cmd = u.map(|c| c * w_max);
        let step = h / options.substeps as f64;
        for _ in 0..options.substeps {
            let input = RigidBodyInput { rotor_speeds: motors.speeds(), ..Default::default() };
            x = body.step(&x, &input, step);
            motors.advance(&cmd, step);
        }
        if x[2] < ground {
            // Resting on the ground at the logged pose.
            x = *initial;
            x[3..6].copy_from_slice(&[0.0; 3]);
            x[10..13].copy_from_slice(&[0.0; 3]);
        }
        let off = (0..3).map(|i| (x[i] - reference.position[i]) * (x[i] - reference.position[i])).sum::<f64>();
        if !x.iter().all(|v| v.is_finite()) || off > 1e4 {
            out.diverged_at_s = Some(t + h);
            break;
        }
    }
    Ok(out)
}

/// `stem` of a path without its `_repN` suffix (`B2_circle_fast_rep1.csv`
/// → `B2_circle_fast`).
pub fn group_of(source: &str) -> String {
    let stem = std::path::Path::new(source).file_stem().and_then(|s| s.to_str()).unwrap_or(source);
    match stem.rfind("_rep") {
        Some(i) if stem[i + 4..].chars().all(|c| c.is_ascii_digit()) && i + 4 < stem.len() => stem[..i].to_string(),
        _ => stem.to_string(),
    }
}

/// The log `s` flown in ftsmc (module docs): needs the set-point.
pub fn fly_log(s: &Series, vehicle: &Vehicle, options: &ClosedLoopOptions) -> Result<ClosedLoopFlight, IdentError> {
    let sp = s.setpoint.as_ref().ok_or_else(|| IdentError::MissingChannel {
        file: s.source.clone(),
        channel: "set-point",
        purpose: "closed-loop validation",
    })?;
    let flying: Vec<usize> = (0..s.len()).filter(|&k| s.flying(k, options.min_command)).collect();
    let (Some(&k0), Some(&k1)) = (flying.first(), flying.last()) else {
        return Err(IdentError::TooShort {
            what: s.source.clone(),
            found: "no sample in flight".into(),
            needed: format!("samples with every rotor command ≥ {}", options.min_command),
        });
    };
    let top = (k0..=k1).map(|k| sp.position_m[k][2]).fold(f64::NEG_INFINITY, f64::max);
    let high: Vec<usize> = (k0..=k1).filter(|&k| sp.position_m[k][2] >= 0.9 * top).collect();
    let (Some(&w0), Some(&w1)) = (high.first(), high.last()) else {
        return Err(IdentError::TooShort {
            what: s.source.clone(),
            found: "no set-point at 90 % of the flight's highest".into(),
            needed: "a tracking window".into(),
        });
    };
    if w1 <= w0 {
        return Err(IdentError::TooShort {
            what: s.source.clone(),
            found: "a tracking window of one sample".into(),
            needed: "two".into(),
        });
    }
    let track = SetpointTrack {
        time_s: &s.time_s[k0..=k1],
        position_m: &sp.position_m[k0..=k1],
        yaw_rad: &sp.yaw_rad[k0..=k1],
        battery_v: s.battery_v.as_ref().map(|v| &v[k0..=k1]),
    };
    let traj = fly(vehicle, options.controller, &state_at(s, k0), &track, options)?;
    let h = 1.0 / ATTITUDE_RATE_HZ;
    let mut f = ClosedLoopFlight {
        source: s.source.clone(),
        group: group_of(&s.source),
        time_s: Vec::new(),
        setpoint_m: Vec::new(),
        real_m: Vec::new(),
        sim_m: Vec::new(),
        real_commands: Vec::new(),
        sim_commands: Vec::new(),
        real_rms_m: f64::NAN,
        sim_rms_m: f64::NAN,
        diverged_at_s: traj.diverged_at_s,
    };
    let (mut se_real, mut se_sim) = (0.0, 0.0);
    for k in w0..=w1 {
        let tick = ((s.time_s[k] - s.time_s[k0]) / h).round() as usize;
        let (p_sim, u_sim) = match (traj.state.get(tick), traj.commands.get(tick)) {
            (Some(x), Some(u)) => ([x[0], x[1], x[2]], *u),
            _ => ([f64::NAN; 3], [f64::NAN; 4]),
        };
        let p_sp = sp.position_m[k];
        let p_real = s.position_m[k];
        se_real += (0..3).map(|i| (p_real[i] - p_sp[i]) * (p_real[i] - p_sp[i])).sum::<f64>();
        se_sim += (0..3).map(|i| (p_sim[i] - p_sp[i]) * (p_sim[i] - p_sp[i])).sum::<f64>();
        f.time_s.push(s.time_s[k]);
        f.setpoint_m.push(p_sp);
        f.real_m.push(p_real);
        f.sim_m.push(p_sim);
        f.real_commands.push(s.commands[k]);
        f.sim_commands.push(u_sim);
    }
    let n = (w1 - w0 + 1) as f64;
    f.real_rms_m = (se_real / n).sqrt();
    f.sim_rms_m = (se_sim / n).sqrt();
    Ok(f)
}

/// One line of the sim-to-real table.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedLoopRow {
    /// A flight's log, a trajectory-and-speed group, or `all`.
    pub flight: String,
    /// Flights in the row.
    pub flights: usize,
    /// Mean real tracking RMS, m.
    pub real_rms_m: f64,
    /// Mean simulated tracking RMS, m.
    pub sim_rms_m: f64,
    /// Mean paired difference sim − real, m.
    pub difference_m: f64,
    /// Its 95 % t interval over the flights (−∞ and ∞ with one flight).
    pub difference_lo_m: f64,
    /// Upper end.
    pub difference_hi_m: f64,
}

/// The table of `flights`: one row per flight, per group (module docs) and
/// `all`. A diverged simulation's RMS is NaN (its window was not all
/// flown), and so is every mean over it and its interval: a divergence is
/// visible, not averaged away.
pub fn table(flights: &[ClosedLoopFlight]) -> Vec<ClosedLoopRow> {
    let row = |name: &str, fs: &[&ClosedLoopFlight]| {
        let n = fs.len() as f64;
        let d: Vec<f64> = fs.iter().map(|f| f.sim_rms_m - f.real_rms_m).collect();
        let mean = |v: &mut dyn Iterator<Item = f64>| v.sum::<f64>() / n;
        let ci = if d.iter().all(|x| x.is_finite()) {
            ftsmc_sim::stats::mean::mean_interval(&d, 0.95).ok().flatten()
        } else {
            None
        };
        ClosedLoopRow {
            flight: name.to_string(),
            flights: fs.len(),
            real_rms_m: mean(&mut fs.iter().map(|f| f.real_rms_m)),
            sim_rms_m: mean(&mut fs.iter().map(|f| f.sim_rms_m)),
            difference_m: mean(&mut d.iter().copied()),
            difference_lo_m: ci.map_or(f64::NAN, |i| i.lo),
            difference_hi_m: ci.map_or(f64::NAN, |i| i.hi),
        }
    };
    let mut rows: Vec<ClosedLoopRow> = flights.iter().map(|f| row(&f.source, &[f])).collect();
    let mut groups: Vec<&str> = flights.iter().map(|f| f.group.as_str()).collect();
    groups.sort_unstable();
    groups.dedup();
    for g in groups {
        let fs: Vec<&ClosedLoopFlight> = flights.iter().filter(|f| f.group == g).collect();
        rows.push(row(g, &fs));
    }
    let all: Vec<&ClosedLoopFlight> = flights.iter().collect();
    if !all.is_empty() {
        rows.push(row("all", &all));
    }
    rows
}

/// `closed_loop.csv`: the rows of [`table`].
pub fn table_csv(rows: &[ClosedLoopRow]) -> String {
    let mut out = String::from("flight,flights,real_rms_m,sim_rms_m,difference_m,difference_lo_m,difference_hi_m\n");
    for r in rows {
        out.push_str(&format!(
            "{},{},{},{},{},{},{}\n",
            r.flight, r.flights, r.real_rms_m, r.sim_rms_m, r.difference_m, r.difference_lo_m, r.difference_hi_m
        ));
    }
    out
}

/// `closed_loop_overlay.csv`: every flight's window, one row per log
/// sample (time, set-point, real and simulated position, m; real and
/// simulated rotor commands 0–1): the overlay figure's data.
pub fn overlay_csv(flights: &[ClosedLoopFlight]) -> String {
    let mut out = String::from(
        "flight,time_s,sp_x_m,sp_y_m,sp_z_m,real_x_m,real_y_m,real_z_m,sim_x_m,sim_y_m,sim_z_m,\
         real_u1,real_u2,real_u3,real_u4,sim_u1,sim_u2,sim_u3,sim_u4\n",
    );
    for f in flights {
        for k in 0..f.time_s.len() {
            let mut cells = vec![f.source.clone(), f.time_s[k].to_string()];
            for v in f.setpoint_m[k].iter().chain(&f.real_m[k]).chain(&f.sim_m[k]) {
                cells.push(v.to_string());
            }
            for v in f.real_commands[k].iter().chain(&f.sim_commands[k]) {
                cells.push(v.to_string());
            }
            out.push_str(&cells.join(","));
            out.push('\n');
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_drop_the_repetition() {
        assert_eq!(group_of("data/nanobench/B2_circle_fast_rep1.csv"), "B2_circle_fast");
        assert_eq!(group_of("B9_trefoil_slow_rep12.csv"), "B9_trefoil_slow");
        assert_eq!(group_of("flight.csv"), "flight");
        assert_eq!(group_of("x_rep.csv"), "x_rep");
    }
}
