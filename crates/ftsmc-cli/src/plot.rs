//! Figures: each is written once as SVG (crate::svg) and the PNG is that SVG
//! rasterised by resvg (crate::raster), so the two always agree. The only
//! font is the embedded DejaVu Sans. Legends sit above the panels, outside
//! the data; legend samples are dashed and marked like their lines; tick
//! labels use an offset/power of ten on tiny ranges (crate::ticks), and
//! the panels of one figure share their x tick count; references are drawn
//! dashed *on top of* the data, so they stay visible; a chattering signal
//! is drawn as the min–max envelope of the signal per pixel column (a
//! filled band with its edges, named so in the legend); independent
//! samples (`Series::points`) are points, not a line; a series with no
//! drawable point has no legend entry; a run that stopped early ends in a ×
//! and its legend entry says why and when ("diverged (tilt) at 6.49 s"),
//! so no note is written over the data.
//!
//! Two styles ([`Style`]): `screen` (readable at 100 %, text ≥ 14 px) and
//! `paper` (3.5 in or 7 in wide, text ≥ 8 pt, PNG at 300 dpi, SVG in pt).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU8, Ordering};

use anyhow::{Context, Result};

pub use crate::svg::Rgb;
use crate::svg::{text_width, Anchor, Font, Stroke, Svg, VAlign};
use crate::ticks::{self, Ticks};

/// Points drawn per series at most; min/max per bucket keep spikes visible.
const MAX_POINTS: usize = 3000;
/// A line with at most this many points gets a marker at each point.
const MARKER_POINTS: usize = 40;

/// Figure style.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Style {
    /// Sized for a screen: text ≥ 14 px at 100 %, PNG at 1 px per SVG px.
    #[default]
    Screen,
    /// Journal sizes: 3.5 in (one column) or 7 in (two columns) wide, text ≥ 8 pt, PNG at 300 dpi.
    Paper,
}

static STYLE: AtomicU8 = AtomicU8::new(0);

/// Set the style of every figure written from now on.
pub fn set_style(style: Style) {
    STYLE.store(if style == Style::Paper { 2 } else { 1 }, Ordering::Relaxed);
}

/// The style in force: [`set_style`], else `FTSMC_FIGURE_STYLE` (screen|paper), else screen.
pub fn style() -> Style {
    match STYLE.load(Ordering::Relaxed) {
        1 => Style::Screen,
        2 => Style::Paper,
        _ => match std::env::var("FTSMC_FIGURE_STYLE").map(|v| v.trim().to_ascii_lowercase()).as_deref() {
            Ok("paper") => Style::Paper,
            _ => Style::Screen,
        },
    }
}

/// Sizes of one style, in its user unit (px or pt).
struct Look {
    unit: &'static str,
    /// Device pixels per CSS px for the PNG.
    render_scale: f32,
    dpi: Option<u32>,
    narrow: f64,
    wide: f64,
    aspect: f64,
    aspect_single: f64,
    title: f64,
    panel_title: f64,
    label: f64,
    tick: f64,
    legend: f64,
    line: f64,
    thin: f64,
    dash: [f64; 2],
    frame: f64,
    grid: f64,
    tick_len: f64,
    pad: f64,
    marker: f64,
}

fn look() -> Look {
    match style() {
        Style::Screen => Look {
            unit: "px",
            render_scale: 1.0,
            dpi: None,
            narrow: 820.0,
            wide: 1440.0,
            aspect: 0.7,
            aspect_single: 0.6,
            title: 22.0,
            panel_title: 17.0,
            label: 16.0,
            tick: 15.0,
            legend: 15.0,
            line: 1.8,
            thin: 0.8,
            dash: [7.0, 4.0],
            frame: 1.0,
            grid: 0.8,
            tick_len: 5.0,
            pad: 12.0,
            marker: 3.2,
        },
        Style::Paper => Look {
            unit: "pt",
            // 300 dpi: 300/72 device pixels per pt, and 1 pt = 4/3 CSS px.
            render_scale: 300.0 / 96.0,
            dpi: Some(300),
            narrow: 252.0,
            wide: 504.0,
            aspect: 0.78,
            aspect_single: 0.72,
            title: 0.0,
            panel_title: 9.0,
            label: 8.5,
            tick: 8.0,
            legend: 8.0,
            line: 1.0,
            thin: 0.45,
            dash: [3.2, 1.8],
            frame: 0.5,
            grid: 0.35,
            tick_len: 2.5,
            pad: 4.0,
            marker: 1.6,
        },
    }
}

/// One line on a panel. `xs` and `ys` have the same length; non-finite
/// values break the line.
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Abscissae.
    pub xs: Vec<f64>,
    /// Ordinates.
    pub ys: Vec<f64>,
    /// Line colour.
    pub color: Rgb,
    /// Dashed (references, bounds) or solid.
    pub dashed: bool,
    /// Why the line stops early ("diverged (tilt) at 1.22 s"), if it does:
    /// its last point gets a × marker and its legend entry this text.
    pub end: Option<String>,
    /// Independent samples (e.g. tuning candidates): a point per value, no
    /// line joining them.
    pub points: bool,
}

/// One subplot.
pub struct Panel {
    /// Panel title.
    pub title: String,
    /// x-axis label with units.
    pub x_label: String,
    /// y-axis label with units.
    pub y_label: String,
    /// Lines.
    pub series: Vec<Series>,
    /// Logarithmic x axis (non-positive values skipped).
    pub log_x: bool,
    /// Logarithmic y axis (non-positive values skipped).
    pub log_y: bool,
}

/// A grid of panels with an overall title.
pub struct Figure {
    /// Figure title (screen style only; a paper figure has a caption instead).
    pub title: String,
    /// Panels, row-major.
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub columns: usize,
}

/// A 3-D polyline.
pub struct Series3 {
    /// Legend text.
    pub label: String,
    /// Points `[x, y, z]`, m.
    pub points: Vec<[f64; 3]>,
    /// Colour.
    pub color: Rgb,
    /// Dashed (reference) or solid.
    pub dashed: bool,
}

/// One box of a box plot.
pub struct BoxGroup {
    /// Category label (wrapped at spaces to fit under its box).
    pub label: String,
    /// Sample values.
    pub values: Vec<f64>,
    /// Colour.
    pub color: Rgb,
}

/// A box-plot panel: one box per group (box q1–q3, median line, whiskers p5–p95).
pub struct BoxPanel {
    /// Panel title.
    pub title: String,
    /// y-axis label.
    pub y_label: String,
    /// Boxes.
    pub groups: Vec<BoxGroup>,
    /// Logarithmic y axis.
    pub log_y: bool,
}

/// The colour of a controller, the same in every figure.
pub fn controller_color(name: &str) -> Rgb {
    match name {
        "ftaftsmc" => Rgb(31, 119, 180),
        "ranftsmc" => Rgb(255, 127, 14),
        "tsm-sta" => Rgb(44, 160, 44),
        "ftaftsmc-no-mass" => Rgb(148, 103, 189),
        "ftaftsmc-tuned" => Rgb(23, 190, 207),
        "ftaftsmc-zero-derivatives" => Rgb(140, 86, 75),
        "pid" => Rgb(214, 39, 40),
        "se3" => Rgb(227, 119, 194),
        "reference" => Rgb(0, 0, 0),
        other => {
            const PALETTE: [Rgb; 6] = [
                Rgb(214, 39, 40),
                Rgb(227, 119, 194),
                Rgb(127, 127, 127),
                Rgb(188, 189, 34),
                Rgb(140, 86, 75),
                Rgb(23, 190, 207),
            ];
            let hash = other.bytes().fold(5381u32, |h, b| h.wrapping_mul(33) ^ u32::from(b));
            PALETTE[hash as usize % PALETTE.len()]
        }
    }
}

