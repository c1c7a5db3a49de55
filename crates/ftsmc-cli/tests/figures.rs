//! Figure smoke tests: every figure `reproduce` promises is written as SVG and
//! PNG, the PNG decodes and is not blank, and PNG and SVG have the same size
//! (the PNG is the SVG rasterised at the style's scale).

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use resvg::tiny_skia::Pixmap;

mod common;
use common::scratch;

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

/// One `reproduce` (screen style, 4 Monte Carlo runs) shared by the tests
/// of this file: the run takes most of their time.
fn reproduced() -> &'static Path {
    static OUT: OnceLock<PathBuf> = OnceLock::new();
    OUT.get_or_init(|| {
        let tmp = scratch("reproduce");
        let out = tmp.path().join("res");
        ftsmc(&["reproduce", "--realistic-runs", "4", "--out", out.to_str().unwrap()]);
        common::removed_at_exit(tmp).join("res")
    })
}

/// One `ftsmc run` of the rigid-body scenario 1, where FTAFTSMC flips over.
fn flipped() -> &'static Path {
    static OUT: OnceLock<PathBuf> = OnceLock::new();
    OUT.get_or_init(|| {
        let tmp = scratch("flip");
        let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/realism/rigid-body-scenario-1.toml");
        ftsmc(&["run", scenario.to_str().unwrap(), "--out", tmp.path().to_str().unwrap()]);
        common::removed_at_exit(tmp).join("rigid-body-scenario-1/figures")
    })
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The SVG split into panels (each panel starts by defining its clip).
fn panels(svg: &str) -> Vec<&str> {
    svg.split("<clipPath").skip(1).collect()
}

#[test]
fn reproduce_writes_every_figure_as_matching_svg_and_png() {
    let out = reproduced();
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
}

#[test]
fn references_are_drawn_beneath_the_data() {
    // fig6 and fig9: a dashed reference drawn last hid FTAFTSMC, which tracks it closely.
    for name in ["fig6-position-scenario2", "fig4-position-scenario1", "fig1-attitude-scenario1"] {
        let svg = read(&reproduced().join("figures").join(name).with_extension("svg"));
        for (k, panel) in panels(&svg).into_iter().enumerate() {
            let (Some(last_ref), Some(first_data)) = (
                panel.rfind(r#"<g class="reference"#),
                [panel.find(r#"<g class="data">"#), panel.find(r#"<g class="band">"#)].into_iter().flatten().min(),
            ) else {
                continue;
            };
            assert!(last_ref < first_data, "{name}, panel {k}: a reference is drawn over the data");
        }
    }
    let fig9 = read(&reproduced().join("figures/fig9-trajectory-3d-scenario2.svg"));
    let last_ref = fig9.rfind(r#"<g class="reference">"#).expect("fig9 draws the reference");
    let first_data = fig9.find(r#"<g class="data">"#).expect("fig9 draws the flights");
    assert!(last_ref < first_data, "fig9: the reference is drawn over the flights");
}

#[test]
fn chattering_is_drawn_as_a_band_per_pixel_column_with_its_mean() {
    // fig1 and fig2: FTAFTSMC's and RANFTSMC's attitude limit cycle and torques
    // chatter; drawn as lines they filled the panel as solid bands.
    for name in ["fig1-attitude-scenario1", "fig2-controls-scenario1"] {
        let svg = read(&reproduced().join("figures").join(name).with_extension("svg"));
        let ((width, _), _) = svg_size(&svg);
        let bands: Vec<&str> =
            svg.split(r#"<g class="band">"#).skip(1).map(|g| &g[..g.find("</g>").unwrap()]).collect();
        assert!(!bands.is_empty(), "{name}: no chattering band");
        for band in bands {
            // A filled min/max outline and a mean line, each at most one
            // vertex per pixel column and side: not 20 000 points of noise.
            assert!(band.contains("fill-opacity") && band.contains("stroke-width"), "{name}: {band:.200}");
            let vertices = band.matches('L').count();
            assert!(vertices as f64 <= 3.0 * width, "{name}: {vertices} vertices on a {width} wide figure");
        }
    }
}

#[test]
fn no_legend_entry_without_a_drawn_series() {
    // fig7 listed "α̂·m, FTAFTSMC (no mass adaptation)", a column that is
    // empty (no estimate) and never drawn.
    let out = reproduced();
    let csv = read(&out.join("paper-scenario-2/ftaftsmc-no-mass.csv"));
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    // Without mass adaptation there is no estimate: no column, or no number in it.
    let drawn = header.iter().position(|h| *h == "mass_estimate").is_some_and(|col| {
        lines.any(|l| l.split(',').nth(col).and_then(|v| v.parse::<f64>().ok()).is_some_and(f64::is_finite))
    });
    let svg = read(&out.join("figures/fig7-mass-estimate-scenario2.svg"));
    assert_eq!(svg.contains("no mass adaptation"), drawn, "legend entry iff the series has a point to draw");
    assert!(svg.contains("true mass") && svg.contains("α̂·m, FTAFTSMC"), "the drawn series keep their entries");
}

#[test]
fn fig4_has_an_error_panel_per_axis() {
    let svg = read(&reproduced().join("figures/fig4-position-scenario1.svg"));
    for axis in ["x", "y", "z"] {
        assert!(svg.contains(&format!(">{axis} error<")), "fig4: no {axis} error panel");
        assert!(svg.contains(&format!("{axis} − {axis}ref (m)")), "fig4: {axis} error label");
    }
    assert_eq!(panels(&svg).len(), 6, "three position panels and three error panels");
}

#[test]
fn reproduce_draws_a_box_per_controller_of_its_monte_carlo() {
    let stem = reproduced().join("figures/beyond/realistic-calm-2-montecarlo");
    check_pair(&stem);
    let svg = read(&stem.with_extension("svg"));
    for label in ["RANFTSMC", "TSM-STA", "FTAFTSMC", "PID", "SE(3)"] {
        assert!(svg.contains(label), "no box for {label}");
    }
    assert!(svg.contains(" of 4 flew"), "each box says how many of the 4 runs completed");
}

#[test]
fn a_run_that_stops_early_ends_in_a_marker_with_its_reason() {
    // FTAFTSMC flips over at 1.22 s on the rigid body; its line used to just stop.
    let svg = read(&flipped().join("position.svg"));
    let ends: Vec<&str> = svg.split(r#"<g class="end">"#).skip(1).collect();
    assert_eq!(ends.len(), 3, "one marker per position panel (FTAFTSMC only)");
    for e in ends {
        assert!(e[..e.find("</g>").unwrap()].contains("diverged (tilt) at 1.22 s"), "{e:.300}");
    }
}

#[test]
fn ftsmc_run_draws_the_x_y_path() {
    let stem = flipped().join("path");
    check_pair(&stem);
    let svg = read(&stem.with_extension("svg"));
    assert!(svg.contains(">x (m)<") && svg.contains(">y (m)<"), "axes are x and y in metres");
    for label in ["reference", "RANFTSMC", "TSM-STA", "FTAFTSMC"] {
        assert!(svg.contains(label), "{label} in the path figure");
    }
    assert!(svg.contains(r#"<g class="end">"#), "the flipped run's path ends in a marker");
}

#[test]
fn paper_style_is_journal_sized_at_300_dpi() {
    let tmp = scratch("paper");
    let dir = tmp.path();
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
}
