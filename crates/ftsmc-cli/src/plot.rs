//! Figures as SVG and PNG with plotters, using an embedded font (DejaVu Sans)
//! so that no system font is needed. Every figure is written atomically.

use std::path::{Path, PathBuf};
use std::sync::Once;

use anyhow::{anyhow, Context, Result};
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

const FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";
/// Points drawn per series at most; min/max per bucket keep spikes visible.
const MAX_POINTS: usize = 4000;

fn ensure_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in; failure would be a build defect.
        plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("embedded font is not a valid TrueType file"));
    });
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
    pub color: RGBColor,
    /// Dashed (references, bounds) or solid.
    pub dashed: bool,
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
    /// Figure title.
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
    pub color: RGBColor,
    /// Dashed (reference) or solid.
    pub dashed: bool,
}

/// One box of a box plot.
pub struct BoxGroup {
    /// Category label.
    pub label: String,
    /// Sample values.
    pub values: Vec<f64>,
    /// Colour.
    pub color: RGBColor,
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
pub fn controller_color(name: &str) -> RGBColor {
    match name {
        "ftaftsmc" => RGBColor(31, 119, 180),
        "ranftsmc" => RGBColor(255, 127, 14),
        "tsm-sta" => RGBColor(44, 160, 44),
        "ftaftsmc-no-mass" => RGBColor(148, 103, 189),
        "ftaftsmc-tuned" => RGBColor(23, 190, 207),
        "ftaftsmc-zero-derivatives" => RGBColor(140, 86, 75),
        "reference" => RGBColor(0, 0, 0),
        other => {
            const PALETTE: [RGBColor; 6] = [
                RGBColor(214, 39, 40),
                RGBColor(227, 119, 194),
                RGBColor(127, 127, 127),
                RGBColor(188, 189, 34),
                RGBColor(140, 86, 75),
                RGBColor(23, 190, 207),
            ];
            let hash = other.bytes().fold(5381u32, |h, b| h.wrapping_mul(33) ^ u32::from(b));
            PALETTE[hash as usize % PALETTE.len()]
        }
    }
}

fn plot_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("plotting failed: {e:?}")
}

/// Render with both backends to `<stem>.svg` and `<stem>.png`, atomically.
fn render(
    stem: &Path,
    size: (u32, u32),
    draw_svg: impl Fn(DrawingArea<SVGBackend, Shift>) -> Result<()>,
    draw_png: impl Fn(DrawingArea<BitMapBackend, Shift>) -> Result<()>,
) -> Result<Vec<PathBuf>> {
    ensure_font();
    if let Some(dir) = stem.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let svg_path = stem.with_extension("svg");
    let png_path = stem.with_extension("png");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_svg(root.clone())?;
        root.present().map_err(plot_err)?;
    }
    crate::output::write_atomic(&svg_path, svg.as_bytes())?;
    let tmp_png = stem.with_extension("tmp.png");
    {
        let root = BitMapBackend::new(&tmp_png, size).into_drawing_area();
        draw_png(root.clone())?;
        root.present().map_err(plot_err).with_context(|| format!("cannot write {}", tmp_png.display()))?;
    }
    std::fs::rename(&tmp_png, &png_path).with_context(|| format!("cannot rename to {}", png_path.display()))?;
    Ok(vec![svg_path, png_path])
}

/// Write `fig` to `<stem>.svg` and `<stem>.png`.
pub fn write_figure(fig: &Figure, stem: &Path) -> Result<Vec<PathBuf>> {
    let columns = fig.columns.max(1);
    let rows = fig.panels.len().div_ceil(columns).max(1);
    let size = ((560 * columns as u32).max(1000), 70 + 400 * rows as u32);
    render(stem, size, |root| draw_figure(root, fig), |root| draw_figure(root, fig))
}

fn title_and_body<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, title: &str) -> Result<DrawingArea<DB, Shift>> {
    root.fill(&WHITE).map_err(plot_err)?;
    let (top, body) = root.split_vertically(60);
    let (w, _) = top.dim_in_pixel();
    let style = TextStyle::from((FAMILY, 26).into_font()).pos(Pos::new(HPos::Center, VPos::Center));
    top.draw_text(title, &style, (w as i32 / 2, 30)).map_err(plot_err)?;
    Ok(body)
}

