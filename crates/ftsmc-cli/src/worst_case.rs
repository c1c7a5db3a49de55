//! `reproduce`'s worst-case table (`--worst-case-budget N`): on two rungs
//! of the wind ladder, every controller with its default gains and with
//! its committed tuned gains (`scenarios/tuned/`) is falsified
//! (`ftsmc_sim::falsify::search::cmaes` over the rung's `[falsify]` box,
//! N flights) and gets its failure probability under the rung's own draws
//! (`ftsmc_sim::falsify::rare::cross_entropy`, N flights; plain Monte
//! Carlo when failure is not rare), at equal budgets. Writes `beyond/worst-case.md`, `beyond/worst-case.json`, each
//! worst case as a replayable `beyond/worst-case/<rung>-<controller>-<gains>.toml`
//! and, with figures, `figures/beyond/<rung>-worst-gust.{svg,png}`: the
//! gust of each controller's worst case against time (default and tuned
//! gains in two panels). docs/falsification.md explains the method.

use std::fmt::Write as _;

use anyhow::{anyhow, Context, Result};
use ftsmc_sim::falsify::rare::{cross_entropy, Estimate};
use ftsmc_sim::falsify::search::cmaes;
use ftsmc_sim::falsify::{Objective, Problem, RareProblem};
use ftsmc_sim::scenario::Scenario;
use serde_json::{json, Map, Value};

use crate::console::{num, Table};
use crate::output::ResultDir;
use crate::plot::{controller_color, write_figure, Figure, Panel, Series};

/// The two rungs: a breeze and a light wind, one per paper scenario.
pub const RUNGS: [&str; 2] = ["realistic-breeze-1", "realistic-light-2"];

/// Seed of every search and proposal (the turbulence seed is each rung's own, held fixed).
pub const SEARCH_SEED: u64 = 1;

/// One cell of the table.
struct Cell {
    rung: String,
    controller: String,
    gains: &'static str,
    nominal_margin: f64,
    lowest: f64,
    first_violation: Option<u64>,
    violations: usize,
    estimate: Estimate,
    worst: Scenario,
}

/// The scenario a cell flies: the rung with default gains, or its tuned file.
fn scenario(rung: &str, controller: &str, tuned: bool) -> Result<Scenario> {
    let mut s = if tuned {
        let (_, _, text) = crate::tuned::TUNED_FILES
            .iter()
            .find(|(s, c, _)| *s == rung && *c == controller)
            .with_context(|| format!("no tuned file for {controller} on {rung}"))?;
        Scenario::from_toml_str(text, &format!("scenarios/tuned/{rung}-{controller}.toml"))?
    } else {
        let (file, text) = ftsmc_sim::scenario::resolve::built_in(rung).with_context(|| format!("no rung {rung}"))?;
        Scenario::from_toml_str(text, file)?
    };
    s.controllers = vec![controller.to_string()];
    Ok(s)
}

fn cell(rung: &str, controller: &str, tuned: bool, budget: u64, confidence: f64) -> Result<Cell> {
    let base = scenario(rung, controller, tuned)?;
    let problem = Problem::new(&base, controller)?;
    let nominal_margin = problem.margins(&[problem.nominal_point()])[0];
    let search = cmaes(&problem, budget, SEARCH_SEED, Some(problem.nominal_point()));
    let best = search.best().context("no flight of the search has a margin")?;
    let mut worst = problem.scenario(&problem.values(&best.point));
    let gains = if tuned { "tuned" } else { "default" };
    worst.name = format!("{rung}-{controller}-{gains}-worst");
    let rare = RareProblem { problem: problem.clone(), master: base.seed };
    let estimate = cross_entropy(&rare, budget, SEARCH_SEED, confidence);
    Ok(Cell {
        rung: rung.to_string(),
        controller: controller.to_string(),
        gains,
        nominal_margin,
        lowest: best.margin,
        first_violation: search.first_violation().map(|e| e.flight),
        violations: search.violations(),
        estimate,
        worst,
    })
}

