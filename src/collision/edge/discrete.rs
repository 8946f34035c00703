//! `discrete`: the end configuration only — the baseline of paper §IV (ASA + RRT with node-only
//! checks), safe only when `L_max` is small next to the obstacles (the paper uses π/40).

use super::{node_free_with, EdgeChecker, Scratch};
use crate::collision::body::BodyModel;
use crate::collision::scene::CollisionScene;
use crate::kinematics::{Chain, Frames};
use std::sync::Arc;

/// Node-only checking: an edge is free when its end configuration is.
#[derive(Clone, Debug)]
pub struct Discrete {
    scene: Arc<CollisionScene>,
    body: BodyModel,
}

impl Discrete {
    /// A discrete checker over `scene` with the given body model.
    pub fn new(scene: Arc<CollisionScene>, body: BodyModel) -> Self {
        Discrete { scene, body }
    }
}

impl EdgeChecker for Discrete {
    fn name(&self) -> &'static str {
        "discrete"
    }

    fn check_node(
        &self,
        chain: &Chain,
        a: &[f64],
        frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool {
        node_free_with(&self.scene, self.body, chain, a, frames, scratch)
    }

    fn check_edge(
        &self,
        chain: &Chain,
        _from: &[f64],
        to: &[f64],
        to_frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool {
        scratch.stats.edges += 1;
        node_free_with(&self.scene, self.body, chain, to, to_frames, scratch)
    }
}
