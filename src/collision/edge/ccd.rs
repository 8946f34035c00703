//! `ccd`: continuous collision detection of the link capsules with parry's nonlinear shape
//! casts.
//!
//! parry's [`NonlinearRigidMotion`] moves a body with constant linear and angular velocity about
//! one centre. That is not the motion of a link under linear joint interpolation (a link far down
//! the chain follows a composition of rotations about several axes), and parry's root finding
//! bisects along one separating axis, which can miss contacts under large rotations. So the edge
//! is split into sub-steps, and within each the link moves from its exact pose at the sub-step's
//! start to its exact pose at its end with parry's motion model:
//!
//! **Sub-step rule:** `n = clamp(⌈θ / 0.2 rad⌉, 1, 64)`, with `θ = Σ |Δa_j|` over the rotation
//! axes of the step: no link turns more than 0.2 rad relative to the base within a sub-step.
//!
//! Each capsule (radius inflated by the clearance `ε`, since the nonlinear cast has no target
//! distance) is cast against each obstacle the broad phase cannot rule out (its bounding sphere
//! farther than the chain's motion bound for the sub-step). A hit, an initial penetration, or a
//! `Failed` status counts as a collision. What this still misses is measured against the oracle
//! (see the README).

use super::{EdgeChecker, Scratch};
use crate::collision::body::BodyModel;
use crate::collision::scene::CollisionScene;
use crate::kinematics::{Chain, Frames};
use crate::world::convert::{to_parry_point, to_parry_pose};
use nalgebra::{IsometryMatrix3, Point3, Translation3, UnitQuaternion};
use parry3d_f64::math::Vector;
use parry3d_f64::query::{self, NonlinearRigidMotion, ShapeCastStatus};
use parry3d_f64::shape::Capsule;
use std::sync::Arc;

/// Largest total joint rotation (radians) within one sub-step.
pub const MAX_SUBSTEP_ROTATION: f64 = 0.2;
/// Largest number of sub-steps per edge.
pub const MAX_SUBSTEPS: usize = 64;

/// Continuous collision detection with parry shape casts.
#[derive(Clone, Debug)]
pub struct Ccd {
    scene: Arc<CollisionScene>,
}

impl Ccd {
    /// A CCD checker over `scene`.
    pub fn new(scene: Arc<CollisionScene>) -> Self {
        Ccd { scene }
    }
}

/// The rigid frame carrying segment `s` and the segment's end points in it: link bodies ride on
/// `F_{k−1}`, sliders on the joint frame (rotation of `F_k`, origin at the joint).
fn segment_frame(chain: &Chain, frames: &Frames, s: usize, slider: bool) -> IsometryMatrix3<f64> {
    let link = chain.segment_link(s);
    if slider {
        let f = &frames.frames[link];
        IsometryMatrix3::from_parts(
            Translation3::from(frames.joints[link - 1].coords),
            f.rotation,
        )
    } else {
        frames.frames[link - 1]
    }
}

/// Number of sub-steps for a step `delta` (see the module documentation).
pub fn substeps(chain: &Chain, delta: &[f64]) -> usize {
    let theta: f64 = chain
        .free_axes()
        .iter()
        .zip(delta)
        .filter(|(f, _)| f.axis.is_rotation())
        .map(|(_, d)| d.abs())
        .sum();
    ((theta / MAX_SUBSTEP_ROTATION).ceil() as usize).clamp(1, MAX_SUBSTEPS)
}

impl EdgeChecker for Ccd {
    fn name(&self) -> &'static str {
        "ccd"
    }

    fn node_free(&self, chain: &Chain, a: &[f64], scratch: &mut Scratch) -> bool {
        super::node_free_with(&self.scene, BodyModel::Capsules, chain, a, scratch)
    }

    fn edge_free(&self, chain: &Chain, from: &[f64], to: &[f64], scratch: &mut Scratch) -> bool {
        scratch.stats.edges += 1;
        let scene = &*self.scene;
        let eps = scene.clearance();
        let radius = chain.radius() + eps;
        let Scratch {
            fa,
            fb,
            q,
            bounds,
            certified: work,
            stats,
            ..
        } = scratch;
        work.prepare(bounds, from, to);
        let n = substeps(chain, &work.delta);
        stats.fk += 1;
        chain.fk(from, fa);
        for i in 0..n {
            let t1 = (i + 1) as f64 / n as f64;
            for ((qi, a), b) in q.iter_mut().zip(from).zip(to) {
                *qi = a + t1 * (b - a);
            }
            stats.fk += 1;
            chain.fk(q, fb);
            for s in 0..chain.segment_count() {
                let slider = bounds.is_slider(s);
                let g0 = segment_frame(chain, fa, s, slider);
                let g1 = segment_frame(chain, fb, s, slider);
                let [w0a, w0b] = fa.segments[s];
                let [w1a, w1b] = fb.segments[s];
                // Local end points; a slider's length changes: take the longer of its two ends.
                let la = g0.inverse_transform_point(&w0a);
                let lb0 = g0.inverse_transform_point(&w0b);
                let lb1 = g1.inverse_transform_point(&w1b);
                let lb = if lb1.coords.norm() > lb0.coords.norm() {
                    lb1
                } else {
                    lb0
                };
                let step_reach = work.reach[s] / n as f64;
                let capsule = Capsule::new(to_parry_point(&la), to_parry_point(&lb), radius);
                let center = Point3::from((la.coords + lb.coords) * 0.5);
                let c0 = g0 * center;
                let c1 = g1 * center;
                let rot =
                    UnitQuaternion::from_rotation_matrix(&(g1.rotation * g0.rotation.inverse()));
                let w = rot.scaled_axis();
                let motion = NonlinearRigidMotion::new(
                    to_parry_pose(&g0),
                    to_parry_point(&center),
                    Vector::new(c1.x - c0.x, c1.y - c0.y, c1.z - c0.z),
                    Vector::new(w.x, w.y, w.z),
                );
                for k in 0..scene.len() {
                    if scene.lower_bound(k, &w0a, &w0b, chain.radius()) - eps > step_reach {
                        continue;
                    }
                    let o = &scene.obstacles()[k];
                    let still = NonlinearRigidMotion::constant_position(*o.pose());
                    match query::cast_shapes_nonlinear(
                        &motion,
                        &capsule,
                        &still,
                        o.shape().as_ref(),
                        0.0,
                        1.0,
                        true,
                    ) {
                        Ok(None) => {}
                        Ok(Some(hit)) if hit.status == ShapeCastStatus::Failed => return false,
                        Ok(Some(hit)) if hit.time_of_impact <= 1.0 => return false,
                        Ok(Some(_)) => {}
                        Err(_) => {
                            // Unsupported pair: fall back to the capsule at the sub-step's end.
                            if scene.distance(k, &w1a, &w1b, chain.radius()) <= eps {
                                return false;
                            }
                        }
                    }
                }
            }
            std::mem::swap(fa, fb);
        }
        true
    }
}
