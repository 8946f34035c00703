//! Run control: budgets, early stopping, progress display, history, checkpoints and resume.

use super::asa::Asa;
use super::ga::{Ga, GaParams};
use super::objective::Objective;
pub use super::output::{files, HistoryRow, RobustReachability, RunSummary};
use super::pso::{Pso, PsoParams};
use super::{Cutoff, Evaluated, Optimizer, StepContext};
use crate::error::{Error, Result};
use crate::io::write_atomic;
use crate::planning::ReachReport;
use crate::scenario::{Algorithm, ObjectiveWeights, Scenario};
use crate::Design;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

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
    /// Fresh planner seeds the final candidates are re-checked with before the run ends
    /// (0: no re-check).
    #[serde(default = "default_recheck_seeds")]
    pub recheck_seeds: usize,
    /// Extra planner runs that confirm every claimed `R = 1` during the run
    /// ([`Objective::with_confirmation`]).
    #[serde(default)]
    pub confirm_seeds: usize,
}

fn default_recheck_seeds() -> usize {
    crate::scenario::OptimizerConfig::default().recheck_seeds
}

/// The largest number of re-check seeds or confirmation runs a run accepts.
pub const MAX_SEEDS: usize = 1000;

impl RunOptions {
    /// Checks the budgets and counts: finite, non-negative seconds, at least one evaluation,
    /// at most [`MAX_SEEDS`] seeds. Errors name the field (`time_limit`, …) and the value.
    pub fn validate(&self) -> Result<()> {
        self.validate_in("")
    }

    /// As [`RunOptions::validate`], the fields named under `section` (`options.`, as a
    /// checkpoint holds them).
    pub fn validate_in(&self, section: &str) -> Result<()> {
        let name = |field: &str| format!("{section}{field}");
        if let Some(t) = self.time_limit {
            check_seconds(&name("time_limit"), t)?;
        }
        check_seconds(&name("checkpoint_interval"), self.checkpoint_interval)?;
        if self.evaluations == Some(0) {
            return Err(Error::invalid(name("evaluations"), 0, "must be at least 1"));
        }
        for (field, n) in [
            ("recheck_seeds", self.recheck_seeds),
            ("confirm_seeds", self.confirm_seeds),
        ] {
            if n > MAX_SEEDS {
                return Err(Error::invalid(
                    name(field),
                    n,
                    format!("must be at most {MAX_SEEDS}"),
                ));
            }
        }
        Ok(())
    }
}

/// Checks planner settings read from a checkpoint or a `best.json` as a scenario's are checked;
/// errors name the field (`planner.l_max`, …).
pub fn check_planner(p: &crate::planning::PlannerConfig) -> Result<()> {
    let positive = |field: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(Error::invalid(field, v, "must be positive and finite"))
        }
    };
    positive("planner.l_max", p.l_max)?;
    positive("planner.goal_tolerance", p.goal_tolerance)?;
    if let Some(t) = p.time_limit {
        positive("planner.time_limit", t)?;
    }
    if !(p.lambda.is_finite() && p.lambda >= 0.0) {
        return Err(Error::invalid(
            "planner.lambda",
            p.lambda,
            "must be finite and not negative",
        ));
    }
    if !(0.0..=1.0).contains(&p.goal_bias) {
        return Err(Error::invalid(
            "planner.goal_bias",
            p.goal_bias,
            "must lie in [0, 1]",
        ));
    }
    if p.max_iterations == 0 {
        return Err(Error::invalid(
            "planner.max_iterations",
            0,
            "must be at least 1",
        ));
    }
    use crate::limits::{MAX_BUDGET_GROWTH, MAX_POSTURES};
    if p.postures > MAX_POSTURES {
        return Err(Error::invalid(
            "planner.postures",
            p.postures,
            format!("must be at most {MAX_POSTURES}"),
        ));
    }
    if !(1..=MAX_BUDGET_GROWTH).contains(&p.budget_growth) {
        return Err(Error::invalid(
            "planner.budget_growth",
            p.budget_growth,
            format!("must lie in 1..={MAX_BUDGET_GROWTH}"),
        ));
    }
    Ok(())
}

/// A number of seconds given as `field` must be finite and not negative.
pub fn check_seconds(field: &str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            field,
            value,
            "must be a finite, non-negative number of seconds",
        ))
    }
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
    /// Hash of the scenario file's contents when the run started ([`fingerprint`]).
    #[serde(default)]
    pub scenario_hash: Option<String>,
    /// The scenario's shape when the run started: links, free variables, obstacles, tasks.
    #[serde(default)]
    pub scenario_shape: Option<ScenarioShape>,
    /// Hash of the contents of the scenario's mesh files when the run started
    /// ([`meshes_fingerprint`]); absent for a scenario without meshes (and in checkpoints of
    /// older versions, which bound the scenario file only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub meshes_hash: Option<String>,
    /// An island job's islands (then `state` is the array of their states, island by island).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub islands: Option<super::islands::IslandsCheckpoint>,
    /// FNV-1a hash of the checkpoint's own content ([`content_hash`]), which a resume checks:
    /// a checkpoint changed after the run wrote it (a hand edit, a flipped bit that leaves
    /// valid JSON) would resume to another result without a word.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checksum: Option<String>,
    /// What [`Checkpoint::checksum`] says of the content read (not part of the file).
    #[serde(skip)]
    pub integrity: Integrity,
}

/// What a checkpoint's [`Checkpoint::checksum`] says of the content read.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Integrity {
    /// The content hashes to the recorded checksum (or the checkpoint was not read from a
    /// file).
    #[default]
    Intact,
    /// No checksum is recorded (an older version wrote the checkpoint).
    Unsealed,
    /// The content has changed since it was written: it hashes to `now`, the checkpoint
    /// records `recorded`.
    Changed {
        /// The checksum the checkpoint records.
        recorded: String,
        /// The hash of its content.
        now: String,
    },
}

/// The hash [`Checkpoint::checksum`] records: [`fingerprint`] of the checkpoint's JSON value
/// without its `checksum` key (`value` must not hold it), written compactly with its keys
/// sorted (as `serde_json` holds them), so that the file's own layout does not matter.
pub fn content_hash(value: &serde_json::Value) -> String {
    fingerprint(value.to_string().as_bytes())
}

/// One free design variable as a checkpoint records it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariableShape {
    /// Name, e.g. `link3.a`.
    pub name: String,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
}

impl std::fmt::Display for VariableShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} in [{}, {}]", self.name, self.lower, self.upper)
    }
}

/// What a checkpoint must match in the scenario it resumes: the design space's variables and
/// the sizes of the workspace.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScenarioShape {
    /// Links of the generic chain (`robot.links`).
    pub links: usize,
    /// Free design variables, in vector order.
    pub variables: Vec<VariableShape>,
    /// Obstacles.
    pub obstacles: usize,
    /// Task points.
    pub tasks: usize,
}

impl ScenarioShape {
    /// The shape of a scenario.
    pub fn of(s: &Scenario) -> Self {
        ScenarioShape {
            links: s.space.template().links.len(),
            variables: s
                .space
                .variables()
                .iter()
                .map(|v| VariableShape {
                    name: v.name(),
                    lower: v.lower,
                    upper: v.upper,
                })
                .collect(),
            obstacles: s.workspace.obstacles.len(),
            tasks: s.workspace.tasks.len(),
        }
    }

