//! Figure smoke tests: every figure `reproduce` promises is written as SVG and
//! PNG, the PNG decodes and is not blank, and PNG and SVG have the same size
//! (the PNG is the SVG rasterised at the style's scale).

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use resvg::tiny_skia::Pixmap;

use crate::common::scratch;

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
        crate::common::removed_at_exit(tmp).join("res")
    })
}

/// One `ftsmc run` of the rigid-body scenario 1, where FTAFTSMC flips over.
fn flipped() -> &'static Path {
    static OUT: OnceLock<PathBuf> = OnceLock::new();
    OUT.get_or_init(|| {
        let tmp = scratch("flip");
        let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/realism/rigid-body-scenario-1.toml");
        ftsmc(&["run", scenario.to_str().unwrap(), "--out", tmp.path().to_str().unwrap()]);
        crate::common::removed_at_exit(tmp).join("rigid-body-scenario-1/figures")
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
fn references_are_drawn_on_top_of_the_data() {
    // fig6 and fig9 hid the reference under the FTAFTSMC line, which tracks
    // it closely: references are drawn last (dashed, black) in every panel.
    for name in ["fig6-position-scenario2", "fig4-position-scenario1", "fig1-attitude-scenario1"] {
        let svg = read(&reproduced().join("figures").join(name).with_extension("svg"));
        for (k, panel) in panels(&svg).into_iter().enumerate() {
            let (Some(first_ref), Some(last_data)) = (
                panel.find(r#"<g class="reference"#),
                [panel.rfind(r#"<g class="data">"#), panel.rfind(r#"<g class="band">"#)].into_iter().flatten().max(),
            ) else {
                continue;
            };
            assert!(first_ref > last_data, "{name}, panel {k}: data is drawn over a reference");
        }
    }
    let fig9 = read(&reproduced().join("figures/fig9-trajectory-3d-scenario2.svg"));
    let first_ref = fig9.find(r#"<g class="reference">"#).expect("fig9 draws the reference");
    let last_data = fig9.rfind(r#"<g class="data">"#).expect("fig9 draws the flights");
    assert!(first_ref > last_data, "fig9: a flight is drawn over the reference");
}

#[test]
fn fig9_has_depth_cues_and_enough_ticks() {
    // fig9 had two z ticks and nothing to tell near from far.
    let svg = read(&reproduced().join("figures/fig9-trajectory-3d-scenario2.svg"));
    let shadow = svg.split(r#"<g class="shadow">"#).nth(1).expect("floor shadows");
    assert!(shadow[..shadow.find("</g>").unwrap()].matches("<path").count() >= 4, "a shadow per path");
    // Tick labels: numbers drawn as text with a tick mark; at least 3 per axis.
    let numbers = svg
        .split("<text")
        .skip(1)
        .filter(|t| {
            let inner = &t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()];
            inner.replace('−', "-").parse::<f64>().is_ok()
        })
        .count();
    assert!(numbers >= 9, "{numbers} tick labels on three axes");
}

#[test]
fn chattering_is_drawn_as_its_envelope_named_in_the_legend() {
    // fig1 and fig2: FTAFTSMC's and RANFTSMC's attitude limit cycle and torques
    // chatter. A mean line understated the swing; the envelope is the signal.
    for name in ["fig1-attitude-scenario1", "fig2-controls-scenario1"] {
        let svg = read(&reproduced().join("figures").join(name).with_extension("svg"));
        let ((width, _), _) = svg_size(&svg);
        let bands: Vec<&str> =
            svg.split(r#"<g class="band">"#).skip(1).map(|g| &g[..g.find("</g>").unwrap()]).collect();
        assert!(!bands.is_empty(), "{name}: no chattering band");
        for band in bands {
            // A filled min/max band and its two edges, each at most one
            // vertex per pixel column and side: not 20 000 points of noise.
            assert!(band.contains("fill-opacity=\"0.45\""), "{name}: the band is not faint: {band:.200}");
            let segments = band.split("fill-opacity").count() - 1;
            assert_eq!(band.matches("stroke-width").count(), 2 * segments, "{name}: two edges per band, no mean");
            let vertices = band.matches('L').count();
            assert!(vertices as f64 <= 4.0 * width, "{name}: {vertices} vertices on a {width} wide figure");
        }
        assert!(svg.contains("(min–max per pixel)</text>"), "{name}: the legend names the band");
        assert!(svg.contains(r#"<g class="legend band">"#), "{name}: the legend sample is a band");
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
fn fig4_and_fig6_have_an_error_panel_per_axis() {
    // fig6 hid the reference under the FTAFTSMC line: the error row shows it.
    for (name, count) in [("fig4-position-scenario1", 9), ("fig6-position-scenario2", 6)] {
        let svg = read(&reproduced().join("figures").join(name).with_extension("svg"));
        for axis in ["x", "y", "z"] {
            assert!(svg.contains(&format!(">{axis} error<")), "{name}: no {axis} error panel");
            assert!(svg.contains(&format!("{axis} − {axis}ref (m)")), "{name}: {axis} error label");
        }
        assert_eq!(panels(&svg).len(), count, "{name}: panels");
    }
}

#[test]
fn fig1_and_fig4_zoom_on_the_first_seconds() {
    // All the action is in the first 2-3 s of a 20 s axis: a second row shows them.
    for name in ["fig1-attitude-scenario1", "fig4-position-scenario1"] {
        let svg = read(&reproduced().join("figures").join(name).with_extension("svg"));
        let ps = panels(&svg);
        let zoomed: Vec<&&str> = ps.iter().filter(|p| p.contains(", first 3 s<")).collect();
        assert_eq!(zoomed.len(), 3, "{name}: a zoomed panel per axis");
        for p in zoomed {
            // Its x tick labels stay within the first 3 s.
            let ticks: Vec<f64> = p
                .split("text-anchor=\"middle\">")
                .skip(1)
                .filter_map(|t| t[..t.find('<').unwrap()].parse::<f64>().ok())
                .collect();
            assert!(!ticks.is_empty() && ticks.iter().all(|&t| t <= 3.0), "{name}: zoomed ticks {ticks:?}");
        }
        // The full-length panels share their x ticks.
        let first_ticks = |p: &str| -> Vec<f64> {
            p.split("text-anchor=\"middle\">").skip(1).filter_map(|t| t[..t.find('<').unwrap()].parse().ok()).collect()
        };
        assert_eq!(first_ticks(ps[0]), first_ticks(ps[1]), "{name}: the panels' x ticks differ");
    }
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
fn a_run_that_stops_early_ends_in_a_marker_with_its_reason_in_the_legend() {
    // FTAFTSMC flips over at 1.22 s on the rigid body; its line used to just
    // stop, and then its note was written over the other lines.
    let svg = read(&flipped().join("position.svg"));
    let ends: Vec<&str> = svg.split(r#"<g class="end">"#).skip(1).collect();
    assert_eq!(ends.len(), 3, "one marker per position panel (FTAFTSMC only)");
    for e in ends {
        assert!(!e[..e.find("</g>").unwrap()].contains("<text"), "no note over the data: {e:.300}");
    }
    let legend = &svg[..svg.find("<clipPath").unwrap()];
    assert!(legend.contains("FTAFTSMC — diverged (tilt) at 1.22 s</text>"), "the legend says why and when");
}

#[test]
fn rotor_speeds_come_apart_and_their_notes_sit_in_titles() {
    // realistic-moderate-2-rotors: four traces overplotted and
    // "diverged (tilt) at 6.49 s" sat over them.
    let svg = read(&reproduced().join("figures/beyond/realistic-moderate-2-rotors.svg"));
    assert!(!svg.contains(r#"<g class="end">"#), "no note or marker over the rotor traces");
    assert_eq!(svg.matches(": ωᵢ − mean of the four<").count(), 5, "a spread panel per controller");
    assert!(svg.contains("FTAFTSMC — "), "the panel title says how the run ended");
}

#[test]
fn monte_carlo_titles_are_not_clipped() {
    // realistic-breeze-1-montecarlo: the title was cut on both sides. Its
    // band of the PNG has no ink in the outermost pixel columns.
    let stem = reproduced().join("figures/beyond/realistic-breeze-1-montecarlo");
    let svg = read(&stem.with_extension("svg"));
    let size: f64 = svg.split("font-size=\"").nth(1).unwrap().split('"').next().unwrap().parse().unwrap();
    let pix = Pixmap::load_png(stem.with_extension("png")).unwrap();
    let band = (size * 1.6) as u32;
    for y in 0..band {
        for x in [0, 1, 2, pix.width() - 3, pix.width() - 2, pix.width() - 1] {
            let p = pix.pixel(x, y).unwrap();
            assert!(p.red() > 240 && p.green() > 240 && p.blue() > 240, "ink at ({x}, {y}): the title is clipped");
        }
    }
}

#[test]
fn ftsmc_run_draws_the_x_y_path() {
    let stem = flipped().join("path");
    check_pair(&stem);
    let svg = read(&stem.with_extension("svg"));
    assert!(svg.contains(">x (m)<") && svg.contains(">y (m)<"), "axes are x and y in metres");
    for label in ["RANFTSMC", "TSM-STA", "FTAFTSMC"] {
        assert!(svg.contains(label), "{label} in the path figure");
    }
    // Scenario 1's reference steps: its set-points are drawn as points (a
    // dashed "reference" drew next to nothing), above the flights.
    assert!(svg.contains("reference set-points</text>"), "the legend names the set-points");
    let points = svg.rfind(r#"<g class="points">"#).expect("set-points drawn");
    assert!(points > svg.rfind(r#"<g class="data">"#).unwrap(), "set-points above the paths");
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