fn draw_figure<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, fig: &Figure) -> Result<()> {
    let body = title_and_body(&root, &fig.title)?;
    let columns = fig.columns.max(1);
    let rows = fig.panels.len().div_ceil(columns).max(1);
    let areas = body.split_evenly((rows, columns));
    for (panel, area) in fig.panels.iter().zip(areas) {
        draw_panel(&area, panel)?;
    }
    Ok(())
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
        return Some((lo / 1.2, hi * 1.2));
    }
    let (lo, hi) = if hi - lo <= 1e-12 * hi.abs().max(1.0) {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - d, hi + d)
    } else {
        (lo, hi)
    };
    let pad = 0.05 * (hi - lo);
    Some((lo - pad, hi + pad))
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

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, panel: &Panel) -> Result<()> {
    let xr = range(panel.series.iter().flat_map(|s| s.xs.iter().copied()), panel.log_x);
    let yr = range(panel.series.iter().flat_map(|s| s.ys.iter().copied()), panel.log_y);
    let (Some((x0, x1)), Some((y0, y1))) = (xr, yr) else {
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, (FAMILY, 20))
            .margin(12)
            .build_cartesian_2d(0.0..1.0, 0.0..1.0)
            .map_err(plot_err)?;
        chart.configure_mesh().disable_mesh().draw().map_err(plot_err)?;
        chart.draw_series(std::iter::once(Text::new("no data", (0.4, 0.5), (FAMILY, 18)))).map_err(plot_err)?;
        return Ok(());
    };
    match (panel.log_x, panel.log_y) {
        (false, false) => draw_in(area, panel, x0..x1, y0..y1),
        (true, false) => draw_in(area, panel, (x0..x1).log_scale(), y0..y1),
        (false, true) => draw_in(area, panel, x0..x1, (y0..y1).log_scale()),
        (true, true) => draw_in(area, panel, (x0..x1).log_scale(), (y0..y1).log_scale()),
    }
}

fn draw_in<DB, X, Y>(area: &DrawingArea<DB, Shift>, panel: &Panel, x: X, y: Y) -> Result<()>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FAMILY, 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(x, y)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .axis_desc_style((FAMILY, 16))
        .label_style((FAMILY, 13))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(205, 205, 205))
        .draw()
        .map_err(plot_err)?;
    for s in &panel.series {
        // Thick polylines get long miter spikes at sharp reversals: draw
        // chattering signals one pixel wide.
        let width = if is_noisy(&s.ys) { 1 } else { 2 };
        let style = ShapeStyle { color: s.color.to_rgba(), filled: false, stroke_width: width };
        let mut labelled = false;
        for seg in segments(s, panel.log_x, panel.log_y) {
            let anno = if s.dashed {
                chart.draw_series(DashedLineSeries::new(seg, 8, 5, style)).map_err(plot_err)?
            } else {
                chart.draw_series(LineSeries::new(seg, style)).map_err(plot_err)?
            };
            if !labelled {
                let c = s.color;
                anno.label(s.label.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
                labelled = true;
            }
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(120, 120, 120))
        .label_font((FAMILY, 13))
        .position(legend_position(panel))
        .draw()
        .map_err(plot_err)?;
    Ok(())
}

/// More than 10 % of interior samples are local extrema: a chattering signal.
fn is_noisy(ys: &[f64]) -> bool {
    let turns = ys.windows(3).filter(|w| (w[1] - w[0]) * (w[2] - w[1]) < 0.0).count();
    ys.len() > 50 && turns * 10 > ys.len()
}

/// Put the legend in the right-hand corner where the data of the last
/// third of the x range is not: low when the curves end high, and so on.
fn legend_position(panel: &Panel) -> SeriesLabelPosition {
    let finite = |v: &&f64| v.is_finite();
    let (lo, hi) = panel
        .series
        .iter()
        .flat_map(|s| s.ys.iter().filter(finite))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return SeriesLabelPosition::UpperRight;
    }
    let mut upper = 0usize;
    let mut total = 0usize;
    for s in &panel.series {
        let n = s.ys.len();
        for &y in s.ys[2 * n / 3..].iter().filter(finite) {
            total += 1;
            if (y - lo) / (hi - lo) > 0.55 {
                upper += 1;
            }
        }
    }
    if total > 0 && upper * 2 > total {
        SeriesLabelPosition::LowerRight
    } else {
        SeriesLabelPosition::UpperRight
    }
}