    /// The first difference between the shape a checkpoint recorded (`self`) and `now`, as
    /// "robot.links was 8, now 10".
    pub fn difference(&self, now: &ScenarioShape) -> Option<String> {
        let count = |what: &str, was: usize, now: usize| {
            (was != now).then(|| format!("{what} was {was}, now {now}"))
        };
        if let Some(d) = count("robot.links", self.links, now.links) {
            return Some(d);
        }
        if let Some(d) = count(
            "the number of free design variables",
            self.variables.len(),
            now.variables.len(),
        ) {
            let first = self
                .variables
                .iter()
                .zip(&now.variables)
                .position(|(a, b)| a != b)
                .unwrap_or(self.variables.len().min(now.variables.len()));
            let show = |v: Option<&VariableShape>| v.map_or("none".to_string(), |v| v.to_string());
            return Some(format!(
                "{d} (first difference: variable {first} was {}, now {})",
                show(self.variables.get(first)),
                show(now.variables.get(first))
            ));
        }
        if let Some((i, (a, b))) = self
            .variables
            .iter()
            .zip(&now.variables)
            .enumerate()
            .find(|(_, (a, b))| a != b)
        {
            return Some(format!("free variable {i} was {a}, now {b}"));
        }
        count("the number of obstacles", self.obstacles, now.obstacles)
            .or_else(|| count("the number of tasks", self.tasks, now.tasks))
    }
}

/// The fingerprint of the contents of a scenario's mesh files, each once, in the order of the
/// obstacles that first use them (`None` for a scenario without meshes): a checkpoint records
/// it, so that a mesh changed between a run and its resume is found, as a changed scenario
/// file is.
pub fn meshes_fingerprint(s: &Scenario) -> Result<Option<String>> {
    let mut seen: std::collections::HashSet<&Path> = std::collections::HashSet::new();
    let mut each = String::new();
    for o in &s.workspace.obstacles {
        if let crate::world::ObstacleShape::Mesh { file, .. } = &o.geometry {
            if !seen.insert(file.as_path()) {
                continue;
            }
            let bytes = crate::limits::read_file(file, crate::limits::MAX_MESH_FILE_BYTES)
                .map_err(|source| Error::Read {
                    path: file.clone(),
                    source,
                })?;
            each.push_str(&fingerprint(&bytes));
            each.push('\n');
        }
    }
    Ok((!seen.is_empty()).then(|| fingerprint(each.as_bytes())))
}

/// A stable fingerprint of a file's contents: 64-bit FNV-1a, as `fnv1a64:` and 16 hex digits.
/// The same bytes give the same string on every run and platform.
pub fn fingerprint(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("fnv1a64:{h:016x}")
}

/// Marks a recorded planner table (a `best.json`'s `planner`, a checkpoint's) that has no
/// `ik_hold_limits` as clamping: such records were written when the key was left out for its
/// default of the time, false, so they replay and resume as they ran.
fn clamping_unless_recorded(planner: &mut serde_json::Value) {
    if let Some(map) = planner.as_object_mut() {
        map.entry("ik_hold_limits")
            .or_insert(serde_json::Value::Bool(false));
    }
}

/// The random stream, planner seed and settings of the evaluation that produced a `best.json`:
/// enough for `kinsynth reach` to replay it.
#[derive(Clone, Debug, PartialEq)]
pub struct Replay {
    /// Planner seed (the run's seed).
    pub seed: u64,
    /// Random stream of the planner run.
    pub stream: u64,
    /// Planner settings of that run.
    pub planner: crate::planning::PlannerConfig,
    /// The `R` the file records for that run, which the replay gives again (when the file is
    /// as the run wrote it).
    pub recorded: Option<f64>,
}

