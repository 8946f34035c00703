//! The robot body as the collision checks see it: one body model ([`RobotBody`]: capsules,
//! fixed-length slider rods and solids, with the allowed-collision matrix for self-collision),
//! or for the environment check of `discrete` and `segment` the paper's point colliders
//! (Eq. 6–8).

pub mod acm;
pub mod bounds;
pub mod model;

pub use acm::{AllowedCollisions, DisabledPair, Reason, SelfCollisionConfig};
pub use bounds::MotionBounds;
pub use model::{PairBlock, Placed, RobotBody, Solid};

use super::scene::CollisionScene;
use crate::kinematics::{Chain, Frames};
use nalgebra::Point3;
use serde::{Deserialize, Serialize};

/// Which geometry stands for the links.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BodyModel {
    /// A capsule of the link radius around every body segment: the real body.
    #[default]
    Capsules,
    /// The paper's point colliders (Eq. 6–8): `s_i` points along each link, plus the two ends of
    /// every segment (joints and frame origins), each a ball of the link radius. Cheaper, but
    /// blind between the points.
    Points,
}

impl BodyModel {
    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            BodyModel::Capsules => "capsules",
            BodyModel::Points => "points",
        }
    }
}

/// A ball enclosing `points` (centre of their bounding box, radius to the farthest point).
/// Empty input gives a ball of radius −∞ at the origin (it encloses nothing).
pub fn enclosing_ball<'a>(
    points: impl Iterator<Item = &'a Point3<f64>> + Clone,
) -> (Point3<f64>, f64) {
    let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let mut hi = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in points.clone() {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    if lo.x > hi.x {
        return (Point3::origin(), f64::NEG_INFINITY);
    }
    let c = nalgebra::center(&lo, &hi);
    let r2 = points.map(|p| (p - c).norm_squared()).fold(0.0, f64::max);
    (c, r2.sqrt())
}

/// The body points of link `link` (from 1) for the [`BodyModel::Points`] model, in a fixed
/// order: its point colliders (paper Eq. 6, from `colliders`, as filled by
/// [`Chain::colliders`]), then the start of its first segment and the end of each segment.
pub fn link_points<'a>(
    chain: &Chain,
    frames: &'a Frames,
    colliders: &'a [Point3<f64>],
    link: usize,
) -> impl Iterator<Item = &'a Point3<f64>> + Clone + 'a {
    let s = chain.colliders_per_link();
    let segs = &frames.segments[chain.link_segments(link)];
    colliders[(link - 1) * s..link * s]
        .iter()
        .chain(segs.first().map(|g| &g[0]))
        .chain(segs.iter().map(|g| &g[1]))
}

/// True when every body of `body` is clear of every obstacle (distance `> ε`) and every checked
/// self pair is apart (distance `> 0`), with the solids placed in `placed`. The broad phase tests
/// each body's bounding ball against the obstacles' bounding spheres.
pub fn bodies_free(
    scene: &CollisionScene,
    body: &RobotBody,
    frames: &Frames,
    placed: &Placed,
    near: &mut Vec<u32>,
) -> bool {
    clear_of_obstacles(scene, body, frames, placed, 0..body.len(), near)
        && self_free(body, frames, placed)
}

/// True when every solid of `body` (bodies after the capsule segments) is clear of every
/// obstacle.
pub fn solids_free(
    scene: &CollisionScene,
    body: &RobotBody,
    frames: &Frames,
    placed: &Placed,
    near: &mut Vec<u32>,
) -> bool {
    clear_of_obstacles(
        scene,
        body,
        frames,
        placed,
        body.segments()..body.len(),
        near,
    )
}

/// True when the bodies `bodies` are clear of every obstacle (distance `> ε`).
fn clear_of_obstacles(
    scene: &CollisionScene,
    body: &RobotBody,
    frames: &Frames,
    placed: &Placed,
    bodies: std::ops::Range<usize>,
    near: &mut Vec<u32>,
) -> bool {
    let eps = scene.clearance();
    for b in bodies {
        let (c, rad) = body.ball(frames, placed, b);
        scene.near(&c, rad, eps, near);
        for &k in near.iter() {
            if body.obstacle_distance(scene, frames, placed, b, k as usize) <= eps {
                return false;
            }
        }
    }
    true
}

/// True when every checked self pair of `body` is apart (distance `> 0`).
pub fn self_free(body: &RobotBody, frames: &Frames, placed: &Placed) -> bool {
    for &(p, q) in body.self_pairs() {
        let (p, q) = (p as usize, q as usize);
        let (cp, rp) = body.ball(frames, placed, p);
        let (cq, rq) = body.ball(frames, placed, q);
        let gap = rp + rq;
        if (cp - cq).norm_squared() > gap * gap {
            continue;
        }
        if body.pair_distance(frames, placed, p, q) <= 0.0 {
            return false;
        }
    }
    true
}

/// True when every ball of the link radius at the body points (see [`link_points`]) is clear of
/// every obstacle, with the same per-link broad phase.
pub fn points_free(
    scene: &CollisionScene,
    chain: &Chain,
    frames: &Frames,
    colliders: &[Point3<f64>],
    near: &mut Vec<u32>,
) -> bool {
    let r = chain.radius();
    let eps = scene.clearance();
    for link in 1..=chain.link_count() {
        let pts = link_points(chain, frames, colliders, link);
        let (c, rad) = enclosing_ball(pts.clone());
        scene.near(&c, rad + r, eps, near);
        for &k in near.iter() {
            for p in pts.clone() {
                if scene.distance(k as usize, p, p, r) <= eps {
                    return false;
                }
            }
        }
    }
    true
}
