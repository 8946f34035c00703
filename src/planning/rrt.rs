//! A goal-biased RRT in actuation space, grown from home, that serves every task point with one
//! tree (paper §II-D, Eq. 10; the planner of §III), helped by backward trees grown from
//! collision-free inverse-kinematics postures of the tasks it has not reached yet.

use super::ik::{dls_oriented, IkWork};
use super::PlannerConfig;
use crate::collision::{EdgeChecker, Scratch};
use crate::kinematics::{Chain, Frames};
use crate::limits::iteration_cap;
use crate::world::TaskOrientation;
use nalgebra::{Matrix3, Point3};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use std::collections::HashSet;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Greedy steps toward an inverse-kinematics goal in one goal-biased iteration, and toward the
/// other tree when a forward and a backward tree try to join.
pub const CONNECT_STEPS: usize = 25;

/// Share of `L_max` that a steering try aims the metric at (paper Eq. 10), just inside the
/// bound since the metric is only about linear in the step.
pub const STEER_AIM: f64 = 0.95;

/// Share of `L_max` below which an aimed steering's first try is aimed again (longer), with
/// [`PlannerConfig::aimed_steering`].
pub const STEER_SHORT: f64 = 0.8;

/// The tree: configurations, their joint positions `f(a)`, end effectors (TCP positions) and TCP
/// rotations, and parents (the root is its own parent; a grafted branch can have parents of
/// higher index than itself).
#[derive(Clone, Debug)]
pub struct Tree {
    dof: usize,
    links: usize,
    configs: Vec<f64>,
    /// The configurations again, transposed in blocks of [`LANES`] nodes for the nearest-node
    /// scan ([`nearest_blocked`]); a last block's unused lanes hold NaN.
    blocks: Vec<f64>,
    positions: Vec<Point3<f64>>,
    ee: Vec<Point3<f64>>,
    rot: Vec<Matrix3<f64>>,
    parent: Vec<u32>,
}

impl Tree {
    fn new(chain: &Chain) -> Self {
        Tree {
            dof: chain.dof(),
            links: chain.position_count(),
            configs: Vec::new(),
            blocks: Vec::new(),
            positions: Vec::new(),
            ee: Vec::new(),
            rot: Vec::new(),
            parent: Vec::new(),
        }
    }

    fn push(&mut self, q: &[f64], frames: &Frames, parent: u32) -> u32 {
        self.configs.extend_from_slice(q);
        block_push(&mut self.blocks, self.parent.len(), q);
        self.positions.extend_from_slice(&frames.positions);
        self.ee.push(frames.end_effector());
        self.rot.push(*frames.tcp_rotation());
        self.parent.push(parent);
        (self.parent.len() - 1) as u32
    }

    /// Empties the tree, keeping its buffers.
    fn clear(&mut self) {
        self.configs.clear();
        self.blocks.clear();
        self.positions.clear();
        self.ee.clear();
        self.rot.clear();
        self.parent.clear();
    }

    /// Appends every node of `other` and links `other`'s node `at` to this tree's node `onto`:
    /// the parent links on the path from `at` to `other`'s root are reversed, so every grafted
    /// node leads back to this tree's root. Returns the index offset of the grafted nodes.
    fn graft(&mut self, other: &Tree, at: u32, onto: u32) -> u32 {
        let offset = self.len() as u32;
        self.configs.extend_from_slice(&other.configs);
        for (i, q) in other.configs.chunks_exact(self.dof.max(1)).enumerate() {
            block_push(&mut self.blocks, offset as usize + i, q);
        }
        self.positions.extend_from_slice(&other.positions);
        self.ee.extend_from_slice(&other.ee);
        self.rot.extend_from_slice(&other.rot);
        self.parent.extend(other.parent.iter().map(|&p| p + offset));
        let (mut child, mut new_parent) = (at, onto);
        loop {
            let old = other.parent[child as usize];
            self.parent[(offset + child) as usize] = new_parent;
            if child == 0 {
                break;
            }
            new_parent = offset + child;
            child = old;
        }
        offset
    }

