//! Result folders: written whole or not at all, never deleting a file
//! ftsmc did not write, safe under concurrent runs (docs/outputs.md,
//! "Result folders").
//!
//! 1. [`ResultDir::begin`] checks the destination and creates a hidden
//!    staging folder beside it, `.<name>.tmp-XXXXXX` (a unique name made by
//!    the `tempfile` crate); every file of the result is written there.
//! 2. [`ResultDir::commit`], holding an exclusive lock on the parent folder
//!    (so commits into one parent take turns), builds the whole new folder
//!    in the staging folder: beside the new files it puts a *hard link* to
//!    every entry of the current destination that is kept, and it writes the
//!    manifest `.ftsmc-<owner>.manifest`, one line `<sha256> <size> <path>`
//!    per file of the result (hashed as [`ResultDir::write`] and
//!    [`ResultDir::write_with`] wrote it; a file written by other means,
//!    or changed since, is read back). It then swaps the two folders in one step
//!    (Linux `renameat2(RENAME_EXCHANGE)`; elsewhere two renames).
//! 3. The old folder, now at the staging name, loses what is provably ours
//!    to delete: entries that are the same file as the new folder's (the
//!    hard links), and the files this commit replaced or dropped, if they
//!    still have the size and SHA-256 checked in step 2. Anything else is
//!    kept there, with a note on stderr.
//!
//! **What is kept.** An entry of the destination is replaced or dropped
//! only when a manifest (in the destination, its sub-folders or its parent
//! folder) lists it with its current size and SHA-256: it is a file ftsmc
//! wrote and nobody changed since. Files this owner's old manifest lists
//! that the new result does not write are dropped under the same check;
//! every other entry is kept — the user's files, other commands' results, a
//! listed file that was edited, a name appended to a manifest by hand.
//! When the new result would replace a file that does not pass the check,
//! the commit is refused with an error naming it, and nothing changes.
//!
//! A kill at any point leaves the destination whole (old or new: the swap is
//! one system call) and at most a hidden `.<name>.tmp-…` folder beside it,
//! which the next commit into the same destination names on stderr; ftsmc
//! does not delete it (its files cannot all be proven ftsmc's).

use std::collections::{BTreeMap, BTreeSet};
use std::ffi::OsString;
use std::fs::File;
use std::io::Write;
use std::path::{Component, Path, PathBuf};

use anyhow::{bail, Context, Result};
use sha2::{Digest as _, Sha256};

use crate::bounded_read::{read_limited, MAX_MANIFEST_BYTES};

/// Size and SHA-256 (lowercase hex) of a file ftsmc wrote.
type Stamp = (u64, String);

/// The stamp of a file as [`write_file`] wrote it, hashed on the way, and
/// the file's modification time then: [`ResultDir::commit`] takes the
/// stamp without reading the file again while its size and modification
/// time are still these.
type Hashed = (Stamp, Option<std::time::SystemTime>);

/// A result folder being written: files go into a hidden staging folder
/// beside `dest`; [`ResultDir::commit`] swaps it into place; dropping it
/// uncommitted removes the staging folder.
#[derive(Debug)]
pub struct ResultDir {
    dest: PathBuf,
    /// The command writing this result; names its manifest.
    owner: String,
    staging: PathBuf,
    /// Held (locked) while the staging folder is in use: a staging folder
    /// nobody holds was left by a killed run.
    _lock: Option<File>,
    /// Directories created for the staging folder (deepest last), removed
    /// again if they are still empty when the result is dropped.
    created: Vec<PathBuf>,
    /// The files of the result, once the commit has listed them: from then
    /// on the staging folder also holds links to kept files, and only these
    /// are removed on failure.
    written: Option<BTreeMap<String, Stamp>>,
    /// The files [`ResultDir::write`] and [`ResultDir::write_with`] wrote,
    /// by staging path, with their stamps taken as they were written.
    hashed: std::sync::Mutex<BTreeMap<PathBuf, Hashed>>,
    committed: bool,
}

/// The manifest file name of `owner`: `.ftsmc-<owner>.manifest`.
pub fn manifest_file(owner: &str) -> String {
    format!(".ftsmc-{owner}.manifest")
}

/// SHA-256 of `data` as lowercase hex, as `sha256sum` prints it.
pub fn sha256_hex(data: &[u8]) -> String {
    format!("{:x}", Sha256::digest(data))
}

