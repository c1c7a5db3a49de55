//! Forest plots: one row per contestant, its estimate as a dot and its
//! confidence interval as a bar, one panel per metric side by side
//! (`ftsmc compare`'s `forest.svg` / `.png`). Drawn on the project's SVG
//! writer ([`crate::svg`]) and rasterised by [`crate::raster`], like every
//! other figure.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use ftsmc_sim::stats::Interval;

use crate::plot::controller_color;
use crate::svg::{Anchor, Font, Rgb, Stroke, Svg};

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

/// Write `stem.svg` and `stem.png`; returns their paths.
pub fn write_forest(title: &str, panels: &[ForestPanel], stem: &Path) -> Result<Vec<PathBuf>> {
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
        let w = PANEL_W - 30.0;
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
        svg.text(x0 + w / 2.0, TOP - 18.0, &panel.label, &Font::new(11.0, Anchor::Middle));
        let ticks = Font::new(10.0, Anchor::Middle);
        for t in 0..=4 {
            let v = lo + (hi - lo) * f64::from(t) / 4.0;
            svg.line(x(v), y_bottom + 6.0, x(v), y_bottom + 10.0, &frame);
            svg.text(x(v), y_bottom + 20.0, &format!("{v:.3}"), &ticks);
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
    let svg = svg.finish();
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
