//! What a task asks of the tool besides its position: nothing (a point task), a full
//! orientation within a tolerance, or an approach direction of the tool's z axis within a cone.

use nalgebra::{Matrix3, Rotation3, Unit, UnitQuaternion, Vector3};

/// The orientation constraint of one task, on the rotation `R` of the tool centre point (TCP)
/// frame in the world.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum TaskOrientation {
    /// A point task: any orientation.
    #[default]
    Free,
    /// A full pose: the angle of `R_targetᵀ·R` (the rotation that takes the target frame onto
    /// the tool frame) is at most `tolerance` radians.
    Pose {
        /// The target rotation of the TCP frame in the world.
        rotation: Rotation3<f64>,
        /// Largest rotation angle (radians) between the tool and the target, in `[0, π]`.
        tolerance: f64,
    },
    /// An approach cone: the tool's z axis `R·ẑ` lies within `tolerance` radians of `axis`;
    /// the rotation about it is free (drilling, welding, inspection).
    Approach {
        /// The direction the tool's z axis must point along (unit).
        axis: Unit<Vector3<f64>>,
        /// Cone half-angle (radians), in `[0, π]`.
        tolerance: f64,
    },
}

/// The angle (radians, in `[0, π]`) between unit vectors `u` and `v`, accurate near 0 and π.
pub fn angle_between(u: &Vector3<f64>, v: &Vector3<f64>) -> f64 {
    u.cross(v).norm().atan2(u.dot(v))
}

impl TaskOrientation {
    /// True for a point task.
    pub fn is_free(&self) -> bool {
        matches!(self, TaskOrientation::Free)
    }

    /// The tolerance in radians (π for a point task, which any orientation satisfies).
    pub fn tolerance(&self) -> f64 {
        match *self {
            TaskOrientation::Free => std::f64::consts::PI,
            TaskOrientation::Pose { tolerance, .. }
            | TaskOrientation::Approach { tolerance, .. } => tolerance,
        }
    }

    /// The orientation error (radians) of a tool frame with rotation `r`: for a pose, the
    /// rotation angle of `R_targetᵀ·R`; for an approach, the angle between `R·ẑ` and the
    /// approach axis; 0 for a point task.
    pub fn error(&self, r: &Matrix3<f64>) -> f64 {
        match *self {
            TaskOrientation::Free => 0.0,
            TaskOrientation::Pose { rotation, .. } => {
                let d = rotation.matrix().transpose() * r;
                UnitQuaternion::from_matrix(&d).angle()
            }
            TaskOrientation::Approach { axis, .. } => {
                angle_between(&r.column(2).into_owned(), axis.as_ref())
            }
        }
    }

    /// True when a tool frame with rotation `r` satisfies the constraint (error within the
    /// tolerance).
    pub fn holds(&self, r: &Matrix3<f64>) -> bool {
        self.is_free() || self.error(r) <= self.tolerance()
    }

    /// The world-frame rotation error vector that inverse kinematics drives to zero for a tool
    /// frame with rotation `r`: the axis of the smallest rotation that brings the tool inside
    /// `margin × tolerance` of the target, scaled by the angle still to go (zero once inside).
    /// For a pose it is the axis–angle vector of `R_target·Rᵀ` shortened by that margin; for an
    /// approach the vector `(ẑ × a)/‖ẑ × a‖ · (θ − margin·tol)`, normal to the tool's z axis
    /// `ẑ` (rotation about `ẑ` is free). Zero for a point task.
    pub fn ik_error(&self, r: &Matrix3<f64>, margin: f64) -> Vector3<f64> {
        let shorten = |v: Vector3<f64>, angle: f64, tol: f64| {
            let keep = margin * tol;
            if angle <= keep || angle == 0.0 {
                Vector3::zeros()
            } else {
                v * ((angle - keep) / angle)
            }
        };
        match *self {
            TaskOrientation::Free => Vector3::zeros(),
            TaskOrientation::Pose {
                rotation,
                tolerance,
            } => {
                let d = UnitQuaternion::from_matrix(&(rotation.matrix() * r.transpose()));
                let v = d.scaled_axis();
                shorten(v, v.norm(), tolerance)
            }
            TaskOrientation::Approach { axis, tolerance } => {
                let z = r.column(2).into_owned();
                let c = z.cross(axis.as_ref());
                let s = c.norm();
                let angle = s.atan2(z.dot(axis.as_ref()));
                let dir = if s > 1e-12 {
                    c / s
                } else if angle < 1.0 {
                    return Vector3::zeros();
                } else {
                    // Opposite: any axis normal to z turns it toward the target.
                    let x = r.column(0).into_owned();
                    x / x.norm()
                };
                shorten(dir * angle, angle, tolerance)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn errors_are_angles() {
        let pose = TaskOrientation::Pose {
            rotation: Rotation3::from_euler_angles(0.1, 0.2, 0.3),
            tolerance: 0.1,
        };
        let r = Rotation3::from_euler_angles(0.1, 0.2, 0.3)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), 0.05);
        assert!((pose.error(r.matrix()) - 0.05).abs() < 1e-12);
        assert!(pose.holds(r.matrix()));
        let approach = TaskOrientation::Approach {
            axis: Vector3::x_axis(),
            tolerance: 0.2,
        };
        // The identity's z axis is 90° from x; rotating about z changes nothing.
        let id = Matrix3::identity();
        assert!((approach.error(&id) - FRAC_PI_2).abs() < 1e-15);
        let spun = Rotation3::from_axis_angle(&Vector3::z_axis(), 1.0);
        assert!((approach.error(spun.matrix()) - FRAC_PI_2).abs() < 1e-15);
        let down = Rotation3::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2 - 0.1);
        assert!((approach.error(down.matrix()) - 0.1).abs() < 1e-12);
        assert!(approach.holds(down.matrix()));
        assert!(!approach.holds(&id));
        assert_eq!(TaskOrientation::Free.error(&id), 0.0);
    }

    #[test]
    fn ik_error_turns_the_tool_toward_the_target() {
        let approach = TaskOrientation::Approach {
            axis: Vector3::x_axis(),
            tolerance: 0.2,
        };
        let id = Matrix3::identity();
        let e = approach.ik_error(&id, 0.5);
        // Rotating z toward x is a positive turn about y, by 90° less half the tolerance.
        assert!(
            (e - Vector3::new(0.0, FRAC_PI_2 - 0.1, 0.0)).norm() < 1e-12,
            "{e}"
        );
        let flipped = Rotation3::from_axis_angle(&Vector3::x_axis(), PI);
        let e = TaskOrientation::Approach {
            axis: Vector3::z_axis(),
            tolerance: 0.0,
        }
        .ik_error(flipped.matrix(), 0.5);
        assert!((e.norm() - PI).abs() < 1e-9 && e.z.abs() < 1e-12, "{e}");
        let pose = TaskOrientation::Pose {
            rotation: Rotation3::from_axis_angle(&Vector3::z_axis(), 0.4),
            tolerance: 0.2,
        };
        let e = pose.ik_error(&id, 0.5);
        assert!((e - Vector3::new(0.0, 0.0, 0.3)).norm() < 1e-12, "{e}");
        assert_eq!(pose.ik_error(&id, 2.0), Vector3::zeros());
    }
}
