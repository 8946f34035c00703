//! The ground truth for edges: dense sampling of the motion with the exact distances of every
//! robot body to every obstacle and of every checked self pair at every sample. For tests and
//! reports only; the planner never uses it.

use super::body::{Placed, RobotBody};
use super::edge::certified::StepBound;
use super::scene::CollisionScene;
use crate::kinematics::{step_length, Chain};
use nalgebra::{IsometryMatrix3, Point3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Default number of sub-steps of an oracle edge (the samples are `t = i/N`, `i = 0 … N`).
pub const ORACLE_SUBSTEPS: usize = 2000;

/// What the oracle found along an edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OracleVerdict {
    /// True when every sample keeps every body farther than the clearance from every obstacle
    /// and every checked self pair apart.
    pub free: bool,
    /// Smallest body–obstacle distance over the samples.
    pub min_distance: f64,
    /// Smallest distance over the checked self pairs and the samples (`+∞` without pairs).
    pub min_self_distance: f64,
    /// Parameter `t` of the first colliding sample, if any.
    pub first_hit: Option<f64>,
}

/// Judges an edge by sampling it `substeps + 1` times with the exact distances of `body` (the
/// robot body of `chain`). It stops at the first colliding sample.
pub fn judge_edge(
    scene: &CollisionScene,
    chain: &Chain,
    body: &RobotBody,
    from: &[f64],
    to: &[f64],
    substeps: usize,
) -> OracleVerdict {
    let mut frames = chain.frames();
    let mut placed = Placed::default();
    let mut q = vec![0.0; from.len()];
    let mut min_distance = f64::INFINITY;
    let mut min_self_distance = f64::INFINITY;
    for i in 0..=substeps {
        let t = i as f64 / substeps.max(1) as f64;
        for ((qi, a), b) in q.iter_mut().zip(from).zip(to) {
            *qi = a + t * (b - a);
        }
        chain.fk(&q, &mut frames);
        body.place(&frames, &mut placed);
        min_distance = min_distance.min(body.min_obstacle_distance(scene, &frames, &placed));
        min_self_distance = min_self_distance.min(body.min_self_distance(&frames, &placed));
        if min_distance <= scene.clearance() || min_self_distance <= 0.0 {
            return OracleVerdict {
                free: false,
                min_distance,
                min_self_distance,
                first_hit: Some(t),
            };
        }
    }
    OracleVerdict {
        free: true,
        min_distance,
        min_self_distance,
        first_hit: None,
    }
}

/// Bodies and self pairs checked, over all attempts, in the search of [`sample_edges`] for
/// collision-free starts. The bundled scenarios' largest designs check 12 to 108 per attempt,
/// so they get 185,000 attempts or more (10,000 edges come back from each); 64 links of six
/// axes (31,626 pairs) get about 630.
pub const START_CHECK_BUDGET: usize = 20_000_000;

/// How many random starts [`sample_edges`] tries for `count` edges at most: 1,000 per edge and
/// 10,000 more, within [`START_CHECK_BUDGET`] bodies and pairs checked.
pub fn start_attempts(body: &RobotBody, count: usize) -> usize {
    let per_attempt = 1 + body.len() + body.self_pairs().len();
    (1000 * count + 10_000).min(START_CHECK_BUDGET / per_attempt)
}

