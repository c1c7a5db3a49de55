//! Flying a list of planned flights in parallel under one progress bar,
//! each run's CSV written while it flies, and the per-run metrics tables:
//! what `ftsmc run` and `ftsmc reproduce` share.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{anyhow, Result};
use ftsmc_sim::registry::{self, label};
use ftsmc_sim::run::{planned_steps, reference_at, stream_csv, RunOptions, RunOutput, STREAM_CHUNK_ROWS};
use ftsmc_sim::scenario::Scenario;
use rayon::prelude::*;

use crate::console::{num, steps_bar, Table};
use crate::output::ResultDir;

/// One planned flight: which scenario (possibly modified), which controller,
/// and the key it is stored under.
pub struct Job {
    /// Scenario to fly.
    pub scenario: Scenario,
    /// Registry name.
    pub controller: String,
    /// Output key (controller name or a variant name).
    pub key: String,
}

/// Fly all jobs in parallel (deterministic: each job is independent). The
/// progress bar counts simulated control steps, updated from inside each
/// flight. (The commands fly with [`fly_into`], which writes the CSVs too.)
#[cfg(test)]
pub fn fly(jobs: &[Job]) -> Result<Vec<RunOutput>> {
    fly_each(jobs, |job, progress| {
        let options = RunOptions { progress: Some(progress), ..Default::default() };
        registry::run_as(&job.controller, &job.key, &job.scenario, options)
            .map_err(|known| anyhow!("unknown controller `{}` (known: {known})", job.controller))
    })
}

/// `fly_one(job, progress)` for every job in parallel, in the jobs' order,
/// under one progress bar of the jobs' planned control steps (`progress`
/// adds steps to it; hand it to the flight's [`RunOptions::progress`]).
pub fn fly_each(
    jobs: &[Job],
    fly_one: impl Fn(&Job, &(dyn Fn(u64) + Sync)) -> Result<RunOutput> + Sync,
) -> Result<Vec<RunOutput>> {
    let total = jobs.iter().map(|j| planned_steps(&j.scenario)).sum();
    let bar = steps_bar(total, jobs.len() as u64);
    let progress = |n: u64| bar.inc(n);
    let out = jobs.par_iter().map(|job| fly_one(job, &progress)).collect();
    bar.finish_and_clear();
    out
}

/// [`fly`], each run's recording written as CSV into `dir` at `csv(job)`
/// while it flies ([`stream_csv`]: another thread formats, hashes and
/// writes the rows as they are recorded), the bytes those of
/// [`Recording::write_csv`]. A failed write is an error; the file is then
/// removed (and the uncommitted `dir` goes with its staging folder).
pub fn fly_into(jobs: &[Job], dir: &ResultDir, csv: impl Fn(&Job) -> PathBuf + Sync) -> Result<Vec<RunOutput>> {
    fly_each(jobs, |job, progress| {
        let mut flown = None;
        let written = dir.write_with(csv(job), |w| {
            let (run, written) = stream_csv(w, STREAM_CHUNK_ROWS, |stream| {
                let options = RunOptions { progress: Some(progress), stream: Some(stream), ..Default::default() };
                registry::run_as(&job.controller, &job.key, &job.scenario, options)
            });
            flown = Some(run);
            written
        });
        match flown {
            Some(Err(known)) => Err(anyhow!("unknown controller `{}` (known: {known})", job.controller)),
            Some(Ok(run)) => written.map(|()| run),
            None => Err(written.err().unwrap_or_else(|| anyhow!("internal: {} was not flown", job.key))),
        }
    })
}

/// The cell shown instead of a metric of a run that did not complete: its
/// integrals cover a shorter span, so a number would look better than a
/// completed run's.
pub fn not_comparable(run: &RunOutput) -> String {
    format!("— ({})", run.exit.short())
}

pub fn find<'a>(runs: &'a [RunOutput], scenario: &str, key: &str) -> Option<&'a RunOutput> {
    runs.iter().find(|r| r.scenario == scenario && r.controller == key)
}

pub fn axis_value(m: &ftsmc_sim::axes::AxisSet<f64>, axis: &str) -> f64 {
    m.get(axis).copied().unwrap_or(f64::NAN)
}

pub fn settle(m: &ftsmc_sim::axes::AxisSet<Option<f64>>, axis: &str) -> String {
    // (For a completed run; a diverged one shows `—`.)
    m.get(axis).copied().flatten().map_or("not settled".into(), |t| format!("{t:.2}"))
}

/// `|e(0)|` of x, y, z, ψ in `scenario` (the metrics' initial errors).
pub fn initial_errors(scenario: &Scenario) -> [f64; 4] {
    let x = scenario.initial_state.state().to_array();
    let r = reference_at(scenario, 0.0);
    [(x[0] - r.position[0]).abs(), (x[1] - r.position[1]).abs(), (x[2] - r.position[2]).abs(), (x[5] - r.yaw).abs()]
}

/// The flights of one metrics table: each run with the scenario it flew.
pub type Flown<'a> = (&'a RunOutput, &'a Scenario);

