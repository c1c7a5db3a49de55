//! The paper's nine figures (and a few companions) from recorded runs.

use std::path::{Path, PathBuf};

use anyhow::Result;
use ftsmc_sim::registry::label;
use ftsmc_sim::run::{Divergence, ExitStatus, RunOutput};

use ftsmc_sim::batch::montecarlo::McRun;
use ftsmc_sim::Scenario;

use crate::plot::{
    controller_color, write_3d, write_boxplots, write_figure, BoxGroup, BoxPanel, Figure, Panel, Rgb, Series, Series3,
};

/// What a panel shows: recorded column, shared reference column, per-controller
/// reference column, title and y label.
struct PanelSpec<'a> {
    column: &'a str,
    shared_reference: Option<&'a str>,
    own_reference: Option<&'a str>,
    title: &'a str,
    y_label: &'a str,
}

fn series(run: &RunOutput, column: &str, label: String, dashed: bool) -> Series {
    Series {
        points: false,
        label,
        xs: run.recording.column("t").to_vec(),
        ys: run.recording.column(column).to_vec(),
        color: controller_color(&run.controller),
        dashed,
        end: if dashed { None } else { end_note(&run.exit) },
    }
}

/// The note at the end of a run that stopped early: "diverged (tilt) at
/// 1.22 s", "crashed at 0.87 s", "interrupted at 3.00 s"; `None` for a
/// completed run.
pub fn end_note(exit: &ExitStatus) -> Option<String> {
    match exit {
        ExitStatus::Completed => None,
        ExitStatus::Diverged { divergence, time } => {
            let why = match divergence {
                Divergence::NonFinite => "non-finite state",
                Divergence::Tilt { .. } => "tilt",
                Divergence::PositionError { .. } => "position error",
                Divergence::NonFiniteMetric => "metric overflow",
                Divergence::Estimator { .. } => "estimator lost",
                Divergence::RigidBodyOutOfRange { .. } => {
                    return Some(format!("stopped (rigid body out of range) at {time:.2} s"))
                }
            };
            Some(format!("diverged ({why}) at {time:.2} s"))
        }
        ExitStatus::Crashed { time, .. } => Some(format!("crashed at {time:.2} s")),
        ExitStatus::Grounded { since, .. } => Some(format!("landed at {since:.2} s")),
        ExitStatus::Interrupted { time } => Some(format!("interrupted at {time:.2} s")),
    }
}

/// The run with the longest recording (the first of the longest): the one
/// to take a shared reference or plant signal from, so that a run that
/// stopped early does not cut the reference line of every other run.
fn longest<'a>(runs: &[&'a RunOutput]) -> Option<&'a RunOutput> {
    runs.iter()
        .copied()
        .reduce(|a, b| if b.recording.column("t").len() > a.recording.column("t").len() { b } else { a })
}

/// How a run ended, for a panel title: [`end_note`] for a run that stopped
/// early; for a completed one whether it stayed inside the scenario's
/// envelope ("completed, inside the envelope", "completed, left the
/// envelope"), or just "completed" when the scenario has none.
pub fn outcome_note(exit: &ExitStatus, envelope: Option<&ftsmc_sim::envelope::Verdict>) -> String {
    if let Some(note) = end_note(exit) {
        return note;
    }
    match envelope {
        Some(v) if v.success => "completed, inside the envelope".into(),
        Some(_) => "completed, left the envelope".into(),
        None => "completed".into(),
    }
}

fn comparison(title: &str, runs: &[&RunOutput], specs: &[PanelSpec], columns: usize) -> Figure {
    let panels = specs
        .iter()
        .map(|spec| {
            let mut s: Vec<Series> = Vec::new();
            if let (Some(col), Some(first)) = (spec.shared_reference, longest(runs)) {
                s.push(Series {
                    points: false,
                    label: "reference".into(),
                    xs: first.recording.column("t").to_vec(),
                    ys: first.recording.column(col).to_vec(),
                    color: controller_color("reference"),
                    dashed: true,
                    end: None,
                });
            }
            for run in runs {
                s.push(series(run, spec.column, label(&run.controller).to_string(), false));
                if let Some(col) = spec.own_reference {
                    s.push(series(run, col, format!("{} reference", label(&run.controller)), true));
                }
            }
            Panel {
                title: spec.title.into(),
                x_label: "time (s)".into(),
                y_label: spec.y_label.into(),
                series: s,
                log_x: false,
                log_y: false,
            }
        })
        .collect();
    Figure { title: title.into(), panels, columns }
}

