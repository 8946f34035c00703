//! The objective of paper Eq. 23–31: reachability first, then short links, small ranges, few
//! links and few joints.

use super::Problem;
use crate::collision::{CollisionScene, RobotBody};
use crate::design::{Design, DesignSpace};
use crate::kinematics::Chain;
use crate::planning::{PlannerConfig, ReachReport};
use crate::scenario::{ObjectiveWeights, Scenario};
use nalgebra::Point3;
use serde::{Deserialize, Serialize};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// The terms of Eq. 23 for one design.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Breakdown {
    /// The cost `λ0(1 − R) + Σ_i (λ1·A_i + λ2·B_i + λ3·C_i + λ4·D_i) + λ5·E`.
    pub cost: f64,
    /// Reachability `R`.
    pub reachability: f64,
    /// `Σ_i A_i`: `atan` of each link's length when `R = 1`, else 1 per link (Eq. 26).
    pub lengths: f64,
    /// `Σ_i B_i`: sum over the axes of `atan(max − min)` when `R = 1`, else 1 per link (Eq. 27).
    pub ranges: f64,
    /// `Σ_i C_i`: links kept (non-zero length, Eq. 28).
    pub links_kept: usize,
    /// `Σ_i D_i`: joints kept (axes with a non-zero range, Eq. 29).
    pub joints_kept: usize,
    /// `E`: 1 when some task is unreached (Eq. 30).
    pub incomplete: f64,
}

/// Eq. 23–31 for a design whose reachability is `r`.
///
/// Reading of the paper where it is terse: the length of link `i` is `|a_i| + |d_i|` (the
/// paper's `a_i`, with the offset counted for links that have one); `B_i` sums
/// `atan(max − min)` over link `i`'s six axes; `D_i` counts the axes of link `i` with a
/// non-zero range (the paper's vector inequality read per axis, as `B_i` is); `A_i = B_i = 1`
/// when `R < 1`, exactly as Eq. 26–27 state.
pub fn breakdown(design: &Design, r: f64, w: &ObjectiveWeights) -> Breakdown {
    let complete = r >= 1.0;
    let mut lengths = 0.0;
    let mut ranges = 0.0;
    let mut links_kept = 0;
    let mut joints_kept = 0;
    for l in &design.links {
        let length = l.a.abs() + l.d.abs();
        if complete {
            lengths += length.atan();
            ranges += l.axes.0.iter().map(|r| r.width().atan()).sum::<f64>();
        } else {
            lengths += 1.0;
            ranges += 1.0;
        }
        links_kept += usize::from(length > 0.0);
        joints_kept += l.joint_count();
    }
    let incomplete = if complete { 0.0 } else { 1.0 };
    let cost = w.lambda0 * (1.0 - r)
        + w.lambda1 * lengths
        + w.lambda2 * ranges
        + w.lambda3 * links_kept as f64
        + w.lambda4 * joints_kept as f64
        + w.lambda5 * incomplete;
    Breakdown {
        cost,
        reachability: r,
        lengths,
        ranges,
        links_kept,
        joints_kept,
        incomplete,
    }
}

/// Offset of the random streams that confirm a claimed `R = 1` (see
/// [`Objective::with_confirmation`]): confirmation `j` of evaluation `k` plans with the stream
/// `CONFIRM_STREAM + k·m + j`, apart from the evaluations' own streams `k`.
pub const CONFIRM_STREAM: u64 = 1 << 52;

/// A design decoded for planning, with its chain and robot body ([`Objective::prepare`]).
pub struct Prepared {
    /// The design.
    pub design: Design,
    /// Its kinematic chain.
    pub chain: Chain,
    /// Its robot body, shared by its planner runs.
    pub body: Arc<RobotBody>,
}

/// One evaluation of a design: the reachability report of the planner run that set its `R`, the
/// stream of that run and the terms of Eq. 23.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// The report of the planner run that set `R` (replaying its stream gives the same `R` and
    /// paths).
    pub report: ReachReport,
    /// The random stream of that planner run.
    pub stream: u64,
    /// Planner runs made (1, or more when a claimed `R = 1` was confirmed).
    pub planner_runs: usize,
    /// The terms of Eq. 23 with that run's `R`.
    pub breakdown: Breakdown,
}

