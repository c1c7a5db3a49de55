//! Wind: a mean wind vector, discrete 1−cosine gusts and Dryden turbulence
//! in the low-altitude form of MIL-F-8785C §3.7 / MIL-HDBK-1797 (Appendix A,
//! the "Dryden form"), evaluated in the world frame (x, y horizontal, z up,
//! as [`crate::vehicle::rigid_body`]) for the air-relative drag of the truth
//! models.
//!
//! # Spectra (what this module implements)
//!
//! Frozen turbulence seen at airspeed `V`, spatial frequency `Ω = ω/V`
//! (rad/m), **MIL-F-8785C form** with the 8785C scale lengths:
//!
//! ```text
//! Φ_u(Ω) = σ_u² (2 L_u/π) / (1 + (L_u Ω)²)
//! Φ_v(Ω) = σ_v² (L_v/π) (1 + 3 (L_v Ω)²) / (1 + (L_v Ω)²)²      (Φ_w likewise)
//! low altitude, h in ft (h < 1000 ft):
//!   L_w = h,  L_u = L_v = h / (0.177 + 0.000823 h)^1.2
//!   σ_w = 0.1 W₂₀,  σ_u = σ_v = σ_w / (0.177 + 0.000823 h)^0.4
//!   W₂₀ = 15 / 30 / 45 kt (light / moderate / severe)
//! ```
//!
//! MIL-HDBK-1797 writes the same spectra as
//! `Φ_v = σ² (2L/π)(1 + 12 (LΩ)²)/(1 + 4 (LΩ)²)²` with **halved** lateral and
//! vertical scales (`2 L_w = h`, `2 L_v = L_u`); `Φ_u` is identical in both.
//! The two are the same spectrum; the scales [`DrydenScales::length`] returned
//! here are the 8785C ones and must be used with the 8785C form above. Each
//! `Φ(Ω)` is one-sided in Ω (∫₀^∞ Φ dΩ = σ²); in time, `Φ(ω) = Φ(Ω)/V` is
//! one-sided in rad/s (∫₀^∞ Φ(ω) dω = σ²).
//!
//! # Shaping filters and their discretisation
//!
//! With `a = V/L` (1/s), the temporal spectra are those of
//!
//! ```text
//! u:  u̇ = −a u + σ_u √(2a) ξ                         (H_u = σ_u √(2L/(πV)) / (1 + s/a))
//! v:  ż₁ = a z₂,  ż₂ = −a z₁ − 2a z₂ + σ_v √a ξ,  v = z₁ + √3 z₂
//!                                                    (H_v = σ_v √(L/(πV)) (1 + √3 s/a) / (1 + s/a)²)
//! ```
//!
//! (`w` like `v`), `ξ` unit-intensity white noise (`E[ξ(t)ξ(s)] = δ(t − s)`).
//! The states are scaled so that their stationary covariance does not depend
//! on `V`: `u` has variance σ_u², `z₁`, `z₂` are uncorrelated with variance
//! σ²/4 each (so `var v = σ²/4 + 3σ²/4 = σ²`), and changing the airspeed
//! ([`Dryden::set_airspeed`]) changes the coefficients without a transient.
//!
//! The processes are discretised **exactly** at the step `dt` (the sampled
//! sequence has exactly the continuous process's autocovariance at the sample
//! instants): `x_{k+1} = e^{A dt} x_k + w_k`, `w_k ~ N(0, Q_d)`,
//! `Q_d = ∫₀^dt e^{As} B Bᵀ e^{Aᵀs} ds`. For `u`: `e^{−a dt}` and
//! `Q_d = σ_u² (1 − e^{−2a dt})`. For `v`, `w` (double real pole at `−a`,
//! `y = a dt`):
//!
//! ```text
//! e^{A dt} = e^{−y} [[1 + y, y], [−y, 1 − y]]
//! Q_d = σ² [[y³ J₂,  y² J₁ − y³ J₂], [·,  y J₀ − 2 y² J₁ + y³ J₂]],
//! J_n = ∫₀¹ uⁿ e^{−2y u} du   (closed forms, Taylor series for small y)
//! ```
//!
//! and `w_k = chol(Q_d) (n₁, n₂)`. The filters start in their stationary
//! distribution, so the sample is stationary from the first step.
//!
//! # Frame
//!
//! The turbulence components are along the wind axes of a hovering vehicle:
//! `u` along the horizontal direction of the mean wind (world x when the
//! horizontal mean wind is below 1e-9 m/s), `v` horizontal and lateral
//! (`ẑ × u`), `w` world z (up). The airspeed of the spatial-to-temporal
//! conversion defaults to `V = max(‖mean wind‖, airspeed_floor)` (the mean
//! wind carries the frozen field past a hovering vehicle);
//! [`Wind::set_airspeed`] sets it from the vehicle's airspeed.
//!
//! # Random streams
//!
//! Each turbulence axis draws from its own `ChaCha8Rng` keyed by the run's
//! seed, streams [`WIND_TURBULENCE_STREAMS`] (u, v, w), distinct from the
//! drag noise (1–6), motor noise (16) and Monte Carlo sampling (100+), so
//! turning turbulence on or off changes no other source's draws.
//! Each stream is read through a [`crate::noise::NoiseStream`] (the
//! generator's own words, read a block ahead), so the draws are those of
//! [`crate::gauss::standard_normal`] on the `ChaCha8Rng` itself.

use crate::rng::chacha_stream;
use ftsmc_core::law::GainError;
use serde::{Deserialize, Serialize};

use crate::noise::NoiseStream;

/// One knot in m/s (exact: 1852 m / 3600 s ≈ 0.514444).
pub const KNOT: f64 = 1852.0 / 3600.0;

/// One foot in m (exact).
pub const FOOT: f64 = 0.3048;

