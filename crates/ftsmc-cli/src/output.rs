//! Output files: whole result folders ([`ResultDir`]), per-run CSV time
//! series and the JSON summary.
//!
//! # Result folders are whole
//!
//! Every command writes its results into a *staging* folder beside the
//! destination, `.<name>.tmp-<pid>-<nanos>` (hidden, unique per process and
//! start time), and only when every file is complete swaps it into place:
//! the old destination (if any) is renamed to `.<name>.old-<pid>-<nanos>`,
//! the staging folder is renamed to the destination, and the old folder is
//! deleted. A reader therefore sees the whole old result or the whole new
//! one, never a mix, and no file of an older run survives beside the new
//! ones. (Between the two renames — microseconds — the destination does not
//! exist at all.) The one exception is nested results of *other* commands:
//! a sub-folder of the old destination that holds its own `summary.json` or
//! `fixed-time.json`, or whose own sub-folders do (e.g. `results/montecarlo`,
//! parent of `ftsmc montecarlo`'s `results/montecarlo/<scenario>/`),
//! and that the new result does not contain is moved into the new folder
//! before the swap, so `ftsmc reproduce` does not delete a Monte Carlo batch.
//!
//! On every error path (a flight fails, a write fails — disk full included —
//! or a figure cannot be rendered) the staging folder is removed by a drop
//! guard, and directories created only for it are removed again.
//!
//! The destination is checked before any flight: the nearest existing
//! ancestor must be a directory and the staging folder must be creatable
//! in it, so a bad `--out` is refused before any work.
//!
//! **Concurrency** (unique names, no lock): two runs into the same folder
//! each write their own staging folder; each commit is a rename swap, so the
//! run that finishes last wins and the folder is exactly its whole output —
//! never one run's CSV beside the other's summary. A run killed with SIGKILL
//! leaves only a hidden `.<name>.tmp-…` (or, if killed between the two
//! renames, `.<name>.old-…`) folder beside the destination; the next
//! successful run into the same destination deletes such leftovers older
//! than [`STALE_AFTER`] whose process no longer exists (on Linux; elsewhere
//! the age alone decides).

