//! Orientation constraints a chain can never meet, whatever its joint values: proven from the
//! directions of its revolute axes, so that the planner does not wait for such a task and the
//! report can say why it is unreached.

use crate::kinematics::Chain;
use crate::world::task::angle_between;
use crate::world::TaskOrientation;
use nalgebra::{Rotation3, Unit, Vector3};

/// Samples of the rotation angle about a common joint axis in the pose test of
/// [`impossible_orientation`].
const POSE_SAMPLES: usize = 720;

/// Why no configuration of `chain` can satisfy `orientation`, when that is certain; `None`
/// when it may be satisfiable. The argument, independent of the axis ranges (so a `None`
/// promises nothing):
///
/// - without revolute joints the TCP rotation is the same in every configuration, so the
///   constraint holds everywhere or nowhere;
/// - when every revolute axis is parallel to one direction `n` (a planar arm), the TCP rotation
///   is `Rot(n, θ)·R_home` for some `θ` (rotations about `n` keep `n`, translations rotate
///   nothing). For an approach cone the tool's z axis then keeps its angle `β` to `n`, and a
///   cone of half-angle `tol` about `d` is met only if `|β − ∠(d, n)| ≤ tol`. For a pose, the
///   error over `θ` is sampled at `POSE_SAMPLES` angles; it changes by at most `|Δθ|` between
///   samples, so a sampled minimum above `tol + Δθ/2` proves it.
pub fn impossible_orientation(chain: &Chain, orientation: &TaskOrientation) -> Option<String> {
    if orientation.is_free() {
        return None;
    }
    let tol = orientation.tolerance();
    let home = chain.home();
    let mut frames = chain.frames();
    chain.fk(home, &mut frames);
    let r0 = *frames.tcp_rotation();
    let mut ang = vec![0.0; 3 * chain.dof()];
    chain.angular_jacobian(&frames, &mut ang);
    let axes: Vec<Vector3<f64>> = ang
        .chunks_exact(3)
        .map(|c| Vector3::new(c[0], c[1], c[2]))
        .filter(|w| w.norm() > 0.5)
        .collect();
    let deg = f64::to_degrees;
    let what = match orientation {
        TaskOrientation::Approach { .. } => "approach",
        _ => "orientation",
    };
    let Some(n) = axes.first().copied() else {
        let e = orientation.error(&r0);
        return (e > tol).then(|| {
            format!(
                "the design has no revolute joint, so the tool orientation never changes: it is \
                 {:.1}° from the task's {what}, beyond the tolerance of {:.1}°",
                deg(e),
                deg(tol)
            )
        });
    };
    if axes.iter().any(|w| w.cross(&n).norm() > 1e-9) {
        return None;
    }
    let n = Unit::new_normalize(n);
    let axis_text = format!("[{:.3}, {:.3}, {:.3}]", n.x, n.y, n.z);
    match orientation {
        TaskOrientation::Approach { axis, .. } => {
            let beta = angle_between(&r0.column(2).into_owned(), n.as_ref());
            let want = angle_between(axis.as_ref(), n.as_ref());
            let gap = (beta - want).abs();
            (gap > tol).then(|| {
                format!(
                    "every joint axis of the design is parallel to {axis_text} (a planar arm): \
                     its tool z axis stays at {:.1}° to that axis, the approach direction is at \
                     {:.1}°, {:.1}° more than the cone's {:.1}° allow",
                    deg(beta),
                    deg(want),
                    deg(gap - tol),
                    deg(tol)
                )
            })
        }
        TaskOrientation::Pose { .. } => {
            let step = std::f64::consts::TAU / POSE_SAMPLES as f64;
            let best = (0..POSE_SAMPLES)
                .map(|k| {
                    let r = Rotation3::from_axis_angle(&n, k as f64 * step).matrix() * r0;
                    orientation.error(&r)
                })
                .fold(f64::INFINITY, f64::min);
            (best - 0.5 * step > tol).then(|| {
                format!(
                    "every joint axis of the design is parallel to {axis_text} (a planar arm): \
                     the tool can only turn about that axis, which leaves it at least {:.1}° \
                     from the task's orientation, beyond the tolerance of {:.1}°",
                    deg(best - 0.5 * step),
                    deg(tol)
                )
            })
        }
        TaskOrientation::Free => None,
    }
}
