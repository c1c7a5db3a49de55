//! No file-level import circle in any crate of the workspace: reads every
//! `src/**/*.rs` of each crate, collects the files each one reaches through
//! `crate::…` and `super::…` paths (comments excluded; a module's own
//! `mod`/relative child paths do not count), and fails on any cycle, naming
//! the files around it. (The circles this guards against: `ftsmc-core`
//! `pid.rs` ↔ `se3.rs`, `ftsmc-cli` `montecarlo.rs` ↔ `reproduce.rs`.)

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::source::{module_of, paths_after, rust_files, without_comments};

const CRATES: [&str; 6] = ["ftsmc-core", "ftsmc-sim", "ftsmc-logs", "ftsmc-ident", "ftsmc-cli", "ftsmc-py"];

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut circles = Vec::new();
    for krate in CRATES {
        let src = root.join(krate).join("src");
        let files = rust_files(&src);
        let modules: BTreeMap<Vec<String>, PathBuf> = files.iter().map(|f| (module_of(&src, f), f.clone())).collect();
        // The file of the longest module prefix of `path`.
        let resolve = |path: &[String]| -> Option<Vec<String>> {
            (0..=path.len()).rev().map(|n| path[..n].to_vec()).find(|m| modules.contains_key(m))
        };
        let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
        for (module, file) in &modules {
            let text = std::fs::read_to_string(file).unwrap();
            let code = without_comments(&text);
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

#[test]
fn the_parser_sees_the_paths_a_circle_is_made_of() {
    let seg = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(paths_after("use crate::{pid::Pid, se3};", "crate::"), [seg(&["pid", "Pid"]), seg(&["se3"])]);
    assert_eq!(paths_after("use super::console::Table;", "super::"), [seg(&["console", "Table"])]);
    assert_eq!(paths_after("let t = super::super::x::f();", "super::").first(), Some(&seg(&["super", "x", "f"])));
    assert!(paths_after(&without_comments("// crate::pid::Pid"), "crate::").is_empty());
    assert!(paths_after("$crate::pid::Pid", "crate::").is_empty());
}