use std::ffi::OsString;
use std::path::{Component, Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use anyhow::{bail, Context, Result};
use ftsmc_sim::run::{Recording, RunOutput};
use serde_json::{json, Map, Value};

/// Leftover staging / old folders older than this are deleted by the next
/// successful run into the same destination.
pub const STALE_AFTER: Duration = Duration::from_secs(3600);

/// How often a commit retries when a concurrent run puts a folder back in
/// place between our two renames.
const COMMIT_ATTEMPTS: usize = 100;

/// A result folder being written: files go into a hidden staging folder
/// beside `dest`; [`ResultDir::commit`] swaps it into place; dropping it
/// uncommitted removes the staging folder.
#[derive(Debug)]
pub struct ResultDir {
    dest: PathBuf,
    staging: PathBuf,
    /// Directories created for the staging folder (deepest last), removed
    /// again if they are still empty when the transaction fails.
    created: Vec<PathBuf>,
    committed: bool,
}

fn unique_suffix() -> String {
    let nanos = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    format!("{}-{nanos}", std::process::id())
}

fn hidden_name(name: &std::ffi::OsStr, kind: &str) -> OsString {
    let mut s = OsString::from(".");
    s.push(name);
    s.push(format!(".{kind}-{}", unique_suffix()));
    s
}

impl ResultDir {
    /// Start a result folder for `dest`: check it can be written and create
    /// the staging folder. Call before doing any work.
    pub fn begin(dest: &Path) -> Result<Self> {
        let name = match dest.components().next_back() {
            Some(Component::Normal(n)) => n.to_owned(),
            _ => bail!("output folder `{}` must end in a folder name (not `.`, `..` or `/`)", dest.display()),
        };
        let parent = match dest.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if let Ok(meta) = std::fs::symlink_metadata(dest) {
            if !meta.is_dir() {
                bail!("output folder `{}` exists and is not a directory", dest.display());
            }
        }
        // The nearest existing ancestor must be a directory.
        let mut missing = Vec::new();
        let mut probe = parent.clone();
        loop {
            match std::fs::metadata(&probe) {
                Ok(meta) if meta.is_dir() => break,
                Ok(_) => bail!("cannot write to `{}`: `{}` is not a directory", dest.display(), probe.display()),
                // Missing (or below a file: ENOTDIR): look further up; any
                // other problem surfaces when the folders are created.
                Err(_) => {
                    missing.push(probe.clone());
                    match probe.parent() {
                        Some(p) if !p.as_os_str().is_empty() => probe = p.to_path_buf(),
                        _ => break,
                    }
                }
            }
        }
        let mut created = Vec::new();
        for dir in missing.into_iter().rev() {
            match std::fs::create_dir(&dir) {
                Ok(()) => created.push(dir),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => {
                    remove_created(&created);
                    return Err(e).with_context(|| format!("cannot create {}", dir.display()));
                }
            }
        }
        let staging = parent.join(hidden_name(&name, "tmp"));
        if let Err(e) = std::fs::create_dir(&staging) {
            remove_created(&created);
            return Err(e).with_context(|| format!("cannot write to `{}`", dest.display()));
        }
        Ok(Self { dest: dest.to_path_buf(), staging, created, committed: false })
    }

    /// The staging folder: write every file of the result below it.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Write `bytes` to `rel` (relative to the result folder), creating
    /// sub-folders as needed.
    pub fn write(&self, rel: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
        write_file(&self.staging.join(rel), bytes)
    }

    /// Swap the staging folder into place (see the module docs).
    pub fn commit(mut self) -> Result<()> {
        let parent = self.staging.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."));
        let name = self.dest.file_name().map(ToOwned::to_owned).unwrap_or_default();
        let mut olds = Vec::new();
        let mut attempt = 0;
        loop {
            attempt += 1;
            if std::fs::symlink_metadata(&self.dest).is_ok() {
                let old = parent.join(hidden_name(&name, "old"));
                match std::fs::rename(&self.dest, &old) {
                    Ok(()) => {
                        carry_nested_results(&old, &self.staging);
                        olds.push(old);
                    }
                    // A concurrent run moved it away first.
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                    Err(e) => {
                        return Err(e).with_context(|| format!("cannot move the old {} aside", self.dest.display()))
                    }
                }
            }
            match std::fs::rename(&self.staging, &self.dest) {
                Ok(()) => break,
                // A concurrent run put its result in place between our renames: move that aside too.
                Err(_) if attempt < COMMIT_ATTEMPTS && std::fs::symlink_metadata(&self.dest).is_ok() => continue,
                Err(e) => {
                    // Put the old result back if nothing took its place.
                    if let Some(old) = olds.pop() {
                        let _ = std::fs::rename(&old, &self.dest);
                    }
                    for old in &olds {
                        let _ = std::fs::remove_dir_all(old);
                    }
                    return Err(e).with_context(|| {
                        format!("cannot move {} into place as {}", self.staging.display(), self.dest.display())
                    });
                }
            }
        }
        self.committed = true;
        for old in &olds {
            let _ = std::fs::remove_dir_all(old);
        }
        remove_stale(&parent, &name);
        Ok(())
    }
}

impl Drop for ResultDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
            remove_created(&self.created);
        }
    }
}

/// Remove directories we created (deepest first) if they are still empty.
fn remove_created(created: &[PathBuf]) {
    for dir in created.iter().rev() {
        let _ = std::fs::remove_dir(dir);
    }
}

/// True when `dir` is another command's whole result (it holds
/// `summary.json` or `fixed-time.json`) or, `depth` levels down, contains
/// one (`results/montecarlo/<scenario>/`).
fn holds_result(dir: &Path, depth: usize) -> bool {
    if !dir.is_dir() {
        return false;
    }
    if dir.join("summary.json").is_file() || dir.join("fixed-time.json").is_file() {
        return true;
    }
    depth > 0 && std::fs::read_dir(dir).is_ok_and(|rd| rd.flatten().any(|e| holds_result(&e.path(), depth - 1)))
}

/// Move sub-folders of `old` that hold another command's whole result (see
/// [`holds_result`]) and that `new` lacks into `new`.
fn carry_nested_results(old: &Path, new: &Path) {
    let Ok(entries) = std::fs::read_dir(old) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        let is_result = holds_result(&path, 1);
        let target = new.join(entry.file_name());
        if is_result && std::fs::symlink_metadata(&target).is_err() {
            let _ = std::fs::rename(&path, &target);
        }
    }
}

