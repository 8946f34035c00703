//! The collision boundary: conversions between the kinematics types (nalgebra) and parry's
//! glam types. Every such conversion in the crate goes through here.

use nalgebra::{Isometry3, IsometryMatrix3, Point3, UnitQuaternion};
use parry3d_f64::math::{Pose, Vector};

/// A nalgebra point as a parry vector.
#[inline]
pub fn to_parry_point(p: &Point3<f64>) -> Vector {
    Vector::new(p.x, p.y, p.z)
}

/// A parry vector as a nalgebra point.
#[inline]
pub fn from_parry_point(v: Vector) -> Point3<f64> {
    Point3::new(v.x, v.y, v.z)
}

/// A nalgebra rigid transform (rotation matrix form) as a parry pose.
pub fn to_parry_pose(iso: &IsometryMatrix3<f64>) -> Pose {
    let q = UnitQuaternion::from_rotation_matrix(&iso.rotation);
    Isometry3::from_parts(iso.translation, q).into()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Rotation3, Translation3, Vector3};

    #[test]
    fn pose_conversion_transforms_points_identically() {
        let iso = IsometryMatrix3::from_parts(
            Translation3::new(0.3, -1.0, 2.0),
            Rotation3::from_euler_angles(0.4, -1.2, 2.5),
        );
        let pose = to_parry_pose(&iso);
        let p = Point3::new(0.7, 0.1, -0.4);
        let q = from_parry_point(pose.transform_point(to_parry_point(&p)));
        assert_relative_eq!(q, iso * p, epsilon = 1e-12);
        let _ = Vector3::<f64>::zeros();
    }
}
