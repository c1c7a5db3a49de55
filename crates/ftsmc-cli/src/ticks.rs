//! Axis ticks and their labels: "nice" steps, an offset and/or a power-of-ten
//! factor when the labels would otherwise repeat digits (a 30 µm range
//! around 2 m reads "−20, −10, 0, 10" with "×10⁻⁶ + 2"), never "-0".

/// Tick positions, their labels, and the note that applies to all labels
/// ("×10⁻⁶ + 2"), if any.
#[derive(Debug, Clone, PartialEq)]
pub struct Ticks {
    /// Positions, data units.
    pub values: Vec<f64>,
    /// Label per position.
    pub labels: Vec<String>,
    /// Offset and scale to read the labels with.
    pub note: Option<String>,
    /// Unlabelled minor positions (log axes).
    pub minor: Vec<f64>,
}

/// 1, 2 or 5 × 10ⁿ, the smallest such step ≥ `raw`.
pub fn nice_step(raw: f64) -> f64 {
    let e = ftsmc_core::math::log10(raw).floor();
    let base = ftsmc_core::math::powf(10f64, e);
    let f = raw / base;
    let m = if f <= 1.0 + 1e-9 {
        1.0
    } else if f <= 2.0 + 1e-9 {
        2.0
    } else if f <= 5.0 + 1e-9 {
        5.0
    } else {
        10.0
    };
    m * base
}

/// Unicode superscript of an integer ("⁻⁶").
pub fn superscript(k: i32) -> String {
    k.to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            _ => '⁹',
        })
        .collect()
}

/// `v` with `decimals` decimals, a typographic minus, and never "−0".
pub fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{:.*}", decimals, v);
    if s.chars().all(|c| c == '-' || c == '0' || c == '.') {
        // Rounds to zero: drop the sign.
        return s.trim_start_matches('-').to_string();
    }
    match s.strip_prefix('-') {
        Some(rest) => format!("−{rest}"),
        None => s,
    }
}

/// A number in a short general form: plain for 10⁻³ ≤ |v| < 10⁴, else
/// "2×10⁻⁵"; at most three significant digits, trailing zeros dropped.
pub fn general(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v.is_nan() { "NaN".into() } else { fixed(v, 0) };
    }
    let e = ftsmc_core::math::log10(v.abs()).floor() as i32;
    if (-3..4).contains(&e) {
        let d = (2 - e).max(0) as usize;
        let s = fixed(v, d);
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let m = v / 10f64.powi(e);
        let ms = fixed(m, 2);
        let ms = ms.trim_end_matches('0').trim_end_matches('.');
        if ms == "1" {
            format!("10{}", superscript(e))
        } else {
            format!("{ms}×10{}", superscript(e))
        }
    }
}

/// Ticks on a linear axis over `[lo, hi]`, about `target` of them.
/// Infinite or NaN bounds are taken as ±`f64::MAX` / 0, so the number of
/// ticks stays about `target` whatever the input.
pub fn linear(lo: f64, hi: f64, target: usize) -> Ticks {
    let finite = |v: f64| if v.is_nan() { 0.0 } else { v.clamp(-f64::MAX, f64::MAX) };
    let (lo, hi) = (finite(lo) / 2.0, finite(hi) / 2.0);
    let (lo, hi) = if lo <= hi { (lo * 2.0, hi * 2.0) } else { (hi * 2.0, lo * 2.0) };
    if hi - lo > f64::MAX / 4.0 {
        // The span overflows: ticks at nice multiples of the largest bound.
        let m = lo.abs().max(hi.abs());
        let step = nice_step(m / 2.0).min(f64::MAX);
        let values: Vec<f64> = (-2i32..=2).map(|k| f64::from(k) * step).filter(|v| *v >= lo && *v <= hi).collect();
        let labels = values.iter().map(|v| general(*v)).collect();
        return Ticks { values, labels, note: None, minor: Vec::new() };
    }
    let span = (hi - lo).max(f64::MIN_POSITIVE * 1e3);
    let step = nice_step(span / target.max(2) as f64);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    let values: Vec<f64> = (first..=last).map(|k| k as f64 * step).collect();
    let mag = lo.abs().max(hi.abs());
    // An offset when the labels would need five or more identical leading digits.
    let offset = if mag / step >= 1e4 {
        let oexp = ftsmc_core::math::log10(span).floor() + 1.0;
        let unit = ftsmc_core::math::powf(10f64, oexp);
        let o = ((lo + hi) / 2.0 / unit).round() * unit;
        (o != 0.0).then_some((o, (-oexp).max(0.0) as usize))
    } else {
        None
    };
    let shifted_mag = match offset {
        Some((o, _)) => values.iter().map(|v| (v - o).abs()).fold(step, f64::max),
        None => mag,
    };
    // An engineering power of ten when the labels would be long.
    let exp3 = if offset.is_some() {
        3 * (ftsmc_core::math::log10(step) / 3.0).floor() as i32
    } else if !(1e-2..1e5).contains(&shifted_mag) {
        3 * (ftsmc_core::math::log10(shifted_mag) / 3.0).floor() as i32
    } else {
        0
    };
    let scale = 10f64.powi(exp3);
    let scaled_step = step / scale;
    let decimals = (-(ftsmc_core::math::log10(scaled_step)) - 1e-9).ceil().max(0.0) as usize;
    let o = offset.map_or(0.0, |(o, _)| o);
    let labels = values
        .iter()
        .map(|v| {
            let x = (v - o) / scale;
            let x = if x.abs() < scaled_step * 1e-6 { 0.0 } else { x };
            fixed(x, decimals)
        })
        .collect();
    let note = match (offset, exp3) {
        (None, 0) => None,
        (None, e) => Some(format!("×10{}", superscript(e))),
        (Some((o, d)), e) => {
            let os = fixed(o.abs(), d);
            let os = if os.contains('.') { os.trim_end_matches('0').trim_end_matches('.') } else { &os };
            let sign = if o < 0.0 { "−" } else { "+" };
            if e == 0 {
                Some(format!("{sign} {os}"))
            } else {
                Some(format!("×10{} {sign} {os}", superscript(e)))
            }
        }
    };
    Ticks { values, labels, note, minor: Vec::new() }
}

