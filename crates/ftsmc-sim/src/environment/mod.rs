//! Plant-side variations evaluated in time — payload, inertia variation,
//! drag noise and disturbances — built from their own parameter sections
//! ([`EnvironmentParams`]). The controller never sees these.

mod disturbance;
pub mod ground;
mod payload;
mod phasors;
mod variation;
pub mod wind;

pub use disturbance::DisturbanceSignals;
pub use payload::Payload;
pub use variation::DragNoise;

use crate::rng::chacha_stream;
use ftsmc_core::model::QuadrotorParams;

use crate::noise::NoiseStream;
use crate::signal::grid::GridSignal;
use crate::signal::Signal;

/// The environment's parameter sections (borrowed from wherever they are
/// held, e.g. [`crate::scenario::Scenario::environment`]).
#[derive(Clone, Copy, Debug)]
pub struct EnvironmentParams<'a> {
    /// The true plant before variations (the scenario's true vehicle in
    /// paper form: `[plant]` with the keys `[vehicle]` gives,
    /// or its `plant` when the controller's model is exact).
    pub plant: QuadrotorParams,
    /// Payload profile, if any.
    pub payload: Option<&'a Payload>,
    /// Relative inertia variation `ΔI/I`(t), if any.
    pub inertia_variation: Option<&'a Signal>,
    /// Drag noise, if any.
    pub drag_noise: Option<DragNoise>,
    /// Disturbances `D_x … D_ψ`.
    pub disturbance: &'a DisturbanceSignals,
    /// Seed of the drag-noise streams.
    pub seed: u64,
}

/// Plant-side variations of a scenario evaluated in time: payload, inertia
/// variation, drag noise and disturbances. The controller never sees these.
pub struct Environment {
    params: Sections,
    /// One noise stream per drag coefficient, read a block ahead
    /// ([`NoiseStream`]: the generator's own draws, fewer instructions each).
    drag_rngs: Option<[NoiseStream; 6]>,
    drag_factor: [f64; 6],
    grid: Option<Grid>,
}

/// The environment's sections, owned (copied from [`EnvironmentParams`]
/// once per flight), so a flight owns what it samples.
struct Sections {
    plant: QuadrotorParams,
    payload: Option<Payload>,
    inertia_variation: Option<Signal>,
    drag_noise: Option<DragNoise>,
    disturbance: DisturbanceSignals,
}

/// The environment's signals prepared for the run loop's time grid
/// ([`Environment::on_grid`]).
struct Grid {
    disturbance: [GridSignal; 6],
    inertia_variation: Option<GridSignal>,
    /// The window all seven signals have (`Some(None)`: none has one;
    /// `None`: their windows differ), tested once per sample.
    shared_window: Option<Option<[f64; 2]>>,
    /// The signals' sinusoids side by side (the six disturbances, then the
    /// inertia variation if any), when they are made of nothing else: the
    /// grid signals' bits in one pass ([`phasors`]).
    bank: Option<phasors::PhasorBank>,
}

impl Environment {
    /// Drag noise streams are derived from `params.seed`: stream `k` for
    /// coefficient `k` (K_f1x, K_f1y, K_f1z, K_f2x, K_f2y, K_f2z).
    pub fn new(params: EnvironmentParams<'_>) -> Self {
        let drag_rngs = params
            .drag_noise
            .map(|_| core::array::from_fn(|k| NoiseStream::new(chacha_stream(params.seed, 1 + k as u64))));
        let params = Sections {
            plant: params.plant,
            payload: params.payload.copied(),
            inertia_variation: params.inertia_variation.cloned(),
            drag_noise: params.drag_noise,
            disturbance: params.disturbance.clone(),
        };
        Self { params, drag_rngs, drag_factor: [1.0; 6], grid: None }
    }