/// ChaCha streams of the turbulence axes `u`, `v`, `w`, keyed by the run's
/// seed (drag noise uses 1–6, motor noise 16, Monte Carlo sampling 100+).
pub const WIND_TURBULENCE_STREAMS: [u64; 3] = [32, 33, 34];

/// Upper end of the low-altitude Dryden model: 1000 ft, in m.
pub const LOW_ALTITUDE_MAX: f64 = 1000.0 * FOOT;

/// Turbulence intensity: the wind speed at 20 ft, `W₂₀`, directly or by its
/// MIL-F-8785C / MIL-HDBK-1797 preset. In a scenario file: `"light"`,
/// `"moderate"`, `"severe"` or `{ w20 = 7.7 }` (m/s).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum Intensity {
    /// Light: `W₂₀` = 15 kt (7.72 m/s).
    Light,
    /// Moderate: `W₂₀` = 30 kt (15.43 m/s).
    Moderate,
    /// Severe: `W₂₀` = 45 kt (23.15 m/s).
    Severe,
    /// `W₂₀` in m/s.
    W20(f64),
}

impl Intensity {
    /// Wind speed at 20 ft, `W₂₀`, in m/s.
    pub fn w20(self) -> f64 {
        match self {
            Intensity::Light => 15.0 * KNOT,
            Intensity::Moderate => 30.0 * KNOT,
            Intensity::Severe => 45.0 * KNOT,
            Intensity::W20(w) => w,
        }
    }
}

fn default_altitude() -> f64 {
    10.0
}

fn default_airspeed_floor() -> f64 {
    1.0
}

/// Dryden turbulence, low-altitude form (MIL-F-8785C §3.7.2.3,
/// MIL-HDBK-1797 Appendix A): `[wind.turbulence]`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TurbulenceParams {
    /// `W₂₀`: `"light"` | `"moderate"` | `"severe"` | `{ w20 = m/s }`. Required.
    pub intensity: Intensity,
    /// Altitude `h` above ground that sets σ and L, m, fixed for the flight
    /// (the vehicle's altitude is not tracked). Default 10 m. Range
    /// `[0.1, 304.8]` (the low-altitude form holds below 1000 ft).
    #[serde(default = "default_altitude")]
    pub altitude: f64,
    /// Airspeed floor `V_min`, m/s: the spatial-to-temporal conversion uses
    /// `V = max(airspeed, V_min)`, since a hovering vehicle has V ≈ 0.
    /// Default 1 m/s.
    #[serde(default = "default_airspeed_floor")]
    pub airspeed_floor: f64,
}

impl TurbulenceParams {
    /// Moderate turbulence at the default altitude (10 m) and airspeed floor (1 m/s).
    pub fn moderate() -> Self {
        Self { intensity: Intensity::Moderate, altitude: default_altitude(), airspeed_floor: default_airspeed_floor() }
    }

    /// Intensities and scale lengths at [`Self::altitude`], MIL-F-8785C
    /// low-altitude formulas (h in ft inside, results in SI).
    pub fn scales(&self) -> DrydenScales {
        let h_ft = self.altitude / FOOT;
        let k = 0.177 + 0.000823 * h_ft;
        let sigma_w = 0.1 * self.intensity.w20();
        let sigma_uv = sigma_w / ftsmc_core::math::powf(k, 0.4);
        let l_uv = h_ft / ftsmc_core::math::powf(k, 1.2) * FOOT;
        DrydenScales { sigma: [sigma_uv, sigma_uv, sigma_w], length: [l_uv, l_uv, self.altitude] }
    }
}

/// Dryden intensities and scale lengths (MIL-F-8785C convention, see the
/// module documentation), components `[u, v, w]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrydenScales {
    /// `[σ_u, σ_v, σ_w]`, m/s.
    pub sigma: [f64; 3],
    /// `[L_u, L_v, L_w]`, m (8785C: `L_w = h`; MIL-HDBK-1797 halves `L_v`, `L_w`).
    pub length: [f64; 3],
}

impl DrydenScales {
    /// Share of the `u` variance below `frequency` (Hz) at `airspeed` (m/s):
    /// integrating the first-order spectrum (module docs),
    /// `(2/π) atan(2π f L_u / V)`. Turbulence carried by a strong mean wind
    /// has its energy at higher frequencies (gusts); carried at a 1 m/s
    /// floor it is a slowly wandering wind.
    pub fn u_variance_share_below(&self, frequency: f64, airspeed: f64) -> f64 {
        core::f64::consts::FRAC_2_PI
            * ftsmc_core::math::atan(core::f64::consts::TAU * frequency * self.length[0] / airspeed)
    }
}

/// Statistics of a `[wind]` section as flown (after [`WindParams::resolved`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindSummary {
    /// Mean wind speed, m/s.
    pub mean_speed: f64,
    /// Turbulence intensities `[σ_u, σ_v, σ_w]`, m/s (zero without turbulence).
    pub sigma: [f64; 3],
    /// Dryden airspeed `V`, m/s (`None` without turbulence).
    pub airspeed: Option<f64>,
    /// Share of the `u` variance below 0.1 Hz (`None` without turbulence).
    pub u_share_below_0_1_hz: Option<f64>,
}

impl WindParams {
    /// Mean speed, σ and the share of `u` variance below 0.1 Hz of this
    /// wind as [`Wind::new`] flies it (airspeed `max(‖mean‖, floor)`).
    pub fn summary(&self) -> WindSummary {
        let r = self.resolved();
        let mean_speed = r.mean.iter().map(|v| v * v).sum::<f64>().sqrt();
        match r.turbulence {
            None => WindSummary { mean_speed, sigma: [0.0; 3], airspeed: None, u_share_below_0_1_hz: None },
            Some(t) => {
                let scales = t.scales();
                let v = mean_speed.max(t.airspeed_floor);
                WindSummary {
                    mean_speed,
                    sigma: scales.sigma,
                    airspeed: Some(v),
                    u_share_below_0_1_hz: Some(scales.u_variance_share_below(0.1, v)),
                }
            }
        }
    }
}

