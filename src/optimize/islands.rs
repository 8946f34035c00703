//! The island model: `N` populations (GA, PSO or ASA) optimise the same objective (paper
//! Eq. 23) side by side and, every `interval` generations, each sends its best `count` designs
//! to the next island of a ring (`[optimizer] migration = { interval = 10, count = 2 }`).
//!
//! The islands run in lockstep, a generation at a time, over a [`Comm`]: one process for all of
//! them ([`SingleProcess`], `kinsynth optimize --islands N`), or one or more islands per MPI
//! rank (`mpi::MpiComm`, with the cargo feature `mpi`: `mpirun -np N kinsynth optimize
//! --islands`). Migration and every decision are synchronous, so the result depends on the
//! seed and `N` only, not on the number of ranks or threads: island `i` of `N` plans its
//! `k`-th evaluation with the random stream `k·N + i` and draws its step `g` from the optimiser
//! stream `g·N + i`; one island is exactly one population of [`Runner::run`].
//!
//! Rank 0 owns the job as [`Runner::run`] owns a run: budgets, the decision to stop, the
//! history, the progress display, checkpoints (which hold every island) and the results, plus
//! `islands.csv` (a row per island per generation).

#[cfg(feature = "mpi")]
pub mod mpi;

pub use super::output::{IslandRow, IslandsInfo};
use super::runner::{
    cut_reason, files, history_row, step_rng, Checkpoint, Conclusion, Counters, HistoryRow,
    Observer, RunOptions, RunSummary, Runner,
};
use super::{Cutoff, Evaluated, Optimizer, StepContext};
use crate::error::{Error, Result};
use crate::io::write_atomic;
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// The `[optimizer] migration` setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Migration {
    /// Generations between migrations (at least 1). Default 10.
    pub interval: usize,
    /// Designs each island sends to the next (0: islands never migrate). Default 2.
    pub count: usize,
}

impl Migration {
    /// Checks the settings, with field names under `prefix` (`optimizer.migration.` in a
    /// scenario, `islands.migration.` in a checkpoint): an interval from 1 to
    /// [`crate::limits::MAX_ITERATIONS`] generations and at most `max_count` designs (the
    /// population), so that a migration can neither stall nor exhaust memory.
    pub fn check(&self, prefix: &str, max_count: usize) -> Result<()> {
        let max_interval = crate::limits::MAX_ITERATIONS;
        let interval = format!("{prefix}interval");
        crate::scenario::check_count(self.interval, 1, max_interval, interval)?;
        crate::scenario::check_count(self.count, 0, max_count, format!("{prefix}count"))
    }
}

impl Default for Migration {
    fn default() -> Self {
        Migration {
            interval: 10,
            count: 2,
        }
    }
}

/// What a checkpoint of an island job adds to [`Checkpoint`]: `state` is then the array of
/// the islands' optimiser states.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IslandsCheckpoint {
    /// Number of islands `N`: a resumed job must have as many.
    pub islands: usize,
    /// Migration settings of the job.
    pub migration: Migration,
    /// Evaluations of each island.
    pub evaluations: Vec<u64>,
    /// `islands.csv` so far.
    pub rows: Vec<IslandRow>,
}

/// Communication between the processes of an island job. Every call is collective: every
/// rank makes the same calls in the same order.
pub trait Comm {
    /// This process's rank, from 0.
    fn rank(&self) -> usize;
    /// Number of processes.
    fn size(&self) -> usize;
    /// Sends `bytes` to the next rank of the ring (`rank + 1` mod `size`) and returns what the
    /// previous rank sent.
    fn ring_shift(&self, bytes: &[u8]) -> Result<Vec<u8>>;
    /// Every rank's `bytes`, in rank order, at rank 0 (`None` on the other ranks).
    fn gather(&self, bytes: &[u8]) -> Result<Option<Vec<Vec<u8>>>>;
    /// Rank 0's `bytes` on every rank (the other ranks' argument is ignored).
    fn broadcast(&self, bytes: &[u8]) -> Result<Vec<u8>>;
    /// Waits until every rank has called it.
    fn barrier(&self);
    /// Ends the whole job at once with `code` (after a rank failed on its own: the others may
    /// be waiting for it). A single process just returns.
    fn abort(&self, code: i32);
}

