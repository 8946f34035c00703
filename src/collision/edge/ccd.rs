//! `ccd`: continuous collision detection of every robot body with parry's nonlinear shape
//! casts, against the obstacles and over the checked self pairs.
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
//! Each body rides on its carrier frame (the frame after the last free axis that moves it, or
//! the base). Each capsule (radius inflated by the clearance `ε`, since the nonlinear cast has no
//! target distance) is cast against each obstacle the broad phase cannot rule out (the scene's
//! hierarchy, then the obstacle's bounding sphere, farther than the body's motion bound for the
//! sub-step); a solid is cast as it is and
//! also checked at the sub-step's end with the clearance. Self pairs are cast against each other,
//! both moving. A hit, an initial penetration, or a `Failed` status counts as a collision. What this still misses is measured against the oracle
//! (see the README).

use super::{EdgeChecker, Scratch};
use crate::collision::body::{BodyModel, RobotBody};
use crate::collision::scene::CollisionScene;
use crate::kinematics::{Chain, Frames};
use crate::world::convert::{to_parry_point, to_parry_pose};
use nalgebra::{IsometryMatrix3, Point3, UnitQuaternion};
use parry3d_f64::math::Vector;
use parry3d_f64::query::{self, NonlinearRigidMotion, ShapeCastStatus};
use parry3d_f64::shape::{Capsule, Shape};
use std::sync::Arc;

/// Largest total joint rotation (radians) within one sub-step.
pub const MAX_SUBSTEP_ROTATION: f64 = 0.2;
/// Largest number of sub-steps per edge.
pub const MAX_SUBSTEPS: usize = 64;

/// Triangles of a mesh obstacle that count as one shape cast in [`crate::collision::EdgeStats::casts`]:
/// a cast against a triangle mesh costs about as many convex casts as it has tenths of its
/// triangles (the glove box's 808 triangles: about 0.55 ms a cast, 80 convex ones).
pub const TRIANGLES_PER_CAST: u64 = 10;

/// The casts a shape cast against `shape` counts for: one, or one per
/// [`TRIANGLES_PER_CAST`] triangles of a triangle mesh.
#[inline]
fn cast_units(shape: &dyn Shape) -> u64 {
    shape.as_trimesh().map_or(1, |m| {
        (m.indices().len() as u64 / TRIANGLES_PER_CAST).max(1)
    })
}

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

/// The rigid carrier frame of body `b`: the frame after free axis `level − 1`, or the base.
fn carrier<'a>(body: &RobotBody, frames: &'a Frames, b: usize) -> &'a IsometryMatrix3<f64> {
    match body.level(b) {
        0 => &frames.frames[0],
        l => &frames.axis_frames[l - 1],
    }
}

/// One body's motion over a sub-step, with its capsule in the carrier frame (segments only).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Moving {
    motion: NonlinearRigidMotion,
    a: Point3<f64>,
    b: Point3<f64>,
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

/// The motions of every body from the frames `fa` to `fb` (parry's constant-velocity model
/// about each body's centre), into `out`.
fn motions(body: &RobotBody, fa: &Frames, fb: &Frames, out: &mut Vec<Moving>) {
    out.clear();
    let ns = body.segments();
    for b in 0..body.len() {
        let g0 = carrier(body, fa, b);
        let g1 = carrier(body, fb, b);
        let (la, lb, center) = if b < ns {
            let [wa, wb] = fa.segments[b];
            let la = g0.inverse_transform_point(&wa);
            let lb = g0.inverse_transform_point(&wb);
            (la, lb, nalgebra::center(&la, &lb))
        } else {
            let s = &body.solids()[b - ns];
            (Point3::origin(), Point3::origin(), s.center)
        };
        let c0 = g0 * center;
        let c1 = g1 * center;
        let rot = UnitQuaternion::from_rotation_matrix(&(g1.rotation * g0.rotation.inverse()));
        let w = rot.scaled_axis();
        let start = if b < ns {
            to_parry_pose(g0)
        } else {
            to_parry_pose(&(g0 * body.solids()[b - ns].local))
        };
        let local_center = if b < ns {
            center
        } else {
            body.solids()[b - ns].local.inverse_transform_point(&center)
        };
        out.push(Moving {
            motion: NonlinearRigidMotion::new(
                start,
                to_parry_point(&local_center),
                Vector::new(c1.x - c0.x, c1.y - c0.y, c1.z - c0.z),
                Vector::new(w.x, w.y, w.z),
            ),
            a: la,
            b: lb,
        });
    }
}

/// parry's verdict on a cast: `true` for a hit within the sub-step (or a failure).
fn hit(result: Result<Option<query::ShapeCastHit>, query::Unsupported>) -> Option<bool> {
    match result {
        Ok(None) => Some(false),
        Ok(Some(h)) if h.status == ShapeCastStatus::Failed => Some(true),
        Ok(Some(h)) => Some(h.time_of_impact <= 1.0),
        Err(_) => None,
    }
}

