//! Campaigns split over machines: `ftsmc montecarlo --shard K/N` and
//! `ftsmc merge`. Three shards merged give the unsharded batch's files
//! byte for byte, and a campaign with a shard missing, repeated or foreign
//! is refused with an error naming it, writing nothing.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use serde_json::Value;

use crate::common::scratch;

const SCENARIO: &str = "paper-scenario-2";
const RUNS: &str = "7";
const CONTROLLERS: &str = "ftaftsmc,pid";

fn ftsmc(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).current_dir(cwd).output().expect("binary runs")
}

fn ok(args: &[&str], cwd: &Path) {
    let out = ftsmc(args, cwd);
    assert!(out.status.success(), "ftsmc {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// The error line of a command that must fail.
fn refused(args: &[&str], cwd: &Path) -> String {
    let out = ftsmc(args, cwd);
    assert!(!out.status.success(), "ftsmc {args:?} should fail");
    let err = String::from_utf8_lossy(&out.stderr).trim().to_string();
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    err
}

/// One campaign flown once for every test: the unsharded batch in
/// `whole/`, its three shards in `shards/`, and foreign shards (another
/// seed, another run count) in `foreign/`.
fn campaign() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let tmp = scratch("campaign");
        let d = tmp.path();
        let mc = ["montecarlo", SCENARIO, "-c", CONTROLLERS, "--no-figures"];
        ok(&[&mc[..], &["--runs", RUNS, "--out", "whole"]].concat(), d);
        for k in ["1/3", "2/3", "3/3"] {
            ok(&[&mc[..], &["--runs", RUNS, "--shard", k, "--out", "shards"]].concat(), d);
        }
        ok(&[&mc[..], &["--runs", RUNS, "--seed", "99", "--shard", "2/3", "--out", "seed99"]].concat(), d);
        ok(&[&mc[..], &["--runs", "8", "--shard", "2/3", "--out", "runs8"]].concat(), d);
        crate::common::removed_at_exit(tmp)
    })
}

fn shard(k: usize) -> String {
    format!("shards/{SCENARIO}-shard-{k}-of-3")
}