const INK: Rgb = Rgb(40, 40, 40);
const GRID: Rgb = Rgb(228, 228, 228);
const MINOR_GRID: Rgb = Rgb(242, 242, 242);

/// Write `<stem>.svg` and its rasterisation `<stem>.png`, each atomically.
fn write(stem: &Path, svg: String, lk: &Look) -> Result<Vec<PathBuf>> {
    if let Some(dir) = stem.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let svg_path = stem.with_extension("svg");
    let png_path = stem.with_extension("png");
    let png = crate::raster::png_from_svg(&svg, lk.render_scale, lk.dpi)
        .with_context(|| format!("cannot render {}", png_path.display()))?;
    crate::output::write_atomic(&svg_path, svg.as_bytes())?;
    crate::output::write_atomic(&png_path, &png)?;
    Ok(vec![svg_path, png_path])
}

// ---------------------------------------------------------------- legend

/// A legend entry: a line sample (dashed/marked like its line) and a label.
struct Entry {
    label: String,
    color: Rgb,
    dashed: bool,
    marker: bool,
    /// The sample is a filled band (a chattering signal's min–max envelope).
    band: bool,
    /// The sample is a point without a line.
    points: bool,
}

/// Legend suffix of a chattering signal drawn as its envelope.
pub const BAND_NOTE: &str = " (min–max per pixel)";

fn has_markers(s: &Series) -> bool {
    s.points
        || (!s.dashed
            && s.xs.iter().zip(&s.ys).filter(|(x, y)| x.is_finite() && y.is_finite()).count() <= MARKER_POINTS)
}

/// The legend text of `s`: its label, the band note if it is drawn as a
/// band, and why it stopped early.
fn entry_label(s: &Series, band: bool) -> String {
    let mut label = s.label.clone();
    if band {
        label.push_str(BAND_NOTE);
    }
    if let Some(end) = &s.end {
        label.push_str(" — ");
        label.push_str(end);
    }
    label
}

/// Whether `s` is drawn as a band on `panel` (see [`chatters`]).
fn banded(s: &Series, panel: &Panel) -> bool {
    match range(panel.series.iter().flat_map(|s| s.ys.iter().copied()), panel.log_y) {
        Some((y0, y1)) => !s.points && chatters(s, panel, (y1 - y0) * 0.004),
        None => false,
    }
}

/// True when at least one point of `s` can be drawn on `panel`'s axes.
fn drawable(s: &Series, panel: &Panel) -> bool {
    s.xs.iter()
        .zip(&s.ys)
        .any(|(x, y)| x.is_finite() && y.is_finite() && (!panel.log_x || *x > 0.0) && (!panel.log_y || *y > 0.0))
}

/// One entry per distinct label for the series that are drawn (a series
/// without a drawable point has no entry), in the order the series' own
/// labels first appear: the runs in the order they were given (the
/// controller order), a run's variants together — `ω1` drawn as a band on
/// one panel and as a line on another gives two entries side by side, not
/// one at each end of the legend.
fn entries_of<'a>(series: impl Iterator<Item = (&'a Series, &'a Panel)>) -> Vec<Entry> {
    let mut bases: Vec<&str> = Vec::new();
    let mut out: Vec<(usize, Entry)> = Vec::new();
    for (s, panel) in series {
        if s.label.is_empty() || !drawable(s, panel) {
            continue;
        }
        let band = banded(s, panel);
        let label = entry_label(s, band);
        if out.iter().any(|(_, e)| e.label == label) {
            continue;
        }
        let group = bases.iter().position(|b| *b == s.label).unwrap_or_else(|| {
            bases.push(&s.label);
            bases.len() - 1
        });
        out.push((
            group,
            Entry { label, color: s.color, dashed: s.dashed, marker: has_markers(s), band, points: s.points },
        ));
    }
    // Stable: within a group, the order of first appearance.
    out.sort_by_key(|(group, _)| *group);
    out.into_iter().map(|(_, e)| e).collect()
}

/// Rows of entry indices that fit in `width`, and the legend's height.
fn legend_rows(entries: &[Entry], width: f64, lk: &Look) -> (Vec<Vec<usize>>, f64) {
    let mut rows: Vec<Vec<usize>> = Vec::new();
    let mut used = 0.0;
    for (i, e) in entries.iter().enumerate() {
        let w = entry_width(e, lk);
        if rows.is_empty() || used + w > width {
            rows.push(Vec::new());
            used = 0.0;
        }
        rows.last_mut().unwrap().push(i);
        used += w;
    }
    let h = if rows.is_empty() { 0.0 } else { rows.len() as f64 * lk.legend * 1.55 + lk.legend * 0.5 };
    (rows, h)
}

fn sample_len(lk: &Look) -> f64 {
    lk.legend * 2.6
}

fn entry_width(e: &Entry, lk: &Look) -> f64 {
    sample_len(lk) + lk.legend * 0.45 + text_width(&e.label, lk.legend) + lk.legend * 1.5
}

fn draw_legend(svg: &mut Svg, entries: &[Entry], x: f64, y: f64, width: f64, lk: &Look) -> f64 {
    let (rows, h) = legend_rows(entries, width, lk);
    for (r, row) in rows.iter().enumerate() {
        let total: f64 = row.iter().map(|&i| entry_width(&entries[i], lk)).sum::<f64>() - lk.legend * 1.5;
        let mut cx = x + (width - total).max(0.0) / 2.0;
        let cy = y + lk.legend * 0.25 + (r as f64 + 0.5) * lk.legend * 1.55;
        for &i in row {
            let e = &entries[i];
            let stroke =
                Stroke { color: e.color, width: lk.line * 1.15, dash: e.dashed.then_some(lk.dash), opacity: 1.0 };
            if e.band {
                let h = lk.legend * 0.7;
                svg.group("legend band");
                svg.rect(cx, cy - h / 2.0, sample_len(lk), h, Some((e.color, BAND_OPACITY)), None);
                svg.line(cx, cy - h / 2.0, cx + sample_len(lk), cy - h / 2.0, &Stroke::solid(e.color, lk.thin));
                svg.line(cx, cy + h / 2.0, cx + sample_len(lk), cy + h / 2.0, &Stroke::solid(e.color, lk.thin));
                svg.end_group();
            } else if !e.points {
                svg.line(cx, cy, cx + sample_len(lk), cy, &stroke);
            }
            if e.marker {
                svg.circle(cx + sample_len(lk) / 2.0, cy, lk.marker * 1.1, e.color, None);
            }
            let tx = cx + sample_len(lk) + lk.legend * 0.45;
            svg.text(tx, cy, &e.label, &Font::new(lk.legend, Anchor::Start));
            cx += entry_width(e, lk);
        }
    }
    h
}

/// The title's font size: the style's, smaller if the title would not fit
/// in `width` (never clipped at the figure's edges).
fn title_size(title: &str, width: f64, lk: &Look) -> f64 {
    let room = width - 2.0 * lk.pad;
    let w = text_width(title, lk.title);
    if w <= room {
        lk.title
    } else {
        lk.title * room / w
    }
}

/// Fill opacity of a chattering signal's envelope.
const BAND_OPACITY: f64 = 0.45;

