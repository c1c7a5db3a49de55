//! `ftsmc fixed-time`: measure reaching and settling times against the
//! initial error, for every controller and channel, beside the paper's bound.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;
use ftsmc_core::cascade::channel::NAMES;
use ftsmc_sim::analysis::fixed_time;
use ftsmc_sim::analysis::fixed_time::{
    cascade_channel, worst, ChannelTimes, Sampling, SweepSettings, CASCADE_CHANNELS,
};
use ftsmc_sim::registry::label;
use ftsmc_sim::scenario::Scenario;
use rayon::prelude::*;
use serde_json::json;

use crate::args::{load_scenario_with_limits, ControllersArgs, LimitArgs, SetArgs};
use crate::console::Table;
use crate::output::{format_number, provenance, ResultDir};
use crate::plot::{controller_color, write_figure, Figure, Panel, Series};

/// Arguments of `ftsmc fixed-time`.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario whose gains are used (file or built-in name).
    #[arg(long, default_value = "paper-scenario-1")]
    scenario: String,
    /// `--set`.
    #[command(flatten)]
    set: SetArgs,
    /// `--limit`.
    #[command(flatten)]
    limits: LimitArgs,
    /// `-c` (the controllers to sweep).
    #[command(flatten)]
    controllers: ControllersArgs,
    /// Log-spaced magnitudes per decade.
    #[arg(long, allow_negative_numbers = true, default_value_t = 3)]
    per_decade: usize,
    /// Parent folder: the results go to `OUT/<scenario name>/`.
    #[arg(long, default_value = "results/fixed-time")]
    out: PathBuf,
}

/// Runs `ftsmc fixed-time`: checks the sweep's cost before any flight, then sweeps.
pub fn run(args: Args) -> Result<()> {
    let mut scenario = load_scenario_with_limits(&args.scenario, &args.limits.limit, &args.set.set)?;
    let controllers = args.controllers.or_scenario(&scenario)?;
    scenario.controllers = controllers.clone();
    let per_decade = args.per_decade;
    anyhow::ensure!(per_decade >= 1, "--per-decade must be at least 1");
    ftsmc_sim::limits::check_sweep(&scenario.limits, ftsmc_sim::limits::sweep_points(5, per_decade as u64))?;
    // With `max_sweep_points = inf` the check is off: refuse what
    // cannot be counted or held in memory instead of overflowing.
    let points = per_decade.checked_mul(5).and_then(|n| n.checked_add(1));
    let fits = points.is_some_and(|n| Vec::<f64>::new().try_reserve_exact(n).is_ok());
    anyhow::ensure!(fits, "--per-decade {per_decade}: 5 × {per_decade} + 1 magnitudes do not fit in memory");
    let sim = &scenario.simulation;
    let t_max = SweepSettings::default().t_max;
    scenario.limits.ensure(
        "max_steps",
        "integration steps per sweep flight (60 s × control_rate × substeps)",
        t_max * sim.control_rate * f64::from(sim.substeps),
    )?;
    let settings = SweepSettings {
        magnitudes: SweepSettings::log_magnitudes(-3, 2, per_decade),
        dt: scenario.control_period(),
        ..Default::default()
    };
    sweep(&scenario, &controllers, &settings, &args.out)
}

struct Row {
    controller: String,
    axis: usize,
    sampling: Sampling,
    times: Vec<ChannelTimes>,
}

fn opt(v: Option<f64>) -> String {
    v.map_or("—".into(), |v| format!("{v:.3}"))
}

/// Reaching time of one point, or `— (diverged at t s)`.
fn reach_cell(t: Option<&ChannelTimes>) -> String {
    match t {
        Some(ChannelTimes { diverged_at: Some(at), reaching_time: None, .. }) => format!("— (diverged at {at:.2} s)"),
        Some(t) => opt(t.reaching_time),
        None => opt(None),
    }
}

