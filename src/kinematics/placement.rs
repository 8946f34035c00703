//! A rigid placement written the way engineers write it: a position and roll/pitch/yaw.

use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Vector3};
use serde::{Deserialize, Serialize};

/// Position and orientation of a body or of the robot base. The rotation is roll about x, then
/// pitch about y, then yaw about z, all about the fixed axes (`R = Rz(yaw)·Ry(pitch)·Rx(roll)`),
/// the same convention as URDF's `rpy`.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Placement {
    /// Position in metres.
    #[serde(default, deserialize_with = "crate::limits::exact::array")]
    pub position: [f64; 3],
    /// Roll, pitch, yaw in radians.
    #[serde(default, deserialize_with = "crate::limits::exact::array")]
    pub rpy: [f64; 3],
}

impl Placement {
    /// The placement as a rigid transform.
    pub fn isometry(&self) -> IsometryMatrix3<f64> {
        let [r, p, y] = self.rpy;
        IsometryMatrix3::from_parts(
            Translation3::from(Vector3::from(self.position)),
            Rotation3::from_euler_angles(r, p, y),
        )
    }

    /// True when every number is finite.
    pub fn is_finite(&self) -> bool {
        self.position.iter().chain(&self.rpy).all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn rpy_is_fixed_axis_roll_pitch_yaw() {
        let p = Placement {
            position: [1.0, 2.0, 3.0],
            rpy: [0.1, 0.2, 0.3],
        };
        let expected = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), 0.2)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), 0.1);
        assert_relative_eq!(p.isometry().rotation, expected, epsilon = 1e-15);
        assert_relative_eq!(p.isometry().translation.vector, Vector3::new(1.0, 2.0, 3.0));
    }
}