fn draw_title(svg: &mut Svg, title: &str, width: f64, lk: &Look) -> f64 {
    if lk.title <= 0.0 || title.is_empty() {
        return lk.pad * 0.5;
    }
    let f = Font { bold: false, ..Font::new(title_size(title, width, lk), Anchor::Middle) };
    svg.text(width / 2.0, lk.title * 0.95, title, &f);
    lk.title * 1.8
}

// ---------------------------------------------------------------- figures

/// Write `fig` to `<stem>.svg` and `<stem>.png`.
pub fn write_figure(fig: &Figure, stem: &Path) -> Result<Vec<PathBuf>> {
    let lk = look();
    let columns = fig.columns.max(1);
    let rows = fig.panels.len().div_ceil(columns).max(1);
    let width = if columns == 1 { lk.narrow } else { lk.wide };
    let entries = entries_of(fig.panels.iter().flat_map(|p| p.series.iter().map(move |s| (s, p))));
    let inner = width - 2.0 * lk.pad;
    let (_, legend_h) = legend_rows(&entries, inner, &lk);
    let title_h = if lk.title > 0.0 && !fig.title.is_empty() { lk.title * 1.8 } else { lk.pad * 0.5 };
    let panel_w = inner / columns as f64;
    let panel_h = panel_w * if columns == 1 { lk.aspect_single } else { lk.aspect };
    let height = (title_h + legend_h + rows as f64 * panel_h + lk.pad).ceil();
    let mut svg = Svg::new(width, height, lk.unit);
    draw_title(&mut svg, &fig.title, width, &lk);
    draw_legend(&mut svg, &entries, lk.pad, title_h, inner, &lk);
    for (i, panel) in fig.panels.iter().enumerate() {
        let (r, c) = (i / columns, i % columns);
        let x = lk.pad + c as f64 * panel_w;
        let y = title_h + legend_h + r as f64 * panel_h;
        draw_panel(&mut svg, (x, y, panel_w, panel_h), panel, &lk);
    }
    write(stem, svg.finish(), &lk)
}

/// Finite range of values (positive only on a log axis), padded by 5 %.
fn range(values: impl Iterator<Item = f64>, log: bool) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && (!log || *v > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
    if !lo.is_finite() {
        return None;
    }
    if log {
        let (lo, hi) = if hi / lo < 1.5 { (lo / 1.5, hi * 1.5) } else { (lo, hi) };
        // Padding stays within the positive finite doubles (values up to f64::MAX are legal).
        return Some(((lo / 1.2).max(f64::MIN_POSITIVE), (hi * 1.2).min(f64::MAX)));
    }
    let (lo, hi) = if hi - lo <= 1e-12 * hi.abs().max(1.0) {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - d, hi + d)
    } else {
        (lo, hi)
    };
    let pad = 0.05 * (hi / 2.0 - lo / 2.0) * 2.0;
    Some(((lo - pad).max(-f64::MAX), (hi + pad).min(f64::MAX)))
}