/// Size and SHA-256 of the regular file `path` (`None` for anything else),
/// read in a stream: results may hold files of any size.
fn stamp(path: &Path) -> Option<Stamp> {
    if !std::fs::symlink_metadata(path).ok()?.is_file() {
        return None;
    }
    let mut hasher = Sha256::new();
    let size = std::io::copy(&mut File::open(path).ok()?, &mut hasher).ok()?;
    Some((size, format!("{:x}", hasher.finalize())))
}

/// What a manifest lists: the files with their stamps, and the lines that
/// are not `<sha256> <size> <path>` (a name added by hand, a manifest of an
/// older ftsmc), which vouch for nothing. A missing manifest lists nothing;
/// one that is not a regular file within [`MAX_MANIFEST_BYTES`] is an error.
fn read_manifest(path: &Path) -> Result<(BTreeMap<String, Stamp>, Vec<String>)> {
    let (mut listed, mut bad) = (BTreeMap::new(), Vec::new());
    if std::fs::symlink_metadata(path).is_err() {
        return Ok((listed, bad));
    }
    let bytes = read_limited(path, MAX_MANIFEST_BYTES, "manifest")?;
    for line in String::from_utf8_lossy(&bytes).lines().filter(|l| !l.is_empty()) {
        let mut parts = line.splitn(3, ' ');
        let (sha, size, rel) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""), parts.next());
        let sha_ok = sha.len() == 64 && sha.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'));
        match (sha_ok, size.parse::<u64>(), rel) {
            (true, Ok(size), Some(rel)) => drop(listed.insert(rel.to_string(), (size, sha.to_string()))),
            _ => bad.push(line.to_string()),
        }
    }
    Ok((listed, bad))
}

/// Every manifest that can vouch for a file of `dest`: those in `dest` and
/// its sub-folders, and those in its parent folder (`ftsmc run` into a
/// folder of `ftsmc reproduce`'s result): `(command, path relative to dest
/// → stamp)`.
fn manifests_for(dest: &Path) -> Result<Vec<(String, BTreeMap<String, Stamp>)>> {
    let mut found = Vec::new();
    let name = dest.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let (mut files, mut dirs) = (Vec::new(), Vec::new());
    walk(dest, "", &mut files, &mut dirs);
    let mut folders = vec![(parent_of(dest), None), (dest.to_path_buf(), Some(String::new()))];
    folders.extend(dirs.into_iter().map(|d| (dest.join(&d), Some(format!("{d}/")))));
    for (dir, prefix) in folders {
        for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let file_name = entry.file_name().to_string_lossy().into_owned();
            let Some(command) = file_name.strip_prefix(".ftsmc-").and_then(|r| r.strip_suffix(".manifest")) else {
                continue;
            };
            let (listed, _) = read_manifest(&entry.path())?;
            let listed = listed.into_iter().filter_map(|(rel, s)| match &prefix {
                Some(p) => Some((format!("{p}{rel}"), s)),
                None => rel.strip_prefix(&format!("{name}/")).map(|r| (r.to_string(), s)),
            });
            found.push((command.to_string(), listed.collect()));
        }
    }
    Ok(found)
}

fn parent_of(dest: &Path) -> PathBuf {
    match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Every non-directory entry below `dir` as `/`-separated relative paths
/// (with `prefix`), and every directory in `dirs`.
fn walk(dir: &Path, prefix: &str, files: &mut Vec<String>, dirs: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let rel = format!("{prefix}{}", entry.file_name().to_string_lossy());
        if entry.file_type().is_ok_and(|t| t.is_dir()) {
            walk(&entry.path(), &format!("{rel}/"), files, dirs);
            dirs.push(rel);
        } else {
            files.push(rel);
        }
    }
}

/// Whether `a` and `b` are the same file (hard links of one inode).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        match (std::fs::symlink_metadata(a), std::fs::symlink_metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (a, b);
        false
    }
}

