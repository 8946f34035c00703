//! Damped-least-squares inverse kinematics steps toward a task point, or a task point with an
//! orientation or approach cone, within the axis ranges.

use crate::kinematics::{Chain, Frames};
use crate::world::TaskOrientation;
use nalgebra::{Matrix3, Matrix6, Point3, Vector3, Vector6};

/// Reused buffers for [`dls`].
#[derive(Clone, Debug)]
pub struct IkWork {
    frames: Frames,
    jac: Vec<f64>,
    /// Angular Jacobian, for oriented targets.
    ang: Vec<f64>,
    /// The configuration after the last call.
    pub q: Vec<f64>,
    /// Per free axis, the change a step asks of it.
    step: Vec<f64>,
    /// Hold axes at a limit that a step pushes further out (`hold_saturated`); else the
    /// whole step is clamped into the ranges. Default false
    /// ([`crate::planning::PlannerConfig::ik_hold_limits`]).
    pub hold_limits: bool,
}

impl IkWork {
    /// Buffers sized for `chain`.
    pub fn new(chain: &Chain) -> Self {
        IkWork {
            frames: chain.frames(),
            jac: vec![0.0; 3 * chain.dof()],
            ang: vec![0.0; 3 * chain.dof()],
            q: vec![0.0; chain.dof()],
            step: vec![0.0; chain.dof()],
            hold_limits: false,
        }
    }
}

/// Damping `μ` of the least-squares steps (metres).
pub const DAMPING: f64 = 0.05;
/// Largest change of any axis in one step (radians or metres).
pub const MAX_STEP: f64 = 0.5;

/// Holds still the free axes that sit at a limit of their range and that `step` (per axis)
/// pushes further out: zeroes their three entries in each of `columns` (Jacobians, three values
/// per axis). True when there was one. Solving again without them lets the other axes make up
/// for them within the same step; leaving them in, the clamp into the ranges cuts every step
/// short and the error falls only by a constant factor per step.
fn hold_saturated(chain: &Chain, q: &[f64], step: &[f64], columns: &mut [&mut Vec<f64>]) -> bool {
    let mut any = false;
    for (k, ((q, d), axis)) in q.iter().zip(step).zip(chain.free_axes()).enumerate() {
        if (*d > 0.0 && *q >= axis.range.max) || (*d < 0.0 && *q <= axis.range.min) {
            for c in columns.iter_mut() {
                c[3 * k..3 * k + 3].fill(0.0);
            }
            any = true;
        }
    }
    any
}

/// Runs up to `steps` damped-least-squares iterations from `start` toward putting the end
/// effector on `target`: `Δa = Jᵀ(JJᵀ + μ²I)⁻¹ e`, `e = target − p_ee`, each step scaled so no
/// axis moves more than [`MAX_STEP`], and the result clamped into the axis ranges; with
/// `work.hold_limits`, an axis at a limit that the step would push further out is held still
/// and the step solved again without it (`hold_saturated`). Stops early
/// within `tolerance`. The configuration is left in `work.q`; returns the remaining distance.
pub fn dls(
    chain: &Chain,
    start: &[f64],
    target: &Point3<f64>,
    steps: usize,
    tolerance: f64,
    work: &mut IkWork,
) -> f64 {
    work.q.copy_from_slice(start);
    let mut err = f64::INFINITY;
    for _ in 0..=steps {
        chain.fk(&work.q, &mut work.frames);
        let e: Vector3<f64> = target - work.frames.end_effector();
        err = e.norm();
        if err <= tolerance || chain.dof() == 0 {
            break;
        }
        chain.jacobian(&work.frames, &mut work.jac);
        let solve = |jac: &[f64]| {
            let mut jjt = Matrix3::from_diagonal_element(DAMPING * DAMPING);
            for col in jac.chunks_exact(3) {
                let c = Vector3::new(col[0], col[1], col[2]);
                jjt += c * c.transpose();
            }
            jjt.try_inverse().map(|m| m * e)
        };
        let Some(mut y) = solve(&work.jac) else {
            break;
        };
        if work.hold_limits {
            for (d, col) in work.step.iter_mut().zip(work.jac.chunks_exact(3)) {
                *d = col[0] * y.x + col[1] * y.y + col[2] * y.z;
            }
            if hold_saturated(chain, &work.q, &work.step, &mut [&mut work.jac]) {
                let Some(held) = solve(&work.jac) else {
                    break;
                };
                y = held;
            }
        }
        let mut largest: f64 = 0.0;
        for col in work.jac.chunks_exact(3) {
            largest = largest.max((col[0] * y.x + col[1] * y.y + col[2] * y.z).abs());
        }
        let scale = if largest > MAX_STEP {
            MAX_STEP / largest
        } else {
            1.0
        };
        for ((q, col), axis) in work
            .q
            .iter_mut()
            .zip(work.jac.chunks_exact(3))
            .zip(chain.free_axes())
        {
            let d = scale * (col[0] * y.x + col[1] * y.y + col[2] * y.z);
            *q = axis.range.clamp(*q + d);
        }
    }
    err
}