/// Split at non-finite points (and non-positive ones on log axes), then
/// keep at most `MAX_POINTS` per series with min/max per bucket.
fn segments(s: &Series, log_x: bool, log_y: bool) -> Vec<Vec<(f64, f64)>> {
    let n = s.xs.len().min(s.ys.len());
    let bucket = n.div_ceil(MAX_POINTS / 2).max(1);
    let ok = |x: f64, y: f64| x.is_finite() && y.is_finite() && (!log_x || x > 0.0) && (!log_y || y > 0.0);
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    let mut start = 0;
    while start < n {
        let end = (start + bucket).min(n);
        let chunk: Vec<(f64, f64)> = (start..end).map(|i| (s.xs[i], s.ys[i])).collect();
        if chunk.iter().any(|&(x, y)| !ok(x, y)) {
            // Keep the valid points of a broken bucket, then break the line.
            for &(x, y) in &chunk {
                if ok(x, y) {
                    current.push((x, y));
                } else if !current.is_empty() {
                    out.push(std::mem::take(&mut current));
                }
            }
        } else if bucket == 1 {
            current.extend(chunk);
        } else {
            let (imin, imax) = chunk.iter().enumerate().fold((0, 0), |(a, b), (i, p)| {
                (if p.1 < chunk[a].1 { i } else { a }, if p.1 > chunk[b].1 { i } else { b })
            });
            let (first, second) = if imin <= imax { (imin, imax) } else { (imax, imin) };
            current.push(chunk[first]);
            if second != first {
                current.push(chunk[second]);
            }
        }
        start = end;
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

/// Chattering as drawn: more than 150 reversals, each larger than `tol`,
/// among the decimated points: drawn opaque it would fill the plot as a solid band.
fn chatters(s: &Series, panel: &Panel, tol: f64) -> bool {
    let mut reversals = 0;
    for seg in segments(s, panel.log_x, panel.log_y) {
        let mut dir = 0.0;
        let mut anchor = seg.first().map_or(0.0, |p| p.1);
        for &(_, y) in &seg[1..] {
            let d = y - anchor;
            if d.abs() > tol {
                if dir * d < 0.0 {
                    reversals += 1;
                }
                dir = d.signum();
                anchor = y;
            }
        }
    }
    reversals > 150
}

/// Total variation per sample, ignoring non-finite values.
fn variation(ys: &[f64]) -> f64 {
    let tv: f64 = ys.windows(2).map(|w| (w[1] - w[0]).abs()).filter(|d| d.is_finite()).sum();
    tv / ys.len().max(1) as f64
}

/// A data → drawing coordinate map for one axis.
#[derive(Clone, Copy)]
struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
    /// Drawing coordinate of `lo` and of `hi`.
    a: f64,
    b: f64,
}

impl Axis {
    fn map(&self, v: f64) -> f64 {
        let t = |v: f64| if self.log { ftsmc_core::math::log10(v) } else { v };
        self.a + (t(v) - t(self.lo)) / (t(self.hi) - t(self.lo)) * (self.b - self.a)
    }
}

fn axis_ticks(lo: f64, hi: f64, log: bool, target: usize) -> Ticks {
    let mut t = if log { ticks::log(lo, hi, (target * 2 / 3).max(3)) } else { ticks::linear(lo, hi, target) };
    let keep: Vec<bool> = t.values.iter().map(|v| *v >= lo && *v <= hi).collect();
    let mut k = keep.iter();
    t.labels.retain(|_| *k.next().unwrap());
    t.values.retain(|v| *v >= lo && *v <= hi);
    t
}

/// The plot rectangle of a panel and its axes, after laying out labels.
struct Frame {
    x: f64,
    y: f64,
    w: f64,
    h: f64,
    xt: Ticks,
    yt: Ticks,
}

/// Lay out a panel in `rect`: title on top, y label and tick labels to the
/// left, x tick labels and label below.
fn frame(
    rect: (f64, f64, f64, f64),
    title: &str,
    y_label: &str,
    x_range: Option<(f64, f64, bool)>,
    y_range: (f64, f64, bool),
    bottom_lines: usize,
    lk: &Look,
) -> Frame {
    let (x, y, w, h) = rect;
    let top = if title.is_empty() { lk.tick * 1.0 } else { lk.panel_title * 1.7 };
    let bottom = lk.tick_len + bottom_lines as f64 * lk.tick * 1.2 + lk.tick * 0.3 + lk.label * 1.5;
    let est_h = h - top - bottom;
    let yt = axis_ticks(y_range.0, y_range.1, y_range.2, ((est_h / (lk.tick * 2.6)) as usize).clamp(4, 8));
    let ytw = yt.labels.iter().map(|l| text_width(l, lk.tick)).fold(0.0, f64::max);
    let ylab = if y_label.is_empty() { 0.0 } else { lk.label * 1.5 };
    let left = lk.pad * 0.5 + ylab + ytw + lk.tick_len + lk.tick * 0.35;
    let right = lk.pad * 1.8;
    let pw = w - left - right;
    // The x tick count follows the panel's width, not what its y labels
    // leave of it, so the panels of one figure share their x ticks.
    let xt = match x_range {
        Some((lo, hi, log)) => axis_ticks(lo, hi, log, (((w - lk.pad * 6.0) / (lk.tick * 5.0)) as usize).clamp(3, 8)),
        None => Ticks { values: vec![], labels: vec![], note: None, minor: vec![] },
    };
    Frame { x: x + left, y: y + top, w: pw, h: h - top - bottom, xt, yt }
}

fn draw_panel(svg: &mut Svg, rect: (f64, f64, f64, f64), panel: &Panel, lk: &Look) {
    let xr = range(panel.series.iter().flat_map(|s| s.xs.iter().copied()), panel.log_x);
    let yr = range(panel.series.iter().flat_map(|s| s.ys.iter().copied()), panel.log_y);
    let (Some((x0, x1)), Some((y0, y1))) = (xr, yr) else {
        let f = frame(rect, &panel.title, "", None, (0.0, 1.0, false), 1, lk);
        svg.rect(f.x, f.y, f.w, f.h, None, Some(&Stroke::solid(INK, lk.frame)));
        svg.text(f.x + f.w / 2.0, f.y + f.h / 2.0, "no data", &Font::new(lk.label, Anchor::Middle));
        draw_panel_title(svg, &f, &panel.title, None, lk);
        return;
    };
    let f = frame(rect, &panel.title, &panel.y_label, Some((x0, x1, panel.log_x)), (y0, y1, panel.log_y), 1, lk);
    let ax = Axis { lo: x0, hi: x1, log: panel.log_x, a: f.x, b: f.x + f.w };
    let ay = Axis { lo: y0, hi: y1, log: panel.log_y, a: f.y + f.h, b: f.y };
    draw_grid(svg, &f, Some(&ax), &ay, lk);
    let clip = svg.clip_rect(f.x, f.y, f.w, f.h);
    // Chattering signals first, as their min–max envelope per pixel column
    // (the most agitated at the bottom), then the other lines, then the
    // references (dashed) on top so they stay visible, then the end markers.
    let noisy: Vec<bool> = panel.series.iter().map(|s| !s.points && chatters(s, panel, (y1 - y0) * 0.004)).collect();
    let mut order: Vec<(usize, f64)> = panel
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let rank = if s.dashed {
                f64::MAX
            } else if s.points {
                // Set-points and samples above the lines they sit on.
                1.0
            } else if noisy[i] {
                -variation(&s.ys)
            } else {
                0.0
            };
            (i, rank)
        })
        .collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    let column = lk.line.max(lk.thin);
    for &(i, _) in &order {
        let s = &panel.series[i];
        if noisy[i] {
            // The envelope is the signal: a filled band with its two edges
            // drawn (no mean line, which would understate the swing). A
            // chattering reference (the attitude command of a chattering
            // outer loop) gets a fainter band and dashed edges.
            let (opacity, dash) = if s.dashed { (0.2, Some(lk.dash)) } else { (BAND_OPACITY, None) };
            svg.group(if s.dashed { "reference band" } else { "band" });
            for seg in segments(s, panel.log_x, panel.log_y) {
                let pts: Vec<(f64, f64)> = seg.iter().map(|&(x, y)| (ax.map(x), ay.map(y))).collect();
                let cols = pixel_columns(&pts, column);
                let mut outline: Vec<(f64, f64)> = cols.iter().map(|c| (c.0, c.1)).collect();
                outline.extend(cols.iter().rev().map(|c| (c.0, c.2)));
                svg.polygon(&outline, s.color, opacity, Some(&clip));
                let edge = Stroke { dash, ..Stroke::solid(s.color, lk.thin) };
                let top: Vec<(f64, f64)> = cols.iter().map(|c| (c.0, c.1)).collect();
                let bottom: Vec<(f64, f64)> = cols.iter().map(|c| (c.0, c.2)).collect();
                svg.polyline(&top, &edge, Some(&clip));
                svg.polyline(&bottom, &edge, Some(&clip));
            }
            svg.end_group();
            continue;
        }
        svg.group(if s.dashed {
            "reference"
        } else if s.points {
            "points"
        } else {
            "data"
        });
        let stroke = Stroke { color: s.color, width: lk.line, dash: s.dashed.then_some(lk.dash), opacity: 1.0 };
        let markers = has_markers(s);
        for seg in segments(s, panel.log_x, panel.log_y) {
            let pts: Vec<(f64, f64)> = seg.iter().map(|&(x, y)| (ax.map(x), ay.map(y))).collect();
            if !s.points {
                svg.polyline(&pts, &stroke, Some(&clip));
            }
            if markers {
                for &(px, py) in &pts {
                    svg.circle(px, py, lk.marker, s.color, Some(&clip));
                }
            }
        }
        svg.end_group();
    }
    for s in panel.series.iter().filter(|s| s.end.is_some()) {
        let last = segments(s, panel.log_x, panel.log_y).last().and_then(|seg| seg.last().copied());
        if let (Some(_), Some((x, y))) = (&s.end, last) {
            draw_end_marker(svg, (ax.map(x), ay.map(y)), s.color, lk);
        }
    }
    draw_axes(svg, &f, Some(&ax), &ay, lk);
    draw_x_label(svg, &f, &panel.x_label, 1, lk);
    draw_y_label(svg, &f, rect.0, &panel.y_label, lk);
    draw_panel_title(svg, &f, &panel.title, f.yt.note.as_deref(), lk);
}

/// Points in drawing coordinates grouped by pixel column of `width`:
/// `(column centre x, max y, min y, mean y)` per non-empty column, in order
/// (the drawing's y grows downwards, so "max" is the top edge).
fn pixel_columns(pts: &[(f64, f64)], width: f64) -> Vec<(f64, f64, f64, f64)> {
    let mut out: Vec<(f64, f64, f64, f64)> = Vec::new();
    let mut current: Option<(i64, f64, f64, f64, usize)> = None;
    for &(x, y) in pts {
        let k = (x / width).floor() as i64;
        match current.as_mut() {
            Some((ck, top, bottom, sum, n)) if *ck == k => {
                *top = top.min(y);
                *bottom = bottom.max(y);
                *sum += y;
                *n += 1;
            }
            _ => {
                if let Some((ck, top, bottom, sum, n)) = current.take() {
                    out.push(((ck as f64 + 0.5) * width, top, bottom, sum / n as f64));
                }
                current = Some((k, y, y, y, 1));
            }
        }
    }
    if let Some((ck, top, bottom, sum, n)) = current {
        out.push(((ck as f64 + 0.5) * width, top, bottom, sum / n as f64));
    }
    out
}

/// A × at `at` (drawing coordinates) in `color`; why and when the run
/// stopped is in its legend entry ([`entry_label`]), not over the data.
fn draw_end_marker(svg: &mut Svg, at: (f64, f64), color: Rgb, lk: &Look) {
    svg.group("end");
    let r = lk.marker * 1.8;
    let stroke = Stroke::solid(color, lk.line * 1.3);
    svg.line(at.0 - r, at.1 - r, at.0 + r, at.1 + r, &stroke);
    svg.line(at.0 - r, at.1 + r, at.0 + r, at.1 - r, &stroke);
    svg.end_group();
}