/// One panel per spec with the tracking error `column − reference` of each
/// run (m or rad): the differences the position panels draw on top of each
/// other, at a scale where they can be read.
fn error_panels(runs: &[&RunOutput], specs: &[PanelSpec]) -> Vec<Panel> {
    specs
        .iter()
        .filter_map(|spec| {
            let reference = spec.shared_reference.or(spec.own_reference)?;
            let series = runs
                .iter()
                .map(|run| {
                    let mut s = series(run, spec.column, label(&run.controller).to_string(), false);
                    s.ys = s.ys.iter().zip(run.recording.column(reference)).map(|(y, r)| y - r).collect();
                    s
                })
                .collect();
            let unit = spec.y_label.rsplit_once('(').map_or("", |(_, u)| u.trim_end_matches(')'));
            Some(Panel {
                title: format!("{} error", spec.title),
                x_label: "time (s)".into(),
                y_label: format!("{} − {}ref ({unit})", spec.title, spec.title),
                series,
                log_x: false,
                log_y: false,
            })
        })
        .collect()
}

/// Seconds shown by the zoomed row of figures whose action is in the first
/// seconds of a long run (fig. 1 and 4).
pub const FIRST_SECONDS: f64 = 3.0;

/// `panels` again over `0 ≤ t ≤ seconds` only (the same data, cut): a row
/// that shows the transient a full-length axis squeezes into a few pixels.
fn first_seconds(panels: &[Panel], seconds: f64) -> Vec<Panel> {
    panels
        .iter()
        .map(|p| Panel {
            title: format!("{}, first {seconds} s", p.title),
            x_label: p.x_label.clone(),
            y_label: p.y_label.clone(),
            series: p
                .series
                .iter()
                .map(|s| {
                    let keep = s.xs.iter().take_while(|&&x| x.is_nan() || x <= seconds).count();
                    Series {
                        points: s.points,
                        label: s.label.clone(),
                        xs: s.xs[..keep].to_vec(),
                        ys: s.ys[..keep.min(s.ys.len())].to_vec(),
                        color: s.color,
                        dashed: s.dashed,
                        // A run that stops after the window does not stop in it.
                        end: s.end.clone().filter(|_| keep == s.xs.len()),
                    }
                })
                .collect(),
            log_x: p.log_x,
            log_y: p.log_y,
        })
        .collect()
}

/// The horizontal path y against x of each run, over the reference path
/// (dashed): the view of a flight a plan of the ground gives.
fn path_figure(title: &str, runs: &[&RunOutput]) -> Figure {
    let mut s: Vec<Series> = Vec::new();
    if let Some(first) = longest(runs) {
        let (xs, ys) = (first.recording.column("x_ref"), first.recording.column("y_ref"));
        // A step reference holds a few set-points: drawn as a dashed line
        // it is a point or a jump that draws (next to) nothing, so its
        // distinct set-points are drawn as points instead.
        let mut setpoints: Vec<(f64, f64)> = Vec::new();
        for (&x, &y) in xs.iter().zip(ys) {
            if x.is_finite() && y.is_finite() && setpoints.last() != Some(&(x, y)) && !setpoints.contains(&(x, y)) {
                setpoints.push((x, y));
                if setpoints.len() > 40 {
                    break;
                }
            }
        }
        if setpoints.len() <= 40 {
            s.push(Series {
                points: true,
                label: "reference set-points".into(),
                xs: setpoints.iter().map(|p| p.0).collect(),
                ys: setpoints.iter().map(|p| p.1).collect(),
                color: controller_color("reference"),
                dashed: false,
                end: None,
            });
        } else {
            s.push(Series {
                points: false,
                label: "reference".into(),
                xs: xs.to_vec(),
                ys: ys.to_vec(),
                color: controller_color("reference"),
                dashed: true,
                end: None,
            });
        }
    }
    for run in runs {
        let mut one = series(run, "y", label(&run.controller).to_string(), false);
        one.xs = run.recording.column("x").to_vec();
        s.push(one);
    }
    Figure {
        title: title.into(),
        panels: vec![Panel {
            title: "path seen from above".into(),
            x_label: "x (m)".into(),
            y_label: "y (m)".into(),
            series: s,
            log_x: false,
            log_y: false,
        }],
        columns: 1,
    }
}

