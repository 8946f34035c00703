//! Run control: budgets, early stopping, progress display, history, checkpoints and resume.

use super::asa::Asa;
use super::ga::{Ga, GaParams};
use super::objective::{Breakdown, Objective};
use super::pso::{Pso, PsoParams};
use super::{Optimizer, StepContext};
use crate::error::{Error, Result};
use crate::io::write_atomic;
use crate::planning::ReachReport;
use crate::scenario::{Algorithm, Scenario};
use crate::Design;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// How a run is set up (from the scenario's `[optimizer]` section and the command line).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunOptions {
    /// Which optimiser.
    pub algorithm: Algorithm,
    /// Seed of every random stream.
    pub seed: u64,
    /// Wall-clock budget (seconds).
    pub time_limit: Option<f64>,
    /// Budget in objective evaluations.
    pub evaluations: Option<u64>,
    /// Generations without improvement, once `R = 1`, before stopping early.
    pub patience: usize,
    /// Seconds between checkpoints (0: after every generation).
    pub checkpoint_interval: f64,
}

/// One row of `history.csv`: the state after a generation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HistoryRow {
    /// Seconds since the run started (summed over resumed sessions).
    pub elapsed_s: f64,
    /// Evaluations so far.
    pub evaluations: u64,
    /// Best cost so far.
    pub best_cost: f64,
    /// Reachability of the best design so far.
    pub best_reachability: f64,
    /// Links kept by the best design so far.
    pub best_links: usize,
    /// Joints kept by the best design so far.
    pub best_joints: usize,
}

/// Everything needed to continue a run where it stopped.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The scenario file (absolute path).
    pub scenario: PathBuf,
    /// Planner settings used (after command-line overrides).
    pub planner: crate::planning::PlannerConfig,
    /// Run settings.
    pub options: RunOptions,
    /// Generations done.
    pub generation: u64,
    /// Evaluations done.
    pub evaluations: u64,
    /// Seconds spent so far.
    pub elapsed_s: f64,
    /// Generations since the best cost last improved.
    pub stale: usize,
    /// History so far.
    pub history: Vec<HistoryRow>,
    /// The optimiser's state.
    pub state: serde_json::Value,
}

/// The result of a run: the best design and how it was found.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunSummary {
    /// The best design.
    pub design: Design,
    /// Its cost (paper Eq. 23).
    pub cost: f64,
    /// Its reachability.
    pub reachability: f64,
    /// Links with a body.
    pub links_kept: usize,
    /// Axes with a non-zero range.
    pub joints_kept: usize,
    /// Evaluations made.
    pub evaluations: u64,
    /// Generations made.
    pub generations: u64,
    /// Seconds spent.
    pub elapsed_s: f64,
    /// Seed.
    pub seed: u64,
    /// Optimiser name.
    pub optimizer: String,
    /// Edge checker name.
    pub checker: String,
    /// `L_max` used (at the end of any schedule).
    pub l_max: f64,
    /// Why the run stopped.
    pub stopped: String,
    /// The terms of the objective for the best design.
    pub breakdown: Breakdown,
}

fn make_optimizer(
    scenario: &Scenario,
    algorithm: Algorithm,
    seeds: Vec<Vec<f64>>,
) -> Box<dyn Optimizer> {
    let o = &scenario.optimizer;
    match algorithm {
        Algorithm::Ga => Box::new(Ga::new(
            GaParams {
                population: o.population,
                ..o.ga.clone()
            },
            seeds,
        )),
        Algorithm::Pso => Box::new(Pso::new(
            PsoParams {
                swarm: o.population,
                ..o.pso.clone()
            },
            seeds,
        )),
        Algorithm::Asa => Box::new(Asa::new(o.asa.clone(), seeds)),
    }
}

fn load_optimizer(algorithm: Algorithm, state: serde_json::Value) -> Result<Box<dyn Optimizer>> {
    let bad = |e: serde_json::Error| Error::invalid("checkpoint.state", "…", e.to_string());
    Ok(match algorithm {
        Algorithm::Ga => Box::new(Ga::load(state).map_err(bad)?),
        Algorithm::Pso => Box::new(Pso::load(state).map_err(bad)?),
        Algorithm::Asa => Box::new(Asa::load(state).map_err(bad)?),
    })
}

/// Stream offset of the optimisers' own random numbers, apart from the planners' streams.
const OPTIMIZER_STREAM: u64 = 1 << 48;