/// One process for every island.
#[derive(Clone, Copy, Debug, Default)]
pub struct SingleProcess;

impl Comm for SingleProcess {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn ring_shift(&self, bytes: &[u8]) -> Result<Vec<u8>> {
        Ok(bytes.to_vec())
    }
    fn gather(&self, bytes: &[u8]) -> Result<Option<Vec<Vec<u8>>>> {
        Ok(Some(vec![bytes.to_vec()]))
    }
    fn broadcast(&self, bytes: &[u8]) -> Result<Vec<u8>> {
        Ok(bytes.to_vec())
    }
    fn barrier(&self) {}
    fn abort(&self, _: i32) {}
}

fn encode<T: Serialize>(v: &T) -> Vec<u8> {
    serde_json::to_vec(v).expect("island messages serialise")
}

fn decode<T: DeserializeOwned>(comm: &dyn Comm, what: &str, bytes: &[u8]) -> Result<T> {
    serde_json::from_slice(bytes).map_err(|e| Error::Island {
        rank: comm.rank(),
        message: format!("malformed {what} message: {e}"),
    })
}

/// What rank 0 sends every other rank before the job starts: the settings it read from the
/// command line, the scenario and the checkpoint, or why it refused the job.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct JobSpec {
    /// The scenario file (every rank reads it: a shared file system on a cluster).
    pub scenario: PathBuf,
    /// The scenario file's fingerprint on rank 0 (another rank's copy must match it).
    pub scenario_hash: String,
    /// Planner settings.
    pub planner: crate::planning::PlannerConfig,
    /// Run settings.
    pub options: RunOptions,
    /// Output directory (rank 0 writes it).
    pub out: PathBuf,
    /// Number of islands.
    pub islands: usize,
    /// Migration settings (from the scenario, or from the checkpoint on resume).
    pub migration: Migration,
    /// The checkpoint to resume, if any.
    pub checkpoint: Option<Checkpoint>,
}

/// An island job's failure, and whether every rank knows of it: then every rank ends on its
/// own (rank 0 reports it); otherwise this rank failed alone while the others may wait for
/// it, and the job must be aborted ([`Comm::abort`]).
#[derive(Debug)]
pub struct JobError {
    /// What went wrong (on another rank than this one: [`Error::Island`] naming that rank).
    pub error: Error,
    /// Every rank returns this failure.
    pub on_every_rank: bool,
}

impl From<Error> for JobError {
    fn from(error: Error) -> Self {
        JobError {
            error,
            on_every_rank: false,
        }
    }
}

impl std::fmt::Display for JobError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.error.fmt(f)
    }
}

/// Every rank's verdict on its own part of a step (reading the scenario, restoring its
/// islands, …): when all succeeded, each gets its value; otherwise every rank gets the error
/// of the first rank that failed (its own error on that rank, an [`Error::Island`] naming
/// that rank elsewhere), with [`JobError::on_every_rank`] set.
pub fn agree<T>(comm: &dyn Comm, local: Result<T>) -> std::result::Result<T, JobError> {
    let mine: Option<String> = local.as_ref().err().map(ToString::to_string);
    let verdict: Option<(usize, String)> = match comm.gather(&encode(&mine))? {
        Some(parts) => {
            let mut first = None;
            for (r, p) in parts.iter().enumerate() {
                if let Some(m) = decode::<Option<String>>(comm, "verdict", p)? {
                    first = Some((r, m));
                    break;
                }
            }
            first
        }
        None => None,
    };
    let verdict: Option<(usize, String)> =
        decode(comm, "verdict", &comm.broadcast(&encode(&verdict))?)?;
    match (local, verdict) {
        (Ok(v), None) => Ok(v),
        (Err(e), Some((r, _))) if r == comm.rank() => Err(JobError {
            error: e,
            on_every_rank: true,
        }),
        (_, Some((rank, message))) => Err(JobError {
            error: Error::Island { rank, message },
            on_every_rank: true,
        }),
        // Rank 0 saw no failure although this rank failed: cannot happen with a sound
        // transport; end the job.
        (Err(e), None) => Err(e.into()),
    }
}

