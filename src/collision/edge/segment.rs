//! `segment`: the paper's integrated trajectory collision check (§III-A, Eq. 13–17).
//!
//! Every body point (the point colliders of Eq. 6 plus the ends of every body segment) is
//! followed from its position at `from` to its position at `to` along a straight segment, and
//! that segment, thickened by the link radius, must keep more than the clearance `ε` from every
//! obstacle (Eq. 15–16). The distance is the true point-to-*segment* distance (clamped
//! projection), not Eq. 14's distance to the infinite line; see
//! [`crate::collision::distance`]. Spheres, capsules, boxes and triangle meshes use closed forms,
//! convex hulls GJK ([`crate::collision::scene`]), other shapes parry's segment–shape distance.
//!
//! The straight segment is the chord of each point's real (curved) path, so a large rotation
//! can sweep the real body across an obstacle the chords miss; the paper limits `L_max`
//! (π/3 or less) for this reason. Between the points the body is not checked at all, also at
//! the end configuration: [`EdgeChecker::node_free`] (which the planner calls on every new
//! node) checks the configured body model there.
//!
//! Solids (convex link meshes and primitives) and the self-collision pairs have no swept-point
//! form: they are checked at the edge's midpoint and at its end, with the exact distances.

use super::{EdgeChecker, Scratch};
use crate::collision::body::{enclosing_ball, link_points, self_free, solids_free, BodyModel};
use crate::collision::scene::CollisionScene;
use crate::kinematics::{Chain, Frames};
use std::sync::Arc;

/// The paper's swept-point checker.
#[derive(Clone, Debug)]
pub struct SegmentChecker {
    scene: Arc<CollisionScene>,
    body: BodyModel,
}

impl SegmentChecker {
    /// A segment checker over `scene`.
    pub fn new(scene: Arc<CollisionScene>, body: BodyModel) -> Self {
        SegmentChecker { scene, body }
    }
}

impl EdgeChecker for SegmentChecker {
    fn name(&self) -> &'static str {
        "segment"
    }

    fn check_node(
        &self,
        chain: &Chain,
        a: &[f64],
        frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool {
        super::node_free_with(&self.scene, self.body, chain, a, frames, scratch)
    }

    fn check_edge(
        &self,
        chain: &Chain,
        from: &[f64],
        to: &[f64],
        to_frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool {
        scratch.stats.edges += 1;
        scratch.stats.fk += 1;
        let scene = &*self.scene;
        let Scratch {
            fa,
            fb,
            fm,
            q,
            colliders,
            colliders_b,
            near,
            body,
            pm,
            stats,
            ..
        } = scratch;
        chain.fk(from, fa);
        super::fk_or_copy(chain, to, to_frames, fb, stats);
        chain.colliders(fa, colliders);
        chain.colliders(fb, colliders_b);
        let r = chain.radius();
        let eps = scene.clearance();
        for link in 1..=chain.link_count() {
            let pa = link_points(chain, fa, colliders, link);
            let pb = link_points(chain, fb, colliders_b, link);
            // Broad phase: one ball around the link's points at both ends of the edge.
            let (c, rad) = enclosing_ball(pa.clone().chain(pb.clone()));
            scene.near(&c, rad + r, eps, near);
            for &k in near.iter() {
                for (p, q) in pa.clone().zip(pb.clone()) {
                    if scene.distance(k as usize, p, q, r) <= eps {
                        return false;
                    }
                }
            }
        }
        if body.solids().is_empty() && body.self_pairs().is_empty() {
            return true;
        }
        for t in [0.5, 1.0] {
            let frames = if t < 1.0 {
                for ((qi, a), b) in q.iter_mut().zip(from).zip(to) {
                    *qi = a + t * (b - a);
                }
                chain.fk(q, fm);
                &*fm
            } else {
                &*fb
            };
            body.place(frames, pm);
            if !solids_free(scene, body, frames, pm, near) || !self_free(body, frames, pm) {
                return false;
            }
        }
        true
    }
}