/// Ticks on a logarithmic axis over `[lo, hi]` (both > 0): decades (with
/// 2 and 5 between them over at most three decades, enough labels to read
/// a median), or within less than two decades at most about `max_labels`
/// labels. The bounds are clamped to the positive finite doubles, so the
/// work and the number of ticks stay bounded whatever the input (a range up
/// to 1e308 gets about `max_labels` decade labels, no minor ticks).
pub fn log(lo: f64, hi: f64, max_labels: usize) -> Ticks {
    let positive = |v: f64| if v.is_nan() { f64::MIN_POSITIVE } else { v.clamp(f64::MIN_POSITIVE, f64::MAX) };
    let (lo, hi) = (positive(lo), positive(hi));
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
    let (a, b) = (ftsmc_core::math::log10(lo), ftsmc_core::math::log10(hi));
    let d0 = (a - 1e-9).ceil() as i32;
    let d1 = (b + 1e-9).floor() as i32;
    let mut minor = Vec::new();
    // Minor ticks only where they can be told apart (at most 12 decades).
    let minor_decades = (a.floor() as i32)..=(b.ceil() as i32);
    for d in minor_decades.filter(|_| b - a <= 12.0) {
        for m in 2..10 {
            let v = f64::from(m) * 10f64.powi(d);
            if v >= lo && v <= hi {
                minor.push(v);
            }
        }
    }
    if d1 - d0 >= 1 {
        let every = ((d1 - d0) / max_labels.max(3) as i32 + 1).max(1);
        let decades: Vec<i32> = (d0..=d1).filter(|d| (d - d0) % every == 0).collect();
        // Over at most three decades, 2 and 5 between the decades: a median
        // between two labels is read to a factor of about 2, not 10.
        let mantissas: &[f64] = if b - a <= 3.2 { &[1.0, 2.0, 5.0] } else { &[1.0] };
        let mut values: Vec<f64> = Vec::new();
        for d in (d0 - 1)..=d1 {
            for m in mantissas {
                let v = m * 10f64.powi(d);
                let decade = *m == 1.0 && decades.contains(&d);
                if (decade || *m != 1.0) && v >= lo && v <= hi {
                    values.push(v);
                }
            }
        }
        // Decades alone read "10ⁿ"; with 2 and 5 between them every label
        // is a plain number ("0.02, 0.05, 0.1"), one style per axis.
        let plain = mantissas.len() > 1;
        let labels = values
            .iter()
            .map(|v| {
                if plain {
                    general(*v)
                } else {
                    format!("10{}", superscript(ftsmc_core::math::log10(*v).round() as i32))
                }
            })
            .collect();
        return Ticks { values, labels, note: None, minor };
    }
    // Less than two decades: add mantissas by priority (1; 2, 5; 3; 4, 6, 8;
    // 7, 9) while at most `max_labels` fit.
    let mut candidates: Vec<f64> = minor.iter().copied().chain((d0..=d1).map(|d| 10f64.powi(d))).collect();
    candidates.sort_by(f64::total_cmp);
    let class = |v: f64| match (v / ftsmc_core::math::powf(10f64, (ftsmc_core::math::log10(v) + 1e-9).floor())).round()
        as i32
    {
        1 => 0,
        2 | 5 => 1,
        3 => 2,
        4 | 6 | 8 => 3,
        _ => 4,
    };
    let mut values: Vec<f64> = Vec::new();
    for c in 0..5 {
        let more: Vec<f64> = candidates.iter().copied().filter(|v| class(*v) == c).collect();
        if values.len() >= 3 && values.len() + more.len() > max_labels.max(3) {
            break;
        }
        values.extend(more);
    }
    values.sort_by(f64::total_cmp);
    if values.len() < 2 {
        return linear(lo, hi, 4);
    }
    let labels = values.iter().map(|v| general(*v)).collect();
    Ticks { values, labels, note: None, minor }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn never_negative_zero() {
        for (lo, hi) in [(-0.3, 0.7), (-1.0, 1.0), (-0.25, 0.05), (-1e-9, 1e-9), (-5.0, 0.0), (-0.11, 0.0001)] {
            for target in 3..9 {
                let t = linear(lo, hi, target);
                for l in &t.labels {
                    let bare = l.trim_start_matches(['-', '−']);
                    let signed_zero = bare.len() != l.len() && bare.chars().all(|c| c == '0' || c == '.');
                    assert!(!signed_zero, "{lo} {hi}: {l} in {:?}", t.labels);
                }
                assert!(t.values.iter().any(|v| *v == 0.0 || v.abs() > 1e-300), "{t:?}");
            }
        }
        assert_eq!(fixed(-0.00001, 1), "0.0");
        assert_eq!(fixed(-1.5, 1), "−1.5");
    }

    #[test]
    fn tiny_range_gets_an_offset_and_a_scale() {
        // 30 µm around 2 m.
        let t = linear(1.99998, 2.00001, 5);
        assert_eq!(t.note.as_deref(), Some("×10⁻⁶ + 2"), "{t:?}");
        assert!(t.labels.contains(&"0".to_string()) && t.labels.contains(&"−10".to_string()), "{t:?}");
        let distinct: std::collections::BTreeSet<&String> = t.labels.iter().collect();
        assert_eq!(distinct.len(), t.labels.len(), "{t:?}");
        // Negative offset.
        let t = linear(-3.00002, -2.99999, 4);
        assert!(t.note.as_deref().unwrap().ends_with("− 3"), "{t:?}");
    }

    #[test]
    fn small_and_ordinary_ranges() {
        let t = linear(0.0, 0.003, 4);
        assert_eq!(t.note.as_deref(), Some("×10⁻³"));
        assert_eq!(t.labels, ["0", "1", "2", "3"]);
        let t = linear(-0.3, 3.1, 5);
        assert_eq!(t.note, None);
        assert_eq!(t.labels.first().unwrap(), "0");
        let t = linear(0.0, 20.0, 5);
        assert_eq!(t.labels, ["0", "5", "10", "15", "20"]);
    }

    #[test]
    fn ticks_stay_bounded_up_to_the_largest_doubles() {
        // A legal batch whose ISE reaches 1e308: the log axis padded by 20 %
        // goes past f64::MAX; it must not enumerate billions of decades.
        for (lo, hi) in [(1e-3, 1e308 * 1.5), (1e-300, f64::INFINITY), (f64::MIN_POSITIVE, f64::MAX), (0.0, f64::NAN)] {
            let t = log(lo, hi, 6);
            assert!(t.values.len() <= 12, "{lo} {hi}: {t:?}");
            assert!(t.values.len() >= 2 || hi.is_nan(), "{lo} {hi}: {t:?}");
            assert!(t.minor.len() <= 200, "{lo} {hi}: {} minor ticks", t.minor.len());
            assert!(t.values.iter().all(|v| v.is_finite() && *v > 0.0), "{t:?}");
        }
        for (lo, hi) in [(-f64::MAX, f64::MAX), (0.0, f64::INFINITY), (f64::NEG_INFINITY, 1.0), (-1e308, 1e308)] {
            let t = linear(lo, hi, 5);
            assert!(t.values.len() <= 12, "{lo} {hi}: {t:?}");
            assert!(t.values.iter().all(|v| v.is_finite()), "{t:?}");
        }
    }

    #[test]
    fn log_axes_over_a_few_decades_label_2_and_5() {
        // 0.01 to 3: a median near 0.3 lies between labels 0.2 and 0.5.
        let t = log(0.01, 3.0, 6);
        for l in ["0.02", "0.05", "0.1", "0.2", "0.5", "1", "2"] {
            assert!(t.labels.iter().any(|x| x == l), "{l} in {:?}", t.labels);
        }
        // Many decades: decades only.
        let t = log(1e-6, 1e3, 6);
        assert!(t.labels.iter().all(|l| l.starts_with("10")), "{:?}", t.labels);
    }

    #[test]
    fn log_ticks() {
        let t = log(1e-3, 100.0, 6);
        assert_eq!(t.labels.first().unwrap(), "10⁻³");
        assert_eq!(t.labels.last().unwrap(), "10²");
        let t = log(0.013, 0.09, 5);
        assert!(t.labels.len() >= 2, "{t:?}");
        assert!(t.labels.contains(&"0.02".to_string()), "{t:?}");
        let t = log(0.55, 2.5, 4);
        assert_eq!(t.labels, ["0.6", "0.8", "1", "2"]);
        assert_eq!(general(2e-5), "2×10⁻⁵");
        assert_eq!(general(0.5), "0.5");
    }
}
