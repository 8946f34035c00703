//! A goal-biased RRT in actuation space, grown from home, that serves every task point with one
//! tree (paper §II-D, Eq. 10; the planner of §III).

use super::ik::{dls, IkWork};
use super::PlannerConfig;
use crate::collision::{EdgeChecker, Scratch};
use crate::kinematics::{Chain, Frames};
use nalgebra::Point3;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use std::collections::HashSet;
use std::time::Instant;

/// Greedy steps toward an inverse-kinematics goal in one goal-biased iteration.
pub const CONNECT_STEPS: usize = 25;

/// The tree: configurations, their joint positions `f(a)` and end effectors, and parents.
#[derive(Clone, Debug)]
pub struct Tree {
    dof: usize,
    links: usize,
    configs: Vec<f64>,
    positions: Vec<Point3<f64>>,
    ee: Vec<Point3<f64>>,
    parent: Vec<u32>,
}

impl Tree {
    fn new(chain: &Chain) -> Self {
        Tree {
            dof: chain.dof(),
            links: chain.link_count(),
            configs: Vec::new(),
            positions: Vec::new(),
            ee: Vec::new(),
            parent: Vec::new(),
        }
    }

    fn push(&mut self, q: &[f64], frames: &Frames, parent: u32) -> u32 {
        self.configs.extend_from_slice(q);
        self.positions.extend_from_slice(&frames.positions);
        self.ee.push(frames.end_effector());
        self.parent.push(parent);
        (self.parent.len() - 1) as u32
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

    /// End effector of node `i`.
    pub fn end_effector(&self, i: u32) -> Point3<f64> {
        self.ee[i as usize]
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

    /// Nearest node to `q` in actuation space (Euclidean), by linear scan; see
    /// [`nearest_linear`].
    pub fn nearest_config(&self, q: &[f64]) -> u32 {
        nearest_linear(&self.configs, q) as u32
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
/// Measured against a k-d tree (kiddo) by `benches/nearest.rs`; see the README for the figures
/// and the choice.
pub fn nearest_linear(points: &[f64], q: &[f64]) -> usize {
    let dim = q.len().max(1);
    let mut best = (f64::INFINITY, 0);
    for (i, c) in points.chunks_exact(dim).enumerate() {
        // Four independent partial sums let the additions overlap in the pipeline.
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
        let d = (acc[0] + acc[1]) + (acc[2] + acc[3]);
        if d < best.0 {
            best = (d, i);
        }
    }
    best.1
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
    /// True when the home configuration is not collision-free.
    pub home_blocked: bool,
}

impl Growth {
    /// The outcome when the home configuration is blocked before planning starts: an empty
    /// tree, nothing reached.
    pub fn blocked(chain: &Chain, tasks: usize) -> Self {
        Growth {
            tree: Tree::new(chain),
            reached: vec![None; tasks],
            iterations: 0,
            home_blocked: true,
        }
    }
}

/// Reused buffers of the planner.
struct Work {
    frames: Frames,
    q_new: Vec<f64>,
    q_goal: Vec<f64>,
    ik: IkWork,
}

/// `‖f(b) − f(a)‖ + λ‖b − a‖` (paper Eq. 10) from stored joint positions.
fn metric(fa: &[Point3<f64>], fb: &[Point3<f64>], a: &[f64], b: &[f64], lambda: f64) -> f64 {
    let df: f64 = fa.iter().zip(fb).map(|(p, q)| (q - p).norm_squared()).sum();
    let da: f64 = a.iter().zip(b).map(|(x, y)| (y - x) * (y - x)).sum();
    df.sqrt() + lambda * da.sqrt()
}

/// The RRT planner for one chain and one checker.
pub struct Rrt<'a> {
    chain: &'a Chain,
    checker: &'a dyn EdgeChecker,
    config: &'a PlannerConfig,
    tasks: &'a [Point3<f64>],
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
        }
    }

    /// Steers from node `near` toward `target`, cutting the step until the metric of paper
    /// Eq. 10 is within `L_max`; the candidate is left in `work.q_new` with its frames in
    /// `work.frames`. Returns false when no progress is possible.
    fn steer(&self, tree: &Tree, near: u32, target: &[f64], work: &mut Work) -> bool {
        let from = tree.config(near);
        let dist: f64 = from
            .iter()
            .zip(target)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        if dist < 1e-9 {
            return false;
        }
        let mut s: f64 = 1.0;
        for _ in 0..30 {
            for ((q, a), b) in work.q_new.iter_mut().zip(from).zip(target) {
                *q = a + s * (b - a);
            }
            self.chain.fk(&work.q_new, &mut work.frames);
            let m = metric(
                tree.positions(near),
                &work.frames.positions,
                from,
                &work.q_new,
                self.config.lambda,
            );
            if m <= self.config.l_max {
                return s * dist > 1e-9;
            }
            // The metric grows about linearly with the step: aim just inside the bound.
            s *= (0.95 * self.config.l_max / m).min(0.7);
        }
        false
    }

    /// Tries to add the steered candidate as a child of `near`.
    fn extend(
        &self,
        tree: &mut Tree,
        near: u32,
        target: &[f64],
        work: &mut Work,
        scratch: &mut Scratch,
    ) -> Option<u32> {
        if !self.steer(tree, near, target, work) {
            return None;
        }
        if !self.checker.node_free(self.chain, &work.q_new, scratch)
            || !self
                .checker
                .edge_free(self.chain, tree.config(near), &work.q_new, scratch)
        {
            return None;
        }
        Some(tree.push(&work.q_new, &work.frames, near))
    }

    fn mark_reached(&self, tree: &Tree, node: u32, reached: &mut [Option<u32>]) -> bool {
        let ee = tree.end_effector(node);
        let tol2 = self.config.goal_tolerance * self.config.goal_tolerance;
        let mut any = false;
        for (r, t) in reached.iter_mut().zip(self.tasks) {
            if r.is_none() && (ee - t).norm_squared() <= tol2 {
                *r = Some(node);
                any = true;
            }
        }
        any
    }

    /// Grows the tree from home for up to `config.max_iterations` iterations (or the time
    /// cap), until every task is reached. Each iteration either (with probability `goal_bias`)
    /// picks an unreached task, takes the node whose end effector is nearest to it, computes a
    /// goal configuration by damped-least-squares steps from there, and extends greedily toward
    /// it (up to [`CONNECT_STEPS`] steps); when that node was already tried for that task (its
    /// IK goal and steps would only repeat), the IK starts instead from a configuration sampled
    /// uniformly in the ranges and the extension from the node nearest (actuation-space
    /// distance) to its solution: another arm posture for the same point. Otherwise the
    /// iteration samples a configuration uniformly in the ranges and extends the nearest node
    /// (actuation-space distance) one step toward it. Every new node passes `node_free` and its
    /// edge `edge_free`. Deterministic for a given `rng` state.
    pub fn grow(&self, rng: &mut ChaCha8Rng, scratch: &mut Scratch) -> Growth {
        let chain = self.chain;
        let mut tree = Tree::new(chain);
        let mut reached = vec![None; self.tasks.len()];
        let mut work = Work {
            frames: chain.frames(),
            q_new: vec![0.0; chain.dof()],
            q_goal: vec![0.0; chain.dof()],
            ik: IkWork::new(chain),
        };
        let home = chain.home().to_vec();
        if !self.checker.node_free(chain, &home, scratch) {
            return Growth {
                tree,
                reached,
                iterations: 0,
                home_blocked: true,
            };
        }
        chain.fk(&home, &mut work.frames);
        tree.push(&home, &work.frames, 0);
        self.mark_reached(&tree, 0, &mut reached);
        let start = Instant::now();
        let mut iterations = 0;
        let mut unreached: Vec<usize> = Vec::with_capacity(self.tasks.len());
        let mut tried: HashSet<(u32, usize)> = HashSet::new();
        while iterations < self.config.max_iterations && reached.iter().any(Option::is_none) {
            if let Some(limit) = self.config.time_limit {
                if start.elapsed().as_secs_f64() > limit {
                    break;
                }
            }
            iterations += 1;
            if chain.dof() == 0 {
                break;
            }
            if rng.random::<f64>() < self.config.goal_bias {
                unreached.clear();
                unreached.extend((0..reached.len()).filter(|&j| reached[j].is_none()));
                let j = unreached[rng.random_range(0..unreached.len())];
                let target = self.tasks[j];
                let mut node = tree.nearest_end_effector(&target);
                // The same start toward the same task would repeat the same IK goal and the
                // same steps: start the IK from a random configuration instead, and grow
                // toward its solution from the node nearest to it in actuation space.
                let restart = !tried.insert((node, j));
                let ik_start: &[f64] = if restart {
                    chain.sample_config(rng, &mut work.q_new);
                    &work.q_new
                } else {
                    tree.config(node)
                };
                dls(
                    chain,
                    ik_start,
                    &target,
                    self.config.ik_steps,
                    0.25 * self.config.goal_tolerance,
                    &mut work.ik,
                );
                work.q_goal.copy_from_slice(&work.ik.q);
                if restart {
                    node = tree.nearest_config(&work.q_goal);
                }
                let goal = std::mem::take(&mut work.q_goal);
                for _ in 0..CONNECT_STEPS {
                    match self.extend(&mut tree, node, &goal, &mut work, scratch) {
                        Some(n) => {
                            node = n;
                            if self.mark_reached(&tree, n, &mut reached) && reached[j].is_some() {
                                break;
                            }
                        }
                        None => break,
                    }
                }
                work.q_goal = goal;
            } else {
                chain.sample_config(rng, &mut work.q_goal);
                let near = tree.nearest_config(&work.q_goal);
                let goal = std::mem::take(&mut work.q_goal);
                if let Some(n) = self.extend(&mut tree, near, &goal, &mut work, scratch) {
                    self.mark_reached(&tree, n, &mut reached);
                }
                work.q_goal = goal;
            }
        }
        Growth {
            tree,
            reached,
            iterations,
            home_blocked: false,
        }
    }
}