/// Remove from `folder` what is provably ours to delete: entries that are
/// the same file as `dest`'s entry of that name, and files `ours` lists
/// with their current stamp; then the folders left empty. What is kept is
/// named on stderr.
fn remove_ours(folder: &Path, dest: &Path, ours: &BTreeMap<String, Stamp>) {
    let (mut files, mut dirs) = (Vec::new(), Vec::new());
    walk(folder, "", &mut files, &mut dirs);
    let mut kept = Vec::new();
    for rel in files {
        let path = folder.join(&rel);
        let removable =
            same_file(&path, &dest.join(&rel)) || ours.get(&rel).is_some_and(|s| stamp(&path).as_ref() == Some(s));
        if !(removable && std::fs::remove_file(&path).is_ok()) {
            kept.push(rel);
        }
    }
    // `walk` lists sub-folders before their parents.
    for d in dirs {
        let _ = std::fs::remove_dir(folder.join(d));
    }
    let _ = std::fs::remove_dir(folder);
    kept.sort();
    if !kept.is_empty() {
        eprintln!(
            "note: kept {} beside {}: it holds {} file(s) ftsmc cannot prove it wrote ({}); move them where you want them",
            folder.display(),
            dest.display(),
            kept.len(),
            kept[..kept.len().min(3)].join(", ")
        );
    }
}

/// Swap the folders `a` and `b` (both exist) in one step where the system
/// can (Linux), else by two renames through a third name. Afterwards `b`
/// holds what `a` held; returns where `b`'s old content is.
fn swap(a: &Path, b: &Path) -> std::io::Result<PathBuf> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::ffi::OsStrExt as _;
        let c = |p: &Path| std::ffi::CString::new(p.as_os_str().as_bytes()).map_err(std::io::Error::other);
        let (ca, cb) = (c(a)?, c(b)?);
        // SAFETY: two valid NUL-terminated paths; renameat2 only renames.
        let r = unsafe {
            libc::syscall(
                libc::SYS_renameat2,
                libc::AT_FDCWD,
                ca.as_ptr(),
                libc::AT_FDCWD,
                cb.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        };
        if r == 0 {
            return Ok(a.to_path_buf());
        }
        let e = std::io::Error::last_os_error();
        // Not supported by this kernel or filesystem: fall back below.
        if !matches!(e.raw_os_error(), Some(libc::EINVAL) | Some(libc::ENOSYS) | Some(libc::EOPNOTSUPP)) {
            return Err(e);
        }
    }
    let mut aside = a.as_os_str().to_owned();
    aside.push(".old");
    let aside = PathBuf::from(aside);
    std::fs::rename(b, &aside)?;
    if let Err(e) = std::fs::rename(a, b) {
        let _ = std::fs::rename(&aside, b);
        return Err(e);
    }
    Ok(aside)
}

