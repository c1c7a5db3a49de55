//! Output files: atomic writes (temporary file + rename, so an interrupted
//! run never leaves a half-written result), per-run CSV time series and the
//! JSON summary.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use ftsmc_sim::simulate::{Recording, RunOutput};
use serde_json::{json, Map, Value};

/// Write `bytes` to `path` atomically (write `path.tmp`, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).with_context(|| format!("cannot create directory {}", parent.display()))?;
    }
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, bytes).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("cannot rename {} to {}", tmp.display(), path.display()))?;
    Ok(())
}

/// The time series of a run as CSV text (header = column names).
pub fn recording_csv(rec: &Recording) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&rec.names)?;
    let mut row = Vec::with_capacity(rec.names.len());
    for i in 0..rec.len() {
        row.clear();
        row.extend(rec.columns.iter().map(|c| format_number(c[i])));
        w.write_record(&row)?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))
}

/// Shortest round-trip decimal form (`NaN`, `inf` spelled as pandas reads them).
pub fn format_number(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{v}")
    }
}

/// Metrics and exit status of one run as a JSON object.
pub fn run_json(run: &RunOutput) -> Value {
    let mut obj = match serde_json::to_value(&run.metrics) {
        Ok(Value::Object(m)) => m,
        _ => Map::new(),
    };
    obj.insert("exit".into(), json!(run.exit.to_string()));
    obj.insert("exit_status".into(), serde_json::to_value(run.exit).unwrap_or(Value::Null));
    obj.insert("steps".into(), json!(run.steps));
    Value::Object(obj)
}

/// `{"scenarios": {scenario: {controller: {...metrics, "exit": ...}}}}`.
pub fn summary_json(runs: &[&RunOutput], extra: Map<String, Value>) -> Value {
    let mut scenarios: Map<String, Value> = Map::new();
    for run in runs {
        let entry = scenarios.entry(run.scenario.clone()).or_insert_with(|| Value::Object(Map::new()));
        if let Value::Object(m) = entry {
            m.insert(run.controller.clone(), run_json(run));
        }
    }
    let mut root = Map::new();
    root.insert("scenarios".into(), Value::Object(scenarios));
    root.extend(extra);
    Value::Object(root)
}