/// Names of the files a run writes into its output directory.
pub mod files {
    /// The best design and its figures.
    pub const BEST: &str = "best.json";
    /// One row per generation.
    pub const HISTORY: &str = "history.csv";
    /// The reachability report of the best design.
    pub const REACH: &str = "reach.json";
    /// Best R and best cost against time.
    pub const PLOT: &str = "convergence.svg";
    /// The state for `--resume`.
    pub const CHECKPOINT: &str = "checkpoint.json";
    /// The best design as a URDF robot.
    pub const URDF: &str = "robot.urdf";
    /// Folder of the joint trajectories of the best design, one pair of files per reached task.
    pub const TRAJECTORIES: &str = "trajectories";
}

/// Observes a run: called after every generation (for progress displays).
pub trait Observer {
    /// The state after a generation.
    fn generation(&mut self, row: &HistoryRow);
    /// The run is over.
    fn finish(&mut self) {}
}

/// An observer that does nothing.
pub struct Quiet;
impl Observer for Quiet {
    fn generation(&mut self, _: &HistoryRow) {}
}

/// A run: scenario, planner settings, options, output directory; start fresh or from a
/// checkpoint.
pub struct Runner<'a> {
    scenario: &'a Scenario,
    scenario_path: PathBuf,
    planner: crate::planning::PlannerConfig,
    options: RunOptions,
    out: PathBuf,
}

impl<'a> Runner<'a> {
    /// A run of `scenario` (read from `scenario_path`) with the given planner settings and
    /// options, writing into `out`.
    pub fn new(
        scenario: &'a Scenario,
        scenario_path: &Path,
        planner: crate::planning::PlannerConfig,
        options: RunOptions,
        out: &Path,
    ) -> Self {
        Runner {
            scenario,
            scenario_path: std::fs::canonicalize(scenario_path)
                .unwrap_or_else(|_| scenario_path.to_path_buf()),
            planner,
            options,
            out: out.to_path_buf(),
        }
    }

    /// Reads `DIR/checkpoint.json`.
    pub fn read_checkpoint(dir: &Path) -> Result<Checkpoint> {
        let path = dir.join(files::CHECKPOINT);
        let text = crate::limits::read_text(&path, crate::limits::MAX_CHECKPOINT_BYTES).map_err(
            |source| Error::Read {
                path: path.clone(),
                source,
            },
        )?;
        let c: Checkpoint = serde_json::from_str(&text).map_err(|e| Error::Parse {
            file: path.clone(),
            message: e.to_string(),
        })?;
        c.planner.validate().map_err(|e| e.in_file(&path))?;
        Ok(c)
    }