/// Delete `.<name>.tmp-*` / `.<name>.old-*` folders in `parent` older than
/// [`STALE_AFTER`] whose process is gone (left by a killed run).
fn remove_stale(parent: &Path, name: &std::ffi::OsStr) {
    let Ok(entries) = std::fs::read_dir(parent) else { return };
    let name = name.to_string_lossy();
    let prefixes = [format!(".{name}.tmp-"), format!(".{name}.old-")];
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let file_name = file_name.to_string_lossy();
        let Some(rest) = prefixes.iter().find_map(|p| file_name.strip_prefix(p.as_str())) else { continue };
        // A long run's staging folder can be old while it is still flying:
        // keep it while its process (`<pid>-<nanos>`) is alive (Linux /proc).
        let pid = rest.split('-').next().unwrap_or("");
        if !pid.is_empty() && Path::new("/proc").join(pid).exists() {
            continue;
        }
        let old_enough = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age >= STALE_AFTER);
        if old_enough && entry.path().is_dir() {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// Write `bytes` to `path`, creating its parent folders; a partly written
/// file (disk full) is removed before the error is returned.
fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).with_context(|| format!("cannot create directory {}", parent.display()))?;
    }
    if let Err(e) = std::fs::write(path, bytes) {
        let _ = std::fs::remove_file(path);
        return Err(e).with_context(|| format!("cannot write {}", path.display()));
    }
    Ok(())
}

/// Write `bytes` to `path` (temporary file + rename). Commands write inside
/// a [`ResultDir`] staging folder, which is what makes results whole; this
/// only keeps a single file from being seen half-written. The temporary
/// file is removed when writing fails.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    write_file(&tmp, bytes)?;
    if let Err(e) = std::fs::rename(&tmp, path) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e).with_context(|| format!("cannot rename {} to {}", tmp.display(), path.display()));
    }
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