/// The Beaufort wind force scale: `(force, description, lower bound of its
/// mean wind speed at 10 m, m/s)`, force 0 to 12, as tabulated by the WMO
/// (Manual on Marine Meteorological Services, WMO-No. 558, Annex I; the
/// same ranges as the Met Office's "Beaufort wind force scale"). The
/// ranges are given to 0.1 m/s, so a speed is rounded to 0.1 m/s before it
/// is placed ([`beaufort`]).
pub const BEAUFORT: [(u32, &str, f64); 13] = [
    (0, "calm", 0.0),
    (1, "light air", 0.3),
    (2, "light breeze", 1.6),
    (3, "gentle breeze", 3.4),
    (4, "moderate breeze", 5.5),
    (5, "fresh breeze", 8.0),
    (6, "strong breeze", 10.8),
    (7, "near gale", 13.9),
    (8, "gale", 17.2),
    (9, "strong gale", 20.8),
    (10, "storm", 24.5),
    (11, "violent storm", 28.5),
    (12, "hurricane force", 32.7),
];

/// Height of the Beaufort scale's wind speed (the WMO standard height of
/// surface wind measurements), m.
pub const BEAUFORT_HEIGHT: f64 = 10.0;

/// Beaufort force and description of a mean wind of `speed_10m` m/s at
/// 10 m ([`BEAUFORT`]): the highest force whose lower bound the speed,
/// rounded to 0.1 m/s, reaches. A negative or non-finite speed is force 0.
pub fn beaufort(speed_10m: f64) -> (u32, &'static str) {
    let rounded = (speed_10m * 10.0).round() / 10.0;
    let mut out = (BEAUFORT[0].0, BEAUFORT[0].1);
    for &(force, words, lower) in &BEAUFORT {
        if rounded >= lower - 1e-9 {
            out = (force, words);
        }
    }
    out
}

/// The MIL-F-8785C / MIL-HDBK-1797 word for a turbulence of `W₂₀` (m/s):
/// `Some("light")` at 15 kt, `"moderate"` at 30 kt, `"severe"` at 45 kt
/// (to 0.05 kt), `None` for any other `W₂₀` (the specification names only
/// these three).
pub fn mil_intensity_word(w20: f64) -> Option<&'static str> {
    let kt = w20 / KNOT;
    [(15.0, "light"), (30.0, "moderate"), (45.0, "severe")]
        .into_iter()
        .find(|(k, _)| (kt - k).abs() < 0.05)
        .map(|(_, w)| w)
}

impl WindParams {
    /// The altitude this wind's mean speed and turbulence are given at, m:
    /// `altitude` (or the preset's default 5 m) with a preset, else the
    /// turbulence's altitude, else `altitude` if written; `None` for a
    /// mean wind of no stated altitude.
    pub fn stated_altitude(&self) -> Option<f64> {
        if self.preset.is_some() {
            return Some(self.preset_altitude());
        }
        self.turbulence.map(|t| t.altitude).or(self.altitude)
    }

    /// This wind in a user's words, computed from its parameters as flown
    /// ([`WindParams::resolved`]): the mean wind in m/s at its altitude,
    /// the Beaufort force of that wind carried to 10 m by the MIL-F-8785C
    /// §3.7.2.1 logarithmic profile (`u(10 m) = u(h) ln(10 m/z₀)/ln(h/z₀)`,
    /// [`ROUGHNESS_LENGTH`]), and the turbulence as its MIL-F-8785C word
    /// ([`mil_intensity_word`]) or its `W₂₀` in kt, with σ_u. E.g.
    /// `7.4 m/s mean wind at 5 m (Beaufort 5, fresh breeze), light turbulence
    /// (MIL-F-8785C, W₂₀ 15 kt, σ_u 1.50 m/s)`.
    pub fn in_words(&self) -> String {
        let summary = self.summary();
        let resolved = self.resolved();
        let altitude = self.stated_altitude();
        let mean = if summary.mean_speed == 0.0 {
            "no mean wind".to_string()
        } else {
            let at = altitude.map_or_else(String::new, |h| format!(" at {} m", crate::text::show(h)));
            let force = altitude.filter(|&h| h > ROUGHNESS_LENGTH).map(|h| {
                let u10 = summary.mean_speed * ftsmc_core::math::ln(BEAUFORT_HEIGHT / ROUGHNESS_LENGTH)
                    / ftsmc_core::math::ln(h / ROUGHNESS_LENGTH);
                let (force, words) = beaufort(u10);
                format!(" (Beaufort {force}, {words})")
            });
            format!("{:.1} m/s mean wind{at}{}", summary.mean_speed, force.unwrap_or_default())
        };
        let turbulence = match resolved.turbulence {
            None => "no turbulence".to_string(),
            Some(t) => {
                let w20 = t.intensity.w20();
                let kt = w20 / KNOT;
                let sigma = format!("σ_u {:.2} m/s", summary.sigma[0]);
                match mil_intensity_word(w20) {
                    Some(word) => format!("{word} turbulence (MIL-F-8785C, W₂₀ {kt:.0} kt, {sigma})"),
                    None if kt < 15.0 => {
                        format!("turbulence below MIL-F-8785C light (W₂₀ {kt:.0} kt against 15 kt, {sigma})")
                    }
                    None => format!("turbulence of W₂₀ {kt:.0} kt (MIL-F-8785C, {sigma})"),
                }
            }
        };
        if summary.mean_speed == 0.0 && resolved.turbulence.is_none() {
            return "still air (no mean wind, no turbulence)".into();
        }
        format!("{mean}, {turbulence}")
    }

