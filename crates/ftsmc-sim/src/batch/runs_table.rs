//! The rows of `runs.csv`: one per (run, controller) of a Monte Carlo batch,
//! as typed columns. The CLI writes them as CSV and the Python package hands
//! them to pandas, so both read the same table from one implementation.

use crate::batch::montecarlo::{McRun, SAMPLED_COLUMNS};
use crate::run::{push_number, ExitStatus};

/// One column of a [`RunsTable`].
#[derive(Clone, Debug, PartialEq)]
pub enum Column {
    /// Non-negative integers (`run`, `seed`).
    Integer(Vec<u64>),
    /// Text (`controller`, `exit`).
    Text(Vec<String>),
    /// Numbers; `None` is an empty CSV cell (`diverged_at` of a run that did
    /// not diverge, `max_error_after_*` of a run that ended before
    /// `steady_state_after`). `NaN` (a channel that never settled) is
    /// written `NaN`.
    Number(Vec<Option<f64>>),
    /// `true` / `false` (`completed`, `success`, `crashed`).
    Boolean(Vec<bool>),
}

impl Column {
    /// Cell `row` as CSV text (numbers in shortest round-trip form, see
    /// [`push_number`]).
    pub fn cell(&self, row: usize) -> String {
        match self {
            Column::Integer(v) => v[row].to_string(),
            Column::Text(v) => v[row].clone(),
            Column::Number(v) => match v[row] {
                Some(x) => {
                    let mut out = Vec::with_capacity(24);
                    push_number(&mut out, x);
                    String::from_utf8(out).unwrap_or_default()
                }
                None => String::new(),
            },
            Column::Boolean(v) => v[row].to_string(),
        }
    }
}

/// The flight-statistics columns ([`crate::run::FlightStats`]), every flight:
/// `peak_tilt` (rad), `saturated_periods`, `rotor_speed_max` and
/// `rotor_speed_mean` (rad/s).
pub const STATS_COLUMNS: [&str; 4] = ["peak_tilt", "saturated_periods", "rotor_speed_max", "rotor_speed_mean"];

/// The robustness-margin columns ([`crate::margin::Margin`]), after
/// `crashed`: `margin` (1), `margin_position` (m), `margin_tilt` (rad),
/// `ground_clearance` (m), `margin_binds` (text), `margin_at` (s); empty
/// where the flight has no margin.
pub const MARGIN_COLUMNS: [&str; 6] =
    ["margin", "margin_position", "margin_tilt", "ground_clearance", "margin_binds", "margin_at"];

/// `runs.csv` as named columns of equal length, in run order (see
/// docs/outputs.md): `run`, `seed`, `controller`, `exit`, `diverged_at`, the
/// sampled values ([`SAMPLED_COLUMNS`]), every metric of
/// [`crate::metrics::Metrics::flat`], the flight statistics ([`STATS_COLUMNS`]),
/// `completed`, `success`, `crashed`, the margin ([`MARGIN_COLUMNS`]).
/// The integral metrics of a diverged row cover `[0, duration]` (its
/// `duration`-covered span) and `completed` says whether that is the whole
/// scenario.
#[derive(Clone, Debug, PartialEq)]
pub struct RunsTable {
    /// Column names, in order.
    pub names: Vec<String>,
    /// The columns, parallel to `names`.
    pub columns: Vec<Column>,
    /// Number of rows.
    pub rows: usize,
}

impl RunsTable {
    /// Row `row` as CSV fields.
    pub fn record(&self, row: usize) -> Vec<String> {
        self.columns.iter().map(|c| c.cell(row)).collect()
    }
}

/// The table of a batch's rows (metric columns from the first row's
/// [`crate::metrics::Metrics::flat`]; none for an empty batch).
pub fn runs_table(rows: &[McRun]) -> RunsTable {
    let metric_names: Vec<String> =
        rows.first().map(|r| r.metrics.flat().into_iter().map(|(n, _)| n).collect()).unwrap_or_default();
    let mut names: Vec<String> =
        ["run", "seed", "controller", "exit", "diverged_at"].iter().map(|s| s.to_string()).collect();
    names.extend(SAMPLED_COLUMNS.iter().map(|s| s.to_string()));
    names.extend(metric_names.iter().cloned());
    names.extend(STATS_COLUMNS.map(String::from));
    names.extend(["completed", "success", "crashed"].map(String::from));
    names.extend(MARGIN_COLUMNS.map(String::from));

    let mut columns = vec![
        Column::Integer(rows.iter().map(|r| r.index).collect()),
        Column::Integer(rows.iter().map(|r| r.seed).collect()),
        Column::Text(rows.iter().map(|r| r.controller.clone()).collect()),
        Column::Text(rows.iter().map(|r| r.exit.to_string()).collect()),
        Column::Number(
            rows.iter()
                .map(|r| match r.exit {
                    ExitStatus::Diverged { time, .. } => Some(time),
                    ExitStatus::Completed
                    | ExitStatus::Crashed { .. }
                    | ExitStatus::Grounded { .. }
                    | ExitStatus::Interrupted { .. } => None,
                })
                .collect(),
        ),
    ];
    for k in 0..SAMPLED_COLUMNS.len() {
        columns.push(Column::Number(rows.iter().map(|r| Some(r.sampled[k])).collect()));
    }
    let flats: Vec<Vec<(String, f64)>> = rows.iter().map(|r| r.metrics.flat()).collect();
    for name in &metric_names {
        let cells = rows
            .iter()
            .zip(&flats)
            .map(|(r, flat)| {
                let not_reached = name.starts_with("max_error_after_")
                    && r.metrics.max_error_after.to_array().iter().all(Option::is_none);
                match flat.iter().find(|(n, _)| n == name) {
                    Some((_, v)) if !not_reached => Some(*v),
                    _ => None,
                }
            })
            .collect();
        columns.push(Column::Number(cells));
    }
    columns.push(Column::Number(rows.iter().map(|r| Some(r.stats.peak_tilt)).collect()));
    columns.push(Column::Integer(rows.iter().map(|r| r.stats.saturated_periods).collect()));
    columns.push(Column::Number(rows.iter().map(|r| Some(r.stats.rotor_speed_max)).collect()));
    columns.push(Column::Number(rows.iter().map(|r| Some(r.stats.rotor_speed_mean)).collect()));
    columns.push(Column::Boolean(rows.iter().map(|r| r.exit.is_completed()).collect()));
    columns.push(Column::Boolean(rows.iter().map(|r| r.success).collect()));
    columns.push(Column::Boolean(rows.iter().map(|r| r.exit.is_crashed()).collect()));
    let margin = |f: &dyn Fn(&crate::margin::Margin) -> Option<f64>| {
        Column::Number(rows.iter().map(|r| r.margin.as_ref().and_then(f)).collect())
    };
    columns.push(margin(&|m| Some(m.value)));
    columns.push(margin(&|m| m.position));
    columns.push(margin(&|m| m.tilt));
    columns.push(margin(&|m| m.ground_clearance));
    columns.push(Column::Text(
        rows.iter().map(|r| r.margin.map_or(String::new(), |m| m.binds.as_str().to_string())).collect(),
    ));
    columns.push(margin(&|m| Some(m.at)));
    RunsTable { names, columns, rows: rows.len() }
}
