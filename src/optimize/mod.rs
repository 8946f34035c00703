//! Design optimisation (paper §III-B): the objective of Eq. 23 and three optimisers behind one
//! trait — a genetic algorithm, particle swarm optimisation and adaptive simulated annealing —
//! driven by a runner that owns budgets, progress, history and checkpoints.

pub mod asa;
pub mod experiment;
pub mod ga;
pub mod islands;
pub mod lock;
pub mod objective;
pub mod output;
pub mod pso;
pub mod runner;

pub use objective::{Breakdown, Objective};
pub use output::{HistoryRow, RunSummary};
pub use runner::RunOptions;

use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// A box-bounded minimisation problem whose evaluations may be random (a planner inside) but
/// are reproducible: `stream` names the evaluation's random stream.
pub trait Problem: Sync {
    /// Lower bounds.
    fn lower(&self) -> &[f64];
    /// Upper bounds.
    fn upper(&self) -> &[f64];
    /// Cost of `x` (to minimise) and the reachability it reached (1 for problems without one).
    /// `progress` ∈ [0, 1] is how far the optimisation is (for schedules).
    fn evaluate(&self, x: &[f64], stream: u64, progress: f64) -> (f64, f64);
    /// [`Problem::evaluate`], given up (`None`) once `stop` is raised, for problems whose
    /// evaluations take long (the default evaluates whole).
    fn evaluate_until(
        &self,
        x: &[f64],
        stream: u64,
        progress: f64,
        stop: &AtomicBool,
    ) -> Option<(f64, f64)> {
        let _ = stop;
        Some(self.evaluate(x, stream, progress))
    }
    /// Dimension.
    fn dim(&self) -> usize {
        self.lower().len()
    }
}

/// A point with its cost.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evaluated {
    /// The point.
    pub x: Vec<f64>,
    /// Its cost.
    pub cost: f64,
    /// Its reachability `R` (1 for problems without one).
    pub reachability: f64,
    /// The random stream it was evaluated with (re-evaluating with it gives the same result).
    pub stream: u64,
    /// The progress it was evaluated at (for schedules).
    pub progress: f64,
}

impl Evaluated {
    /// True when `self` is strictly better than `other` (lower cost; ties keep the incumbent).
    pub fn better_than(&self, other: &Evaluated) -> bool {
        self.cost < other.cost
    }
}

/// Evaluates a batch of points in parallel (rayon). Point `i` uses the random stream
/// `first_stream + i·stride`, so the results do not depend on the number of threads (`stride`
/// is 1 for one population; island `i` of `N` uses the streams `≡ i (mod N)`).
///
/// A point whose evaluation has not begun when the `cutoff` is reached (the time is up, or the
/// run is told to stop) is skipped, and once the run is told to stop the evaluations under way
/// are given up too ([`Problem::evaluate_until`]); the first point is always evaluated, so that every step
/// evaluates something, unless the cutoff allows a step without any ([`Cutoff::may_skip_all`]). Points past the cutoff's evaluation budget are skipped too (by their
/// place in the batch, so which ones does not depend on timing). The batch is then [`Cut`],
/// with the points that were evaluated, and the step that asked for it leaves its result to
/// the caller (see [`Optimizer::step`]).
pub fn evaluate_batch(
    problem: &dyn Problem,
    xs: Vec<Vec<f64>>,
    first_stream: u64,
    stride: u64,
    progress: f64,
    cutoff: Cutoff<'_>,
) -> Result<Vec<Evaluated>, Cut> {
    let n = xs.len();
    let done: Vec<Evaluated> = xs
        .into_par_iter()
        .enumerate()
        .filter_map(|(i, x)| {
            let always = i == 0 && !cutoff.may_skip_all;
            if cutoff.budget.is_some_and(|b| i as u64 >= b) || (!always && cutoff.reached()) {
                return None;
            }
            let stream = first_stream.wrapping_add((i as u64).wrapping_mul(stride));
            // A raised flag (Ctrl-C) also gives up the evaluations under way, but the one a
            // step always makes.
            let (cost, reachability) = match cutoff.stop {
                Some(stop) if !always => problem.evaluate_until(&x, stream, progress, stop)?,
                _ => problem.evaluate(&x, stream, progress),
            };
            Some(Evaluated {
                x,
                cost,
                reachability,
                stream,
                progress,
            })
        })
        .collect();
    if done.len() == n {
        Ok(done)
    } else {
        Err(Cut { evaluated: done })
    }
}

