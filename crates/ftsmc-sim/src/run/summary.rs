//! One run's entry of `summary.json`: its metrics, exit status and the span
//! they cover, as the CLI writes it and the Python package returns it as
//! `Run.metrics` (one implementation for both).

use serde_json::{json, Map, Value};

use super::RunOutput;

/// Metrics and exit status of one run as a JSON object (the per-controller
/// entry of `summary.json`, see docs/outputs.md): every field of
/// [`crate::metrics::Metrics`], `exit` (text), `exit_status` (tagged),
/// `steps`, `covered` (`[0, t_end]`, s: the span the integral metrics
/// cover), `completed`, and with an `[envelope]` also `success` and
/// `envelope_violation`, and `margin` when the flight has one
/// ([`crate::margin::Margin`]).
pub fn run_json(run: &RunOutput) -> Value {
    let mut obj = match serde_json::to_value(&run.metrics) {
        Ok(Value::Object(m)) => m,
        _ => Map::new(),
    };
    obj.insert("exit".into(), json!(run.exit.to_string()));
    obj.insert("exit_status".into(), serde_json::to_value(run.exit).unwrap_or(Value::Null));
    obj.insert("steps".into(), json!(run.steps));
    // The span the integral metrics (ISE, IAE, ITAE, RMS, energy,
    // chattering) cover: shorter than the scenario for a diverged run.
    obj.insert("covered".into(), json!(run.metrics.covered()));
    obj.insert("completed".into(), json!(run.exit.is_completed()));
    // Only scenarios with an [envelope] say more than `completed`.
    if let Some(v) = &run.envelope {
        obj.insert("success".into(), json!(v.success));
        obj.insert("envelope_violation".into(), json!(v.violation));
    }
    if let Some(m) = &run.margin {
        obj.insert("margin".into(), serde_json::to_value(m).unwrap_or(Value::Null));
    }
    Value::Object(obj)
}
