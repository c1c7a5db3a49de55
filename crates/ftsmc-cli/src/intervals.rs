//! Tables of intervals and paired verdicts, shared by `ftsmc montecarlo`,
//! `compare` and `reproduce`: every number that comes from random draws is
//! printed with its interval (`estimate [lo, hi]`, `∞` where the runs
//! cannot bound it), and the confidence level is stated above the table.

use ftsmc_sim::batch::verdicts::{metric_label, Intervals, Outcomes, PairVerdict};
use ftsmc_sim::registry::label;
use ftsmc_sim::stats::paired::PairedMetric;
use ftsmc_sim::stats::Interval;
use ftsmc_sim::tune::{FlightOutcome, OutcomeStats};

use crate::console::{num, Table};

/// The cells of one gain set's statistics after its `success` and RMS
/// `median` cells (each already formatted with or without its interval):
/// success, completed, crashed, median, p95, thrust and torque activity,
/// saturated fraction. The tune's table and `reproduce`'s tuned table.
pub fn stats_cells(s: &OutcomeStats, success: String, median: String) -> Vec<String> {
    vec![
        success,
        s.completed.to_string(),
        s.crashed.to_string(),
        median,
        num(s.rms_p95),
        num(s.thrust_activity),
        num(s.torque_activity),
        num(s.saturated),
    ]
}

/// The held-out flights as [`Outcomes`] (run order kept: the pairing).
pub fn outcomes(flights: &[FlightOutcome]) -> Outcomes {
    let mut o = Outcomes::default();
    for f in flights {
        o.push(f.success, f.completed, f.crashed, f.rms);
    }
    o
}

/// `label` of a registered controller, else the name as given (a file).
pub fn display_name(name: &str) -> String {
    if ftsmc_sim::registry::check_name(name).is_ok() {
        label(name).to_string()
    } else {
        name.to_string()
    }
}

/// A rate as `90.0 % [83.1, 94.2]`.
pub fn rate_cell(i: &Interval) -> String {
    let p = i.scaled(100.0);
    if p.estimate.is_nan() {
        return "—".into();
    }
    format!("{:.1} % [{:.1}, {:.1}]", p.estimate, p.lo, p.hi)
}

/// A value in metres as `0.123 [0.110, 0.135]`, `—` if absent.
pub fn metre_cell(i: Option<&Interval>) -> String {
    i.map_or_else(|| "—".into(), |i| i.display(3))
}

/// One row per contestant: runs, success (Wilson), completed, RMS position
/// error median / p95 (order statistics), mean (t).
pub fn interval_table(rows: &[(String, Intervals)]) -> Table {
    let mut t =
        Table::new(["contestant", "runs", "success", "completed", "RMS pos. err. median (m)", "p95 (m)", "mean (m)"]);
    for (name, i) in rows {
        t.row(vec![
            display_name(name),
            i.runs.to_string(),
            rate_cell(&i.success_rate),
            rate_cell(&i.completed_rate),
            metre_cell(i.rms_median.as_ref()),
            metre_cell(i.rms_p95.as_ref()),
            metre_cell(i.rms_mean.as_ref()),
        ]);
    }
    t
}

/// The effect of a paired test: `p_A − p_B` in percentage points, or the
/// median RMS difference `A − B` in metres, with its interval.
pub fn effect_cell(v: &PairVerdict) -> String {
    match v.test.metric {
        PairedMetric::Success => {
            let e = v.test.effect.scaled(100.0);
            format!("{:+.1} pp [{:+.1}, {:+.1}]", e.estimate, e.lo, e.hi)
        }
        PairedMetric::Error => {
            let e = v.test.effect;
            if e.estimate.is_nan() {
                "—".into()
            } else {
                metres_with_justified_digits(e.estimate, e.lo, e.hi)
            }
        }
    }
}

/// A signed effect in metres with its interval, to the digits the
/// interval justifies: two significant digits of its width (so `+0.0000
/// [−0.0000, −0.0000]` never appears); scientific notation below 1e-4 m;
/// an infinite bound as `−∞`/`+∞`.
pub fn metres_with_justified_digits(estimate: f64, lo: f64, hi: f64) -> String {
    let width = if lo.is_finite() && hi.is_finite() { hi - lo } else { 0.0 };
    let scale = if width > 0.0 { width } else { estimate.abs() };
    let bound = |x: f64, d: usize, sci: bool| {
        if x == f64::INFINITY {
            "+∞".to_string()
        } else if x == f64::NEG_INFINITY {
            "−∞".to_string()
        } else if sci {
            format!("{x:+.1e}")
        } else {
            format!("{x:+.d$}")
        }
    };
    if scale > 0.0 && scale < 1e-4 {
        return format!("{} m [{}, {}]", bound(estimate, 0, true), bound(lo, 0, true), bound(hi, 0, true));
    }
    let digits = if scale > 0.0 { (1.0 - ftsmc_core::math::log10(scale).floor()).clamp(1.0, 6.0) as usize } else { 4 };
    format!("{} m [{}, {}]", bound(estimate, digits, false), bound(lo, digits, false), bound(hi, digits, false))
}