    /// [`WindParams::in_words`] short enough for a figure title: the mean
    /// wind in m/s at its altitude and the turbulence's MIL-F-8785C word
    /// (or `W₂₀` in kt), e.g. `7.4 m/s mean wind at 5 m, light turbulence`.
    pub fn in_short_words(&self) -> String {
        let summary = self.summary();
        let resolved = self.resolved();
        if summary.mean_speed == 0.0 && resolved.turbulence.is_none() {
            return "still air".into();
        }
        let at = self.stated_altitude().map_or_else(String::new, |h| format!(" at {} m", crate::text::show(h)));
        let turbulence = match resolved.turbulence {
            None => "no turbulence".to_string(),
            Some(t) => match mil_intensity_word(t.intensity.w20()) {
                Some(word) => format!("{word} turbulence"),
                None => format!("turbulence of W₂₀ {:.0} kt", t.intensity.w20() / KNOT),
            },
        };
        format!("{:.1} m/s mean wind{at}, {turbulence}", summary.mean_speed)
    }
}

/// A discrete 1−cosine gust (MIL-F-8785C §3.7.3):
/// `v(t) = A/2 (1 − cos(2π (t − t₀)/d))` for `t ∈ [t₀, t₀ + d]`, zero outside.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Gust {
    /// Start time `t₀`, s.
    pub start: f64,
    /// Duration `d`, s (the peak `A` is reached at `t₀ + d/2`).
    pub duration: f64,
    /// Amplitude `A`, world frame, m/s.
    pub amplitude: [f64; 3],
}

impl Gust {
    /// Gust velocity at `t` (s), world frame, m/s.
    #[inline]
    pub fn velocity(&self, t: f64) -> [f64; 3] {
        if t < self.start || t > self.start + self.duration {
            return [0.0; 3];
        }
        let s = 0.5 * (1.0 - ftsmc_core::math::cos(2.0 * core::f64::consts::PI * (t - self.start) / self.duration));
        self.amplitude.map(|a| a * s)
    }
}

/// A rung of the wind ladder (`[wind] preset = "calm" | "breeze" | "light" |
/// "moderate"`): the wind speed at 20 ft `W₂₀` that sets both the mean wind
/// at the flight's altitude (MIL-F-8785C §3.7.2.1 logarithmic profile) and
/// the Dryden turbulence (MIL-F-8785C §3.7.2.3, σ_w = 0.1 W₂₀).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum WindPreset {
    /// Still air (`W₂₀` = 0): an indoor motion-capture room. No mean wind,
    /// no turbulence.
    Calm,
    /// `W₂₀` = 5 kt (2.57 m/s): Beaufort force 2, "light breeze" (4–6 kt),
    /// with the MIL-F-8785C low-altitude relations applied at that `W₂₀`
    /// (the specification itself starts its table at 15 kt).
    Breeze,
    /// `W₂₀` = 15 kt (7.72 m/s): MIL-F-8785C / MIL-HDBK-1797 "light".
    Light,
    /// `W₂₀` = 30 kt (15.43 m/s): MIL-F-8785C / MIL-HDBK-1797 "moderate".
    Moderate,
}

impl WindPreset {
    /// Wind speed at 20 ft, `W₂₀`, m/s.
    pub fn w20(self) -> f64 {
        match self {
            WindPreset::Calm => 0.0,
            WindPreset::Breeze => 5.0 * KNOT,
            WindPreset::Light => 15.0 * KNOT,
            WindPreset::Moderate => 30.0 * KNOT,
        }
    }
}

/// Roughness length `z₀` of the MIL-F-8785C §3.7.2.1 mean-wind profile for
/// Category C flight phases (take-off, approach, landing): 0.15 ft, in m.
pub const ROUGHNESS_LENGTH: f64 = 0.15 * FOOT;

/// Mean wind speed (m/s) at `altitude` (m) for a wind of `w20` (m/s) at
/// 20 ft: MIL-F-8785C §3.7.2.1, `u(h) = W₂₀ ln(h/z₀) / ln(20 ft/z₀)`,
/// `z₀` = [`ROUGHNESS_LENGTH`]; 0 at or below `z₀`.
pub fn mean_wind_at(w20: f64, altitude: f64) -> f64 {
    if altitude <= ROUGHNESS_LENGTH {
        return 0.0;
    }
    w20 * ftsmc_core::math::ln(altitude / ROUGHNESS_LENGTH) / ftsmc_core::math::ln(20.0 * FOOT / ROUGHNESS_LENGTH)
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// The `[wind]` keys a `preset` owns: a file that sets `preset` replaces
/// what a base file gave them unless it sets them too (the mean wind's
/// `speed`, its vector `mean`, and the `turbulence`).
pub const PRESET_OWNED_KEYS: [&str; 3] = ["speed", "mean", "turbulence"];

/// Wind parameters (`[wind]`): mean wind, gusts and turbulence; every part
/// optional, the default is still air.
///
/// The mean wind is given either as a vector (`mean`), or as a speed and a
/// direction (`speed`, `direction`), or by a ladder rung (`preset`, which
/// also sets the turbulence unless `turbulence` is given). With a preset
/// the Dryden airspeed is the mean wind at `altitude` (the frozen field is
/// carried past a hovering vehicle by the mean wind; the floor only matters
/// for `calm`, which has no turbulence).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct WindParams {
    /// A rung of the wind ladder: mean wind at `altitude` along `direction`
    /// and Dryden turbulence of the same `W₂₀` (see [`WindPreset`]). Default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preset: Option<WindPreset>,
    /// Mean wind speed, m/s, horizontal along `direction` (replaces the
    /// preset's). Default none. Not together with a non-zero `mean`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
    /// Direction the mean wind blows towards, degrees from world x towards
    /// world y (0: along +x). Default 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub direction: f64,
    /// Altitude of the preset's mean wind and turbulence, m (`[0.1, 304.8]`).
    /// Default 5 m (the middle of the paper scenarios' altitudes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub altitude: Option<f64>,
    /// Mean wind, world frame, m/s. Default `[0, 0, 0]`.
    pub mean: [f64; 3],
    /// Discrete 1−cosine gusts, added to the mean. Default none.
    pub gusts: Vec<Gust>,
    /// Dryden turbulence. Default off.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub turbulence: Option<TurbulenceParams>,
}

