//! The island model in one process and over ranks simulated by threads (no MPI needed):
//! one island is the plain run, the result depends on the seed and the number of islands only
//! (not on how islands are spread over ranks), migration follows the ring, and a stopped job
//! resumes to the uninterrupted result.

use kinsynth::optimize::islands::{Comm, IslandJob, IslandRow, Migration, SingleProcess};
use kinsynth::optimize::runner::{Checkpoint, HistoryRow, Observer, Quiet, RunOptions, Runner};
use kinsynth::optimize::RunSummary;
use kinsynth::scenario::Algorithm;
use kinsynth::Scenario;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Barrier, Mutex};

/// paper-2d with a population of 8, written into `dir`.
fn small_scenario(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios/paper-2d.toml"),
    )
    .unwrap()
    .replace("population = 32", "population = 8");
    assert!(text.contains("population = 8"));
    let path = dir.join("small.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn options(algorithm: Algorithm, evaluations: u64) -> RunOptions {
    RunOptions {
        algorithm,
        seed: 5,
        time_limit: None,
        evaluations: Some(evaluations),
        patience: 1000,
        checkpoint_interval: 0.0,
        recheck_seeds: 2,
        confirm_seeds: 1,
    }
}

fn best_json(dir: &Path) -> serde_json::Value {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("best.json")).unwrap()).unwrap();
    assert!(
        v.get("elapsed_s").is_none(),
        "wall-clock time is kept out of best.json"
    );
    v
}

fn island_rows(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("islands.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("generation,island,evaluations,best_cost,best_reachability")
    );
    lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Resumes the island job of `n` islands of `runner` from `checkpoint`, in one process.
fn resume_islands(runner: &Runner<'_>, n: usize, migration: Migration, checkpoint: Checkpoint) {
    IslandJob::new(runner, n, migration)
        .run(
            &SingleProcess,
            Some(checkpoint),
            &AtomicBool::new(false),
            &mut Quiet,
        )
        .unwrap();
}

/// Runs an island job of `n` islands in one process.
fn islands(
    scenario: &Path,
    out: &Path,
    n: usize,
    migration: Migration,
    o: RunOptions,
) -> RunSummary {
    let s = Scenario::load(scenario).unwrap();
    let runner = Runner::new(&s, scenario, s.planner.clone(), o, out);
    IslandJob::new(&runner, n, migration)
        .run(&SingleProcess, None, &AtomicBool::new(false), &mut Quiet)
        .unwrap()
        .expect("rank 0 gets the outcome")
        .summary
}

#[test]
fn one_island_is_the_plain_run() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = small_scenario(dir.path());
    let s = Scenario::load(&scenario).unwrap();
    for algorithm in [Algorithm::Ga, Algorithm::Pso] {
        let plain = dir.path().join(format!("plain-{algorithm:?}"));
        let runner = Runner::new(
            &s,
            &scenario,
            s.planner.clone(),
            options(algorithm, 40),
            &plain,
        );
        runner
            .run(None, &AtomicBool::new(false), &mut Quiet)
            .unwrap();
        let island = dir.path().join(format!("island-{algorithm:?}"));
        islands(
            &scenario,
            &island,
            1,
            Migration::default(),
            options(algorithm, 40),
        );
        let mut got = best_json(&island);
        assert_eq!(got["islands"]["islands"], 1);
        got.as_object_mut().unwrap().remove("islands");
        assert_eq!(got, best_json(&plain), "{algorithm:?}");
        let history = |d: &Path| std::fs::read_to_string(d.join("history.csv")).unwrap();
        let cut = |t: String| -> Vec<String> {
            t.lines()
                .map(|l| l.split_once(',').map_or(l, |(_, rest)| rest).to_string())
                .collect()
        };
        assert_eq!(cut(history(&island)), cut(history(&plain)));
        // 40 evaluations: GA 8 + 6 children (2 elites) per generation, so six whole
        // generations (38) and two of the seventh, which is cut at the budget (its points
        // count in best.json and history.csv, islands.csv keeps whole generations); PSO 8 per
        // generation, five whole ones.
        let generations = if algorithm == Algorithm::Ga { 6 } else { 5 };
        assert_eq!(
            island_rows(&island).len(),
            generations,
            "one row per generation"
        );
    }
}

