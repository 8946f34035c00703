//! Edge checkers: does the straight actuation-space motion `from → to` stay collision-free?
//!
//! The planner sees the geometry only through [`EdgeChecker`], as OMPL's planners see it only
//! through a motion validator. Four strategies, selectable by name (`planner.checker`,
//! `--checker`):
//!
//! | name | checks | guarantee |
//! | --- | --- | --- |
//! | `discrete` | the end configuration only (paper §IV baseline) | none between nodes |
//! | `segment` | the segments swept by the body points (paper §III-A) | exact for points moving on straight lines; approximate for the real, curved motion |
//! | `ccd` | parry's nonlinear shape casts of each link capsule, in sub-steps | approximate (constant-velocity motion model) |
//! | `certified` | conservative advancement with chain motion bounds | never calls a colliding edge free |

pub mod ccd;
pub mod certified;
pub mod discrete;
pub mod segment;

use super::body::{BodyModel, MotionBounds, Placed, RobotBody};
use super::scene::CollisionScene;
use crate::kinematics::{Chain, Frames};
use nalgebra::Point3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Edge-checking strategy, chosen by name in `planner.checker` and `--checker`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CheckerKind {
    /// End configuration only (the paper's §IV baseline; safe only with a small `L_max`).
    Discrete,
    /// The paper's §III-A fast path: point colliders and the segments they sweep.
    Segment,
    /// Continuous collision detection of the link capsules with parry shape casts.
    Ccd,
    /// Conservative advancement with chain motion bounds: free only when proven free (the
    /// default).
    #[default]
    Certified,
}

impl CheckerKind {
    /// All strategies.
    pub const ALL: [CheckerKind; 4] = [
        CheckerKind::Discrete,
        CheckerKind::Segment,
        CheckerKind::Ccd,
        CheckerKind::Certified,
    ];

    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            CheckerKind::Discrete => "discrete",
            CheckerKind::Segment => "segment",
            CheckerKind::Ccd => "ccd",
            CheckerKind::Certified => "certified",
        }
    }
}

impl std::str::FromStr for CheckerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        CheckerKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!("unknown checker `{s}` (expected discrete, segment, ccd or certified)")
            })
    }
}

impl std::fmt::Display for CheckerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Work counters of one scratch buffer (one planner thread).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EdgeStats {
    /// Calls of [`EdgeChecker::node_free`].
    pub nodes: u64,
    /// Calls of [`EdgeChecker::edge_free`].
    pub edges: u64,
    /// Forward-kinematics evaluations made by the checker: whole, or (at a bisection point of
    /// `certified`) of the first links only ([`Chain::fk_links`]); none for a configuration
    /// `certified` kept from an earlier check.
    pub fk: u64,
    /// Shape casts made by `ccd` (its unit of work: one body against one obstacle, or one
    /// self pair, over one sub-step; a cast against a triangle mesh counts one more per
    /// triangle whose bounding box comes near the moving body).
    pub casts: u64,
}

/// Per-thread working memory of the checkers for one chain: frame buffers, point buffers,
/// the chain's motion bounds and counters. Create one per (chain, thread) and reuse it: the
/// checkers then allocate nothing per call once the buffers have grown to their working size.
#[derive(Clone, Debug)]
pub struct Scratch {
    pub(crate) fa: Frames,
    pub(crate) fb: Frames,
    pub(crate) fm: Frames,
    pub(crate) q: Vec<f64>,
    pub(crate) colliders: Vec<Point3<f64>>,
    pub(crate) colliders_b: Vec<Point3<f64>>,
    pub(crate) near: Vec<u32>,
    pub(crate) body: Arc<RobotBody>,
    pub(crate) pa: Placed,
    pub(crate) pb: Placed,
    pub(crate) pm: Placed,
    pub(crate) bounds: MotionBounds,
    pub(crate) certified: certified::Work,
    /// `certified`'s recent configurations: frames, placement and clearances kept for the
    /// steps that start (or end) there ([`certified::KEPT`] of them, made on first use).
    pub(crate) kept: Vec<certified::Kept>,
    pub(crate) ccd: Vec<ccd::Moving>,
    /// Counters since creation.
    pub stats: EdgeStats,
}

impl Scratch {
    /// Scratch space sized for `chain`, whose body is its capsules with the default
    /// self-collision settings ([`RobotBody::of_chain`]).
    pub fn new(chain: &Chain) -> Self {
        Self::with_body(chain, Arc::new(RobotBody::of_chain(chain)))
    }

