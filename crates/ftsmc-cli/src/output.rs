//! Output files: whole result folders ([`ResultDir`]), per-run CSV time
//! series and the JSON summary.
//!
//! # Result folders are whole, and hold only what each command owns
//!
//! Every command writes its results into a *staging* folder beside the
//! destination, `.<name>.tmp-<pid>-<nanos>` (hidden, unique per process and
//! start time), and only when every file is complete swaps it into place:
//! the old destination (if any) is renamed to `.<name>.old-<pid>-<nanos>`,
//! every entry of it that this command does not own is moved into the
//! staging folder, the staging folder is renamed to the destination, and
//! what is left of the old folder is deleted. A reader therefore sees the
//! whole old result or the whole new one, never a mix. (Between the two
//! renames — microseconds — the destination does not exist at all.)
//!
//! **Ownership.** Each command (`owner`: `reproduce`, `run`, `montecarlo`,
//! `fixed-time`, …) records the files it wrote in a manifest in the result
//! folder, `.ftsmc-<owner>.manifest` (one path per line, relative to the
//! folder, `/`-separated). At the next commit by the same owner into the
//! same folder, the files of its old manifest that the new result does not
//! write again are deleted (so no file of an older run survives beside the
//! new ones); the files the new result writes replace those of the same
//! name, whoever wrote them; **every other file is kept** — the user's own
//! files, another command's results (`ftsmc run X` and `ftsmc montecarlo X`
//! into one `--out` keep each other's CSVs), and files of a folder written
//! before manifests existed. ftsmc therefore never deletes a file it did
//! not write, except by writing a file of the same name. A command that
//! replaces a file another command's manifest lists is told so on stderr,
//! and the file leaves that manifest (it belongs to the last writer alone,
//! so the other command's next run cannot delete it).
//!
//! On every error path (a flight fails, a write fails — disk full included
//! — or a figure cannot be rendered) the staging folder is removed by a drop
//! guard, and directories created only for it are removed again; a commit
//! that fails after moving kept entries into the staging folder moves them
//! back first.
//!
//! The destination is checked before any flight: the nearest existing
//! ancestor must be a directory and the staging folder must be creatable
//! in it, so a bad `--out` is refused before any work.
//!
//! **Concurrency** (unique names, no lock): two runs into the same folder
//! each write their own staging folder; each commit is a rename swap that
//! carries the other owners' files along, so for one owner the run that
//! finishes last wins and its files are exactly its whole output — never
//! one run's CSV beside the other's summary. A run killed with SIGKILL
//! leaves only a hidden `.<name>.tmp-…` (or, if killed between the two
//! renames, `.<name>.old-…`) folder beside the destination; the next
//! successful run into the same destination cleans up such leftovers older
//! than [`STALE_AFTER`] whose process no longer exists (on Linux; elsewhere
//! the age alone decides) — but only the files ftsmc provably wrote: a
//! staging folder carries a marker ([`STAGING_MARKER`], naming its command)
//! until it is renamed into place, so one without it is never touched; in a
//! staging folder killed while committing, only its manifest's files go;
//! in an old folder, only the files its manifests list. Anything else (your
//! files, caught mid-move by the kill) stays where it is and the run says
//! so on stderr. The same rule removes the old folder after a commit, so a
//! file that could not be moved into the new result is kept, not deleted.