#[test]
fn the_same_seed_and_number_of_islands_give_the_same_result_and_migration_follows_the_ring() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = small_scenario(dir.path());
    let every = Migration {
        interval: 1,
        count: 2,
    };
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    islands(&scenario, &a, 3, every, options(Algorithm::Ga, 96));
    islands(&scenario, &b, 3, every, options(Algorithm::Ga, 96));
    assert_eq!(best_json(&a), best_json(&b));
    assert_eq!(island_rows(&a), island_rows(&b));
    let rows = island_rows(&a);
    // 96 evaluations by 3 islands of 8: 24 and then 18 (2 elites each) per generation.
    assert_eq!(rows.len(), 5 * 3, "5 generations of 3 islands");
    // Migration after every generation along the ring 0 → 1 → 2 → 0: island i+1 takes in
    // island i's best of this generation, which is no worse than island i's best of the last.
    let cost =
        |rows: &[Vec<String>], g: usize, i: usize| -> f64 { rows[g * 3 + i][3].parse().unwrap() };
    for g in 1..5 {
        for i in 0..3 {
            assert!(
                cost(&rows, g, (i + 1) % 3) <= cost(&rows, g - 1, i),
                "generation {g}: island {} is worse than island {i} was: {rows:?}",
                (i + 1) % 3
            );
        }
    }
    // Without migration the islands keep apart.
    let apart = dir.path().join("apart");
    islands(
        &scenario,
        &apart,
        3,
        Migration {
            interval: 1,
            count: 0,
        },
        options(Algorithm::Ga, 96),
    );
    let apart = island_rows(&apart);
    assert!(
        (1..5).any(|g| (0..3).any(|i| cost(&apart, g, (i + 1) % 3) > cost(&apart, g - 1, i))),
        "islands without migration look as if they migrated: {apart:?}"
    );
    // Two islands that migrate after every generation share their best.
    let two = dir.path().join("two");
    islands(&scenario, &two, 2, every, options(Algorithm::Ga, 64));
    for g in island_rows(&two).chunks(2) {
        assert_eq!(g[0][3], g[1][3]);
    }
    // And a different number of islands gives another job.
    let four = dir.path().join("four");
    islands(&scenario, &four, 4, every, options(Algorithm::Ga, 96));
    assert_ne!(island_rows(&four), island_rows(&a));
}

/// Ranks simulated by threads: a channel per ordered pair of ranks.
struct ThreadComm {
    rank: usize,
    size: usize,
    to: Vec<Sender<Vec<u8>>>,
    from: Vec<Mutex<Receiver<Vec<u8>>>>,
    barrier: Arc<Barrier>,
}

fn thread_comms(size: usize) -> Vec<ThreadComm> {
    let mut senders: Vec<Vec<Option<Sender<Vec<u8>>>>> = (0..size).map(|_| vec![]).collect();
    let mut receivers: Vec<Vec<Option<Receiver<Vec<u8>>>>> = (0..size)
        .map(|_| (0..size).map(|_| None).collect())
        .collect();
    for (from, s) in senders.iter_mut().enumerate() {
        for (to, r) in receivers.iter_mut().enumerate() {
            let (tx, rx) = channel();
            s.push(Some(tx));
            r[from] = Some(rx);
            let _ = to;
        }
    }
    let barrier = Arc::new(Barrier::new(size));
    senders
        .into_iter()
        .zip(receivers)
        .enumerate()
        .map(|(rank, (s, r))| ThreadComm {
            rank,
            size,
            to: s.into_iter().map(Option::unwrap).collect(),
            from: r.into_iter().map(|r| Mutex::new(r.unwrap())).collect(),
            barrier: barrier.clone(),
        })
        .collect()
}

impl ThreadComm {
    fn recv(&self, from: usize) -> Vec<u8> {
        self.from[from].lock().unwrap().recv().unwrap()
    }
}