/// When a step's evaluations stop being begun: at a deadline (the run's time limit), when a
/// flag is raised (Ctrl-C), or after a number of evaluations (what is left of the run's
/// evaluation budget). The default never comes.
#[derive(Clone, Copy, Debug, Default)]
pub struct Cutoff<'a> {
    /// The instant the run's time is up.
    pub deadline: Option<Instant>,
    /// Raised to stop the run.
    pub stop: Option<&'a AtomicBool>,
    /// How many evaluations the step may still make (`None`: no limit). Unlike the deadline
    /// it is counted by the points' places in the step, so a cut by it is the same on every
    /// run.
    pub budget: Option<u64>,
    /// When set, a step begun after the deadline (or the flag) evaluates nothing; by default
    /// its first point is evaluated all the same, so that a run has a result. An island job
    /// sets it on every island but the first of a new job: otherwise each of its islands
    /// would evaluate a design after the time is up, one after another.
    pub may_skip_all: bool,
}

impl Cutoff<'_> {
    /// True once the deadline has passed or the flag is raised.
    #[inline]
    pub fn reached(&self) -> bool {
        self.stop.is_some_and(|s| s.load(Ordering::Relaxed))
            || self.deadline.is_some_and(|d| Instant::now() >= d)
    }
}

/// A batch of evaluations cut short by the cutoff of its step: the points that were
/// evaluated (in stream order), which the step did not take in.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cut {
    /// The points evaluated before the cutoff.
    pub evaluated: Vec<Evaluated>,
}

/// What one optimiser step did.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    /// Objective evaluations made in the step (a cut step: those evaluated before the
    /// cutoff).
    pub evaluations: u64,
    /// `Some` when the step's cutoff cut a batch short: the step is incomplete, the
    /// optimiser's state must be restored from a [`Optimizer::snapshot`] taken before it, and
    /// the points evaluated are offered to the run's result only.
    pub cut: Option<Cut>,
}

impl StepReport {
    /// A complete step of `evaluations` evaluations.
    pub fn done(evaluations: u64) -> Self {
        StepReport {
            evaluations,
            cut: None,
        }
    }

    /// A step cut short at its cutoff.
    pub fn cut(cut: Cut) -> Self {
        StepReport {
            evaluations: cut.evaluated.len() as u64,
            cut: Some(cut),
        }
    }
}

/// Everything a step needs from its caller: the problem, a random stream for this step only,
/// the first evaluation stream to use, and the progress for schedules.
pub struct StepContext<'a> {
    /// The problem.
    pub problem: &'a dyn Problem,
    /// Random numbers of this step (derived from the seed and the step index by the runner).
    pub rng: &'a mut ChaCha8Rng,
    /// Stream of the step's first evaluation; evaluation `j` of the step uses
    /// `first_stream + j·stride`.
    pub first_stream: u64,
    /// Distance between the streams of consecutive evaluations: 1 for one population, the
    /// number of islands in an island job (each island keeps to its own residue class).
    pub stride: u64,
    /// Progress ∈ [0, 1].
    pub progress: f64,
    /// When the step's evaluations stop being begun (the run's time limit, Ctrl-C, the rest of
    /// its evaluation budget): the step is then cut ([`evaluate_batch`]).
    pub cutoff: Cutoff<'a>,
}