    /// Parent of node `i` (the root is its own parent).
    pub fn parent(&self, i: u32) -> u32 {
        self.parent[i as usize]
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// True when the tree has no node.
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// Configuration of node `i`.
    pub fn config(&self, i: u32) -> &[f64] {
        let i = i as usize;
        &self.configs[i * self.dof..(i + 1) * self.dof]
    }

    /// Joint positions `f(a)` of node `i`.
    pub fn positions(&self, i: u32) -> &[Point3<f64>] {
        let i = i as usize;
        &self.positions[i * self.links..(i + 1) * self.links]
    }

    /// End effector (TCP position) of node `i`.
    pub fn end_effector(&self, i: u32) -> Point3<f64> {
        self.ee[i as usize]
    }

    /// Rotation of the TCP frame of node `i` in the world.
    pub fn tcp_rotation(&self, i: u32) -> &Matrix3<f64> {
        &self.rot[i as usize]
    }

    /// Per node, the number of configurations of its path from the root ([`Self::path_to`]'s
    /// length; 1 for the root): in time linear in the tree, whatever its depth.
    pub fn path_lengths(&self) -> Vec<u32> {
        let n = self.parent.len();
        let mut len = vec![0u32; n];
        if n == 0 {
            return len;
        }
        len[0] = 1;
        let mut walk = Vec::new();
        for i in 0..n {
            let mut k = i;
            while len[k] == 0 {
                walk.push(k);
                k = self.parent[k] as usize;
            }
            let mut l = len[k];
            while let Some(j) = walk.pop() {
                l += 1;
                len[j] = l;
            }
        }
        len
    }

    /// The configurations from the root (home) to node `i`, in order.
    pub fn path_to(&self, i: u32) -> Vec<Vec<f64>> {
        let mut out = Vec::new();
        let mut n = i;
        loop {
            out.push(self.config(n).to_vec());
            if n == 0 {
                break;
            }
            n = self.parent[n as usize];
        }
        out.reverse();
        out
    }

    /// Nearest node to `q` in actuation space (Euclidean), by linear scan: the node
    /// [`nearest_linear`] finds, [`LANES`] nodes at a time ([`nearest_blocked`]).
    pub fn nearest_config(&self, q: &[f64]) -> u32 {
        if self.dof == 0 {
            return 0;
        }
        nearest_blocked(&self.blocks, q) as u32
    }

    /// Node whose end effector is nearest to `p`.
    pub fn nearest_end_effector(&self, p: &Point3<f64>) -> u32 {
        let mut best = (f64::INFINITY, 0u32);
        for (i, e) in self.ee.iter().enumerate() {
            let d = (e - p).norm_squared();
            if d < best.0 {
                best = (d, i as u32);
            }
        }
        best.1
    }
}

/// Index of the point of `points` (flat, `q.len()` values per point) nearest to `q`
/// (squared Euclidean), by linear scan; 0 for an empty set.
///
/// Measured against the planner's scan of four nodes at a time ([`nearest_blocked`], the same
/// answers) and a k-d tree (kiddo) by `benches/nearest.rs`; see the README for the figures
/// and the choice.
pub fn nearest_linear(points: &[f64], q: &[f64]) -> usize {
    let dim = q.len().max(1);
    let mut best = (f64::INFINITY, 0);
    for (i, c) in points.chunks_exact(dim).enumerate() {
        let d = squared_distance(c, q);
        if d < best.0 {
            best = (d, i);
        }
    }
    best.1
}

/// The squared Euclidean distance of the nearest-node scans, summed in their order: four
/// partial sums over the axes `4m + l` of the first `dim − dim % 4` axes (independent, so that
/// the additions overlap in the pipeline), the remaining axes added to the first, then
/// `(s0 + s1) + (s2 + s3)`.
#[inline(always)]
pub fn squared_distance(c: &[f64], q: &[f64]) -> f64 {
    let dim = q.len();
    let mut acc = [0.0f64; 4];
    let mut quads = c.chunks_exact(4).zip(q.chunks_exact(4));
    for (a, b) in &mut quads {
        for l in 0..4 {
            let d = a[l] - b[l];
            acc[l] += d * d;
        }
    }
    let tail = dim - dim % 4;
    for (a, b) in c[tail..].iter().zip(&q[tail..]) {
        acc[0] += (a - b) * (a - b);
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// Nodes per block of [`nearest_blocked`]'s transposed layout.
pub const LANES: usize = 4;

/// Writes node `index`'s configuration `q` into the transposed blocks `blocks` (block
/// `index / LANES`, axis `k`, lane `index % LANES` at `(block·dim + k)·LANES + lane`),
/// appending a block of NaN when `index` starts one. Nodes are written in index order.
pub fn block_push(blocks: &mut Vec<f64>, index: usize, q: &[f64]) {
    let dim = q.len();
    let (block, lane) = (index / LANES, index % LANES);
    if lane == 0 {
        blocks.resize((block + 1) * dim * LANES, f64::NAN);
    }
    let base = block * dim * LANES;
    for (k, &v) in q.iter().enumerate() {
        blocks[base + k * LANES + lane] = v;
    }
}

/// The index [`nearest_linear`] returns, from the transposed blocks of [`block_push`] (the
/// nodes' configurations, `q.len()` values each): the same sums of squares in the same order,
/// computed for [`LANES`] nodes at once (a vector lane per node, no sum across lanes), so the
/// same node bit for bit, the first of the nearest. 0 for no node.
pub fn nearest_blocked(blocks: &[f64], q: &[f64]) -> usize {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor supports AVX2 (just checked).
        return unsafe { nearest_blocked_avx2(blocks, q) }.0;
    }
    nearest_blocked_by(blocks, q).0
}

/// [`nearest_blocked`] compiled for AVX2 (four lanes in one register).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn nearest_blocked_avx2(blocks: &[f64], q: &[f64]) -> (usize, f64) {
    nearest_blocked_by(blocks, q)
}

/// The scan of [`nearest_blocked`], with the nearest node's squared distance: per lane the
/// sum of [`squared_distance`] in its order; a lane's best changes only on a smaller sum, and
/// the lanes' bests are merged by sum, then by index.
#[inline(always)]
fn nearest_blocked_by(blocks: &[f64], q: &[f64]) -> (usize, f64) {
    let dim = q.len().max(1);
    let quads = q.len() - q.len() % 4;
    let mut best = [f64::INFINITY; LANES];
    // Node indices as f64 (exact below 2^53), so that the update is one select per lane.
    let mut at = [0.0f64; LANES];
    let sq = |axis: &[f64], x: f64, acc: &mut [f64; LANES]| {
        for (a, &v) in acc.iter_mut().zip(axis) {
            let d = v - x;
            *a += d * d;
        }
    };
    for (b, block) in blocks.chunks_exact(dim * LANES).enumerate() {
        let (mut s0, mut s1, mut s2, mut s3) =
            ([0.0f64; LANES], [0.0; LANES], [0.0; LANES], [0.0; LANES]);
        let (head, tail) = block.split_at(quads * LANES);
        for (axes, xs) in head.chunks_exact(4 * LANES).zip(q.chunks_exact(4)) {
            sq(&axes[..LANES], xs[0], &mut s0);
            sq(&axes[LANES..2 * LANES], xs[1], &mut s1);
            sq(&axes[2 * LANES..3 * LANES], xs[2], &mut s2);
            sq(&axes[3 * LANES..], xs[3], &mut s3);
        }
        for (axis, &x) in tail.chunks_exact(LANES).zip(&q[quads..]) {
            sq(axis, x, &mut s0);
        }
        let first = (b * LANES) as f64;
        for lane in 0..LANES {
            let d = (s0[lane] + s1[lane]) + (s2[lane] + s3[lane]);
            let closer = d < best[lane];
            best[lane] = if closer { d } else { best[lane] };
            at[lane] = if closer {
                first + lane as f64
            } else {
                at[lane]
            };
        }
    }
    let mut winner = (f64::INFINITY, 0usize);
    for (&d, &i) in best.iter().zip(&at) {
        let i = i as usize;
        if d < winner.0 || (d == winner.0 && i < winner.1) {
            winner = (d, i);
        }
    }
    (winner.1, winner.0)
}

/// What one RRT run produced.
#[derive(Clone, Debug)]
pub struct Growth {
    /// The tree (node 0 is home; empty when home collides).
    pub tree: Tree,
    /// For each task, the first node whose end effector came within tolerance of it.
    pub reached: Vec<Option<u32>>,
    /// Iterations used.
    pub iterations: usize,
    /// Backward trees joined to the tree from home (each reached its task through the join).
    pub joins: usize,
    /// True when the home configuration is not collision-free.
    pub home_blocked: bool,
    /// True when the run stopped because its checker's work reached
    /// [`crate::limits::MAX_CCD_CASTS`] (before the iteration budget).
    pub work_limited: bool,
    /// True when the run stopped because its trees held [`crate::limits::node_cap`] nodes
    /// (before the iteration budget).
    pub node_limited: bool,
    /// True when the run stopped because its checks reached [`crate::limits::MAX_BODY_TESTS`]
    /// body tests (before the iteration budget).
    pub tests_limited: bool,
    /// True when the run stopped because its checker evaluated the kinematics
    /// [`crate::limits::MAX_CHECK_FK`] times (before the iteration budget).
    pub fk_limited: bool,
    /// True when the run was told to stop ([`Rrt::with_interrupt`]) before it ended: its
    /// result is not the one of a whole run.
    pub interrupted: bool,
}

impl Growth {
    /// The outcome when the home configuration is blocked before planning starts: an empty
    /// tree, nothing reached.
    pub fn blocked(chain: &Chain, tasks: usize) -> Self {
        Growth {
            tree: Tree::new(chain),
            reached: vec![None; tasks],
            iterations: 0,
            joins: 0,
            home_blocked: true,
            work_limited: false,
            node_limited: false,
            tests_limited: false,
            fk_limited: false,
            interrupted: false,
        }
    }
}

/// Reused buffers of the planner.
struct Work {
    frames: Frames,
    q_new: Vec<f64>,
    q_goal: Vec<f64>,
    q_join: Vec<f64>,
    ik: IkWork,
    /// The metric (paper Eq. 10) per unit of actuation-space distance of the last steering
    /// try (0 before the first): the first try of the next one aims by it.
    slope: f64,
}

/// `‖f(b) − f(a)‖ + λ‖b − a‖` (paper Eq. 10) from stored joint positions.
fn metric(fa: &[Point3<f64>], fb: &[Point3<f64>], a: &[f64], b: &[f64], lambda: f64) -> f64 {
    let df: f64 = fa.iter().zip(fb).map(|(p, q)| (q - p).norm_squared()).sum();
    let da: f64 = a.iter().zip(b).map(|(x, y)| (y - x) * (y - x)).sum();
    df.sqrt() + lambda * da.sqrt()
}

/// Euclidean distance in actuation space.
fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// What one extension step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    /// No progress: the target is the node itself, or the step collides.
    Blocked,
    /// A new node was added.
    Added(u32),
    /// The target, a node of another tree, is one free step away; nothing was added.
    Arrived,
}