use std::collections::HashSet;
use std::ffi::OsString;
use std::io::Write as _;
use std::path::{Component, Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use anyhow::{bail, Context, Result};
use ftsmc_sim::run::{Recording, RunOutput};
use serde_json::{json, Map, Value};

/// Leftover staging / old folders older than this are deleted by the next
/// successful run into the same destination.
pub const STALE_AFTER: Duration = Duration::from_secs(3600);

/// The marker file of a staging folder, holding the name of the command
/// writing it: present from [`ResultDir::begin`] until the folder is renamed
/// into place. A leftover folder is cleaned only when it has it.
pub const STAGING_MARKER: &str = ".ftsmc-staging";

/// How often a commit retries when a concurrent run puts a folder back in
/// place between our two renames.
const COMMIT_ATTEMPTS: usize = 100;

/// A result folder being written: files go into a hidden staging folder
/// beside `dest`; [`ResultDir::commit`] swaps it into place; dropping it
/// uncommitted removes the staging folder.
#[derive(Debug)]
pub struct ResultDir {
    dest: PathBuf,
    /// The command writing this result; names its manifest.
    owner: String,
    staging: PathBuf,
    /// Directories created for the staging folder (deepest last), removed
    /// again if they are still empty when the transaction fails.
    created: Vec<PathBuf>,
    committed: bool,
    /// Once a commit has started: the files of the result (relative to the
    /// staging folder). Entries of the old folder are moved in beside them,
    /// so from then on only these (and the manifest) are ours to delete.
    written: Option<HashSet<String>>,
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
    /// Start a result folder for `dest`, written by the command `owner`
    /// (`run`, `montecarlo`, …: names its manifest, see the module docs):
    /// check it can be written and create the staging folder. Call before
    /// doing any work.
    pub fn begin(dest: &Path, owner: &str) -> Result<Self> {
        if owner.is_empty() || !owner.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') {
            bail!("internal: result owner `{owner}` must be a plain name");
        }
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
        let dir = Self {
            dest: dest.to_path_buf(),
            owner: owner.to_string(),
            staging,
            created,
            committed: false,
            written: None,
        };
        // On failure `dir` is dropped: the staging folder and the folders
        // created for it go again.
        write_file(&dir.staging.join(STAGING_MARKER), format!("{owner}\n").as_bytes())
            .with_context(|| format!("cannot write to `{}`", dest.display()))?;
        Ok(dir)
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

    /// Swap the staging folder into place, keeping every file of the old
    /// folder this owner does not own (see the module docs).
    pub fn commit(mut self) -> Result<()> {
        let parent = self.staging.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."));
        let name = self.dest.file_name().map(ToOwned::to_owned).unwrap_or_default();
        let manifest_name = manifest_file(&self.owner);
        // The manifest lists what this result wrote: every file in staging
        // but the marker.
        let mut written = Vec::new();
        list_files(&self.staging, "", &mut written);
        written.retain(|f| f != STAGING_MARKER);
        written.sort();
        let mut text = String::new();
        for f in &written {
            text.push_str(f);
            text.push('\n');
        }
        write_file(&self.staging.join(&manifest_name), text.as_bytes())?;
        let written: HashSet<String> = written.into_iter().collect();
        // From here on the old folder's entries join the staging folder:
        // an error path deletes only the result's own files.
        self.written = Some(written.clone());
        let mut olds = Vec::new();
        // Entries moved from an old folder into staging: (from, to).
        let mut carried: Vec<(PathBuf, PathBuf)> = Vec::new();
        let mut attempt = 0;
        loop {
            attempt += 1;
            if std::fs::symlink_metadata(&self.dest).is_ok() {
                let old = parent.join(hidden_name(&name, "old"));
                match std::fs::rename(&self.dest, &old) {
                    Ok(()) => {
                        let owned = read_manifest(&old.join(&manifest_name));
                        warn_replaced(&old, &self.owner, &written, &self.dest);
                        carry_unowned(&old, &self.staging, "", &owned, &manifest_name, &mut carried);
                        olds.push(old);
                    }
                    // A concurrent run moved it away first.
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                    Err(e) => {
                        undo_carries(&carried);
                        return Err(e).with_context(|| format!("cannot move the old {} aside", self.dest.display()));
                    }
                }
            }
            // The marker must not reach the destination. Without it a
            // staging folder left by a kill from here on is never cleaned
            // (it may hold files carried from the old folder).
            let _ = std::fs::remove_file(self.staging.join(STAGING_MARKER));
            match std::fs::rename(&self.staging, &self.dest) {
                Ok(()) => break,
                // A concurrent run put its result in place between our renames: move that aside too.
                Err(_) if attempt < COMMIT_ATTEMPTS && std::fs::symlink_metadata(&self.dest).is_ok() => continue,
                Err(e) => {
                    // Give the kept files back, then put the old result back
                    // if nothing took its place.
                    undo_carries(&carried);
                    if let Some(old) = olds.pop() {
                        let _ = std::fs::rename(&old, &self.dest);
                    }
                    // Results of concurrent runs moved aside: nothing of
                    // ours replaced them, so only their own files go.
                    for old in &olds {
                        remove_old(old, &HashSet::new(), &self.dest);
                    }
                    return Err(e).with_context(|| {
                        format!("cannot move {} into place as {}", self.staging.display(), self.dest.display())
                    });
                }
            }
        }
        self.committed = true;
        for old in &olds {
            remove_old(old, &written, &self.dest);
        }
        remove_stale(&parent, &name, &self.dest);
        disown_replaced(&self.dest, &self.owner, &written);
        Ok(())
    }
}

/// Write a whole result folder in one call: `files` (paths relative to
/// `dest`, `/`-separated, with their bytes) are written into a staging
/// folder and committed as the result of the command `owner` (see the
/// module docs: the owner's older files in `dest` are replaced, every other
/// file is kept). Nothing is written when any file fails.
#[cfg_attr(not(test), allow(dead_code))] // the API `ftsmc merge` writes through
pub fn write_result(dest: &Path, owner: &str, files: &[(&str, &[u8])]) -> Result<()> {
    let dir = ResultDir::begin(dest, owner)?;
    for (rel, bytes) in files {
        let rel_path = Path::new(rel);
        if rel_path.components().any(|c| !matches!(c, Component::Normal(_))) || rel.is_empty() {
            bail!("result file `{rel}` must be a relative path inside `{}`", dest.display());
        }
        dir.write(rel_path, bytes)?;
    }
    dir.commit()
}

/// The manifest file name of `owner`: `.ftsmc-<owner>.manifest`.
pub fn manifest_file(owner: &str) -> String {
    format!(".ftsmc-{owner}.manifest")
}

/// The relative paths a manifest lists (empty when it is missing).
fn read_manifest(path: &Path) -> HashSet<String> {
    std::fs::read_to_string(path)
        .map(|t| t.lines().filter(|l| !l.is_empty()).map(str::to_string).collect())
        .unwrap_or_default()
}

/// Every regular file (and symlink) below `dir`, as `/`-separated paths
/// relative to it, prefixed with `prefix`.
fn list_files(dir: &Path, prefix: &str, out: &mut Vec<String>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let rel = format!("{prefix}{}", entry.file_name().to_string_lossy());
        match entry.file_type() {
            Ok(t) if t.is_dir() => list_files(&entry.path(), &format!("{rel}/"), out),
            _ => out.push(rel),
        }
    }
}