/// The time series of a run as CSV text (header = column names; see
/// [`Recording::write_csv`] and docs/outputs.md).
pub fn recording_csv(rec: &Recording) -> Vec<u8> {
    rec.to_csv()
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
    p.insert("command_line".into(), json!(std::env::args().collect::<Vec<_>>()));
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

/// SHA-256 (FIPS 180-4) of `data` as lowercase hex.
pub fn sha256_hex(data: &[u8]) -> String {
    const K: [u32; 64] = [
        0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5, 0xd807aa98,
        0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786,
        0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8,
        0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13,
        0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819,
        0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a,
        0x5b9cca4f, 0x682e6ff3, 0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
        0xc67178f2,
    ];
    let mut h: [u32; 8] =
        [0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19];
    let mut msg = data.to_vec();
    let bits = (data.len() as u64).wrapping_mul(8);
    msg.push(0x80);
    while msg.len() % 64 != 56 {
        msg.push(0);
    }
    msg.extend_from_slice(&bits.to_be_bytes());
    for block in msg.chunks_exact(64) {
        let mut w = [0u32; 64];
        for (i, word) in block.chunks_exact(4).enumerate() {
            w[i] = u32::from_be_bytes([word[0], word[1], word[2], word[3]]);
        }
        for i in 16..64 {
            let s0 = w[i - 15].rotate_right(7) ^ w[i - 15].rotate_right(18) ^ (w[i - 15] >> 3);
            let s1 = w[i - 2].rotate_right(17) ^ w[i - 2].rotate_right(19) ^ (w[i - 2] >> 10);
            w[i] = w[i - 16].wrapping_add(s0).wrapping_add(w[i - 7]).wrapping_add(s1);
        }
        let [mut a, mut b, mut c, mut d, mut e, mut f, mut g, mut hh] = h;
        for i in 0..64 {
            let s1 = e.rotate_right(6) ^ e.rotate_right(11) ^ e.rotate_right(25);
            let ch = (e & f) ^ (!e & g);
            let t1 = hh.wrapping_add(s1).wrapping_add(ch).wrapping_add(K[i]).wrapping_add(w[i]);
            let s0 = a.rotate_right(2) ^ a.rotate_right(13) ^ a.rotate_right(22);
            let maj = (a & b) ^ (a & c) ^ (b & c);
            let t2 = s0.wrapping_add(maj);
            hh = g;
            g = f;
            f = e;
            e = d.wrapping_add(t1);
            d = c;
            c = b;
            b = a;
            a = t1.wrapping_add(t2);
        }
        for (x, y) in h.iter_mut().zip([a, b, c, d, e, f, g, hh]) {
            *x = x.wrapping_add(y);
        }
    }
    h.iter().map(|x| format!("{x:08x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("ftsmc-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Names in `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn a_failed_write_removes_the_staging_folder_and_keeps_the_old_result() {
        let root = temp("fail");
        let dest = root.join("res");
        std::fs::create_dir_all(&dest).unwrap();
        std::fs::write(dest.join("old.csv"), "old").unwrap();
        {
            let dir = ResultDir::begin(&dest).unwrap();
            dir.write("a.csv", b"1,2\n").unwrap();
            // Fails midway, like a full disk: `a.csv` is a file, not a folder.
            assert!(dir.write("a.csv/b.csv", b"x").is_err());
            assert_eq!(names(&root).len(), 2, "staging exists while writing: {:?}", names(&root));
        }
        assert_eq!(names(&root), ["res"], "staging folder left behind");
        assert_eq!(names(&dest), ["old.csv"]);
        std::fs::remove_dir_all(&root).ok();
    }

    #[test]
    fn a_failed_transaction_removes_the_folders_it_created() {
        let root = temp("created");
        let dest = root.join("a/b/res");
        drop(ResultDir::begin(&dest).unwrap());
        assert!(names(&root).is_empty(), "{:?}", names(&root));
        std::fs::remove_dir_all(&root).ok();
    }

    #[test]
    fn commit_replaces_the_whole_folder_but_keeps_nested_results_of_other_commands() {
        let root = temp("commit");
        let dest = root.join("res");
        std::fs::create_dir_all(dest.join("montecarlo/paper-scenario-2")).unwrap();
        std::fs::create_dir_all(dest.join("paper-scenario-1")).unwrap();
        std::fs::write(dest.join("montecarlo/paper-scenario-2/summary.json"), "{}").unwrap();
        std::fs::write(dest.join("junk.csv"), "stale").unwrap();
        std::fs::write(dest.join("paper-scenario-1/stale.csv"), "stale").unwrap();
        let dir = ResultDir::begin(&dest).unwrap();
        dir.write("paper-scenario-1/new.csv", b"new").unwrap();
        dir.write("summary.json", b"{}").unwrap();
        dir.commit().unwrap();
        assert_eq!(names(&root), ["res"], "no staging or old folder left");
        assert_eq!(names(&dest), ["montecarlo", "paper-scenario-1", "summary.json"]);
        assert_eq!(names(&dest.join("paper-scenario-1")), ["new.csv"]);
        std::fs::remove_dir_all(&root).ok();
    }

    #[test]
    fn a_destination_under_a_regular_file_is_refused_and_nothing_is_written() {
        let root = temp("refuse");
        std::fs::write(root.join("file"), "x").unwrap();
        let err = ResultDir::begin(&root.join("file/sub/res")).unwrap_err().to_string();
        assert!(err.contains("is not a directory"), "{err}");
        assert!(ResultDir::begin(&root.join("file")).is_err(), "an existing file as destination");
        assert!(ResultDir::begin(Path::new(".")).is_err());
        assert_eq!(names(&root), ["file"]);
        std::fs::remove_dir_all(&root).ok();
    }

    #[test]
    fn stale_staging_folders_of_a_killed_run_are_removed_by_the_next_commit() {
        let root = temp("stale");
        let stale = root.join(".res.tmp-4194305-1"); // above Linux pid_max
        let fresh = root.join(".res.tmp-4194305-2");
        let other = root.join(".other.tmp-4194305-1");
        for d in [&stale, &fresh, &other] {
            std::fs::create_dir_all(d).unwrap();
            std::fs::write(d.join("x.csv"), "partial").unwrap();
        }
        let two_hours_ago = SystemTime::now() - Duration::from_secs(7200);
        for d in [&stale, &other] {
            std::fs::File::open(d).unwrap().set_modified(two_hours_ago).unwrap();
        }
        let dir = ResultDir::begin(&root.join("res")).unwrap();
        dir.write("summary.json", b"{}").unwrap();
        dir.commit().unwrap();
        // The stale one goes; a fresh one may belong to a concurrent run,
        // and another destination's is not ours to touch.
        assert_eq!(names(&root), [".other.tmp-4194305-1", ".res.tmp-4194305-2", "res"]);
        // An old staging folder of a live process (a long run) stays.
        let live = root.join(format!(".res.tmp-{}-3", std::process::id()));
        std::fs::create_dir_all(&live).unwrap();
        std::fs::File::open(&live).unwrap().set_modified(two_hours_ago).unwrap();
        ResultDir::begin(&root.join("res")).unwrap().commit().unwrap();
        assert!(live.exists());
        std::fs::remove_dir_all(&root).ok();
    }

    #[test]
    fn sha256_matches_the_standard_test_vectors() {
        assert_eq!(sha256_hex(b""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
        assert_eq!(sha256_hex(b"abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
        assert_eq!(
            sha256_hex(b"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"
        );
        assert_eq!(sha256_hex(&[b'a'; 1000]), "41edece42d63e8d9bf515a9ba6932e1c20cbc9f5a5d134645adb5db1b9737ea3");
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