/// Hands rank 0's job to every rank: rank 0 passes `Some(Ok(spec))`, or `Some(Err(reason))`
/// when it refuses the job (a bad option, a held lock, …); the others pass `None`. Every rank
/// gets the spec, or the refusal (with [`JobError::on_every_rank`] set).
pub fn share_job(
    comm: &dyn Comm,
    spec: Option<std::result::Result<JobSpec, String>>,
) -> std::result::Result<JobSpec, JobError> {
    /// The job as sent. What reading the checkpoint found of its checksum
    /// ([`Checkpoint::integrity`]) is no part of the checkpoint's serialised form, so it
    /// travels beside it: every rank (rank 0 as well, which takes the job from the broadcast)
    /// refuses a changed checkpoint, and warns of an unsealed one, as a single run does.
    #[derive(Serialize, Deserialize)]
    struct Wire {
        job: std::result::Result<JobSpec, String>,
        integrity: super::runner::Integrity,
    }
    let message = match (spec, comm.rank() == 0) {
        (Some(job), true) => {
            let integrity = job
                .as_ref()
                .ok()
                .and_then(|j| j.checkpoint.as_ref())
                .map(|c| c.integrity.clone())
                .unwrap_or_default();
            encode(&Wire { job, integrity })
        }
        _ => Vec::new(),
    };
    let bytes = comm.broadcast(&message)?;
    let Wire { job, integrity } = decode(comm, "job", &bytes)?;
    let mut job = job.map_err(|message| JobError {
        error: Error::Island { rank: 0, message },
        on_every_rank: true,
    })?;
    if let Some(c) = &mut job.checkpoint {
        c.integrity = integrity;
    }
    Ok(job)
}

/// Figures of an island job that the results do not hold: where its time went.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IslandTimings {
    /// Generations made in this session.
    pub generations: u64,
    /// Migrations made in this session.
    pub migrations: u64,
    /// Seconds rank 0 spent exchanging the islands' status and the next decision, per
    /// generation (includes waiting for the slowest rank).
    pub sync_s: f64,
    /// Seconds rank 0 spent waiting at the barrier before each migration (for the slowest
    /// island to finish its generation).
    pub wait_s: f64,
    /// Seconds rank 0 spent migrating after that barrier: choosing, serialising, sending,
    /// receiving and taking in the migrants.
    pub migration_s: f64,
}

/// What rank 0 gets from an island job.
#[derive(Debug)]
pub struct IslandOutcome {
    /// The result, as a single run's.
    pub summary: RunSummary,
    /// Where the time went.
    pub timings: IslandTimings,
}

/// An island's status after a generation, as rank 0 gathers it.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Status {
    island: usize,
    evaluations: u64,
    best: Option<Evaluated>,
}

/// Rank 0's decision before a generation.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Decision {
    /// Why the job stops now.
    stop: Option<String>,
    /// Write a checkpoint of the state now.
    checkpoint: bool,
    /// Progress of the job for the next generation (schedules).
    progress: f64,
    /// Evaluations left of the job's budget (`None`: no evaluation budget), shared among the
    /// islands in index order ([`budget_share`]).
    left: Option<u64>,
}

/// What a rank's islands did in a generation, for the decision to undo it: whether one was
/// cut short (and whether by its share of the evaluation budget), the evaluations made, and
/// the points that count for the result if it is undone (the cut steps' evaluations, the best
/// of each whole step made in it).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct CutReport {
    cut: bool,
    by_budget: bool,
    evaluations: u64,
    points: Vec<Evaluated>,
}

/// Island `island`'s share of `left` evaluations among `islands`: an equal part, the
/// remainder one each to the first islands, so that the shares add up to `left`.
fn budget_share(left: u64, islands: usize, island: usize) -> u64 {
    let n = islands.max(1) as u64;
    left / n + u64::from((island as u64) < left % n)
}

/// An island held by this process.
struct Island {
    index: usize,
    optimizer: Box<dyn Optimizer>,
    evaluations: u64,
}

