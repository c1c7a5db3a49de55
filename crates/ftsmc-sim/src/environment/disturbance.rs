//! External disturbances `D_x … D_ψ` of Eq. 1 as time signals.

use serde::{Deserialize, Serialize};

use crate::signal::Signal;

/// External disturbances `D_x … D_ψ` of Eq. 1 as accelerations (m/s², rad/s²).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct DisturbanceSignals {
    /// D_x, m/s².
    pub x: Signal,
    /// D_y, m/s².
    pub y: Signal,
    /// D_z, m/s².
    pub z: Signal,
    /// D_φ, rad/s².
    pub phi: Signal,
    /// D_θ, rad/s².
    pub theta: Signal,
    /// D_ψ, rad/s².
    pub psi: Signal,
}

impl DisturbanceSignals {
    /// `[D_x, D_y, D_z, D_φ, D_θ, D_ψ]` at `t`.
    pub fn at(&self, t: f64) -> [f64; 6] {
        [self.x.value(t), self.y.value(t), self.z.value(t), self.phi.value(t), self.theta.value(t), self.psi.value(t)]
    }

    /// `[D_x, D_y, D_z, D_φ, D_θ, D_ψ]` to change in place.
    pub fn signals_mut(&mut self) -> [&mut Signal; 6] {
        [&mut self.x, &mut self.y, &mut self.z, &mut self.phi, &mut self.theta, &mut self.psi]
    }

    /// With their names.
    pub fn named(&self) -> [(&'static str, &Signal); 6] {
        [("x", &self.x), ("y", &self.y), ("z", &self.z), ("phi", &self.phi), ("theta", &self.theta), ("psi", &self.psi)]
    }
}
