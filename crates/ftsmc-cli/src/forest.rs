//! Forest plots: one row per contestant, its estimate as a dot and its
//! confidence interval as a bar, one panel per metric side by side
//! (`ftsmc compare`'s `forest.svg` / `.png`). Drawn on the project's SVG
//! writer ([`crate::svg`]) and rasterised by [`crate::raster`], like every
//! other figure.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use ftsmc_sim::stats::Interval;

use crate::plot::controller_color;
use crate::svg::{text_width, Anchor, Font, Rgb, Stroke, Svg};

/// One panel: a metric and each contestant's interval (`None`: no value).
pub struct ForestPanel {
    /// Axis label, with the unit.
    pub label: String,
    /// `(contestant, controller for the colour, interval)`.
    pub rows: Vec<(String, String, Option<Interval>)>,
}

const ROW: f64 = 26.0;
const NAME_W: f64 = 150.0;
const PANEL_W: f64 = 300.0;
const TOP: f64 = 46.0;
const BOTTOM: f64 = 40.0;
/// Tick label size, px.
const TICK_SIZE: f64 = 10.0;
/// Gap between two panels' frames, px: a tick label may reach into it by
/// at most [`LABEL_OVERHANG`], so labels of neighbouring panels keep apart.
const PANEL_GAP: f64 = 30.0;
/// How far a tick label may reach beyond its panel's frame, px.
const LABEL_OVERHANG: f64 = 8.0;
/// Least space between two tick labels of one axis, px.
const LABEL_SPACE: f64 = 6.0;

/// Write `stem.svg` and `stem.png`; returns their paths.
pub fn write_forest(title: &str, panels: &[ForestPanel], stem: &Path) -> Result<Vec<PathBuf>> {
    let svg = forest_svg(title, panels);
    if let Some(dir) = stem.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let (svg_path, png_path) = (stem.with_extension("svg"), stem.with_extension("png"));
    let png = crate::raster::png_from_svg(&svg, 2.0, None)
        .with_context(|| format!("cannot render {}", png_path.display()))?;
    crate::output::write_atomic(&svg_path, svg.as_bytes())?;
    crate::output::write_atomic(&png_path, &png)?;
    Ok(vec![svg_path, png_path])
}

