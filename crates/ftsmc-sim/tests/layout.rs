//! The crate's layout rule (see the top doc comment of `lib.rs`): modules
//! sit on floors and a module only uses modules on its own floor or below.
//! This test reads every `src/**/*.rs`, collects its `crate::…` paths
//! (in `use` items and inline, comments excluded) and fails on any path
//! that reaches a module on a higher floor.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Module path (as written after `crate::`) → floor. The longest matching
/// prefix decides, so a sub-module may sit on another floor than its parent.
const FLOORS: &[(&str, u32)] = &[
    ("text", 1),
    ("axes", 1),
    ("limits", 1),
    ("signal", 1),
    ("vehicle", 2),
    ("actuators", 2),
    ("environment", 2),
    ("metrics", 2),
    ("envelope", 2),
    ("sensors", 2),
    ("controllers", 2),
    ("scenario", 3),
    ("run", 4),
    ("registry", 5),
    ("analysis", 6),
    ("batch", 6),
    ("gym", 6),
    // The crate root only re-exports.
    ("", 7),
];

fn floor_of(module: &str) -> u32 {
    FLOORS
        .iter()
        .filter(|(m, _)| m.is_empty() || module == *m || module.starts_with(&format!("{m}::")))
        .max_by_key(|(m, _)| m.len())
        .map(|(_, f)| *f)
        .unwrap_or_else(|| panic!("module `{module}` has no floor in tests/layout.rs; add it to FLOORS"))
}

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

/// `src/run/exit.rs` → `run::exit`; `src/signal/mod.rs` → `signal`; `src/lib.rs` → ``.
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).expect("under src").with_extension("");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
        parts.pop();
    }
    parts.join("::")
}

/// Every `crate::a::b…` path in `code` (comments removed), including the
/// items of grouped imports `use crate::{a::X, b};`.
fn crate_paths(code: &str) -> Vec<String> {
    let code: String = code
        .lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n");
    let mut out = Vec::new();
    let mut rest = code.as_str();
    while let Some(i) = rest.find("crate::") {
        let boundary = i == 0 || !rest[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == '$');
        rest = &rest[i + "crate::".len()..];
        if !boundary {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let item = item.trim();
                if !item.is_empty() {
                    out.push(path_head(item));
                }
            }
        } else {
            out.push(path_head(rest));
        }
    }
    out
}

/// The module part of a path: `run::exit::ExitStatus` → `run::exit`
/// (segments up to the first that starts with an upper-case letter).
fn path_head(path: &str) -> String {
    let end = path.find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')).unwrap_or(path.len());
    path[..end]
        .split("::")
        .take_while(|s| !s.is_empty() && s.chars().next().is_some_and(|c| c.is_lowercase()))
        .collect::<Vec<_>>()
        .join("::")
}

fn violations(src: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let mut found = Vec::new();
    for file in &files {
        let module = module_of(src, file);
        let own = floor_of(&module);
        let text = std::fs::read_to_string(file).expect("read source");
        let mut seen = BTreeMap::new();
        for target in crate_paths(&text) {
            let target_floor = floor_of(&target);
            if target_floor > own {
                seen.insert(target.clone(), target_floor);
            }
        }
        for (target, floor) in seen {
            found.push(format!("{} (`{module}`, floor {own}) uses `crate::{target}` (floor {floor})", file.display()));
        }
    }
    found
}

#[test]
fn no_module_imports_one_on_a_higher_floor() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let found = violations(&src);
    assert!(found.is_empty(), "upward imports:\n{}", found.join("\n"));
}

#[test]
fn every_top_level_module_has_a_floor() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    for file in files {
        let module = module_of(&src, &file);
        let top = module.split("::").next().unwrap_or("");
        assert!(
            FLOORS.iter().any(|(m, _)| *m == top),
            "{} (`{module}`) is not in FLOORS; give its top-level module a floor",
            file.display()
        );
    }
}

#[test]
fn the_parser_sees_upward_imports() {
    assert_eq!(crate_paths("use crate::run::exit::ExitStatus;"), ["run::exit"]);
    assert_eq!(crate_paths("use crate::{axes::AxisSet, run};"), ["axes", "run"]);
    assert_eq!(crate_paths("let x = crate::registry::run(a);"), ["registry::run"]);
    assert_eq!(floor_of("registry::run"), 5);
    assert_eq!(crate_paths("// see crate::registry::run\nfoo();"), Vec::<String>::new());
    assert_eq!(crate_paths("use $crate::x;"), Vec::<String>::new());
    assert!(floor_of("run") > floor_of("scenario::distributions"));
    assert_eq!(floor_of("signal::waypoints"), 1);
}