fn closed(field: &'static str, value: f64, lo: f64, hi: f64, expected: &'static str) -> Result<(), GainError> {
    if (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(GainError { field, value, expected })
    }
}

impl WindParams {
    /// Reject non-physical values:
    ///
    /// | parameter | range |
    /// |---|---|
    /// | `mean` components (m/s) | `[−100, 100]` |
    /// | `gusts.start` (s) | `[0, 1e7]` |
    /// | `gusts.duration` (s) | `(0, 1e6]` |
    /// | `gusts.amplitude` components (m/s) | `[−100, 100]` |
    /// | `turbulence.intensity.w20` (m/s) | `[0, 100]` |
    /// | `turbulence.altitude` (m) | `[0.1, 304.8]` (below 1000 ft) |
    /// | `turbulence.airspeed_floor` (m/s) | `[0.01, 1000]` |
    pub fn check(&self) -> Result<(), GainError> {
        if let Some(v) = self.speed {
            closed("speed", v, 0.0, 100.0, "0 <= speed <= 100 m/s")?;
            if self.mean != [0.0; 3] {
                return Err(GainError {
                    field: "speed",
                    value: v,
                    expected: "either speed (and direction) or mean, not both",
                });
            }
        }
        if self.preset.is_some() && self.mean != [0.0; 3] {
            return Err(GainError {
                field: "mean",
                value: self.mean[0],
                expected: "no mean with a preset (use speed and direction to change the preset's mean wind)",
            });
        }
        closed("direction", self.direction, -360.0, 360.0, "-360 <= direction <= 360 degrees")?;
        if let Some(h) = self.altitude {
            closed("altitude", h, 0.1, LOW_ALTITUDE_MAX, "0.1 <= altitude <= 304.8 m (low-altitude Dryden form)")?;
        }
        for &m in &self.mean {
            closed("mean", m, -100.0, 100.0, "-100 <= mean <= 100 m/s per component")?;
        }
        for g in &self.gusts {
            closed("gusts.start", g.start, 0.0, 1e7, "0 <= start <= 1e7 s")?;
            if !(g.duration > 0.0 && g.duration <= 1e6) {
                return Err(GainError {
                    field: "gusts.duration",
                    value: g.duration,
                    expected: "0 < duration <= 1e6 s",
                });
            }
            for &a in &g.amplitude {
                closed("gusts.amplitude", a, -100.0, 100.0, "-100 <= amplitude <= 100 m/s per component")?;
            }
        }
        if let Some(t) = &self.turbulence {
            if let Intensity::W20(w) = t.intensity {
                closed("turbulence.intensity.w20", w, 0.0, 100.0, "0 <= w20 <= 100 m/s")?;
            }
            closed(
                "turbulence.altitude",
                t.altitude,
                0.1,
                LOW_ALTITUDE_MAX,
                "0.1 <= altitude <= 304.8 m (low-altitude Dryden form, below 1000 ft)",
            )?;
            closed("turbulence.airspeed_floor", t.airspeed_floor, 0.01, 1000.0, "0.01 <= airspeed_floor <= 1000 m/s")?;
        }
        Ok(())
    }

    /// The altitude of the preset, m (default 5).
    pub fn preset_altitude(&self) -> f64 {
        self.altitude.unwrap_or(5.0)
    }

    /// These parameters with `preset`, `speed` and `direction` expanded
    /// into `mean` and `turbulence` (what [`Wind::new`] flies): the mean
    /// wind is `speed` (or the preset's [`mean_wind_at`] its altitude)
    /// along `direction`; a preset other than `calm` adds Dryden turbulence
    /// of its `W₂₀` at its altitude unless `turbulence` is given. Without
    /// any of them the parameters are returned unchanged.
    pub fn resolved(&self) -> WindParams {
        let mut out = self.clone();
        let speed = match (self.speed, self.preset) {
            (Some(v), _) => Some(v),
            (None, Some(p)) => Some(mean_wind_at(p.w20(), self.preset_altitude())),
            (None, None) => None,
        };
        if let Some(v) = speed {
            let (s, c) = ftsmc_core::math::sin_cos(self.direction.to_radians());
            out.mean = [v * c, v * s, 0.0];
        }
        if let Some(p) = self.preset {
            if out.turbulence.is_none() && p != WindPreset::Calm {
                out.turbulence = Some(TurbulenceParams {
                    intensity: Intensity::W20(p.w20()),
                    altitude: self.preset_altitude(),
                    airspeed_floor: default_airspeed_floor(),
                });
            }
        }
        out
    }

    /// Mean wind plus gusts at `t` (s), world frame, m/s.
    #[inline]
    pub fn deterministic(&self, t: f64) -> [f64; 3] {
        let mut v = self.mean;
        for g in &self.gusts {
            let gv = g.velocity(t);
            for i in 0..3 {
                v[i] += gv[i];
            }
        }
        v
    }
}

