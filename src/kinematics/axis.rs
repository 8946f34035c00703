//! The six actuation axes of a link (paper Eq. 2) and their ranges (paper Eq. 18).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// One of the six actuation axes applied after a link's fixed geometry, in the order of paper
/// Eq. 2: `Rx(φ)·Ry(γ)·Rz(ψ)·Trans(x, y, z)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// Rotation about local x (φ, roll).
    Rx,
    /// Rotation about local y (γ, pitch).
    Ry,
    /// Rotation about local z (ψ, yaw).
    Rz,
    /// Translation along local x.
    Tx,
    /// Translation along local y.
    Ty,
    /// Translation along local z.
    Tz,
}

impl Axis {
    /// All six axes in the order they are applied (paper Eq. 2).
    pub const ALL: [Axis; 6] = [Axis::Rx, Axis::Ry, Axis::Rz, Axis::Tx, Axis::Ty, Axis::Tz];

    /// Position of the axis in [`Axis::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// Short lowercase name used in files and joint names (`rx`, …, `tz`).
    pub fn name(self) -> &'static str {
        match self {
            Axis::Rx => "rx",
            Axis::Ry => "ry",
            Axis::Rz => "rz",
            Axis::Tx => "tx",
            Axis::Ty => "ty",
            Axis::Tz => "tz",
        }
    }

    /// Parses a short name (`rx` … `tz`).
    pub fn from_name(name: &str) -> Option<Axis> {
        Axis::ALL.into_iter().find(|a| a.name() == name)
    }

    /// True for the three rotations, false for the three translations.
    pub fn is_rotation(self) -> bool {
        matches!(self, Axis::Rx | Axis::Ry | Axis::Rz)
    }

    /// The unit direction of the axis in the link's local frame.
    pub fn direction(self) -> Vector3<f64> {
        match self {
            Axis::Rx | Axis::Tx => Vector3::x(),
            Axis::Ry | Axis::Ty => Vector3::y(),
            Axis::Rz | Axis::Tz => Vector3::z(),
        }
    }
}

impl std::fmt::Display for Axis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The closed interval `[min, max]` an axis may move in (paper Eq. 18). A zero-width range means
/// the axis is not a joint: it stays at `min` (usually 0) and is folded into the fixed geometry.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Range {
    /// Lower limit (radians for rotations, metres for translations).
    pub min: f64,
    /// Upper limit.
    pub max: f64,
}

impl Range {
    /// The empty range at zero: the axis is absent.
    pub const ZERO: Range = Range { min: 0.0, max: 0.0 };

    /// A range from its limits.
    pub fn new(min: f64, max: f64) -> Self {
        Range { min, max }
    }

    /// `max − min`.
    pub fn width(&self) -> f64 {
        self.max - self.min
    }

    /// True when the axis can move (`max > min`): it is a joint.
    pub fn is_joint(&self) -> bool {
        self.max > self.min
    }

    /// `v` clamped into the range.
    pub fn clamp(&self, v: f64) -> f64 {
        v.clamp(self.min, self.max)
    }

    /// The home value of the axis: 0 clamped into the range (paper §II-D puts home at `a_0 = 0`;
    /// where 0 lies outside `[min, max]` the nearest limit is used instead).
    pub fn home(&self) -> f64 {
        self.clamp(0.0)
    }

    /// True when `v` lies in the range (inclusive).
    pub fn contains(&self, v: f64) -> bool {
        v >= self.min && v <= self.max
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for a in Axis::ALL {
            assert_eq!(Axis::from_name(a.name()), Some(a));
            assert_eq!(Axis::ALL[a.index()], a);
        }
        assert_eq!(Axis::from_name("rw"), None);
    }

    #[test]
    fn home_is_zero_clamped_into_the_range() {
        assert_eq!(Range::new(-1.0, 1.0).home(), 0.0);
        assert_eq!(Range::new(0.2, 1.0).home(), 0.2);
        assert_eq!(Range::new(-1.0, -0.3).home(), -0.3);
        assert!(!Range::new(0.5, 0.5).is_joint());
        assert!(Range::new(0.5, 0.6).is_joint());
    }
}