/// A 3-D trajectory plot (reference dashed), axes in metres.
pub fn write_3d(title: &str, series: &[Series3], stem: &Path) -> Result<Vec<PathBuf>> {
    render(stem, (1100, 900), |root| draw_3d(root, title, series), |root| draw_3d(root, title, series))
}

fn draw_3d<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, title: &str, series: &[Series3]) -> Result<()> {
    let body = title_and_body(&root, title)?;
    let axis =
        |k: usize| range(series.iter().flat_map(|s| s.points.iter().map(move |p| p[k])), false).unwrap_or((-1.0, 1.0));
    let ((x0, x1), (y0, y1), (z0, z1)) = (axis(0), axis(1), axis(2));
    let mut chart = ChartBuilder::on(&body).margin(20).build_cartesian_3d(x0..x1, z0..z1, y0..y1).map_err(plot_err)?;
    chart.with_projection(|mut p| {
        p.pitch = 0.45;
        p.yaw = 0.7;
        p.scale = 0.85;
        p.into_matrix()
    });
    chart
        .configure_axes()
        .label_style((FAMILY, 14))
        .light_grid_style(RGBColor(225, 225, 225))
        .max_light_lines(4)
        .draw()
        .map_err(plot_err)?;
    // Flights first, references (dashed) on top.
    let ordered = series.iter().filter(|s| !s.dashed).chain(series.iter().filter(|s| s.dashed));
    for s in ordered {
        // Plot (x, z, y) so that altitude is vertical.
        let pts: Vec<(f64, f64, f64)> =
            s.points.iter().filter(|p| p.iter().all(|v| v.is_finite())).map(|p| (p[0], p[2], p[1])).collect();
        if pts.is_empty() {
            continue;
        }
        let style = ShapeStyle { color: s.color.to_rgba(), filled: false, stroke_width: if s.dashed { 1 } else { 2 } };
        let step = pts.len().div_ceil(MAX_POINTS).max(1);
        let pts: Vec<(f64, f64, f64)> = pts.into_iter().step_by(step).collect();
        let c = s.color;
        if s.dashed {
            let dash = (pts.len() / 120).max(2);
            let mut first = true;
            for chunk in pts.chunks(dash).step_by(2) {
                let anno = chart.draw_series(LineSeries::new(chunk.to_vec(), style)).map_err(plot_err)?;
                if first {
                    anno.label(s.label.as_str())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
                    first = false;
                }
            }
        } else {
            chart
                .draw_series(LineSeries::new(pts, style))
                .map_err(plot_err)?
                .label(s.label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(120, 120, 120))
        .label_font((FAMILY, 15))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(plot_err)?;
    let (w, h) = body.dim_in_pixel();
    let note = TextStyle::from((FAMILY, 15).into_font()).pos(Pos::new(HPos::Right, VPos::Bottom));
    body.draw_text("axes: x (m) horizontal, y (m) depth, z (m) vertical", &note, (w as i32 - 20, h as i32 - 10))
        .map_err(plot_err)?;
    Ok(())
}

/// Nearest-rank percentile of sorted values.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    sorted[((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1]
}

/// Box plots, one panel per [`BoxPanel`].
pub fn write_boxplots(title: &str, panels: &[BoxPanel], columns: usize, stem: &Path) -> Result<Vec<PathBuf>> {
    let columns = columns.max(1);
    let rows = panels.len().div_ceil(columns).max(1);
    let size = (600 * columns as u32, 70 + 420 * rows as u32);
    render(stem, size, |root| draw_boxes(root, title, panels, columns), |root| draw_boxes(root, title, panels, columns))
}

fn draw_boxes<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    panels: &[BoxPanel],
    columns: usize,
) -> Result<()> {
    let body = title_and_body(&root, title)?;
    let rows = panels.len().div_ceil(columns).max(1);
    for (panel, area) in panels.iter().zip(body.split_evenly((rows, columns))) {
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
                Some([
                    percentile(&v, 0.05),
                    percentile(&v, 0.25),
                    percentile(&v, 0.5),
                    percentile(&v, 0.75),
                    percentile(&v, 0.95),
                ])
            })
            .collect();
        let n = panel.groups.len().max(1);
        let x = -0.5..(n as f64 - 0.5);
        let Some((y0, y1)) = range(stats.iter().flatten().flat_map(|s| s.iter().copied()), panel.log_y) else {
            draw_panel(
                &area,
                &Panel {
                    title: panel.title.clone(),
                    x_label: String::new(),
                    y_label: String::new(),
                    series: vec![],
                    log_x: false,
                    log_y: false,
                },
            )?;
            continue;
        };
        if panel.log_y {
            draw_box_panel(&area, panel, &stats, x, (y0..y1).log_scale())?;
        } else {
            draw_box_panel(&area, panel, &stats, x, y0..y1)?;
        }
    }
    Ok(())
}