impl<'a> StepContext<'a> {
    /// How the step's evaluations are numbered and cut, starting at its first stream.
    pub fn batch(&self) -> Batch<'a> {
        Batch {
            problem: self.problem,
            first_stream: self.first_stream,
            stride: self.stride,
            progress: self.progress,
            cutoff: self.cutoff,
        }
    }
}

/// A step's evaluations: the problem, the random streams (`first_stream + i·stride` for point
/// `i`), the progress and the cutoff ([`StepContext::batch`]).
#[derive(Clone, Copy)]
pub struct Batch<'a> {
    problem: &'a dyn Problem,
    first_stream: u64,
    stride: u64,
    progress: f64,
    cutoff: Cutoff<'a>,
}

impl<'a> Batch<'a> {
    /// The same numbering `count` evaluations on (for a second batch within a step), with
    /// `count` fewer left of the evaluation budget.
    pub fn after(self, count: u64) -> Batch<'a> {
        Batch {
            first_stream: self
                .first_stream
                .wrapping_add(count.wrapping_mul(self.stride)),
            cutoff: Cutoff {
                budget: self.cutoff.budget.map(|b| b.saturating_sub(count)),
                ..self.cutoff
            },
            ..self
        }
    }

    /// Evaluates `xs` ([`evaluate_batch`]): all of them, or [`Cut`] at the cutoff.
    pub fn evaluate(&self, xs: Vec<Vec<f64>>) -> Result<Vec<Evaluated>, Cut> {
        evaluate_batch(
            self.problem,
            xs,
            self.first_stream,
            self.stride,
            self.progress,
            self.cutoff,
        )
    }
}

/// An optimiser: it proposes points, has them evaluated (in parallel) and updates its state.
/// The whole state serialises, so a run can be checkpointed and resumed.
pub trait Optimizer: Send {
    /// The algorithm's name (`ga`, `pso`, `asa`).
    fn name(&self) -> &'static str;
    /// One generation / iteration. When its [`StepContext::cutoff`] cuts a batch short, it
    /// returns at once with [`StepReport::cut`]; its state may then be half-updated, and the
    /// caller restores the [`Optimizer::snapshot`] it took before the step.
    fn step(&mut self, ctx: StepContext<'_>) -> StepReport;
    /// A copy of the whole state, to restore after a step cut short.
    fn snapshot(&self) -> Box<dyn Optimizer>;
    /// The best point so far (`None` before the first step).
    fn best(&self) -> Option<&Evaluated>;
    /// The state as JSON, for checkpoints.
    fn save(&self) -> serde_json::Value;
    /// The points the optimiser would offer as its result, best first or in any order: the
    /// final population, the personal bests or the annealer's current and best points. The
    /// runner re-checks the best of them with fresh planner seeds.
    fn candidates(&self) -> Vec<&Evaluated>;
    /// The `count` best distinct points, best first: what an island sends to the next one
    /// when it migrates.
    fn emigrants(&self, count: usize) -> Vec<Evaluated>;
    /// Takes in points sent by another island (already evaluated): they replace the worst
    /// members of the population (GA) or the worst particles (PSO, position and personal
    /// best; velocities are kept), or the current point if the best of them is better (ASA).
    /// The best so far is updated.
    fn immigrate(&mut self, migrants: &[Evaluated]);
    /// Checks a restored state against the problem it continues (`space`): every point and
    /// vector has the problem's dimension, every index is in range, every point lies in the
    /// bounds (a coordinate outside them only where a starting design has it), the starting
    /// designs are the problem's, and the optimiser's own numbers lie where it keeps them. The
    /// error names the field of the state, e.g. `population[3].x has 10 values, the design
    /// space 8`.
    fn validate(&self, space: &StateSpace<'_>) -> Result<(), String>;
}

/// What a restored optimiser state is checked against ([`Optimizer::validate`]): the
/// problem's bounds and the starting designs every run of it begins from.
#[derive(Clone, Copy, Debug)]
pub struct StateSpace<'a> {
    /// Lower bounds.
    pub lower: &'a [f64],
    /// Upper bounds.
    pub upper: &'a [f64],
    /// The starting designs, as the optimisers are given them (`seeds`).
    pub seeds: &'a [Vec<f64>],
}

impl StateSpace<'_> {
    /// The problem's dimension.
    pub fn dim(&self) -> usize {
        self.lower.len()
    }
}