    /// Scratch space for `chain` with the robot body `body` (built for that chain).
    pub fn with_body(chain: &Chain, body: Arc<RobotBody>) -> Self {
        Scratch {
            fa: chain.frames(),
            fb: chain.frames(),
            fm: chain.frames(),
            kept: Vec::new(),
            q: vec![0.0; chain.dof()],
            colliders: Vec::new(),
            colliders_b: Vec::new(),
            near: Vec::new(),
            bounds: MotionBounds::new(chain, &body),
            body,
            pa: Placed::default(),
            pb: Placed::default(),
            pm: Placed::default(),
            certified: certified::Work::default(),
            ccd: Vec::new(),
            stats: EdgeStats::default(),
        }
    }

    /// The robot body checked.
    pub fn body(&self) -> &Arc<RobotBody> {
        &self.body
    }
}

/// Decides whether configurations and straight actuation-space motions are collision-free.
pub trait EdgeChecker: Send + Sync {
    /// The strategy's name.
    fn name(&self) -> &'static str;
    /// True when the body at configuration `a` is clear of every obstacle. `frames`, when
    /// given, are the result of [`Chain::fk`] for `a` (a caller that has them saves the checker
    /// evaluating them again; the answer is the same).
    fn check_node(
        &self,
        chain: &Chain,
        a: &[f64],
        frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool;
    /// True when the motion `a(t) = from + t·(to − from)`, `t ∈ [0, 1]`, is judged free. The
    /// start `from` is assumed to have passed [`EdgeChecker::node_free`]. `to_frames`, when
    /// given, are the result of [`Chain::fk`] for `to` (a planner has them from steering; the
    /// answer is the same).
    fn check_edge(
        &self,
        chain: &Chain,
        from: &[f64],
        to: &[f64],
        to_frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool;
    /// True when [`EdgeChecker::edge_free`] answers "free" only if the end configuration `to`
    /// is free as well (the whole motion, end included, is checked), so that a planner need
    /// not call [`EdgeChecker::node_free`] on a step's end before checking the step.
    fn edge_checks_end(&self) -> bool {
        false
    }
    /// [`EdgeChecker::check_node`] without frames.
    fn node_free(&self, chain: &Chain, a: &[f64], scratch: &mut Scratch) -> bool {
        self.check_node(chain, a, None, scratch)
    }
    /// [`EdgeChecker::check_edge`] without frames.
    fn edge_free(&self, chain: &Chain, from: &[f64], to: &[f64], scratch: &mut Scratch) -> bool {
        self.check_edge(chain, from, to, None, scratch)
    }
}

/// Node check shared by the strategies: the body model at `a`, using `scratch.fa` (a copy of
/// `frames` when given: [`Chain::fk`] of `a`).
pub(crate) fn node_free_with(
    scene: &CollisionScene,
    body: BodyModel,
    chain: &Chain,
    a: &[f64],
    frames: Option<&Frames>,
    scratch: &mut Scratch,
) -> bool {
    scratch.stats.nodes += 1;
    fk_or_copy(chain, a, frames, &mut scratch.fa, &mut scratch.stats);
    scratch.body.place(&scratch.fa, &mut scratch.pa);
    match body {
        BodyModel::Capsules => super::body::bodies_free(
            scene,
            &scratch.body,
            &scratch.fa,
            &scratch.pa,
            &mut scratch.near,
        ),
        BodyModel::Points => {
            chain.colliders(&scratch.fa, &mut scratch.colliders);
            super::body::points_free(
                scene,
                chain,
                &scratch.fa,
                &scratch.colliders,
                &mut scratch.near,
            ) && super::body::solids_free(
                scene,
                &scratch.body,
                &scratch.fa,
                &scratch.pa,
                &mut scratch.near,
            ) && super::body::self_free(&scratch.body, &scratch.fa, &scratch.pa)
        }
    }
}

/// Writes the frames of `a` to `out`: a copy of `known` when given (the caller's [`Chain::fk`]
/// of `a`), otherwise [`Chain::fk`] (counted in `stats`).
#[inline]
pub(crate) fn fk_or_copy(
    chain: &Chain,
    a: &[f64],
    known: Option<&Frames>,
    out: &mut Frames,
    stats: &mut EdgeStats,
) {
    match known {
        Some(f) => out.copy_from(f),
        None => {
            stats.fk += 1;
            chain.fk(a, out);
        }
    }
}

/// The checker for a strategy over a scene, with a body model (used by `discrete` and
/// `segment`; `ccd` and `certified` always check the capsules, the real body).
pub fn make_checker(
    kind: CheckerKind,
    scene: Arc<CollisionScene>,
    body: BodyModel,
) -> Box<dyn EdgeChecker> {
    match kind {
        CheckerKind::Discrete => Box::new(discrete::Discrete::new(scene, body)),
        CheckerKind::Segment => Box::new(segment::SegmentChecker::new(scene, body)),
        CheckerKind::Ccd => Box::new(ccd::Ccd::new(scene)),
        CheckerKind::Certified => Box::new(certified::Certified::new(scene)),
    }
}
