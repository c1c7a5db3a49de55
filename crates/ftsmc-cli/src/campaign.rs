//! What a Monte Carlo campaign writes and prints, whoever flew it
//! (`ftsmc montecarlo`, `ftsmc merge`, `ftsmc compare`, the ladder of
//! `ftsmc reproduce`): `runs.csv`, the summary tables, the `shard` record
//! and the ISE box plots.

use std::path::Path;

use anyhow::Result;
use ftsmc_sim::batch::montecarlo::{ControllerSummary, McRun};
use ftsmc_sim::batch::runs_table::runs_table;
use ftsmc_sim::batch::shard::Shard;
use ftsmc_sim::registry::label;
use serde_json::{json, Value};

use crate::console::{num, Table};
use crate::plot::{controller_color, write_boxplots, BoxGroup, BoxPanel};

/// `runs.csv` text: one row per (run, controller), in run order (the
/// columns of [`runs_table`], shared with the Python package). The integral
/// metrics of a diverged row cover `[0, duration]` (its last column) and
/// the `completed` column says whether that is the whole scenario;
/// `max_error_after_*` is empty when the run ended before
/// `steady_state_after` (`settling_time_*` is `NaN` when not settled).
pub fn runs_csv(rows: &[McRun]) -> Result<Vec<u8>> {
    let table = runs_table(rows);
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&table.names)?;
    for row in 0..table.rows {
        w.write_record(table.record(row))?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))
}

/// The printed table: statistics over the completed runs (a diverged run's
/// integrals cover a shorter span and would look better), with the count of
/// diverged runs; `— (all N diverged)` when none completed.
///
/// Two tables, each within 120 columns: success counts with the z and ψ
/// statistics, then the x and y statistics (median [p5, p95]).
pub fn mc_table(summaries: &[(String, ControllerSummary)]) -> String {
    let stat_cell = |s: &ControllerSummary, m: &str| {
        s.metrics.get(m).map_or_else(
            || match (s.diverged, s.crashed) {
                (0, 0) => "—".to_string(),
                (d, 0) => format!("— (all {d} diverged)"),
                (d, c) => format!("— (none completed: {d} diverged, {c} crashed)"),
            },
            |st| format!("{} [{}, {}]", num(st.median), num(st.p5), num(st.p95)),
        )
    };
    let mut a =
        Table::new(["controller", "diverged", "ISE z median [p5, p95]", "worst ISE z", "ISE ψ median [p5, p95]"]);
    let mut b = Table::new(["controller", "ISE x median [p5, p95]", "ISE y median [p5, p95]"]);
    for (name, s) in summaries {
        a.row(vec![
            label(name).to_string(),
            if s.crashed > 0 { format!("{} (+{} crashed)", s.diverged, s.crashed) } else { s.diverged.to_string() },
            stat_cell(s, "ise_z"),
            s.metrics.get("ise_z").map_or_else(|| stat_cell(s, "ise_z"), |st| num(st.worst)),
            stat_cell(s, "ise_psi"),
        ]);
        b.row(vec![label(name).to_string(), stat_cell(s, "ise_x"), stat_cell(s, "ise_y")]);
    }
    let mut md = String::from(
        "ISE ∫e² dt over the completed runs (m²·s; ψ rad²·s): median and the 5th and 95th percentiles of the runs (their spread, not an interval):\n\n",
    );
    md.push_str(&a.render());
    md.push('\n');
    md.push_str(&b.render());
    md
}

/// Every table of a batch, as printed and in report.md: the headline
/// (success and RMS position error with their intervals at `confidence`),
/// then the paper's ISE ([`mc_table`]).
pub fn tables(summaries: &[(String, ControllerSummary)], confidence: f64) -> String {
    let rows: Vec<(String, ftsmc_sim::batch::verdicts::Intervals)> =
        summaries.iter().map(|(n, s)| (n.clone(), s.intervals.clone())).collect();
    format!(
        "Headline: success and RMS position error √(rms_x² + rms_y² + rms_z²). {}\n\n{}\n{}",
        crate::intervals::level_note(confidence),
        crate::intervals::interval_table(&rows).render(),
        mc_table(summaries)
    )
}

/// The box plots of ISE x, y, z, ψ over the completed runs, one box per
/// controller: `completed` holds `(controller, [ISE x, y, z, ψ])` of every
/// completed row; written to `path.{svg,png}`.
pub fn write_ise_boxplots(
    what: &str,
    controllers: &[String],
    summaries: &[(String, ControllerSummary)],
    completed: &[(&str, [f64; 4])],
    path: &Path,
) -> Result<()> {
    {
        let panels: Vec<BoxPanel> = ["x", "y", "z", "psi"]
            .iter()
            .map(|axis| BoxPanel {
                title: format!("ISE {}", if *axis == "psi" { "ψ" } else { axis }),
                y_label: format!("ISE ({}), log scale", if *axis == "psi" { "rad²·s" } else { "m²·s" }),
                groups: controllers
                    .iter()
                    .map(|c| BoxGroup {
                        // Counts, not a rate: the rate's interval is in the tables.
                        label: summaries.iter().find(|(n, _)| n == c).map_or_else(
                            || label(c).to_string(),
                            |(_, s)| format!("{} ({}/{} ok)", label(c), s.intervals.successes, s.intervals.runs),
                        ),
                        values: completed
                            .iter()
                            .filter(|(name, _)| name == c)
                            .map(|(_, ise)| match *axis {
                                "x" => ise[0],
                                "y" => ise[1],
                                "z" => ise[2],
                                _ => ise[3],
                            })
                            .collect(),
                        color: controller_color(c),
                    })
                    .collect(),
                log_y: true,
            })
            .collect();
        write_boxplots(
            &format!("Monte Carlo — {what} (completed runs; boxes q1–q3, whiskers p5–p95)"),
            &panels,
            2,
            path,
        )?;
    }
    Ok(())
}

/// The `shard` object of a shard's `summary.json`: `index` K and `count` N
/// (`--shard K/N`) and the run indices it holds, `first_run` ..
/// `end_run` (end excluded).
pub fn shard_json(shard: Shard, indices: &std::ops::Range<u64>) -> Value {
    json!({"index": shard.index, "count": shard.count, "first_run": indices.start, "end_run": indices.end})
}