fn attitude_specs<'a>() -> [PanelSpec<'a>; 3] {
    [
        PanelSpec {
            column: "phi",
            shared_reference: None,
            own_reference: Some("phi_ref"),
            title: "roll φ",
            y_label: "φ (rad)",
        },
        PanelSpec {
            column: "theta",
            shared_reference: None,
            own_reference: Some("theta_ref"),
            title: "pitch θ",
            y_label: "θ (rad)",
        },
        PanelSpec {
            column: "psi",
            shared_reference: Some("psi_ref"),
            own_reference: None,
            title: "yaw ψ",
            y_label: "ψ (rad)",
        },
    ]
}

fn position_specs<'a>() -> [PanelSpec<'a>; 3] {
    [
        PanelSpec { column: "x", shared_reference: Some("x_ref"), own_reference: None, title: "x", y_label: "x (m)" },
        PanelSpec { column: "y", shared_reference: Some("y_ref"), own_reference: None, title: "y", y_label: "y (m)" },
        PanelSpec { column: "z", shared_reference: Some("z_ref"), own_reference: None, title: "z", y_label: "z (m)" },
    ]
}

fn control_specs<'a>() -> [PanelSpec<'a>; 4] {
    [
        PanelSpec {
            column: "thrust",
            shared_reference: None,
            own_reference: None,
            title: "thrust U1",
            y_label: "U1 (N)",
        },
        PanelSpec {
            column: "roll_torque",
            shared_reference: None,
            own_reference: None,
            title: "roll torque u2",
            y_label: "u2 (N·m)",
        },
        PanelSpec {
            column: "pitch_torque",
            shared_reference: None,
            own_reference: None,
            title: "pitch torque u3",
            y_label: "u3 (N·m)",
        },
        PanelSpec {
            column: "yaw_torque",
            shared_reference: None,
            own_reference: None,
            title: "yaw torque u4",
            y_label: "u4 (N·m)",
        },
    ]
}

/// Adaptive states of one controller: one panel per channel; each estimate
/// is `(legend label, CSV column prefix, colour, units on position
/// channels, units on attitude channels)`; the column of an axis is
/// `<prefix>_<axis>`.
type Estimate<'a> = (&'a str, &'a str, crate::plot::Rgb, &'a str, &'a str);

fn adaptive_figure(title: &str, run: &RunOutput, estimates: &[Estimate], y_name: &str) -> Figure {
    let mut panels = Vec::new();
    for (axis, name) in [("x", "x"), ("y", "y"), ("z", "z"), ("phi", "φ"), ("theta", "θ"), ("psi", "ψ")] {
        let attitude = matches!(axis, "phi" | "theta" | "psi");
        let mut s = Vec::new();
        for &(label, column, color, pos_unit, att_unit) in estimates {
            // With several estimates the units go in the legend, one entry per estimate.
            let label = match (estimates.len(), pos_unit == att_unit) {
                (1, _) => label.to_string(),
                (_, true) => format!("{label} ({pos_unit})"),
                _ => format!("{label} ({pos_unit}; {att_unit} on φ, θ, ψ)"),
            };
            let mut one = series(run, &format!("{column}_{axis}"), label, false);
            one.color = color;
            s.push(one);
        }
        let y_label = match estimates {
            [(_, _, _, pos_unit, att_unit)] => format!("{y_name} ({})", if attitude { att_unit } else { pos_unit }),
            _ => y_name.to_string(),
        };
        panels.push(Panel {
            title: format!("{name} channel"),
            x_label: "time (s)".into(),
            y_label,
            series: s,
            log_x: false,
            log_y: false,
        });
    }
    Figure { title: title.into(), panels, columns: 3 }
}

