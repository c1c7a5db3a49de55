//! The time-series CSV: every number reads back to the same bits, and each
//! controller writes its own named estimate columns (docs/outputs.md).

use ftsmc_core::allocation::forces_from_squared_speeds;
use ftsmc_core::model::Command;
use ftsmc_sim::registry;
use ftsmc_sim::run::{push_number, Recording, RunOptions};
use ftsmc_sim::scenario::Scenario;

fn short_scenario_2() -> Scenario {
    let mut s = Scenario::paper_scenarios().remove(1);
    s.duration = 3.0;
    s
}

/// Parse `csv` (header + rows) back into names and rows of numbers.
fn parse(csv: &[u8]) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::str::from_utf8(csv).unwrap();
    assert!(text.ends_with('\n') && !text.contains('\r'));
    let mut lines = text.lines();
    let names: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| match v {
                    "NaN" => f64::NAN,
                    "inf" => f64::INFINITY,
                    "-inf" => f64::NEG_INFINITY,
                    v => v.parse::<f64>().unwrap_or_else(|e| panic!("`{v}`: {e}")),
                })
                .collect()
        })
        .collect();
    (names, rows)
}

fn assert_round_trips(rec: &Recording) {
    let (names, rows) = parse(&rec.to_csv());
    assert_eq!(names, rec.names);
    assert_eq!(rows.len(), rec.len());
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), rec.columns.len(), "row {i}");
        for (j, &v) in row.iter().enumerate() {
            let want = rec.columns[j][i];
            assert!(
                v.to_bits() == want.to_bits() || (v.is_nan() && want.is_nan()),
                "row {i} column {}: wrote {want:e}, read back {v:e}",
                names[j]
            );
        }
    }
}

#[test]
fn every_number_of_a_flight_reads_back_to_the_same_bits() {
    let s = short_scenario_2();
    for name in ["ftaftsmc", "ranftsmc", "tsm-sta"] {
        let run = registry::run(name, &s, RunOptions::default()).unwrap();
        assert!(run.recording.len() > 100);
        assert_round_trips(&run.recording);
    }
}

#[test]
fn extreme_values_read_back_to_the_same_bits() {
    let values = [
        0.0,
        -0.0,
        1.0,
        -1.5,
        0.1,
        1.0 / 3.0,
        1e-7,
        -2.5e-300,
        5e-324,
        f64::MIN_POSITIVE,
        f64::MAX,
        f64::MIN,
        f64::EPSILON,
        1e16,
        123456789012345680.0,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut rec = Recording::with_columns(vec!["a".into(), "b".into()]);
    for (i, &v) in values.iter().enumerate() {
        rec.push_row(&[v, values[values.len() - 1 - i]]);
    }
    assert_round_trips(&rec);
    let mut out = Vec::new();
    push_number(&mut out, f64::NAN);
    out.push(b' ');
    push_number(&mut out, f64::NEG_INFINITY);
    assert_eq!(out, b"NaN -inf");
}

#[test]
fn each_controller_writes_its_named_estimates_and_the_rotor_side_columns() {
    let s = short_scenario_2();
    let has = |rec: &Recording, name: &str| rec.names.iter().any(|n| n == name);
    for (controller, estimates, mass) in [
        ("ftaftsmc", &["delta_hat"][..], true),
        ("ftaftsmc-no-mass", &["delta_hat"][..], false),
        ("ranftsmc", &["a_hat0", "a_hat1", "a_hat2"][..], false),
        ("tsm-sta", &["nu"][..], false),
    ] {
        let rec = registry::run(controller, &s, RunOptions::default()).unwrap().recording;
        assert!(rec.names.iter().all(|n| !n.starts_with("est_")), "{controller}: {:?}", rec.names);
        for axis in ["x", "y", "z", "phi", "theta", "psi"] {
            for e in estimates {
                assert!(has(&rec, &format!("{e}_{axis}")), "{controller}: {e}_{axis}");
            }
        }
        let n_estimates =
            rec.names.iter().filter(|n| ["delta_hat_", "a_hat", "nu_"].iter().any(|p| n.starts_with(p))).count();
        assert_eq!(n_estimates, 6 * estimates.len(), "{controller}");
        assert_eq!(has(&rec, "alpha_hat"), mass, "{controller}");
        assert_eq!(has(&rec, "mass_estimate"), mass, "{controller}");
        let mut unique = rec.names.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), rec.names.len(), "{controller}: duplicate column");

        // Without a rotor-speed limit the applied command is the commanded
        // one, and the rotor speeds produce it.
        let p = s.true_vehicle();
        for i in (0..rec.len()).step_by(37) {
            let col = |n: &str| rec.column(n)[i];
            for n in ["thrust", "roll_torque", "pitch_torque", "yaw_torque"] {
                assert_eq!(col(n).to_bits(), col(&format!("{n}_cmd")).to_bits(), "{controller} {n} row {i}");
            }
            let omega = [col("omega_1"), col("omega_2"), col("omega_3"), col("omega_4")];
            assert!(omega.iter().all(|o| *o >= 0.0));
            assert_eq!(col("omega_bar"), omega[0] - omega[1] + omega[2] - omega[3]);
            let cmd =
                Command { thrust: col("thrust"), torque: [col("roll_torque"), col("pitch_torque"), col("yaw_torque")] };
            let back = forces_from_squared_speeds(&p, &omega.map(|o| o * o));
            // Exact only while every squared speed is feasible (≥ 0).
            if omega.iter().all(|o| *o > 0.0) {
                assert!((back.thrust - cmd.thrust).abs() < 1e-9 * cmd.thrust.abs().max(1.0));
            }
        }
    }
}