/// Checks that the point `x` (the state field `field`) has the problem's dimension, finite
/// values, and each value within its bounds or equal to a starting design's (decoding a
/// design can leave a starting design's value outside the bounds, and the optimisers copy
/// values unchanged).
pub(crate) fn check_point(field: &str, x: &[f64], space: &StateSpace<'_>) -> Result<(), String> {
    check_len(field, x, space.dim())?;
    for (i, &v) in x.iter().enumerate() {
        let (lo, hi) = (space.lower[i], space.upper[i]);
        let inside = lo <= v && v <= hi;
        if !inside && !space.seeds.iter().any(|s| s.get(i) == Some(&v)) {
            return Err(format!(
                "{field}[{i}] = {}: outside the design space's [{}, {}]",
                crate::error::Num(v),
                crate::error::Num(lo),
                crate::error::Num(hi)
            ));
        }
    }
    Ok(())
}

/// Checks that `v` (the state field `field`) has `dim` finite values.
pub(crate) fn check_len(field: &str, v: &[f64], dim: usize) -> Result<(), String> {
    if v.len() != dim {
        return Err(format!(
            "{field} has {} values, the design space {dim}",
            v.len()
        ));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(format!("{field}[{i}] = {}: must be finite", v[i]));
    }
    Ok(())
}

/// Checks an evaluated point of a restored state: a point of the design space
/// ([`check_point`]), a finite cost that is not negative (paper Eq. 23 sums non-negative
/// terms), and `R` and the progress within [0, 1].
pub(crate) fn check_evaluated(
    field: &str,
    e: &Evaluated,
    space: &StateSpace<'_>,
) -> Result<(), String> {
    check_point(&format!("{field}.x"), &e.x, space)?;
    if !(e.cost.is_finite() && e.cost >= 0.0) {
        return Err(format!(
            "{field}.cost = {}: must be finite and not negative",
            crate::error::Num(e.cost)
        ));
    }
    for (name, v) in [("reachability", e.reachability), ("progress", e.progress)] {
        if !(0.0..=1.0).contains(&v) {
            return Err(format!(
                "{field}.{name} = {}: must lie in [0, 1]",
                crate::error::Num(v)
            ));
        }
    }
    Ok(())
}

/// Checks the seed points of a restored state (the problem's starting designs, as every run
/// of it begins) and its optional incumbent.
pub(crate) fn check_points(
    seeds: &[Vec<f64>],
    best: Option<&Evaluated>,
    space: &StateSpace<'_>,
) -> Result<(), String> {
    for (i, x) in seeds.iter().enumerate() {
        check_len(&format!("seeds[{i}]"), x, space.dim())?;
    }
    if seeds.len() != space.seeds.len() {
        return Err(format!(
            "seeds has {} points, the scenario's starting designs {}",
            seeds.len(),
            space.seeds.len()
        ));
    }
    for (i, (x, want)) in seeds.iter().zip(space.seeds).enumerate() {
        if let Some(k) = (0..x.len()).find(|&k| x[k] != want[k]) {
            return Err(format!(
                "seeds[{i}][{k}] = {}: the scenario's starting design has {}",
                crate::error::Num(x[k]),
                crate::error::Num(want[k])
            ));
        }
    }
    if let Some(b) = best {
        check_evaluated("best", b, space)?;
    }
    Ok(())
}