impl EdgeChecker for Ccd {
    fn name(&self) -> &'static str {
        "ccd"
    }

    fn check_node(
        &self,
        chain: &Chain,
        a: &[f64],
        frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool {
        super::node_free_with(&self.scene, BodyModel::Capsules, chain, a, frames, scratch)
    }

    fn check_edge(
        &self,
        chain: &Chain,
        from: &[f64],
        to: &[f64],
        _to_frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool {
        scratch.stats.edges += 1;
        let scene = &*self.scene;
        let eps = scene.clearance();
        let Scratch {
            fa,
            fb,
            q,
            bounds,
            certified: work,
            stats,
            body,
            pa,
            pb,
            ccd: moving,
            near,
            ..
        } = scratch;
        let body = &**body;
        let ns = body.segments();
        work.prepare(bounds, body, from, to);
        let n = substeps(chain, &work.delta);
        stats.fk += 1;
        chain.fk(from, fa);
        body.place(fa, pa);
        for i in 0..n {
            let t1 = (i + 1) as f64 / n as f64;
            for ((qi, a), b) in q.iter_mut().zip(from).zip(to) {
                *qi = a + t1 * (b - a);
            }
            stats.fk += 1;
            chain.fk(q, fb);
            body.place(fb, pb);
            motions(body, fa, fb, moving);
            for (b, m) in moving.iter().enumerate() {
                let step_reach = work.relative(bounds, b, 0) / n as f64;
                let capsule;
                let shape: &dyn Shape = if b < ns {
                    capsule = Capsule::new(
                        to_parry_point(&m.a),
                        to_parry_point(&m.b),
                        body.radius(b) + eps,
                    );
                    &capsule
                } else {
                    body.solids()[b - ns].shape.as_ref()
                };
                // Broad phase: the obstacles near the ball around the body at the sub-step's
                // start grown by its motion bound (the hierarchy: the cost follows the nearby
                // obstacles, not their number); then their bounding spheres.
                let (center, radius) = body.ball(fa, pa, b);
                scene.near(&center, radius + step_reach, eps, near);
                for &k in near.iter() {
                    let k = k as usize;
                    if body.obstacle_lower_bound(scene, fa, pa, b, k) - eps > step_reach {
                        continue;
                    }
                    let o = &scene.obstacles()[k];
                    stats.casts += cast_units(o.shape().as_ref());
                    let still = NonlinearRigidMotion::constant_position(*o.pose());
                    let cast = query::cast_shapes_nonlinear(
                        &m.motion,
                        shape,
                        &still,
                        o.shape().as_ref(),
                        0.0,
                        1.0,
                        true,
                    );
                    let blocked = match hit(cast) {
                        Some(h) => h,
                        None => body.obstacle_distance(scene, fb, pb, b, k) <= eps,
                    };
                    let end_hit = b >= ns && body.obstacle_distance(scene, fb, pb, b, k) <= eps;
                    if blocked || end_hit {
                        return false;
                    }
                }
            }
            for &(p, qb) in body.self_pairs() {
                let (p, qb) = (p as usize, qb as usize);
                let reach = work.relative(bounds, qb, body.level(p)) / n as f64;
                let (cp, rp) = body.ball(fa, pa, p);
                let (cq, rq) = body.ball(fa, pa, qb);
                if (cp - cq).norm() - rp - rq > reach {
                    continue;
                }
                let (cap_p, cap_q);
                let sp: &dyn Shape = if p < ns {
                    let m = &moving[p];
                    cap_p =
                        Capsule::new(to_parry_point(&m.a), to_parry_point(&m.b), body.radius(p));
                    &cap_p
                } else {
                    body.solids()[p - ns].shape.as_ref()
                };
                let sq: &dyn Shape = if qb < ns {
                    let m = &moving[qb];
                    cap_q =
                        Capsule::new(to_parry_point(&m.a), to_parry_point(&m.b), body.radius(qb));
                    &cap_q
                } else {
                    body.solids()[qb - ns].shape.as_ref()
                };
                stats.casts += 1;
                let cast = query::cast_shapes_nonlinear(
                    &moving[p].motion,
                    sp,
                    &moving[qb].motion,
                    sq,
                    0.0,
                    1.0,
                    true,
                );
                let blocked = match hit(cast) {
                    Some(h) => h,
                    None => body.pair_distance(fb, pb, p, qb) <= 0.0,
                };
                if blocked || body.pair_distance(fb, pb, p, qb) <= 0.0 {
                    return false;
                }
            }
            std::mem::swap(fa, fb);
            std::mem::swap(pa, pb);
        }
        true
    }
}