/// Figures 1–4 (scenario 1): attitude, controls, adaptive gains, position.
pub fn scenario_1(runs: &[&RunOutput], dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut fig1 = comparison("Fig. 1 — attitude tracking (scenario 1)", runs, &attitude_specs(), 3);
    let zoom = first_seconds(&fig1.panels, FIRST_SECONDS);
    fig1.panels.extend(zoom);
    out.extend(write_figure(&fig1, &dir.join("fig1-attitude-scenario1"))?);
    out.extend(write_figure(
        &comparison("Fig. 2 — thrust and torques (scenario 1)", runs, &control_specs(), 2),
        &dir.join("fig2-controls-scenario1"),
    )?);
    for run in runs {
        match run.controller.as_str() {
            "ftaftsmc" => out.extend(write_figure(
                // δ̂ estimates δ = Λ², the square of the disturbance bound (an acceleration).
                &adaptive_figure(
                    "Fig. 3 — FTAFTSMC adaptive gains δ̂ (Eq. 17), scenario 1",
                    run,
                    &[("δ̂", "delta_hat", controller_color("ftaftsmc"), "m²/s⁴", "rad²/s⁴")],
                    "δ̂",
                ),
                &dir.join("fig3-adaptive-gains-scenario1"),
            )?),
            "ranftsmc" => out.extend(write_figure(
                &adaptive_figure(
                    "RANFTSMC adaptive gains â0, â1, â2 (scenario 1)",
                    run,
                    // v = … − (â0 + â1|e| + â2|ė| + h) sign(σ): every term is an acceleration.
                    &[
                        ("â0", "a_hat0", controller_color("ranftsmc"), "m/s²", "rad/s²"),
                        ("â1", "a_hat1", Rgb(148, 103, 189), "1/s²", "1/s²"),
                        ("â2", "a_hat2", Rgb(70, 70, 70), "1/s", "1/s"),
                    ],
                    "â0, â1, â2",
                ),
                &dir.join("fig3b-ranftsmc-gains-scenario1"),
            )?),
            _ => {}
        }
    }
    let mut fig4 = comparison("Fig. 4 — position tracking (scenario 1)", runs, &position_specs(), 3);
    let zoom = first_seconds(&fig4.panels, FIRST_SECONDS);
    fig4.panels.extend(zoom);
    fig4.panels.extend(error_panels(runs, &position_specs()));
    out.extend(write_figure(&fig4, &dir.join("fig4-position-scenario1"))?);
    Ok(out)
}

/// Figures 5–9 (scenario 2): inertia, position, mass estimate, attitude, 3-D.
pub fn scenario_2(runs: &[&RunOutput], no_mass: Option<&RunOutput>, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let Some(first) = longest(runs) else { return Ok(out) };
    let inertia_panels = (1..=3)
        .map(|i| Panel {
            title: format!("I{i}(t)"),
            x_label: "time (s)".into(),
            y_label: format!("I{i} (kg·m²)"),
            series: vec![Series {
                points: false,
                label: "plant (true value)".into(),
                xs: first.recording.column("t").to_vec(),
                ys: first.recording.column(&format!("inertia_{i}")).to_vec(),
                color: controller_color("reference"),
                dashed: false,
                end: None,
            }],
            log_x: false,
            log_y: false,
        })
        .collect();
    out.extend(write_figure(
        &Figure { title: "Fig. 5 — moments of inertia (scenario 2)".into(), panels: inertia_panels, columns: 3 },
        &dir.join("fig5-inertia-scenario2"),
    )?);
    // The error row shows what the reference, under the FTAFTSMC line, hides.
    let mut fig6 = comparison("Fig. 6 — position tracking (scenario 2)", runs, &position_specs(), 3);
    fig6.panels.extend(error_panels(runs, &position_specs()));
    out.extend(write_figure(&fig6, &dir.join("fig6-position-scenario2"))?);
    let mut mass = vec![Series {
        points: false,
        label: "true mass".into(),
        xs: first.recording.column("t").to_vec(),
        ys: first.recording.column("mass_true").to_vec(),
        color: controller_color("reference"),
        dashed: true,
        end: None,
    }];
    for run in runs.iter().copied().filter(|r| r.controller == "ftaftsmc").chain(no_mass) {
        mass.push(series(run, "mass_estimate", format!("α̂·m, {}", label(&run.controller)), false));
    }
    out.extend(write_figure(
        &Figure {
            title: "Fig. 7 — mass estimate α̂·m against the true mass (scenario 2)".into(),
            panels: vec![Panel {
                title: "mass".into(),
                x_label: "time (s)".into(),
                y_label: "mass (kg)".into(),
                series: mass,
                log_x: false,
                log_y: false,
            }],
            columns: 1,
        },
        &dir.join("fig7-mass-estimate-scenario2"),
    )?);
    out.extend(write_figure(
        &comparison("Fig. 8 — attitude tracking (scenario 2)", runs, &attitude_specs(), 3),
        &dir.join("fig8-attitude-scenario2"),
    )?);
    let points = |run: &RunOutput, cols: [&str; 3]| -> Vec<[f64; 3]> {
        let [a, b, c] = cols.map(|n| run.recording.column(n));
        (0..a.len()).map(|i| [a[i], b[i], c[i]]).collect()
    };
    let mut s3 = vec![Series3 {
        label: "reference".into(),
        points: points(first, ["x_ref", "y_ref", "z_ref"]),
        color: controller_color("reference"),
        dashed: true,
    }];
    for run in runs {
        s3.push(Series3 {
            label: label(&run.controller).into(),
            points: points(run, ["x", "y", "z"]),
            color: controller_color(&run.controller),
            dashed: false,
        });
    }
    out.extend(write_3d("Fig. 9 — 3-D trajectory (scenario 2)", &s3, &dir.join("fig9-trajectory-3d-scenario2"))?);
    Ok(out)
}