impl Comm for ThreadComm {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.size
    }
    fn ring_shift(&self, bytes: &[u8]) -> kinsynth::Result<Vec<u8>> {
        self.to[(self.rank + 1) % self.size]
            .send(bytes.to_vec())
            .unwrap();
        Ok(self.recv((self.rank + self.size - 1) % self.size))
    }
    fn gather(&self, bytes: &[u8]) -> kinsynth::Result<Option<Vec<Vec<u8>>>> {
        if self.rank != 0 {
            self.to[0].send(bytes.to_vec()).unwrap();
            return Ok(None);
        }
        let mut all = vec![bytes.to_vec()];
        all.extend((1..self.size).map(|r| self.recv(r)));
        Ok(Some(all))
    }
    fn broadcast(&self, bytes: &[u8]) -> kinsynth::Result<Vec<u8>> {
        if self.rank == 0 {
            for r in 1..self.size {
                self.to[r].send(bytes.to_vec()).unwrap();
            }
            Ok(bytes.to_vec())
        } else {
            Ok(self.recv(0))
        }
    }
    fn barrier(&self) {
        self.barrier.wait();
    }
    fn abort(&self, _: i32) {}
}

/// Runs an island job of `n` islands over `ranks` thread-ranks.
/// Runs an island job of `n` islands over `ranks` simulated ranks; rank 0's summary.
fn islands_on_ranks(
    scenario: &Path,
    out: &Path,
    n: usize,
    ranks: usize,
    o: RunOptions,
) -> RunSummary {
    let s = Scenario::load(scenario).unwrap();
    let migration = Migration {
        interval: 2,
        count: 2,
    };
    std::thread::scope(|scope| {
        let handles: Vec<_> = thread_comms(ranks)
            .into_iter()
            .map(|comm| {
                let (s, o) = (&s, o.clone());
                scope.spawn(move || {
                    let runner = Runner::new(s, scenario, s.planner.clone(), o, out);
                    let got = IslandJob::new(&runner, n, migration)
                        .run(&comm, None, &AtomicBool::new(false), &mut Quiet)
                        .unwrap();
                    assert_eq!(got.is_some(), comm.rank == 0);
                    got.map(|g| g.summary)
                })
            })
            .collect();
        let mut summaries: Vec<RunSummary> = handles
            .into_iter()
            .filter_map(|h| h.join().unwrap())
            .collect();
        summaries.pop().expect("rank 0's summary")
    })
}

/// A time limit cuts an island generation short on every rank together: 8 islands of 50
/// designs over 2 ranks (4 islands stepped in turn per rank, about 0.1 s each here) under a
/// 0.3 s limit stop within the first generation, some islands having finished their step and
/// the later ones cut. Every island returns to its last whole generation (none), counts
/// included, and the designs evaluated still give the result.
#[test]
fn a_time_limit_cuts_an_island_generation_short_on_every_rank() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(small_scenario(dir.path()))
        .unwrap()
        .replace("population = 8", "population = 50");
    let scenario = dir.path().join("wide.toml");
    std::fs::write(&scenario, text).unwrap();
    let out = dir.path().join("cut");
    let o = RunOptions {
        time_limit: Some(0.3),
        evaluations: None,
        ..options(Algorithm::Ga, 0)
    };
    let summary = islands_on_ranks(&scenario, &out, 8, 2, o);
    assert_eq!(summary.stopped, "time limit reached");
    assert!(
        (1..400).contains(&summary.evaluations),
        "the first generation is cut short: {} of 400 evaluated",
        summary.evaluations
    );
    assert!(summary.cost.is_finite());
    // history.csv has one row, for the cut generation; the checkpoint none.
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    assert_eq!(history.lines().count(), 2, "{history}");
    let checkpoint: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("checkpoint.json")).unwrap())
            .unwrap();
    assert_eq!(checkpoint["generation"], 0);
    assert_eq!(checkpoint["evaluations"], 0);
    let per_island = checkpoint["islands"]["evaluations"].as_array().unwrap();
    assert_eq!(per_island.len(), 8);
    assert!(per_island.iter().all(|e| e == 0), "{per_island:?}");
}

