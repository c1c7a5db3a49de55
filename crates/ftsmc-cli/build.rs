//! Records the git commit the binary is built from as `FTSMC_GIT_COMMIT`
//! (`<sha>` or `<sha>-dirty`; `unknown` outside a git checkout of this
//! project, e.g. from a tarball or a Python sdist). Never fails the build.
//!
//! `FTSMC_GIT_COMMIT` set in the environment wins (for packagers who know
//! the commit but build without `.git`).

use std::path::{Path, PathBuf};
use std::process::Command;

fn git(dir: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).current_dir(dir).output().ok()?;
    if !out.status.success() {
        return None;
    }
    Some(String::from_utf8(out.stdout).ok()?.trim().to_string())
}

/// `path` as printed by git, relative to `dir` unless absolute.
fn resolve(dir: &Path, path: &str) -> PathBuf {
    let p = PathBuf::from(path);
    if p.is_absolute() {
        p
    } else {
        dir.join(p)
    }
}

fn commit(dir: &Path) -> Option<String> {
    // Only a repository that tracks this crate counts: an unpacked tarball
    // inside some other repository must not borrow that one's commit.
    git(dir, &["ls-files", "--error-unmatch", "Cargo.toml"])?;
    let head = git(dir, &["rev-parse", "HEAD"])?;
    // In a worktree `.git` is a file: ask git where HEAD and the refs live.
    if let Some(git_dir) = git(dir, &["rev-parse", "--git-dir"]) {
        let git_dir = resolve(dir, &git_dir);
        println!("cargo:rerun-if-changed={}", git_dir.join("HEAD").display());
        println!("cargo:rerun-if-changed={}", git_dir.join("index").display());
        let common = git(dir, &["rev-parse", "--git-common-dir"]).map_or(git_dir.clone(), |c| resolve(dir, &c));
        if let Some(reference) = git(dir, &["symbolic-ref", "-q", "HEAD"]) {
            println!("cargo:rerun-if-changed={}", common.join(reference).display());
        }
        println!("cargo:rerun-if-changed={}", common.join("packed-refs").display());
    }
    // Tracked files changed but not committed: `-dirty` (untracked files
    // do not count; a new source file needs a changed `mod` line anyway).
    let dirty = git(dir, &["status", "--porcelain", "--untracked-files=no"]).is_none_or(|s| !s.is_empty());
    Some(if dirty { format!("{head}-dirty") } else { head })
}

fn main() {
    let dir = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_else(|| ".".into()));
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=FTSMC_GIT_COMMIT");
    // Sources whose edits make the checkout dirty (Cargo watches
    // directories recursively by modification time).
    for watched in ["src", "../ftsmc-sim/src", "../ftsmc-core/src", "../../scenarios", "../../Cargo.toml"] {
        if dir.join(watched).exists() {
            println!("cargo:rerun-if-changed={}", dir.join(watched).display());
        }
    }
    let commit = match std::env::var("FTSMC_GIT_COMMIT") {
        Ok(c) if !c.trim().is_empty() => c.trim().to_string(),
        _ => commit(&dir).unwrap_or_else(|| "unknown".into()),
    };
    println!("cargo:rustc-env=FTSMC_GIT_COMMIT={commit}");
}