#[test]
fn applied_inputs_differ_from_commanded_under_a_rotor_speed_limit() {
    let mut s = short_scenario_2();
    s.simulation.max_rotor_speed = Some(300.0);
    let rec = registry::run("ranftsmc", &s, RunOptions::default()).unwrap().recording;
    let limited = (0..rec.len()).any(|i| rec.column("thrust")[i] != rec.column("thrust_cmd")[i]);
    assert!(limited, "a 300 rad/s limit must clip some command");
    for o in ["omega_1", "omega_2", "omega_3", "omega_4"] {
        assert!(rec.column(o).iter().all(|w| *w <= 300.0), "{o}");
    }
}

/// A writer that keeps the sizes of the writes it was handed, and fails
/// once it holds more than `fail_after` bytes.
struct Chunks {
    bytes: Vec<u8>,
    writes: Vec<usize>,
    fail_after: usize,
}

impl std::io::Write for Chunks {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.bytes.len() > self.fail_after {
            return Err(std::io::Error::other("disk full"));
        }
        self.bytes.extend_from_slice(buf);
        self.writes.push(buf.len());
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_streamed_recording_is_the_same_bytes_in_chunks_and_a_write_error_is_returned() {
    let run = registry::run("ftaftsmc", &short_scenario_2(), RunOptions::default()).unwrap();
    let whole = run.recording.to_csv();
    assert!(whole.len() > 3 * ftsmc_sim::run::CSV_CHUNK_BYTES, "{} bytes", whole.len());
    let mut out = Chunks { bytes: Vec::new(), writes: Vec::new(), fail_after: usize::MAX };
    run.recording.write_csv(&mut out).unwrap();
    assert_eq!(out.bytes, whole);
    // Handed on in chunks of about CSV_CHUNK_BYTES (never the whole file).
    assert!(out.writes.len() >= 3, "{:?}", out.writes);
    let largest = *out.writes.iter().max().unwrap();
    assert!(largest < ftsmc_sim::run::CSV_CHUNK_BYTES + 4096, "{largest}");
    // A failing writer: its error, not a panic or a silent short file.
    let mut full = Chunks { bytes: Vec::new(), writes: Vec::new(), fail_after: 1000 };
    let err = run.recording.write_csv(&mut full).unwrap_err();
    assert_eq!(err.to_string(), "disk full");
}
