//! No file-level import circle in any crate of the workspace: reads every
//! `src/**/*.rs` of each crate, collects the files each one reaches through
//! `crate::…` and `super::…` paths (comments excluded; a module's own
//! `mod`/relative child paths do not count), and fails on any cycle, naming
//! the files around it. (The circles this guards against: `ftsmc-core`
//! `pid.rs` ↔ `se3.rs`, `ftsmc-cli` `montecarlo.rs` ↔ `reproduce.rs`.)

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const CRATES: [&str; 4] = ["ftsmc-core", "ftsmc-sim", "ftsmc-cli", "ftsmc-py"];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// `src/run/exit.rs` → `["run", "exit"]`; `src/run/mod.rs` → `["run"]`; `src/lib.rs` → `[]`.
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).expect("under src").with_extension("");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        parts.pop();
    }
    parts
}

/// The segments of every path starting with `prefix` (`crate::` or
/// `super::`), grouped imports expanded one level (`use crate::{a::X, b};`).
fn paths_after(code: &str, prefix: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        let boundary = i == 0 || !rest[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':');
        rest = &rest[i + prefix.len()..];
        if !boundary {
            continue;
        }
        let head: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':').collect();
        let mut base: Vec<String> = head.split("::").filter(|s| !s.is_empty()).map(String::from).collect();
        if head.ends_with("::") && rest[head.len()..].starts_with('{') {
            let inner = &rest[head.len() + 1..];
            let inner = &inner[..inner.find('}').unwrap_or(inner.len())];
            for item in inner.split(',') {
                let mut p = base.clone();
                p.extend(item.trim().split("::").map(|s| s.trim().to_string()).filter(|s| !s.is_empty()));
                out.push(p);
            }
            continue;
        }
        if base.is_empty() {
            continue;
        }
        out.push(std::mem::take(&mut base));
    }
    out
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut circles = Vec::new();
    for krate in CRATES {
        let src = root.join(krate).join("src");
        let mut files = Vec::new();
        rust_files(&src, &mut files);
        let modules: BTreeMap<Vec<String>, PathBuf> = files.iter().map(|f| (module_of(&src, f), f.clone())).collect();
        // The file of the longest module prefix of `path`.
        let resolve = |path: &[String]| -> Option<Vec<String>> {
            (0..=path.len()).rev().map(|n| path[..n].to_vec()).find(|m| modules.contains_key(m))
        };
        let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
        for (module, file) in &modules {
            let text = std::fs::read_to_string(file).unwrap();
            let code: String = text
                .lines()
                .map(|l| match l.find("//") {
                    Some(i) => &l[..i],
                    None => l,
                })
                .collect::<Vec<_>>()
                .join("\n");
            let is_mod_file = file.file_stem().is_some_and(|s| s == "mod" || s == "lib" || s == "main");
            let parent: Vec<String> = if is_mod_file {
                module[..module.len().saturating_sub(1)].to_vec()
            } else {
                module[..module.len() - 1].to_vec()
            };
            let mut targets = Vec::new();
            for p in paths_after(&code, "crate::") {
                targets.push(p);
            }
            for p in paths_after(&code, "super::") {
                let mut full = parent.clone();
                full.extend(p);
                targets.push(full);
            }
            let out = edges.entry(module.clone()).or_default();
            for t in targets {
                if let Some(m) = resolve(&t) {
                    // A file reaching its own module or a parent's re-exports is not a circle of files.
                    if &m != module && !module.starts_with(&m) {
                        out.insert(m);
                    }
                }
            }
        }
        // Depth-first search for a back edge.
        fn visit(
            node: &Vec<String>,
            edges: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
            state: &mut BTreeMap<Vec<String>, u8>,
            stack: &mut Vec<Vec<String>>,
            found: &mut Vec<String>,
        ) {
            state.insert(node.clone(), 1);
            stack.push(node.clone());
            for next in edges.get(node).into_iter().flatten() {
                match state.get(next).copied().unwrap_or(0) {
                    0 => visit(next, edges, state, stack, found),
                    1 => {
                        let start = stack.iter().position(|m| m == next).unwrap();
                        let names: Vec<String> = stack[start..].iter().chain([next]).map(|m| m.join("::")).collect();
                        found.push(names.join(" → "));
                    }
                    _ => {}
                }
            }
            stack.pop();
            state.insert(node.clone(), 2);
        }
        let mut state = BTreeMap::new();
        let mut found = Vec::new();
        for m in modules.keys() {
            if !state.contains_key(m) {
                visit(m, &edges, &mut state, &mut Vec::new(), &mut found);
            }
        }
        circles.extend(found.into_iter().map(|c| format!("{krate}: {c}")));
    }
    assert!(circles.is_empty(), "file-level import circles:\n{}", circles.join("\n"));
}
