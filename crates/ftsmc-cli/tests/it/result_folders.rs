//! Result folders are whole: a bad `--out` is refused before any flight,
//! stale files of an older run never survive, two runs into one folder
//! leave exactly one run's whole output, and no command deletes a file it
//! did not write (the user's, or another command's results).

use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Command, Output, Stdio};

use crate::common::scratch;

fn ftsmc(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).current_dir(cwd).output().expect("binary runs")
}

/// Every name in `dir` (hidden ones included), sorted.
fn names(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect()
}

#[test]
fn stale_files_of_an_older_run_are_gone_and_the_users_files_stay() {
    let tmp = scratch("stale");
    let dir = tmp.path();
    let folder = dir.join("res/paper-scenario-1");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::write(folder.join("junk.csv"), "t,x\n0,1\n").unwrap();
    let first = ftsmc(&["run", "paper-scenario-1", "-c", "tsm-sta", "--out", "res", "--no-figures"], dir);
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    assert!(folder.join("tsm-sta.csv").is_file());
    let out = ftsmc(&["run", "paper-scenario-1", "-c", "ftaftsmc", "--out", "res", "--no-figures"], dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // The first run's tsm-sta.csv is gone (the run wrote it); junk.csv is the user's.
    let expected: BTreeSet<String> =
        [".ftsmc-run.manifest", "ftaftsmc.csv", "junk.csv", "report.html", "scenario.toml", "summary.json"]
            .map(String::from)
            .into();
    assert_eq!(names(&folder), expected);
    assert_eq!(std::fs::read_to_string(folder.join("junk.csv")).unwrap(), "t,x\n0,1\n");
    assert_eq!(names(&dir.join("res")), ["paper-scenario-1".to_string()].into(), "no staging or old folder left");
}

#[test]
fn commands_sharing_an_out_keep_each_others_results() {
    let tmp = scratch("shared");
    let dir = tmp.path();
    let folder = dir.join("out/paper-scenario-2");
    let run = ftsmc(&["run", "paper-scenario-2", "-c", "ftaftsmc", "--out", "out", "--no-figures"], dir);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let run_csv = std::fs::read(folder.join("ftaftsmc.csv")).unwrap();
    let mc = ftsmc(
        &["montecarlo", "paper-scenario-2", "--runs", "2", "-c", "ftaftsmc", "--out", "out", "--no-figures"],
        dir,
    );
    assert!(mc.status.success(), "{}", String::from_utf8_lossy(&mc.stderr));
    let err = String::from_utf8_lossy(&mc.stderr);
    // Both write report.html, summary.json and scenario.toml: the user is told.
    assert!(err.contains("replaced report.html, scenario.toml, summary.json") && err.contains("ftsmc run"), "{err}");
    assert_eq!(std::fs::read(folder.join("ftaftsmc.csv")).unwrap(), run_csv, "the run's CSV is kept");
    assert!(folder.join("runs.csv").is_file());
    // A user's file in the reproduce folder survives `run` and `reproduce`.
    std::fs::write(dir.join("out/notes.md"), "my notes").unwrap();
    let rep = ftsmc(&["reproduce", "--out", "out", "--no-figures", "--realistic-runs", "0"], dir);
    assert!(rep.status.success(), "{}", String::from_utf8_lossy(&rep.stderr));
    assert_eq!(std::fs::read_to_string(dir.join("out/notes.md")).unwrap(), "my notes");
    assert!(folder.join("runs.csv").is_file(), "reproduce keeps the Monte Carlo batch");
    // After reproduce, `run paper-scenario-1` keeps reproduce's tuned variant,
    // so reproduce's summary.json points only at files that exist.
    let s1 = dir.join("out/paper-scenario-1");
    assert!(s1.join("ftaftsmc-tuned.csv").is_file());
    let run1 = ftsmc(&["run", "paper-scenario-1", "--out", "out", "--no-figures"], dir);
    assert!(run1.status.success(), "{}", String::from_utf8_lossy(&run1.stderr));
    let err = String::from_utf8_lossy(&run1.stderr);
    assert!(err.contains("note: replaced ftaftsmc.csv, ranftsmc.csv, scenario.toml, tsm-sta.csv"), "{err}");
    assert!(err.contains("written by `ftsmc reproduce`"), "{err}");
    assert!(s1.join("ftaftsmc-tuned.csv").is_file());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap()).unwrap();
    for (scenario, runs) in summary["scenarios"].as_object().unwrap() {
        for controller in runs.as_object().unwrap().keys() {
            let csv = dir.join("out").join(scenario).join(format!("{controller}.csv"));
            assert!(csv.is_file(), "summary.json names {} which is gone", csv.display());
        }
    }
    for s in summary["provenance"]["scenarios"].as_array().unwrap() {
        assert!(dir.join("out").join(s["scenario_file"].as_str().unwrap()).is_file(), "{s}");
    }
    assert_eq!(std::fs::read_to_string(dir.join("out/notes.md")).unwrap(), "my notes");
}