/// A tree grown backward from a collision-free inverse-kinematics posture of one task: its
/// root reaches the task, and joining it to the forward tree gives a path from home.
struct GoalTree {
    task: usize,
    tree: Tree,
}

/// The state of one run of [`Rrt::grow`].
struct Search {
    /// The forward tree, rooted at home.
    tree: Tree,
    reached: Vec<Option<u32>>,
    /// Tasks farther from the base than the chain can reach ([`Chain::reach_bound`] plus the
    /// goal tolerance): never targeted, and not waited for.
    beyond: Vec<bool>,
    /// Backward trees of unreached tasks.
    goals: Vec<GoalTree>,
    /// Emptied backward trees, kept for their buffers.
    spare: Vec<Tree>,
    /// (node, task) pairs whose IK goal was already tried.
    tried: HashSet<(u32, usize)>,
    unreached: Vec<usize>,
    /// Alternates forward and backward exploration while backward trees exist.
    backward_turn: bool,
    /// Backward trees grafted so far.
    joins: usize,
    work: Work,
}

/// The RRT planner for one chain and one checker.
pub struct Rrt<'a> {
    chain: &'a Chain,
    checker: &'a dyn EdgeChecker,
    config: &'a PlannerConfig,
    tasks: &'a [Point3<f64>],
    /// One per task, or empty: every task is a point task.
    orientations: &'a [TaskOrientation],
    /// Most shape casts of the checker per run ([`crate::limits::MAX_CCD_CASTS`]).
    cast_cap: u64,
    /// Most nodes of the run's trees together ([`crate::limits::node_cap`]).
    node_cap: usize,
    /// Most body tests per run ([`crate::limits::MAX_BODY_TESTS`]).
    tests_cap: u64,
    /// Most kinematics evaluations of the checker per run ([`crate::limits::MAX_CHECK_FK`]).
    fk_cap: u64,
    /// Raised to stop the run before its next iteration ([`Rrt::with_interrupt`]).
    interrupt: Option<&'a AtomicBool>,
}

impl<'a> Rrt<'a> {
    /// A planner over `tasks` with the settings in `config` (its `l_max` and `max_iterations`
    /// are used as given; schedules are applied by the caller).
    pub fn new(
        chain: &'a Chain,
        checker: &'a dyn EdgeChecker,
        config: &'a PlannerConfig,
        tasks: &'a [Point3<f64>],
    ) -> Self {
        Rrt {
            chain,
            checker,
            config,
            tasks,
            orientations: &[],
            cast_cap: crate::limits::MAX_CCD_CASTS,
            node_cap: crate::limits::node_cap(chain.dof()),
            tests_cap: crate::limits::MAX_BODY_TESTS,
            fk_cap: crate::limits::MAX_CHECK_FK,
            interrupt: None,
        }
    }

    /// The same planner with another cap on the checker's shape casts (tests).
    #[cfg(test)]
    fn with_cast_cap(mut self, cap: u64) -> Self {
        self.cast_cap = cap;
        self
    }

    /// The same planner with another cap on its trees' nodes (tests).
    #[cfg(test)]
    fn with_node_cap(mut self, cap: usize) -> Self {
        self.node_cap = cap;
        self
    }

    /// The same planner, stopped before its next iteration once `flag` is raised (a user's
    /// stop signal): the run then reports [`Growth::interrupted`].
    pub fn with_interrupt(mut self, flag: &'a AtomicBool) -> Self {
        self.interrupt = Some(flag);
        self
    }

    /// The same planner with another cap on its checker's kinematics evaluations (tests).
    #[cfg(test)]
    fn with_fk_cap(mut self, cap: u64) -> Self {
        self.fk_cap = cap;
        self
    }

    /// The same planner with another cap on its body tests (tests).
    #[cfg(test)]
    fn with_tests_cap(mut self, cap: u64) -> Self {
        self.tests_cap = cap;
        self
    }

    /// The same planner with an orientation constraint per task (`orientations` has one entry
    /// per task, or none: point tasks). A task then counts as reached when the TCP is within
    /// the goal tolerance of its point and the TCP rotation satisfies its constraint, and the
    /// IK goals take the constraint into account ([`dls_oriented`], with
    /// `config.orientation_weight`).
    ///
    /// # Panics
    /// When `orientations` is neither empty nor one per task.
    pub fn with_orientations(mut self, orientations: &'a [TaskOrientation]) -> Self {
        assert!(
            orientations.is_empty() || orientations.len() == self.tasks.len(),
            "one orientation per task"
        );
        self.orientations = orientations;
        self
    }

    /// The orientation constraint of task `j`.
    fn orientation(&self, j: usize) -> TaskOrientation {
        self.orientations.get(j).copied().unwrap_or_default()
    }

    /// Steers from node `near` toward `target`, cutting the step until the metric of paper
    /// Eq. 10 is within `L_max`; the candidate is left in `work.q_new` with its frames in
    /// `work.frames`. Returns `None` when no progress is possible, else whether the step goes
    /// the whole way to `target`.
    ///
    /// The metric grows about linearly with the step, so each cut aims at [`STEER_AIM`]` ×
    /// L_max` by the metric of the try before. The first try is the whole step, or with
    /// [`PlannerConfig::aimed_steering`] it is aimed the same way by the metric per unit of
    /// actuation-space distance of the last steering (the planner mostly steers from nearby
    /// nodes), and aimed again once if it lands below [`STEER_SHORT`]` × L_max`, so the steps
    /// stay as long as the bound allows: most steps then take one or two kinematics
    /// evaluations instead of about three.
    fn steer(&self, tree: &Tree, near: u32, target: &[f64], work: &mut Work) -> Option<bool> {
        let from = tree.config(near);
        let dist = distance(from, target);
        if dist < 1e-9 {
            return None;
        }
        let aim = STEER_AIM * self.config.l_max;
        let aimed = self.config.aimed_steering;
        let mut s: f64 = if aimed && work.slope > 0.0 {
            (aim / (work.slope * dist)).min(1.0)
        } else {
            1.0
        };
        let mut first = aimed;
        for _ in 0..30 {
            // A point between two configurations within the ranges may round past a limit
            // (`a + 1·(b − a)` may differ from `b` in its last bit): it is held within them,
            // since a waypoint past a limit by one unit in the last place fails a strict
            // bounds check elsewhere (MoveIt's, with its default margin of 0).
            let steps = work.q_new.iter_mut().zip(from).zip(target);
            for (((q, a), b), axis) in steps.zip(self.chain.free_axes()) {
                *q = axis.range.clamp(a + s * (b - a));
            }
            self.chain.fk(&work.q_new, &mut work.frames);
            let m = metric(
                tree.positions(near),
                &work.frames.positions,
                from,
                &work.q_new,
                self.config.lambda,
            );
            work.slope = m / (s * dist);
            if first && s < 1.0 && m < STEER_SHORT * self.config.l_max {
                first = false;
                s = (s * aim / m).min(1.0);
                continue;
            }
            first = false;
            if m <= self.config.l_max {
                return (s * dist > 1e-9).then_some(s == 1.0);
            }
            s *= (aim / m).min(0.7);
        }
        None
    }