    /// From now on the drag noise draws from the streams of `seed` (stream
    /// `1 + k` for coefficient `k`, as [`Environment::new`]), each at its
    /// first word; the current drag multipliers are kept (a flight branched
    /// with fresh noise, `falsify::splitting`). Nothing without drag noise.
    pub fn reseed_noise(&mut self, seed: u64) {
        if let Some(rngs) = &mut self.drag_rngs {
            *rngs = core::array::from_fn(|k| NoiseStream::new(chacha_stream(seed, 1 + k as u64)));
        }
    }

    /// The same environment sampled by [`Environment::time_varying_on_grid`]
    /// on the grid `t_m = m·step` (s): the run loop's substep boundaries.
    /// Its sines and cosines are rotated along the grid
    /// ([`crate::signal::grid`]), equal to [`Environment::time_varying`]'s
    /// to rounding.
    pub fn on_grid(mut self, step: f64) -> Self {
        let d = &self.params.disturbance;
        let g = |s: &Signal| GridSignal::new(s, step);
        let disturbance = [g(&d.x), g(&d.y), g(&d.z), g(&d.phi), g(&d.theta), g(&d.psi)];
        let inertia_variation = self.params.inertia_variation.as_ref().map(g);
        let mut windows = disturbance.iter().chain(&inertia_variation).map(GridSignal::window);
        let first = windows.next().flatten();
        let same = |w: Option<[f64; 2]>| w.map(|w| w.map(f64::to_bits)) == first.map(|w| w.map(f64::to_bits));
        let shared_window = windows.all(same).then_some(first);
        let signals: Vec<&Signal> = [&d.x, &d.y, &d.z, &d.phi, &d.theta, &d.psi]
            .into_iter()
            .chain(self.params.inertia_variation.as_ref())
            .collect();
        let bank = phasors::PhasorBank::new(&signals, step);
        self.grid = Some(Grid { disturbance, inertia_variation, shared_window, bank });
        self
    }

