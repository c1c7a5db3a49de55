//! The crate's layout rule (see the top doc comment of `lib.rs`): modules
//! sit on floors and a module only uses modules on its own floor or below.
//! This test reads every `src/**/*.rs`, collects its `crate::…` paths
//! (in `use` items and inline, comments excluded) and fails on any path
//! that reaches a module on a higher floor.

use std::collections::BTreeMap;
use std::path::Path;

use crate::source::{module_of, paths_after, rust_files, without_comments};

/// Module path (as written after `crate::`) → floor. The longest matching
/// prefix decides, so a sub-module may sit on another floor than its parent.
const FLOORS: &[(&str, u32)] = &[
    ("gauss", 0),
    ("rng", 0),
    ("stats", 0),
    ("defaults", 1),
    ("text", 1),
    ("escape", 1),
    ("axes", 1),
    ("limits", 1),
    ("isa", 1),
    ("desaturation", 1),
    ("signal", 1),
    ("trajectory", 1),
    ("noise", 1),
    ("vehicle", 2),
    ("actuators", 2),
    ("environment", 2),
    ("metrics", 2),
    ("envelope", 2),
    ("margin", 2),
    ("sensors", 2),
    ("controllers", 2),
    ("scenario", 3),
    ("run", 4),
    ("registry", 5),
    ("analysis", 6),
    ("batch", 6),
    ("gym", 6),
    ("tune", 7),
    ("falsify", 7),
    // The crate root only re-exports.
    ("", 8),
];

fn floor_of(module: &str) -> u32 {
    FLOORS
        .iter()
        .filter(|(m, _)| m.is_empty() || module == *m || module.starts_with(&format!("{m}::")))
        .max_by_key(|(m, _)| m.len())
        .map(|(_, f)| *f)
        .unwrap_or_else(|| panic!("module `{module}` has no floor in tests/layout.rs; add it to FLOORS"))
}

/// `src/run/exit.rs` → `run::exit`; `src/signal/mod.rs` → `signal`; `src/lib.rs` → ``.
fn module_name(src: &Path, file: &Path) -> String {
    module_of(src, file).join("::")
}

/// The module part of every `crate::…` path in `code` (comments removed),
/// including the items of grouped imports `use crate::{a::X, b};`: the
/// segments up to the first that does not start with a lower-case letter
/// (`run::exit::ExitStatus` → `run::exit`).
fn crate_paths(code: &str) -> Vec<String> {
    paths_after(&without_comments(code), "crate::")
        .into_iter()
        .map(|p| {
            p.iter()
                .take_while(|s| s.chars().next().is_some_and(|c| c.is_lowercase()))
                .cloned()
                .collect::<Vec<_>>()
                .join("::")
        })
        .filter(|m| !m.is_empty())
        .collect()
}

fn violations(src: &Path) -> Vec<String> {
    let files = rust_files(src);
    let mut found = Vec::new();
    for file in &files {
        let module = module_name(src, file);
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
    let files = rust_files(&src);
    for file in files {
        let module = module_name(&src, &file);
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