/// The design problem: decode a vector, plan, score. Implements [`Problem`] for the
/// optimisers.
pub struct Objective {
    space: DesignSpace,
    scene: Arc<CollisionScene>,
    tasks: Vec<Point3<f64>>,
    orientations: Vec<crate::world::TaskOrientation>,
    planner: PlannerConfig,
    weights: ObjectiveWeights,
    seed: u64,
    confirm: usize,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl Objective {
    /// The objective of a scenario, with its planner settings as given (override them on the
    /// scenario first for `--checker`/`--lmax`).
    pub fn new(scenario: &Scenario, planner: PlannerConfig, seed: u64) -> Self {
        Objective {
            lower: scenario.space.lower(),
            upper: scenario.space.upper(),
            space: scenario.space.clone(),
            scene: Arc::new(CollisionScene::new(&scenario.workspace)),
            tasks: scenario.workspace.tasks.clone(),
            orientations: scenario.workspace.orientations.clone(),
            planner,
            weights: scenario.objective.clone(),
            seed,
            confirm: 0,
        }
    }

    /// Confirms every claimed `R = 1` with `m` more planner runs on their own random streams
    /// ([`CONFIRM_STREAM`]): the first run that falls short sets the design's `R`. A design that reaches a
    /// task only in a lucky run (at the edge of the goal tolerance) then rarely scores `R = 1`.
    pub fn with_confirmation(mut self, m: usize) -> Self {
        self.confirm = m;
        self
    }

    /// The planner's seed (the run's seed).
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The objective's weights.
    pub fn weights(&self) -> &ObjectiveWeights {
        &self.weights
    }

    /// One planner run for `x` with the random stream `(seed, stream)`: its report and the
    /// breakdown of Eq. 23. No confirmation.
    pub fn plan_once(&self, x: &[f64], stream: u64, progress: f64) -> (ReachReport, Breakdown) {
        self.plan_design(&self.prepare(x), stream, progress)
    }

    /// What every planner run of `x` shares: its design, chain and robot body (the capsules
    /// with their allowed-collision matrix, which samples the chain's configurations), built
    /// once for the runs of one evaluation or re-check.
    pub fn prepare(&self, x: &[f64]) -> Prepared {
        let design = self.space.decode(x);
        let chain = design.chain();
        let body = Arc::new(RobotBody::capsules(&chain, &self.planner.self_collision));
        Prepared {
            design,
            chain,
            body,
        }
    }

    /// [`Objective::plan_once`] for a prepared design.
    pub fn plan_design(
        &self,
        d: &Prepared,
        stream: u64,
        progress: f64,
    ) -> (ReachReport, Breakdown) {
        self.plan_design_until(d, stream, progress, None)
            .expect("a run without a stop flag ends whole")
    }

    /// [`Objective::plan_design`], given up (`None`) once `stop` is raised.
    fn plan_design_until(
        &self,
        d: &Prepared,
        stream: u64,
        progress: f64,
        stop: Option<&AtomicBool>,
    ) -> Option<(ReachReport, Breakdown)> {
        let report = crate::planning::reachability_until(
            &d.chain,
            Some(d.body.clone()),
            &self.scene,
            (&self.tasks, &self.orientations),
            &self.planner_at(progress),
            (self.seed, stream),
            stop,
        )?;
        let b = breakdown(&d.design, report.reachability, &self.weights);
        Some((report, b))
    }

    /// As [`Objective::plan_once`]'s report, with the planner's tree kept for drawing
    /// ([`crate::planning::reach::reachability_with_tree`]).
    pub fn plan_with_tree(&self, x: &[f64], stream: u64, progress: f64) -> ReachReport {
        let chain = self.space.decode(x).chain();
        let planner = self.planner_at(progress);
        crate::planning::reach::reachability_with_tree(
            &chain,
            None,
            &self.scene,
            &self.tasks,
            &self.orientations,
            &planner,
            self.seed,
            stream,
        )
    }

    /// Evaluates `x` as the optimisers do: one planner run on `stream`, and when it reaches
    /// every task, the confirmation runs; the first of them that falls short sets `R`.
    pub fn evaluate_confirmed(&self, x: &[f64], stream: u64, progress: f64) -> Evaluation {
        self.evaluate_confirmed_until(x, stream, progress, None)
            .expect("an evaluation without a stop flag ends whole")
    }

    /// [`Objective::evaluate_confirmed`], given up (`None`) once `stop` is raised: a planner
    /// run then stops before its next iteration, and the evaluation would not be the one of
    /// whole runs.
    pub fn evaluate_confirmed_until(
        &self,
        x: &[f64],
        stream: u64,
        progress: f64,
        stop: Option<&AtomicBool>,
    ) -> Option<Evaluation> {
        let prepared = self.prepare(x);
        let (mut report, mut b) = self.plan_design_until(&prepared, stream, progress, stop)?;
        let mut worst = stream;
        let mut planner_runs = 1;
        if report.reachability >= 1.0 {
            for j in 0..self.confirm as u64 {
                let s = CONFIRM_STREAM
                    .wrapping_add(stream.wrapping_mul(self.confirm as u64))
                    .wrapping_add(j);
                let (r, rb) = self.plan_design_until(&prepared, s, progress, stop)?;
                planner_runs += 1;
                if r.reachability < report.reachability {
                    (report, b, worst) = (r, rb, s);
                    break;
                }
            }
        }
        Some(Evaluation {
            report,
            stream: worst,
            planner_runs,
            breakdown: b,
        })
    }

    /// The design space.
    pub fn space(&self) -> &DesignSpace {
        &self.space
    }

    /// The planner settings at `progress` (schedules applied).
    pub fn planner_at(&self, progress: f64) -> PlannerConfig {
        let mut p = self.planner.clone();
        if let Some(s) = &self.planner.schedule {
            p.l_max = s.l_max_at(progress);
            p.max_iterations = s.iterations_at(progress);
        }
        p
    }

    /// Plans for `x` as [`Objective::evaluate_confirmed`] does and returns the report of the
    /// run that set `R` and the breakdown of Eq. 23.
    pub fn evaluate_full(&self, x: &[f64], stream: u64, progress: f64) -> (ReachReport, Breakdown) {
        let e = self.evaluate_confirmed(x, stream, progress);
        (e.report, e.breakdown)
    }
}

impl Problem for Objective {
    fn lower(&self) -> &[f64] {
        &self.lower
    }
    fn upper(&self) -> &[f64] {
        &self.upper
    }
    fn evaluate(&self, x: &[f64], stream: u64, progress: f64) -> (f64, f64) {
        let b = self.evaluate_confirmed(x, stream, progress).breakdown;
        (b.cost, b.reachability)
    }
    fn evaluate_until(
        &self,
        x: &[f64],
        stream: u64,
        progress: f64,
        stop: &AtomicBool,
    ) -> Option<(f64, f64)> {
        let b = self
            .evaluate_confirmed_until(x, stream, progress, Some(stop))?
            .breakdown;
        Some((b.cost, b.reachability))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{AxisRanges, LinkDesign};
    use crate::kinematics::{Axis, Placement, Range};

    fn design() -> Design {
        let mut a1 = AxisRanges::default();
        *a1.get_mut(Axis::Ry) = Range::new(-1.0, 1.0);
        *a1.get_mut(Axis::Tx) = Range::new(0.0, 0.5);
        let mut a3 = AxisRanges::default();
        *a3.get_mut(Axis::Rz) = Range::new(0.3, 0.3); // fixed: not a joint
        Design {
            base: Placement::default(),
            link_radius: 0.02,
            colliders_per_link: 2,
            links: vec![
                LinkDesign {
                    a: 0.5,
                    axes: a1,
                    ..LinkDesign::default()
                },
                LinkDesign::default(), // zero length, no joint: removed
                LinkDesign {
                    a: 0.2,
                    d: 0.1,
                    axes: a3,
                    ..LinkDesign::default()
                },
            ],
            tool: None,
        }
    }

    /// An evaluation given a stop flag is the evaluation without one while the flag is down,
    /// and is given up (`None`) once it is raised (a planner run stops before its next
    /// iteration, so an evaluation under way at Ctrl-C ends at once); as a [`Problem`], too.
    #[test]
    fn an_evaluation_is_given_up_once_the_stop_flag_is_raised() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios/paper-2d.toml");
        let s = Scenario::load(&path).unwrap();
        let o = Objective::new(&s, s.planner.clone(), 7).with_confirmation(2);
        let x = o.space().encode(&o.space().largest());
        let (down, up) = (AtomicBool::new(false), AtomicBool::new(true));
        for stream in 0..4 {
            let whole = o.evaluate_confirmed(&x, stream, 0.0);
            let watched = o
                .evaluate_confirmed_until(&x, stream, 0.0, Some(&down))
                .unwrap();
            assert_eq!(watched.breakdown, whole.breakdown);
            assert_eq!(
                (watched.stream, watched.planner_runs),
                (whole.stream, whole.planner_runs)
            );
            assert!(o
                .evaluate_confirmed_until(&x, stream, 0.0, Some(&up))
                .is_none());
            let b = whole.breakdown;
            assert_eq!(
                o.evaluate_until(&x, stream, 0.0, &down),
                Some((b.cost, b.reachability))
            );
            assert_eq!(o.evaluate_until(&x, stream, 0.0, &up), None);
        }
    }