/// An evaluation budget is exact for an island job too: what is left of it is shared among
/// the islands in index order, and a generation that needs more is cut at it on every rank
/// (the islands return to their last whole generation; the designs evaluated count for the
/// result). 4 islands of 8 over 1 and 2 ranks with 10 evaluations: 3, 3, 2 and 2 of the first
/// generation's 32, the same result on both. Resumed to 60 (32, 24, and 1 of each island's
/// third step), the job gives the uninterrupted 60's result.
#[test]
fn an_evaluation_budget_cuts_an_island_generation_at_it_on_every_rank() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = small_scenario(dir.path());
    let s = Scenario::load(&scenario).unwrap();
    let one = dir.path().join("one");
    let summary = islands_on_ranks(&scenario, &one, 4, 1, options(Algorithm::Ga, 10));
    assert_eq!(summary.stopped, "evaluation budget spent");
    assert_eq!(summary.evaluations, 10);
    let two = dir.path().join("two");
    let summary = islands_on_ranks(&scenario, &two, 4, 2, options(Algorithm::Ga, 10));
    assert_eq!(summary.evaluations, 10);
    assert_eq!(best_json(&one), best_json(&two));
    assert_eq!(best_json(&one)["evaluations"], 10);
    let history = std::fs::read_to_string(one.join("history.csv")).unwrap();
    assert_eq!(history.lines().count(), 2, "{history}");
    let checkpoint: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(one.join("checkpoint.json")).unwrap())
            .unwrap();
    assert_eq!(checkpoint["generation"], 0);
    let per_island = checkpoint["islands"]["evaluations"].as_array().unwrap();
    assert!(per_island.iter().all(|e| e == 0), "{per_island:?}");

    let migration = Migration {
        interval: 2,
        count: 2,
    };
    let whole = dir.path().join("whole");
    let summary = islands(&scenario, &whole, 4, migration, options(Algorithm::Ga, 60));
    assert_eq!(summary.evaluations, 60);
    let runner = Runner::new(
        &s,
        &scenario,
        s.planner.clone(),
        options(Algorithm::Ga, 60),
        &one,
    );
    let checkpoint = Runner::read_checkpoint(&one).unwrap();
    resume_islands(&runner, 4, migration, checkpoint);
    assert_eq!(best_json(&one), best_json(&whole));
}

/// Past its time limit a new island job evaluates one design, the first island's first (so
/// that it has a result), not one per island one after another: with a limit of 0, 8 islands
/// over 2 ranks make one evaluation, as a plain run does, and report it.
#[test]
fn a_new_island_job_evaluates_one_design_under_a_spent_time_limit() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = small_scenario(dir.path());
    let out = dir.path().join("zero");
    let o = RunOptions {
        time_limit: Some(0.0),
        evaluations: None,
        ..options(Algorithm::Ga, 0)
    };
    let summary = islands_on_ranks(&scenario, &out, 8, 2, o);
    assert_eq!(summary.stopped, "time limit reached");
    assert_eq!(summary.evaluations, 1);
    assert!(summary.cost.is_finite());
    assert_eq!(best_json(&out)["evaluations"], 1);
}

#[test]
fn the_result_does_not_depend_on_how_islands_are_spread_over_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = small_scenario(dir.path());
    for algorithm in [Algorithm::Ga, Algorithm::Pso] {
        let o = options(algorithm, 160);
        let one = dir.path().join(format!("one-{algorithm:?}"));
        islands_on_ranks(&scenario, &one, 4, 1, o.clone());
        let two = dir.path().join(format!("two-{algorithm:?}"));
        islands_on_ranks(&scenario, &two, 4, 2, o.clone());
        let four = dir.path().join(format!("four-{algorithm:?}"));
        islands_on_ranks(&scenario, &four, 4, 4, o);
        assert_eq!(best_json(&one), best_json(&two), "{algorithm:?}");
        assert_eq!(best_json(&one), best_json(&four), "{algorithm:?}");
        assert_eq!(island_rows(&one), island_rows(&four), "{algorithm:?}");
    }
}