fn draw_grid(svg: &mut Svg, f: &Frame, ax: Option<&Axis>, ay: &Axis, lk: &Look) {
    let minor = Stroke::solid(MINOR_GRID, lk.grid);
    let major = Stroke::solid(GRID, lk.grid);
    if let Some(ax) = ax {
        for &v in f.xt.minor.iter().filter(|v| **v >= ax.lo && **v <= ax.hi) {
            let px = ax.map(v);
            svg.line(px, f.y, px, f.y + f.h, &minor);
        }
        for &v in &f.xt.values {
            let px = ax.map(v);
            svg.line(px, f.y, px, f.y + f.h, &major);
        }
    }
    for &v in f.yt.minor.iter().filter(|v| **v >= ay.lo && **v <= ay.hi) {
        let py = ay.map(v);
        svg.line(f.x, py, f.x + f.w, py, &minor);
    }
    for &v in &f.yt.values {
        let py = ay.map(v);
        svg.line(f.x, py, f.x + f.w, py, &major);
    }
}

fn draw_axes(svg: &mut Svg, f: &Frame, ax: Option<&Axis>, ay: &Axis, lk: &Look) {
    let ink = Stroke::solid(INK, lk.frame);
    svg.rect(f.x, f.y, f.w, f.h, None, Some(&ink));
    let tf = Font::new(lk.tick, Anchor::End);
    for (v, l) in f.yt.values.iter().zip(&f.yt.labels) {
        let py = ay.map(*v);
        svg.line(f.x - lk.tick_len, py, f.x, py, &ink);
        svg.text(f.x - lk.tick_len - lk.tick * 0.3, py, l, &tf);
    }
    if let Some(ax) = ax {
        let tf = Font { valign: VAlign::Top, ..Font::new(lk.tick, Anchor::Middle) };
        for (v, l) in f.xt.values.iter().zip(&f.xt.labels) {
            let px = ax.map(*v);
            svg.line(px, f.y + f.h, px, f.y + f.h + lk.tick_len, &ink);
            svg.text(px, f.y + f.h + lk.tick_len + lk.tick * 0.3, l, &tf);
        }
    }
}

fn draw_x_label(svg: &mut Svg, f: &Frame, label: &str, lines: usize, lk: &Look) {
    let y = f.y + f.h + lk.tick_len + lines as f64 * lk.tick * 1.2 + lk.tick * 0.3 + lk.label * 0.2;
    let font = Font { valign: VAlign::Top, ..Font::new(lk.label, Anchor::Middle) };
    svg.text(f.x + f.w / 2.0, y, label, &font);
    if let Some(note) = &f.xt.note {
        let font = Font { valign: VAlign::Top, ..Font::new(lk.tick, Anchor::End) };
        svg.text(f.x + f.w, y, note, &font);
    }
}

fn draw_y_label(svg: &mut Svg, f: &Frame, left: f64, label: &str, lk: &Look) {
    let font = Font { rotate: -90.0, valign: VAlign::Top, ..Font::new(lk.label, Anchor::Middle) };
    svg.text(left + lk.pad * 0.5, f.y + f.h / 2.0, label, &font);
}

/// Panel title centred over the plot; the y tick note ("×10⁻⁶ + 2") at its
/// top-left corner, the title moved right if they would touch.
fn draw_panel_title(svg: &mut Svg, f: &Frame, title: &str, note: Option<&str>, lk: &Look) {
    let baseline = f.y - lk.tick * 0.45;
    let mut note_end = f.x - f64::INFINITY;
    if let Some(note) = note {
        let font = Font { valign: VAlign::Baseline, ..Font::new(lk.tick, Anchor::Start) };
        svg.text(f.x, baseline, note, &font);
        note_end = f.x + text_width(note, lk.tick) + lk.tick;
    }
    if title.is_empty() {
        return;
    }
    let tw = text_width(title, lk.panel_title);
    let centre = f.x + f.w / 2.0;
    let font = Font { valign: VAlign::Baseline, ..Font::new(lk.panel_title, Anchor::Middle) };
    if centre - tw / 2.0 >= note_end {
        svg.text(centre, baseline, title, &font);
    } else {
        svg.text(note_end, baseline, title, &Font { anchor: Anchor::Start, ..font });
    }
}

// ---------------------------------------------------------------- 3-D