/// `J_n(x) = ∫₀¹ uⁿ e^{−x u} du` for n = 0, 1, 2, accurate for all `x ≥ 0`.
fn j_integrals(x: f64) -> [f64; 3] {
    if x < 1.0 {
        // Σ_k (−x)^k / (k! (n + k + 1)); 25 terms leave < 1e-25 at x < 1.
        let mut out = [0.0; 3];
        let mut term = 1.0; // (−x)^k / k!
        for k in 0..25 {
            for (n, o) in out.iter_mut().enumerate() {
                *o += term / (n + k + 1) as f64;
            }
            term *= -x / (k + 1) as f64;
        }
        out
    } else {
        let e = ftsmc_core::math::exp(-x);
        [(1.0 - e) / x, (1.0 - e * (1.0 + x)) / (x * x), (2.0 - e * (2.0 + 2.0 * x + x * x)) / (x * x * x)]
    }
}

/// Exact discretisation of the first-order (`u`) shaping filter at one
/// airspeed: `x ← φ x + g n`.
#[derive(Clone, Copy, Debug)]
struct FirstOrder {
    phi: f64,
    gain: f64,
}

impl FirstOrder {
    fn new(sigma: f64, a: f64, dt: f64) -> Self {
        let y = a * dt;
        Self { phi: ftsmc_core::math::exp(-y), gain: sigma * (-ftsmc_core::math::exp_m1(-2.0 * y)).sqrt() }
    }
}

/// Exact discretisation of a second-order (`v`, `w`) shaping filter at one
/// airspeed: `z ← Φ z + L (n₁, n₂)`, `L` lower triangular.
#[derive(Clone, Copy, Debug)]
struct SecondOrder {
    phi: [[f64; 2]; 2],
    chol: [[f64; 2]; 2],
}

impl SecondOrder {
    fn new(sigma: f64, a: f64, dt: f64) -> Self {
        let y = a * dt;
        let e = ftsmc_core::math::exp(-y);
        let phi = [[e * (1.0 + y), e * y], [-e * y, e * (1.0 - y)]];
        let [j0, j1, j2] = j_integrals(2.0 * y);
        let s2 = sigma * sigma;
        let q11 = s2 * y * y * y * j2;
        let q12 = s2 * (y * y * j1 - y * y * y * j2);
        let q22 = s2 * (y * j0 - 2.0 * y * y * j1 + y * y * y * j2);
        let l11 = q11.max(0.0).sqrt();
        let l21 = if l11 > 0.0 { q12 / l11 } else { 0.0 };
        let l22 = (q22 - l21 * l21).max(0.0).sqrt();
        Self { phi, chol: [[l11, 0.0], [l21, l22]] }
    }
}

/// The `v` and `w` filters ([`SecondOrder`]) side by side, entry by entry
/// (`[v, w]`), so that one step of both is one pass of paired operations.
#[derive(Clone, Copy, Debug, Default)]
struct SecondOrderPair {
    /// `Φ[r][c]` of each filter.
    phi: [[[f64; 2]; 2]; 2],
    /// `L[r][c]` of each filter (lower triangular).
    chol: [[[f64; 2]; 2]; 2],
}

impl SecondOrderPair {
    fn new(filters: &[SecondOrder; 2]) -> Self {
        let mut pair = Self::default();
        for (k, f) in filters.iter().enumerate() {
            for r in 0..2 {
                for c in 0..2 {
                    pair.phi[r][c][k] = f.phi[r][c];
                    pair.chol[r][c][k] = f.chol[r][c];
                }
            }
        }
        pair
    }

    /// One step of both filters' states `(z₁, z₂)` (`z1[k]`, `z2[k]` of
    /// filter `k`) with their draws `n₁`, `n₂`: for each filter
    /// `z₁ ← Φ₁₁ z₁ + Φ₁₂ z₂ + L₁₁ n₁`, `z₂ ← Φ₂₁ z₁ + Φ₂₂ z₂ + L₂₁ n₁ + L₂₂ n₂`
    /// (old `z` on the right), summed left to right.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn step(&self, z1: &mut [f64; 2], z2: &mut [f64; 2], n1: [f64; 2], n2: [f64; 2]) {
        let [[p11, p12], [p21, p22]] = self.phi;
        let [[l11, _], [l21, l22]] = self.chol;
        let (a, b) = (*z1, *z2);
        for k in 0..2 {
            z1[k] = p11[k] * a[k] + p12[k] * b[k] + l11[k] * n1[k];
            z2[k] = p21[k] * a[k] + p22[k] * b[k] + l21[k] * n1[k] + l22[k] * n2[k];
        }
    }
}

/// Dryden turbulence generator: three shaping filters discretised exactly at
/// `dt`, each with its own random stream ([`WIND_TURBULENCE_STREAMS`]).
/// Output in the wind axes `[u, v, w]` (see the module documentation).
#[derive(Clone, Debug)]
pub struct Dryden {
    params: TurbulenceParams,
    scales: DrydenScales,
    dt: f64,
    airspeed: f64,
    /// The `u` filter.
    u_filter: FirstOrder,
    /// The `v` and `w` filters, side by side.
    vw_filters: SecondOrderPair,
    /// The `u` state.
    u: f64,
    /// The `v` and `w` states: `z₁` of each, then `z₂` of each.
    vw: [[f64; 2]; 2],
    rngs: [NoiseStream; 3],
}

impl Dryden {
    /// A generator at step `dt` (s), airspeed `max(airspeed, airspeed_floor)`
    /// (m/s), streams [`WIND_TURBULENCE_STREAMS`] of `seed`; the filters
    /// start in their stationary distribution (first draws of each stream).
    /// `params` and `dt` are assumed checked ([`WindParams::check`], `dt > 0`).
    pub fn new(params: TurbulenceParams, dt: f64, airspeed: f64, seed: u64) -> Self {
        let mut rngs: [NoiseStream; 3] =
            core::array::from_fn(|k| NoiseStream::new(chacha_stream(seed, WIND_TURBULENCE_STREAMS[k])));
        let scales = params.scales();
        let u = scales.sigma[0] * rngs[0].normal();
        let mut vw = [[0.0; 2]; 2];
        for k in 0..2 {
            let sigma = scales.sigma[1 + k];
            vw[0][k] = 0.5 * sigma * rngs[1 + k].normal();
            vw[1][k] = 0.5 * sigma * rngs[1 + k].normal();
        }
        let mut d = Self {
            params,
            scales,
            dt,
            airspeed: f64::NAN,
            u_filter: FirstOrder { phi: 0.0, gain: 0.0 },
            vw_filters: SecondOrderPair::default(),
            u,
            vw,
            rngs,
        };
        d.set_airspeed(airspeed);
        d
    }