/// The per-run metrics as four tables narrow enough for a 120-column
/// console: ISE (with the scenario's window), IAE and the error after
/// `steady_state_after`, settling times, and exit status with chattering.
/// A diverged run shows `—` beside its exit status (its integrals cover a
/// shorter span and would look better than a completed run's; the numbers
/// stay in the JSON, with `covered` and `completed`). A settling time shows
/// `—` for a channel that starts within the settling floor (nothing to
/// settle from).
pub fn metrics_table(runs: &[Flown], title: &str) -> String {
    let Some((_, first)) = runs.first() else { return format!("### {title}\n\n(no runs)\n") };
    let sim = &first.simulation;
    let window = sim.metrics_window;
    let mut md = String::new();
    let _ = writeln!(md, "### {title}\n");
    let dash = || "—".to_string();
    let completed = |r: &RunOutput| r.exit.is_completed();

    let mut header = vec!["controller".to_string()];
    header.extend(["x", "y", "z", "ψ"].map(|a| format!("ISE {a}")));
    if let Some([a, b]) = window {
        header.push(format!("ISE z {a}–{b} s"));
    }
    let mut ise = Table::new(header);
    let mut iae = Table::new([
        "controller",
        "IAE x",
        "IAE y",
        "IAE z",
        "IAE ψ",
        &format!("max err z after {} s", sim.steady_state_after),
    ]);
    let mut settling = Table::new(["controller", "settle x (s)", "settle y (s)", "settle z (s)", "settle ψ (s)"]);
    let mut control = Table::new(["controller", "exit", "chattering U1 (N/s)", "chattering u2 (N·m/s)"]);
    // Realistic flights: the envelope's verdict and what was asked of the rotors.
    let mut actuators = Table::new(["controller", "success", "peak ω demand (rad/s)", "saturated", "why not"]);
    let mut realistic = false;
    let mut notes = Vec::new();
    let mut on_reference = false;
    for (run, scenario) in runs {
        let m = &run.metrics;
        let name = label(&run.controller).to_string();
        let ok = completed(run);
        let v = |x: f64| if ok { num(x) } else { dash() };
        let mut row = vec![name.clone(), v(m.ise.x), v(m.ise.y), v(m.ise.z), v(m.ise.psi)];
        if window.is_some() {
            row.push(if ok { m.ise_window.as_ref().map_or_else(dash, |w| num(w.z)) } else { dash() });
        }
        ise.row(row);
        iae.row(vec![
            name.clone(),
            v(m.iae.x),
            v(m.iae.y),
            v(m.iae.z),
            v(m.iae.psi),
            if ok { m.max_error_after.z.map_or_else(dash, num) } else { dash() },
        ]);
        let e0 = initial_errors(scenario);
        let floor = scenario.simulation.settling_floor;
        let mut row = vec![name.clone()];
        for (i, axis) in ["x", "y", "z", "psi"].into_iter().enumerate() {
            row.push(if !ok {
                dash()
            } else if e0[i] <= floor {
                on_reference = true;
                dash()
            } else {
                settle(&m.settling_time, axis)
            });
        }
        settling.row(row);
        control.row(vec![name.clone(), run.exit.short(), v(m.chattering.thrust), v(m.chattering.roll_torque)]);
        if run.envelope.is_some() || m.peak_rotor_speed_demand.is_some() {
            realistic = true;
        }
        let why = match run.envelope.as_ref().and_then(|e| e.violation.clone()) {
            _ if !ok => run.exit.short(),
            Some(violation) => {
                notes.push(format!("- {name}: left the envelope: {violation}."));
                "envelope (below)".to_string()
            }
            None => dash(),
        };
        actuators.row(vec![
            name.clone(),
            if run.success() { "yes" } else { "no" }.to_string(),
            m.peak_rotor_speed_demand.map_or_else(dash, |w| format!("{w:.0}")),
            m.saturation_fraction.map_or_else(dash, |f| format!("{:.1} %", 100.0 * f)),
            if run.success() { dash() } else { why },
        ]);
        if !ok {
            notes.push(format!("- {name}: {}; metrics `—` (shorter span).", run.exit));
        }
    }
    let units = "m²·s; ψ rad²·s";
    let _ = writeln!(md, "ISE ∫e² dt ({units}):\n\n{}", ise.render());
    let _ = writeln!(
        md,
        "IAE ∫|e| dt (m·s; ψ rad·s) and max |e_z| (m) after {} s:\n\n{}",
        sim.steady_state_after,
        iae.render()
    );
    let _ = writeln!(
        md,
        "Settling: |e| within {} % of |e(0)| (at least {}) from then on{}:\n\n{}",
        100.0 * sim.settling_band,
        sim.settling_floor,
        if on_reference { "; — where the channel starts within that floor (nothing to settle)" } else { "" },
        settling.render()
    );
    let _ = write!(md, "Exit status and chattering (total variation Σ|Δu| per second):\n\n{}", control.render());
    if realistic {
        let _ = write!(
            md,
            "\nSuccess (completed and inside `[envelope]`) and rotors (peak demand before the limits; periods the mixer saturated):\n\n{}",
            actuators.render()
        );
    }
    if !notes.is_empty() {
        md.push('\n');
        for n in notes {
            md.push_str(&n);
            md.push('\n');
        }
    }
    md
}