    /// Draw the drag multipliers for the next control period (nothing
    /// without drag noise: the loop calls it every period).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn next_period(&mut self) {
        if self.drag_rngs.is_some() {
            self.draw_drag_factors();
        }
    }

    /// [`Environment::next_period`]'s draws.
    #[inline(never)]
    fn draw_drag_factors(&mut self) {
        if let (Some(rngs), Some(noise)) = (&mut self.drag_rngs, self.params.drag_noise) {
            for (factor, rng) in self.drag_factor.iter_mut().zip(rngs.iter_mut()) {
                let w = rng.normal();
                *factor = (1.0 + noise.std * w).max(0.0);
            }
        }
    }

    /// Drag multipliers of the current period.
    pub fn drag_factor(&self) -> [f64; 6] {
        self.drag_factor
    }

    /// The smooth time-varying plant inputs at `t` (s): true mass, inertia
    /// and disturbances (drag noise is per control period and kept apart).
    #[cfg_attr(not(debug_assertions), inline(always))] // the loop calls it every substep; LLVM's heuristics left it out of line
    pub fn time_varying(&self, t: f64) -> TimeVarying {
        let variation = self.params.inertia_variation.as_ref().map(|var| var.value(t));
        self.time_varying_from(t, variation, self.params.disturbance.at(t))
    }

    /// The time-varying inputs at `t` (s) from the values of the inertia
    /// variation (relative, when there is one) and of the disturbances: the
    /// true mass (with the payload at `t`) and the inertia scaled by
    /// `1 + variation`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn time_varying_from(&self, t: f64, variation: Option<f64>, disturbance: [f64; 6]) -> TimeVarying {
        let base = self.params.plant;
        let mut mass = base.mass;
        if let Some(payload) = &self.params.payload {
            mass += payload.added_mass(t);
        }
        let mut inertia = base.inertia;
        if let Some(v) = variation {
            let scale = 1.0 + v;
            for i in &mut inertia {
                *i *= scale;
            }
        }
        TimeVarying { mass, inertia, disturbance }
    }

    /// [`Environment::time_varying`] at grid point `m` of
    /// [`Environment::on_grid`], whose time the caller computed as `t` (s):
    /// the payload, the windows and the non-sinusoid terms at `t`, the
    /// sinusoids rotated to `m`. Without a grid, `time_varying(t)`.
    #[cfg_attr(not(debug_assertions), inline(always))] // the loop calls it every substep
    pub fn time_varying_on_grid(&mut self, m: u64, t: f64) -> TimeVarying {
        let Some(grid) = self.grid.as_mut() else {
            return self.time_varying(t);
        };
        let (variation, disturbance) = match grid.shared_window {
            // One window for all: outside, every value is 0 (as each signal's own test gives).
            Some(Some([start, end])) if t < start || t > end => {
                (grid.inertia_variation.as_ref().map(|_| 0.0), [0.0; 6])
            }
            _ if grid.bank.is_some() => {
                let mut v = [0.0; 7];
                if let Some(bank) = grid.bank.as_mut() {
                    bank.values(m, t, &mut v);
                }
                // Inside a shared window every signal counts; without one,
                // each signal's own window (outside: 0, as its own test gives).
                let shared = grid.shared_window.is_some();
                let inside = |s: &GridSignal| shared || !s.outside(t);
                let mut disturbance = [0.0; 6];
                for (k, s) in grid.disturbance.iter().enumerate() {
                    if inside(s) {
                        disturbance[k] = v[k];
                    }
                }
                let variation = grid.inertia_variation.as_ref().map(|s| if inside(s) { v[6] } else { 0.0 });
                (variation, disturbance)
            }
            Some(_) => {
                let variation = grid.inertia_variation.as_mut().map(|var| var.value_inside(m, t));
                let [x, y, z, phi, theta, psi] = &mut grid.disturbance;
                let disturbance = [
                    x.value_inside(m, t),
                    y.value_inside(m, t),
                    z.value_inside(m, t),
                    phi.value_inside(m, t),
                    theta.value_inside(m, t),
                    psi.value_inside(m, t),
                ];
                (variation, disturbance)
            }
            None => {
                let variation = grid.inertia_variation.as_mut().map(|var| var.value(m, t));
                let [x, y, z, phi, theta, psi] = &mut grid.disturbance;
                let disturbance =
                    [x.value(m, t), y.value(m, t), z.value(m, t), phi.value(m, t), theta.value(m, t), psi.value(m, t)];
                (variation, disturbance)
            }
        };
        self.time_varying_from(t, variation, disturbance)
    }

    /// Plant parameters for given time-varying inputs and the current
    /// period's drag noise (without drag noise every multiplier is 1 and
    /// the coefficients are the plant's: `x · 1 = x` exactly, not formed).
    #[inline]
    pub fn params_with(&self, tv: &TimeVarying) -> QuadrotorParams {
        let mut p = self.params.plant;
        p.mass = tv.mass;
        p.inertia = tv.inertia;
        if self.drag_rngs.is_some() {
            for i in 0..3 {
                p.drag_translational[i] *= self.drag_factor[i];
                p.drag_rotational[i] *= self.drag_factor[3 + i];
            }
        }
        p
    }

    /// Plant parameters at time `t` (s).
    #[inline]
    pub fn params(&self, t: f64) -> QuadrotorParams {
        self.params_with(&self.time_varying(t))
    }

    /// Disturbances `[D_x … D_ψ]` at `t`.
    #[inline]
    pub fn disturbance(&self, t: f64) -> [f64; 6] {
        self.params.disturbance.at(t)
    }
}

/// Mass (kg), inertia (kg·m²) and disturbances (m/s², rad/s²) at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimeVarying {
    /// True mass, kg.
    pub mass: f64,
    /// True `[I1, I2, I3]`, kg·m².
    pub inertia: [f64; 3],
    /// `[D_x, D_y, D_z, D_φ, D_θ, D_ψ]`.
    pub disturbance: [f64; 6],
}