    /// Tries to add the steered candidate as a child of `near`. With `join`, `target` is a node
    /// of another tree: when it is one step away, only the edge to it is checked and nothing is
    /// added ([`Step::Arrived`]).
    fn extend(
        &self,
        tree: &mut Tree,
        near: u32,
        target: &[f64],
        join: bool,
        work: &mut Work,
        scratch: &mut Scratch,
    ) -> Step {
        if join && distance(tree.config(near), target) < 1e-9 {
            return Step::Arrived;
        }
        let Some(whole) = self.steer(tree, near, target, work) else {
            return Step::Blocked;
        };
        if join && whole {
            return if self
                .checker
                .edge_free(self.chain, tree.config(near), target, scratch)
            {
                Step::Arrived
            } else {
                Step::Blocked
            };
        }
        // A checker that proves the whole step (its end included) needs no separate node
        // check of the end: the decision is the same.
        // `work.frames` holds the kinematics of `q_new` from steering.
        if (!self.checker.edge_checks_end()
            && !self
                .checker
                .check_node(self.chain, &work.q_new, Some(&work.frames), scratch))
            || !self.checker.check_edge(
                self.chain,
                tree.config(near),
                &work.q_new,
                Some(&work.frames),
                scratch,
            )
        {
            return Step::Blocked;
        }
        Step::Added(tree.push(&work.q_new, &work.frames, near))
    }

    /// Marks the tasks within tolerance of node `node`'s end effector, and whose orientation
    /// constraint its TCP rotation satisfies, as reached by it; true when there was one.
    fn mark_reached(&self, tree: &Tree, node: u32, reached: &mut [Option<u32>]) -> bool {
        let ee = tree.end_effector(node);
        let mut any = false;
        for (j, (r, t)) in reached.iter_mut().zip(self.tasks).enumerate() {
            if r.is_none()
                && self.within_tolerance(&ee, t)
                && self.orientation(j).holds(tree.tcp_rotation(node))
            {
                debug_assert!(
                    (t - self.chain.base().translation.vector).coords.norm()
                        <= self.chain.reach_bound() + self.config.goal_tolerance + 1e-9,
                    "a task beyond the reach bound was reached"
                );
                *r = Some(node);
                any = true;
            }
        }
        any
    }

    fn within_tolerance(&self, ee: &Point3<f64>, task: &Point3<f64>) -> bool {
        (ee - task).norm_squared() <= self.config.goal_tolerance * self.config.goal_tolerance
    }

    /// Extends `tree` greedily from `node` toward `target` for up to [`CONNECT_STEPS`] steps,
    /// until blocked or (with `join`, `target` being a node of another tree) arrived. With
    /// `reached`, every new node is marked as reaching the tasks within its tolerance, and the
    /// extension stops once task `stop_at` is reached. Returns the last node and whether it
    /// arrived.
    #[allow(clippy::too_many_arguments)]
    fn connect(
        &self,
        tree: &mut Tree,
        mut node: u32,
        target: &[f64],
        join: bool,
        mut reached: Option<&mut [Option<u32>]>,
        stop_at: Option<usize>,
        work: &mut Work,
        scratch: &mut Scratch,
    ) -> (u32, bool) {
        for _ in 0..CONNECT_STEPS {
            match self.extend(tree, node, target, join, work, scratch) {
                Step::Added(n) => {
                    node = n;
                    if let Some(r) = reached.as_deref_mut() {
                        if self.mark_reached(tree, n, r) && stop_at.is_some_and(|j| r[j].is_some())
                        {
                            break;
                        }
                    }
                }
                Step::Arrived => return (node, true),
                Step::Blocked => break,
            }
        }
        (node, false)
    }

    /// Grafts backward tree `gi` onto the forward tree, its node `at` linked to forward node
    /// `onto`, marks the tasks its nodes reach (its own task at least: its root is on it), and
    /// retires it.
    fn graft(&self, s: &mut Search, gi: usize, at: u32, onto: u32) {
        let mut g = s.goals.swap_remove(gi);
        let offset = s.tree.graft(&g.tree, at, onto);
        for k in offset..s.tree.len() as u32 {
            self.mark_reached(&s.tree, k, &mut s.reached);
        }
        g.tree.clear();
        s.spare.push(g.tree);
        s.joins += 1;
    }

    /// A goal-biased iteration: picks an unreached task, takes the node whose end effector is
    /// nearest to it, computes a goal configuration by damped-least-squares steps from there
    /// and extends greedily toward it. When that node was already tried for that task (its IK
    /// goal and steps would only repeat), the IK starts instead from a configuration sampled
    /// uniformly in the ranges: another arm posture. A posture that does not reach the task or
    /// collides is dropped; one that does becomes the root of a backward tree while the task has
    /// fewer than `postures`, and the forward tree grows toward it from its node nearest in
    /// actuation space.
    fn toward_task(&self, s: &mut Search, rng: &mut ChaCha8Rng, scratch: &mut Scratch) {
        let chain = self.chain;
        s.unreached.clear();
        s.unreached
            .extend((0..s.reached.len()).filter(|&j| s.reached[j].is_none() && !s.beyond[j]));
        let j = s.unreached[rng.random_range(0..s.unreached.len())];
        let target = self.tasks[j];
        let mut node = s.tree.nearest_end_effector(&target);
        let restart = !s.tried.insert((node, j));
        let work = &mut s.work;
        let ik_start: &[f64] = if restart {
            chain.sample_config(rng, &mut work.q_new);
            &work.q_new
        } else {
            s.tree.config(node)
        };
        let orientation = self.orientation(j);
        dls_oriented(
            chain,
            ik_start,
            &target,
            &orientation,
            self.config.orientation_weight,
            self.config.ik_steps,
            0.25 * self.config.goal_tolerance,
            &mut work.ik,
        );
        work.q_goal.copy_from_slice(&work.ik.q);
        let goal = std::mem::take(&mut work.q_goal);
        let mut join = false;
        if restart {
            chain.fk(&goal, &mut work.frames);
            if !self.within_tolerance(&work.frames.end_effector(), &target)
                || !orientation.holds(work.frames.tcp_rotation())
                || !self.checker.node_free(chain, &goal, scratch)
            {
                work.q_goal = goal;
                return;
            }
            if s.goals.iter().filter(|g| g.task == j).count() < self.config.postures {
                let mut t = s.spare.pop().unwrap_or_else(|| Tree::new(chain));
                t.push(&goal, &work.frames, 0);
                s.goals.push(GoalTree { task: j, tree: t });
                join = true;
            }
            node = s.tree.nearest_config(&goal);
        }
        let (last, arrived) = self.connect(
            &mut s.tree,
            node,
            &goal,
            join,
            Some(&mut s.reached),
            Some(j),
            work,
            scratch,
        );
        s.work.q_goal = goal;
        if arrived {
            self.graft(s, s.goals.len() - 1, 0, last);
        }
    }