#[test]
fn a_bad_out_is_refused_before_any_flight_and_nothing_is_written() {
    let tmp = scratch("badout");
    let dir = tmp.path();
    std::fs::write(dir.join("file"), "a regular file").unwrap();
    let cases: [&[&str]; 4] = [
        &["reproduce", "--out", "file/res", "--no-figures"],
        &["run", "paper-scenario-1", "--out", "file/res", "--no-figures"],
        &["montecarlo", "paper-scenario-2", "--runs", "2", "--out", "file/mc", "--no-figures"],
        &["fixed-time", "--controllers", "ftaftsmc", "--per-decade", "1", "--out", "file/ft"],
    ];
    for args in cases {
        let out = ftsmc(args, dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(
            err.starts_with("error: ") && err.contains("file") && err.contains("not a directory"),
            "{args:?}: {err}"
        );
        // `reproduce` announces its flights on stderr; nothing was flown or printed.
        assert!(!err.contains("flying"), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}: {}", String::from_utf8_lossy(&out.stdout));
        assert_eq!(names(dir), ["file".to_string()].into(), "{args:?}");
    }
}

#[test]
fn concurrent_runs_into_one_folder_leave_one_whole_result() {
    let tmp = scratch("concurrent");
    let dir = tmp.path();
    // Two different runs of the same scenario name into the same folder.
    let a: &[&str] = &["run", "paper-scenario-1", "-c", "ftaftsmc", "--out", "res", "--no-figures"];
    let b: &[&str] = &["run", "paper-scenario-1", "-c", "ranftsmc,tsm-sta", "--out", "res", "--no-figures"];
    let folder = dir.join("res/paper-scenario-1");
    for round in 0..4 {
        let spawn = |args: &[&str]| {
            Command::new(env!("CARGO_BIN_EXE_ftsmc"))
                .args(args)
                .current_dir(dir)
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        };
        // Alternate which one starts first.
        let (first, second) = if round % 2 == 0 { (a, b) } else { (b, a) };
        let p1 = spawn(first);
        let p2 = spawn(second);
        for p in [p1, p2] {
            let out = p.wait_with_output().unwrap();
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        }
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(folder.join("summary.json")).unwrap()).unwrap();
        let controllers: BTreeSet<String> =
            summary["scenarios"]["paper-scenario-1"].as_object().unwrap().keys().cloned().collect();
        let mut expected: BTreeSet<String> = controllers.iter().map(|c| format!("{c}.csv")).collect();
        expected.insert(".ftsmc-run.manifest".into());
        expected.insert("summary.json".into());
        expected.insert("scenario.toml".into());
        expected.insert("report.html".into());
        assert_eq!(names(&folder), expected, "round {round}: the files must be exactly those of one run");
        assert!(
            controllers == ["ftaftsmc".to_string()].into()
                || controllers == ["ranftsmc".to_string(), "tsm-sta".to_string()].into(),
            "{controllers:?}"
        );
        assert_eq!(names(&dir.join("res")), ["paper-scenario-1".to_string()].into(), "round {round}");
    }
}