fn read(path: PathBuf) -> Vec<u8> {
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn json(path: PathBuf) -> Value {
    serde_json::from_slice(&read(path)).unwrap()
}

#[test]
fn three_shards_merge_into_the_unsharded_files_byte_for_byte() {
    let d = campaign();
    // Any order on the command line.
    ok(&["merge", &shard(3), &shard(1), &shard(2), "--out", "merged", "--no-figures"], d);
    let whole = d.join("whole").join(SCENARIO);
    let merged = d.join("merged").join(SCENARIO);
    let runs_csv = read(whole.join("runs.csv"));
    assert_eq!(runs_csv, read(merged.join("runs.csv")), "merged runs.csv differs from the unsharded one");
    assert_eq!(read(whole.join("scenario.toml")), read(merged.join("scenario.toml")));

    // Each shard flew its contiguous block of the rows, nothing else.
    let text = String::from_utf8(runs_csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + 7 * 2);
    let mut at = 1;
    for (k, (first, end)) in [(0u64, 2u64), (2, 4), (4, 7)].into_iter().enumerate() {
        let dir = d.join(shard(k + 1));
        let shard_text = String::from_utf8(read(dir.join("runs.csv"))).unwrap();
        let rows: Vec<&str> = shard_text.lines().skip(1).collect();
        assert_eq!(rows, lines[at..at + rows.len()], "shard {}", k + 1);
        at += rows.len();
        let s = json(dir.join("summary.json"));
        assert_eq!((s["shard"]["first_run"].as_u64(), s["shard"]["end_run"].as_u64()), (Some(first), Some(end)));
    }
    assert_eq!(at, lines.len());

    // summary.json: equal to the unsharded one except its provenance, which records the merge.
    let (mut a, mut b) = (json(whole.join("summary.json")), json(merged.join("summary.json")));
    let prov = b.as_object_mut().unwrap().remove("provenance").unwrap();
    a.as_object_mut().unwrap().remove("provenance");
    assert_eq!(a, b, "merged summary.json differs from the unsharded one beyond its provenance");
    let from = prov["merged_from"].as_array().unwrap();
    let indices: Vec<u64> = from.iter().map(|s| s["shard"]["index"].as_u64().unwrap()).collect();
    assert_eq!(indices, [1, 2, 3]);
    assert!(from[0]["folder"].as_str().unwrap().ends_with("shard-1-of-3"));
    assert_eq!(prov["command_line"][1], "merge");
    assert_eq!(prov["scenario_sha256"], json(whole.join("summary.json"))["provenance"]["scenario_sha256"]);
}

#[test]
fn merge_refuses_a_missing_repeated_foreign_or_incomplete_shard() {
    let d = campaign();
    let foreign_seed = format!("seed99/{SCENARIO}-shard-2-of-3");
    let foreign_runs = format!("runs8/{SCENARIO}-shard-2-of-3");
    let cases: Vec<(Vec<String>, Vec<String>)> = vec![
        (vec![shard(1), shard(3)], vec!["1 of 3 shards missing: 2/3".into(), format!("{SCENARIO}-shard-2-of-3")]),
        (vec![shard(1), shard(2), shard(2), shard(3)], vec!["shard 2/3 is given twice".into(), shard(2)]),
        (
            vec![shard(1), foreign_seed.clone(), shard(3)],
            vec![format!("`{foreign_seed}` is foreign"), "master seed is 99".into()],
        ),
        (
            vec![shard(1), foreign_runs.clone(), shard(3)],
            vec![format!("`{foreign_runs}` is foreign"), "run count is 8".into()],
        ),
        (vec![format!("whole/{SCENARIO}"), shard(2)], vec![format!("`whole/{SCENARIO}` is not a shard folder")]),
    ];
    for (dirs, expected) in cases {
        let mut args = vec!["merge".to_string()];
        args.extend(dirs.iter().cloned());
        args.extend(["--out".into(), "refused".into()]);
        let err = refused(&args.iter().map(String::as_str).collect::<Vec<_>>(), d);
        for e in expected {
            assert!(err.contains(&e), "{dirs:?}: `{e}` not in: {err}");
        }
        assert!(!d.join("refused").exists(), "{dirs:?}: a refused merge wrote {}", d.join("refused").display());
    }

    // A shard whose runs.csv lost its last row (a job killed while copying).
    let cut = d.join("cut");
    std::fs::create_dir_all(&cut).unwrap();
    let cut_shard = cut.join(format!("{SCENARIO}-shard-3-of-3"));
    std::fs::create_dir_all(&cut_shard).unwrap();
    for f in ["summary.json", "scenario.toml"] {
        std::fs::copy(d.join(shard(3)).join(f), cut_shard.join(f)).unwrap();
    }
    let text = String::from_utf8(read(d.join(shard(3)).join("runs.csv"))).unwrap();
    let kept: Vec<&str> = text.lines().collect();
    std::fs::write(cut_shard.join("runs.csv"), kept[..kept.len() - 1].join("\n") + "\n").unwrap();
    let cut_arg = format!("cut/{SCENARIO}-shard-3-of-3");
    let err = refused(&["merge", &shard(1), &shard(2), &cut_arg, "--out", "refused"], d);
    assert!(err.contains(&cut_arg) && err.contains("incomplete"), "{err}");

    // A shard whose scenario.toml was edited after the flight.
    let edited = cut.join("edited");
    std::fs::create_dir_all(&edited).unwrap();
    for f in ["summary.json", "runs.csv"] {
        std::fs::copy(d.join(shard(3)).join(f), edited.join(f)).unwrap();
    }
    let toml = String::from_utf8(read(d.join(shard(3)).join("scenario.toml"))).unwrap();
    std::fs::write(edited.join("scenario.toml"), toml + "\n# edited\n").unwrap();
    let err = refused(&["merge", &shard(1), &shard(2), "cut/edited", "--out", "refused"], d);
    assert!(err.contains("cut/edited") && err.contains("changed after the shard was flown"), "{err}");
    assert!(!d.join("refused").exists());
}

#[test]
fn bad_shard_values_are_refused_before_any_flight() {
    let tmp = scratch("bad");
    let d = tmp.path();
    for (shard, runs, expected) in [
        ("4/3", "7", "need 1 <= K <= N"),
        ("0/3", "7", "need 1 <= K <= N"),
        ("2", "7", "is not K/N"),
        ("1/5", "3", "5 shards for 3 runs"),
    ] {
        // (clap's own usage hint may follow the error line.)
        let out = ftsmc(&["montecarlo", SCENARIO, "--runs", runs, "--shard", shard, "--out", "out"], d);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr).lines().next().unwrap_or("").to_string();
        assert!(err.contains(expected) && err.contains(shard), "{shard}: {err}");
        assert!(!d.join("out").exists());
    }
}