/// Uniform random point in the box.
pub(crate) fn random_point(lower: &[f64], upper: &[f64], rng: &mut ChaCha8Rng) -> Vec<f64> {
    use rand::RngExt;
    lower
        .iter()
        .zip(upper)
        .map(|(&l, &u)| if u > l { rng.random_range(l..=u) } else { l })
        .collect()
}

/// The `count` best points of `pool` with distinct `x`, best first (ties: lower stream).
pub(crate) fn best_distinct<'a>(
    pool: impl IntoIterator<Item = &'a Evaluated>,
    count: usize,
) -> Vec<Evaluated> {
    let mut pool: Vec<&Evaluated> = pool.into_iter().collect();
    pool.sort_by(|a, b| a.cost.total_cmp(&b.cost).then(a.stream.cmp(&b.stream)));
    let mut out: Vec<Evaluated> = Vec::with_capacity(count);
    for e in pool {
        if out.len() == count {
            break;
        }
        if out.iter().all(|o| o.x != e.x) {
            out.push(e.clone());
        }
    }
    out
}

/// The better of two optional incumbents.
pub(crate) fn keep_best(best: &mut Option<Evaluated>, candidate: &Evaluated) {
    if best.as_ref().is_none_or(|b| candidate.better_than(b)) {
        *best = Some(candidate.clone());
    }
}

/// Standard test functions for the optimisers (used in tests and documentation), shifted so
/// their minimum is not at the origin (as in the CEC benchmark suites): an optimiser gains
/// nothing from a bias toward 0 or toward the centre of the box.
pub mod testfn {
    use super::Problem;

    /// The shift of coordinate `i`: values in [−2.5, 3.5], away from 0 and the box centre.
    pub fn shift(i: usize) -> f64 {
        1.234 + 2.2 * ((i as f64) * 2.399).sin()
    }

    /// `f(x) = Σ (x_i − o_i)²` on `[-5.12, 5.12]^n`; minimum 0 at `o` ([`shift`]).
    pub struct Sphere {
        lower: Vec<f64>,
        upper: Vec<f64>,
    }

    impl Sphere {
        /// In `n` dimensions.
        pub fn new(n: usize) -> Self {
            Sphere {
                lower: vec![-5.12; n],
                upper: vec![5.12; n],
            }
        }
    }

    impl Problem for Sphere {
        fn lower(&self) -> &[f64] {
            &self.lower
        }
        fn upper(&self) -> &[f64] {
            &self.upper
        }
        fn evaluate(&self, x: &[f64], _: u64, _: f64) -> (f64, f64) {
            let f = x
                .iter()
                .enumerate()
                .map(|(i, v)| (v - shift(i)).powi(2))
                .sum();
            (f, 1.0)
        }
    }

    /// Rastrigin, `f(x) = 10n + Σ (z_i² − 10 cos 2πz_i)`, `z = x − o`, on `[-5.12, 5.12]^n`;
    /// minimum 0 at `o` ([`shift`]), surrounded by a grid of local minima (the nearest at
    /// about 1 per displaced coordinate).
    pub struct Rastrigin {
        lower: Vec<f64>,
        upper: Vec<f64>,
    }

    impl Rastrigin {
        /// In `n` dimensions.
        pub fn new(n: usize) -> Self {
            Rastrigin {
                lower: vec![-5.12; n],
                upper: vec![5.12; n],
            }
        }
    }

    impl Problem for Rastrigin {
        fn lower(&self) -> &[f64] {
            &self.lower
        }
        fn upper(&self) -> &[f64] {
            &self.upper
        }
        fn evaluate(&self, x: &[f64], _: u64, _: f64) -> (f64, f64) {
            let n = x.len() as f64;
            let s: f64 = x
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    let z = v - shift(i);
                    z * z - 10.0 * (2.0 * std::f64::consts::PI * z).cos()
                })
                .sum();
            (10.0 * n + s, 1.0)
        }
    }
}
