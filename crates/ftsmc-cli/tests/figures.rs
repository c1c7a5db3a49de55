//! Figure smoke tests: every figure `reproduce` promises is written as SVG and
//! PNG, the PNG decodes and is not blank, and PNG and SVG have the same size
//! (the PNG is the SVG rasterised at the style's scale).

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use resvg::tiny_skia::Pixmap;

const FIGURES: [&str; 10] = [
    "fig1-attitude-scenario1",
    "fig2-controls-scenario1",
    "fig3-adaptive-gains-scenario1",
    "fig3b-ranftsmc-gains-scenario1",
    "fig4-position-scenario1",
    "fig5-inertia-scenario2",
    "fig6-position-scenario2",
    "fig7-mass-estimate-scenario2",
    "fig8-attitude-scenario2",
    "fig9-trajectory-3d-scenario2",
];

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ftsmc-figures-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn ftsmc(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_ftsmc"))
        .args(args)
        .env_remove("FTSMC_FIGURE_STYLE")
        .output()
        .expect("binary runs");
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// `width="1440px"` → (1440, "px").
fn svg_size(svg: &str) -> ((f64, f64), String) {
    let attr = |name: &str| -> (f64, String) {
        let start = svg.find(&format!(" {name}=\"")).unwrap_or_else(|| panic!("no {name} in SVG")) + name.len() + 3;
        let value = &svg[start..start + svg[start..].find('"').unwrap()];
        let split = value.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(value.len());
        (value[..split].parse().unwrap(), value[split..].to_string())
    };
    let ((w, unit), (h, _)) = (attr("width"), attr("height"));
    ((w, h), unit)
}

/// Decodes, is not blank (many colours), and matches the SVG's size:
/// px at scale 1 (screen) or pt at 300 dpi (paper).
fn check_pair(stem: &Path) -> (u32, u32) {
    let svg_path = stem.with_extension("svg");
    let png_path = stem.with_extension("png");
    let svg = std::fs::read_to_string(&svg_path).unwrap_or_else(|e| panic!("{}: {e}", svg_path.display()));
    assert!(svg.len() > 1000 && svg.trim_end().ends_with("</svg>"), "{}", svg_path.display());
    let pix = Pixmap::load_png(&png_path).unwrap_or_else(|e| panic!("{}: {e}", png_path.display()));
    let colours: HashSet<[u8; 4]> = pix.pixels().iter().map(|p| [p.red(), p.green(), p.blue(), p.alpha()]).collect();
    assert!(colours.len() > 50, "{} looks blank: {} colours", png_path.display(), colours.len());
    let ((w, h), unit) = svg_size(&svg);
    let scale = match unit.as_str() {
        "px" => 1.0,
        "pt" => 300.0 / 72.0,
        other => panic!("unexpected SVG unit {other}"),
    };
    let (ew, eh) = (w * scale, h * scale);
    assert!(
        (f64::from(pix.width()) - ew).abs() <= 1.0 && (f64::from(pix.height()) - eh).abs() <= 1.0,
        "{}: PNG {}×{} but SVG {w}×{h}{unit} × {scale}",
        png_path.display(),
        pix.width(),
        pix.height()
    );
    (pix.width(), pix.height())
}

#[test]
fn reproduce_writes_every_figure_as_matching_svg_and_png() {
    let dir = temp_dir("reproduce");
    let out = dir.join("res");
    ftsmc(&["reproduce", "--realistic-runs", "4", "--out", out.to_str().unwrap()]);
    for name in FIGURES {
        let (w, _) = check_pair(&out.join("figures").join(name));
        assert!(w >= 800, "{name}: screen figures are at least 800 px wide, got {w}");
    }
    // Text is real text in the SVG (not paths), hats as combining marks.
    let fig3 = std::fs::read_to_string(out.join("figures/fig3-adaptive-gains-scenario1.svg")).unwrap();
    assert!(fig3.contains("δ\u{302}"), "δ̂ is written as text");
    // References are dashed, and so are their legend samples.
    let fig1 = std::fs::read_to_string(out.join("figures/fig1-attitude-scenario1.svg")).unwrap();
    assert!(fig1.matches("stroke-dasharray").count() >= 6, "dashed references and legend samples");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn paper_style_is_journal_sized_at_300_dpi() {
    let dir = temp_dir("paper");
    ftsmc(&["run", "paper-scenario-1", "--style", "paper", "--out", dir.to_str().unwrap()]);
    let figs = dir.join("paper-scenario-1/figures");
    for name in ["position", "attitude", "controls"] {
        let (w, _) = check_pair(&figs.join(name));
        // Seven inches (double column) at 300 dpi.
        assert_eq!(w, 2100, "{name}");
        let svg = std::fs::read_to_string(figs.join(name).with_extension("svg")).unwrap();
        assert!(svg.contains(r#"width="504pt""#), "{name}: SVG is 7 in wide");
        // No text below 8 pt.
        for part in svg.split("font-size=\"").skip(1) {
            let size: f64 = part[..part.find('"').unwrap()].parse().unwrap();
            assert!(size >= 8.0, "{name}: {size} pt text");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