    /// An exploration iteration: samples a configuration uniformly in the ranges and extends
    /// the nearest node (actuation-space distance) of the forward tree one step toward it. While
    /// backward trees exist, every other such iteration grows a backward tree instead (chosen at
    /// random), and after either step the other side tries to join the new node greedily; a
    /// join grafts the backward tree onto the forward one.
    fn explore(&self, s: &mut Search, rng: &mut ChaCha8Rng, scratch: &mut Scratch) {
        self.chain.sample_config(rng, &mut s.work.q_goal);
        let sample = std::mem::take(&mut s.work.q_goal);
        if s.goals.is_empty() || !s.backward_turn {
            let near = s.tree.nearest_config(&sample);
            let step = self.extend(&mut s.tree, near, &sample, false, &mut s.work, scratch);
            if let Step::Added(n) = step {
                self.mark_reached(&s.tree, n, &mut s.reached);
                if !s.goals.is_empty() {
                    let gi = rng.random_range(0..s.goals.len());
                    s.work.q_join.copy_from_slice(s.tree.config(n));
                    let join = std::mem::take(&mut s.work.q_join);
                    let g = &mut s.goals[gi].tree;
                    let from = g.nearest_config(&join);
                    let (last, arrived) =
                        self.connect(g, from, &join, true, None, None, &mut s.work, scratch);
                    s.work.q_join = join;
                    if arrived {
                        self.graft(s, gi, last, n);
                    }
                }
            }
        } else {
            let gi = rng.random_range(0..s.goals.len());
            let g = &mut s.goals[gi].tree;
            let near = g.nearest_config(&sample);
            if let Step::Added(m) = self.extend(g, near, &sample, false, &mut s.work, scratch) {
                s.work.q_join.copy_from_slice(g.config(m));
                let join = std::mem::take(&mut s.work.q_join);
                let from = s.tree.nearest_config(&join);
                let (last, arrived) = self.connect(
                    &mut s.tree,
                    from,
                    &join,
                    true,
                    Some(&mut s.reached),
                    None,
                    &mut s.work,
                    scratch,
                );
                s.work.q_join = join;
                if arrived {
                    self.graft(s, gi, m, last);
                }
            }
        }
        s.backward_turn = !s.backward_turn;
        s.work.q_goal = sample;
    }

    /// For each task, whether it lies farther from the base origin than
    /// [`Chain::reach_bound`] plus the goal tolerance, or asks for an orientation the chain can
    /// never take ([`super::feasible::impossible_orientation`]): no configuration reaches it.
    fn beyond_reach(&self) -> Vec<bool> {
        let origin = Point3::from(self.chain.base().translation.vector);
        let limit = self.chain.reach_bound() + self.config.goal_tolerance;
        self.tasks
            .iter()
            .enumerate()
            .map(|(j, t)| {
                (t - origin).norm() > limit * (1.0 + 1e-12) + 1e-12
                    || super::feasible::impossible_orientation(self.chain, &self.orientation(j))
                        .is_some()
            })
            .collect()
    }

    /// Grows the forward tree from home until every task is reached (every task within the
    /// chain's reach bound: the others cannot be, see [`Chain::reach_bound`]), for up to
    /// `config.max_iterations` iterations, or up to `budget_growth` times as many while an
    /// unreached task has a backward tree ([`budgets`]: both at most
    /// [`crate::limits::iteration_cap`] of the design's axes and IK steps; a collision-free posture
    /// on the task is known, so more work is likely to pay), and within the time cap if set.
    /// Each iteration is, with probability `goal_bias`, a goal-biased one: greedy extensions
    /// toward IK goals of an unreached task, whose collision-free postures on the task root the
    /// backward trees (up to `postures` per task). Otherwise it is an exploration one: a uniform
    /// sample that the forward tree, or every other time a backward tree, grows toward, and a
    /// greedy attempt of the other side to join the new node; a join grafts the backward tree
    /// onto the forward one. Every new edge passes `edge_free`, and every new node `node_free`
    /// (unless the checker proves a step's end with the step, [`EdgeChecker::edge_checks_end`]).
    /// Deterministic for a given `rng` state.
    pub fn grow(&self, rng: &mut ChaCha8Rng, scratch: &mut Scratch) -> Growth {
        let chain = self.chain;
        let mut s = Search {
            tree: Tree::new(chain),
            reached: vec![None; self.tasks.len()],
            beyond: self.beyond_reach(),
            goals: Vec::new(),
            spare: Vec::new(),
            tried: HashSet::new(),
            unreached: Vec::with_capacity(self.tasks.len()),
            backward_turn: false,
            joins: 0,
            work: Work {
                frames: chain.frames(),
                q_new: vec![0.0; chain.dof()],
                q_goal: vec![0.0; chain.dof()],
                q_join: vec![0.0; chain.dof()],
                ik: IkWork::new(chain),
                slope: 0.0,
            },
        };
        s.work.ik.hold_limits = self.config.ik_hold_limits;
        let home = chain.home().to_vec();
        if !self.checker.node_free(chain, &home, scratch) {
            return Growth {
                tree: s.tree,
                reached: s.reached,
                iterations: 0,
                joins: 0,
                home_blocked: true,
                work_limited: false,
                node_limited: false,
                tests_limited: false,
                fk_limited: false,
                interrupted: false,
            };
        }
        chain.fk(&home, &mut s.work.frames);
        s.tree.push(&home, &s.work.frames, 0);
        self.mark_reached(&s.tree, 0, &mut s.reached);
        let (base, grown) = budgets(
            self.config.max_iterations,
            self.config.budget_growth,
            chain.dof(),
            self.config.ik_steps,
        );
        let start = Instant::now();
        let mut iterations = 0;
        let casts_before = scratch.stats.casts;
        let mut work_limited = false;
        let mut node_limited = false;
        let node_cap = self.node_cap;
        // Every node or edge check tests each body and each checked self pair.
        let mut tests_limited = false;
        let per_check = (scratch.body.len() + scratch.body.self_pairs().len()).max(1) as u64;
        let check_cap = self.tests_cap / per_check;
        let checks_before = scratch.stats.nodes + scratch.stats.edges;
        let mut interrupted = false;
        let (mut fk_limited, fk_before) = (false, scratch.stats.fk);
        while s
            .reached
            .iter()
            .zip(&s.beyond)
            .any(|(r, &b)| r.is_none() && !b)
        {
            let budget = if s.goals.is_empty() { base } else { grown };
            if iterations >= budget {
                break;
            }
            if let Some(limit) = self.config.time_limit {
                if start.elapsed().as_secs_f64() > limit {
                    break;
                }
            }
            // `ccd`'s cost per edge grows with the motion and the bodies (up to 64 sub-steps
            // of every body and self pair): its work, counted in shape casts, is capped.
            if scratch.stats.casts - casts_before >= self.cast_cap {
                work_limited = true;
                break;
            }
            // Short unblocked steps add many nodes per iteration, and each search for the
            // nearest node scans a tree: the nodes are capped too.
            if s.tree.len() + s.goals.iter().map(|g| g.tree.len()).sum::<usize>() >= node_cap {
                node_limited = true;
                break;
            }
            if scratch.stats.nodes + scratch.stats.edges - checks_before >= check_cap {
                tests_limited = true;
                break;
            }
            if scratch.stats.fk - fk_before >= self.fk_cap {
                fk_limited = true;
                break;
            }
            if self.interrupt.is_some_and(|f| f.load(Ordering::Relaxed)) {
                interrupted = true;
                break;
            }
            iterations += 1;
            if chain.dof() == 0 {
                break;
            }
            if rng.random::<f64>() < self.config.goal_bias {
                self.toward_task(&mut s, rng, scratch);
            } else {
                self.explore(&mut s, rng, scratch);
            }
            // A task reached by the forward tree retires its backward trees.
            let mut k = 0;
            while k < s.goals.len() {
                if s.reached[s.goals[k].task].is_some() {
                    let mut g = s.goals.swap_remove(k);
                    g.tree.clear();
                    s.spare.push(g.tree);
                } else {
                    k += 1;
                }
            }
        }
        Growth {
            tree: s.tree,
            reached: s.reached,
            iterations,
            joins: s.joins,
            home_blocked: false,
            work_limited,
            node_limited,
            tests_limited,
            fk_limited,
            interrupted,
        }
    }
}

