//! SVG → PNG with resvg, the only path to a PNG: the PNG is the SVG drawn by a
//! full SVG renderer (text shaped by rustybuzz) with the embedded font only.

use std::sync::{Arc, OnceLock};

use anyhow::{anyhow, Context, Result};
use resvg::tiny_skia::{Color, Pixmap, Transform};
use resvg::usvg;

fn options() -> &'static usvg::Options<'static> {
    static OPTIONS: OnceLock<usvg::Options<'static>> = OnceLock::new();
    OPTIONS.get_or_init(|| {
        let mut db = usvg::fontdb::Database::new();
        db.load_font_data(crate::svg::FONT.to_vec());
        let family = crate::svg::FAMILY.to_string();
        db.set_sans_serif_family(family.clone());
        usvg::Options { font_family: family, fontdb: Arc::new(db), ..usvg::Options::default() }
    })
}

/// Rasterise `svg` at `scale` device pixels per CSS pixel (1 pt = 4/3 px);
/// `dpi` is written into the PNG (pHYs) when given.
pub fn png_from_svg(svg: &str, scale: f32, dpi: Option<u32>) -> Result<Vec<u8>> {
    let tree = usvg::Tree::from_str(svg, options()).context("internal SVG does not parse")?;
    let size = tree.size();
    let (w, h) = ((size.width() * scale).round() as u32, (size.height() * scale).round() as u32);
    let mut pixmap = Pixmap::new(w, h).ok_or_else(|| anyhow!("empty figure {w}×{h}"))?;
    pixmap.fill(Color::WHITE);
    resvg::render(&tree, Transform::from_scale(scale, scale), &mut pixmap.as_mut());
    let png = pixmap.encode_png().map_err(|e| anyhow!("PNG encoding failed: {e}"))?;
    Ok(match dpi {
        Some(dpi) => with_phys(png, dpi),
        None => png,
    })
}

/// Insert a pHYs chunk (pixels per metre) right after IHDR.
fn with_phys(png: Vec<u8>, dpi: u32) -> Vec<u8> {
    // 8-byte signature, then IHDR: 4 length + 4 type + 13 data + 4 CRC.
    let at = 8 + 25;
    if png.len() < at || &png[12..16] != b"IHDR" {
        return png;
    }
    let ppm = (f64::from(dpi) / 0.0254).round() as u32;
    let mut chunk = Vec::with_capacity(21);
    chunk.extend_from_slice(&9u32.to_be_bytes());
    chunk.extend_from_slice(b"pHYs");
    chunk.extend_from_slice(&ppm.to_be_bytes());
    chunk.extend_from_slice(&ppm.to_be_bytes());
    chunk.push(1);
    let crc = crc32(&chunk[4..]);
    chunk.extend_from_slice(&crc.to_be_bytes());
    let mut out = Vec::with_capacity(png.len() + chunk.len());
    out.extend_from_slice(&png[..at]);
    out.extend_from_slice(&chunk);
    out.extend_from_slice(&png[at..]);
    out
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rasterises_with_the_embedded_font_and_records_dpi() {
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="72pt" height="36pt" viewBox="0 0 72 36"><text x="4" y="24" font-size="16">δ̂ α̂·m</text></svg>"#;
        let png = png_from_svg(svg, 300.0 / 96.0, Some(300)).unwrap();
        let pix = Pixmap::decode_png(&png).unwrap();
        assert_eq!((pix.width(), pix.height()), (300, 150));
        assert!(pix.pixels().iter().any(|p| p.red() < 100), "text was drawn");
        assert_eq!(&png[37..41], b"pHYs");
        assert_eq!(crc32(b"IEND"), 0xAE42_6082);
    }
}