/// Position, attitude and control figures for any scenario (`ftsmc run`).
pub fn generic(runs: &[&RunOutput], dir: &Path) -> Result<Vec<PathBuf>> {
    let Some(first) = runs.first() else { return Ok(Vec::new()) };
    let name = &first.scenario;
    let mut out = Vec::new();
    out.extend(write_figure(
        &comparison(&format!("position tracking ({name})"), runs, &position_specs(), 3),
        &dir.join("position"),
    )?);
    out.extend(write_figure(
        &comparison(&format!("attitude tracking ({name})"), runs, &attitude_specs(), 3),
        &dir.join("attitude"),
    )?);
    out.extend(write_figure(
        &comparison(&format!("thrust and torques ({name})"), runs, &control_specs(), 2),
        &dir.join("controls"),
    )?);
    out.extend(write_figure(&path_figure(&format!("x–y path ({name})"), runs), &dir.join("path"))?);
    Ok(out)
}

/// "Beyond the paper" figures of one realistic scenario: positions against
/// the reference (`<scenario>-position`) and the actual rotor speeds
/// ω1..ω4 of each controller, one panel per controller, with the rotor
/// limit `omega_max` dashed (`<scenario>-rotors`).
pub fn beyond(runs: &[&RunOutput], omega_max: f64, dir: &Path) -> Result<Vec<PathBuf>> {
    let Some(first) = runs.first() else { return Ok(Vec::new()) };
    let name = &first.scenario;
    let mut out = Vec::new();
    out.extend(write_figure(
        &comparison(&format!("Beyond the paper — position tracking ({name})"), runs, &position_specs(), 3),
        &dir.join(format!("{name}-position")),
    )?);
    let shades = [Rgb(31, 119, 180), Rgb(255, 127, 14), Rgb(44, 160, 44), Rgb(214, 39, 40)];
    // One row per controller: the four speeds with the limit, and beside
    // them each speed minus the mean of the four, where the four traces,
    // which overplot at the speeds' scale, come apart.
    let mut panels = Vec::new();
    for run in runs {
        let t = run.recording.column("t").to_vec();
        let omegas: Vec<&[f64]> = (1..=4).map(|i| run.recording.column(&format!("omega_{i}"))).collect();
        let mean: Vec<f64> = (0..t.len()).map(|k| omegas.iter().map(|w| w[k]).sum::<f64>() / 4.0).collect();
        // Why and when the run stopped: in the panel title, not over the data.
        let why = outcome_note(&run.exit, run.envelope.as_ref());
        let mut s: Vec<Series> = (1..=4)
            .map(|i| Series {
                points: false,
                label: format!("ω{i}"),
                xs: t.clone(),
                ys: omegas[i - 1].to_vec(),
                color: shades[i - 1],
                dashed: false,
                end: None,
            })
            .collect();
        if omega_max.is_finite() {
            let span = [t.first().copied().unwrap_or(0.0), t.last().copied().unwrap_or(0.0)];
            s.push(Series {
                points: false,
                label: "ω max".into(),
                xs: span.to_vec(),
                ys: vec![omega_max; 2],
                color: controller_color("reference"),
                dashed: true,
                end: None,
            });
        }
        panels.push(Panel {
            title: format!("{} — {why}", label(&run.controller)),
            x_label: "time (s)".into(),
            y_label: "rotor speed (rad/s)".into(),
            series: s,
            log_x: false,
            log_y: false,
        });
        let spread = (1..=4)
            .map(|i| Series {
                points: false,
                label: format!("ω{i}"),
                xs: t.clone(),
                ys: omegas[i - 1].iter().zip(&mean).map(|(w, m)| w - m).collect(),
                color: shades[i - 1],
                dashed: false,
                end: None,
            })
            .collect();
        panels.push(Panel {
            title: format!("{}: ωᵢ − mean of the four", label(&run.controller)),
            x_label: "time (s)".into(),
            y_label: "ωᵢ − mean ω (rad/s)".into(),
            series: spread,
            log_x: false,
            log_y: false,
        });
    }
    out.extend(write_figure(
        &Figure { title: format!("Beyond the paper — rotor speeds ({name})"), panels, columns: 2 },
        &dir.join(format!("{name}-rotors")),
    )?);
    Ok(out)
}