/// The other commands' manifests that concern the result in `dest`:
/// `(command, manifest path, prefix)` for each `.ftsmc-<command>.manifest`
/// in `folder` (prefix "", the owner's own manifest skipped) and in
/// `dest`'s parent folder (prefix `<dest name>/`: `ftsmc run
/// paper-scenario-1` after `ftsmc reproduce` replaces CSVs that `reproduce`
/// lists there).
fn other_manifests(folder: &Path, dest: &Path, owner: &str) -> Vec<(String, PathBuf, String)> {
    let name = dest.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let parent = dest.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut found = Vec::new();
    for (dir, prefix) in [(folder, String::new()), (parent, format!("{name}/"))] {
        let Ok(entries) = std::fs::read_dir(dir) else { continue };
        for entry in entries.flatten() {
            let file_name = entry.file_name().to_string_lossy().into_owned();
            let Some(other) = file_name.strip_prefix(".ftsmc-").and_then(|r| r.strip_suffix(".manifest")) else {
                continue;
            };
            if other == owner && prefix.is_empty() {
                continue;
            }
            found.push((other.to_string(), entry.path(), prefix.clone()));
        }
    }
    found
}

/// Tell the user when this result replaces files another command's
/// manifest (in `old`, or in the parent folder) lists.
fn warn_replaced(old: &Path, owner: &str, written: &HashSet<String>, dest: &Path) {
    for (other, manifest, prefix) in other_manifests(old, dest, owner) {
        let mut replaced: Vec<String> = read_manifest(&manifest)
            .into_iter()
            .filter_map(|f| f.strip_prefix(prefix.as_str()).map(str::to_string))
            .filter(|f| written.contains(f))
            .collect();
        if !replaced.is_empty() {
            replaced.sort();
            eprintln!(
                "note: replaced {} in {} written by `ftsmc {other}` (its other files are kept)",
                replaced.join(", "),
                dest.display()
            );
        }
    }
}