    /// A design's planner runs share one robot body ([`Objective::prepare`]): each gives the
    /// report of a planner run that builds its own, on paper-3d (self-collision on), for random
    /// designs and several streams.
    #[test]
    fn runs_that_share_a_body_plan_as_runs_that_build_their_own() {
        use rand::{RngExt, SeedableRng};
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios/paper-3d.toml");
        let s = Scenario::load(&path).unwrap();
        let o = Objective::new(&s, s.planner.clone(), 7);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let mut reached = 0;
        for _ in 0..4 {
            let x: Vec<f64> = o
                .lower
                .iter()
                .zip(&o.upper)
                .map(|(l, u)| if l < u { rng.random_range(*l..=*u) } else { *l })
                .collect();
            let prepared = o.prepare(&x);
            assert!(!prepared.body.self_pairs().is_empty());
            for stream in 0..3 {
                let (shared, _) = o.plan_design(&prepared, stream, 0.5);
                let own = crate::planning::reachability(
                    &prepared.chain,
                    &o.scene,
                    &o.tasks,
                    &o.planner_at(0.5),
                    7,
                    stream,
                );
                assert_eq!(shared.targets, own.targets);
                assert_eq!(shared.iterations, own.iterations);
                assert_eq!(shared.edge_checks, own.edge_checks);
                reached += shared.targets.iter().filter(|t| t.reached).count();
            }
        }
        assert!(reached > 0, "the designs reach something");
    }

