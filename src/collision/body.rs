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

/// The body points of the [`BodyModel::Points`] model at the configuration in `frames`: the
/// point colliders of paper Eq. 6, then the start and end of every body segment. `colliders`
/// and `out` are caller-owned buffers (cleared and refilled).
pub fn body_points(
    chain: &Chain,
    frames: &Frames,
    colliders: &mut Vec<Point3<f64>>,
    out: &mut Vec<Point3<f64>>,
) {
    chain.colliders(frames, colliders);
    out.clear();
    out.extend_from_slice(colliders);
    for s in &frames.segments {
        out.push(s[0]);
        out.push(s[1]);
    }
}

/// True when every body segment's capsule is clear of every obstacle (distance `> ε`).
pub fn capsules_free(scene: &CollisionScene, chain: &Chain, frames: &Frames) -> bool {
    let r = chain.radius();
    frames
        .segments
        .iter()
        .all(|s| scene.capsule_free(&s[0], &s[1], r))
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

/// True when every ball of the link radius at `points` is clear of every obstacle.
pub fn points_free(scene: &CollisionScene, radius: f64, points: &[Point3<f64>]) -> bool {
    points.iter().all(|p| scene.capsule_free(p, p, radius))
}
