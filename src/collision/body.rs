//! The robot body as the collision checks see it: capsules around the link segments, or the
//! paper's point colliders (Eq. 6–8).

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

/// True when every body segment's capsule is clear of every obstacle (distance `> ε`). The
/// broad phase tests each link's enclosing ball against the obstacles' bounding spheres.
pub fn capsules_free(
    scene: &CollisionScene,
    chain: &Chain,
    frames: &Frames,
    near: &mut Vec<u32>,
) -> bool {
    let r = chain.radius();
    let eps = scene.clearance();
    for link in 1..=chain.link_count() {
        let segs = &frames.segments[chain.link_segments(link)];
        if segs.is_empty() {
            continue;
        }
        let (c, rad) = enclosing_ball(segs.iter().flatten());
        scene.near(&c, rad + r, eps, near);
        for &k in near.iter() {
            for g in segs {
                if scene.distance(k as usize, &g[0], &g[1], r) <= eps {
                    return false;
                }
            }
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

/// Smallest distance between any body capsule and any obstacle (`+∞` without obstacles or
/// segments).
pub fn capsules_min_distance(scene: &CollisionScene, chain: &Chain, frames: &Frames) -> f64 {
    let r = chain.radius();
    frames
        .segments
        .iter()
        .map(|s| scene.min_distance(&s[0], &s[1], r, f64::INFINITY))
        .fold(f64::INFINITY, f64::min)
}