/// The iteration budgets of a planner run on a design of `axes` free axes: the base budget
/// `max_iterations` and the grown one, `budget_growth` times as many, both within
/// [`iteration_cap`] of the axes and inverse-kinematics steps per extension (100,000
/// iterations up to 24 axes and 20 steps, fewer beyond).
pub fn budgets(
    max_iterations: usize,
    budget_growth: usize,
    axes: usize,
    ik_steps: usize,
) -> (usize, usize) {
    let cap = iteration_cap(axes, ik_steps);
    let base = max_iterations.min(cap);
    let grown = base.saturating_mul(budget_growth).min(cap).max(base);
    (base, grown)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::CheckerKind;
    use crate::kinematics::{Axis, Dh, Link, Range};
    use nalgebra::IsometryMatrix3;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// The linear scan (four partial sums per point) returns the index a plain scan returns
        /// (the first of the nearest points), or one at the same distance up to rounding, at
        /// every dimension from 1 to 13 and with duplicate points.
        #[test]
        fn nearest_linear_matches_a_full_scan(
            dim in 1usize..14,
            n in 1usize..200,
            seed in any::<u64>(),
        ) {
            use rand::SeedableRng;
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut points: Vec<f64> = (0..n * dim).map(|_| rng.random_range(-3.0..3.0)).collect();
            // Repeat some points, so that ties occur.
            for k in (dim..points.len()).step_by(7 * dim) {
                let (head, rest) = points.split_at_mut(k);
                rest[..dim].copy_from_slice(&head[..dim]);
            }
            let q: Vec<f64> = if seed % 3 == 0 {
                points[..dim].to_vec()
            } else {
                (0..dim).map(|_| rng.random_range(-3.0..3.0)).collect()
            };
            let mut best = (f64::INFINITY, 0);
            for (i, c) in points.chunks_exact(dim).enumerate() {
                let d: f64 = c.iter().zip(&q).map(|(a, b)| (a - b) * (a - b)).sum();
                if d < best.0 {
                    best = (d, i);
                }
            }
            let found = nearest_linear(&points, &q);
            let d = |i: usize| -> f64 {
                points[i * dim..(i + 1) * dim].iter().zip(&q).map(|(a, b)| (a - b) * (a - b)).sum()
            };
            // The same point, or (rounding of the sums differs) one at the same distance.
            prop_assert!(found == best.1 || (d(found) - best.0).abs() <= 1e-12 * (1.0 + best.0));
            prop_assert!(found <= best.1 || (d(found) - best.0).abs() <= 1e-12 * (1.0 + best.0));
        }

        /// The scan four nodes at a time returns exactly the index the linear scan returns (the
        /// first of the nearest), at every dimension from 1 to 30, for every tree size (a last
        /// block part empty), with repeated points and queries on a point.
        #[test]
        fn nearest_blocked_is_the_linear_scan(
            dim in 1usize..31,
            n in 0usize..150,
            seed in any::<u64>(),
        ) {
            use rand::SeedableRng;
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            // Coarse values for half the seeds, so that sums tie often; else any.
            let mut points: Vec<f64> = (0..n * dim)
                .map(|_| match seed % 2 {
                    0 => f64::from(rng.random_range(-4i32..5)) * 0.5,
                    _ => rng.random_range(-3.0..3.0),
                })
                .collect();
            for k in (dim..points.len()).step_by(5 * dim) {
                let (head, rest) = points.split_at_mut(k);
                rest[..dim].copy_from_slice(&head[k - dim..k]);
            }
            let q: Vec<f64> = if n > 0 && seed % 3 == 0 {
                points[(n / 2) * dim..(n / 2 + 1) * dim].to_vec()
            } else {
                (0..dim).map(|_| rng.random_range(-3.0..3.0)).collect()
            };
            let mut blocks = Vec::new();
            for (i, p) in points.chunks_exact(dim).enumerate() {
                block_push(&mut blocks, i, p);
            }
            prop_assert_eq!(blocks.len(), n.div_ceil(LANES) * LANES * dim);
            let linear = nearest_linear(&points, &q);
            prop_assert_eq!(nearest_blocked(&blocks, &q), linear);
            let (i, d) = nearest_blocked_by(&blocks, &q);
            prop_assert_eq!(i, linear);
            // The same sum bit for bit (what near ties are decided on).
            if n > 0 {
                let sum = squared_distance(&points[i * dim..(i + 1) * dim], &q);
                prop_assert_eq!(d.to_bits(), sum.to_bits());
            }
        }
    }

    /// A planar arm of two unit links turning about z.
    fn arm() -> Chain {
        let mut r = [Range::ZERO; 6];
        r[Axis::Rz.index()] = Range::new(-3.0, 3.0);
        let links = vec![
            Link::from_dh(&Dh::default(), r),
            Link::from_dh(
                &Dh {
                    a: 1.0,
                    ..Dh::default()
                },
                r,
            ),
        ];
        Chain::new(IsometryMatrix3::identity(), &links, 0.01, 1)
    }

    fn push(tree: &mut Tree, chain: &Chain, q: &[f64], parent: u32) -> u32 {
        let mut frames = chain.frames();
        chain.fk(q, &mut frames);
        tree.push(q, &frames, parent)
    }

    #[test]
    fn the_nearest_node_of_a_grown_grafted_and_cleared_tree_is_the_linear_scans() {
        use rand::SeedableRng;
        let chain = arm();
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut q = [0.0; 2];
        let mut grow = |tree: &mut Tree, n: usize, rng: &mut ChaCha8Rng| {
            for _ in 0..n {
                chain.sample_config(rng, &mut q);
                let parent = tree.len().saturating_sub(1) as u32;
                push(tree, &chain, &q, parent);
            }
        };
        let check = |tree: &Tree, rng: &mut ChaCha8Rng| {
            for _ in 0..50 {
                let x = [rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0)];
                assert_eq!(
                    tree.nearest_config(&x) as usize,
                    nearest_linear(&tree.configs, &x)
                );
            }
            assert_eq!(tree.blocks.len(), tree.len().div_ceil(LANES) * LANES * 2);
        };
        let (mut main, mut other) = (Tree::new(&chain), Tree::new(&chain));
        grow(&mut main, 7, &mut rng);
        grow(&mut other, 6, &mut rng);
        check(&main, &mut rng);
        main.graft(&other, 3, 2);
        check(&main, &mut rng);
        grow(&mut main, 9, &mut rng);
        check(&main, &mut rng);
        main.clear();
        assert_eq!(main.nearest_config(&[0.5, 0.5]), 0);
        grow(&mut main, 5, &mut rng);
        check(&main, &mut rng);
    }

    #[test]
    fn a_grafted_tree_is_re_rooted_so_every_node_leads_home() {
        let chain = arm();
        let mut main = Tree::new(&chain);
        push(&mut main, &chain, &[0.0, 0.0], 0);
        push(&mut main, &chain, &[0.1, 0.0], 0);
        // Backward tree: root 0 at the goal, 1 and 3 its children, 2 a child of 1.
        let mut back = Tree::new(&chain);
        push(&mut back, &chain, &[0.5, 0.5], 0);
        push(&mut back, &chain, &[0.4, 0.3], 0);
        push(&mut back, &chain, &[0.2, 0.1], 1);
        push(&mut back, &chain, &[0.6, 0.7], 0);
        let offset = main.graft(&back, 2, 1);
        assert_eq!(offset, 2);
        assert_eq!(main.len(), 6);
        let to_goal = main.path_to(offset);
        assert_eq!(
            to_goal,
            vec![
                vec![0.0, 0.0],
                vec![0.1, 0.0],
                vec![0.2, 0.1],
                vec![0.4, 0.3],
                vec![0.5, 0.5]
            ]
        );
        let to_side = main.path_to(offset + 3);
        assert_eq!(to_side[..5], to_goal[..]);
        assert_eq!(to_side[5], vec![0.6, 0.7]);
        assert_eq!(
            main.end_effector(offset + 3),
            chain.end_effector(&[0.6, 0.7])
        );
        assert_eq!(main.positions(offset + 1).len(), chain.link_count());
    }

    #[test]
    fn grafting_at_the_root_links_the_root_itself() {
        let chain = arm();
        let mut main = Tree::new(&chain);
        push(&mut main, &chain, &[0.0, 0.0], 0);
        let mut back = Tree::new(&chain);
        push(&mut back, &chain, &[0.3, 0.0], 0);
        push(&mut back, &chain, &[0.6, 0.0], 0);
        let offset = main.graft(&back, 0, 0);
        assert_eq!(
            main.path_to(offset + 1),
            vec![vec![0.0, 0.0], vec![0.3, 0.0], vec![0.6, 0.0]]
        );
    }

    /// The bundled paper-2d scenario, its largest design's chain, its collision scene and a
    /// task out of reach of every collision-free posture (the centre of its first obstacle),
    /// on which a run spends its whole budget.
    fn task_inside_an_obstacle() -> (
        crate::Scenario,
        Chain,
        std::sync::Arc<crate::collision::CollisionScene>,
        [Point3<f64>; 1],
    ) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios/paper-2d.toml");
        let s = crate::Scenario::load(&path).unwrap();
        let chain = s.space.largest().chain();
        let scene = std::sync::Arc::new(crate::collision::CollisionScene::new(&s.workspace));
        let t = s.workspace.obstacles[0].pose().translation;
        let tasks = [Point3::new(t.x, t.y, t.z)];
        (s, chain, scene, tasks)
    }

    /// A run of 300 iterations (its budget not grown) toward [`task_inside_an_obstacle`] with
    /// the checker `kind`, its planner settings changed by `tune` and its planner by `cap`
    /// (one of the work caps): what it grew, with the checker's counters.
    fn capped_run(
        kind: crate::collision::CheckerKind,
        tune: impl Fn(&mut PlannerConfig),
        cap: impl for<'r> Fn(Rrt<'r>) -> Rrt<'r>,
    ) -> (Growth, crate::collision::EdgeStats) {
        use crate::collision::{make_checker, BodyModel};
        let (s, chain, scene, tasks) = task_inside_an_obstacle();
        let checker = make_checker(kind, scene, BodyModel::Capsules);
        let mut config = s.planner.clone();
        config.checker = kind;
        config.max_iterations = 300;
        config.budget_growth = 1;
        tune(&mut config);
        let mut scratch = Scratch::new(&chain);
        let rrt = cap(Rrt::new(&chain, checker.as_ref(), &config, &tasks));
        let mut rng = rand::SeedableRng::seed_from_u64(4);
        let growth = rrt.grow(&mut rng, &mut scratch);
        (growth, scratch.stats)
    }

    /// `ccd`'s work is capped: a run whose task lies inside an obstacle (so it would spend its
    /// whole budget) stops once its shape casts reach the cap, soon after (the cap is checked
    /// before each iteration, whose extensions may check several edges), and says so; with
    /// the real cap the same run spends its iteration budget.
    #[test]
    fn the_ccd_checkers_work_is_capped() {
        let run = |cap: u64| {
            let (growth, stats) = capped_run(CheckerKind::Ccd, |_| {}, |r| r.with_cast_cap(cap));
            (growth, stats.casts, stats.edges)
        };
        let (whole, casts, edges) = run(crate::limits::MAX_CCD_CASTS);
        assert!(!whole.work_limited);
        assert_eq!(whole.iterations, 300);
        assert!(whole.reached[0].is_none());
        let cap = casts / 3;
        let (capped, spent, _) = run(cap);
        assert!(capped.work_limited);
        assert!(capped.iterations < 300, "{}", capped.iterations);
        // The check comes before each iteration: a few edges' casts beyond the cap at most.
        let per_edge = casts / edges.max(1);
        assert!(
            spent >= cap && spent < cap + 50 * per_edge.max(1),
            "{spent} vs {cap}"
        );
    }

    /// The trees' nodes are capped: with a huge `lambda` every step is tiny and never blocked,
    /// so each iteration adds up to [`CONNECT_STEPS`] nodes; such a run stops once its trees
    /// hold the cap (a connect's nodes beyond it at most) and says so, where the same run with
    /// the scenario's `lambda` spends its iteration budget without coming near the cap.
    #[test]
    fn the_trees_nodes_are_capped() {
        let run = |lambda: f64| {
            let tune = |c: &mut PlannerConfig| c.lambda = lambda;
            capped_run(CheckerKind::Certified, tune, |r| r.with_node_cap(1_000)).0
        };
        let tiny = run(1e6);
        assert!(tiny.node_limited);
        assert!(tiny.iterations < 300, "{}", tiny.iterations);
        assert!(
            (1_000..1_000 + 2 * CONNECT_STEPS).contains(&tiny.tree.len()),
            "{}",
            tiny.tree.len()
        );
        let plain = run(task_inside_an_obstacle().0.planner.lambda);
        assert!(!plain.node_limited);
        assert_eq!(plain.iterations, 300);
        assert!(plain.tree.len() < 1_000, "{}", plain.tree.len());
        assert_eq!(crate::limits::node_cap(24), crate::limits::MAX_TREE_NODES);
        assert_eq!(crate::limits::node_cap(384), 6_250);
    }

    /// The body tests are capped: with a cap of 100 checks' tests (bodies and checked self
    /// pairs per check), a run toward a task inside an obstacle stops after about 100 node
    /// and edge checks (the cap is checked before each iteration, whose extensions may check
    /// up to [`CONNECT_STEPS`] edges) and says so; with the real cap it spends its budget.
    #[test]
    fn the_body_tests_are_capped() {
        let (_, chain, _, _) = task_inside_an_obstacle();
        let scratch = Scratch::new(&chain);
        let per_check = (scratch.body.len() + scratch.body.self_pairs().len()) as u64;
        let run = |cap: u64| {
            let tests = cap * per_check;
            let (growth, stats) =
                capped_run(CheckerKind::Certified, |_| {}, |r| r.with_tests_cap(tests));
            (growth, stats.nodes + stats.edges)
        };
        let (whole, checks) = run(crate::limits::MAX_BODY_TESTS);
        assert!(!whole.tests_limited);
        assert_eq!(whole.iterations, 300);
        assert!(checks > 200, "{checks}");
        let (capped, checks) = run(100);
        assert!(capped.tests_limited);
        assert!(capped.iterations < 300, "{}", capped.iterations);
        assert!(
            (100..100 + 2 * CONNECT_STEPS as u64).contains(&checks),
            "{checks}"
        );
    }

    /// The checker's kinematics evaluations are capped: with a cap of 100, a run toward a
    /// task inside an obstacle stops soon after 100 (the cap is checked before each
    /// iteration) and says so; with the real cap it spends its budget.
    #[test]
    fn the_checkers_kinematics_are_capped() {
        let run = |cap: u64| {
            let (growth, stats) =
                capped_run(CheckerKind::Certified, |_| {}, |r| r.with_fk_cap(cap));
            (growth, stats.fk)
        };
        let (whole, fk) = run(crate::limits::MAX_CHECK_FK);
        assert!(!whole.fk_limited);
        assert_eq!(whole.iterations, 300);
        assert!(fk > 200, "{fk}");
        let (capped, fk) = run(100);
        assert!(capped.fk_limited);
        assert!(capped.iterations < 300, "{}", capped.iterations);
        assert!((100..200).contains(&fk), "{fk}");
    }

    /// Every node lies within the axis ranges, to the last bit, also where the ranges' limits
    /// are values that an interpolation toward them overshoots by rounding: the paper-2d
    /// design with each moving axis cut to an odd range, over 10 planner seeds.
    #[test]
    fn every_node_lies_within_the_ranges() {
        use crate::collision::{make_checker, BodyModel, CheckerKind, CollisionScene};
        use std::sync::Arc;
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios/paper-2d.toml");
        let s = crate::Scenario::load(&path).unwrap();
        let mut design = s.space.largest();
        for (i, link) in design.links.iter_mut().enumerate() {
            for r in link.axes.0.iter_mut().filter(|r| r.max > r.min) {
                let f = 1.0 + i as f64 / 7.0;
                (r.min, r.max) = (-0.026370230686744066 * f, 0.02571272691296143 * f);
            }
        }
        let chain = design.chain();
        let scene = Arc::new(CollisionScene::new(&s.workspace));
        let checker = make_checker(CheckerKind::Certified, scene, BodyModel::Capsules);
        let mut config = s.planner.clone();
        config.max_iterations = 200;
        config.budget_growth = 1;
        let (mut nodes, mut at_limit) = (0, 0);
        for seed in 0..10 {
            let mut scratch = Scratch::new(&chain);
            let rrt = Rrt::new(&chain, checker.as_ref(), &config, &s.workspace.tasks);
            let mut rng = rand::SeedableRng::seed_from_u64(seed);
            let growth = rrt.grow(&mut rng, &mut scratch);
            for i in 0..growth.tree.len() as u32 {
                for (q, axis) in growth.tree.config(i).iter().zip(chain.free_axes()) {
                    assert!(
                        axis.range.min <= *q && *q <= axis.range.max,
                        "seed {seed}, node {i}: {q:e} outside [{:e}, {:e}]",
                        axis.range.min,
                        axis.range.max
                    );
                    at_limit += usize::from(*q == axis.range.min || *q == axis.range.max);
                }
                nodes += 1;
            }
        }
        assert!(
            nodes > 100 && at_limit > 0,
            "{nodes} nodes, {at_limit} values at a limit"
        );
    }

    #[test]
    fn budgets_shrink_with_the_axes_beyond_24() {
        // Up to 24 axes: the configured budget, grown up to 100,000.
        assert_eq!(budgets(2_000, 5, 8, 20), (2_000, 10_000));
        assert_eq!(budgets(100_000, 5, 24, 20), (100_000, 100_000));
        assert_eq!(budgets(30_000, 100, 2, 20), (30_000, 100_000));
        // 384 axes (64 links of six): at most 2,400,000 / 384 = 6,250 iterations.
        assert_eq!(budgets(100_000, 5, 384, 20), (6_250, 6_250));
        assert_eq!(budgets(2_000, 5, 384, 20), (2_000, 6_250));
        assert_eq!(budgets(2_000, 1, 48, 20), (2_000, 2_000));
        assert_eq!(budgets(60_000, 2, 48, 20), (50_000, 50_000));
        // Inverse-kinematics steps beyond 20 lower the cap in proportion.
        assert_eq!(budgets(100_000, 5, 24, 10_000), (200, 200));
        assert_eq!(budgets(2_000, 5, 24, 100), (2_000, 10_000));
        assert_eq!(budgets(100_000, 1, 8, 1), (100_000, 100_000));
    }
}