/// A copy of shard 3 in `<campaign>/tamper/<name>` for one test to edit.
fn shard_copy(name: &str) -> (PathBuf, String) {
    let d = campaign();
    let to = d.join("tamper").join(name);
    std::fs::create_dir_all(&to).unwrap();
    for f in ["summary.json", "scenario.toml", "runs.csv"] {
        std::fs::copy(d.join(shard(3)).join(f), to.join(f)).unwrap();
    }
    (to, format!("tamper/{name}"))
}

/// `runs.csv` of `dir` with `column` of the first completed row set to `value`.
fn edit_completed_cell(dir: &Path, column: &str, value: &str) -> String {
    let text = String::from_utf8(read(dir.join("runs.csv"))).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let at = header.iter().position(|c| *c == column).unwrap();
    let completed = header.iter().position(|c| *c == "completed").unwrap();
    let row = (1..lines.len()).find(|&i| lines[i].split(',').nth(completed) == Some("true")).expect("a completed run");
    let mut cells: Vec<String> = lines[row].split(',').map(String::from).collect();
    assert_ne!(cells[at], value);
    cells[at] = value.to_string();
    lines[row] = cells.join(",");
    let edited = lines.join("\n") + "\n";
    std::fs::write(dir.join("runs.csv"), &edited).unwrap();
    edited
}

#[test]
fn merge_refuses_edited_rows_non_finite_metrics_and_inputs_that_are_not_regular_files() {
    let d = campaign();
    let merge = |arg: &str| refused(&["merge", &shard(1), &shard(2), arg, "--out", "refused-tamper"], d);

    // One ISE value edited: the rows no longer have the recorded SHA-256.
    let (dir, arg) = shard_copy("ise");
    edit_completed_cell(&dir, "ise_z", "0.001");
    let err = merge(&arg);
    assert!(err.contains(&arg) && err.contains("runs.csv has sha256") && err.contains("summary.json records"), "{err}");

    // A NaN in a completed row, the digest forged to match: refused by value.
    let (dir, arg) = shard_copy("nan");
    let edited = edit_completed_cell(&dir, "ise_x", "NaN");
    let mut summary = json(dir.join("summary.json"));
    summary["shard"]["runs_csv_sha256"] = Value::String(sha256_hex(edited.as_bytes()));
    std::fs::write(dir.join("summary.json"), serde_json::to_string_pretty(&summary).unwrap()).unwrap();
    let err = merge(&arg);
    assert!(err.contains(&arg) && err.contains("`ise_x`") && err.contains("NaN") && err.contains("completed"), "{err}");

    // Inputs that are not regular files, or too large, are refused without
    // being read: a FIFO (opening it would wait for a writer), a device
    // that never ends, a sparse file over the size limit.
    #[cfg(unix)]
    {
        let (dir, arg) = shard_copy("fifo");
        std::fs::remove_file(dir.join("runs.csv")).unwrap();
        let path = std::ffi::CString::new(dir.join("runs.csv").to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo only creates a file.
        assert_eq!(unsafe { libc::mkfifo(path.as_ptr(), 0o600) }, 0);
        let err = merge(&arg);
        assert!(err.contains(&arg) && err.contains("runs.csv") && err.contains("not a regular file"), "{err}");

        let (dir, arg) = shard_copy("zero");
        std::fs::remove_file(dir.join("summary.json")).unwrap();
        std::os::unix::fs::symlink("/dev/zero", dir.join("summary.json")).unwrap();
        let err = merge(&arg);
        assert!(err.contains(&arg) && err.contains("summary.json") && err.contains("not a regular file"), "{err}");
    }
    let (dir, arg) = shard_copy("huge");
    std::fs::File::options().write(true).open(dir.join("runs.csv")).unwrap().set_len((1 << 30) + 1).unwrap();
    let err = merge(&arg);
    assert!(err.contains(&arg) && err.contains("larger than the limit of 1073741824 bytes"), "{err}");
    assert!(!d.join("refused-tamper").exists());
}

/// SHA-256 as lowercase hex.
fn sha256_hex(data: &[u8]) -> String {
    use sha2::Digest as _;
    sha2::Sha256::digest(data).iter().map(|b| format!("{b:02x}")).collect()
}