/// Run the sweep and write `fixed-time.csv`, `fixed-time.md`,
/// `fixed-time.json`, `scenario.toml` and figures to `out/<name>/`.
fn sweep(scenario: &Scenario, controllers: &[String], settings: &SweepSettings, out: &Path) -> Result<()> {
    let folder = out.join(&scenario.name);
    // Refuse a bad --out before any flight; write into a staging folder.
    let dir = ResultDir::begin(&folder, "fixed-time")?;
    let file = dir.write_scenario("scenario.toml", scenario, "scenario.toml")?;
    let mut plan = Vec::new();
    for c in controllers {
        for axis in 0..6 {
            for sampling in [Sampling::Continuous, Sampling::Sampled] {
                plan.push((c.clone(), axis, sampling));
            }
        }
    }
    let bar = points_bar(plan.len() as u64, "decoupled-channel sweep points");
    let rows: Vec<Row> = plan
        .par_iter()
        .map(|(c, axis, sampling)| {
            let times = fixed_time::sweep_channel(c, scenario, *axis, settings, *sampling).map_err(anyhow::Error::msg);
            bar.inc(1);
            times.map(|times| Row { controller: c.clone(), axis: *axis, sampling: *sampling, times })
        })
        .collect::<Result<_>>()?;
    bar.finish_and_clear();

    // CSV of every point.
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "controller",
        "channel",
        "sampling",
        "e0",
        "s0",
        "reaching_time",
        "settling_time",
        "diverged_at",
        "bound",
    ])?;
    for r in &rows {
        let bound = fixed_time::reaching_time_bound(&r.controller, scenario, r.axis);
        for t in &r.times {
            let o = |v: Option<f64>| v.map_or(String::new(), format_number);
            w.write_record([
                r.controller.clone(),
                NAMES[r.axis].to_string(),
                format!("{:?}", r.sampling).to_lowercase(),
                format_number(t.e0),
                format_number(t.s0),
                o(t.reaching_time),
                o(t.settling_time),
                o(t.diverged_at),
                o(bound),
            ])?;
        }
    }
    dir.write("fixed-time.csv", &w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))?)?;

    // Summary table.
    let mut md = String::new();
    let _ = writeln!(
        md,
        "### Fixed-time check: decoupled channel ë = v_fb (exact model cancellation), e(0) = ±{:.0e} … ±{:.0e}, ė(0) = 0\n",
        settings.magnitudes.first().copied().unwrap_or(0.0),
        settings.magnitudes.last().copied().unwrap_or(0.0)
    );
    let _ = writeln!(
        md,
        "Reaching: first |S| ≤ {}; settling: |e| ≤ {} |e0| from then on. Continuous = the closed loop the theorem \
speaks of, integrated by adaptive Dormand–Prince 5(4) (tolerances 1e-10) with the reaching instant located on its \
dense output (the run stops there, so it has no settling time); sampled = zero-order hold at {} s, {} s per flight. \
Each |e0| is flown with both signs ({} points per channel and mode).\n",
        settings.reaching_band,
        settings.settling_fraction,
        settings.dt,
        settings.t_max,
        2 * settings.magnitudes.len()
    );
    let mut continuous = Table::new([
        "controller",
        "channel",
        "bound Eq. 38 (s)",
        "worst reaching (s)",
        "within bound?",
        "reaching, min → max |e0| (s)",
    ]);
    let mut sampled = Table::new([
        "controller",
        "channel",
        "reached",
        "worst reaching (s)",
        "settled",
        "worst settling (s)",
        "first |e0| not settled",
    ]);
    let mut json_rows = Vec::new();
    for c in controllers {
        for axis in 0..6 {
            let get =
                |s: Sampling| rows.iter().find(|r| &r.controller == c && r.axis == axis && r.sampling == s).unwrap();
            let cont = get(Sampling::Continuous);
            let samp = get(Sampling::Sampled);
            let bound = fixed_time::reaching_time_bound(c, scenario, axis);
            let wc = worst(cont.times.iter().map(|t| t.reaching_time));
            // Sampled: worst over the initial errors that did not diverge.
            let ws = worst(samp.times.iter().filter(|t| t.diverged_at.is_none()).map(|t| t.reaching_time));
            let wset = worst(samp.times.iter().filter(|t| t.diverged_at.is_none()).map(|t| t.settling_time));
            let diverge_from =
                samp.times.iter().filter(|t| t.diverged_at.is_some()).map(|t| t.e0.abs()).fold(f64::INFINITY, f64::min);
            // What the sampled runs achieved: how many points reached / settled
            // (within t_max), the worst time among those, and the smallest
            // |e0| that did not settle (a sampled run that fails saturates
            // rather than diverging, so "diverged" alone says little).
            let n = samp.times.len();
            let reached: Vec<f64> = samp.times.iter().filter_map(|t| t.reaching_time).collect();
            let settled: Vec<f64> = samp.times.iter().filter_map(|t| t.settling_time).collect();
            let max = |v: &[f64]| v.iter().copied().fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x))));
            let not_settled_from = samp
                .times
                .iter()
                .filter(|t| t.settling_time.is_none())
                .map(|t| t.e0.abs())
                .fold(f64::INFINITY, f64::min);
            // A continuous flight that diverged has no reaching time; say so
            // instead of "not reached".
            let cont_diverge_from =
                cont.times.iter().filter(|t| t.diverged_at.is_some()).map(|t| t.e0.abs()).fold(f64::INFINITY, f64::min);
            let cont_diverged = cont_diverge_from.is_finite();
            let within = match (bound, wc) {
                (_, None) if cont_diverged => "**no — diverged**",
                (Some(b), Some(w)) => {
                    if w <= b {
                        "yes"
                    } else {
                        "**no — exceeds**"
                    }
                }
                (Some(_), None) => "**no — not reached**",
                (None, _) => "no bound",
            };
            continuous.row(vec![
                label(c).to_string(),
                NAMES[axis].to_string(),
                opt(bound),
                match wc {
                    Some(v) => format!("{v:.3}"),
                    None if cont_diverged => format!("— (diverged from |e0| = {cont_diverge_from:.3e})"),
                    None => "not reached".into(),
                },
                within.to_string(),
                format!(
                    "{} → {}",
                    reach_cell(cont.times.first()),
                    reach_cell(cont.times.iter().rev().find(|t| t.e0 > 0.0))
                ),
            ]);
            sampled.row(vec![
                label(c).to_string(),
                NAMES[axis].to_string(),
                format!("{}/{n}", reached.len()),
                opt(max(&reached)),
                format!("{}/{n}", settled.len()),
                opt(max(&settled)),
                if not_settled_from.is_finite() {
                    let diverged = if diverge_from <= not_settled_from { " (diverged)" } else { "" };
                    format!("{not_settled_from:.0e}{diverged}")
                } else {
                    "— (all settled)".into()
                },
            ]);
            json_rows.push(json!({
                "controller": c, "channel": NAMES[axis], "bound": bound,
                "worst_reaching_continuous": wc, "worst_reaching_sampled": ws, "worst_settling_sampled": wset,
                "sampled_diverges_from": if diverge_from.is_finite() { Some(diverge_from) } else { None },
                "sampled_points": n, "sampled_reached": reached.len(), "sampled_settled": settled.len(),
                "sampled_not_settled_from": if not_settled_from.is_finite() { Some(not_settled_from) } else { None },
            }));
        }
    }
    let _ =
        writeln!(md, "Continuous closed loop — reaching time against the paper's bound:\n\n{}", continuous.render());
    let _ = writeln!(
        md,
        "Sampled at the control rate — points that reached / settled within {} s, the worst time among them, and the \
smallest |e0| that did not settle:\n\n{}",
        settings.t_max,
        sampled.render()
    );
    let record = json!({ "channels": json_rows, "provenance": provenance(&[file]) });
    dir.write("fixed-time.json", serde_json::to_string_pretty(&record)?.as_bytes())?;

    // Figures: reaching (continuous) and settling (sampled) against |e0|.
    for (sampling, field, stem, what) in [
        (Sampling::Continuous, 0, "fixed-time-reaching", "reaching time, continuous closed loop"),
        (Sampling::Sampled, 1, "fixed-time-settling", "2 % settling time, sampled at the control rate"),
    ] {
        let panels = (0..6)
            .map(|axis| {
                let mut series = Vec::new();
                for c in controllers {
                    let r =
                        rows.iter().find(|r| &r.controller == c && r.axis == axis && r.sampling == sampling).unwrap();
                    let mut pts: Vec<(f64, f64)> = Vec::new();
                    for &m in &settings.magnitudes {
                        let times: Vec<Option<f64>> = r
                            .times
                            .iter()
                            .filter(|t| t.e0.abs() == m)
                            .map(|t| if field == 0 { t.reaching_time } else { t.settling_time })
                            .collect();
                        pts.push((m, worst(times).unwrap_or(f64::NAN)));
                    }
                    series.push(Series {
                        points: false,
                        label: label(c).into(),
                        xs: pts.iter().map(|p| p.0).collect(),
                        ys: pts.iter().map(|p| p.1).collect(),
                        color: controller_color(c),
                        dashed: false,
                        end: None,
                    });
                    if let (0, Some(b)) = (field, fixed_time::reaching_time_bound(c, scenario, axis)) {
                        series.push(Series {
                            points: false,
                            label: format!("Eq. 38 bound, {}", label(c)),
                            xs: vec![settings.magnitudes[0], *settings.magnitudes.last().unwrap()],
                            ys: vec![b, b],
                            color: controller_color(c),
                            dashed: true,
                            end: None,
                        });
                    }
                }
                Panel {
                    title: format!("{} channel", NAMES[axis]),
                    x_label: format!("|e(0)| ({})", if axis < 3 { "m" } else { "rad" }),
                    y_label: "time (s)".into(),
                    series,
                    log_x: true,
                    log_y: false,
                }
            })
            .collect();
        write_figure(
            &Figure {
                title: format!("Fixed-time check — {what} (worst of ±e0; gaps: not reached or diverged)"),
                panels,
                columns: 3,
            },
            &dir.path().join(stem),
        )?;
    }
    let cascade_md = cascade_sweep(scenario, controllers, settings, &dir)?;
    let md = format!("{md}\n{cascade_md}");
    dir.write("fixed-time.md", md.as_bytes())?;
    dir.commit()?;
    println!("{md}");
    println!(
        "wrote {}/ (fixed-time.csv, fixed-time-cascade.csv, fixed-time.md, fixed-time.json, scenario.toml, fixed-time-reaching.{{svg,png}}, fixed-time-settling.{{svg,png}}, fixed-time-cascade.{{svg,png}})",
        folder.display()
    );
    Ok(())
}