/// A p-value: 3 significant digits, `below 1e-12` under it (no `<`: the cell is printed as Markdown).
pub fn p_cell(p: f64) -> String {
    if p < 1e-12 {
        "below 1e-12".into()
    } else if p < 0.001 {
        format!("{p:.1e}")
    } else {
        format!("{p:.3}")
    }
}

/// One row per pair and metric: A, B, metric, effect (A − B) with its
/// interval, p, Holm-adjusted p, verdict.
pub fn verdict_table(verdicts: &[PairVerdict]) -> Table {
    let mut t = Table::new(["A", "B", "metric", "effect A − B [interval]", "pairs", "p", "p (Holm)", "verdict"]);
    for v in verdicts {
        t.row(vec![
            display_name(&v.a),
            display_name(&v.b),
            metric_label(v.test.metric).to_string(),
            effect_cell(v),
            v.test.pairs.to_string(),
            p_cell(v.test.p),
            p_cell(v.p_holm),
            match v.verdict {
                ftsmc_sim::stats::paired::Verdict::NoDifference => "no difference shown".into(),
                ftsmc_sim::stats::paired::Verdict::ABetter => format!("{} better", display_name(&v.a)),
                ftsmc_sim::stats::paired::Verdict::BBetter => format!("{} better", display_name(&v.b)),
            },
        ]);
    }
    t
}

/// One row per pair and metric against `--min-effect`'s margins: A, B,
/// metric, effect [interval], the test's verdict, the practical verdict.
pub fn practical_table(verdicts: &[PairVerdict], m: &ftsmc_sim::batch::verdicts::MinEffect) -> Table {
    use ftsmc_sim::batch::verdicts::{practical, Practical};
    let mut t = Table::new(["A", "B", "metric", "effect A − B [interval]", "margin", "practical verdict"]);
    for v in verdicts {
        let (a, b) = (display_name(&v.a), display_name(&v.b));
        let margin = match v.test.metric {
            PairedMetric::Success => format!("±{:.1} pp", 100.0 * m.success),
            PairedMetric::Error => format!("±{} m", m.rms),
        };
        let said = match practical(v, m) {
            Practical::ABetter => format!("{a} better by more than the margin"),
            Practical::BBetter => format!("{b} better by more than the margin"),
            Practical::Equivalent => "equivalent within the margin".to_string(),
            Practical::Undecided => "not decided at this margin".to_string(),
        };
        t.row(vec![a, b, metric_label(v.test.metric).to_string(), effect_cell(v), margin, said]);
    }
    t
}

/// The pairwise verdict matrix: row A, column B, the verdict on RMS
/// position error and on success (`A` = the row is better, `B` = the
/// column, `=` no difference shown), e.g. `RMS A · succ =`.
pub fn verdict_matrix(names: &[String], verdicts: &[PairVerdict]) -> Table {
    let mut header = vec![String::from("row A vs column B")];
    header.extend(names.iter().map(|n| display_name(n)));
    let mut t = Table::new(header);
    let mark = |v: &PairVerdict, flip: bool| match (v.verdict, flip) {
        (ftsmc_sim::stats::paired::Verdict::NoDifference, _) => "=",
        (ftsmc_sim::stats::paired::Verdict::ABetter, false) | (ftsmc_sim::stats::paired::Verdict::BBetter, true) => "A",
        _ => "B",
    };
    for a in names {
        let mut row = vec![display_name(a)];
        for b in names {
            if a == b {
                row.push("·".into());
                continue;
            }
            let find = |m: PairedMetric| {
                verdicts.iter().find_map(|v| {
                    if v.test.metric != m {
                        None
                    } else if &v.a == a && &v.b == b {
                        Some(mark(v, false))
                    } else if &v.a == b && &v.b == a {
                        Some(mark(v, true))
                    } else {
                        None
                    }
                })
            };
            row.push(format!(
                "RMS {} · succ {}",
                find(PairedMetric::Error).unwrap_or("?"),
                find(PairedMetric::Success).unwrap_or("?")
            ));
        }
        t.row(row);
    }
    t
}

/// A confidence level as a percentage with no more digits than it needs
/// (0.95 → "95", 0.995 → "99.5", 0.999 → "99.9").
pub fn level_percent(confidence: f64) -> String {
    let s = format!("{:.4}", 100.0 * confidence);
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The sentence above every table of intervals.
pub fn level_note(confidence: f64) -> String {
    format!(
        "{} % intervals: rates Wilson score; median and p95 distribution-free order statistics (∞: too few runs \
         to bound); mean Student t (docs/statistics.md).",
        level_percent(confidence)
    )
}

#[cfg(test)]
mod digits_tests {
    use super::metres_with_justified_digits as f;

    #[test]
    fn an_effect_gets_the_digits_its_interval_justifies() {
        assert_eq!(f(-0.0123, -0.0150, -0.0100), "-0.0123 m [-0.0150, -0.0100]");
        assert_eq!(f(-0.2, -0.31, -0.12), "-0.20 m [-0.31, -0.12]");
        // Never "−0.0000 [−0.0000, −0.0000]" for a tiny but real effect.
        assert_eq!(f(-1.8e-11, -2.0e-11, -1.6e-11), "-1.8e-11 m [-2.0e-11, -1.6e-11]");
        assert_eq!(f(0.01, f64::NEG_INFINITY, f64::INFINITY), "+0.010 m [−∞, +∞]");
    }
}