    fn weights() -> ObjectiveWeights {
        ObjectiveWeights {
            lambda0: 10.0,
            lambda1: 1.0,
            lambda2: 0.5,
            lambda3: 2.0,
            lambda4: 3.0,
            lambda5: 7.0,
        }
    }

    #[test]
    fn complete_reachability_uses_arctangents() {
        let b = breakdown(&design(), 1.0, &weights());
        let lengths = 0.5f64.atan() + 0.0f64.atan() + 0.3f64.atan();
        let ranges = 2.0f64.atan() + 0.5f64.atan(); // zero-width axes add atan(0) = 0
        assert!((b.lengths - lengths).abs() < 1e-15);
        assert!((b.ranges - ranges).abs() < 1e-15);
        assert_eq!(b.links_kept, 2);
        assert_eq!(b.joints_kept, 2);
        assert_eq!(b.incomplete, 0.0);
        let cost = 1.0 * lengths + 0.5 * ranges + 2.0 * 2.0 + 3.0 * 2.0;
        assert!((b.cost - cost).abs() < 1e-12, "{} vs {cost}", b.cost);
    }

    #[test]
    fn incomplete_reachability_sets_a_and_b_to_one() {
        let b = breakdown(&design(), 0.6, &weights());
        assert_eq!(b.lengths, 3.0, "A_i = 1 for each of the 3 links");
        assert_eq!(b.ranges, 3.0, "B_i = 1 for each of the 3 links");
        let cost = 10.0 * 0.4 + 3.0 + 0.5 * 3.0 + 2.0 * 2.0 + 3.0 * 2.0 + 7.0;
        assert!((b.cost - cost).abs() < 1e-12, "{} vs {cost}", b.cost);
    }

    #[test]
    fn removing_a_link_or_a_joint_lowers_the_cost() {
        let base = breakdown(&design(), 1.0, &weights()).cost;
        let mut fewer_joints = design();
        *fewer_joints.links[0].axes.get_mut(Axis::Tx) = Range::ZERO;
        let b = breakdown(&fewer_joints, 1.0, &weights());
        assert_eq!(b.joints_kept, 1);
        assert!((base - b.cost - (3.0 + 0.5 * 0.5f64.atan())).abs() < 1e-12);
        let mut fewer_links = design();
        fewer_links.links[2].a = 0.0;
        fewer_links.links[2].d = 0.0;
        let b = breakdown(&fewer_links, 1.0, &weights());
        assert_eq!(b.links_kept, 1);
        assert!((base - b.cost - (2.0 + 0.3f64.atan())).abs() < 1e-12);
    }
}
