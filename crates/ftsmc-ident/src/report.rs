//! The tables of an identification and of a validation, as the CLI writes
//! them (`parameters.csv`, `identification.json`, `validation.csv`,
//! `validation.json`) and as the Python binding returns them: one
//! definition of each column, so the two front ends cannot disagree.
//! Numbers are written in Rust's `{:e}` form (round-trip exact); a
//! non-finite value is `null` in JSON.

use serde_json::{json, Map, Value};

use crate::identify::Identification;
use crate::validate::ValidationRow;

/// Header of [`parameters_csv`].
pub const PARAMETERS_HEADER: &str = "name,unit,value,lo,hi,basis,base";

/// Header of [`validation_csv`].
pub const VALIDATION_HEADER: &str =
    "flight,horizon_s,steps,quantity,axis,n,r2,r2_lo,r2_hi,rms,rms_lo,rms_hi,baseline_r2,baseline_rms";

fn num(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// One row per identified quantity: name, unit, value, the 95 % bootstrap
/// interval `lo`–`hi`, what it needs (`basis`: `log`, `log + mass`, …) and
/// the base vehicle's value.
pub fn parameters_csv(id: &Identification) -> String {
    let mut csv = format!("{PARAMETERS_HEADER}\n");
    for e in &id.estimates {
        csv.push_str(&format!("{},{},{:e},{:e},{:e},{},{:e}\n", e.name, e.unit, e.value, e.lo, e.hi, e.basis, e.base));
    }
    csv
}

/// The whole identification: flights, mass and its source, sample steps,
/// segments, bootstrap replicates and seed, the reference battery voltage
/// (V), the fits' R², the thrust maps tried and every estimate.
pub fn identification_json(id: &Identification) -> Value {
    json!({
        "flights": id.flights,
        "base_vehicle": id.base.name,
        "mass_kg": id.mass_kg,
        "mass_source": id.mass_source,
        "rows": id.rows,
        "segments": id.segments,
        "bootstrap_replicates": id.replicates,
        "seed": id.seed,
        "battery_ref_v": num(id.battery_ref_v),
        "r2": id.r2.iter().map(|(n, v)| (n.to_string(), num(*v))).collect::<Map<_, _>>(),
        "thrust_maps": id.thrust_maps.iter().map(|m| json!({
            "name": m.name, "linear_n": m.linear_n, "quadratic_n": m.quadratic_n, "r2": num(m.r2)
        })).collect::<Vec<_>>(),
        "estimates": id.estimates.iter().map(|e| json!({
            "name": e.name, "unit": e.unit, "value": num(e.value), "lo": num(e.lo), "hi": num(e.hi),
            "basis": e.basis, "base": num(e.base)
        })).collect::<Vec<_>>(),
    })
}

/// One row per flight (and `all`, pooled), horizon (s) and axis: R² with
/// its 95 % interval, RMS residual with its interval (the quantity's unit:
/// m/s² or rad/s²), and the constant-acceleration baseline's R² and RMS.
pub fn validation_csv(rows: &[ValidationRow]) -> String {
    let mut csv = format!("{VALIDATION_HEADER}\n");
    for r in rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            r.flight.replace(',', ";"),
            r.horizon_s,
            r.steps,
            r.quantity,
            r.axis,
            r.n,
            r.r2,
            r.r2_lo,
            r.r2_hi,
            r.rms,
            r.rms_lo,
            r.rms_hi,
            r.baseline_r2,
            r.baseline_rms
        ));
    }
    csv
}

/// The validation of vehicle `vehicle` on `flights` (their paths): every
/// row of [`validation_csv`].
pub fn validation_json(vehicle: &str, flights: &[String], rows: &[ValidationRow]) -> Value {
    json!({
        "vehicle": vehicle,
        "flights": flights,
        "rows": rows.iter().map(|r| json!({
            "flight": r.flight, "horizon_s": r.horizon_s, "steps": r.steps, "quantity": r.quantity, "axis": r.axis,
            "n": r.n, "r2": num(r.r2), "r2_lo": num(r.r2_lo), "r2_hi": num(r.r2_hi), "rms": num(r.rms),
            "rms_lo": num(r.rms_lo), "rms_hi": num(r.rms_hi), "baseline_r2": num(r.baseline_r2),
            "baseline_rms": num(r.baseline_rms)
        })).collect::<Vec<_>>(),
    })
}