impl TimeVarying {
    /// Linear interpolation `a + w (b − a)`.
    #[inline]
    pub fn lerp(a: &Self, b: &Self, w: f64) -> Self {
        let l = |x: f64, y: f64| x + w * (y - x);
        Self {
            mass: l(a.mass, b.mass),
            inertia: core::array::from_fn(|i| l(a.inertia[i], b.inertia[i])),
            disturbance: core::array::from_fn(|i| l(a.disturbance[i], b.disturbance[i])),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::Term;

    fn sine(amplitude: f64, omega: f64, window: Option<[f64; 2]>) -> Signal {
        Signal { terms: vec![Term::Sine { amplitude, omega: Some(omega), frequency: None, phase: 0.3 }], window }
    }

    /// With one window for all seven signals (tested once) or with
    /// different ones (each its own), the grid's time-varying inputs have
    /// the bits of every signal's own [`GridSignal::value`]: with a
    /// polynomial among them (the grid signals) and with sinusoids and
    /// constants only (the phasor bank).
    #[test]
    fn a_shared_window_gives_the_bits_of_every_signals_own_window() {
        let payload = Payload { mass: 0.37, start: 1.0, decay_start: Some(2.0), tau: Some(3.0) };
        let polynomial = vec![Term::Constant { value: 0.1 }, Term::Polynomial { coefficients: vec![0.0, 0.2] }];
        let sinusoids = vec![
            Term::Constant { value: 0.1 },
            Term::Cosine { amplitude: 0.2, omega: None, frequency: Some(1.5), phase: -0.4 },
            Term::Sine { amplitude: -0.3, omega: Some(2.2), frequency: None, phase: 0.0 },
        ];
        let windows_list =
            [[Some([1.0, 2.0]); 7], [None; 7], [Some([1.0, 2.0]), None, None, None, None, None, Some([0.5, 1.5])]];
        for (windows, y_terms) in windows_list.iter().flat_map(|w| [(*w, polynomial.clone()), (*w, sinusoids.clone())])
        {
            let banked = y_terms.len() == 3;
            let [wx, wy, wz, wphi, wtheta, wpsi, wvar] = windows;
            let disturbance = DisturbanceSignals {
                x: sine(0.5, 0.4, wx),
                y: Signal { terms: y_terms, window: wy },
                z: sine(0.7, 0.3, wz),
                phi: sine(0.5, 0.4, wphi),
                theta: sine(-0.5, 0.5, wtheta),
                psi: sine(0.5, 0.7, wpsi),
            };
            let variation = sine(0.15, 3.1, wvar);
            let params = EnvironmentParams {
                plant: QuadrotorParams::default(),
                payload: Some(&payload),
                inertia_variation: Some(&variation),
                drag_noise: None,
                disturbance: &disturbance,
                seed: 7,
            };
            let step = 2.5e-4;
            let mut env = Environment::new(params).on_grid(step);
            assert_eq!(env.grid.as_ref().is_some_and(|g| g.bank.is_some()), banked);
            let d = &disturbance;
            let mut own = [&d.x, &d.y, &d.z, &d.phi, &d.theta, &d.psi, &variation].map(|s| GridSignal::new(s, step));
            for m in 0..12_000u64 {
                let t = m as f64 * step;
                let tv = env.time_varying_on_grid(m, t);
                let values: [f64; 7] = core::array::from_fn(|i| own[i].value(m, t));
                let expected = env.time_varying_from(t, Some(values[6]), values[..6].try_into().unwrap());
                let bits = |tv: &TimeVarying| {
                    let mut b = vec![tv.mass.to_bits()];
                    b.extend(tv.inertia.iter().chain(&tv.disturbance).map(|v| v.to_bits()));
                    b
                };
                assert_eq!(bits(&tv), bits(&expected), "windows {windows:?}, t = {t}");
            }
        }
    }
}