impl Replay {
    /// The replay data of a `best.json`, or `None` for another design file (or a `best.json`
    /// written before streams were recorded).
    pub fn from_best(path: &Path) -> Result<Option<Replay>> {
        let text = crate::limits::read_text(path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(
            |source| Error::Read {
                path: path.to_path_buf(),
                source,
            },
        )?;
        let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| Error::Parse {
            file: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let (Some(seed), Some(stream), Some(planner)) =
            (v.get("seed"), v.get("stream"), v.get("planner"))
        else {
            return Ok(None);
        };
        let parse = |field: &str, e: serde_json::Error| Error::Parse {
            file: path.to_path_buf(),
            message: format!("{field}: {e}"),
        };
        let mut planner = planner.clone();
        clamping_unless_recorded(&mut planner);
        let planner: crate::planning::PlannerConfig =
            from_value_at(planner).map_err(|m| Error::Parse {
                file: path.to_path_buf(),
                message: format!("planner{m}"),
            })?;
        check_planner(&planner).map_err(|e| e.in_file(path))?;
        Ok(Some(Replay {
            seed: serde_json::from_value(seed.clone()).map_err(|e| parse("seed", e))?,
            stream: serde_json::from_value(stream.clone()).map_err(|e| parse("stream", e))?,
            planner,
            recorded: v.get("reachability").and_then(serde_json::Value::as_f64),
        }))
    }
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

/// The designs a fresh run starts from, encoded: the largest design (it reaches most), then
/// the largest design with one link removed, for each removable link
/// ([`DesignSpace::largest_shortened`]). A GA or a swarm puts them all into its first
/// generation, the rest being random; ASA starts from the first. When the largest arm is too
/// long for the cell, its one-link-shorter neighbours often reach every task, and they are the
/// first step of the topology synthesis the objective rewards (paper Eq. 28).
pub(crate) fn initial_designs(space: &crate::design::DesignSpace) -> Vec<Vec<f64>> {
    std::iter::once(space.largest())
        .chain(space.largest_shortened())
        .map(|d| space.encode(&d))
        .collect()
}

/// Deserialises `value`; a failure's message starts with the path of the value at fault
/// (`.population[5].x[2]: invalid type: map, expected f64`), or with `: ` for the whole value.
fn from_value_at<T: serde::de::DeserializeOwned>(
    value: serde_json::Value,
) -> std::result::Result<T, String> {
    crate::strict::deserialize(value).map_err(|e| {
        let path = crate::strict::path(&e);
        if path == "." {
            format!(": {}", e.inner())
        } else {
            format!(".{path}: {}", e.inner())
        }
    })
}

/// Restores the optimiser of a checkpoint and checks its state against the design space
/// ([`Optimizer::validate`]). Errors name the state's field.
fn load_optimizer(
    algorithm: Algorithm,
    state: serde_json::Value,
    space: &crate::design::DesignSpace,
) -> Result<Box<dyn Optimizer>> {
    let bad = |m: String| Error::Parse {
        file: PathBuf::new(),
        message: format!("state{m}"),
    };
    let optimizer: Box<dyn Optimizer> = match algorithm {
        Algorithm::Ga => Box::new(from_value_at::<Ga>(state).map_err(bad)?),
        Algorithm::Pso => Box::new(from_value_at::<Pso>(state).map_err(bad)?),
        Algorithm::Asa => Box::new(from_value_at::<Asa>(state).map_err(bad)?),
    };
    let (lower, upper, seeds) = (space.lower(), space.upper(), initial_designs(space));
    let bounds = super::StateSpace {
        lower: &lower,
        upper: &upper,
        seeds: &seeds,
    };
    optimizer.validate(&bounds).map_err(|m| Error::Parse {
        file: PathBuf::new(),
        message: format!("state.{m}"),
    })?;
    Ok(optimizer)
}

/// Stream offset of the optimisers' own random numbers, apart from the planners' streams.
const OPTIMIZER_STREAM: u64 = 1 << 48;

/// Stream offset of the final re-check: seed `j` of the re-check plans with the stream
/// `RECHECK_STREAM + j` for every candidate (common random numbers).
pub const RECHECK_STREAM: u64 = 1 << 50;

/// Distinct final candidates re-checked at the end of a run (the best by cost).
pub const RECHECK_CANDIDATES: usize = 8;

/// The lowest cost (paper Eq. 23) `design` can have for any reachability `R` in `[0, 1]`: a
/// bound no re-check can go below. The cost is affine in `R` below 1 and has its own value at
/// `R = 1`, so the bound is the least of the values at 0, just below 1, and 1 (each computed
/// as [`super::objective::breakdown`] computes it, so that the bound holds in floating point).
pub(crate) fn lowest_possible_cost(design: &Design, weights: &ObjectiveWeights) -> f64 {
    let below_one = 1.0 - f64::EPSILON / 2.0;
    [0.0, below_one, 1.0]
        .into_iter()
        .map(|r| super::objective::breakdown(design, r, weights).cost)
        .fold(f64::INFINITY, f64::min)
}

/// The re-check's choice among `chosen` (distinct candidates in run order, with their
/// designs): `recheck(e)` gives a candidate's `R` for each of the `k` re-check seeds. Returns
/// the index of the candidate whose cost is lowest with its lowest re-checked `R` (ties:
/// higher mean `R`, then lower cost in the run, then run order) and its figures, whose
/// `candidates` counts the candidates re-checked.
///
/// Candidates are re-checked in the order of [`lowest_possible_cost`] (ties: run order), and
/// once that bound exceeds the lowest robust cost found, the rest are left out: each of them
/// would cost more than the pick whatever its re-check gave, so the choice is the one of
/// re-checking every candidate.
pub(crate) fn pick_rechecked(
    chosen: &[(Evaluated, Design)],
    weights: &ObjectiveWeights,
    k: usize,
    mut recheck: impl FnMut(&Evaluated) -> Vec<f64>,
) -> Result<(usize, RobustReachability)> {
    let floors: Vec<f64> = chosen
        .iter()
        .map(|(_, d)| lowest_possible_cost(d, weights))
        .collect();
    let mut order: Vec<usize> = (0..chosen.len()).collect();
    order.sort_by(|&a, &b| floors[a].total_cmp(&floors[b]).then(a.cmp(&b)));
    // Per candidate, once re-checked: its robust cost, mean R and figures.
    let mut done: Vec<Option<(f64, f64, RobustReachability)>> = vec![None; chosen.len()];
    let mut lowest = f64::INFINITY;
    let mut rechecked = 0;
    for &c in &order {
        if floors[c] > lowest {
            break; // neither this candidate nor a later one can beat or tie the pick
        }
        let (e, design) = &chosen[c];
        let values = recheck(e);
        let min = values.iter().copied().fold(f64::INFINITY, f64::min);
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mean = values.iter().sum::<f64>() / k as f64;
        let robust_cost = super::objective::breakdown(design, min, weights).cost;
        lowest = lowest.min(robust_cost);
        rechecked += 1;
        let figures = RobustReachability {
            seeds: k,
            first_stream: RECHECK_STREAM,
            min,
            mean,
            max,
            values,
            candidates: 0,
        };
        done[c] = Some((robust_cost, mean, figures));
    }
    // The pick among the re-checked, in run order as if every candidate had been re-checked
    // (one left out could not have been picked).
    let mut pick: Option<(f64, f64, usize)> = None;
    for (c, d) in done.iter().enumerate() {
        let Some((robust_cost, mean, _)) = d else {
            continue;
        };
        let (robust_cost, mean) = (*robust_cost, *mean);
        let better = match pick {
            None => true,
            Some((cost, m, p)) => {
                robust_cost < cost
                    || (robust_cost == cost
                        && (mean > m || (mean == m && chosen[c].0.cost < chosen[p].0.cost)))
            }
        };
        if better {
            pick = Some((robust_cost, mean, c));
        }
    }
    let (_, _, c) = pick.ok_or_else(|| Error::invalid("recheck", 0, "no candidate"))?;
    let (_, _, mut robust) = done[c].take().expect("the pick was re-checked");
    robust.candidates = rechecked;
    Ok((c, robust))
}

/// The counters of a run that a checkpoint records.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Counters {
    /// Generations done.
    pub generation: u64,
    /// Evaluations done.
    pub evaluations: u64,
    /// Seconds spent.
    pub elapsed_s: f64,
    /// Generations since the best cost last improved.
    pub stale: usize,
}

/// What [`Runner::prepare`] gives a run: its objective and what binds its checkpoints to the
/// scenario.
pub(crate) struct Setup {
    /// The objective (paper Eq. 23) with the run's planner settings and seed.
    pub objective: Objective,
    /// The scenario file's fingerprint.
    pub hash: String,
    /// The scenario's shape.
    pub shape: ScenarioShape,
    /// The fingerprint of its mesh files' contents ([`meshes_fingerprint`]).
    pub meshes_hash: Option<String>,
    /// Warnings about the checkpoint resumed, printed once the whole checkpoint is known to
    /// be good (an error about it then stays alone on one line).
    pub warnings: Vec<String>,
}

impl Setup {
    /// Prints the warnings, if any, to standard error (once the checkpoint has loaded).
    pub(crate) fn warn(&self) {
        for w in &self.warnings {
            eprintln!("warning: {w}");
        }
    }
}

impl Checkpoint {
    /// Checks that the counters agree with each other, as a run writes them: a generation
    /// makes at least one evaluation, the generations without improvement are some of the
    /// generations made, and the history's evaluations rise to at most those made. A
    /// checkpoint whose checksum was made anew after an edit is caught here where the edit
    /// breaks them (`stale = 1000000` would end the run as converged).
    pub(crate) fn check_counters(&self) -> Result<()> {
        if self.generation > self.evaluations {
            return Err(Error::invalid(
                "generation",
                self.generation,
                format!(
                    "more than the evaluations made ({}): a generation makes at least one",
                    self.evaluations
                ),
            ));
        }
        if self.stale as u64 > self.generation {
            return Err(Error::invalid(
                "stale",
                self.stale,
                format!(
                    "more generations without improvement than generations made ({})",
                    self.generation
                ),
            ));
        }
        let mut before = 0;
        for (i, row) in self.history.iter().enumerate() {
            if row.evaluations < before || row.evaluations > self.evaluations {
                return Err(Error::invalid(
                    format!("history[{i}].evaluations"),
                    row.evaluations,
                    format!(
                        "must lie between the row before's ({before}) and the evaluations made ({})",
                        self.evaluations
                    ),
                ));
            }
            before = row.evaluations;
        }
        Ok(())
    }
}

impl Integrity {
    /// Refuses a checkpoint (read from `path`) whose content has changed since it was
    /// written; one that records no checksum passes. A resume asks once the rest of the
    /// checkpoint has been checked, so that a value out of its domain is named by itself.
    pub fn check(&self, path: &Path) -> Result<()> {
        match self {
            Integrity::Changed { recorded, now } => Err(Error::invalid(
                "checksum",
                recorded,
                format!("the content hashes to {now}: the checkpoint was changed after the run wrote it, and would resume to another result; use the checkpoint as written"),
            )
            .in_file(path)),
            Integrity::Intact | Integrity::Unsealed => Ok(()),
        }
    }

    /// The warning for a checkpoint (read from `path`) that records no checksum, which a
    /// resume and `merge` print.
    pub fn warning(&self, path: &Path) -> Option<String> {
        (*self == Integrity::Unsealed).then(|| {
            format!(
                "{}: the checkpoint records no checksum (an older version wrote it); changes made to it since are not detected",
                path.display()
            )
        })
    }
}

/// The end of a run, as [`Runner::conclude`] takes it.
pub(crate) struct Conclusion<'a> {
    /// Optimiser name.
    pub optimizer: &'static str,
    /// The final candidates (population, swarm, annealer; of every island).
    pub candidates: Vec<&'a Evaluated>,
    /// The best point of the run.
    pub best: Evaluated,
    /// Counters at the end.
    pub counters: Counters,
    /// Seconds since the run started (over resumed sessions).
    pub elapsed: &'a dyn Fn() -> f64,
    /// Why it stopped.
    pub stopped: String,
    /// Its history.
    pub history: &'a [HistoryRow],
    /// An island job's islands.
    pub islands: Option<super::islands::IslandsInfo>,
}

/// Why a run stopped when its time limit was reached (between generations or within one).
pub(crate) const TIME_LIMIT_REACHED: &str = "time limit reached";

/// Why a run stops when its evaluation budget is spent.
pub(crate) const EVALUATION_BUDGET_SPENT: &str = "evaluation budget spent";

/// Why a step was cut short: Ctrl-C, else the evaluation budget when it ran out (`by_budget`),
/// else the time limit.
pub(crate) fn cut_reason(stop: &AtomicBool, by_budget: bool) -> String {
    if stop.load(Ordering::SeqCst) {
        "interrupted".to_string()
    } else if by_budget {
        EVALUATION_BUDGET_SPENT.to_string()
    } else {
        TIME_LIMIT_REACHED.to_string()
    }
}

/// The random numbers of an optimiser step: the run's seed on stream
/// `OPTIMIZER_STREAM + stream` (the generation, for one population).
pub(crate) fn step_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(OPTIMIZER_STREAM.wrapping_add(stream));
    rng
}

