//! Reading the workspace's own Rust sources as text, for the layout tests
//! (`tests/layout.rs`: floors; `tests/import_cycles.rs`: file-level
//! circles). Included by `#[path]`, so each test takes only this file.

use std::path::{Path, PathBuf};

/// Every `*.rs` file below `dir`, recursively, sorted.
pub fn rust_files(dir: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("read src") {
            let path = entry.expect("dir entry").path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, &mut out);
    out.sort();
    out
}

/// The module of a file under `src`: `src/run/exit.rs` → `["run", "exit"]`;
/// `src/run/mod.rs` → `["run"]`; `src/lib.rs` or `src/main.rs` → `[]`.
pub fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).expect("under src").with_extension("");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        parts.pop();
    }
    parts
}

/// `text` without its `//` comments (doc comments included), line by line.
pub fn without_comments(text: &str) -> String {
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The segments of every path in `code` starting with `prefix` (`crate::`
/// or `super::`), grouped imports expanded one level
/// (`use crate::{a::X, b};` → `[a, X]`, `[b]`). A prefix glued to a longer
/// path or to a macro's `$crate` does not count.
pub fn paths_after(code: &str, prefix: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        let boundary =
            i == 0 || !rest[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':' || c == '$');
        rest = &rest[i + prefix.len()..];
        if !boundary {
            continue;
        }
        let head: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':').collect();
        let base: Vec<String> = head.split("::").filter(|s| !s.is_empty()).map(String::from).collect();
        if rest[head.len()..].starts_with('{') && (head.is_empty() || head.ends_with("::")) {
            let inner = &rest[head.len() + 1..];
            let inner = &inner[..inner.find('}').unwrap_or(inner.len())];
            for item in inner.split(',') {
                let mut p = base.clone();
                p.extend(item.trim().split("::").map(|s| s.trim().to_string()).filter(|s| !s.is_empty()));
                if !p.is_empty() {
                    out.push(p);
                }
            }
            continue;
        }
        if !base.is_empty() {
            out.push(base);
        }
    }
    out
}
