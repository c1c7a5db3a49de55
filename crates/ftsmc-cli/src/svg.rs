//! A minimal SVG writer for the figures: lines with real dash patterns and
//! opacity, clipped polylines, rectangles, circles and text. Text widths for
//! layout come from the embedded font's advance widths, so layout and the
//! rendered glyphs (resvg, same font) agree.

use std::fmt::Write as _;
use std::sync::OnceLock;

/// The embedded font (DejaVu Sans); no system font is ever used.
pub const FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
/// The family name inside [`FONT`].
pub const FAMILY: &str = "DejaVu Sans";

/// An sRGB colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.0, self.1, self.2)
    }
}

/// How a line is stroked.
#[derive(Clone, Copy, Debug)]
pub struct Stroke {
    /// Colour.
    pub color: Rgb,
    /// Width in user units.
    pub width: f64,
    /// Dash and gap lengths, or solid.
    pub dash: Option<[f64; 2]>,
    /// 0–1.
    pub opacity: f64,
}

impl Stroke {
    /// A solid opaque stroke.
    pub fn solid(color: Rgb, width: f64) -> Self {
        Self { color, width, dash: None, opacity: 1.0 }
    }

    fn attrs(&self) -> String {
        let mut a = format!(
            r#"fill="none" stroke="{}" stroke-width="{}" stroke-linejoin="round" stroke-linecap="butt""#,
            self.color.hex(),
            n(self.width)
        );
        if let Some([d, g]) = self.dash {
            let _ = write!(a, r#" stroke-dasharray="{} {}""#, n(d), n(g));
        }
        if self.opacity < 1.0 {
            let _ = write!(a, r#" stroke-opacity="{}""#, n(self.opacity));
        }
        a
    }
}

/// Horizontal text anchor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// Text starts at x.
    Start,
    /// Text is centred on x.
    Middle,
    /// Text ends at x.
    End,
}

/// Vertical placement of text relative to y.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VAlign {
    /// y is the top of the capitals.
    Top,
    /// y is the middle of the capitals.
    Center,
    /// y is the baseline.
    Baseline,
}

/// A text style.
#[derive(Clone, Copy, Debug)]
pub struct Font {
    /// Size in user units.
    pub size: f64,
    /// Horizontal anchor.
    pub anchor: Anchor,
    /// Vertical alignment.
    pub valign: VAlign,
    /// Bold.
    pub bold: bool,
    /// Colour.
    pub color: Rgb,
    /// Rotation in degrees (−90: reads bottom to top).
    pub rotate: f64,
}

impl Font {
    /// Black, regular, anchored at `anchor`, vertically centred.
    pub fn new(size: f64, anchor: Anchor) -> Self {
        Self { size, anchor, valign: VAlign::Center, bold: false, color: Rgb(0, 0, 0), rotate: 0.0 }
    }
}

/// Numbers in SVG coordinates: two decimals, no "-0".
fn n(v: f64) -> String {
    let s = format!("{:.2}", v);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" || s.is_empty() {
        "0".into()
    } else {
        s.to_string()
    }
}

use ftsmc_sim::escape::xml_text as escape;

struct Metrics {
    units_per_em: f64,
    advance: Vec<(char, f64)>,
    fallback: f64,
}

fn metrics() -> &'static Metrics {
    static M: OnceLock<Metrics> = OnceLock::new();
    M.get_or_init(|| {
        let face = ttf_parser::Face::parse(FONT, 0).expect("embedded font parses");
        let units_per_em = f64::from(face.units_per_em());
        let adv =
            |c: char| face.glyph_index(c).and_then(|g| face.glyph_hor_advance(g)).map(|a| f64::from(a) / units_per_em);
        let fallback = adv('n').unwrap_or(0.6);
        let mut advance: Vec<(char, f64)> = (' '..='~').filter_map(|c| adv(c).map(|a| (c, a))).collect();
        for c in "φθψδαâ̂·–—−×⁰¹²³⁴⁵⁶⁷⁸⁹⁻µ%°ωΩ".chars() {
            if let Some(a) = adv(c) {
                advance.push((c, a));
            }
        }
        advance.sort_by_key(|p| p.0);
        Metrics { units_per_em, advance, fallback }
    })
}

/// Width of `s` set at `size` (combining marks take no room).
pub fn text_width(s: &str, size: f64) -> f64 {
    let m = metrics();
    let _ = m.units_per_em;
    s.chars()
        .map(|c| {
            if ('\u{300}'..='\u{36f}').contains(&c) {
                0.0
            } else {
                m.advance.binary_search_by_key(&c, |p| p.0).map_or(m.fallback, |i| m.advance[i].1)
            }
        })
        .sum::<f64>()
        * size
}

/// An SVG document being written.
pub struct Svg {
    buf: String,
    clips: usize,
}

impl Svg {
    /// A white `w` × `h` canvas; `unit` is "px" or "pt" (the viewBox is in
    /// the same numbers, so one user unit is one px or one pt).
    pub fn new(w: f64, h: f64, unit: &str) -> Self {
        let mut buf = String::with_capacity(1 << 16);
        let _ = writeln!(
            buf,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}{unit}" height="{h}{unit}" viewBox="0 0 {w} {h}" font-family="{FAMILY}">"#,
            w = n(w),
            h = n(h)
        );
        let _ = writeln!(buf, r#"<rect x="0" y="0" width="{}" height="{}" fill="white"/>"#, n(w), n(h));
        Self { buf, clips: 0 }
    }