    /// From now on the filters are driven by the streams
    /// [`WIND_TURBULENCE_STREAMS`] of `seed`, each at its first word; the
    /// filter states carry over (a flight branched with fresh noise,
    /// `falsify::splitting`).
    pub fn reseed_noise(&mut self, seed: u64) {
        self.rngs = core::array::from_fn(|k| NoiseStream::new(chacha_stream(seed, WIND_TURBULENCE_STREAMS[k])));
    }

    /// Set the airspeed of the spatial-to-temporal conversion to
    /// `max(airspeed, airspeed_floor)` (m/s) and rediscretise the filters;
    /// the states carry over (their stationary law does not depend on V).
    pub fn set_airspeed(&mut self, airspeed: f64) {
        let v =
            if airspeed.is_finite() { airspeed.max(self.params.airspeed_floor) } else { self.params.airspeed_floor };
        if v == self.airspeed {
            return;
        }
        self.airspeed = v;
        let s = &self.scales;
        self.u_filter = FirstOrder::new(s.sigma[0], v / s.length[0], self.dt);
        self.vw_filters = SecondOrderPair::new(&[
            SecondOrder::new(s.sigma[1], v / s.length[1], self.dt),
            SecondOrder::new(s.sigma[2], v / s.length[2], self.dt),
        ]);
    }

    /// The airspeed in use, m/s.
    pub fn airspeed(&self) -> f64 {
        self.airspeed
    }

    /// Intensities and scale lengths in use.
    pub fn scales(&self) -> DrydenScales {
        self.scales
    }

    /// The current turbulence `[u, v, w]` (m/s, wind axes).
    #[inline]
    pub fn current(&self) -> [f64; 3] {
        let [z1, z2] = self.vw;
        let out = |k: usize| z1[k] + 3f64.sqrt() * z2[k];
        [self.u, out(0), out(1)]
    }

    /// Return the current turbulence `[u, v, w]` (m/s, wind axes), then
    /// advance the filters by one step `dt` (draws: one on `u`'s stream,
    /// then two on `v`'s, then two on `w`'s).
    #[inline]
    pub fn step(&mut self) -> [f64; 3] {
        let now = self.current();
        let [u_rng, v_rng, w_rng] = &mut self.rngs;
        let FirstOrder { phi, gain } = self.u_filter;
        self.u = phi * self.u + gain * u_rng.normal();
        let (v1, v2) = (v_rng.normal(), v_rng.normal());
        let (w1, w2) = (w_rng.normal(), w_rng.normal());
        let [z1, z2] = &mut self.vw;
        self.vw_filters.step(z1, z2, [v1, w1], [v2, w2]);
        now
    }
}

/// The wind of a flight: mean + gusts + turbulence, world frame.
#[derive(Clone, Debug)]
pub struct Wind {
    params: WindParams,
    turbulence: Option<Dryden>,
    /// Unit vectors of the wind axes u, v, w in the world frame.
    axes: [[f64; 3]; 3],
}

impl Wind {
    /// The wind for steps of `dt` (s), turbulence seeded by `seed` (streams
    /// [`WIND_TURBULENCE_STREAMS`]), airspeed `max(‖mean‖, airspeed_floor)`.
    /// Rejects parameters [`WindParams::check`] rejects and `dt` outside `(0, 10]` s.
    pub fn new(params: WindParams, dt: f64, seed: u64) -> Result<Self, GainError> {
        params.check()?;
        let params = params.resolved();
        if !(dt > 0.0 && dt <= 10.0) {
            return Err(GainError { field: "dt", value: dt, expected: "0 < dt <= 10 s" });
        }
        let [mx, my, mz] = params.mean;
        let horizontal = ftsmc_core::math::hypot(mx, my);
        let e_u = if horizontal > 1e-9 { [mx / horizontal, my / horizontal, 0.0] } else { [1.0, 0.0, 0.0] };
        let axes = [e_u, [-e_u[1], e_u[0], 0.0], [0.0, 0.0, 1.0]];
        let speed = (horizontal * horizontal + mz * mz).sqrt();
        let turbulence = params.turbulence.map(|t| Dryden::new(t, dt, speed, seed));
        Ok(Self { params, turbulence, axes })
    }

    /// From now on the turbulence draws from the streams of `seed`
    /// ([`Dryden::reseed_noise`]); the mean wind and gusts are deterministic.
    pub fn reseed_noise(&mut self, seed: u64) {
        if let Some(d) = &mut self.turbulence {
            d.reseed_noise(seed);
        }
    }

    /// Set the airspeed of the turbulence's spatial-to-temporal conversion
    /// (m/s; the floor applies). No effect without turbulence.
    pub fn set_airspeed(&mut self, airspeed: f64) {
        if let Some(d) = &mut self.turbulence {
            d.set_airspeed(airspeed);
        }
    }

    /// The turbulence generator, if turbulence is on.
    pub fn turbulence(&self) -> Option<&Dryden> {
        self.turbulence.as_ref()
    }

    /// Unit vectors of the turbulence axes `u`, `v`, `w` in the world frame.
    pub fn axes(&self) -> [[f64; 3]; 3] {
        self.axes
    }

    /// The parameters.
    pub fn params(&self) -> &WindParams {
        &self.params
    }