/// The forest plot as an SVG document. Ticks are "nice" values
/// ([`crate::ticks::linear`]); a tick label that would overlap the one
/// before it, or reach more than [`LABEL_OVERHANG`] beyond its panel, is
/// left out (its tick stays), so no two labels collide.
fn forest_svg(title: &str, panels: &[ForestPanel]) -> String {
    let rows = panels.first().map_or(0, |p| p.rows.len());
    let width = NAME_W + PANEL_W * panels.len() as f64 + 20.0;
    let height = TOP + ROW * rows as f64 + BOTTOM;
    let mut svg = Svg::new(width, height, "px");
    let mut bold = Font::new(13.0, Anchor::Start);
    bold.bold = true;
    svg.text(10.0, 14.0, title, &bold);
    if let Some(first) = panels.first() {
        for (r, (name, _, _)) in first.rows.iter().enumerate() {
            svg.text(NAME_W - 8.0, TOP + ROW * (r as f64 + 0.5), name, &Font::new(11.0, Anchor::End));
        }
    }
    let frame = Stroke::solid(Rgb(120, 120, 120), 0.8);
    for (k, panel) in panels.iter().enumerate() {
        let x0 = NAME_W + PANEL_W * k as f64 + 10.0;
        let w = PANEL_W - PANEL_GAP;
        let finite: Vec<f64> = panel
            .rows
            .iter()
            .filter_map(|r| r.2)
            .flat_map(|i| [i.lo, i.estimate, i.hi])
            .filter(|x| x.is_finite())
            .collect();
        let (mut lo, mut hi) =
            finite.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
        if !lo.is_finite() {
            (lo, hi) = (0.0, 1.0);
        }
        if hi - lo < 1e-12 {
            (lo, hi) = (lo - 0.5 * lo.abs().max(1e-3), hi + 0.5 * hi.abs().max(1e-3));
        }
        let pad = 0.05 * (hi - lo);
        let (lo, hi) = (lo - pad, hi + pad);
        let x = |v: f64| x0 + w * ((v.clamp(lo, hi) - lo) / (hi - lo));
        let y_bottom = TOP + ROW * rows as f64;
        svg.rect(x0, TOP - 6.0, w, y_bottom - TOP + 12.0, None, Some(&frame));
        let ticks = crate::ticks::linear(lo, hi, 5);
        let label = match &ticks.note {
            Some(note) => format!("{} ({note})", panel.label),
            None => panel.label.clone(),
        };
        svg.text(x0 + w / 2.0, TOP - 18.0, &label, &Font::new(11.0, Anchor::Middle));
        let font = Font::new(TICK_SIZE, Anchor::Middle);
        let mut right_of_last = f64::NEG_INFINITY;
        for (v, text) in ticks.values.iter().zip(&ticks.labels) {
            if *v < lo || *v > hi {
                continue;
            }
            let xv = x(*v);
            svg.line(xv, y_bottom + 6.0, xv, y_bottom + 10.0, &frame);
            let half = text_width(text, TICK_SIZE) / 2.0;
            let fits = xv - half >= x0 - LABEL_OVERHANG && xv + half <= x0 + w + LABEL_OVERHANG;
            if fits && xv - half >= right_of_last + LABEL_SPACE {
                svg.text(xv, y_bottom + 20.0, text, &font);
                right_of_last = xv + half;
            }
        }
        svg.group("data");
        for (r, (_, controller, interval)) in panel.rows.iter().enumerate() {
            let y = TOP + ROW * (r as f64 + 0.5);
            let Some(i) = interval else {
                svg.text(x0 + 6.0, y, "—", &Font::new(11.0, Anchor::Start));
                continue;
            };
            let color = controller_color(controller);
            // An infinite bound runs to the frame, with an arrow-like cap left off.
            svg.line(x(i.lo), y, x(i.hi), y, &Stroke::solid(color, 2.0));
            for b in [i.lo, i.hi].into_iter().filter(|b| b.is_finite()) {
                svg.line(x(b), y - 5.0, x(b), y + 5.0, &Stroke::solid(color, 1.5));
            }
            if i.estimate.is_finite() {
                svg.circle(x(i.estimate), y, 4.0, color, None);
            }
        }
        svg.end_group();
    }
    svg.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(x, y, width)` of every text of `svg` on the line `y`, its width
    /// estimated as 0.6 × font size per character, placed by its anchor.
    fn boxes(svg: &str) -> Vec<(f64, f64, f64, String)> {
        let doc = resvg::usvg::roxmltree::Document::parse(svg).unwrap();
        doc.descendants()
            .filter(|n| n.has_tag_name("text"))
            .map(|n| {
                let num = |a: &str| n.attribute(a).unwrap().parse::<f64>().unwrap();
                let text = n.text().unwrap_or("").to_string();
                let w = 0.6 * num("font-size") * text.chars().count() as f64;
                let left = match n.attribute("text-anchor") {
                    Some("middle") => num("x") - w / 2.0,
                    Some("end") => num("x") - w,
                    _ => num("x"),
                };
                (left, num("y"), w, text)
            })
            .collect()
    }

    fn interval(lo: f64, estimate: f64, hi: f64) -> Option<Interval> {
        Some(Interval { lo, estimate, hi })
    }

    /// Three panels whose ranges give long labels (large, small, offset
    /// values): no two texts on one line overlap.
    #[test]
    fn tick_labels_never_overlap() {
        let panel = |label: &str, a: [f64; 3], b: [f64; 3]| ForestPanel {
            label: label.into(),
            rows: vec![
                ("pid".into(), "pid".into(), interval(a[0], a[1], a[2])),
                ("se3".into(), "se3".into(), interval(b[0], b[1], b[2])),
            ],
        };
        for panels in [
            vec![
                panel("success (pp)", [-32.0, -28.4, 0.1], [-6.5, -5.5, 100.0]),
                panel("RMS (m)", [0.0631, 0.0672, 0.0719], [0.1341, 0.139, 0.1452]),
                panel("ISE", [123456.7, 234567.8, 345678.9], [-98765.4, 1.0, 99999.9]),
            ],
            vec![
                panel("a", [2.000001, 2.000002, 2.000003], [2.0000015, 2.0000025, 2.0000031]),
                panel("b", [-1e-7, 0.0, 3e-7], [-2e-7, 1e-7, 4e-7]),
                panel("c", [-0.3333, 0.1234, 0.9876], [0.5555, 0.6666, 0.7777]),
            ],
        ] {
            let svg = forest_svg("forest", &panels);
            let b = boxes(&svg);
            assert!(b.len() >= 10, "{svg}");
            for (i, p) in b.iter().enumerate() {
                for q in &b[i + 1..] {
                    if (p.1 - q.1).abs() < 1.0 {
                        assert!(p.0 + p.2 <= q.0 || q.0 + q.2 <= p.0, "{p:?} overlaps {q:?}\n{svg}");
                    }
                }
            }
        }
    }
}