    /// Define a clip rectangle; returns its id for [`Svg::polyline`].
    pub fn clip_rect(&mut self, x: f64, y: f64, w: f64, h: f64) -> String {
        self.clips += 1;
        let id = format!("c{}", self.clips);
        let _ = writeln!(
            self.buf,
            r#"<clipPath id="{id}"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath>"#,
            n(x),
            n(y),
            n(w),
            n(h)
        );
        id
    }

    /// An open polyline.
    pub fn polyline(&mut self, pts: &[(f64, f64)], stroke: &Stroke, clip: Option<&str>) {
        if pts.len() < 2 {
            return;
        }
        let mut d = String::with_capacity(pts.len() * 14);
        for (i, (x, y)) in pts.iter().enumerate() {
            let _ = write!(d, "{}{} {}", if i == 0 { "M" } else { "L" }, n(*x), n(*y));
        }
        let clip = clip.map_or(String::new(), |c| format!(r#" clip-path="url(#{c})""#));
        let _ = writeln!(self.buf, r#"<path d="{d}" {}{clip}/>"#, stroke.attrs());
    }

    /// A closed polygon filled with `fill` at `opacity`, no outline (the
    /// min/max band of a chattering signal).
    pub fn polygon(&mut self, pts: &[(f64, f64)], fill: Rgb, opacity: f64, clip: Option<&str>) {
        if pts.len() < 3 {
            return;
        }
        let mut d = String::with_capacity(pts.len() * 14);
        for (i, (x, y)) in pts.iter().enumerate() {
            let _ = write!(d, "{}{} {}", if i == 0 { "M" } else { "L" }, n(*x), n(*y));
        }
        let clip = clip.map_or(String::new(), |c| format!(r#" clip-path="url(#{c})""#));
        let _ = writeln!(
            self.buf,
            r#"<path d="{d}Z" fill="{}" fill-opacity="{}" stroke="none"{clip}/>"#,
            fill.hex(),
            n(opacity)
        );
    }

    /// Open a group of the given class (`reference`, `reference band`, `data`, `band`, `end`):
    /// what a drawn element is, for readers of the SVG and for the tests.
    pub fn group(&mut self, class: &str) {
        let _ = writeln!(self.buf, r#"<g class="{}">"#, escape(class));
    }

    /// Close the group opened by [`Svg::group`].
    pub fn end_group(&mut self) {
        self.buf.push_str("</g>\n");
    }

    /// A straight line.
    pub fn line(&mut self, x1: f64, y1: f64, x2: f64, y2: f64, stroke: &Stroke) {
        self.polyline(&[(x1, y1), (x2, y2)], stroke, None);
    }

    /// A rectangle, filled and/or stroked.
    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, fill: Option<(Rgb, f64)>, stroke: Option<&Stroke>) {
        let fill = fill.map_or("fill=\"none\"".to_string(), |(c, o)| {
            if o < 1.0 {
                format!(r#"fill="{}" fill-opacity="{}""#, c.hex(), n(o))
            } else {
                format!(r#"fill="{}""#, c.hex())
            }
        });
        let stroke = stroke.map_or(String::new(), |s| s.attrs().replacen("fill=\"none\" ", "", 1));
        let _ = writeln!(
            self.buf,
            r#"<rect x="{}" y="{}" width="{}" height="{}" {fill} {stroke}/>"#,
            n(x),
            n(y),
            n(w),
            n(h)
        );
    }

    /// A filled circle.
    pub fn circle(&mut self, cx: f64, cy: f64, r: f64, fill: Rgb, clip: Option<&str>) {
        let clip = clip.map_or(String::new(), |c| format!(r#" clip-path="url(#{c})""#));
        let _ =
            writeln!(self.buf, r#"<circle cx="{}" cy="{}" r="{}" fill="{}"{clip}/>"#, n(cx), n(cy), n(r), fill.hex());
    }

    /// Text at (x, y).
    pub fn text(&mut self, x: f64, y: f64, s: &str, f: &Font) {
        if s.is_empty() {
            return;
        }
        // Baseline offsets of DejaVu Sans: capitals are 0.73 em tall.
        let dy = match f.valign {
            VAlign::Top => 0.73 * f.size,
            VAlign::Center => 0.365 * f.size,
            VAlign::Baseline => 0.0,
        };
        let anchor = match f.anchor {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        };
        let mut attrs = format!(r#"font-size="{}" text-anchor="{anchor}""#, n(f.size));
        if f.bold {
            attrs.push_str(r#" font-weight="bold""#);
        }
        if f.color != Rgb(0, 0, 0) {
            let _ = write!(attrs, r#" fill="{}""#, f.color.hex());
        }
        if f.rotate != 0.0 {
            // Rotate about (x, y); the baseline shift is applied along the rotated axis.
            let _ = writeln!(
                self.buf,
                r#"<text transform="translate({} {}) rotate({})" x="0" y="{}" {attrs}>{}</text>"#,
                n(x),
                n(y),
                n(f.rotate),
                n(dy),
                escape(s)
            );
        } else {
            let _ = writeln!(self.buf, r#"<text x="{}" y="{}" {attrs}>{}</text>"#, n(x), n(y + dy), escape(s));
        }
    }

    /// The finished document.
    pub fn finish(mut self) -> String {
        self.buf.push_str("</svg>\n");
        self.buf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_widths() {
        assert_eq!(n(-0.001), "0");
        assert_eq!(n(1.5), "1.5");
        assert_eq!(n(2.0), "2");
        let w = text_width("time (s)", 10.0);
        assert!(w > 30.0 && w < 60.0, "{w}");
        assert_eq!(text_width("δ\u{302}", 10.0), text_width("δ", 10.0));
    }
}