/// A 3-D trajectory plot (reference dashed), axes in metres, altitude up.
pub fn write_3d(title: &str, series: &[Series3], stem: &Path) -> Result<Vec<PathBuf>> {
    let lk = look();
    let width = lk.narrow;
    let inner = width - 2.0 * lk.pad;
    let entries: Vec<Entry> = series
        .iter()
        .filter(|s| s.points.iter().any(|p| p.iter().all(|v| v.is_finite())))
        .map(|s| Entry {
            label: s.label.clone(),
            color: s.color,
            dashed: s.dashed,
            marker: false,
            band: false,
            points: false,
        })
        .collect();
    let (_, legend_h) = legend_rows(&entries, inner, &lk);
    let title_h = if lk.title > 0.0 && !title.is_empty() { lk.title * 1.8 } else { lk.pad * 0.5 };
    let plot_h = inner * 0.82;
    let height = (title_h + legend_h + plot_h + lk.pad).ceil();
    let mut svg = Svg::new(width, height, lk.unit);
    draw_title(&mut svg, title, width, &lk);
    draw_legend(&mut svg, &entries, lk.pad, title_h, inner, &lk);

    let axis =
        |k: usize| range(series.iter().flat_map(|s| s.points.iter().map(move |p| p[k])), false).unwrap_or((-1.0, 1.0));
    let ranges = [axis(0), axis(1), axis(2)];
    // Fewer ticks on a small box: the edges are foreshortened.
    let box_w = inner - 2.0 * (lk.tick * 5.5 + lk.label * 1.5);
    let target = ((box_w / (lk.tick * 6.0)) as usize).clamp(4, 6);
    // At least three labelled ticks on every axis (a short z range would
    // otherwise get two).
    let ticks: Vec<Ticks> = ranges
        .iter()
        .map(|&(lo, hi)| {
            let mut t = axis_ticks(lo, hi, false, target);
            let mut more = target;
            while t.values.len() < 3 && more < 12 {
                more += 2;
                t = axis_ticks(lo, hi, false, more);
            }
            t
        })
        .collect();
    // Orthographic view: yaw about the vertical axis, then pitch.
    let (yaw, pitch) = (0.7f64, 0.45f64);
    let norm = |k: usize, v: f64| 2.0 * (v - ranges[k].0) / (ranges[k].1 - ranges[k].0) - 1.0;
    let project = |n: [f64; 3]| {
        let u = n[0] * ftsmc_core::math::cos(yaw) - n[1] * ftsmc_core::math::sin(yaw);
        let depth = n[0] * ftsmc_core::math::sin(yaw) + n[1] * ftsmc_core::math::cos(yaw);
        let v = n[2] * ftsmc_core::math::cos(pitch) * 0.9 + depth * ftsmc_core::math::sin(pitch);
        (u, v)
    };
    let mut corners = Vec::new();
    for a in [-1.0, 1.0] {
        for b in [-1.0, 1.0] {
            for c in [-1.0, 1.0] {
                corners.push(project([a, b, c]));
            }
        }
    }
    let (umin, umax) = corners.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p.0), h.max(p.0)));
    let (vmin, vmax) = corners.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p.1), h.max(p.1)));
    // Room for tick and axis labels around the box.
    let margin_x = lk.tick * 5.5 + lk.label * 1.5;
    let margin_y = lk.tick * 2.5 + lk.label * 1.5;
    let (bx, by) = (lk.pad + margin_x, title_h + legend_h + lk.tick);
    let (bw, bh) = (inner - 2.0 * margin_x, plot_h - margin_y - lk.tick);
    let s = (bw / (umax - umin)).min(bh / (vmax - vmin));
    let ox = bx + (bw - s * (umax - umin)) / 2.0;
    let oy = by + (bh - s * (vmax - vmin)) / 2.0;
    let to_px = |n: [f64; 3]| {
        let (u, v) = project(n);
        (ox + (u - umin) * s, oy + (vmax - v) * s)
    };
    let grid = Stroke::solid(GRID, lk.grid);
    let ink = Stroke::solid(INK, lk.frame);
    // Back planes: floor z = −1, walls x = +1 and y = +1, with grid lines.
    for (k, t) in ticks.iter().enumerate() {
        for &v in &t.values {
            let nv = norm(k, v);
            let lines: Vec<([f64; 3], [f64; 3])> = match k {
                0 => vec![([nv, -1.0, -1.0], [nv, 1.0, -1.0]), ([nv, 1.0, -1.0], [nv, 1.0, 1.0])],
                1 => vec![([-1.0, nv, -1.0], [1.0, nv, -1.0]), ([1.0, nv, -1.0], [1.0, nv, 1.0])],
                _ => vec![([1.0, -1.0, nv], [1.0, 1.0, nv]), ([-1.0, 1.0, nv], [1.0, 1.0, nv])],
            };
            for (a, b) in lines {
                let (p, q) = (to_px(a), to_px(b));
                svg.line(p.0, p.1, q.0, q.1, &grid);
            }
        }
    }
    for (a, b) in [
        ([-1.0, -1.0, -1.0], [1.0, -1.0, -1.0]),
        ([1.0, -1.0, -1.0], [1.0, 1.0, -1.0]),
        ([1.0, 1.0, -1.0], [-1.0, 1.0, -1.0]),
        ([-1.0, 1.0, -1.0], [-1.0, -1.0, -1.0]),
        ([1.0, -1.0, -1.0], [1.0, -1.0, 1.0]),
        ([1.0, 1.0, -1.0], [1.0, 1.0, 1.0]),
        ([-1.0, 1.0, -1.0], [-1.0, 1.0, 1.0]),
        ([1.0, -1.0, 1.0], [1.0, 1.0, 1.0]),
        ([-1.0, 1.0, 1.0], [1.0, 1.0, 1.0]),
    ] {
        let (p, q) = (to_px(a), to_px(b));
        svg.line(p.0, p.1, q.0, q.1, &ink);
    }
    // Tick labels on the front floor edges (x, y) and the left vertical edge (z).
    let edge_label = |svg: &mut Svg, k: usize, at: &dyn Fn(f64) -> [f64; 3], out: (f64, f64), name: &str| {
        let t = &ticks[k];
        let anchor = if out.0 < -0.3 {
            Anchor::End
        } else if out.0 > 0.3 {
            Anchor::Start
        } else {
            Anchor::Middle
        };
        for (v, l) in t.values.iter().zip(&t.labels) {
            let p = to_px(at(norm(k, *v)));
            let q = (p.0 + out.0 * lk.tick_len * 1.6, p.1 + out.1 * lk.tick_len * 1.6);
            svg.line(p.0, p.1, q.0, q.1, &ink);
            let font =
                Font { valign: if out.1 > 0.5 { VAlign::Top } else { VAlign::Center }, ..Font::new(lk.tick, anchor) };
            svg.text(q.0 + out.0 * lk.tick * 0.3, q.1 + out.1 * lk.tick * 0.2, l, &font);
        }
        let mid = to_px(at(0.0));
        let d = lk.tick * 3.6 + lk.label * 0.9;
        let name = match &t.note {
            Some(n) => format!("{name}  {n}"),
            None => name.to_string(),
        };
        let font = Font { valign: VAlign::Center, ..Font::new(lk.label, Anchor::Middle) };
        let (lx, ly) = (mid.0 + out.0 * d, mid.1 + out.1 * d);
        if k == 2 {
            svg.text(lx, ly, &name, &Font { rotate: -90.0, ..font });
        } else {
            svg.text(lx, ly, &name, &font);
        }
    };
    // Outward directions on screen: perpendicular-ish to each edge, away from the box.
    let (c, sn) = (ftsmc_core::math::cos(yaw), ftsmc_core::math::sin(yaw));
    edge_label(&mut svg, 0, &|v| [v, -1.0, -1.0], (sn * 0.6, 0.8), "x (m)");
    edge_label(&mut svg, 1, &|v| [-1.0, v, -1.0], (-c * 0.9, 0.45), "y (m)");
    edge_label(&mut svg, 2, &|v| [-1.0, 1.0, v], (-1.0, 0.0), "z (m)");
    let finite = |s: &Series3| -> Vec<[f64; 3]> {
        let pts: Vec<[f64; 3]> = s.points.iter().copied().filter(|p| p.iter().all(|v| v.is_finite())).collect();
        let step = pts.len().div_ceil(MAX_POINTS).max(1);
        pts.into_iter().step_by(step).map(|p| [norm(0, p[0]), norm(1, p[1]), norm(2, p[2])]).collect()
    };
    // Depth cue: every path's shadow on the floor (z at its lowest), faint.
    svg.group("shadow");
    for s in series {
        let px: Vec<(f64, f64)> = finite(s).into_iter().map(|n| to_px([n[0], n[1], -1.0])).collect();
        let stroke = Stroke { color: s.color, width: lk.thin, dash: s.dashed.then_some(lk.dash), opacity: 0.35 };
        svg.polyline(&px, &stroke, None);
    }
    svg.end_group();
    // Flights first, then the references dashed on top over a white halo,
    // so a reference under a flight stays visible.
    let ordered = series.iter().filter(|s| !s.dashed).chain(series.iter().filter(|s| s.dashed));
    for s in ordered {
        svg.group(if s.dashed { "reference" } else { "data" });
        let px: Vec<(f64, f64)> = finite(s).into_iter().map(to_px).collect();
        if s.dashed {
            let halo = Stroke { color: Rgb(255, 255, 255), width: lk.line * 2.2, dash: None, opacity: 0.7 };
            svg.polyline(&px, &halo, None);
        }
        let stroke = Stroke {
            color: s.color,
            width: if s.dashed { lk.line * 1.1 } else { lk.line },
            dash: s.dashed.then_some(lk.dash),
            opacity: 1.0,
        };
        svg.polyline(&px, &stroke, None);
        svg.end_group();
    }
    write(stem, svg.finish(), &lk)
}

// ---------------------------------------------------------------- box plots

/// Nearest-rank percentile of sorted values.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    sorted[((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1]
}

/// Word wrap of `s` to `width` at `size`: whole if it fits, else a
/// parenthesised tail ("(1000/1000 ok)") on its own line, then greedy by words.
fn wrap(s: &str, width: f64, size: f64) -> Vec<String> {
    if text_width(s, size) <= width {
        return vec![s.to_string()];
    }
    let parts: Vec<&str> = match s.find(" (") {
        Some(i) => vec![&s[..i], &s[i + 1..]],
        None => vec![s],
    };
    let mut lines: Vec<String> = Vec::new();
    for part in parts {
        if text_width(part, size) <= width {
            lines.push(part.to_string());
            continue;
        }
        let start = lines.len();
        for word in part.split(' ') {
            let joinable = lines.len() > start;
            match lines.last_mut() {
                Some(l) if joinable && text_width(&format!("{l} {word}"), size) <= width => {
                    l.push(' ');
                    l.push_str(word);
                }
                _ => lines.push(word.to_string()),
            }
        }
    }
    lines
}