/// A progress bar over `len` independent sweep points (each short).
fn points_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{spinner}} [{{elapsed_precise}}] {{bar:30}} {{pos}}/{{len}} {what}"
        ))
        .expect("valid template"),
    );
    bar
}

/// The same sweep through the full cascade and plant for the channels that
/// need no tilt (z and ψ), 30 s per flight.
fn cascade_sweep(
    scenario: &Scenario,
    controllers: &[String],
    settings: &SweepSettings,
    dir: &ResultDir,
) -> Result<String> {
    let settings = SweepSettings { t_max: 30.0, ..settings.clone() };
    let mut plan = Vec::new();
    for c in controllers {
        for &axis in &CASCADE_CHANNELS {
            for &m in &settings.magnitudes {
                for sign in [1.0, -1.0] {
                    plan.push((c.clone(), axis, sign * m));
                }
            }
        }
    }
    let bar = points_bar(plan.len() as u64, "full-cascade flights");
    let points: Vec<(String, usize, ChannelTimes)> = plan
        .par_iter()
        .map(|(c, axis, e0)| {
            let t = cascade_channel(c, scenario, *axis, *e0, &settings).map_err(anyhow::Error::msg);
            bar.inc(1);
            t.map(|t| (c.clone(), *axis, t))
        })
        .collect::<Result<_>>()?;
    bar.finish_and_clear();

    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["controller", "channel", "e0", "reaching_time", "settling_time", "diverged_at"])?;
    let o = |v: Option<f64>| v.map_or(String::new(), format_number);
    for (c, axis, t) in &points {
        w.write_record([
            c.clone(),
            NAMES[*axis].to_string(),
            format_number(t.e0),
            o(t.reaching_time),
            o(t.settling_time),
            o(t.diverged_at),
        ])?;
    }
    dir.write("fixed-time-cascade.csv", &w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))?)?;

    let cell = |c: &str, axis: usize, m: f64| {
        let pts: Vec<&ChannelTimes> =
            points.iter().filter(|(pc, pa, t)| pc == c && *pa == axis && t.e0.abs() == m).map(|(_, _, t)| t).collect();
        let first_divergence = pts.iter().filter_map(|t| t.diverged_at).fold(f64::INFINITY, f64::min);
        if first_divergence.is_finite() {
            format!("— (diverged at {first_divergence:.2} s)")
        } else {
            worst(pts.iter().map(|t| t.settling_time)).map_or("not settled".into(), |v| format!("{v:.2}"))
        }
    };
    let shown: Vec<f64> = settings.magnitudes.iter().copied().step_by(3).collect();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "### Full cascade and plant (z and ψ need no tilt): 2 % settling time (s), worst of ±e0, {} s per flight\n",
        settings.t_max
    );
    let mut header = vec!["controller".to_string(), "channel".to_string()];
    header.extend(shown.iter().map(|m| format!("|e0| = {m:.0e}")));
    let mut table = Table::new(header);
    let mut panels = Vec::new();
    for &axis in &CASCADE_CHANNELS {
        let mut series = Vec::new();
        for c in controllers {
            let mut cells = vec![label(c).to_string(), NAMES[axis].to_string()];
            cells.extend(shown.iter().map(|&m| cell(c, axis, m)));
            table.row(cells);
            let ys: Vec<f64> =
                settings.magnitudes.iter().map(|&m| cell(c, axis, m).parse::<f64>().unwrap_or(f64::NAN)).collect();
            series.push(Series {
                points: false,
                label: label(c).into(),
                xs: settings.magnitudes.clone(),
                ys,
                color: controller_color(c),
                dashed: false,
                end: None,
            });
        }
        panels.push(Panel {
            title: format!("{} channel, full cascade", NAMES[axis]),
            x_label: format!("|e(0)| ({})", if axis < 3 { "m" } else { "rad" }),
            y_label: "2 % settling time (s)".into(),
            series,
            log_x: true,
            log_y: false,
        });
    }
    md.push_str(&table.render());
    write_figure(
        &Figure {
            title: "Fixed-time check through the full cascade (gaps: not settled or diverged)".into(),
            panels,
            columns: 2,
        },
        &dir.path().join("fixed-time-cascade"),
    )?;
    Ok(md)
}
