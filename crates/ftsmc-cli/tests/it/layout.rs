//! The CLI's layout rule (`src/commands/mod.rs`): each subcommand is one
//! module `commands::<name>` (a file, or a folder of sub-modules), a
//! command never uses another command, and nothing outside `commands/`
//! but `main.rs` (the dispatch) uses a command. What two commands share
//! lives outside `commands/` (`args`, `campaign`, `flights`, …). This test
//! reads every `src/**/*.rs`, collects its `crate::…` and `super::…`
//! paths (comments excluded) and fails on a path that breaks the rule.

use std::path::Path;

#[path = "../../../ftsmc-sim/tests/common/source.rs"]
mod source;

use source::{module_of, paths_after, rust_files, without_comments};

/// The command a path of `module`'s code reaches, if any: `crate::commands::X…`
/// anywhere, `super::X…` in a command's own file (`commands::Y`, whose
/// `super` is `commands`).
fn commands_used(module: &[String], code: &str) -> Vec<String> {
    let code = without_comments(code);
    let mut used: Vec<String> = paths_after(&code, "crate::")
        .into_iter()
        .filter(|p| p.first().is_some_and(|s| s == "commands") && p.len() > 1)
        .map(|p| p[1].clone())
        .collect();
    if module.len() == 2 && module[0] == "commands" {
        used.extend(
            paths_after(&code, "super::")
                .into_iter()
                .filter_map(|p| p.first().cloned())
                .filter(|s| s.chars().next().is_some_and(|c| c.is_lowercase())),
        );
    }
    used.sort();
    used.dedup();
    used
}

/// Every use that breaks the rule in the file of `module` with text `code`.
fn violations_in(module: &[String], code: &str) -> Vec<String> {
    let used = commands_used(module, code);
    match module {
        // main.rs dispatches to every command; commands/mod.rs declares them.
        [] => Vec::new(),
        [c] if c == "commands" => Vec::new(),
        [c, own, ..] if c == "commands" => {
            used.into_iter().filter(|u| u != own).map(|u| format!("command `{own}` uses command `{u}`")).collect()
        }
        _ => used.into_iter().map(|u| format!("`{}` (not a command) uses command `{u}`", module.join("::"))).collect(),
    }
}

#[test]
fn no_command_imports_another_and_only_main_imports_commands() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = rust_files(&src);
    assert!(files.iter().any(|f| f.ends_with("commands/compare.rs")), "no commands/ folder under {}", src.display());
    let mut found = Vec::new();
    for file in &files {
        let module = module_of(&src, file);
        let text = std::fs::read_to_string(file).expect("read source");
        for v in violations_in(&module, &text) {
            found.push(format!("{}: {v}", file.display()));
        }
    }
    assert!(found.is_empty(), "commands importing commands:\n{}", found.join("\n"));
}

#[test]
fn every_subcommand_has_its_own_module() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let main = std::fs::read_to_string(src.join("main.rs")).expect("main.rs");
    let dispatch = &main[main.find("fn run(command: Command)").expect("the dispatch")..];
    // Every arm calls `<module>::run`, and `<module>` is a file of commands/.
    let arms: Vec<&str> = dispatch.lines().filter(|l| l.contains("=> ")).collect();
    assert!(arms.len() >= 15, "{arms:?}");
    for arm in arms {
        let call = arm.split("=> ").nth(1).unwrap();
        let module = call.split("::").next().unwrap().trim();
        assert!(src.join("commands").join(format!("{module}.rs")).exists(), "{arm}: no commands/{module}.rs");
    }
}

#[test]
fn the_checker_sees_a_command_importing_another() {
    let m = |s: &str| s.split("::").map(String::from).collect::<Vec<_>>();
    let code = "use crate::campaign::runs_csv;\nuse crate::commands::tune::outcomes;\n// crate::commands::merge\n";
    assert_eq!(violations_in(&m("commands::compare"), code), ["command `compare` uses command `tune`"]);
    assert_eq!(
        violations_in(&m("commands::compare"), "use super::montecarlo::Options;"),
        ["command `compare` uses command `montecarlo`"]
    );
    assert!(violations_in(&m("commands::compare"), "use super::*;\nuse crate::commands::compare::Args;").is_empty());
    assert_eq!(
        violations_in(&m("ladder"), "let x = crate::commands::montecarlo::run;"),
        ["`ladder` (not a command) uses command `montecarlo`"]
    );
    assert!(violations_in(&[], "use commands::{compare, tune};\ncrate::commands::tune::run(a)").is_empty());
}