/// Raises `stop` after `after` generations, as Ctrl-C would.
struct StopAfter {
    after: usize,
    seen: usize,
    islands_seen: usize,
    stop: Arc<AtomicBool>,
}

impl Observer for StopAfter {
    fn generation(&mut self, _: &HistoryRow) {
        self.seen += 1;
        if self.seen == self.after {
            self.stop.store(true, Ordering::SeqCst);
        }
    }
    fn islands(&mut self, rows: &[IslandRow]) {
        assert_eq!(rows.len(), 2);
        self.islands_seen += 1;
    }
}

#[test]
fn a_stopped_job_resumes_to_the_uninterrupted_result_and_refuses_another_number_of_islands() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = small_scenario(dir.path());
    let s = Scenario::load(&scenario).unwrap();
    let migration = Migration {
        interval: 2,
        count: 1,
    };
    let whole = dir.path().join("whole");
    islands(
        &scenario,
        &whole,
        2,
        migration,
        options(Algorithm::Pso, 112),
    );

    let stopped = dir.path().join("stopped");
    let runner = Runner::new(
        &s,
        &scenario,
        s.planner.clone(),
        options(Algorithm::Pso, 112),
        &stopped,
    );
    let stop = Arc::new(AtomicBool::new(false));
    let mut observer = StopAfter {
        after: 3,
        seen: 0,
        islands_seen: 0,
        stop: stop.clone(),
    };
    IslandJob::new(&runner, 2, migration)
        .run(&SingleProcess, None, &stop, &mut observer)
        .unwrap();
    assert_eq!(observer.islands_seen, 3);
    assert_eq!(best_json(&stopped)["stopped"], "interrupted");
    let checkpoint = Runner::read_checkpoint(&stopped).unwrap();
    assert_eq!(checkpoint.generation, 3);
    assert_eq!(checkpoint.islands.as_ref().unwrap().islands, 2);

    // Another number of islands, or no islands, is refused with a clear error.
    let err = IslandJob::new(&runner, 3, migration)
        .run(
            &SingleProcess,
            Some(checkpoint.clone()),
            &AtomicBool::new(false),
            &mut Quiet,
        )
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("checkpoint.json") && err.contains("holds 2 islands, this job has 3"),
        "{err}"
    );
    let err = runner
        .run(
            Some(checkpoint.clone()),
            &AtomicBool::new(false),
            &mut Quiet,
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains("resume it with --islands"), "{err}");
    // The checkpoint's migration settings obey a scenario's rules (a count of 10^9 asked for
    // memory at the first migration), and so do the islands' own settings.
    let with_migration = |interval, count| {
        let mut bad = checkpoint.clone();
        bad.islands.as_mut().unwrap().migration = Migration { interval, count };
        bad
    };
    let mut small_swarm = checkpoint.clone();
    small_swarm.state[1]["params"]["swarm"] = serde_json::json!(1);
    // Read from a file whose content no longer matches its checksum.
    let mut changed = checkpoint.clone();
    changed.integrity = kinsynth::optimize::runner::Integrity::Changed {
        recorded: "fnv1a64:0".into(),
        now: "fnv1a64:1".into(),
    };
    for (bad, says) in [
        (
            with_migration(2, 1_000_000_000),
            "islands.migration.count = 1000000000: must be at most 10000 (the limit)",
        ),
        (
            with_migration(0, 1),
            "islands.migration.interval = 0: must be at least 1",
        ),
        (small_swarm, "state[1].params.swarm = 1"),
        (
            changed,
            "checksum = fnv1a64:0: the content hashes to fnv1a64:1: the checkpoint was changed",
        ),
    ] {
        let err = IslandJob::new(&runner, 2, migration)
            .run(
                &SingleProcess,
                Some(bad),
                &AtomicBool::new(false),
                &mut Quiet,
            )
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("checkpoint.json") && err.contains(says),
            "{err}"
        );
    }

    resume_islands(&runner, 2, migration, checkpoint);
    assert_eq!(best_json(&stopped), best_json(&whole));
    assert_eq!(island_rows(&stopped), island_rows(&whole));
}
