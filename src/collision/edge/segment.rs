//! `segment`: the paper's integrated trajectory collision check (§III-A, Eq. 13–17).
//!
//! Every body point (the point colliders of Eq. 6 plus the ends of every body segment) is
//! followed from its position at `from` to its position at `to` along a straight segment, and
//! that segment, thickened by the link radius, must keep more than the clearance `ε` from every
//! obstacle (Eq. 15–16). The distance is the true point-to-*segment* distance (clamped
//! projection), not Eq. 14's distance to the infinite line; see
//! [`crate::collision::distance`]. Spheres use the closed form, other shapes parry's
//! segment–shape distance.
//!
//! The straight segment is the chord of each point's real (curved) path, so a large rotation
//! can sweep the real body across an obstacle the chords miss; the paper limits `L_max`
//! (π/3 or less) for this reason. With [`BodyModel::Capsules`] the end configuration's capsules
//! are checked too.

use super::{EdgeChecker, Scratch};
use crate::collision::body::{body_points, capsules_free, BodyModel};
use crate::collision::scene::CollisionScene;
use crate::kinematics::Chain;
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

    fn node_free(&self, chain: &Chain, a: &[f64], scratch: &mut Scratch) -> bool {
        super::node_free_with(&self.scene, self.body, chain, a, scratch)
    }

    fn edge_free(&self, chain: &Chain, from: &[f64], to: &[f64], scratch: &mut Scratch) -> bool {
        scratch.stats.edges += 1;
        scratch.stats.fk += 2;
        chain.fk(from, &mut scratch.fa);
        chain.fk(to, &mut scratch.fb);
        if self.body == BodyModel::Capsules && !capsules_free(&self.scene, chain, &scratch.fb) {
            return false;
        }
        body_points(chain, &scratch.fa, &mut scratch.colliders, &mut scratch.pa);
        body_points(chain, &scratch.fb, &mut scratch.colliders, &mut scratch.pb);
        let r = chain.radius();
        scratch
            .pa
            .iter()
            .zip(&scratch.pb)
            .all(|(p, q)| self.scene.capsule_free(p, q, r))
    }
}