/// Fraction of an orientation tolerance that [`dls_oriented`] aims inside: it stops turning the
/// tool once the orientation error is within `ORIENTATION_MARGIN × tolerance`, which leaves room
/// for the rest of the tolerance along a path.
pub const ORIENTATION_MARGIN: f64 = 0.5;

/// [`dls`] toward a task with an orientation constraint. The error stacks the position error
/// (metres) and `weight ×` the rotation error vector ([`TaskOrientation::ik_error`], radians, so
/// `weight` is in metres per radian: at `0.1`, 1 rad of orientation counts as much as 0.1 m):
/// `e = [p_target − p_tcp; w·e_R]`, `J = [J_p; w·J_ω]` (6 × dof), and each step is
/// `Δa = Jᵀ(JJᵀ + μ²I₆)⁻¹ e`, scaled so no axis moves more than [`MAX_STEP`] and clamped into the
/// ranges (with `work.hold_limits`, the axes at a limit that it pushes further out held still
/// as in [`dls`]). For an approach cone the angular rows are projected normal to the tool's z
/// axis, as rotation about it is free. Stops once the position is within `tolerance` and the
/// orientation within [`ORIENTATION_MARGIN`] of its tolerance. A point task
/// ([`TaskOrientation::Free`]) runs [`dls`] unchanged. Returns the remaining position distance
/// and orientation error (radians); the configuration is left in `work.q`. Allocation-free.
#[allow(clippy::too_many_arguments)]
pub fn dls_oriented(
    chain: &Chain,
    start: &[f64],
    target: &Point3<f64>,
    orientation: &TaskOrientation,
    weight: f64,
    steps: usize,
    tolerance: f64,
    work: &mut IkWork,
) -> (f64, f64) {
    if orientation.is_free() {
        return (dls(chain, start, target, steps, tolerance, work), 0.0);
    }
    work.q.copy_from_slice(start);
    let (mut err, mut angle) = (f64::INFINITY, f64::INFINITY);
    let approach = matches!(orientation, TaskOrientation::Approach { .. });
    for _ in 0..=steps {
        chain.fk(&work.q, &mut work.frames);
        let ep: Vector3<f64> = target - work.frames.end_effector();
        let r = *work.frames.tcp_rotation();
        err = ep.norm();
        angle = orientation.error(&r);
        let er = orientation.ik_error(&r, ORIENTATION_MARGIN);
        if (err <= tolerance && er == Vector3::zeros()) || chain.dof() == 0 {
            break;
        }
        chain.jacobian(&work.frames, &mut work.jac);
        chain.angular_jacobian(&work.frames, &mut work.ang);
        let z = r.column(2).into_owned();
        let project = |w: Vector3<f64>| if approach { w - z * z.dot(&w) } else { w };
        let column = |lin: &[f64], ang: &[f64]| {
            let w = project(Vector3::new(ang[0], ang[1], ang[2])) * weight;
            Vector6::new(lin[0], lin[1], lin[2], w.x, w.y, w.z)
        };
        let e = Vector6::new(
            ep.x,
            ep.y,
            ep.z,
            weight * er.x,
            weight * er.y,
            weight * er.z,
        );
        let solve = |jac: &[f64], ang: &[f64]| {
            let mut jjt = Matrix6::from_diagonal_element(DAMPING * DAMPING);
            for (lin, ang) in jac.chunks_exact(3).zip(ang.chunks_exact(3)) {
                let c = column(lin, ang);
                jjt += c * c.transpose();
            }
            jjt.cholesky().map(|c| c.solve(&e))
        };
        let Some(mut y) = solve(&work.jac, &work.ang) else {
            break;
        };
        if work.hold_limits {
            let columns = work.jac.chunks_exact(3).zip(work.ang.chunks_exact(3));
            for (d, (lin, ang)) in work.step.iter_mut().zip(columns) {
                *d = column(lin, ang).dot(&y);
            }
            let rows = &mut [&mut work.jac, &mut work.ang];
            if hold_saturated(chain, &work.q, &work.step, rows) {
                let Some(held) = solve(&work.jac, &work.ang) else {
                    break;
                };
                y = held;
            }
        }
        let mut largest: f64 = 0.0;
        for (lin, ang) in work.jac.chunks_exact(3).zip(work.ang.chunks_exact(3)) {
            largest = largest.max(column(lin, ang).dot(&y).abs());
        }
        let scale = if largest > MAX_STEP {
            MAX_STEP / largest
        } else {
            1.0
        };
        for ((q, (lin, ang)), axis) in work
            .q
            .iter_mut()
            .zip(work.jac.chunks_exact(3).zip(work.ang.chunks_exact(3)))
            .zip(chain.free_axes())
        {
            *q = axis.range.clamp(*q + scale * column(lin, ang).dot(&y));
        }
    }
    (err, angle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::{Axis, Dh, Link, Range};
    use nalgebra::IsometryMatrix3;

    fn planar(n: usize) -> Chain {
        let mut r = [Range::ZERO; 6];
        r[Axis::Rz.index()] = Range::new(-2.5, 2.5);
        let mut links = vec![Link::from_dh(&Dh::default(), r)];
        for _ in 0..n {
            links.push(Link::from_dh(
                &Dh {
                    a: 0.5,
                    ..Dh::default()
                },
                r,
            ));
        }
        Chain::new(IsometryMatrix3::identity(), &links, 0.01, 1)
    }

    /// An axis held at its limit leaves the others to make up for it in the same step: the
    /// error still falls quadratically. (Clamping the full step instead cuts every step short,
    /// and ten steps then leave the error far above the tolerance.)
    #[test]
    fn an_axis_at_its_limit_is_held_and_the_others_converge_fast() {
        let mut r = [Range::ZERO; 6];
        r[Axis::Rz.index()] = Range::new(-2.5, 2.5);
        let mut base = r;
        base[Axis::Rz.index()] = Range::new(-0.1, 0.1);
        let mut links = vec![Link::from_dh(&Dh::default(), base)];
        for _ in 0..3 {
            links.push(Link::from_dh(
                &Dh {
                    a: 0.5,
                    ..Dh::default()
                },
                r,
            ));
        }
        let chain = Chain::new(IsometryMatrix3::identity(), &links, 0.01, 1);
        let mut work = IkWork::new(&chain);
        work.hold_limits = true;
        let target = Point3::new(1.2 * 0.6f64.cos(), 1.2 * 0.6f64.sin(), 0.0);
        let err = dls(&chain, chain.home(), &target, 10, 1e-10, &mut work);
        assert!(err <= 1e-10, "{err}");
        assert!(chain.within_ranges(&work.q));
        // The paper planner's clamping (`hold_limits` false) is still far off after ten steps.
        work.hold_limits = false;
        let err = dls(&chain, chain.home(), &target, 10, 1e-10, &mut work);
        assert!(err > 1e-3, "{err}");
        assert!(chain.within_ranges(&work.q));
    }

    #[test]
    fn converges_to_a_reachable_point_within_ranges() {
        let chain = planar(3);
        let mut work = IkWork::new(&chain);
        let target = Point3::new(0.3, 0.9, 0.0);
        let err = dls(&chain, chain.home(), &target, 100, 1e-6, &mut work);
        assert!(err <= 1e-6, "{err}");
        assert!(chain.within_ranges(&work.q));
        assert!((chain.end_effector(&work.q) - target).norm() <= 1e-6);
    }

    #[test]
    fn a_planar_arm_meets_an_in_plane_approach() {
        let chain = planar(3);
        let mut work = IkWork::new(&chain);
        // The tool's z axis is the world z axis whatever the joints: an approach along x is
        // out of reach, one along z is met at once.
        let target = Point3::new(0.3, 0.9, 0.0);
        let cone = |axis: Vector3<f64>| TaskOrientation::Approach {
            axis: nalgebra::Unit::new_normalize(axis),
            tolerance: 0.2,
        };
        let (err, angle) = dls_oriented(
            &chain,
            chain.home(),
            &target,
            &cone(Vector3::z()),
            0.1,
            100,
            1e-6,
            &mut work,
        );
        assert!(err <= 1e-6 && angle < 1e-12, "{err} {angle}");
        let (_, angle) = dls_oriented(
            &chain,
            chain.home(),
            &target,
            &cone(Vector3::x()),
            0.1,
            100,
            1e-6,
            &mut work,
        );
        assert!(
            (angle - std::f64::consts::FRAC_PI_2).abs() < 1e-9,
            "{angle}"
        );
    }

    #[test]
    fn a_pose_about_the_plane_normal_is_met() {
        let chain = planar(3);
        let mut work = IkWork::new(&chain);
        let target = Point3::new(0.6, 0.6, 0.0);
        let pose = TaskOrientation::Pose {
            rotation: nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), 2.0),
            tolerance: 0.05,
        };
        let (err, angle) = dls_oriented(
            &chain,
            chain.home(),
            &target,
            &pose,
            0.1,
            200,
            1e-6,
            &mut work,
        );
        assert!(err <= 1e-6 && angle <= 0.5 * 0.05 + 1e-9, "{err} {angle}");
        let mut f = chain.frames();
        chain.fk(&work.q, &mut f);
        assert!(pose.holds(f.tcp_rotation()));
        assert!(chain.within_ranges(&work.q));
    }

    #[test]
    fn an_unreachable_point_gets_closer_and_stays_in_range() {
        let chain = planar(2);
        let mut work = IkWork::new(&chain);
        let target = Point3::new(-3.0, 0.5, 0.0);
        let start_err = (chain.end_effector(chain.home()) - target).norm();
        let err = dls(&chain, chain.home(), &target, 50, 1e-6, &mut work);
        assert!(err < start_err);
        assert!(err > 1.0, "beyond reach");
        assert!(chain.within_ranges(&work.q));
    }
}