fn draw_box_panel<DB, Y>(
    area: &DrawingArea<DB, Shift>,
    panel: &BoxPanel,
    stats: &[Option<[f64; 5]>],
    x: std::ops::Range<f64>,
    y: Y,
) -> Result<()>
where
    DB: DrawingBackend,
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let labels: Vec<String> = panel.groups.iter().map(|g| g.label.clone()).collect();
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FAMILY, 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(75)
        .build_cartesian_2d(x, y)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(labels.len().max(1))
        .x_label_formatter(&|v: &f64| {
            let i = v.round();
            if (v - i).abs() < 1e-6 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .y_desc(panel.y_label.as_str())
        .axis_desc_style((FAMILY, 15))
        .label_style((FAMILY, 13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(plot_err)?;
    for (i, (g, s)) in panel.groups.iter().zip(stats).enumerate() {
        let Some([p5, q1, med, q3, p95]) = *s else { continue };
        let xi = i as f64;
        let c = g.color;
        chart
            .draw_series(std::iter::once(Rectangle::new([(xi - 0.25, q1), (xi + 0.25, q3)], c.mix(0.35).filled())))
            .map_err(plot_err)?;
        chart
            .draw_series(std::iter::once(Rectangle::new([(xi - 0.25, q1), (xi + 0.25, q3)], c.stroke_width(2))))
            .map_err(plot_err)?;
        for seg in [
            vec![(xi - 0.25, med), (xi + 0.25, med)],
            vec![(xi, q3), (xi, p95)],
            vec![(xi, q1), (xi, p5)],
            vec![(xi - 0.1, p95), (xi + 0.1, p95)],
            vec![(xi - 0.1, p5), (xi + 0.1, p5)],
        ] {
            chart.draw_series(std::iter::once(PathElement::new(seg, c.stroke_width(2)))).map_err(plot_err)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("ftsmc-plot-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn renders_svg_and_png_and_survives_nan_and_empty_input() {
        let dir = tmp_dir("fig");
        let t: Vec<f64> = (0..20_000).map(|k| k as f64 * 1e-3).collect();
        let fig = Figure {
            title: "test φ θ ψ".into(),
            panels: vec![
                Panel {
                    title: "lines".into(),
                    x_label: "time (s)".into(),
                    y_label: "x (m)".into(),
                    series: vec![
                        Series {
                            label: "a".into(),
                            xs: t.clone(),
                            ys: t.iter().map(|v| v.sin()).collect(),
                            color: controller_color("ftaftsmc"),
                            dashed: false,
                        },
                        Series {
                            label: "nan".into(),
                            xs: t.clone(),
                            ys: t.iter().map(|v| if *v > 5.0 && *v < 6.0 { f64::NAN } else { 1.0 }).collect(),
                            color: controller_color("reference"),
                            dashed: true,
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
                color: RGBColor(0, 0, 0),
                dashed: true,
            }],
            &dir.join("s3"),
        )
        .unwrap();
        assert_eq!(s3.len(), 2);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn decimation_keeps_extremes() {
        let n = 100_000;
        let mut ys = vec![0.0; n];
        ys[54_321] = 10.0;
        let s = Series {
            label: String::new(),
            xs: (0..n).map(|i| i as f64).collect(),
            ys,
            color: RGBColor(0, 0, 0),
            dashed: false,
        };
        let seg = segments(&s, false, false);
        let pts: usize = seg.iter().map(Vec::len).sum();
        assert!(pts <= MAX_POINTS + 2, "{pts}");
        assert!(seg.iter().flatten().any(|p| p.1 == 10.0));
    }
}
