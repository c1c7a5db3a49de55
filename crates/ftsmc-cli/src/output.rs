//! Output files: per-run CSV time series, the JSON summary and its
//! provenance record, single files written atomically, and error lines
//! for the terminal. Whole result folders are [`crate::result_dir`].

use std::io::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use ftsmc_sim::run::RunOutput;
use serde_json::{json, Map, Value};

pub use crate::result_dir::{sha256_hex, ResultDir};

/// Write `bytes` to `path` (temporary file + rename), creating its parent
/// folders. Commands write inside a [`ResultDir`] staging folder, which is
/// what makes results whole; this only keeps a single file from being seen
/// half-written. The temporary file is a new hidden file of a unique name
/// beside `path` (created exclusively: never a file someone else wrote, and
/// two processes rewriting one manifest do not share it), removed when
/// writing fails.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create directory {}", dir.display()))?;
    let mut tmp = tempfile::Builder::new()
        .prefix(".ftsmc-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    tmp.write_all(bytes).with_context(|| format!("cannot write {}", tmp.path().display()))?;
    tmp.persist(path).map_err(|e| {
        anyhow::Error::new(e.error).context(format!("cannot rename a temporary file to {}", path.display()))
    })?;
    Ok(())
}

/// Longest error message `main` prints, in characters.
pub const MAX_ERROR_CHARS: usize = 300;

/// One line of at most `max` characters for the terminal: lines of a
/// multi-line message (the TOML parser's source snippet) are joined with
/// ` | `, snippet lines (`12 | text`, `   |   ^`) are dropped, and the result
/// is cut at `max` characters with `…`.
pub fn one_line(text: &str, max: usize) -> String {
    let is_snippet = |line: &str| {
        let rest = line.trim_start().trim_start_matches(|c: char| c.is_ascii_digit()).trim_start();
        rest.starts_with('|') && rest.len() < line.len()
    };
    let parts: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty() && !is_snippet(l)).map(str::trim).collect();
    let joined = parts.join(" | ");
    let joined: String = joined.chars().map(|c| if c.is_control() { ' ' } else { c }).collect();
    if joined.chars().count() <= max {
        joined
    } else {
        let mut cut: String = joined.chars().take(max.saturating_sub(1)).collect();
        cut.push('…');
        cut
    }
}

/// Shortest round-trip decimal form, as in the time series (`0.3`, `1.0`,
/// `2.5e-7`; `NaN`, `inf` spelled as pandas reads them; see
/// [`ftsmc_sim::run::push_number`]).
pub fn format_number(v: f64) -> String {
    let mut out = Vec::with_capacity(24);
    ftsmc_sim::run::push_number(&mut out, v);
    String::from_utf8(out).unwrap_or_default()
}

pub use ftsmc_sim::run::summary::run_json;

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

/// The program version (`Cargo.toml`).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The git commit the binary was built from (`<sha>`, `<sha>-dirty` when
/// tracked files differed from it, `unknown` outside a git checkout; see
/// `build.rs`).
pub const GIT_COMMIT: &str = env!("FTSMC_GIT_COMMIT");

/// The resolved scenario as written to `scenario.toml`: every field, with
/// every default filled in ([`Scenario::to_toml`](ftsmc_sim::scenario::Scenario::to_toml));
/// loading it gives back an identical [`Scenario`](ftsmc_sim::scenario::Scenario).
pub fn scenario_toml(scenario: &ftsmc_sim::scenario::Scenario) -> Result<String> {
    scenario.to_toml().context("cannot write the scenario as TOML")
}

/// One scenario file written into a result folder, for the provenance record.
#[derive(Clone, Debug)]
pub struct ScenarioFile {
    /// Path relative to the folder holding `summary.json`.
    pub file: String,
    /// SHA-256 of the file's bytes (hex), as `sha256sum` prints it.
    pub sha256: String,
    /// The scenario's seed (for a Monte Carlo batch, the master seed).
    pub seed: u64,
}

impl ResultDir {
    /// Write `scenario` (resolved) to `rel` and return its provenance record.
    pub fn write_scenario(
        &self,
        rel: &str,
        scenario: &ftsmc_sim::scenario::Scenario,
        file_in_summary: &str,
    ) -> Result<ScenarioFile> {
        let text = scenario_toml(scenario)?;
        self.write(rel, text.as_bytes())?;
        Ok(ScenarioFile { file: file_in_summary.to_string(), sha256: sha256_hex(text.as_bytes()), seed: scenario.seed })
    }
}