/// Hold an exclusive lock (`flock`) on `dir` (a directory) while the
/// returned file is open, waiting for it or not; `None` when it is held
/// elsewhere, or where directories cannot be locked (not Unix).
fn lock_dir(dir: &Path, wait: bool) -> Option<File> {
    #[cfg(unix)]
    {
        use std::os::fd::AsRawFd as _;
        let file = File::open(dir).ok()?;
        let op = if wait { libc::LOCK_EX } else { libc::LOCK_EX | libc::LOCK_NB };
        loop {
            // SAFETY: flock on a file descriptor this function owns.
            if unsafe { libc::flock(file.as_raw_fd(), op) } == 0 {
                return Some(file);
            }
            if std::io::Error::last_os_error().kind() != std::io::ErrorKind::Interrupted {
                return None;
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (dir, wait);
        None
    }
}

impl ResultDir {
    /// Start a result folder for `dest`, written by the command `owner`
    /// (`run`, `montecarlo`, …: names its manifest): check it can be
    /// written, that its manifests can be read, and create the staging
    /// folder. Call before doing any work.
    pub fn begin(dest: &Path, owner: &str) -> Result<Self> {
        debug_assert!(owner.chars().all(|c| c.is_ascii_alphanumeric() || c == '-'), "owner `{owner}`");
        let name = match dest.components().next_back() {
            Some(Component::Normal(n)) => n.to_owned(),
            _ => bail!("output folder `{}` must end in a folder name (not `.`, `..` or `/`)", dest.display()),
        };
        let parent = parent_of(dest);
        if let Ok(meta) = std::fs::symlink_metadata(dest) {
            if !meta.is_dir() {
                bail!("output folder `{}` exists and is not a directory", dest.display());
            }
        }
        manifests_for(dest)?;
        // The nearest existing ancestor must be a directory.
        let mut missing = Vec::new();
        let mut probe = parent.clone();
        loop {
            match std::fs::metadata(&probe) {
                Ok(meta) if meta.is_dir() => break,
                Ok(_) => bail!("cannot write to `{}`: `{}` is not a directory", dest.display(), probe.display()),
                Err(_) => {
                    missing.push(probe.clone());
                    match probe.parent() {
                        Some(p) if !p.as_os_str().is_empty() => probe = p.to_path_buf(),
                        _ => break,
                    }
                }
            }
        }
        let mut dir = Self {
            dest: dest.to_path_buf(),
            owner: owner.to_string(),
            staging: PathBuf::new(),
            _lock: None,
            created: Vec::new(),
            written: None,
            hashed: Default::default(),
            committed: false,
        };
        // On failure `dir` is dropped: the folders created go again.
        for d in missing.into_iter().rev() {
            match std::fs::create_dir(&d) {
                Ok(()) => dir.created.push(d),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(e).with_context(|| format!("cannot create {}", d.display())),
            }
        }
        let mut prefix = OsString::from(".");
        prefix.push(&name);
        prefix.push(".tmp-");
        let staging = tempfile::Builder::new().prefix(&prefix).tempdir_in(&parent);
        dir.staging = staging.with_context(|| format!("cannot write to `{}`", dest.display()))?.keep();
        dir._lock = lock_dir(&dir.staging, false);
        Ok(dir)
    }

    /// The staging folder: write every file of the result below it.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Write `bytes` to `rel` (relative to the result folder), creating
    /// sub-folders as needed.
    pub fn write(&self, rel: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
        self.write_with(rel, |f| f.write_all(bytes))
    }

    /// Write `rel` as `fill` streams it (a large time series is written
    /// chunk by chunk, never held whole), creating sub-folders as needed.
    pub fn write_with(
        &self,
        rel: impl AsRef<Path>,
        fill: impl FnOnce(&mut (dyn Write + Send)) -> std::io::Result<()>,
    ) -> Result<()> {
        let path = self.staging.join(rel);
        let hashed = write_file(&path, fill)?;
        self.hashed.lock().unwrap_or_else(std::sync::PoisonError::into_inner).insert(path, hashed);
        Ok(())
    }

    /// The stamp of `path` taken as it was written, if the file still has
    /// that size and modification time; otherwise (written by other means,
    /// or changed since) it is read and hashed again ([`stamp`]).
    fn stamp_of(&self, path: &Path) -> Option<Stamp> {
        let hashed = self.hashed.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let unchanged = |(size, _): &Stamp, modified: &Option<std::time::SystemTime>| {
            std::fs::symlink_metadata(path)
                .is_ok_and(|m| m.is_file() && m.len() == *size && modified.is_some() && m.modified().ok() == *modified)
        };
        match hashed.get(path) {
            Some((s, modified)) if unchanged(s, modified) => Some(s.clone()),
            _ => stamp(path),
        }
    }

    /// Put the result in place (see the module docs): afterwards `dest`
    /// holds the new result and every entry of the old folder that is not
    /// provably a file this owner replaced or dropped.
    pub fn commit(mut self) -> Result<()> {
        let manifest_name = manifest_file(&self.owner);
        let (mut files, mut dirs) = (Vec::new(), Vec::new());
        walk(&self.staging, "", &mut files, &mut dirs);
        let mut written = BTreeMap::new();
        for rel in files {
            if rel.chars().any(char::is_control) {
                bail!("internal: result file name {rel:?} has a control character");
            }
            let s = self.stamp_of(&self.staging.join(&rel)).with_context(|| format!("cannot read back {rel}"))?;
            written.insert(rel, s);
        }
        self.written = Some(written.clone());
        if killed_at(1) {
            return self.die();
        }
        let parent = parent_of(&self.dest);
        let _parent_lock = lock_dir(&parent, true);

        // What the destination holds now, and what vouches for it.
        let manifests = manifests_for(&self.dest)?;
        let (own_old, by_hand) = read_manifest(&self.dest.join(&manifest_name))?;
        let (mut old_files, mut old_dirs) = (Vec::new(), Vec::new());
        walk(&self.dest, "", &mut old_files, &mut old_dirs);
        let mut dropped = BTreeMap::new();
        let mut replaced: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
        let new_dirs: BTreeSet<&str> = dirs.iter().map(String::as_str).collect();
        for d in &old_dirs {
            if written.contains_key(d) {
                bail!("cannot write {}: {d} there is a folder; move it away and run again", self.dest.display());
            }
        }
        for rel in &old_files {
            let path = self.dest.join(rel);
            let vouched = || {
                let now = stamp(&path)?;
                manifests.iter().find(|(_, m)| m.get(rel) == Some(&now)).map(|(c, _)| (c.as_str(), now))
            };
            if rel == &manifest_name {
                continue;
            }
            if written.contains_key(rel) || new_dirs.contains(rel.as_str()) {
                let Some((command, now)) = vouched() else {
                    bail!(
                        "refusing to replace {}: ftsmc did not write it, or it changed since (no manifest lists its size and SHA-256); move it away and run again",
                        path.display()
                    );
                };
                if command != self.owner {
                    replaced.entry(command).or_default().push(rel);
                }
                dropped.insert(rel.clone(), now);
                continue;
            }
            if own_old.contains_key(rel) || by_hand.contains(rel) {
                match stamp(&path) {
                    Some(now) if own_old.get(rel) == Some(&now) => {
                        dropped.insert(rel.clone(), now);
                        continue;
                    }
                    _ => eprintln!(
                        "note: kept {}: the manifest of `ftsmc {}` lists it, but not with its present size and SHA-256 (changed since, or listed by hand)",
                        path.display(),
                        self.owner
                    ),
                }
            }
            let target = self.staging.join(rel);
            if let Some(p) = target.parent() {
                std::fs::create_dir_all(p).with_context(|| format!("cannot create {}", p.display()))?;
            }
            std::fs::hard_link(&path, &target).with_context(|| {
                format!(
                    "cannot keep {} in the new result (hard link failed); move it away and run again",
                    path.display()
                )
            })?;
        }
        // Empty folders are kept too (the others exist if they keep a file).
        for d in old_dirs.iter().filter(|d| !old_files.iter().chain(&old_dirs).any(|f| f.starts_with(&format!("{d}/"))))
        {
            let _ = std::fs::create_dir_all(self.staging.join(d));
        }
        if killed_at(2) {
            return self.die();
        }
        for (command, names) in &mut replaced {
            names.sort_unstable();
            eprintln!(
                "note: replaced {} in {} written by `ftsmc {command}` (its other files are kept)",
                names.join(", "),
                self.dest.display()
            );
        }
        let mut text = String::new();
        for (rel, (size, sha)) in &written {
            text.push_str(&format!("{sha} {size} {rel}\n"));
        }
        let (manifest_stamp, _) = write_file(&self.staging.join(&manifest_name), |f| f.write_all(text.as_bytes()))?;
        if let Some(w) = self.written.as_mut() {
            w.insert(manifest_name.clone(), manifest_stamp);
        }

        if killed_at(3) {
            return self.die();
        }
        let old = if std::fs::symlink_metadata(&self.dest).is_ok() {
            Some(
                swap(&self.staging, &self.dest)
                    .with_context(|| format!("cannot put {} in place", self.dest.display()))?,
            )
        } else {
            std::fs::rename(&self.staging, &self.dest)
                .with_context(|| format!("cannot put {} in place", self.dest.display()))?;
            None
        };
        self.committed = true;
        if killed_at(4) {
            return self.die();
        }
        if let Some(old) = old {
            // The old manifest of this owner is ours to drop too.
            let mut ours = dropped;
            if let Some(s) = stamp(&old.join(&manifest_name)) {
                ours.insert(manifest_name.clone(), s);
            }
            remove_ours(&old, &self.dest, &ours);
        }
        self.note_leftovers(&parent);
        Ok(())
    }

    /// Stop here as a kill would: nothing cleaned up (tests only).
    fn die(mut self) -> Result<()> {
        self.committed = true;
        self._lock = None;
        bail!("killed (test)")
    }

    /// Name the staging folders of this destination left by killed runs
    /// (nobody holds their lock).
    fn note_leftovers(&self, parent: &Path) {
        let name = self.dest.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let prefix = format!(".{name}.tmp-");
        for entry in std::fs::read_dir(parent).into_iter().flatten().flatten() {
            let path = entry.path();
            let leftover = entry.file_name().to_string_lossy().starts_with(&prefix)
                && path != self.staging
                && !path.as_os_str().to_string_lossy().starts_with(&*self.staging.as_os_str().to_string_lossy())
                && lock_dir(&path, false).is_some();
            if leftover {
                eprintln!(
                    "note: {} was left by an interrupted run into {}; ftsmc does not delete it: delete it when you no longer need it",
                    path.display(),
                    self.dest.display()
                );
            }
        }
    }
}

impl Drop for ResultDir {
    fn drop(&mut self) {
        if !self.committed {
            match &self.written {
                // Nothing but the result's own files yet.
                None => {
                    let _ = std::fs::remove_dir_all(&self.staging);
                }
                Some(written) => remove_ours(&self.staging, &self.dest, written),
            }
            for d in self.created.iter().rev() {
                let _ = std::fs::remove_dir(d);
            }
        }
    }
}

#[cfg(test)]
thread_local! {
    /// The commit step at which a test kills the commit (see [`killed_at`]).
    static KILL_AT: std::cell::Cell<u32> = const { std::cell::Cell::new(0) };
}

/// Whether a test asked the commit to stop at `step` as a kill would
/// (1: files listed, 2: kept entries linked, 3: manifest written, 4: swapped).
#[cfg(test)]
fn killed_at(step: u32) -> bool {
    KILL_AT.with(|k| k.get() == step)
}

#[cfg(not(test))]
fn killed_at(_step: u32) -> bool {
    false
}

/// Write a whole result folder in one call: `files` (paths relative to
/// `dest`, `/`-separated, with their bytes) are written into a staging
/// folder and committed as the result of the command `owner`.
#[cfg(test)]
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

/// Write to `path` what `fill` streams into it (buffered), creating its
/// parent folders, and return its stamp, hashed as the bytes went by (the
/// file is not read back), with its modification time once written; a
/// partly written file (disk full, a failing `fill`) is removed before the
/// error is returned.
fn write_file(path: &Path, fill: impl FnOnce(&mut (dyn Write + Send)) -> std::io::Result<()>) -> Result<Hashed> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).with_context(|| format!("cannot create directory {}", parent.display()))?;
    }
    let written = File::create(path).and_then(|file| {
        let mut out = Hashing { inner: std::io::BufWriter::with_capacity(1 << 16, file), sha: Sha256::new(), size: 0 };
        fill(&mut out)?;
        out.inner.flush()?;
        let modified = out.inner.get_ref().metadata()?.modified().ok();
        Ok(((out.size, format!("{:x}", out.sha.finalize())), modified))
    });
    written.or_else(|e| {
        let _ = std::fs::remove_file(path);
        Err(e).with_context(|| format!("cannot write {}", path.display()))
    })
}