/// Fly the table with `budget` flights per search and per estimate, write
/// it under `beyond/`, and return its Markdown; `None` when `budget` is 0.
pub fn write(
    dir: &ResultDir,
    budget: u64,
    controllers: &[&str],
    confidence: f64,
    figures: bool,
) -> Result<Option<String>> {
    if budget == 0 {
        return Ok(None);
    }
    let total = RUNGS.len() * controllers.len() * 2;
    eprintln!("beyond the paper: worst cases, {total} searches and failure probabilities of {budget} flights each …");
    let mut cells = Vec::new();
    for rung in RUNGS {
        for controller in controllers {
            for tuned in [false, true] {
                cells.push(cell(rung, controller, tuned, budget, confidence)?);
            }
        }
    }
    let level = crate::intervals::level_percent(confidence);
    let p_header = format!("P(fail) [{level} % interval]");
    let mut table = Table::new([
        "rung",
        "controller",
        "gains",
        "nominal margin",
        "lowest margin found",
        "first violation (flight)",
        "violating flights",
        p_header.as_str(),
        "estimator",
        "ESS",
    ]);
    let mut json_cells = Vec::new();
    for c in &cells {
        let e = &c.estimate;
        table.row(vec![
            c.rung.clone(),
            ftsmc_sim::registry::label(&c.controller).to_string(),
            c.gains.to_string(),
            num(c.nominal_margin),
            num(c.lowest),
            c.first_violation.map_or_else(|| "none".into(), |f| f.to_string()),
            format!("{}/{budget}", c.violations),
            if e.one_sided {
                format!("0 [0, {}] one-sided", prob(e.hi))
            } else {
                format!("{} [{}, {}]", prob(e.p), prob(e.lo), prob(e.hi))
            },
            if e.levels.is_empty() { "plain (not rare)".into() } else { format!("CE, {} levels", e.levels.len()) },
            if e.reliable { format!("{:.0}", e.ess) } else { format!("{:.0} (unreliable)", e.ess) },
        ]);
        let file = format!("beyond/worst-case/{}-{}-{}.toml", c.rung, c.controller, c.gains);
        dir.write_scenario(&file, &c.worst, &file)?;
        let mut m = Map::new();
        m.insert("rung".into(), json!(c.rung));
        m.insert("controller".into(), json!(c.controller));
        m.insert("gains".into(), json!(c.gains));
        m.insert("nominal_margin".into(), json!(c.nominal_margin));
        m.insert("lowest_margin".into(), json!(c.lowest));
        m.insert("first_violation_flight".into(), json!(c.first_violation));
        m.insert("violating_flights".into(), json!(c.violations));
        m.insert("worst_case_file".into(), json!(file));
        m.insert(
            "failure_probability".into(),
            json!({"p": e.p, "lo": e.lo, "hi": e.hi, "confidence": e.confidence, "flights": e.flights,
                   "levels": e.levels.len(), "effective_sample_size": e.ess, "failures": e.failures,
                   "one_sided": e.one_sided, "reliable": e.reliable}),
        );
        json_cells.push(Value::Object(m));
    }
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n### Worst cases and failure probabilities ({budget} flights per search and per estimate)\n\n\
         Each controller with its default gains and its committed tuned gains, on two rungs: CMA-ES with restarts \
         minimises the robustness margin (the envelope's slack over its limit, min(ρ_p / E, ρ_θ / Θ); negative: the flight leaves its envelope; docs/outputs.md) over the rung's `[falsify]` \
         box (mean wind, one 1−cosine gust), starting from the nominal point, with the rung's turbulence seed held \
         fixed; P(fail), the probability that the margin is negative under the rung's own draws (its Monte Carlo \
         draws of mass, inertia, drag and turbulence, the box's values at their nominal distributions), is \
         estimated by cross-entropy importance sampling (CE; plain Monte Carlo when a tenth of the first level's \
         nominal draws already fail), with its {level} % interval and the effective sample size (ESS) of its \
         failing draws: with an ESS of a few the interval rests on a few weights and is not to be trusted \
         (docs/falsification.md). A search that \
         finds no violation proves nothing. Each worst case is a file under `beyond/worst-case/`: `ftsmc run` of it \
         gives the margin shown.\n\n{}",
        table.render()
    );
    dir.write("beyond/worst-case.md", md.as_bytes())?;
    let record = json!({"budget": budget, "search_seed": SEARCH_SEED, "confidence": confidence, "cells": json_cells});
    dir.write("beyond/worst-case.json", serde_json::to_string_pretty(&record)?.as_bytes())?;
    if figures {
        for rung in RUNGS {
            let of: Vec<&Cell> = cells.iter().filter(|c| c.rung == rung).collect();
            worst_gust_figure(rung, &of, &dir.path().join("figures").join("beyond"))?;
        }
    }
    Ok(Some(md))
}