/// The `provenance` object of `summary.json` / `fixed-time.json`:
/// `ftsmc_version`, `git_commit`, `command_line` (the arguments as given),
/// and for one scenario `scenario_file`, `scenario_sha256` and `seed`; for
/// several (`ftsmc reproduce`) a `scenarios` list of
/// `{scenario_file, scenario_sha256, seed}`.
pub fn provenance(files: &[ScenarioFile]) -> Value {
    let mut p = Map::new();
    p.insert("ftsmc_version".into(), json!(VERSION));
    p.insert("git_commit".into(), json!(GIT_COMMIT));
    p.insert(
        "command_line".into(),
        json!(std::env::args_os().map(|a| a.to_string_lossy().into_owned()).collect::<Vec<_>>()),
    );
    let entry = |f: &ScenarioFile| json!({"scenario_file": f.file, "scenario_sha256": f.sha256, "seed": f.seed});
    match files {
        [one] => {
            if let Value::Object(m) = entry(one) {
                p.extend(m);
            }
        }
        many => {
            p.insert("scenarios".into(), Value::Array(many.iter().map(entry).collect()));
        }
    }
    Value::Object(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh scratch folder `<temp dir>/ftsmc-output-<name>-<random>`,
    /// removed when the returned guard drops: when the test ends, passed or failed.
    fn temp(name: &str) -> tempfile::TempDir {
        tempfile::Builder::new().prefix(&format!("ftsmc-output-{name}-")).tempdir().unwrap()
    }

    /// Names in `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn write_atomic_never_touches_a_file_it_did_not_write() {
        let tmp = temp("atomic");
        let root = tmp.path();
        // A user's file with the name a fixed-suffix temporary would take.
        std::fs::write(root.join("fig.svg.tmp"), "mine").unwrap();
        write_atomic(&root.join("fig.svg"), b"<svg/>").unwrap();
        write_atomic(&root.join("fig.svg"), b"<svg></svg>").unwrap();
        assert_eq!(std::fs::read_to_string(root.join("fig.svg.tmp")).unwrap(), "mine");
        assert_eq!(std::fs::read_to_string(root.join("fig.svg")).unwrap(), "<svg></svg>");
        assert_eq!(names(root), ["fig.svg", "fig.svg.tmp"], "no temporary file left");
        // Parent folders are created; a failed write leaves nothing behind.
        write_atomic(&root.join("a/b/c.txt"), b"x").unwrap();
        assert_eq!(std::fs::read_to_string(root.join("a/b/c.txt")).unwrap(), "x");
        assert!(write_atomic(&root.join("fig.svg/inside"), b"x").is_err(), "a file is not a folder");
        std::fs::create_dir(root.join("d")).unwrap();
        assert!(write_atomic(&root.join("d"), b"x").is_err(), "a folder is not replaced by a file");
        assert_eq!(names(root), ["a", "d", "fig.svg", "fig.svg.tmp"]);
        assert!(names(&root.join("d")).is_empty());
    }

    #[test]
    fn concurrent_write_atomic_of_one_file_leaves_one_whole_version() {
        let tmp = temp("atomic-race");
        let path = tmp.path().join("manifest");
        let texts: Vec<String> = (0..8).map(|k| format!("{k}\n").repeat(20_000)).collect();
        std::thread::scope(|scope| {
            for text in &texts {
                let path = &path;
                scope.spawn(move || {
                    for _ in 0..20 {
                        write_atomic(path, text.as_bytes()).unwrap();
                    }
                });
            }
        });
        let got = std::fs::read_to_string(&path).unwrap();
        assert!(texts.contains(&got), "a torn or mixed file ({} bytes)", got.len());
        assert_eq!(names(tmp.path()), ["manifest"], "no temporary file left");
    }

    #[test]
    fn error_lines_are_single_and_bounded() {
        let toml = "deep.toml: TOML parse error at line 1, column 85\n  |\n1 | a = [[[[[[[[\n  |     ^\ncannot recurse further; max recursion depth met\n";
        assert_eq!(
            one_line(toml, 300),
            "deep.toml: TOML parse error at line 1, column 85 | cannot recurse further; max recursion depth met"
        );
        let long = "x".repeat(100_000);
        let cut = one_line(&long, 300);
        assert_eq!(cut.chars().count(), 300);
        assert!(cut.ends_with('…'));
        assert_eq!(one_line("a\tb\u{1b}[31m", 300), "a b [31m");
    }
}
