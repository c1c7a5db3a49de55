//! `report.html` in a real browser: headless Chromium (Debian's `chromium`)
//! opens the page of an `ftsmc run` with no script error, runs the 3-D
//! replay, and its screenshot shows the table, a figure and the replay
//! (non-blank pixels where the page says they are). Skipped, with a
//! message, where no Chromium is installed (`.ci/run` installs it).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use resvg::tiny_skia::Pixmap;

use crate::common::scratch;

/// Viewport of both the DOM dump and the screenshot, CSS px.
const WINDOW: (u32, u32) = (1280, 5200);

fn chromium() -> Option<PathBuf> {
    let candidates = ["chromium", "chromium-browser", "google-chrome", "google-chrome-stable"];
    for name in candidates {
        if let Ok(out) = Command::new(name).arg("--version").output() {
            if out.status.success() {
                return Some(PathBuf::from(name));
            }
        }
    }
    None
}

/// One `ftsmc run paper-scenario-1` with figures; its folder.
fn flown() -> &'static Path {
    static OUT: OnceLock<PathBuf> = OnceLock::new();
    OUT.get_or_init(|| {
        let tmp = scratch("html");
        let out = Command::new(env!("CARGO_BIN_EXE_ftsmc"))
            .args(["run", "paper-scenario-1", "--out", tmp.path().to_str().unwrap()])
            .env_remove("FTSMC_FIGURE_STYLE")
            .output()
            .expect("binary runs");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        crate::common::removed_at_exit(tmp).join("paper-scenario-1")
    })
}

fn headless(browser: &Path, profile: &Path, args: &[String]) -> (String, String) {
    let out = Command::new(browser)
        .args([
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            "--no-first-run",
            "--disable-extensions",
            "--hide-scrollbars",
            "--enable-logging=stderr",
            "--v=0",
            "--virtual-time-budget=3000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--window-size={},{}", WINDOW.0, WINDOW.1))
        .args(args)
        .output()
        .expect("chromium runs");
    (String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn report_html_is_self_contained() {
    let page = std::fs::read_to_string(flown().join("report.html")).unwrap();
    // Offline: nothing is fetched (the SVG namespace is a name, not a fetch).
    for bad in ["src=\"http", "href=\"http", "@import", "<link "] {
        assert!(!page.contains(bad), "report.html fetches something: {bad}");
    }
    for part in
        ["<table>", "<svg", "id=\"replay-canvas\"", "href=\"summary.json\"", "href=\"ftaftsmc.csv\"", "@media print"]
    {
        assert!(page.contains(part), "report.html lacks {part}");
    }
}

#[test]
fn chromium_opens_report_html_without_errors_and_renders_it() {
    let Some(browser) = chromium() else {
        eprintln!("SKIPPED: no chromium on PATH (apt-get install chromium) — report.html not opened in a browser");
        return;
    };
    let page = flown().join("report.html");
    let url = format!("file://{}", page.display());
    let tmp = scratch("chromium");
    let profile = tmp.path().join("profile");

    let (dom, log) = headless(&browser, &profile, &["--dump-dom".to_string(), url.clone()]);
    assert!(dom.contains("data-replay=\"ready\""), "the replay script did not finish: {log}");
    let errors = dom.split("id=\"page-errors\"").nth(1).expect("the error box is in the page");
    let errors = &errors[errors.find('>').unwrap() + 1..errors.find("</pre>").unwrap()];
    assert!(errors.trim().is_empty(), "script errors: {errors}");
    let console_errors: Vec<&str> = log.lines().filter(|l| l.contains("CONSOLE") || l.contains("Uncaught")).collect();
    assert!(console_errors.is_empty(), "console: {console_errors:?}");

    // Where the page put its table, first figure and replay.
    let layout = dom.split("data-layout=\"").nth(1).expect("layout attribute");
    let layout = layout[..layout.find('"').unwrap()].replace("&quot;", "\"");
    let layout: serde_json::Value = serde_json::from_str(&layout).unwrap();

    let shot = tmp.path().join("shot.png");
    let (_, log) = headless(&browser, &profile, &[format!("--screenshot={}", shot.display()), url]);
    let pix = Pixmap::load_png(&shot).unwrap_or_else(|e| panic!("no screenshot ({e}): {log}"));
    for region in ["table", "figure", "replay"] {
        let r: Vec<u32> = layout[region]
            .as_array()
            .unwrap_or_else(|| panic!("{region} not on the page"))
            .iter()
            .map(|v| v.as_u64().unwrap() as u32)
            .collect();
        assert!(r[2] > 50 && r[3] > 20, "{region} is {}×{} px", r[2], r[3]);
        let (x1, y1) = ((r[0] + r[2]).min(pix.width()), (r[1] + r[3]).min(pix.height()));
        assert!(r[1] < pix.height(), "{region} starts below the screenshot ({} px)", pix.height());
        let mut ink = 0usize;
        let mut total = 0usize;
        for y in r[1]..y1 {
            for x in r[0]..x1 {
                let p = pix.pixel(x, y).unwrap();
                total += 1;
                if u32::from(p.red()) + u32::from(p.green()) + u32::from(p.blue()) < 600 {
                    ink += 1;
                }
            }
        }
        let share = ink as f64 / total.max(1) as f64;
        assert!(share > 0.005, "{region}: {ink} of {total} pixels drawn");
    }
}