/// A writer that hashes (SHA-256) and counts the bytes it hands on.
struct Hashing<W> {
    inner: W,
    sha: Sha256,
    size: u64,
}

impl<W: Write> Write for Hashing<W> {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(bytes)?;
        self.sha.update(&bytes[..n]);
        self.size += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> tempfile::TempDir {
        tempfile::Builder::new().prefix(&format!("ftsmc-result-{name}-")).tempdir().unwrap()
    }

    /// Names in `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    /// Every file below `dir` (hidden ones included) with its text.
    fn tree(dir: &Path) -> BTreeMap<String, String> {
        let (mut files, mut dirs) = (Vec::new(), Vec::new());
        walk(dir, "", &mut files, &mut dirs);
        files.into_iter().map(|f| (f.clone(), std::fs::read_to_string(dir.join(&f)).unwrap())).collect()
    }

    fn read(path: &Path) -> String {
        std::fs::read_to_string(path).unwrap()
    }

    #[test]
    fn sha256_matches_the_standard_test_vectors() {
        assert_eq!(sha256_hex(b""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
        assert_eq!(sha256_hex(b"abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    }

    /// The manifest lists every file as it ends up: hashed while written,
    /// or read back when it was written by other means or changed since.
    #[test]
    fn the_manifest_stamps_each_file_as_it_ends_up() {
        let tmp = temp("stamps");
        let dest = tmp.path().join("res");
        let dir = ResultDir::begin(&dest, "run").unwrap();
        dir.write_with("a.csv", |w| {
            w.write_all(b"t,x\n")?;
            w.write_all(b"0,1\n")
        })
        .unwrap();
        dir.write("b.txt", b"first").unwrap();
        std::fs::write(dir.path().join("b.txt"), b"second, longer").unwrap();
        std::fs::write(dir.path().join("c.txt"), b"direct").unwrap();
        dir.commit().unwrap();
        let manifest = read(&dest.join(manifest_file("run")));
        for (name, bytes) in [("a.csv", &b"t,x\n0,1\n"[..]), ("b.txt", b"second, longer"), ("c.txt", b"direct")] {
            assert!(manifest.contains(&format!("{} {} {name}\n", sha256_hex(bytes), bytes.len())), "{manifest}");
        }
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
        // Folders created for a result that never came are removed again.
        drop(ResultDir::begin(&root.join("a/b/res"), "run").unwrap());
        assert_eq!(names(root), ["res"]);
    }

    #[test]
    fn commit_replaces_the_owners_files_and_keeps_every_other_file() {
        let tmp = temp("commit");
        let root = tmp.path();
        let dest = root.join("res");
        std::fs::create_dir_all(dest.join("montecarlo/paper-scenario-2")).unwrap();
        std::fs::write(dest.join("montecarlo/paper-scenario-2/summary.json"), "{}").unwrap();
        std::fs::write(dest.join("notes.txt"), "mine").unwrap();
        std::fs::create_dir_all(dest.join("drafts/empty")).unwrap();
        write_result(
            &dest,
            "reproduce",
            &[("s1/old.csv", b"old"), ("s1/both.csv", b"old"), ("figures/a.svg", b"old"), ("summary.json", b"{1}")],
        )
        .unwrap();
        // The user adds a file inside a folder reproduce writes.
        std::fs::write(dest.join("s1/mine.csv"), "mine").unwrap();
        // A second result no longer writes old.csv nor figures/.
        write_result(&dest, "reproduce", &[("s1/both.csv", b"new"), ("summary.json", b"{2}")]).unwrap();
        assert_eq!(names(root), ["res"], "no staging or old folder left");
        assert_eq!(
            names(&dest),
            [".ftsmc-reproduce.manifest", "drafts", "montecarlo", "notes.txt", "s1", "summary.json"]
        );
        assert_eq!(names(&dest.join("s1")), ["both.csv", "mine.csv"]);
        assert_eq!(names(&dest.join("drafts")), ["empty"]);
        assert_eq!(read(&dest.join("s1/both.csv")), "new");
        assert_eq!(read(&dest.join("notes.txt")), "mine");
        let manifest = read(&dest.join(".ftsmc-reproduce.manifest"));
        assert_eq!(manifest, format!("{} 3 s1/both.csv\n{} 3 summary.json\n", sha256_hex(b"new"), sha256_hex(b"{2}")));
        // Another owner into the same folder keeps reproduce's files.
        write_result(&dest, "merge", &[("merged.csv", b"m")]).unwrap();
        assert!(dest.join("s1/both.csv").is_file() && dest.join("summary.json").is_file());
        assert!(write_result(&dest, "merge", &[("../escape.csv", b"m")]).is_err());
        assert!(!root.join("escape.csv").exists());
    }

    #[test]
    fn a_file_another_command_replaced_is_not_the_first_commands_to_delete() {
        let tmp = temp("replaced");
        let dest = tmp.path().join("res").join("scen");
        write_result(&dest, "run", &[("summary.json", b"run"), ("pid.csv", b"csv")]).unwrap();
        write_result(&dest, "montecarlo", &[("summary.json", b"mc"), ("runs.csv", b"rows")]).unwrap();
        // `run` no longer writes summary.json: montecarlo's is not the one it wrote.
        write_result(&dest, "run", &[("pid.csv", b"csv2")]).unwrap();
        assert_eq!(read(&dest.join("summary.json")), "mc");
        assert_eq!(read(&dest.join("runs.csv")), "rows");
    }

    #[test]
    fn a_tampered_manifest_cannot_delete_or_replace_a_users_file() {
        let tmp = temp("tamper");
        let dest = tmp.path().join("res");
        write_result(&dest, "run", &[("a.csv", b"a"), ("b.csv", b"b"), ("c.csv", b"c")]).unwrap();
        let manifest = dest.join(".ftsmc-run.manifest");
        // The user's file named by hand, another with a forged stamp, and a
        // listed file the user edited.
        std::fs::write(dest.join("notes.txt"), "mine").unwrap();
        std::fs::write(dest.join("paper.pdf"), "pdf").unwrap();
        let mut text = read(&manifest);
        text.push_str("notes.txt\n");
        text.push_str(&format!("{} 3 paper.pdf\n", sha256_hex(b"xyz")));
        std::fs::write(&manifest, text).unwrap();
        std::fs::write(dest.join("b.csv"), "edited").unwrap();
        write_result(&dest, "run", &[("a.csv", b"a2")]).unwrap();
        assert_eq!(names(&dest), [".ftsmc-run.manifest", "a.csv", "b.csv", "notes.txt", "paper.pdf"]);
        assert_eq!(read(&dest.join("b.csv")), "edited");
        assert_eq!(read(&dest.join("notes.txt")), "mine");
        // A file of the new result's name that ftsmc cannot vouch for is
        // not replaced: the commit is refused and nothing changes.
        let before = tree(&dest);
        let err = write_result(&dest, "run", &[("b.csv", b"b3")]).unwrap_err().to_string();
        assert!(err.contains("refusing to replace") && err.contains("b.csv"), "{err}");
        assert_eq!(tree(&dest), before);
        assert_eq!(names(tmp.path()), ["res"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_manifest_is_refused_before_any_work() {
        let tmp = temp("fifo");
        let dest = tmp.path().join("res");
        std::fs::create_dir_all(&dest).unwrap();
        let fifo = std::ffi::CString::new(dest.join(".ftsmc-run.manifest").to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo only creates a file.
        assert_eq!(unsafe { libc::mkfifo(fifo.as_ptr(), 0o600) }, 0);
        let err = ResultDir::begin(&dest, "run").unwrap_err().to_string();
        assert!(err.contains("not a regular file"), "{err}");
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

    /// A kill at each step of a commit leaves the destination whole — the
    /// old result or the new one, the user's file in it — and at most a
    /// hidden folder beside it that the next commit names and does not
    /// delete; the next commit succeeds.
    #[test]
    fn a_kill_at_any_step_of_a_commit_leaves_the_old_result_or_the_new() {
        for step in 1..=4 {
            let tmp = temp("kill");
            let root = tmp.path();
            let dest = root.join("res");
            write_result(&dest, "run", &[("a.csv", b"old"), ("sub/b.csv", b"old")]).unwrap();
            std::fs::write(dest.join("notes.txt"), "mine").unwrap();
            let old = tree(&dest);
            KILL_AT.with(|k| k.set(step));
            let killed = write_result(&dest, "run", &[("a.csv", b"new"), ("c.csv", b"new")]);
            KILL_AT.with(|k| k.set(0));
            assert!(killed.is_err(), "step {step}");
            let now = tree(&dest);
            let new: BTreeMap<String, String> = [
                (".ftsmc-run.manifest", format!("{} 3 a.csv\n{} 3 c.csv\n", sha256_hex(b"new"), sha256_hex(b"new"))),
                ("a.csv", "new".into()),
                ("c.csv", "new".into()),
                ("notes.txt", "mine".into()),
            ]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
            assert!(now == old || now == new, "step {step}: {now:?}");
            assert_eq!(now == new, step == 4, "step {step}");
            // The next commit works and leaves the user's file.
            write_result(&dest, "run", &[("a.csv", b"next")]).unwrap();
            assert_eq!(read(&dest.join("notes.txt")), "mine", "step {step}");
            assert_eq!(read(&dest.join("a.csv")), "next", "step {step}");
            assert_eq!(names(root).len(), 2, "step {step}: the killed run's folder is kept: {:?}", names(root));
        }
    }

    #[test]
    fn concurrent_commits_into_one_folder_leave_one_whole_result() {
        let tmp = temp("race");
        let dest = tmp.path().join("res");
        std::fs::create_dir_all(&dest).unwrap();
        std::fs::write(dest.join("notes.txt"), "mine").unwrap();
        std::thread::scope(|scope| {
            for k in 0..6 {
                let dest = &dest;
                scope.spawn(move || {
                    for round in 0..5 {
                        let name = format!("{k}-{round}.csv");
                        write_result(dest, "run", &[(name.as_str(), b"x"), ("summary.json", name.as_bytes())]).unwrap();
                    }
                });
            }
        });
        let files = names(&dest);
        assert_eq!(files.len(), 4, "{files:?}");
        let summary = read(&dest.join("summary.json"));
        assert_eq!(files, [".ftsmc-run.manifest".to_string(), summary, "notes.txt".into(), "summary.json".into()]);
        assert_eq!(names(tmp.path()), ["res"]);
    }
}