    /// Runs until a budget is spent, the run converges (`R = 1` and no improvement for
    /// `patience` generations) or `stop` is raised (Ctrl-C); then writes `best.json`,
    /// `history.csv`, `reach.json`, `convergence.svg`, `robot.urdf`, `trajectories/` and a
    /// final checkpoint. With `resume`,
    /// continues from that checkpoint: for the same seed and an evaluation budget, the result
    /// equals that of an uninterrupted run.
    pub fn run(
        &self,
        resume: Option<Checkpoint>,
        stop: &AtomicBool,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary> {
        std::fs::create_dir_all(&self.out).map_err(|source| Error::Write {
            path: self.out.clone(),
            source,
        })?;
        let objective = Objective::new(self.scenario, self.planner.clone(), self.options.seed);
        let o = &self.options;
        let (
            mut optimizer,
            mut generation,
            mut evaluations,
            elapsed_before,
            mut stale,
            mut history,
        ) = match resume {
            Some(c) => (
                load_optimizer(o.algorithm, c.state)?,
                c.generation,
                c.evaluations,
                c.elapsed_s,
                c.stale,
                c.history,
            ),
            None => {
                // The largest design starts in the first generation: it reaches most.
                let seeds = vec![self.scenario.space.encode(&self.scenario.space.largest())];
                (
                    make_optimizer(self.scenario, o.algorithm, seeds),
                    0,
                    0,
                    0.0,
                    0,
                    Vec::new(),
                )
            }
        };
        let start = Instant::now();
        let elapsed = || elapsed_before + start.elapsed().as_secs_f64();
        let mut last_checkpoint = Instant::now();
        let mut best_cost = optimizer.best().map_or(f64::INFINITY, |b| b.cost);
        let stopped;
        loop {
            if stop.load(Ordering::SeqCst) {
                stopped = "interrupted".to_string();
                break;
            }
            if o.evaluations.is_some_and(|n| evaluations >= n) {
                stopped = "evaluation budget spent".to_string();
                break;
            }
            if o.time_limit.is_some_and(|t| elapsed() >= t) {
                stopped = "time limit reached".to_string();
                break;
            }
            if let Some(b) = optimizer.best() {
                if b.reachability >= 1.0 && stale >= o.patience {
                    stopped = format!("converged: R = 1, no improvement for {stale} generations");
                    break;
                }
            }
            let progress = match (o.evaluations, o.time_limit) {
                (Some(n), Some(t)) => (evaluations as f64 / n as f64).max(elapsed() / t),
                (Some(n), None) => evaluations as f64 / n as f64,
                (None, Some(t)) => elapsed() / t,
                (None, None) => 0.0,
            }
            .clamp(0.0, 1.0);
            let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
            rng.set_stream(OPTIMIZER_STREAM + generation);
            let report = optimizer.step(StepContext {
                problem: &objective,
                rng: &mut rng,
                first_stream: evaluations,
                progress,
            });
            evaluations += report.evaluations;
            generation += 1;
            let best = optimizer.best().expect("a best after a step").clone();
            if best.cost < best_cost {
                best_cost = best.cost;
                stale = 0;
            } else {
                stale += 1;
            }
            let best_design = objective.space().decode(&best.x);
            let row = HistoryRow {
                elapsed_s: elapsed(),
                evaluations,
                best_cost: best.cost,
                best_reachability: best.reachability,
                best_links: best_design.links_kept(),
                best_joints: best_design.joints_kept(),
            };
            observer.generation(&row);
            history.push(row);
            if last_checkpoint.elapsed().as_secs_f64() >= o.checkpoint_interval {
                self.write_checkpoint(
                    optimizer.as_ref(),
                    generation,
                    evaluations,
                    elapsed(),
                    stale,
                    &history,
                )?;
                last_checkpoint = Instant::now();
            }
        }
        observer.finish();
        self.write_checkpoint(
            optimizer.as_ref(),
            generation,
            evaluations,
            elapsed(),
            stale,
            &history,
        )?;
        let best = optimizer
            .best()
            .cloned()
            .ok_or_else(|| Error::invalid("budget", 0, "the run stopped before any evaluation"))?;
        let (report, breakdown) = objective.evaluate_full(&best.x, best.stream, best.progress);
        let summary = RunSummary {
            design: objective.space().decode(&best.x),
            cost: breakdown.cost,
            reachability: breakdown.reachability,
            links_kept: breakdown.links_kept,
            joints_kept: breakdown.joints_kept,
            evaluations,
            generations: generation,
            elapsed_s: elapsed(),
            seed: o.seed,
            optimizer: optimizer.name().to_string(),
            checker: self.planner.checker.name().to_string(),
            l_max: objective.planner_at(best.progress).l_max,
            stopped,
            breakdown,
        };
        self.write_results(&summary, &report, &history)?;
        Ok(summary)
    }

    fn write_checkpoint(
        &self,
        optimizer: &dyn Optimizer,
        generation: u64,
        evaluations: u64,
        elapsed_s: f64,
        stale: usize,
        history: &[HistoryRow],
    ) -> Result<()> {
        let c = Checkpoint {
            scenario: self.scenario_path.clone(),
            planner: self.planner.clone(),
            options: self.options.clone(),
            generation,
            evaluations,
            elapsed_s,
            stale,
            history: history.to_vec(),
            state: optimizer.save(),
        };
        let json = serde_json::to_string(&c).expect("a checkpoint serialises");
        write_atomic(&self.out.join(files::CHECKPOINT), json.as_bytes())
    }

    fn write_results(
        &self,
        summary: &RunSummary,
        report: &ReachReport,
        history: &[HistoryRow],
    ) -> Result<()> {
        let best = serde_json::to_string_pretty(summary).expect("a summary serialises");
        write_atomic(&self.out.join(files::BEST), best.as_bytes())?;
        write_atomic(&self.out.join(files::REACH), report.to_json().as_bytes())?;
        crate::export::write_urdf(&summary.design, &self.out.join(files::URDF))?;
        crate::export::trajectory::write_trajectories(report, &self.out.join(files::TRAJECTORIES))?;
        let mut csv = String::from("elapsed_s,evaluations,best_cost,best_reachability\n");
        for r in history {
            csv.push_str(&format!(
                "{:.3},{},{},{}\n",
                r.elapsed_s, r.evaluations, r.best_cost, r.best_reachability
            ));
        }
        write_atomic(&self.out.join(files::HISTORY), csv.as_bytes())?;
        let svg = crate::export::plot::convergence_svg(
            &format!(
                "{} — {} + {}",
                self.scenario.name, summary.optimizer, summary.checker
            ),
            history,
        );
        write_atomic(&self.out.join(files::PLOT), svg.as_bytes())
    }
}

/// Evaluations per second over a history (0 when too short).
pub fn rate(history: &[HistoryRow]) -> f64 {
    match history.last() {
        Some(r) if r.elapsed_s > 0.0 => r.evaluations as f64 / r.elapsed_s,
        _ => 0.0,
    }
}