/// Box plots, one panel per [`BoxPanel`].
pub fn write_boxplots(title: &str, panels: &[BoxPanel], columns: usize, stem: &Path) -> Result<Vec<PathBuf>> {
    let lk = look();
    let columns = columns.max(1);
    let rows = panels.len().div_ceil(columns).max(1);
    let width = if columns == 1 { lk.narrow } else { lk.wide };
    let inner = width - 2.0 * lk.pad;
    let title_h = if lk.title > 0.0 && !title.is_empty() { lk.title * 1.8 } else { lk.pad * 0.5 };
    let panel_w = inner / columns as f64;
    let panel_h = panel_w * if columns == 1 { lk.aspect_single } else { lk.aspect };
    let height = (title_h + rows as f64 * panel_h + lk.pad).ceil();
    let mut svg = Svg::new(width, height, lk.unit);
    draw_title(&mut svg, title, width, &lk);
    for (i, panel) in panels.iter().enumerate() {
        let (r, c) = (i / columns, i % columns);
        let rect = (lk.pad + c as f64 * panel_w, title_h + r as f64 * panel_h, panel_w, panel_h);
        draw_box_panel(&mut svg, rect, panel, &lk);
    }
    write(stem, svg.finish(), &lk)
}

fn draw_box_panel(svg: &mut Svg, rect: (f64, f64, f64, f64), panel: &BoxPanel, lk: &Look) {
    let stats: Vec<Option<[f64; 5]>> = panel
        .groups
        .iter()
        .map(|g| {
            let mut v: Vec<f64> =
                g.values.iter().copied().filter(|x| x.is_finite() && (!panel.log_y || *x > 0.0)).collect();
            if v.is_empty() {
                return None;
            }
            v.sort_by(f64::total_cmp);
            Some([0.05, 0.25, 0.5, 0.75, 0.95].map(|q| percentile(&v, q)))
        })
        .collect();
    let n = panel.groups.len().max(1);
    // Category labels wrapped to their slot (estimate the slot from the panel width).
    let slot = (rect.2 - lk.tick * 4.0 - lk.label * 1.5 - lk.pad * 2.3) / n as f64;
    let labels: Vec<Vec<String>> = panel.groups.iter().map(|g| wrap(&g.label, slot * 0.98, lk.tick)).collect();
    let lines = labels.iter().map(Vec::len).max().unwrap_or(1).max(1);
    let Some((y0, y1)) = range(stats.iter().flatten().flat_map(|s| s.iter().copied()), panel.log_y) else {
        let f = frame(rect, &panel.title, "", None, (0.0, 1.0, false), lines, lk);
        svg.rect(f.x, f.y, f.w, f.h, None, Some(&Stroke::solid(INK, lk.frame)));
        svg.text(f.x + f.w / 2.0, f.y + f.h / 2.0, "no data", &Font::new(lk.label, Anchor::Middle));
        draw_panel_title(svg, &f, &panel.title, None, lk);
        return;
    };
    // The axis is widened until a tick lies beyond every box and whisker at
    // both ends, so no box rises above the highest tick label.
    let drawn = stats.iter().flatten().flat_map(|s| s.iter().copied()).filter(|v| v.is_finite());
    let (dlo, dhi) = drawn.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
    let (mut y0, mut y1) = (y0, y1);
    let mut f = frame(rect, &panel.title, &panel.y_label, None, (y0, y1, panel.log_y), lines, lk);
    for _ in 0..40 {
        let top = f.yt.values.last().is_some_and(|&v| v >= dhi);
        let bottom = f.yt.values.first().is_some_and(|&v| v <= dlo);
        if top && bottom {
            break;
        }
        let span = y1 - y0;
        if !top {
            y1 = if panel.log_y { (y1 * 1.15).min(f64::MAX) } else { (y1 + 0.05 * span).min(f64::MAX) };
        }
        if !bottom {
            y0 = if panel.log_y { (y0 / 1.15).max(f64::MIN_POSITIVE) } else { (y0 - 0.05 * span).max(-f64::MAX) };
        }
        f = frame(rect, &panel.title, &panel.y_label, None, (y0, y1, panel.log_y), lines, lk);
    }
    // x label row is not used by box plots: give it to the plot.
    f.h += lk.label * 1.5;
    let ay = Axis { lo: y0, hi: y1, log: panel.log_y, a: f.y + f.h, b: f.y };
    draw_grid(svg, &f, None, &ay, lk);
    let slot = f.w / n as f64;
    for (i, (g, s)) in panel.groups.iter().zip(&stats).enumerate() {
        let cx = f.x + (i as f64 + 0.5) * slot;
        let font = Font { valign: VAlign::Top, ..Font::new(lk.tick, Anchor::Middle) };
        for (k, line) in labels[i].iter().enumerate() {
            svg.text(cx, f.y + f.h + lk.tick_len + lk.tick * (0.3 + 1.2 * k as f64), line, &font);
        }
        let Some([p5, q1, med, q3, p95]) = *s else { continue };
        let half = slot * 0.22;
        let (yq1, yq3) = (ay.map(q1), ay.map(q3));
        let edge = Stroke::solid(g.color, lk.line);
        svg.rect(cx - half, yq3, 2.0 * half, (yq1 - yq3).max(lk.frame), Some((g.color, 0.3)), Some(&edge));
        let ym = ay.map(med);
        svg.line(cx - half, ym, cx + half, ym, &Stroke::solid(g.color, lk.line * 1.6));
        for (a, b) in [(q3, p95), (q1, p5)] {
            svg.line(cx, ay.map(a), cx, ay.map(b), &edge);
            svg.line(cx - half * 0.45, ay.map(b), cx + half * 0.45, ay.map(b), &edge);
        }
    }
    draw_axes(svg, &f, None, &ay, lk);
    draw_y_label(svg, &f, rect.0, &panel.y_label, lk);
    draw_panel_title(svg, &f, &panel.title, f.yt.note.as_deref(), lk);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A legend lists a series' entries together, in the order the series
    /// are given, even when one of them is a band on one panel only.
    #[test]
    fn legend_entries_keep_the_series_order() {
        let xs: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
        let line = |label: &str, ys: Vec<f64>| Series {
            points: false,
            label: label.into(),
            xs: xs.clone(),
            ys,
            color: Rgb(0, 0, 0),
            dashed: false,
            end: None,
        };
        let smooth: Vec<f64> = xs.iter().map(|x| x * 0.1).collect();
        let chatter: Vec<f64> = (0..1000).map(|k| if k % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let panel = |series: Vec<Series>| Panel {
            title: "p".into(),
            x_label: "t".into(),
            y_label: "y".into(),
            series,
            log_x: false,
            log_y: false,
        };
        let a = panel(vec![line("ω1", chatter), line("ω2", smooth.clone())]);
        let b = panel(vec![line("ω1", smooth.clone()), line("ω2", smooth)]);
        let entries = entries_of([&a, &b].into_iter().flat_map(|p| p.series.iter().map(move |s| (s, p))));
        let labels: Vec<String> = entries.iter().map(|e| e.label.clone()).collect();
        assert_eq!(labels, [format!("ω1{BAND_NOTE}"), "ω1".into(), "ω2".into()]);
    }

    /// A fresh scratch folder `<temp dir>/ftsmc-plot-<name>-<random>`,
    /// removed when the returned guard drops: when the test ends, passed or failed.
    fn tmp_dir(name: &str) -> tempfile::TempDir {
        tempfile::Builder::new().prefix(&format!("ftsmc-plot-{name}-")).tempdir().unwrap()
    }

    #[test]
    fn renders_svg_and_png_and_survives_nan_and_empty_input() {
        let tmp = tmp_dir("fig");
        let dir = tmp.path();
        let t: Vec<f64> = (0..20_000).map(|k| k as f64 * 1e-3).collect();
        let fig = Figure {
            title: "test φ θ ψ δ̂".into(),
            panels: vec![
                Panel {
                    title: "lines".into(),
                    x_label: "time (s)".into(),
                    y_label: "x (m)".into(),
                    series: vec![
                        Series {
                            points: false,
                            label: "a".into(),
                            xs: t.clone(),
                            ys: t.iter().map(|v| ftsmc_core::math::sin(*v)).collect(),
                            color: controller_color("ftaftsmc"),
                            dashed: false,
                            end: None,
                        },
                        Series {
                            points: false,
                            label: "nan".into(),
                            xs: t.clone(),
                            ys: t.iter().map(|v| if *v > 5.0 && *v < 6.0 { f64::NAN } else { 1.0 }).collect(),
                            color: controller_color("reference"),
                            dashed: true,
                            end: None,
                        },
                    ],
                    log_x: false,
                    log_y: false,
                },
                Panel {
                    title: "empty".into(),
                    x_label: String::new(),
                    y_label: String::new(),
                    series: vec![],
                    log_x: true,
                    log_y: true,
                },
            ],
            columns: 2,
        };
        let files = write_figure(&fig, &dir.join("fig")).unwrap();
        for f in &files {
            assert!(std::fs::metadata(f).unwrap().len() > 1000, "{}", f.display());
        }
        let svg = std::fs::read_to_string(&files[0]).unwrap();
        assert!(svg.contains("stroke-dasharray"), "dashed lines are real dashes");
        let boxes = write_boxplots(
            "boxes",
            &[BoxPanel {
                title: "ISE".into(),
                y_label: "ISE".into(),
                groups: vec![BoxGroup {
                    label: "a".into(),
                    values: vec![0.1, 0.2, 0.3, f64::NAN],
                    color: controller_color("tsm-sta"),
                }],
                log_y: true,
            }],
            1,
            &dir.join("box"),
        )
        .unwrap();
        assert_eq!(boxes.len(), 2);
        let s3 = write_3d(
            "3d",
            &[Series3 {
                label: "r".into(),
                points: vec![[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]],
                color: Rgb(0, 0, 0),
                dashed: true,
            }],
            &dir.join("s3"),
        )
        .unwrap();
        assert_eq!(s3.len(), 2);
    }

    #[test]
    fn a_box_plot_of_values_up_to_1e308_is_drawn_with_bounded_ticks() {
        // A legal batch whose ISE reaches 1e308: the padded log axis passes
        // f64::MAX, and the ticks once enumerated every decade to i32::MAX.
        let tmp = tmp_dir("huge");
        let dir = tmp.path();
        let files = write_boxplots(
            "huge",
            &[BoxPanel {
                title: "ISE".into(),
                y_label: "ISE".into(),
                groups: vec![BoxGroup {
                    label: "a".into(),
                    values: vec![1e-3, 1.0, 1e100, 1e308, f64::MAX],
                    color: controller_color("pid"),
                }],
                log_y: true,
            }],
            1,
            &dir.join("box"),
        )
        .unwrap();
        let svg = std::fs::read_to_string(&files[0]).unwrap();
        assert!(svg.len() < 200_000, "{} bytes", svg.len());
        let decades = svg.matches(r#"text-anchor="end">10"#).count();
        assert!(svg.contains(">10⁻³<") && (4..=12).contains(&decades), "decade labels from 1e-3 up: {decades}");
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "every coordinate is finite");
    }

    #[test]
    fn decimation_keeps_extremes() {
        let n = 100_000;
        let mut ys = vec![0.0; n];
        ys[54_321] = 10.0;
        let s = Series {
            points: false,
            label: String::new(),
            xs: (0..n).map(|i| i as f64).collect(),
            ys,
            color: Rgb(0, 0, 0),
            dashed: false,
            end: None,
        };
        let seg = segments(&s, false, false);
        let pts: usize = seg.iter().map(Vec::len).sum();
        assert!(pts <= MAX_POINTS + 2, "{pts}");
        assert!(seg.iter().flatten().any(|p| p.1 == 10.0));
    }

    #[test]
    fn long_titles_shrink_to_fit_the_figure() {
        // beyond/realistic-breeze-1-montecarlo: a long title was cut on both sides.
        let lk = look();
        let title =
            "10 runs of realistic-breeze-1: ISE of the completed runs per controller, box q1–q3, whiskers p5–p95";
        let size = title_size(title, lk.narrow, &lk);
        assert!(size < lk.title && text_width(title, size) <= lk.narrow - 2.0 * lk.pad, "{size}");
        assert_eq!(title_size("short", lk.narrow, &lk), lk.title);
    }

    #[test]
    fn box_plot_axes_end_at_ticks_beyond_the_boxes() {
        // The tutorial's montecarlo-ise.png: a box rose above the highest tick label.
        for (log, values) in [(true, vec![0.25, 0.3, 0.4, 0.9, 1.6]), (false, vec![0.31, 0.5, 0.62, 7.1, 7.4])] {
            let tmp = tmp_dir("bracket");
            let files = write_boxplots(
                "t",
                &[BoxPanel {
                    title: "ISE".into(),
                    y_label: "ISE".into(),
                    groups: vec![BoxGroup {
                        label: "a".into(),
                        values: values.clone(),
                        color: controller_color("pid"),
                    }],
                    log_y: log,
                }],
                1,
                &tmp.path().join("box"),
            )
            .unwrap();
            let svg = std::fs::read_to_string(&files[0]).unwrap();
            let ticks: Vec<f64> = svg
                .split(r#"text-anchor="end">"#)
                .skip(1)
                .filter_map(|t| t[..t.find('<').unwrap()].replace('−', "-").parse::<f64>().ok())
                .collect();
            let (lo, hi) = ticks.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
            assert!(hi >= 1.6_f64.min(values[4]) && hi >= values[4] && lo <= values[0], "log {log}: ticks {ticks:?}");
        }
    }

    #[test]
    fn panels_of_one_figure_share_their_x_ticks() {
        // fig1 and fig4: the y labels' width changed each panel's x tick count.
        let lk = look();
        let rect = (0.0, 0.0, 470.0, 330.0);
        let narrow_y = frame(rect, "a", "φ (rad)", Some((0.0, 20.0, false)), (0.0, 1.0, false), 1, &lk);
        let wide_y = frame(rect, "b", "φ (rad)", Some((0.0, 20.0, false)), (-123456.7, 98765.4, false), 1, &lk);
        assert_eq!(narrow_y.xt.values, wide_y.xt.values);
    }

    #[test]
    fn wrap_fits_words() {
        let lines = wrap("RANFTSMC [19] (100 % ok)", 90.0, 15.0);
        assert!(lines.len() >= 2, "{lines:?}");
        assert_eq!(lines.join(" "), "RANFTSMC [19] (100 % ok)");
    }
}