/// An island job: `islands` islands with `migration`, run by a [`Runner`] (which supplies the
/// scenario, planner settings, options and output directory).
pub struct IslandJob<'r, 'a> {
    runner: &'r Runner<'a>,
    islands: usize,
    migration: Migration,
    scenario_hash: Option<String>,
}

impl<'r, 'a> IslandJob<'r, 'a> {
    /// A job of `islands` islands.
    pub fn new(runner: &'r Runner<'a>, islands: usize, migration: Migration) -> Self {
        IslandJob {
            runner,
            islands,
            migration,
            scenario_hash: None,
        }
    }

    /// Requires every rank's scenario file to have this fingerprint (rank 0's,
    /// [`JobSpec::scenario_hash`]).
    pub fn expect_scenario_hash(mut self, hash: String) -> Self {
        self.scenario_hash = Some(hash);
        self
    }

    /// Runs the job on every rank of `comm` (each calls it with the same arguments) until a
    /// budget is spent, the job converges or `stop` is raised on rank 0. Rank 0 writes the
    /// results into the runner's output directory (every file of [`Runner::run`], plus
    /// `islands.csv`) and returns them; the other ranks return `None`. With `resume`, continues
    /// from that checkpoint, which must hold an island job of as many islands.
    pub fn run(
        &self,
        comm: &dyn Comm,
        resume: Option<Checkpoint>,
        stop: &AtomicBool,
        observer: &mut dyn Observer,
    ) -> std::result::Result<Option<IslandOutcome>, JobError> {
        let runner = self.runner;
        let n = self.islands;
        let (rank, size) = (comm.rank(), comm.size());
        let root = rank == 0;
        let per_rank = n / size.max(1);
        let setup = agree(comm, self.start(comm, resume.as_ref()))?;
        let (setup, mut local) = setup;
        let objective = &setup.objective;
        let o = runner.options().clone();
        let (mut generation, mut total, elapsed_before, mut stale, mut history, mut rows) =
            match &resume {
                Some(c) => (
                    c.generation,
                    c.evaluations,
                    c.elapsed_s,
                    c.stale,
                    c.history.clone(),
                    c.islands
                        .as_ref()
                        .map(|i| i.rows.clone())
                        .unwrap_or_default(),
                ),
                None => (0, 0, 0.0, 0, Vec::new(), Vec::new()),
            };
        debug_assert_eq!(local.len(), per_rank);
        let start = Instant::now();
        let elapsed = || elapsed_before + start.elapsed().as_secs_f64();
        let mut timings = IslandTimings::default();
        let mut last_checkpoint = Instant::now();
        let first_generation = generation;
        let deadline = runner.deadline(start, elapsed_before);
        // The points of a generation cut short (time limit, Ctrl-C; gathered at rank 0).
        let (mut late, mut late_count): (Vec<Evaluated>, u64) = (Vec::new(), 0);
        // Rank 0's view of every island: evaluations and best.
        let mut statuses = self.gather_status(comm, &local, &mut timings)?;
        let mut best_cost = global_best(statuses.as_deref()).map_or(f64::INFINITY, |b| b.1.cost);
        let stride = n as u64;
        // A new job's first generation is always taken, whatever its time limit: every island
        // evaluates at least its first design.
        let mut first = resume.is_none();
        let stopped = loop {
            let clock = (!first).then(elapsed);
            first = false;
            let decision = if root {
                let best = global_best(statuses.as_deref()).map(|b| b.1);
                let stop_now = runner.stop_reason(stop, total, clock, best, stale);
                Decision {
                    checkpoint: stop_now.is_none()
                        && generation > first_generation
                        && last_checkpoint.elapsed().as_secs_f64() >= o.checkpoint_interval,
                    stop: stop_now,
                    progress: runner.progress(total, elapsed()),
                    left: runner.evaluations_left(total),
                }
            } else {
                Decision::default()
            };
            let t = Instant::now();
            let decision: Decision =
                decode(comm, "decision", &comm.broadcast(&encode(&decision))?)?;
            timings.sync_s += t.elapsed().as_secs_f64();
            if decision.checkpoint {
                self.checkpoint(
                    comm,
                    &local,
                    statuses.as_deref(),
                    Counters {
                        generation,
                        evaluations: total,
                        elapsed_s: elapsed(),
                        stale,
                    },
                    &history,
                    &rows,
                    &setup,
                )?;
                last_checkpoint = Instant::now();
            }
            if let Some(why) = decision.stop {
                break why;
            }
            // Each island's state and count before the step, to return to if the generation
            // is cut short anywhere.
            let mut before = Vec::new();
            let mut mine = CutReport::default();
            let cutoff = Cutoff {
                deadline,
                stop: Some(stop),
                budget: None,
                may_skip_all: true,
            };
            let mut whole = Vec::new();
            for (k, island) in local.iter_mut().enumerate() {
                let i = island.index as u64;
                let share = decision.left.map(|l| budget_share(l, n, island.index));
                // Past the time limit only the first island of a new job evaluates a design
                // (its first), so that the job has a result; the others stop at once.
                let cutoff = Cutoff {
                    budget: share,
                    may_skip_all: island.index != 0 || total > 0,
                    ..cutoff
                };
                before.push((island.optimizer.snapshot(), island.evaluations));
                let report = island.optimizer.step(StepContext {
                    problem: objective,
                    rng: &mut step_rng(o.seed, generation.wrapping_mul(stride).wrapping_add(i)),
                    first_stream: island.evaluations.wrapping_mul(stride).wrapping_add(i),
                    stride,
                    progress: decision.progress,
                    cutoff,
                });
                mine.evaluations = mine.evaluations.saturating_add(report.evaluations);
                match report.cut {
                    Some(c) => {
                        mine.cut = true;
                        mine.by_budget |= share.is_some_and(|b| report.evaluations >= b);
                        mine.points.extend(c.evaluated);
                    }
                    None => {
                        island.evaluations = island.evaluations.saturating_add(report.evaluations);
                        whole.push(k);
                    }
                }
            }
            // Should the generation be undone (an island here or on another rank was cut
            // short: then the cutoff has come here too, or a share of the evaluation budget
            // ran out somewhere), the best of each whole step still counts for the result.
            if mine.cut || cutoff.reached() || decision.left.is_some() {
                let bests = whole
                    .iter()
                    .filter_map(|&k| local[k].optimizer.best().cloned());
                mine.points.extend(bests);
            }
            // A generation cut short on any rank is undone on every rank: each island returns
            // to its last whole generation, the points evaluated go to the result.
            if let Some(all) = self.gather_cut(comm, &mine, &mut timings)? {
                for (island, (was, evaluations)) in local.iter_mut().zip(before) {
                    island.optimizer = was;
                    island.evaluations = evaluations;
                }
                // At rank 0: the evaluations of the undone generation are added to the job's
                // total for the result only (the checkpoint keeps whole generations).
                late_count = all.evaluations;
                late = all.points;
                break cut_reason(stop, all.by_budget);
            }
            generation = generation.saturating_add(1);
            timings.generations += 1;
            if self.migrates_after(generation) {
                self.migrate(comm, &mut local, &mut timings)?;
            }
            statuses = self.gather_status(comm, &local, &mut timings)?;
            if let Some(all) = statuses.as_deref() {
                total = all.iter().map(|s| s.evaluations).sum();
                let (_, best) = global_best(Some(all)).expect("a best after a generation");
                if best.cost < best_cost {
                    best_cost = best.cost;
                    stale = 0;
                } else {
                    stale = stale.saturating_add(1);
                }
                let row = history_row(objective, best, total, elapsed())?;
                let new_rows: Vec<IslandRow> = all
                    .iter()
                    .map(|s| {
                        let b = s.best.as_ref().expect("a best after a generation");
                        IslandRow {
                            generation,
                            island: s.island,
                            evaluations: s.evaluations,
                            best_cost: b.cost,
                            best_reachability: b.reachability,
                        }
                    })
                    .collect();
                observer.generation(&row);
                observer.islands(&new_rows);
                history.push(row);
                rows.extend(new_rows);
                super::output::thin_history(&mut history);
                super::output::thin_island_rows(&mut rows);
            }
        };
        if root {
            observer.finish();
        }
        let counters = Counters {
            generation,
            evaluations: total,
            elapsed_s: elapsed(),
            stale,
        };
        let states = self.checkpoint(
            comm,
            &local,
            statuses.as_deref(),
            counters,
            &history,
            &rows,
            &setup,
        )?;
        let (Some(states), Some(all)) = (states, statuses) else {
            return Ok(None);
        };
        // Rank 0: the result from the candidates of every island.
        let optimizers: Vec<Box<dyn Optimizer>> = states
            .into_iter()
            .enumerate()
            .map(|(i, s)| runner.load_optimizer(s).map_err(|e| prefix_state(e, i)))
            .collect::<Result<_>>()?;
        let (best_island, mut best) = match global_best(Some(&all)) {
            Some((i, b)) => (i, Some(b.clone())),
            None => (0, None),
        };
        for e in &late {
            super::keep_best(&mut best, e);
        }
        let best = best.ok_or_else(|| runner.nothing_evaluated(&stopped))?;
        let mut candidates: Vec<&Evaluated> =
            optimizers.iter().flat_map(|o| o.candidates()).collect();
        candidates.extend(&late);
        // history.csv ends with the cut generation (the checkpoint keeps whole generations).
        if !late.is_empty() {
            let total = counters.evaluations.saturating_add(late_count);
            history.push(history_row(objective, &best, total, elapsed())?);
            super::output::thin_history(&mut history);
        }
        let summary = runner.conclude(
            objective,
            Conclusion {
                optimizer: optimizers[0].name(),
                candidates,
                best,
                counters: Counters {
                    evaluations: counters.evaluations.saturating_add(late_count),
                    ..counters
                },
                elapsed: &elapsed,
                stopped,
                history: &history,
                islands: Some(IslandsInfo {
                    islands: n,
                    migration: self.migration,
                    best_island,
                }),
            },
        )?;
        write_islands_csv(runner, &rows)?;
        Ok(Some(IslandOutcome { summary, timings }))
    }