    /// World wind velocity (m/s) at `t` (s): mean + gusts at `t` + the
    /// current turbulence sample, which then advances by one step `dt`.
    /// Call once per step, at `t = t₀ + k dt`; deterministic per seed.
    #[inline]
    pub fn step(&mut self, t: f64) -> [f64; 3] {
        let mut v = self.params.deterministic(t);
        if let Some(d) = &mut self.turbulence {
            let uvw = d.step();
            for (axis, c) in self.axes.iter().zip(uvw) {
                for i in 0..3 {
                    v[i] += c * axis[i];
                }
            }
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The paired `v`, `w` step is each filter's own step
    /// `z₁ ← Φ₁₁ z₁ + Φ₁₂ z₂ + L₁₁ n₁`, `z₂ ← Φ₂₁ z₁ + Φ₂₂ z₂ + L₂₁ n₁ + L₂₂ n₂`
    /// bit for bit, over airspeeds from the floor to a gale.
    #[test]
    fn paired_filters_step_as_each_filter_alone() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let scales = TurbulenceParams::moderate().scales();
        for airspeed in [0.5, 1.0, 14.8, 60.0] {
            let filters: [SecondOrder; 2] =
                core::array::from_fn(|k| SecondOrder::new(scales.sigma[1 + k], airspeed / scales.length[1 + k], 1e-3));
            let pair = SecondOrderPair::new(&filters);
            let (mut z1, mut z2) = ([0.3, -1.2], [0.7, 0.05]);
            let mut alone = [[z1[0], z2[0]], [z1[1], z2[1]]];
            for _ in 0..2000 {
                let n1: [f64; 2] = core::array::from_fn(|_| rng.random_range(-4.0..4.0));
                let n2: [f64; 2] = core::array::from_fn(|_| rng.random_range(-4.0..4.0));
                pair.step(&mut z1, &mut z2, n1, n2);
                for (k, (f, z)) in filters.iter().zip(alone.iter_mut()).enumerate() {
                    let (p, l) = (f.phi, f.chol);
                    let [a, b] = *z;
                    z[0] = p[0][0] * a + p[0][1] * b + l[0][0] * n1[k];
                    z[1] = p[1][0] * a + p[1][1] * b + l[1][0] * n1[k] + l[1][1] * n2[k];
                    assert_eq!([z1[k].to_bits(), z2[k].to_bits()], [z[0].to_bits(), z[1].to_bits()]);
                }
            }
        }
    }

    #[test]
    fn rungs_in_words_give_the_mean_wind_beaufort_force_and_mil_turbulence_from_the_parameters() {
        // MIL-F-8785C / MIL-HDBK-1797: light, moderate, severe are W20 = 15, 30, 45 kt at 20 ft.
        assert!((Intensity::Light.w20() / KNOT - 15.0).abs() < 1e-12);
        assert!((Intensity::Moderate.w20() / KNOT - 30.0).abs() < 1e-12);
        assert!((Intensity::Severe.w20() / KNOT - 45.0).abs() < 1e-12);
        assert!((mean_wind_at(WindPreset::Light.w20(), 20.0 * FOOT) - 15.0 * KNOT).abs() < 1e-12);
        let words = |preset| WindParams { preset: Some(preset), ..Default::default() }.in_words();
        assert_eq!(words(WindPreset::Calm), "still air (no mean wind, no turbulence)");
        assert_eq!(
            words(WindPreset::Breeze),
            "2.5 m/s mean wind at 5 m (Beaufort 2, light breeze), turbulence below MIL-F-8785C light \
             (W₂₀ 5 kt against 15 kt, σ_u 0.50 m/s)"
        );
        assert_eq!(
            words(WindPreset::Light),
            "7.4 m/s mean wind at 5 m (Beaufort 5, fresh breeze), light turbulence (MIL-F-8785C, W₂₀ 15 kt, σ_u 1.50 m/s)"
        );
        assert_eq!(
            words(WindPreset::Moderate),
            "14.8 m/s mean wind at 5 m (Beaufort 7, near gale), moderate turbulence (MIL-F-8785C, W₂₀ 30 kt, σ_u 3.00 m/s)"
        );
        // The words follow the parameters, not the preset's name.
        let faster = WindParams { preset: Some(WindPreset::Light), speed: Some(12.0), ..Default::default() };
        assert!(
            faster.in_words().starts_with("12.0 m/s mean wind at 5 m (Beaufort 6, strong breeze)"),
            "{}",
            faster.in_words()
        );
        let gusty = WindParams { mean: [3.0, 4.0, 0.0], ..Default::default() };
        assert_eq!(gusty.in_words(), "5.0 m/s mean wind, no turbulence");
        let light = WindParams { preset: Some(WindPreset::Light), ..Default::default() };
        assert_eq!(light.in_short_words(), "7.4 m/s mean wind at 5 m, light turbulence");
        assert_eq!(WindParams::default().in_short_words(), "still air");
    }

    #[test]
    fn beaufort_places_a_speed_by_the_wmo_table_rounded_to_a_tenth() {
        assert_eq!(beaufort(0.0), (0, "calm"));
        assert_eq!(beaufort(0.24), (0, "calm"));
        assert_eq!(beaufort(0.26), (1, "light air"));
        assert_eq!(beaufort(1.54), (1, "light air"));
        assert_eq!(beaufort(1.56), (2, "light breeze"));
        assert_eq!(beaufort(7.9), (4, "moderate breeze"));
        assert_eq!(beaufort(8.0), (5, "fresh breeze"));
        assert_eq!(beaufort(32.7), (12, "hurricane force"));
        assert_eq!(beaufort(-1.0), (0, "calm"));
        assert_eq!(beaufort(f64::NAN), (0, "calm"));
        assert!(BEAUFORT.windows(2).all(|w| w[0].0 + 1 == w[1].0 && w[0].2 < w[1].2));
    }
}