/// The row of `history.csv` for the best point `best` after `evaluations` evaluations.
pub(crate) fn history_row(
    objective: &Objective,
    best: &Evaluated,
    evaluations: u64,
    elapsed_s: f64,
) -> Result<HistoryRow> {
    let design = objective.space().try_decode(&best.x)?;
    Ok(HistoryRow {
        elapsed_s,
        evaluations,
        best_cost: best.cost,
        best_reachability: best.reachability,
        best_links: design.links_kept(),
        best_joints: design.joints_kept(),
    })
}

/// Observes a run: called after every generation (for progress displays).
pub trait Observer {
    /// The state after a generation.
    fn generation(&mut self, row: &HistoryRow);
    /// Every island's state after a generation (island jobs only, after [`Self::generation`]).
    fn islands(&mut self, _rows: &[super::islands::IslandRow]) {}
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
        let parse = |e: serde_json::Error| Error::Parse {
            file: path.clone(),
            message: e.to_string(),
        };
        let mut v: serde_json::Value = serde_json::from_str(&text).map_err(parse)?;
        // The content as written, without its checksum and before anything read is filled in.
        let recorded = v.as_object_mut().and_then(|m| m.remove("checksum"));
        let now = content_hash(&v);
        if let Some(planner) = v.get_mut("planner") {
            clamping_unless_recorded(planner);
        }
        let mut c: Checkpoint = from_value_at(v).map_err(|m| Error::Parse {
            file: path.clone(),
            message: m.trim_start_matches(['.', ':', ' ']).to_string(),
        })?;
        c.checksum = match recorded {
            None => None,
            Some(serde_json::Value::String(r)) => Some(r),
            Some(other) => {
                return Err(Error::invalid(
                    "checksum",
                    other,
                    "must be a string, as the run writes it (fnv1a64:…)",
                )
                .in_file(&path))
            }
        };
        c.integrity = match &c.checksum {
            None => Integrity::Unsealed,
            Some(recorded) if *recorded == now => Integrity::Intact,
            Some(recorded) => Integrity::Changed {
                recorded: recorded.clone(),
                now,
            },
        };
        c.planner.validate().map_err(|e| e.in_file(&path))?;
        // The time limit of a resumed run counts from the seconds already spent: a negative
        // or non-finite count would never (or at once) reach it.
        check_seconds("elapsed_s", c.elapsed_s).map_err(|e| e.in_file(&path))?;
        // The history is carried into the run's plots and averaged by `merge`.
        super::output::check_history(&c.history).map_err(|e| e.in_file(&path))?;
        // Counters that disagree in a changed checkpoint: the change is named.
        if let Err(e) = c.check_counters() {
            c.integrity.check(&path)?;
            return Err(e.in_file(&path));
        }
        Ok(c)
    }

    /// Runs until a budget is spent, the run converges (`R = 1` and no improvement for
    /// `patience` generations) or `stop` is raised (Ctrl-C); then writes `best.json`,
    /// `history.csv`, `reach.json`, `convergence.svg`, `report.html`, `robot.urdf`,
    /// `trajectories/` and a final checkpoint. With `resume`,
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
        let setup = self.prepare(resume.as_ref())?;
        let objective = &setup.objective;
        let o = &self.options;
        // A new run's first step is always taken, whatever its time limit: it evaluates at
        // least its first design ([`evaluate_batch`]).
        let mut first = resume.is_none();
        let (
            mut optimizer,
            mut generation,
            mut evaluations,
            elapsed_before,
            mut stale,
            mut history,
        ) = match resume {
            Some(c) => {
                if let Some(i) = &c.islands {
                    return Err(Error::invalid(
                        "islands",
                        i.islands,
                        "the checkpoint holds an island job: resume it with --islands",
                    )
                    .in_file(self.checkpoint_path()));
                }
                let optimizer = load_optimizer(o.algorithm, c.state, &self.scenario.space)
                    .map_err(|e| e.in_file(self.checkpoint_path()))?;
                c.integrity.check(&self.checkpoint_path())?;
                setup.warn();
                (
                    optimizer,
                    c.generation,
                    c.evaluations,
                    c.elapsed_s,
                    c.stale,
                    c.history,
                )
            }
            None => (self.new_optimizer(), 0, 0, 0.0, 0, Vec::new()),
        };
        let start = Instant::now();
        let elapsed = || elapsed_before + start.elapsed().as_secs_f64();
        let mut last_checkpoint = Instant::now();
        let mut best_cost = optimizer.best().map_or(f64::INFINITY, |b| b.cost);
        let deadline = self.deadline(start, elapsed_before);
        // The points of a generation cut short (time limit, Ctrl-C): offered to the result only.
        let mut late: Vec<Evaluated> = Vec::new();
        let stopped = loop {
            let clock = (!first).then(elapsed);
            first = false;
            if let Some(why) = self.stop_reason(stop, evaluations, clock, optimizer.best(), stale) {
                break why;
            }
            let before = optimizer.snapshot();
            let left = self.evaluations_left(evaluations);
            let report = optimizer.step(StepContext {
                problem: objective,
                rng: &mut step_rng(o.seed, generation),
                first_stream: evaluations,
                stride: 1,
                progress: self.progress(evaluations, elapsed()),
                cutoff: Cutoff {
                    deadline,
                    stop: Some(stop),
                    budget: left,
                    may_skip_all: false,
                },
            });
            if let Some(cut) = report.cut {
                // The state stays that of the last whole generation (which a resume repeats
                // from, with the same streams); the points evaluated still count for the result.
                optimizer = before;
                let by_budget = left.is_some_and(|l| report.evaluations >= l);
                late = cut.evaluated;
                break cut_reason(stop, by_budget);
            }
            evaluations = evaluations.saturating_add(report.evaluations);
            generation = generation.saturating_add(1);
            let best = optimizer.best().expect("a best after a step").clone();
            if best.cost < best_cost {
                best_cost = best.cost;
                stale = 0;
            } else {
                stale = stale.saturating_add(1);
            }
            let row = history_row(objective, &best, evaluations, elapsed())?;
            observer.generation(&row);
            history.push(row);
            super::output::thin_history(&mut history);
            if last_checkpoint.elapsed().as_secs_f64() >= o.checkpoint_interval {
                self.write_checkpoint(
                    optimizer.save(),
                    None,
                    Counters {
                        generation,
                        evaluations,
                        elapsed_s: elapsed(),
                        stale,
                    },
                    &history,
                    &setup,
                )?;
                last_checkpoint = Instant::now();
            }
        };
        observer.finish();
        let counters = Counters {
            generation,
            evaluations,
            elapsed_s: elapsed(),
            stale,
        };
        self.write_checkpoint(optimizer.save(), None, counters, &history, &setup)?;
        let mut best = optimizer.best().cloned();
        for e in &late {
            super::keep_best(&mut best, e);
        }
        let best = best.ok_or_else(|| self.nothing_evaluated(&stopped))?;
        let mut candidates = optimizer.candidates();
        candidates.extend(&late);
        // history.csv ends with the cut generation, so that it agrees with best.json (the
        // checkpoint, written above, keeps the whole generations only).
        if !late.is_empty() {
            let total = evaluations.saturating_add(late.len() as u64);
            history.push(history_row(objective, &best, total, elapsed())?);
            super::output::thin_history(&mut history);
        }
        self.conclude(
            objective,
            Conclusion {
                optimizer: optimizer.name(),
                candidates,
                best,
                counters: Counters {
                    evaluations: evaluations.saturating_add(late.len() as u64),
                    ..counters
                },
                elapsed: &elapsed,
                stopped,
                history: &history,
                islands: None,
            },
        )
    }

    /// The checkpoint file of the run.
    pub(crate) fn checkpoint_path(&self) -> PathBuf {
        self.out.join(files::CHECKPOINT)
    }

    /// The run's options.
    pub(crate) fn options(&self) -> &RunOptions {
        &self.options
    }

    /// The scenario file (absolute when it could be resolved).
    pub(crate) fn scenario_path(&self) -> &Path {
        &self.scenario_path
    }

    /// The run's output directory.
    pub(crate) fn out(&self) -> &Path {
        &self.out
    }

    /// The scenario of the run.
    pub(crate) fn scenario(&self) -> &Scenario {
        self.scenario
    }

    /// Refuses a run of `islands` populations whose checkpoint could not be read back
    /// ([`crate::limits::check_population_variables`]); the error names the scenario.
    pub(crate) fn check_population(&self, islands: usize) -> Result<()> {
        let population = match self.options.algorithm {
            Algorithm::Ga | Algorithm::Pso => self.scenario.optimizer.population,
            Algorithm::Asa => 0,
        };
        crate::limits::check_population_variables(population, islands, self.scenario.space.dim())
            .map_err(|e| e.in_file(&self.scenario_path))
    }

    /// Binds a checkpoint to the scenario (hash and shape),
    /// checks the settings and builds the objective.
    pub(crate) fn prepare(&self, resume: Option<&Checkpoint>) -> Result<Setup> {
        let checkpoint_path = self.checkpoint_path();
        let scenario_bytes =
            crate::limits::read_file(&self.scenario_path, crate::limits::MAX_TEXT_FILE_BYTES)
                .map_err(|source| Error::Read {
                    path: self.scenario_path.clone(),
                    source,
                })?;
        let hash = fingerprint(&scenario_bytes);
        let shape = ScenarioShape::of(self.scenario);
        let meshes_hash = meshes_fingerprint(self.scenario)?;
        let mut warnings = Vec::new();
        if let Some(c) = resume {
            // A changed checkpoint that no longer binds (its recorded scenario hash or shape
            // edited) is named as changed, not as a changed scenario.
            let binding = self
                .check_binding(c, &hash, &shape)
                .and_then(|w| self.check_meshes(c, meshes_hash.as_deref()).map(|()| w))
                .map_err(|e| e.in_file(&checkpoint_path));
            if binding.is_err() {
                c.integrity.check(&checkpoint_path)?;
            }
            warnings.extend(binding?);
            if let Some(budget) = self.options.evaluations.filter(|&b| b < c.evaluations) {
                return Err(Error::invalid(
                    "--evaluations",
                    budget,
                    format!(
                        "the checkpoint has made {} evaluations already: a resumed run goes on from there (give at least that many, or start a new run)",
                        c.evaluations
                    ),
                ));
            }
            check_planner(&self.planner).map_err(|e| e.in_file(&checkpoint_path))?;
            warnings.extend(c.integrity.warning(&checkpoint_path));
            if let Some(w) = self.schedule_moved(c) {
                warnings.push(format!("{}: {w}", checkpoint_path.display()));
            }
        }
        // Resumed, the options are the checkpoint's (with the budgets given anew).
        let section = if resume.is_some() { "options." } else { "" };
        self.options
            .validate_in(section)
            .map_err(|e| e.in_file(&checkpoint_path))?;
        self.check_population(1)?;
        let objective = Objective::new(self.scenario, self.planner.clone(), self.options.seed)
            .with_confirmation(self.options.confirm_seeds);
        Ok(Setup {
            objective,
            hash,
            shape,
            meshes_hash,
            warnings,
        })
    }

    /// A fresh optimiser of the run's algorithm, started from [`initial_designs`].
    pub(crate) fn new_optimizer(&self) -> Box<dyn Optimizer> {
        let seeds = initial_designs(&self.scenario.space);
        make_optimizer(self.scenario, self.options.algorithm, seeds)
    }

    /// Restores an optimiser of the run's algorithm from a checkpoint's state.
    pub(crate) fn load_optimizer(&self, state: serde_json::Value) -> Result<Box<dyn Optimizer>> {
        load_optimizer(self.options.algorithm, state, &self.scenario.space)
    }

    /// Why the run stops before its next generation, if it does: Ctrl-C, a budget spent, or
    /// convergence (`R = 1` and no improvement for `patience` generations). The time limit is
    /// checked against `elapsed` when it is given.
    pub(crate) fn stop_reason(
        &self,
        stop: &AtomicBool,
        evaluations: u64,
        elapsed: Option<f64>,
        best: Option<&Evaluated>,
        stale: usize,
    ) -> Option<String> {
        let o = &self.options;
        if stop.load(Ordering::SeqCst) {
            return Some("interrupted".to_string());
        }
        if o.evaluations.is_some_and(|n| evaluations >= n) {
            return Some(EVALUATION_BUDGET_SPENT.to_string());
        }
        if o.time_limit.zip(elapsed).is_some_and(|(t, e)| e >= t) {
            return Some(TIME_LIMIT_REACHED.to_string());
        }
        match best {
            Some(b) if b.reachability >= 1.0 && stale >= o.patience => Some(format!(
                "converged: R = 1, no improvement for {stale} generations"
            )),
            _ => None,
        }
    }

    /// What is left of the evaluation budget after `done` evaluations (`None`: no budget).
    pub(crate) fn evaluations_left(&self, done: u64) -> Option<u64> {
        self.options.evaluations.map(|n| n.saturating_sub(done))
    }

    /// The error of a run that stopped (`stopped` says why) before it evaluated anything: only
    /// a resumed run can (a run's first design is always evaluated), so a spent time limit is
    /// the one its checkpoint records, unless the command line replaced it.
    pub(crate) fn nothing_evaluated(&self, stopped: &str) -> Error {
        match self.options.time_limit {
            Some(t) if stopped == TIME_LIMIT_REACHED => Error::invalid(
                "options.time_limit",
                t,
                "was spent before any design was evaluated: give a larger --time-limit (a total over the run)",
            )
            .in_file(self.checkpoint_path()),
            _ => Error::invalid("budget", 0, "the run stopped before any evaluation"),
        }
    }

    /// The instant the run's time limit is up, for a session started at `start` after
    /// `elapsed_before` seconds of earlier sessions (`None` without a time limit, or one
    /// beyond what the clock can represent).
    pub(crate) fn deadline(&self, start: Instant, elapsed_before: f64) -> Option<Instant> {
        let left = self.options.time_limit? - elapsed_before;
        // Limits are checked finite; a century stands for "later than any run".
        start.checked_add(Duration::from_secs_f64(left.clamp(0.0, 3.2e9)))
    }

    /// How far the run is, in [0, 1], by its budgets (for schedules).
    pub(crate) fn progress(&self, evaluations: u64, elapsed: f64) -> f64 {
        match (self.options.evaluations, self.options.time_limit) {
            (Some(n), Some(t)) => (evaluations as f64 / n as f64).max(elapsed / t),
            (Some(n), None) => evaluations as f64 / n as f64,
            (None, Some(t)) => elapsed / t,
            (None, None) => 0.0,
        }
        .clamp(0.0, 1.0)
    }

    /// Ends a run: re-checks the candidates, evaluates the result once more for its report
    /// and writes the results.
    pub(crate) fn conclude(&self, objective: &Objective, c: Conclusion<'_>) -> Result<RunSummary> {
        let o = &self.options;
        let recheck_start = Instant::now();
        let (best, robust) = self.recheck(objective, c.candidates, c.best)?;
        let recheck_s = recheck_start.elapsed().as_secs_f64();
        let evaluation = objective.evaluate_confirmed(&best.x, best.stream, best.progress);
        let (report, breakdown) = (evaluation.report, evaluation.breakdown);
        let robust_cost = robust.as_ref().map(|r| {
            super::objective::breakdown(
                &objective.space().decode(&best.x),
                r.min,
                objective.weights(),
            )
            .cost
        });
        let summary = RunSummary {
            design: objective.space().try_decode(&best.x)?,
            cost: breakdown.cost,
            reachability: breakdown.reachability,
            links_kept: breakdown.links_kept,
            joints_kept: breakdown.joints_kept,
            evaluations: c.counters.evaluations,
            generations: c.counters.generation,
            elapsed_s: (c.elapsed)(),
            seed: o.seed,
            optimizer: c.optimizer.to_string(),
            checker: self.planner.checker.name().to_string(),
            l_max: objective.planner_at(best.progress).l_max,
            stopped: c.stopped,
            breakdown,
            stream: evaluation.stream,
            planner: objective.planner_at(best.progress),
            robust_reachability: robust,
            robust_cost,
            islands: c.islands,
            recheck_s,
        };
        // The report page also draws the planner's tree: the same plan, its tree kept.
        let drawn = objective.plan_with_tree(&best.x, evaluation.stream, best.progress);
        debug_assert_eq!(drawn.targets, report.targets);
        self.write_results(&summary, &report, &drawn, c.history)?;
        Ok(summary)
    }

    /// Why a run resumed from `c` with another evaluation budget does not end where an
    /// uninterrupted run with that budget would, if it does not: what follows the share of the
    /// budget spent (a swarm's inertia, the planner's schedule) has followed the old budget's
    /// so far. GA and ASA without a planner schedule take nothing from the budget but when to
    /// stop.
    fn schedule_moved(&self, c: &Checkpoint) -> Option<String> {
        let (was, now) = (c.options.evaluations?, self.options.evaluations?);
        let pso = self.options.algorithm == Algorithm::Pso;
        let schedule = self.planner.schedule.is_some();
        if was == now || !(pso || schedule) {
            return None;
        }
        let what = match (pso, schedule) {
            (true, true) => "the swarm's inertia and the planner's schedule follow",
            (true, false) => "the swarm's inertia follows",
            _ => "the planner's schedule follows",
        };
        Some(format!(
            "the evaluation budget changes from {was} to {now}, and {what} the share of the budget spent: the run goes on by the new budget from here, so its result differs from that of an uninterrupted run of {now} evaluations"
        ))
    }

    /// Refuses a checkpoint whose scenario's mesh files have changed since it was written (an
    /// STL moved or rescaled gives another cell, with the same scenario file). A checkpoint
    /// that records no mesh hash (no meshes, or an older version) is not checked.
    fn check_meshes(&self, c: &Checkpoint, now: Option<&str>) -> Result<()> {
        match (&c.meshes_hash, now) {
            (Some(was), now) if Some(was.as_str()) != now => Err(Error::invalid(
                "scenario",
                self.scenario_path.display(),
                format!(
                    "its mesh files have changed since the checkpoint: their contents hash {}, the checkpoint's {was}; --resume needs the meshes the run started with",
                    now.unwrap_or("nothing (no meshes)")
                ),
            )),
            _ => Ok(()),
        }
    }

    /// Refuses a checkpoint that does not belong to the scenario: another file, or the same
    /// file edited since the run started. The error says what changed. A checkpoint that
    /// records no hash gives a warning instead.
    fn check_binding(
        &self,
        c: &Checkpoint,
        hash: &str,
        shape: &ScenarioShape,
    ) -> Result<Option<String>> {
        let scenario = self.scenario_path.display();
        if let Some(was) = &c.scenario_shape {
            if let Some(d) = was.difference(shape) {
                return Err(Error::invalid(
                    "scenario",
                    &scenario,
                    format!("does not match the checkpoint: {d}; --resume needs the scenario the run started with"),
                ));
            }
        }
        match &c.scenario_hash {
            Some(was) if was != hash => Err(Error::invalid(
                "scenario",
                &scenario,
                format!("has changed since the checkpoint: its contents hash {hash}, the checkpoint's {was}; --resume needs the scenario the run started with"),
            )),
            Some(_) => Ok(None),
            None => Ok(Some(format!(
                "{}: the checkpoint records no scenario hash (an older version wrote it); {scenario} is not checked against it",
                self.out.join(files::CHECKPOINT).display()
            ))),
        }
    }

    /// Re-checks the best distinct final candidates with `recheck_seeds` fresh planner seeds
    /// and returns the one whose cost is lowest with its lowest re-checked `R` (ties: higher
    /// mean `R`, then lower cost in the run), with its figures. Without a re-check, `best`.
    ///
    /// The candidates are re-checked one at a time (its seeds in parallel), in the order of
    /// the lowest cost any re-check could give them ([`lowest_possible_cost`]), until none of
    /// the others could beat or tie the pick: those could not be chosen, so the result is the
    /// one of re-checking them all. Usually the first candidate re-checks at `R = 1` and is
    /// the only one re-checked.
    fn recheck(
        &self,
        objective: &Objective,
        candidates: Vec<&Evaluated>,
        best: Evaluated,
    ) -> Result<(Evaluated, Option<RobustReachability>)> {
        use rayon::prelude::*;
        let k = self.options.recheck_seeds;
        if k == 0 {
            return Ok((best, None));
        }
        let space = objective.space();
        let weights = objective.weights();
        let mut pool: Vec<&Evaluated> = candidates;
        pool.push(&best);
        pool.sort_by(|a, b| a.cost.total_cmp(&b.cost).then(a.stream.cmp(&b.stream)));
        let mut chosen: Vec<(Evaluated, Design)> = Vec::new();
        for e in pool {
            let design = space.try_decode(&e.x)?;
            if chosen.iter().all(|(_, d)| *d != design) {
                chosen.push((e.clone(), design));
                if chosen.len() == RECHECK_CANDIDATES {
                    break;
                }
            }
        }
        let (c, robust) = pick_rechecked(&chosen, weights, k, |e| {
            // Its chain and body are built once for its re-check runs.
            let prepared = objective.prepare(&e.x);
            (0..k as u64)
                .into_par_iter()
                .map(|j| {
                    objective
                        .plan_design(&prepared, RECHECK_STREAM + j, e.progress)
                        .0
                        .reachability
                })
                .collect()
        })?;
        Ok((chosen.swap_remove(c).0, Some(robust)))
    }

    /// Writes `checkpoint.json` (atomically) with the optimiser state `state` (for an island
    /// job: the states of every island, with `islands`).
    pub(crate) fn write_checkpoint(
        &self,
        state: serde_json::Value,
        islands: Option<super::islands::IslandsCheckpoint>,
        Counters {
            generation,
            evaluations,
            elapsed_s,
            stale,
        }: Counters,
        history: &[HistoryRow],
        setup: &Setup,
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
            state,
            scenario_hash: Some(setup.hash.clone()),
            scenario_shape: Some(setup.shape.clone()),
            meshes_hash: setup.meshes_hash.clone(),
            islands,
            checksum: None,
            integrity: Integrity::Intact,
        };
        let value = serde_json::to_value(&c).expect("a checkpoint serialises");
        let c = Checkpoint {
            checksum: Some(content_hash(&value)),
            ..c
        };
        let json = serde_json::to_string(&c).expect("a checkpoint serialises");
        write_atomic(&self.out.join(files::CHECKPOINT), json.as_bytes())
    }

    fn write_results(
        &self,
        summary: &RunSummary,
        report: &ReachReport,
        drawn: &ReachReport,
        history: &[HistoryRow],
    ) -> Result<()> {
        // A trajectories folder this call creates is removed again if the results fail.
        let trajectories = self.out.join(files::TRAJECTORIES);
        let created = !trajectories.exists();
        let written = self.stage_results(summary, report, drawn, history);
        if written.is_err() && created {
            let _ = std::fs::remove_dir(&trajectories); // only if still empty
        }
        written
    }

    /// [`Runner::write_results`]' work: every result staged, then all put in place.
    fn stage_results(
        &self,
        summary: &RunSummary,
        report: &ReachReport,
        drawn: &ReachReport,
        history: &[HistoryRow],
    ) -> Result<()> {
        // Every result is staged, then all are put in place together: an error writing one
        // (a full disk) leaves the folder's earlier results as they were.
        let mut staged = crate::io::Staged::default();
        let best = serde_json::to_string_pretty(summary).expect("a summary serialises");
        staged.add(&self.out.join(files::BEST), best.as_bytes())?;
        let time = serde_json::json!({
            "elapsed_s": summary.elapsed_s,
            "recheck_s": summary.recheck_s,
        });
        staged.add(
            &self.out.join(files::TIME),
            serde_json::to_string_pretty(&time)
                .expect("numbers serialise")
                .as_bytes(),
        )?;
        let reach = serde_json::to_string_pretty(&report.to_json_value(summary.stream))
            .expect("a report serialises");
        staged.add(&self.out.join(files::REACH), reach.as_bytes())?;
        let urdf = self.out.join(files::URDF);
        let text = crate::export::urdf::urdf_text(&summary.design, &urdf);
        staged.add(&urdf, text.as_bytes())?;
        let srdf = self.out.join(files::SRDF);
        let checked = crate::collision::RobotBody::capsules(
            &summary.design.chain(),
            &self.scenario.planner.self_collision,
        );
        let text = crate::export::srdf::body_srdf_text(&checked, None, None, &srdf);
        staged.add(&srdf, text.as_bytes())?;
        let trajectories = self.out.join(files::TRAJECTORIES);
        crate::export::trajectory::stage_trajectories(report, &trajectories, &mut staged)?;
        let mut csv = String::from("elapsed_s,evaluations,best_cost,best_reachability\n");
        for r in history {
            csv.push_str(&format!(
                "{:.3},{},{},{}\n",
                r.elapsed_s, r.evaluations, r.best_cost, r.best_reachability
            ));
        }
        staged.add(&self.out.join(files::HISTORY), csv.as_bytes())?;
        let svg = crate::export::plot::convergence_svg(
            &format!(
                "{} — {} + {}",
                self.scenario.name, summary.optimizer, summary.checker
            ),
            history,
        );
        staged.add(&self.out.join(files::PLOT), svg.as_bytes())?;
        let chain = summary.design.chain();
        let body = crate::collision::RobotBody::capsules(&chain, &summary.planner.self_collision);
        let view = crate::export::view::ViewInput {
            title: format!(
                "{} — {} + {}",
                self.scenario.name, summary.optimizer, summary.checker
            ),
            workspace: &self.scenario.workspace,
            chain: &chain,
            body: &body,
            joint_names: None,
            design: Some(&summary.design),
            report: Some(drawn),
            run: Some(crate::export::view::RunView {
                summary,
                history,
                convergence_svg: Some(&svg),
            }),
        };
        let html = crate::export::view::report_html(&view);
        staged.add(&self.out.join(files::REPORT), html.as_bytes())?;
        staged.commit()
    }
}