    /// This rank's part of the start: checks the number of islands and the checkpoint, binds
    /// the checkpoint to the scenario, and restores (or creates) this rank's islands.
    fn start(
        &self,
        comm: &dyn Comm,
        resume: Option<&Checkpoint>,
    ) -> Result<(super::runner::Setup, Vec<Island>)> {
        let runner = self.runner;
        let n = self.islands;
        let (rank, size) = (comm.rank(), comm.size());
        if n == 0 || n % size != 0 || n > crate::limits::MAX_POPULATION {
            return Err(Error::invalid(
                "--islands",
                n,
                format!(
                    "must be at least 1, a multiple of the number of MPI ranks ({size}) and at most {}",
                    crate::limits::MAX_POPULATION
                ),
            ));
        }
        let checkpoint_path = runner.checkpoint_path();
        if let Some(c) = resume {
            check_resume(c, n).map_err(|e| e.in_file(&checkpoint_path))?;
        }
        if rank == 0 {
            std::fs::create_dir_all(runner.out()).map_err(|source| Error::Write {
                path: runner.out().to_path_buf(),
                source,
            })?;
        }
        let setup = runner.prepare(resume)?;
        runner.check_population(n)?;
        if let Some(expected) = &self.scenario_hash {
            if *expected != setup.hash {
                return Err(Error::invalid(
                    "scenario",
                    runner.scenario_path().display(),
                    format!(
                        "differs on rank {rank} from rank 0's copy (contents hash {}, rank 0's {expected}): every rank must read the same file",
                        setup.hash
                    ),
                ));
            }
        }
        let per_rank = n / size;
        let mut local = Vec::with_capacity(per_rank);
        for index in rank * per_rank..(rank + 1) * per_rank {
            let (optimizer, evaluations) = match resume {
                Some(c) => {
                    let states = c.state.as_array().expect("checked by check_resume");
                    let island = c.islands.as_ref().expect("checked by check_resume");
                    let optimizer = runner
                        .load_optimizer(states[index].clone())
                        .map_err(|e| prefix_state(e, index).in_file(&checkpoint_path))?;
                    (optimizer, island.evaluations[index])
                }
                None => (runner.new_optimizer(), 0),
            };
            local.push(Island {
                index,
                optimizer,
                evaluations,
            });
        }
        if let Some(c) = resume {
            c.integrity.check(&checkpoint_path)?;
        }
        if rank == 0 {
            setup.warn();
        }
        Ok((setup, local))
    }