/// Remove the files this result wrote (`written`, relative to `dest`) from
/// every other command's manifest, in `dest` and in its parent folder
/// (prefixed with the destination's name): the file now belongs to `owner`
/// alone, so the other command's next commit, if it no longer writes that
/// name, does not delete a file it did not write last. Best effort: a
/// manifest that cannot be rewritten keeps the entry (the file then stays
/// listed twice, never unlisted).
fn disown_replaced(dest: &Path, owner: &str, written: &HashSet<String>) {
    for (_, manifest, prefix) in other_manifests(dest, dest, owner) {
        let Ok(text) = std::fs::read_to_string(&manifest) else { continue };
        let listed: Vec<&str> = text.lines().filter(|l| !l.is_empty()).collect();
        let kept: Vec<&str> = listed
            .iter()
            .copied()
            .filter(|l| !l.strip_prefix(prefix.as_str()).is_some_and(|f| written.contains(f)))
            .collect();
        if kept.len() != listed.len() {
            let mut out = kept.join("\n");
            if !out.is_empty() {
                out.push('\n');
            }
            let _ = write_atomic(&manifest, out.as_bytes());
        }
    }
}

/// Move every entry of `old` that the owner does not own (not in `owned`,
/// its manifest) and that `new` does not already hold into `new`,
/// descending into folders both hold and folders holding owned files.
/// Records each move in `carried`.
fn carry_unowned(
    old: &Path,
    new: &Path,
    prefix: &str,
    owned: &HashSet<String>,
    manifest_name: &str,
    carried: &mut Vec<(PathBuf, PathBuf)>,
) {
    let Ok(entries) = std::fs::read_dir(old) else { return };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let rel = format!("{prefix}{}", file_name.to_string_lossy());
        if prefix.is_empty() && file_name.to_string_lossy() == manifest_name {
            continue;
        }
        let path = entry.path();
        let target = new.join(&file_name);
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        let sub_prefix = format!("{rel}/");
        match std::fs::symlink_metadata(&target) {
            // The new result has this name: a file there wins; two folders merge.
            Ok(meta) => {
                if is_dir && meta.is_dir() {
                    carry_unowned(&path, &target, &sub_prefix, owned, manifest_name, carried);
                }
            }
            Err(_) => {
                if is_dir && owned.iter().any(|f| f.starts_with(&sub_prefix)) {
                    if std::fs::create_dir(&target).is_ok() {
                        carry_unowned(&path, &target, &sub_prefix, owned, manifest_name, carried);
                        // Nothing kept in it: it held only our old files.
                        let _ = std::fs::remove_dir(&target);
                    }
                } else if !owned.contains(&rel) && std::fs::rename(&path, &target).is_ok() {
                    carried.push((path, target));
                }
            }
        }
    }
}

/// Move carried entries back where they came from (latest first).
fn undo_carries(carried: &[(PathBuf, PathBuf)]) {
    for (from, to) in carried.iter().rev() {
        if let Some(p) = from.parent() {
            let _ = std::fs::create_dir_all(p);
        }
        let _ = std::fs::rename(to, from);
    }
}

impl Drop for ResultDir {
    fn drop(&mut self) {
        if !self.committed {
            // A failed commit has moved the old folder's entries back; any
            // it could not move stay, with a note.
            remove_staging(&self.staging, &self.owner, self.written.as_ref(), &self.dest);
            remove_created(&self.created);
        }
    }
}

/// Remove the staging folder `staging` of the command `owner` for a result
/// into `dest`: whole before its commit started (`written` `None`: all of
/// it is the result's), else only the result's files `written`, its
/// manifest and its marker, with a note naming what is kept (entries of
/// the old folder moved in).
fn remove_staging(staging: &Path, owner: &str, written: Option<&HashSet<String>>, dest: &Path) {
    match written {
        None => {
            let _ = std::fs::remove_dir_all(staging);
        }
        Some(written) => {
            let manifest = manifest_file(owner);
            let ours = |rel: &str| written.contains(rel) || rel == manifest || rel == STAGING_MARKER;
            let kept = remove_ours(staging, &ours);
            warn_kept(staging, &kept, dest);
        }
    }
}

