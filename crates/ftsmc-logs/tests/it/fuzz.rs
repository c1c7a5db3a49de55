//! The readers never panic, whatever the bytes: random files, and good
//! logs (synthetic, and the fetched samples when data/ has them) with bytes
//! flipped, spans cut out or repeated, or the end cut off. Every case must
//! return a log or an error; a panic, or an abort from unbounded recursion
//! or allocation, fails the test. Sized to run in a few seconds.

use std::path::Path;

use crate::common::*;
use ftsmc_logs::ulog::{read_ulog, read_ulog_flight};
use ftsmc_logs::{read_log, LogLimits};
use proptest::prelude::*;

/// A mutation of a byte string.
#[derive(Clone, Debug)]
enum Mutation {
    /// Byte at (position mod len) replaced.
    Set(usize, u8),
    /// Bytes from position, this many, removed.
    Cut(usize, usize),
    /// Bytes from position, this many, written twice.
    Repeat(usize, usize),
    /// The file ends at position.
    End(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        6 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Mutation::Set(p, b)),
        1 => (any::<usize>(), 1usize..64).prop_map(|(p, n)| Mutation::Cut(p, n)),
        1 => (any::<usize>(), 1usize..64).prop_map(|(p, n)| Mutation::Repeat(p, n)),
        1 => any::<usize>().prop_map(Mutation::End),
    ]
}

fn mutate(bytes: &[u8], mutations: &[Mutation]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    for m in mutations {
        if b.is_empty() {
            break;
        }
        let len = b.len();
        match *m {
            Mutation::Set(p, v) => b[p % len] = v,
            Mutation::Cut(p, n) => {
                let p = p % len;
                b.drain(p..(p + n).min(len));
            }
            Mutation::Repeat(p, n) => {
                let p = p % len;
                let span = b[p..(p + n).min(len)].to_vec();
                b.splice(p..p, span);
            }
            Mutation::End(p) => b.truncate(p % len),
        }
    }
    b
}

/// Every reader on `bytes`, written to a file in `dir`: none may panic.
fn read_all(dir: &Path, bytes: &[u8]) {
    let path = write(dir, "case", bytes);
    let limits = LogLimits::default();
    let _ = read_log(&path, &limits);
    let _ = read_ulog(&path, &limits, None);
    let _ = read_ulog_flight(&path, &limits);
    let _ = ftsmc_logs::generic_csv::read_generic_csv(&path, &limits);
    let _ = ftsmc_logs::nanobench::read_nanobench(&path, &limits);
}

/// `cases` cases, or `PROPTEST_CASES` if set (for longer runs by hand).
fn config(cases: u32) -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(cases);
    ProptestConfig { cases, failure_persistence: None, ..ProptestConfig::default() }
}

proptest! {
    #![proptest_config(config(1024))]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600), magic in any::<bool>()) {
        let tmp = tempfile::tempdir().unwrap();
        let mut b = if magic { b"ULog\x01\x12\x35\x01\0\0\0\0\0\0\0\0".to_vec() } else { Vec::new() };
        b.extend(bytes);
        read_all(tmp.path(), &b);
    }

    #[test]
    fn mutated_synthetic_ulogs_never_panic(mutations in prop::collection::vec(mutation(), 1..6)) {
        let tmp = tempfile::tempdir().unwrap();
        let good = synthetic(Options::default()).writer.bytes;
        read_all(tmp.path(), &mutate(&good, &mutations));
    }

    #[test]
    fn mutated_csv_never_panics(mutations in prop::collection::vec(mutation(), 1..6), generic in any::<bool>()) {
        let tmp = tempfile::tempdir().unwrap();
        let good = if generic {
            "# frame: zup-flu\ntime_s,x_m,y_m,z_m,qw,qx,qy,qz,battery_v\n0,1,2,3,1,0,0,0,4.1\n0.01,1,2,3,1,0,0,0,4.1\n".to_string()
        } else {
            nanobench_csv(12)
        };
        read_all(tmp.path(), &mutate(good.as_bytes(), &mutations));
    }
}

proptest! {
    #![proptest_config(config(48))]

    /// The fetched samples (data/fetch.sh), mutated; skipped with a message
    /// when data/ has not been filled.
    #[test]
    fn mutated_samples_never_panic(which in 0usize..6, mutations in prop::collection::vec(mutation(), 1..4)) {
        let files = [
            "ulog/sample_log_small.ulg",
            "ulog/sample_appended_multiple.ulg",
            "nanobench/B2_circle_slow_rep1.csv",
            "nanobench/B3_figure8_slow_rep1.csv",
            "nanobench/B2_circle_fast_rep1.csv",
            "nanobench/B3_figure8_fast_rep1.csv",
        ];
        let path = data_dir().join(files[which]);
        let Ok(good) = std::fs::read(&path) else {
            eprintln!("skipped: {} is absent (run data/fetch.sh)", path.display());
            return Ok(());
        };
        let tmp = tempfile::tempdir().unwrap();
        read_all(tmp.path(), &mutate(&good, &mutations));
    }
}
