//! What a run produces, apart from the runner that produces it: the history rows, the run's
//! summary (`best.json`) and the names of the files in its output directory. The exports
//! (`export::plot`, `export::view`) read these types; the runner writes them.

use super::islands::Migration;
use super::objective::Breakdown;
use crate::Design;
use serde::{Deserialize, Serialize};

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

/// One row of `islands.csv`: an island after a generation and its migration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IslandRow {
    /// Generation (from 1).
    pub generation: u64,
    /// Island index (from 0).
    pub island: usize,
    /// Evaluations of this island so far.
    pub evaluations: u64,
    /// The island's best cost so far (a migrant counts once it has arrived).
    pub best_cost: f64,
    /// Reachability of that design.
    pub best_reachability: f64,
}

/// Where an island job's results came from, as `best.json` records it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IslandsInfo {
    /// Number of islands.
    pub islands: usize,
    /// Migration settings.
    pub migration: Migration,
    /// The island whose best design was the job's best before the final re-check.
    pub best_island: usize,
}

/// How `R` of a run's result held when re-checked with fresh planner seeds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustReachability {
    /// Planner seeds (random streams) of the re-check.
    pub seeds: usize,
    /// Stream of the first of them (the others follow) with the run's seed.
    pub first_stream: u64,
    /// Lowest `R` over the seeds: the robust figure the result is chosen by.
    pub min: f64,
    /// Mean `R`.
    pub mean: f64,
    /// Highest `R`.
    pub max: f64,
    /// `R` for each seed.
    pub values: Vec<f64>,
    /// Distinct final candidates that were re-checked.
    pub candidates: usize,
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
    /// Seconds spent. Wall-clock time is not fixed by the seed, so it is written to
    /// `time.json` ([`files::TIME`]), not to `best.json`: two runs with the same seed write the
    /// same `best.json`, byte for byte.
    #[serde(skip)]
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
    /// Random stream (with the planner seed `seed`) of the planner run that produced
    /// `reachability`: `kinsynth reach --design best.json` replays it.
    pub stream: u64,
    /// Planner settings of that run (after overrides and any schedule).
    pub planner: crate::planning::PlannerConfig,
    /// `R` of the result re-checked with fresh planner seeds (absent when the re-check is off).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust_reachability: Option<RobustReachability>,
    /// The cost of Eq. 23 with the lowest re-checked `R`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust_cost: Option<f64>,
    /// The islands of an island job (absent for one population).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub islands: Option<IslandsInfo>,
    /// Seconds the final re-check took (included in `elapsed_s`; not written to `best.json`).
    #[serde(skip)]
    pub recheck_s: f64,
}

/// Names of the files a run writes into its output directory.
pub mod files {
    /// The best design and its figures.
    pub const BEST: &str = "best.json";
    /// The run's wall-clock seconds (`elapsed_s`, `recheck_s`), kept apart from `best.json`.
    pub const TIME: &str = "time.json";
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
    /// Its SRDF: planning group and allowed-collision matrix.
    pub const SRDF: &str = "robot.srdf";
    /// The browser report: the scene, the best design and its paths in 3D, with the run's
    /// convergence, cost breakdown and settings.
    pub const REPORT: &str = "report.html";
    /// One row per island per generation (island jobs only).
    pub const ISLANDS: &str = "islands.csv";
    /// Folder of the joint trajectories of the best design, one pair of files per reached task.
    pub const TRAJECTORIES: &str = "trajectories";
}