/// Delete the files of `folder` for which `ours(relative path)` holds, then
/// the sub-folders that held them once empty (deepest first; an empty
/// folder of someone else's stays), and `folder` itself if empty. Returns
/// the files kept, relative to `folder`, sorted.
fn remove_ours(folder: &Path, ours: &dyn Fn(&str) -> bool) -> Vec<String> {
    let mut files = Vec::new();
    list_files(folder, "", &mut files);
    let mut kept: Vec<String> = Vec::new();
    let mut emptied: Vec<PathBuf> = Vec::new();
    for f in files {
        if ours(&f) {
            let _ = std::fs::remove_file(folder.join(&f));
            let mut dir = Path::new(&f).parent();
            while let Some(d) = dir.filter(|d| !d.as_os_str().is_empty()) {
                emptied.push(d.to_path_buf());
                dir = d.parent();
            }
        } else {
            kept.push(f);
        }
    }
    // Deepest first: a folder goes only once everything below it has.
    emptied.sort_by(|a, b| b.components().count().cmp(&a.components().count()).then_with(|| a.cmp(b)));
    emptied.dedup();
    for d in &emptied {
        let _ = std::fs::remove_dir(folder.join(d));
    }
    let _ = std::fs::remove_dir(folder);
    kept.sort();
    kept
}

/// Tell the user that `folder` was kept because it still holds `kept`,
/// files ftsmc did not write (a leftover of a run into `dest`).
fn warn_kept(folder: &Path, kept: &[String], dest: &Path) {
    if kept.is_empty() {
        return;
    }
    let shown: Vec<&str> = kept.iter().take(3).map(String::as_str).collect();
    let more = if kept.len() > 3 { format!(" and {} more", kept.len() - 3) } else { String::new() };
    eprintln!(
        "note: kept {}: it holds {} file(s) ftsmc did not write ({}{more}), left there by an interrupted run into {}; \
         move them where you want them and delete the folder",
        folder.display(),
        kept.len(),
        shown.join(", "),
        dest.display()
    );
}

/// The files of an old result folder that ftsmc wrote: those its manifests
/// (`.ftsmc-<command>.manifest` at its top) list, and the manifests.
fn old_result_files(old: &Path) -> HashSet<String> {
    let mut ours = HashSet::new();
    let Ok(entries) = std::fs::read_dir(old) else { return ours };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with(".ftsmc-") && name.ends_with(".manifest") {
            ours.extend(read_manifest(&entry.path()));
            ours.insert(name);
        }
    }
    ours
}

/// Remove the old result folder `old`: the files its manifests list and
/// those a new result (`written`, empty when none of ours replaced it)
/// replaced by name; anything else (an entry that could not be moved into
/// the new result, or that a kill caught before its move) is kept, with a
/// note.
fn remove_old(old: &Path, written: &HashSet<String>, dest: &Path) {
    let ours = old_result_files(old);
    let kept = remove_ours(old, &|rel: &str| ours.contains(rel) || written.contains(rel));
    warn_kept(old, &kept, dest);
}

/// Remove directories we created (deepest first) if they are still empty.
fn remove_created(created: &[PathBuf]) {
    for dir in created.iter().rev() {
        let _ = std::fs::remove_dir(dir);
    }
}

