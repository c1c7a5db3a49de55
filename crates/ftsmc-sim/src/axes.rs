//! Per-axis containers: [`AxisSet`], one value per controlled channel.

use serde::{Deserialize, Serialize};

/// One value per controlled channel `x, y, z, φ, θ, ψ`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AxisSet<T> {
    /// x channel.
    pub x: T,
    /// y channel.
    pub y: T,
    /// z channel.
    pub z: T,
    /// Roll φ channel.
    pub phi: T,
    /// Pitch θ channel.
    pub theta: T,
    /// Yaw ψ channel.
    pub psi: T,
}

impl<T> AxisSet<T> {
    /// `[x, y, z, φ, θ, ψ]` with their names.
    pub fn named(&self) -> [(&'static str, &T); 6] {
        [("x", &self.x), ("y", &self.y), ("z", &self.z), ("phi", &self.phi), ("theta", &self.theta), ("psi", &self.psi)]
    }

    /// The value of channel `axis` (`"x"`, `"y"`, `"z"`, `"phi"`, `"theta"`, `"psi"`).
    pub fn get(&self, axis: &str) -> Option<&T> {
        self.named().into_iter().find(|(n, _)| *n == axis).map(|(_, v)| v)
    }

    /// Same position gains on x, y, z and attitude gains on φ, θ, ψ.
    pub fn split(position: T, attitude: T) -> Self
    where
        T: Clone,
    {
        Self {
            x: position.clone(),
            y: position.clone(),
            z: position,
            phi: attitude.clone(),
            theta: attitude.clone(),
            psi: attitude,
        }
    }

    /// Apply `f` to the channels `axes` (indices 0..6 = x, y, z, φ, θ, ψ;
    /// 5 and above mean ψ).
    pub fn each_mut(&mut self, axes: &[usize], f: impl Fn(&mut T)) {
        for &axis in axes {
            f(match axis {
                0 => &mut self.x,
                1 => &mut self.y,
                2 => &mut self.z,
                3 => &mut self.phi,
                4 => &mut self.theta,
                _ => &mut self.psi,
            });
        }
    }

    /// As an array `[x, y, z, φ, θ, ψ]`.
    pub fn to_array(&self) -> [T; 6]
    where
        T: Clone,
    {
        [self.x.clone(), self.y.clone(), self.z.clone(), self.phi.clone(), self.theta.clone(), self.psi.clone()]
    }
}

impl<T: Default> Default for AxisSet<T> {
    fn default() -> Self {
        Self {
            x: T::default(),
            y: T::default(),
            z: T::default(),
            phi: T::default(),
            theta: T::default(),
            psi: T::default(),
        }
    }
}