/// Run `args` (in `dir`) twice, `folder` being its result folder and
/// `manifest` its manifest there; between the runs, two files of the user's
/// are named in the manifest by hand (one plain, one with a forged size and
/// SHA-256). The second run keeps both, says so on stderr, and exits 0.
fn a_hand_edited_manifest_deletes_nothing(dir: &Path, args: &[&str], folder: &str, manifest: &str) {
    let run = |what: &str| {
        let out = ftsmc(args, dir);
        assert!(out.status.success(), "{what} {args:?}: {}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    run("first");
    let folder = dir.join(folder);
    let manifest = folder.join(manifest);
    assert!(manifest.is_file(), "{} missing", manifest.display());
    std::fs::write(folder.join("mine.txt"), "mine").unwrap();
    std::fs::write(folder.join("paper.md"), "my paper").unwrap();
    let mut text = std::fs::read_to_string(&manifest).unwrap();
    text.push_str("mine.txt\n");
    text.push_str("e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855 0 paper.md\n");
    std::fs::write(&manifest, text).unwrap();
    let err = run("second");
    assert_eq!(std::fs::read_to_string(folder.join("mine.txt")).unwrap(), "mine", "{args:?}");
    assert_eq!(std::fs::read_to_string(folder.join("paper.md")).unwrap(), "my paper", "{args:?}");
    assert!(err.contains("note: kept") && err.contains("mine.txt") && err.contains("paper.md"), "{args:?}: {err}");
    // The new manifest lists neither.
    let text = std::fs::read_to_string(&manifest).unwrap();
    assert!(!text.contains("mine.txt") && !text.contains("paper.md"), "{text}");
}

#[test]
fn a_hand_edited_manifest_of_run_deletes_nothing() {
    let tmp = scratch("tamper-run");
    let args = ["run", "paper-scenario-1", "-c", "pid", "--out", "o", "--no-figures"];
    a_hand_edited_manifest_deletes_nothing(tmp.path(), &args, "o/paper-scenario-1", ".ftsmc-run.manifest");
}

#[test]
fn a_hand_edited_manifest_of_montecarlo_deletes_nothing() {
    let tmp = scratch("tamper-mc");
    let args = ["montecarlo", "paper-scenario-2", "--runs", "2", "-c", "pid", "--out", "o", "--no-figures"];
    a_hand_edited_manifest_deletes_nothing(tmp.path(), &args, "o/paper-scenario-2", ".ftsmc-montecarlo.manifest");
}

#[test]
fn a_hand_edited_manifest_of_fixed_time_deletes_nothing() {
    let tmp = scratch("tamper-ft");
    let args = ["fixed-time", "--controllers", "ftaftsmc", "--per-decade", "1", "--out", "o"];
    a_hand_edited_manifest_deletes_nothing(tmp.path(), &args, "o/paper-scenario-1", ".ftsmc-fixed-time.manifest");
}

#[test]
fn a_hand_edited_manifest_of_tune_deletes_nothing() {
    let tmp = scratch("tamper-tune");
    let tiny = "extends = \"realistic-scenario-2\"\nname = \"tiny-tune\"\nduration = 1.0\n\n[tune]\nruns = 1\nvalidation_runs = 1\npopulation = 4\n";
    std::fs::write(tmp.path().join("tiny.toml"), tiny).unwrap();
    let args = ["tune", "tiny.toml", "-c", "pid", "--budget", "6", "--out", "o", "--no-figures"];
    a_hand_edited_manifest_deletes_nothing(tmp.path(), &args, "o/tiny-tune", ".ftsmc-tune-pid.manifest");
}

#[test]
fn a_hand_edited_manifest_of_merge_deletes_nothing() {
    let tmp = scratch("tamper-merge");
    let shard = ["montecarlo", "paper-scenario-2", "--runs", "2", "-c", "pid", "--shard", "1/1", "--out", "s"];
    let out = ftsmc(&[&shard[..], &["--no-figures"]].concat(), tmp.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let args = ["merge", "s/paper-scenario-2-shard-1-of-1", "--out", "o", "--no-figures"];
    a_hand_edited_manifest_deletes_nothing(tmp.path(), &args, "o/paper-scenario-2", ".ftsmc-montecarlo.manifest");
}

#[test]
fn a_hand_edited_manifest_of_reproduce_deletes_nothing() {
    let tmp = scratch("tamper-reproduce");
    let args = ["reproduce", "--out", "o", "--no-figures", "--realistic-runs", "0"];
    a_hand_edited_manifest_deletes_nothing(tmp.path(), &args, "o", ".ftsmc-reproduce.manifest");
}