/// Clean up the `.<name>.tmp-*` / `.<name>.old-*` folders in `parent`
/// older than [`STALE_AFTER`] whose process is gone (left by a killed run
/// into `dest`), deleting only files ftsmc wrote:
/// - a staging folder with its [`STAGING_MARKER`] and no manifest of its
///   command was killed before committing: all of it is the result's;
/// - one with its marker and its manifest was killed while moving the old
///   folder's entries in: only the manifest's files (and the manifest and
///   marker) go;
/// - one without the marker is not touched (not ours, or past the marker's
///   removal just before the final rename);
/// - an old folder loses the files its manifests list.
///
/// What is kept is reported on stderr.
fn remove_stale(parent: &Path, name: &std::ffi::OsStr, dest: &Path) {
    let Ok(entries) = std::fs::read_dir(parent) else { return };
    let name = name.to_string_lossy();
    let (tmp, old) = (format!(".{name}.tmp-"), format!(".{name}.old-"));
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let file_name = file_name.to_string_lossy();
        let (rest, staging) = match (file_name.strip_prefix(tmp.as_str()), file_name.strip_prefix(old.as_str())) {
            (Some(rest), _) => (rest, true),
            (None, Some(rest)) => (rest, false),
            (None, None) => continue,
        };
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
        let folder = entry.path();
        if !old_enough || !entry.file_type().is_ok_and(|t| t.is_dir()) {
            continue;
        }
        if staging {
            let Ok(owner) = std::fs::read_to_string(folder.join(STAGING_MARKER)) else { continue };
            let owner = owner.trim();
            // Its manifest is written when the commit starts.
            let manifest = folder.join(manifest_file(owner));
            let listed = std::fs::symlink_metadata(&manifest).is_ok().then(|| read_manifest(&manifest));
            remove_staging(&folder, owner, listed.as_ref(), dest);
        } else {
            remove_old(&folder, &HashSet::new(), dest);
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
    fn a_failed_write_removes_the_staging_folder_and_keeps_the_old_result() {
        let tmp = temp("fail");
        let root = tmp.path();
        let dest = root.join("res");
        std::fs::create_dir_all(&dest).unwrap();
        std::fs::write(dest.join("old.csv"), "old").unwrap();
        {
            let dir = ResultDir::begin(&dest, "run").unwrap();
            dir.write("a.csv", b"1,2\n").unwrap();
            // Fails midway, like a full disk: `a.csv` is a file, not a folder.
            assert!(dir.write("a.csv/b.csv", b"x").is_err());
            assert_eq!(names(root).len(), 2, "staging exists while writing: {:?}", names(root));
        }
        assert_eq!(names(root), ["res"], "staging folder left behind");
        assert_eq!(names(&dest), ["old.csv"]);
    }

    #[test]
    fn a_failed_transaction_removes_the_folders_it_created() {
        let tmp = temp("created");
        let root = tmp.path();
        let dest = root.join("a/b/res");
        drop(ResultDir::begin(&dest, "run").unwrap());
        assert!(names(root).is_empty(), "{:?}", names(root));
    }

    #[test]
    fn a_file_another_command_replaced_is_no_longer_the_first_commands_to_delete() {
        let tmp = temp("disown");
        let root = tmp.path();
        let dest = root.join("res").join("scen");
        // `run` writes summary.json and its CSV; `montecarlo` then replaces summary.json.
        write_result(&dest, "run", &[("summary.json", b"run"), ("pid.csv", b"csv")]).unwrap();
        write_result(&dest, "montecarlo", &[("summary.json", b"mc"), ("runs.csv", b"rows")]).unwrap();
        assert_eq!(std::fs::read_to_string(dest.join(".ftsmc-run.manifest")).unwrap(), "pid.csv\n");
        // A later `run` that no longer writes summary.json must not delete montecarlo's.
        write_result(&dest, "run", &[("pid.csv", b"csv2")]).unwrap();
        assert_eq!(std::fs::read_to_string(dest.join("summary.json")).unwrap(), "mc");
        assert_eq!(std::fs::read_to_string(dest.join("runs.csv")).unwrap(), "rows");
        // The parent's manifest too: `reproduce` listed scen/pid.csv, `run` replaced it.
        let parent = root.join("res");
        std::fs::write(parent.join(".ftsmc-reproduce.manifest"), "scen/pid.csv\nsummary.json\n").unwrap();
        write_result(&dest, "run", &[("pid.csv", b"csv3")]).unwrap();
        assert_eq!(std::fs::read_to_string(parent.join(".ftsmc-reproduce.manifest")).unwrap(), "summary.json\n");
    }

    #[test]
    fn commit_replaces_the_owners_files_and_keeps_every_other_file() {
        let tmp = temp("commit");
        let root = tmp.path();
        let dest = root.join("res");
        std::fs::create_dir_all(dest.join("montecarlo/paper-scenario-2")).unwrap();
        std::fs::write(dest.join("montecarlo/paper-scenario-2/summary.json"), "{}").unwrap();
        std::fs::write(dest.join("notes.txt"), "mine").unwrap();
        // A first result of `reproduce`.
        let dir = ResultDir::begin(&dest, "reproduce").unwrap();
        dir.write("paper-scenario-1/old.csv", b"old").unwrap();
        dir.write("paper-scenario-1/both.csv", b"old").unwrap();
        dir.write("figures/a.svg", b"old").unwrap();
        dir.write("summary.json", b"{1}").unwrap();
        dir.commit().unwrap();
        // The user adds a file inside a folder reproduce writes.
        std::fs::write(dest.join("paper-scenario-1/mine.csv"), "mine").unwrap();
        // A second result of `reproduce` no longer writes old.csv nor figures/.
        let dir = ResultDir::begin(&dest, "reproduce").unwrap();
        dir.write("paper-scenario-1/both.csv", b"new").unwrap();
        dir.write("summary.json", b"{2}").unwrap();
        dir.commit().unwrap();
        assert_eq!(names(root), ["res"], "no staging or old folder left");
        assert_eq!(
            names(&dest),
            [".ftsmc-reproduce.manifest", "montecarlo", "notes.txt", "paper-scenario-1", "summary.json"]
        );
        assert_eq!(names(&dest.join("paper-scenario-1")), ["both.csv", "mine.csv"]);
        assert_eq!(std::fs::read_to_string(dest.join("paper-scenario-1/both.csv")).unwrap(), "new");
        assert_eq!(std::fs::read_to_string(dest.join("notes.txt")).unwrap(), "mine");
        assert_eq!(
            std::fs::read_to_string(dest.join(".ftsmc-reproduce.manifest")).unwrap(),
            "paper-scenario-1/both.csv\nsummary.json\n"
        );
        // Another owner into the same folder keeps reproduce's files.
        write_result(&dest, "merge", &[("merged.csv", b"m")]).unwrap();
        assert!(dest.join("paper-scenario-1/both.csv").is_file() && dest.join("summary.json").is_file());
        assert!(dest.join("merged.csv").is_file() && dest.join(".ftsmc-merge.manifest").is_file());
        assert!(write_result(&dest, "merge", &[("../escape.csv", b"m")]).is_err());
        assert!(!root.join("escape.csv").exists());
    }

    #[test]
    fn a_destination_under_a_regular_file_is_refused_and_nothing_is_written() {
        let tmp = temp("refuse");
        let root = tmp.path();
        std::fs::write(root.join("file"), "x").unwrap();
        let err = ResultDir::begin(&root.join("file/sub/res"), "run").unwrap_err().to_string();
        assert!(err.contains("is not a directory"), "{err}");
        assert!(ResultDir::begin(&root.join("file"), "run").is_err(), "an existing file as destination");
        assert!(ResultDir::begin(Path::new("."), "run").is_err());
        assert_eq!(names(root), ["file"]);
    }

    /// A staging folder as a run killed at that point leaves it: `dir`'s
    /// folder renamed to a dead process's name (a pid above Linux's
    /// `pid_max`) with `tag`, its age set two hours back.
    fn killed(dir: ResultDir, tag: &str) -> PathBuf {
        let staging = dir.path().to_path_buf();
        std::mem::forget(dir);
        let name = staging.file_name().unwrap().to_string_lossy().into_owned();
        let (prefix, _) = name.split_once(".tmp-").unwrap();
        let dead = staging.with_file_name(format!("{prefix}.tmp-4194305-{tag}"));
        std::fs::rename(&staging, &dead).unwrap();
        age(&dead);
        dead
    }

    /// Set `dir`'s modification time two hours back (older than
    /// [`STALE_AFTER`]).
    fn age(dir: &Path) {
        let two_hours_ago = SystemTime::now() - Duration::from_secs(7200);
        std::fs::File::open(dir).unwrap().set_modified(two_hours_ago).unwrap();
    }

    #[test]
    fn stale_staging_folders_of_a_killed_run_are_removed_by_the_next_commit() {
        let tmp = temp("stale");
        let root = tmp.path();
        let dir = ResultDir::begin(&root.join("res"), "run").unwrap();
        dir.write("sub/x.csv", b"partial").unwrap();
        let stale = killed(dir, "1");
        assert!(stale.join(STAGING_MARKER).exists());
        let dir = ResultDir::begin(&root.join("res"), "run").unwrap();
        dir.write("x.csv", b"partial").unwrap();
        let fresh = killed(dir, "2");
        std::fs::File::open(&fresh).unwrap().set_modified(SystemTime::now()).unwrap();
        let dir = ResultDir::begin(&root.join("other"), "run").unwrap();
        let other = killed(dir, "1");
        let dir = ResultDir::begin(&root.join("res"), "run").unwrap();
        dir.write("summary.json", b"{}").unwrap();
        dir.commit().unwrap();
        // The stale one goes; a fresh one may belong to a concurrent run,
        // and another destination's is not ours to touch.
        assert_eq!(names(root), [".other.tmp-4194305-1", ".res.tmp-4194305-2", "res"]);
        assert!(fresh.exists() && other.exists() && !stale.exists());
        // The marker never reaches the result, nor its manifest.
        assert_eq!(names(&root.join("res")), [".ftsmc-run.manifest", "summary.json"]);
        assert_eq!(std::fs::read_to_string(root.join("res/.ftsmc-run.manifest")).unwrap(), "summary.json\n");
        // An old staging folder of a live process (a long run) stays.
        let live = root.join(format!(".res.tmp-{}-3", std::process::id()));
        std::fs::create_dir_all(&live).unwrap();
        std::fs::write(live.join(STAGING_MARKER), "run\n").unwrap();
        age(&live);
        ResultDir::begin(&root.join("res"), "run").unwrap().commit().unwrap();
        assert!(live.exists());
    }

    #[test]
    fn leftovers_are_cleaned_of_ftsmc_files_only() {
        let tmp = temp("leftover");
        let root = tmp.path();
        // A folder named like a staging folder but without the marker: a
        // user's (or past the marker's removal): untouched.
        let foreign = root.join(".res.tmp-4194305-1");
        std::fs::create_dir_all(foreign.join("deep")).unwrap();
        std::fs::write(foreign.join("deep/notes.txt"), "mine").unwrap();
        age(&foreign);
        // A staging folder killed while committing: its manifest's files
        // beside a user's file carried in from the old folder.
        let dir = ResultDir::begin(&root.join("res"), "montecarlo").unwrap();
        dir.write("runs.csv", b"a,b\n").unwrap();
        let mid_commit = killed(dir, "2");
        std::fs::write(mid_commit.join(".ftsmc-montecarlo.manifest"), "runs.csv\n").unwrap();
        std::fs::create_dir_all(mid_commit.join("data")).unwrap();
        std::fs::write(mid_commit.join("data/mine.csv"), "mine").unwrap();
        age(&mid_commit);
        // An old result folder caught mid-move: listed files and a user's.
        let old = root.join(".res.old-4194305-3");
        std::fs::create_dir_all(&old).unwrap();
        std::fs::write(old.join(".ftsmc-run.manifest"), "a.csv\nsub/b.csv\n").unwrap();
        std::fs::write(old.join("a.csv"), "ours").unwrap();
        std::fs::create_dir_all(old.join("sub")).unwrap();
        std::fs::write(old.join("sub/b.csv"), "ours").unwrap();
        std::fs::write(old.join("paper.pdf"), "mine").unwrap();
        std::fs::create_dir_all(old.join("drafts/empty")).unwrap();
        age(&old);
        // And one holding only listed files: removed whole.
        let old_ours = root.join(".res.old-4194305-4");
        std::fs::create_dir_all(&old_ours).unwrap();
        std::fs::write(old_ours.join(".ftsmc-run.manifest"), "a.csv\n").unwrap();
        std::fs::write(old_ours.join("a.csv"), "ours").unwrap();
        age(&old_ours);

        ResultDir::begin(&root.join("res"), "run").unwrap().commit().unwrap();
        assert_eq!(names(root), [".res.old-4194305-3", ".res.tmp-4194305-1", ".res.tmp-4194305-2", "res"]);
        assert_eq!(std::fs::read_to_string(foreign.join("deep/notes.txt")).unwrap(), "mine");
        assert_eq!(names(&mid_commit), ["data"]);
        assert_eq!(std::fs::read_to_string(mid_commit.join("data/mine.csv")).unwrap(), "mine");
        // The sub-folder emptied of listed files goes; the user's empty one stays.
        assert_eq!(names(&old), ["drafts", "paper.pdf"]);
        assert_eq!(names(&old.join("drafts")), ["empty"]);
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