/// Evaluations per second over a history (0 when too short).
pub fn rate(history: &[HistoryRow]) -> f64 {
    match history.last() {
        Some(r) if r.elapsed_s > 0.0 => r.evaluations as f64 / r.elapsed_s,
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the bundled paper-2d scenario (8 links, lengths free from 0), a run starts from the
    /// largest design and the eight designs that drop one of its links.
    #[test]
    fn a_run_starts_from_the_largest_design_and_its_one_link_shorter_neighbours() {
        let s = Scenario::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios/paper-2d.toml"),
        )
        .unwrap();
        let xs = initial_designs(&s.space);
        assert_eq!(xs.len(), 9);
        let largest = s.space.largest();
        assert_eq!(xs[0], s.space.encode(&largest));
        for (k, x) in xs[1..].iter().enumerate() {
            let d = s.space.decode(x);
            assert_eq!(d.links.len(), largest.links.len());
            for (j, (l, big)) in d.links.iter().zip(&largest.links).enumerate() {
                if j == k {
                    assert_eq!(l.a, 0.0, "link {} removed", j + 1);
                    assert_eq!(l.axes, big.axes, "its joint kept");
                } else {
                    assert_eq!(l, big, "link {} as in the largest design", j + 1);
                }
            }
        }
    }

    /// The re-check leaves out only candidates that could not be chosen: on random candidates
    /// of the paper-2d design space, random weights (`λ0` of either sign) and random re-check
    /// values, its choice and figures are those of re-checking every candidate (brute force),
    /// and the bound it orders by is below the cost at every `R`. When the first candidate
    /// re-checks at `R = 1` and costs least, it is the only one re-checked.
    #[test]
    fn the_recheck_leaves_out_only_candidates_that_could_not_be_chosen() {
        use rand::{RngExt, SeedableRng};
        let s = Scenario::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios/paper-2d.toml"),
        )
        .unwrap();
        let (lo, hi) = (s.space.lower(), s.space.upper());
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let mut skipped = 0;
        for case in 0..2000 {
            let w = ObjectiveWeights {
                lambda0: rng.random_range(-5.0..20.0),
                lambda1: rng.random_range(0.0..2.0),
                lambda2: rng.random_range(0.0..2.0),
                lambda3: rng.random_range(0.0..1.0),
                lambda4: rng.random_range(0.0..1.0),
                lambda5: rng.random_range(0.0..30.0),
            };
            let n = rng.random_range(1..=RECHECK_CANDIDATES);
            let k = rng.random_range(1..=4);
            let chosen: Vec<(Evaluated, Design)> = (0..n)
                .map(|i| {
                    let x: Vec<f64> = lo
                        .iter()
                        .zip(hi.iter())
                        .map(|(&a, &b)| {
                            if rng.random_bool(0.3) {
                                a
                            } else {
                                rng.random_range(a..=b)
                            }
                        })
                        .collect();
                    let e = Evaluated {
                        x: x.clone(),
                        cost: rng.random_range(0.0..40.0),
                        reachability: 1.0,
                        stream: i as u64,
                        progress: 0.0,
                    };
                    (e, s.space.decode(&x))
                })
                .collect();
            // Re-check values per candidate: mostly 1, else a tenth.
            let values: Vec<Vec<f64>> = (0..n)
                .map(|_| {
                    (0..k)
                        .map(|_| {
                            if rng.random_bool(0.6) {
                                1.0
                            } else {
                                f64::from(rng.random_range(0..10u8)) / 10.0
                            }
                        })
                        .collect()
                })
                .collect();
            for (_, d) in &chosen {
                let floor = lowest_possible_cost(d, &w);
                for t in 0..=10 {
                    let r = f64::from(t) / 10.0;
                    let cost = crate::optimize::objective::breakdown(d, r, &w).cost;
                    assert!(
                        floor <= cost,
                        "case {case}: bound {floor} above {cost} at R = {r}"
                    );
                }
            }
            let at = |e: &Evaluated| e.stream as usize;
            let mut calls = 0;
            let (c, robust) = pick_rechecked(&chosen, &w, k, |e| {
                calls += 1;
                values[at(e)].clone()
            })
            .unwrap();
            // Brute force: every candidate re-checked, the first best in run order kept.
            let scored: Vec<(f64, f64)> = chosen
                .iter()
                .zip(&values)
                .map(|((_, d), v)| {
                    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
                    let mean = v.iter().sum::<f64>() / k as f64;
                    (crate::optimize::objective::breakdown(d, min, &w).cost, mean)
                })
                .collect();
            let mut best = 0;
            for i in 1..n {
                let ((ci, mi), (cb, mb)) = (scored[i], scored[best]);
                if ci < cb
                    || (ci == cb
                        && (mi > mb || (mi == mb && chosen[i].0.cost < chosen[best].0.cost)))
                {
                    best = i;
                }
            }
            assert_eq!(c, best, "case {case}");
            assert_eq!(robust.values, values[best], "case {case}");
            assert_eq!(robust.mean, scored[best].1, "case {case}");
            assert_eq!(robust.candidates, calls, "case {case}");
            skipped += n - calls;
        }
        assert!(skipped > 0, "no candidate was ever left out");
        // A typical end of run: the best candidate (the largest design without a link)
        // re-checks at R = 1 and is the only one re-checked (the largest costs more at any R).
        let w = ObjectiveWeights::default();
        let largest = s.space.largest();
        let shorter = s.space.decode(&initial_designs(&s.space)[1]);
        let run = |d: &Design, stream| Evaluated {
            x: s.space.encode(d),
            cost: crate::optimize::objective::breakdown(d, 1.0, &w).cost,
            reachability: 1.0,
            stream,
            progress: 0.0,
        };
        let chosen = vec![
            (run(&shorter, 0), shorter.clone()),
            (run(&largest, 1), largest.clone()),
        ];
        let (c, robust) = pick_rechecked(&chosen, &w, 2, |_| vec![1.0, 1.0]).unwrap();
        assert_eq!((c, robust.candidates), (0, 1));
    }

    /// A `best.json` whose planner record has no `ik_hold_limits` (written when the key was
    /// left out for its then default, false) replays with the clamping inverse kinematics; a
    /// record that has the key keeps its value.
    #[test]
    fn a_replay_record_without_ik_hold_limits_plans_with_clamping() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("best.json");
        let mut planner = serde_json::to_value(crate::planning::PlannerConfig::default()).unwrap();
        planner.as_object_mut().unwrap().remove("ik_hold_limits");
        let best = |planner: &serde_json::Value| {
            serde_json::json!({ "seed": 3, "stream": 7, "planner": planner }).to_string()
        };
        std::fs::write(&path, best(&planner)).unwrap();
        let r = Replay::from_best(&path).unwrap().unwrap();
        assert_eq!((r.seed, r.stream), (3, 7));
        assert!(!r.planner.ik_hold_limits);
        planner["ik_hold_limits"] = serde_json::Value::Bool(true);
        std::fs::write(&path, best(&planner)).unwrap();
        assert!(
            Replay::from_best(&path)
                .unwrap()
                .unwrap()
                .planner
                .ik_hold_limits
        );
    }

    /// The same for a checkpoint: one without the key resumes with clamping.
    #[test]
    fn a_checkpoint_without_ik_hold_limits_resumes_with_clamping() {
        let dir = tempfile::tempdir().unwrap();
        let c = Checkpoint {
            scenario: PathBuf::from("s.toml"),
            planner: crate::planning::PlannerConfig::default(),
            options: RunOptions {
                algorithm: Algorithm::Ga,
                seed: 1,
                time_limit: None,
                evaluations: Some(10),
                patience: 30,
                checkpoint_interval: 10.0,
                recheck_seeds: 8,
                confirm_seeds: 3,
            },
            generation: 0,
            evaluations: 0,
            elapsed_s: 0.0,
            stale: 0,
            history: Vec::new(),
            state: serde_json::Value::Null,
            scenario_hash: None,
            scenario_shape: None,
            meshes_hash: None,
            islands: None,
            checksum: None,
            integrity: Integrity::Intact,
        };
        let mut v = serde_json::to_value(&c).unwrap();
        let path = dir.path().join(files::CHECKPOINT);
        std::fs::write(&path, v.to_string()).unwrap();
        assert!(
            Runner::read_checkpoint(dir.path())
                .unwrap()
                .planner
                .ik_hold_limits
        );
        v["planner"]
            .as_object_mut()
            .unwrap()
            .remove("ik_hold_limits");
        std::fs::write(&path, v.to_string()).unwrap();
        assert!(
            !Runner::read_checkpoint(dir.path())
                .unwrap()
                .planner
                .ik_hold_limits
        );
    }
}