/// The Monte Carlo figure of `reproduce` (`<scenario>-montecarlo`): one box
/// per controller of the RMS position error √(rms_x² + rms_y² + rms_z²) (m)
/// of its completed runs, and how many runs completed, diverged or crashed.
pub fn montecarlo(scenario: &Scenario, rows: &[McRun], controllers: &[String], dir: &Path) -> Result<Vec<PathBuf>> {
    let groups = controllers
        .iter()
        .map(|c| {
            let mine: Vec<&McRun> = rows.iter().filter(|r| &r.controller == c).collect();
            let completed = mine.iter().filter(|r| r.exit.is_completed()).count();
            let crashed = mine.iter().filter(|r| r.exit.is_crashed()).count();
            let diverged = mine.len() - completed - crashed;
            let mut tail = format!("{completed} of {} flew", mine.len());
            if diverged > 0 {
                tail.push_str(&format!(", {diverged} div."));
            }
            if crashed > 0 {
                tail.push_str(&format!(", {crashed} crash."));
            }
            BoxGroup {
                label: format!("{} ({tail})", label(c)),
                values: mine
                    .iter()
                    .filter(|r| r.exit.is_completed())
                    .map(|r| (r.metrics.rms.x.powi(2) + r.metrics.rms.y.powi(2) + r.metrics.rms.z.powi(2)).sqrt())
                    .collect(),
                color: controller_color(c),
            }
        })
        .collect();
    let runs = rows.len() / controllers.len().max(1);
    write_boxplots(
        &format!(
            "Beyond the paper — Monte Carlo, {runs} runs of {} per controller{}",
            scenario.name,
            ftsmc_sim::scenario::ladder::rung_title(scenario).map_or_else(String::new, |w| format!(" ({w})"))
        ),
        &[BoxPanel {
            title: "completed runs: box q1–q3, whiskers p5–p95".into(),
            y_label: "RMS position error (m)".into(),
            groups,
            log_y: true,
        }],
        1,
        &dir.join(format!("{}-montecarlo", scenario.name)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use ftsmc_sim::envelope::Verdict;

    /// A run that completed but left the envelope is not shown as plainly
    /// "completed"; one that stopped early says how and when.
    #[test]
    fn a_panel_title_says_whether_a_completed_run_stayed_inside() {
        let out = Verdict { success: false, violation: Some("position error 0.41 m at 14.4 s".into()) };
        let inside = Verdict { success: true, violation: None };
        assert_eq!(outcome_note(&ExitStatus::Completed, Some(&out)), "completed, left the envelope");
        assert_eq!(outcome_note(&ExitStatus::Completed, Some(&inside)), "completed, inside the envelope");
        assert_eq!(outcome_note(&ExitStatus::Completed, None), "completed");
        let crashed = ExitStatus::Crashed { time: 11.66, impact_speed: 3.0 };
        assert_eq!(outcome_note(&crashed, Some(&out)), "crashed at 11.66 s");
    }

    /// One short flight of `controller` on paper scenario 1 (0.3 s).
    fn flight(controller: &str) -> RunOutput {
        let mut s =
            ftsmc_sim::scenario::Scenario::from_toml_str(ftsmc_sim::scenario::PAPER_SCENARIO_1, "p1.toml").unwrap();
        s.duration = 0.3;
        ftsmc_sim::registry::run(controller, &s, ftsmc_sim::run::RunOptions::default()).unwrap()
    }

    /// The reference line spans the whole flight even when the first run
    /// drawn stopped early, and the legend lists the runs in the order given.
    #[test]
    fn an_early_stop_does_not_cut_the_reference() {
        let full = flight("pid");
        let mut short = flight("se3");
        let rows = short.recording.column("t").len() / 3;
        short.recording.columns.iter_mut().for_each(|c| c.truncate(rows));
        short.exit = ExitStatus::Diverged { divergence: Divergence::Tilt { angle: 0.9 }, time: 0.1 };
        let fig = comparison("t", &[&short, &full], &position_specs(), 3);
        let reference = fig.panels[0].series.iter().find(|s| s.label == "reference").unwrap();
        assert_eq!(reference.xs.len(), full.recording.column("t").len());
        assert!(reference.xs.len() > 2 * rows);
        let labels: Vec<&str> = fig.panels[0].series.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(labels, ["reference", label("se3"), label("pid")]);
    }
}