/// Random edges like the planner's: a start configuration drawn uniformly in the ranges whose
/// body is clear (every body and self pair, by exact distance), steered toward another uniform sample and cut
/// back (by bisection on the step parameter) until the step metric of paper Eq. 10,
/// `‖f(b) − f(a)‖ + λ‖b − a‖`, is at most `l_max`. Deterministic for a seed. Fewer than `count`
/// edges come back when collision-free starts are too rare to find.
pub fn sample_edges(
    scene: &CollisionScene,
    chain: &Chain,
    body: &RobotBody,
    l_max: f64,
    lambda: f64,
    count: usize,
    seed: u64,
) -> Vec<(Vec<f64>, Vec<f64>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut fa = chain.frames();
    let mut fb = chain.frames();
    let mut placed = Placed::default();
    let mut out = Vec::with_capacity(count);
    let draw = |rng: &mut ChaCha8Rng| -> Vec<f64> {
        let mut q = vec![0.0; chain.dof()];
        chain.sample_config(rng, &mut q);
        q
    };
    // Each start is checked with every body and self pair: the attempts are bounded by that
    // work too, so that an arm of thousands of pairs whose starts hardly ever come free does
    // not search for minutes (64 links of six axes: 31,626 pairs, 2.7 ms per attempt).
    let max_attempts = start_attempts(body, count);
    let mut attempts = 0usize;
    while out.len() < count {
        attempts += 1;
        if attempts > max_attempts {
            break; // hardly any collision-free start: return what was found
        }
        let a = draw(&mut rng);
        chain.fk(&a, &mut fa);
        body.place(&fa, &mut placed);
        if body.min_obstacle_distance(scene, &fa, &placed) <= scene.clearance()
            || body.min_self_distance(&fa, &placed) <= 0.0
        {
            continue;
        }
        let target = draw(&mut rng);
        let at = |s: f64| -> Vec<f64> {
            a.iter()
                .zip(&target)
                .map(|(x, y)| x + s * (y - x))
                .collect()
        };
        let mut b = target.clone();
        chain.fk(&b, &mut fb);
        if step_length(&fa, &fb, &a, &b, lambda) > l_max {
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                let c = at(mid);
                chain.fk(&c, &mut fb);
                if step_length(&fa, &fb, &a, &c, lambda) > l_max {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            b = at(lo);
        }
        out.push((a, b));
    }
    out
}

/// How one checker's verdicts compare with the oracle's over a set of edges.
#[derive(Clone, Debug, PartialEq)]
pub struct Agreement {
    /// Checker name.
    pub checker: String,
    /// Edges compared.
    pub edges: usize,
    /// Edges the oracle finds blocked.
    pub blocked: usize,
    /// Edges the checker calls free that the oracle finds blocked (unsafe errors).
    pub false_free: usize,
    /// Edges the checker calls blocked that the oracle finds free (lost motions).
    pub false_blocked: usize,
    /// Mean wall-clock time per `edge_free` call (seconds).
    pub seconds_per_edge: f64,
    /// Mean forward-kinematics evaluations per edge.
    pub fk_per_edge: f64,
}

impl Agreement {
    /// `false_free / blocked` (0 when no edge is blocked).
    pub fn false_free_rate(&self) -> f64 {
        if self.blocked == 0 {
            0.0
        } else {
            self.false_free as f64 / self.blocked as f64
        }
    }

    /// `false_blocked / free` (0 when no edge is free).
    pub fn false_blocked_rate(&self) -> f64 {
        let free = self.edges - self.blocked;
        if free == 0 {
            0.0
        } else {
            self.false_blocked as f64 / free as f64
        }
    }
}

/// Judges every edge with the oracle (`verdicts`, from [`judge_edge`]) and compares a checker's
/// `edge_free` answers with them.
pub fn agreement(
    checker: &dyn super::EdgeChecker,
    chain: &Chain,
    body: &RobotBody,
    edges: &[(Vec<f64>, Vec<f64>)],
    verdicts: &[OracleVerdict],
) -> Agreement {
    let mut scratch = super::Scratch::with_body(chain, std::sync::Arc::new(body.clone()));
    let mut false_free = 0;
    let mut false_blocked = 0;
    let start = std::time::Instant::now();
    let answers: Vec<bool> = edges
        .iter()
        .map(|(a, b)| checker.edge_free(chain, a, b, &mut scratch))
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    for (free, v) in answers.iter().zip(verdicts) {
        match (*free, v.free) {
            (true, false) => false_free += 1,
            (false, true) => false_blocked += 1,
            _ => {}
        }
    }
    Agreement {
        checker: checker.name().to_string(),
        edges: edges.len(),
        blocked: verdicts.iter().filter(|v| !v.free).count(),
        false_free,
        false_blocked,
        seconds_per_edge: seconds / edges.len().max(1) as f64,
        fk_per_edge: scratch.stats.fk as f64 / edges.len().max(1) as f64,
    }
}

/// How far the capsule core of each item's body travels along the straight step `from → to`,
/// measured with `substeps` steps: the larger of its two ends' path lengths, in the world for
/// an item against the environment and relative to the links of the other body's level for a
/// self pair; `None` for a solid body. The dense measurement that `certified`'s motion bounds
/// ([`crate::collision::edge::certified::step_bounds`]) are compared with. Allocates.
pub fn travel(
    chain: &Chain,
    body: &RobotBody,
    from: &[f64],
    to: &[f64],
    items: &[StepBound],
    substeps: usize,
) -> Vec<Option<f64>> {
    let substeps = substeps.max(1);
    let mut frames = chain.frames();
    let mut q = vec![0.0; from.len()];
    // Per item, the path lengths of the core's two ends, and their last positions.
    let mut length = vec![[0.0f64; 2]; items.len()];
    let mut last: Vec<Option<[Point3<f64>; 2]>> = vec![None; items.len()];
    for k in 0..=substeps {
        let t = k as f64 / substeps as f64;
        for ((qi, a), b) in q.iter_mut().zip(from).zip(to) {
            *qi = a + t * (b - a);
        }
        chain.fk(&q, &mut frames);
        for (i, it) in items.iter().enumerate() {
            if it.body >= body.segments() {
                continue;
            }
            let inv = match it.relative_to.map_or(0, |p| body.level(p)) {
                0 => IsometryMatrix3::identity(),
                l => frames.axis_frames[l - 1].inverse(),
            };
            let ends = frames.segments[it.body].map(|p| inv * p);
            if let Some(before) = last[i] {
                for ((len, now), was) in length[i].iter_mut().zip(ends).zip(before) {
                    *len += (now - was).norm();
                }
            }
            last[i] = Some(ends);
        }
    }
    items
        .iter()
        .zip(length)
        .map(|(it, [a, b])| (it.body < body.segments()).then_some(a.max(b)))
        .collect()
}
