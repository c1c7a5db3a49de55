//! The same seed gives the same bits whatever the CPU's feature level.
//!
//! glibc picks an FMA or a non-FMA build of `sin`, `atan2`, `exp`, `pow` …
//! by the CPU at run time (`GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA`
//! makes it pick the baseline build on any CPU), and the two differ in the
//! last bit for some arguments. Before every transcendental function went
//! through the one pure-Rust maths library (`ftsmc_core::math`), the
//! runs.csv of both Monte Carlo batches below differed from their first row
//! between the two settings. This test flies each batch twice, as the CPU
//! is and with glibc's AVX2/FMA builds switched off, and compares the files
//! byte for byte. (Where the C library is not glibc the variable is ignored
//! and the two runs are the same by construction; CI runs on glibc.)
//!
//! The flights in lanes run their control laws on the widest instruction
//! set the CPU has (AVX2 + FMA on most x86-64 machines, `ftsmc_sim::isa`);
//! `FTSMC_ISA=baseline` forces the baseline (SSE2) build of the same code.
//! The batches below are flown on 4 lanes both ways, and on one lane, and
//! must give the same bytes.

use std::path::Path;
use std::process::Command;

use crate::common::scratch;

/// Fly `file` as a Monte Carlo batch on `lanes` lanes into `dir/<out>`;
/// `baseline` asks glibc for its baseline (no AVX, no FMA) maths and ftsmc
/// for its baseline lane kernels.
fn fly(dir: &Path, file: &str, out: &str, baseline: bool, lanes: &str) -> Vec<u8> {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_ftsmc"));
    cmd.args(["montecarlo", file, "--runs", "5", "--threads", "2", "--lanes", lanes, "--no-figures", "--out", out])
        .current_dir(dir);
    if baseline {
        cmd.env("GLIBC_TUNABLES", "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX,-FMA4");
        cmd.env("FTSMC_ISA", "baseline");
    } else {
        cmd.env_remove("GLIBC_TUNABLES");
        cmd.env_remove("FTSMC_ISA");
    }
    let run = cmd.output().expect("binary runs");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let name = file.trim_end_matches(".toml");
    std::fs::read(dir.join(out).join(name).join("runs.csv")).unwrap()
}

#[test]
fn monte_carlo_is_byte_identical_with_and_without_avx2_and_fma() {
    let tmp = scratch("cpu-levels");
    let dir = tmp.path();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    // Shortened so the debug build flies them in seconds; every controller
    // of each scenario, with its turbulence, sensors and disturbances.
    for file in ["paper-scenario-2.toml", "realistic-scenario-2.toml"] {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        let mut short = String::new();
        for line in text.lines().filter(|l| !l.starts_with("duration =")) {
            short.push_str(line);
            short.push('\n');
            if line.starts_with("name =") {
                short.push_str("duration = 10.0\n");
            }
        }
        assert!(short.contains("duration = 10.0"), "{file} has no top-level `name`");
        std::fs::write(dir.join(file), short).unwrap();
        let native = fly(dir, file, "native", false, "4");
        let baseline = fly(dir, file, "baseline", true, "4");
        let one_lane = fly(dir, file, "one-lane", false, "1");
        assert!(String::from_utf8_lossy(&native).lines().count() > 3, "{file}: no rows");
        assert!(native == baseline, "{file}: runs.csv differs between the CPU's maths and the baseline maths");
        assert!(native == one_lane, "{file}: runs.csv differs between 4 lanes and one");
    }
}
