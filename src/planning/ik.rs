//! Damped-least-squares inverse kinematics steps toward a task point, within the axis ranges.

use crate::kinematics::{Chain, Frames};
use nalgebra::{Matrix3, Point3, Vector3};

/// Reused buffers for [`dls`].
#[derive(Clone, Debug)]
pub struct IkWork {
    frames: Frames,
    jac: Vec<f64>,
    /// The configuration after the last call.
    pub q: Vec<f64>,
}

impl IkWork {
    /// Buffers sized for `chain`.
    pub fn new(chain: &Chain) -> Self {
        IkWork {
            frames: chain.frames(),
            jac: vec![0.0; 3 * chain.dof()],
            q: vec![0.0; chain.dof()],
        }
    }
}

/// Damping `μ` of the least-squares steps (metres).
pub const DAMPING: f64 = 0.05;
/// Largest change of any axis in one step (radians or metres).
pub const MAX_STEP: f64 = 0.5;

/// Runs up to `steps` damped-least-squares iterations from `start` toward putting the end
/// effector on `target`: `Δa = Jᵀ(JJᵀ + μ²I)⁻¹ e`, `e = target − p_ee`, each step scaled so no
/// axis moves more than [`MAX_STEP`], and the result clamped into the axis ranges. Stops early
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
        chain.jacobian(&work.q, &work.frames, &mut work.jac);
        let mut jjt = Matrix3::from_diagonal_element(DAMPING * DAMPING);
        for col in work.jac.chunks_exact(3) {
            let c = Vector3::new(col[0], col[1], col[2]);
            jjt += c * c.transpose();
        }
        let Some(y) = jjt.try_inverse().map(|m| m * e) else {
            break;
        };
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