/// The gust of each cell's worst case, |Σ gusts(t)| in the horizontal
/// plane against time, one panel for the default gains and one for the
/// tuned; each legend entry gives the margin and the mean wind found with it.
fn worst_gust_figure(rung: &str, cells: &[&Cell], folder: &std::path::Path) -> Result<()> {
    let mut panels = Vec::new();
    for gains in ["default", "tuned"] {
        let mut series = Vec::new();
        for c in cells.iter().filter(|c| c.gains == gains) {
            let wind = c.worst.wind.clone().unwrap_or_default().resolved();
            let mean = (wind.mean[0] * wind.mean[0] + wind.mean[1] * wind.mean[1]).sqrt();
            let n = 1001;
            let xs: Vec<f64> = (0..n).map(|k| c.worst.duration * k as f64 / (n - 1) as f64).collect();
            let ys = xs
                .iter()
                .map(|&t| {
                    let w = wind.deterministic(t);
                    let (gx, gy) = (w[0] - wind.mean[0], w[1] - wind.mean[1]);
                    (gx * gx + gy * gy).sqrt()
                })
                .collect();
            series.push(Series {
                label: format!(
                    "{}, {gains} gains (margin {}, mean wind {mean:.1} m/s)",
                    ftsmc_sim::registry::label(&c.controller),
                    num(c.lowest)
                ),
                xs,
                ys,
                color: controller_color(&c.controller),
                dashed: false,
                end: None,
                points: false,
            });
        }
        panels.push(Panel {
            title: format!("{gains} gains: gust speed of the worst case found"),
            x_label: "t (s)".into(),
            y_label: "m/s".into(),
            series,
            log_x: false,
            log_y: false,
        });
    }
    std::fs::create_dir_all(folder).map_err(|e| anyhow!("cannot create {}: {e}", folder.display()))?;
    write_figure(
        &Figure { title: format!("Worst gust found per controller: {rung}"), panels, columns: 1 },
        &folder.join(format!("{rung}-worst-gust.svg")),
    )?;
    Ok(())
}

/// A probability for the table: `0` and `1` as such, otherwise three
/// significant digits in scientific form (`4.42e-4`), never `0.00e0`.
fn prob(p: f64) -> String {
    if p == 0.0 {
        "0".into()
    } else if p == 1.0 {
        "1".into()
    } else {
        format!("{p:.2e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ftsmc_sim::falsify::margin_of;

    /// Probabilities print as `0`, `1` or three significant digits.
    #[test]
    fn probabilities_print_without_a_zero_mantissa() {
        assert_eq!(prob(0.0), "0");
        assert_eq!(prob(1.0), "1");
        assert_eq!(prob(4.4213e-4), "4.42e-4");
        assert_eq!(prob(9.992e-1), "9.99e-1");
    }

    /// A cell's worst case, written as its file and read back, flies to the
    /// margin the table prints, bit for bit; the tuned cell flies the
    /// tuned file's gains (the default cell's differ).
    #[test]
    fn a_cell_replays_to_its_margin_and_tuned_cells_fly_the_tuned_gains() {
        let c = cell("realistic-breeze-1", "pid", true, 20, 0.95).unwrap();
        assert_eq!(c.gains, "tuned");
        let text = crate::output::scenario_toml(&c.worst).unwrap();
        let replay = Scenario::from_toml_str(&text, "worst.toml").unwrap();
        let out = ftsmc_sim::registry::run("pid", &replay, ftsmc_sim::RunOptions::default()).unwrap();
        assert_eq!(margin_of(&out).to_bits(), c.lowest.to_bits());
        assert!(c.lowest <= c.nominal_margin, "the search starts at the nominal point");
        let (p, lo, hi) = (c.estimate.p, c.estimate.lo, c.estimate.hi);
        assert!(lo <= p && p <= hi && (0.0..=1.0).contains(&p), "[{lo}, {hi}] ∌ {p}");
        let default = scenario("realistic-breeze-1", "pid", false).unwrap();
        let tuned = scenario("realistic-breeze-1", "pid", true).unwrap();
        assert_ne!(format!("{:?}", default.gains), format!("{:?}", tuned.gains));
        assert_eq!(format!("{:?}", tuned.gains), format!("{:?}", replay.gains));
    }
}
