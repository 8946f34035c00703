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
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::query::{self, NonlinearRigidMotion, ShapeCastStatus};
use parry3d_f64::shape::{Capsule, Shape};
use std::sync::Arc;

/// Largest total joint rotation (radians) within one sub-step.
pub const MAX_SUBSTEP_ROTATION: f64 = 0.2;
/// Largest number of sub-steps per edge.
pub const MAX_SUBSTEPS: usize = 64;

/// The casts a shape cast against `shape` (at world pose `pose`) counts for, when the moving
/// body stays within the ball `(center, radius)` over the cast: one for a convex shape; for a
/// triangle mesh, one plus one per triangle whose bounding box meets that ball's (those are
/// the triangles the cast may have to test: a cast against the glove box's 808 triangles costs
/// about 0.55 ms, some 80 convex casts, and one against a soup of large triangles that all
/// overlap costs as many convex casts as it has triangles).
#[inline]
fn cast_units(shape: &dyn Shape, pose: &Pose, center: &Point3<f64>, radius: f64) -> u64 {
    shape.as_trimesh().map_or(1, |m| {
        let local = pose.inverse_transform_point(to_parry_point(center));
        let reach = Vector::splat(radius);
        let ball = Aabb::new(local - reach, local + reach);
        1 + m.bvh().intersect_aabb(&ball).count() as u64
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
                    stats.casts += cast_units(
                        o.shape().as_ref(),
                        o.pose(),
                        &center,
                        radius + step_reach + eps,
                    );
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

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d_f64::shape::{Ball, TriMesh};

    /// A cast counts one for a convex shape, and against a triangle mesh one more per triangle
    /// whose box meets the moving body's ball (in the mesh's frame): every triangle of a soup
    /// that overlaps the ball, none of a mesh far from it.
    #[test]
    fn a_cast_counts_the_triangles_near_the_body() {
        let n = 50u32;
        // n triangles across the unit square at heights 0 … 0.49, each its own vertices.
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        for i in 0..n {
            let z = f64::from(i) * 0.01;
            for v in [[0.0, 0.0, z], [1.0, 0.0, z], [0.0, 1.0, z]] {
                vertices.push(Vector::new(v[0], v[1], v[2]));
            }
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let soup = TriMesh::new(vertices, indices).unwrap();
        let moved = Pose::translation(10.0, 0.0, 0.0);
        let near = Point3::new(10.3, 0.3, 0.2);
        assert_eq!(cast_units(&soup, &moved, &near, 0.6), 1 + u64::from(n));
        // Only the triangles within 0.055 of z = 0.2 (heights 0.15 … 0.25), 0.105 (0.1 … 0.3).
        assert_eq!(cast_units(&soup, &moved, &near, 0.055), 1 + 11);
        assert_eq!(cast_units(&soup, &moved, &near, 0.105), 1 + 21);
        // In the world frame the mesh lies 10 m away from this ball.
        assert_eq!(
            cast_units(&soup, &moved, &Point3::new(0.3, 0.3, 0.2), 0.1),
            1
        );
        assert_eq!(cast_units(&Ball::new(0.1), &moved, &near, 0.1), 1);
    }
}