    /// True when the islands migrate after generation `generation` (from 1).
    fn migrates_after(&self, generation: u64) -> bool {
        self.islands > 1
            && self.migration.count > 0
            && generation % self.migration.interval.max(1) as u64 == 0
    }

    /// Each island sends its best `count` designs to the next island of the ring and takes in
    /// those of the previous one; all choose their emigrants before any takes migrants in.
    fn migrate(
        &self,
        comm: &dyn Comm,
        local: &mut [Island],
        timings: &mut IslandTimings,
    ) -> Result<()> {
        let t = Instant::now();
        comm.barrier();
        timings.wait_s += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let count = self.migration.count;
        let out: Vec<Vec<Evaluated>> = local.iter().map(|i| i.optimizer.emigrants(count)).collect();
        let last = out.last().cloned().unwrap_or_default();
        let from_previous_rank: Vec<Evaluated> =
            decode(comm, "migration", &comm.ring_shift(&encode(&last))?)?;
        let dim = self.runner.scenario().space.dim();
        if let Some(bad) = from_previous_rank.iter().find(|e| e.x.len() != dim) {
            return Err(Error::Island {
                rank: comm.rank(),
                message: format!(
                    "a migrant has {} values, the design space {dim}",
                    bad.x.len()
                ),
            });
        }
        for (j, island) in local.iter_mut().enumerate() {
            let incoming = if j == 0 {
                &from_previous_rank
            } else {
                &out[j - 1]
            };
            island.optimizer.immigrate(incoming);
        }
        timings.migrations += 1;
        timings.migration_s += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// Whether any rank's islands were cut short in this generation (every rank learns it):
    /// `Some` with every rank's report summed (at rank 0; empty elsewhere) when one was.
    fn gather_cut(
        &self,
        comm: &dyn Comm,
        mine: &CutReport,
        timings: &mut IslandTimings,
    ) -> Result<Option<CutReport>> {
        let t = Instant::now();
        let gathered = comm.gather(&encode(mine))?;
        let mut all = CutReport::default();
        if let Some(parts) = gathered {
            for p in &parts {
                let got: CutReport = decode(comm, "cut", p)?;
                all.cut |= got.cut;
                all.by_budget |= got.by_budget;
                all.evaluations = all.evaluations.saturating_add(got.evaluations);
                all.points.extend(got.points);
            }
        }
        let (any, by_budget): (bool, bool) = decode(
            comm,
            "cut decision",
            &comm.broadcast(&encode(&(all.cut, all.by_budget)))?,
        )?;
        all.by_budget = by_budget;
        timings.sync_s += t.elapsed().as_secs_f64();
        Ok(any.then_some(all))
    }

    /// Every island's status at rank 0, by island index.
    fn gather_status(
        &self,
        comm: &dyn Comm,
        local: &[Island],
        timings: &mut IslandTimings,
    ) -> Result<Option<Vec<Status>>> {
        let mine: Vec<Status> = local
            .iter()
            .map(|i| Status {
                island: i.index,
                evaluations: i.evaluations,
                best: i.optimizer.best().cloned(),
            })
            .collect();
        let t = Instant::now();
        let gathered = comm.gather(&encode(&mine))?;
        timings.sync_s += t.elapsed().as_secs_f64();
        let Some(parts) = gathered else {
            return Ok(None);
        };
        let mut all = Vec::with_capacity(self.islands);
        for p in &parts {
            all.extend(decode::<Vec<Status>>(comm, "status", p)?);
        }
        check_islands(comm, all.iter().map(|s| s.island), self.islands)?;
        Ok(Some(all))
    }

    /// Gathers every island's state at rank 0 and writes the checkpoint there; returns the
    /// states, by island (rank 0 only).
    #[allow(clippy::too_many_arguments)]
    fn checkpoint(
        &self,
        comm: &dyn Comm,
        local: &[Island],
        statuses: Option<&[Status]>,
        counters: Counters,
        history: &[HistoryRow],
        rows: &[IslandRow],
        setup: &super::runner::Setup,
    ) -> Result<Option<Vec<serde_json::Value>>> {
        let mine: Vec<(usize, serde_json::Value)> = local
            .iter()
            .map(|i| (i.index, i.optimizer.save()))
            .collect();
        let Some(parts) = comm.gather(&encode(&mine))? else {
            return Ok(None);
        };
        let mut all: Vec<(usize, serde_json::Value)> = Vec::with_capacity(self.islands);
        for p in &parts {
            all.extend(decode::<Vec<(usize, serde_json::Value)>>(comm, "state", p)?);
        }
        check_islands(comm, all.iter().map(|s| s.0), self.islands)?;
        let states: Vec<serde_json::Value> = all.into_iter().map(|s| s.1).collect();
        let evaluations = statuses
            .map(|s| s.iter().map(|s| s.evaluations).collect())
            .unwrap_or_else(|| vec![0; self.islands]);
        self.runner.write_checkpoint(
            serde_json::Value::Array(states.clone()),
            Some(IslandsCheckpoint {
                islands: self.islands,
                migration: self.migration,
                evaluations,
                rows: rows.to_vec(),
            }),
            counters,
            history,
            setup,
        )?;
        Ok(Some(states))
    }
}

/// The island with the lowest best cost (ties: the lower index) and its best.
fn global_best(statuses: Option<&[Status]>) -> Option<(usize, &Evaluated)> {
    statuses?
        .iter()
        .filter_map(|s| s.best.as_ref().map(|b| (s.island, b)))
        .min_by(|a, b| a.1.cost.total_cmp(&b.1.cost).then(a.0.cmp(&b.0)))
}

/// The gathered islands must be `0 … n−1` in order.
fn check_islands(comm: &dyn Comm, got: impl Iterator<Item = usize>, n: usize) -> Result<()> {
    let got: Vec<usize> = got.collect();
    if got.iter().copied().eq(0..n) {
        Ok(())
    } else {
        Err(Error::Island {
            rank: comm.rank(),
            message: format!("expected islands 0…{} in order, got {got:?}", n - 1),
        })
    }
}

/// A checkpoint must hold an island job of `n` islands, with a state and a count for each.
fn check_resume(c: &Checkpoint, n: usize) -> Result<()> {
    let Some(i) = &c.islands else {
        return Err(Error::invalid(
            "islands",
            "none",
            "the checkpoint holds a single-population run: resume it without --islands",
        ));
    };
    if i.islands != n {
        return Err(Error::invalid(
            "islands",
            i.islands,
            format!(
                "the checkpoint holds {} islands, this job has {n}: resume it with {} islands (mpirun -np {} … --islands, or --islands {})",
                i.islands, i.islands, i.islands, i.islands
            ),
        ));
    }
    // The migration settings by a scenario's rules (a count of 10^9 asked for memory at the
    // first migration).
    i.migration
        .check("islands.migration.", crate::limits::MAX_POPULATION)?;
    let states = c.state.as_array().map_or(0, Vec::len);
    if states != n || i.evaluations.len() != n {
        return Err(Error::invalid(
            "state",
            format!("{states} states, {} counts", i.evaluations.len()),
            format!("an island job of {n} islands needs {n} of each"),
        ));
    }
    Ok(())
}

/// Names the island in an error about a restored state (`state[1].population…`).
fn prefix_state(e: Error, island: usize) -> Error {
    match e {
        Error::Parse { file, message } => Error::Parse {
            file,
            message: message.replacen("state", &format!("state[{island}]"), 1),
        },
        other => other,
    }
}

/// Writes `islands.csv`: `generation,island,evaluations,best_cost,best_reachability`.
fn write_islands_csv(runner: &Runner<'_>, rows: &[IslandRow]) -> Result<()> {
    let mut csv = String::from("generation,island,evaluations,best_cost,best_reachability\n");
    for r in rows {
        csv.push_str(&format!(
            "{},{},{},{},{}\n",
            r.generation, r.island, r.evaluations, r.best_cost, r.best_reachability
        ));
    }
    write_atomic(&runner.out().join(files::ISLANDS), csv.as_bytes())
}
