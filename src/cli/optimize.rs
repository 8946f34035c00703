//! `kinsynth optimize`: optimises a design for a scenario (fresh or resumed) and writes its results.

use super::{override_planner, progress, whole};
use kinsynth::Scenario;
use std::path::PathBuf;

/// The output-directory lock file of a running `optimize`, removed by the Ctrl-C handler when
/// a second Ctrl-C ends the process at once.
static LOCK_PATH: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();

/// The largest evaluation budget `--evaluations` accepts.
const MAX_EVALUATIONS: u64 = 1_000_000_000_000;

/// Optimise a design for a scenario (the main job): GA, PSO or ASA over the design space.
///
/// Writes into --out (or the --resume directory): best.json (the best design and its
/// figures; the same bytes for the same seed), time.json (the run's wall-clock seconds),
/// history.csv (one row per generation), reach.json (the best design's
/// reachability report), convergence.svg (best R and cost against time), report.html (the
/// browser report in 3D: scene, design, paths, cost and settings), robot.urdf (the
/// best design as URDF), robot.srdf (its planning group and allowed-collision matrix),
/// trajectories/ (task_{i}.csv and task_{i}.json per reached task)
/// and checkpoint.json (the state for --resume); .kinsynth.lock exists while the run lasts.
/// With --islands also islands.csv (one row per island per generation).
#[derive(clap::Args, Clone)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The scenario file (TOML). With --resume: default the checkpoint's, and if given it
    /// must be the scenario the run started with.
    pub file: Option<PathBuf>,
    /// Optimiser. Default: the scenario's.
    #[arg(long, conflicts_with = "resume")]
    pub optimizer: Option<kinsynth::scenario::Algorithm>,
    /// Edge checker: discrete, segment, ccd or certified. Default: the scenario's.
    #[arg(long, conflicts_with = "resume")]
    pub checker: Option<kinsynth::collision::CheckerKind>,
    /// Step bound L_max. Default: the scenario's.
    #[arg(long, conflicts_with = "resume")]
    pub lmax: Option<f64>,
    /// The paper's baseline: ASA with node-only (discrete) checks at L_max = π/40, planned as
    /// the paper's RRT does (no backward trees, a fixed budget).
    #[arg(long, conflicts_with_all = ["optimizer", "checker", "lmax", "resume"])]
    pub baseline: bool,
    /// Seed. Default: the scenario's.
    #[arg(long, conflicts_with = "resume")]
    pub seed: Option<u64>,
    /// Wall-clock budget in seconds, over the whole run (with --resume: a new total, which
    /// extends the run); the generation running when it is up stops there, keeping the designs
    /// it evaluated. Default: the scenario's budgets, when neither --time-limit nor
    /// --evaluations is given (either replaces both of the scenario's).
    #[arg(long)]
    pub time_limit: Option<f64>,
    /// Budget in objective evaluations, over the whole run (with --resume: a new total): the
    /// run makes exactly this many (fewer if it converges first), cutting its last generation
    /// short where needed. Default: the scenario's budgets, when neither --time-limit nor
    /// --evaluations is given (either replaces both of the scenario's: `--evaluations N` alone
    /// runs N evaluations however long they take, so the result depends on the seed only).
    #[arg(long)]
    pub evaluations: Option<f64>,
    /// Seconds between checkpoints. Default: the scenario's.
    #[arg(long)]
    pub checkpoint_interval: Option<f64>,
    /// Fresh planner seeds the final candidates are re-checked with (0: none). Default:
    /// the scenario's optimizer.recheck_seeds.
    #[arg(long)]
    pub recheck_seeds: Option<f64>,
    /// Extra planner runs that confirm every R = 1 an evaluation claims. Default: the
    /// scenario's optimizer.confirm_seeds.
    #[arg(long, conflicts_with = "resume")]
    pub confirm_seeds: Option<f64>,
    /// Output directory.
    #[arg(long, required_unless_present = "resume", conflicts_with = "resume")]
    pub out: Option<PathBuf>,
    /// Continue the run whose checkpoint is in this directory (results go there too).
    #[arg(long)]
    pub resume: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// An island job: one island (population) per MPI rank under `mpirun`/`srun` (built with
    /// `--features mpi`), or N islands in this process. Every `[optimizer] migration.interval`
    /// generations each island sends its best `migration.count` designs to the next; also
    /// writes islands.csv (one row per island per generation). With --resume: the job must
    /// have as many islands as the checkpoint.
    #[arg(long, value_name = "N", num_args = 0..=1)]
    pub islands: Option<Option<usize>>,
}

/// The files a run writes into its output directory (beside the folder of trajectories).
const OUTPUT_FILES: [&str; 10] = {
    use kinsynth::optimize::output::files;
    [
        files::BEST,
        files::TIME,
        files::HISTORY,
        files::REACH,
        files::PLOT,
        files::CHECKPOINT,
        files::URDF,
        files::SRDF,
        files::REPORT,
        files::ISLANDS,
    ]
};

/// What `optimize` has read and checked before a run starts, with the output lock held.
pub struct Prepared {
    /// The scenario.
    pub scenario: Scenario,
    /// Its file.
    pub scenario_path: PathBuf,
    /// Planner settings.
    pub planner: kinsynth::planning::PlannerConfig,
    /// Run settings.
    pub options: kinsynth::optimize::RunOptions,
    /// The checkpoint to resume (read under the lock).
    pub checkpoint: Option<kinsynth::optimize::runner::Checkpoint>,
    /// Output directory.
    pub out: PathBuf,
    /// The output-directory lock.
    pub lock: kinsynth::optimize::lock::OutputLock,
}

/// Runs the command.
pub fn run(args: Args) -> Result<(), kinsynth::Error> {
    if let Some(islands) = args.islands {
        return super::islands::run(args, islands);
    }
    let Prepared {
        scenario: s,
        scenario_path,
        planner,
        options,
        checkpoint,
        out,
        lock,
    } = prepare(&args)?;
    let stop = stop_on_ctrl_c();
    let runner = kinsynth::optimize::runner::Runner::new(
        &s,
        &scenario_path,
        planner.clone(),
        options.clone(),
        &out,
    );
    let mut observer = progress::Bar::new(&options, args.quiet);
    let summary = runner.run(checkpoint, &stop, &mut observer)?;
    report(&out, &summary);
    drop(lock);
    Ok(())
}

/// Reads and checks the options, the scenario and any checkpoint, and takes the output lock.
pub fn prepare(args: &Args) -> Result<Prepared, kinsynth::Error> {
    let Args {
        file,
        optimizer,
        checker,
        lmax,
        baseline,
        seed,
        time_limit,
        evaluations,
        checkpoint_interval,
        recheck_seeds,
        confirm_seeds,
        out,
        resume,
        quiet: _,
        islands: _,
    } = args.clone();
    use kinsynth::optimize::lock::OutputLock;
    use kinsynth::optimize::runner::{check_seconds, Checkpoint, RunOptions, Runner};
    if let Some(t) = time_limit {
        check_seconds("--time-limit", t)?;
    }
    if let Some(t) = checkpoint_interval {
        check_seconds("--checkpoint-interval", t)?;
    }
    let max_seeds = kinsynth::optimize::runner::MAX_SEEDS as u64;
    let evaluations = whole("--evaluations", evaluations, 1, MAX_EVALUATIONS)?;
    let recheck_seeds = whole("--recheck-seeds", recheck_seeds, 0, max_seeds)?.map(|n| n as usize);
    let confirm_seeds = whole("--confirm-seeds", confirm_seeds, 0, max_seeds)?.map(|n| n as usize);
    let out = match (&resume, out) {
        (Some(dir), _) => dir.clone(),
        (None, Some(out)) => out,
        (None, None) => {
            return Err(kinsynth::Error::invalid(
                "--out",
                "missing",
                "give an output directory (or --resume DIR)",
            ))
        }
    };
    // A run's folder without a checkpoint: the run was stopped before it wrote its first.
    if let Some(dir) = resume.as_ref().filter(|d| d.is_dir()) {
        let file = kinsynth::optimize::runner::files::CHECKPOINT;
        if std::fs::symlink_metadata(dir.join(file)).is_err() {
            return Err(kinsynth::Error::invalid(
                "--resume",
                dir.display(),
                format!(
                    "holds no {file}: the run there was stopped before its first checkpoint (or it is no run's folder); start it anew without --resume"
                ),
            ));
        }
    }
    let checkpoint = match &resume {
        Some(dir) => Some(Runner::read_checkpoint(dir)?),
        None => None,
    };
    if let Some(l) = lmax {
        override_planner(&mut Default::default(), None, Some(l))?;
    }
    let scenario_path = match (&checkpoint, file) {
        (_, Some(f)) => f,
        (Some(c), None) => c.scenario.clone(),
        (None, None) => {
            return Err(kinsynth::Error::invalid(
                "SCENARIO",
                "missing",
                "give a scenario file (or --resume DIR)",
            ))
        }
    };
    let s = Scenario::load(&scenario_path).map_err(|e| match (&checkpoint, e) {
        // The scenario the checkpoint names cannot be read: say where the name comes from.
        (Some(_), kinsynth::Error::Read { path, source }) if args.file.is_none() => {
            kinsynth::Error::invalid(
                "scenario",
                path.display(),
                format!("cannot read the scenario this checkpoint records: {source}"),
            )
            .in_file(out.join(kinsynth::optimize::output::files::CHECKPOINT))
        }
        (_, e) => e,
    })?;
    let settings = |checkpoint: &Option<Checkpoint>| match checkpoint {
        Some(c) => {
            let mut options = c.options.clone();
            // A budget given again replaces the checkpoint's: the run goes on to it.
            if time_limit.is_some() {
                options.time_limit = time_limit;
            }
            if evaluations.is_some() {
                options.evaluations = evaluations;
            }
            if let Some(t) = checkpoint_interval {
                options.checkpoint_interval = t;
            }
            if let Some(k) = recheck_seeds {
                options.recheck_seeds = k;
            }
            Ok((c.planner.clone(), options))
        }
        None => {
            let mut planner = s.planner.clone();
            let mut algorithm = s.optimizer.algorithm;
            if baseline {
                algorithm = kinsynth::scenario::Algorithm::Asa;
                planner.checker = kinsynth::collision::CheckerKind::Discrete;
                planner.l_max = std::f64::consts::PI / 40.0;
                planner.schedule = None;
                // The paper's RRT: from home alone, within the fixed budget, its inverse
                // kinematics clamping whole steps into the ranges, each step tried whole first.
                planner.postures = 0;
                planner.budget_growth = 1;
                planner.ik_hold_limits = false;
                planner.aimed_steering = false;
            }
            if let Some(a) = optimizer {
                algorithm = a;
            }
            override_planner(&mut planner, checker, lmax)?;
            // Budgets on the command line replace both of the scenario's (its time limit
            // would otherwise cut an evaluation budget short on a slow machine).
            let given = time_limit.is_some() || evaluations.is_some();
            let options = RunOptions {
                algorithm,
                seed: seed.unwrap_or(s.seed),
                time_limit: if given {
                    time_limit
                } else {
                    s.optimizer.time_limit
                },
                evaluations: if given {
                    evaluations
                } else {
                    s.optimizer.evaluations
                },
                patience: s.optimizer.patience,
                checkpoint_interval: checkpoint_interval.unwrap_or(s.optimizer.checkpoint_interval),
                recheck_seeds: recheck_seeds.unwrap_or(s.optimizer.recheck_seeds),
                confirm_seeds: confirm_seeds.unwrap_or(s.optimizer.confirm_seeds),
            };
            Ok((planner, options))
        }
    };
    let (_, options) = settings(&checkpoint)?;
    if options.time_limit.is_none() && options.evaluations.is_none() {
        return Err(kinsynth::Error::invalid(
            "budget",
            "none",
            "give --time-limit or --evaluations (or set them in [optimizer])",
        ));
    }
    // No result may replace the scenario or one of its meshes: checked before the lock file
    // is written.
    {
        use kinsynth::optimize::output::files;
        let flag = if resume.is_some() {
            "--resume"
        } else {
            "--out"
        };
        let inputs = super::inputs(&scenario_path, &s, &[]);
        let results = OUTPUT_FILES.iter().map(|name| out.join(name));
        kinsynth::io::check_dir_not_input(flag, &out, results, &inputs)?;
        let trajectories = out.join(files::TRAJECTORIES);
        let paths = (0..s.workspace.tasks.len())
            .flat_map(|i| kinsynth::export::trajectory::trajectory_files(&trajectories, i));
        kinsynth::io::check_dir_not_input(flag, &trajectories, paths, &inputs)?;
    }
    // A file (or a device) where the folder should be: say so, before the lock is taken in it.
    kinsynth::io::check_output_dir(&out)?;
    let (lock, acquired) = OutputLock::acquire(&out)?;
    if let Some(o) = &acquired.took_over {
        // The lock file's fields as they are, on one line and of a readable length.
        let message = format!(
            "{}: taking over the lock of pid {} on host {} ({}), which is no longer running",
            lock.path().display(),
            o.pid,
            o.host,
            o.command
        );
        eprintln!("warning: {}", kinsynth::error::shorten(&message));
    }
    if !acquired.removed.is_empty() {
        eprintln!(
            "warning: {}: removed {} temporary file(s) left by a killed run",
            out.display(),
            acquired.removed.len()
        );
    }
    let _ = LOCK_PATH.set(lock.path().to_path_buf());
    // The run's output names must take files (and a folder): found wrong only after the run,
    // the results written before them would be left beside a failure.
    {
        use kinsynth::optimize::output::files;
        for name in OUTPUT_FILES {
            kinsynth::io::check_output_file(&out.join(name))?;
        }
        kinsynth::io::check_output_dir(&out.join(files::TRAJECTORIES))?;
    }
    // A new run in a folder that holds an earlier run's results replaces them (`--resume DIR`
    // continues that run instead): say so.
    if resume.is_none() {
        use kinsynth::optimize::output::files;
        let earlier = out.join(files::BEST);
        if earlier.is_file() {
            eprintln!(
                "warning: {}: replacing the results of an earlier run (--resume {} continues it instead)",
                out.display(),
                out.display()
            );
        }
    }
    // Read again under the lock: the state the last run left.
    let checkpoint = match &resume {
        Some(dir) => Some(Runner::read_checkpoint(dir)?),
        None => None,
    };
    let (planner, options) = settings(&checkpoint)?;
    Ok(Prepared {
        scenario: s,
        scenario_path,
        planner,
        options,
        checkpoint,
        out,
        lock,
    })
}

/// Raises the returned flag on Ctrl-C, SIGTERM or SIGHUP (the run stops within its generation,
/// keeping the designs evaluated, and writes its results); a second signal ends the process at
/// once, removing the lock file (the operating system releases the lock itself).
pub fn stop_on_ctrl_c() -> std::sync::Arc<std::sync::atomic::AtomicBool> {
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    {
        let stop = stop.clone();
        let _ = ctrlc::set_handler(move || {
            if stop.swap(true, std::sync::atomic::Ordering::SeqCst) {
                if let Some(p) = LOCK_PATH.get() {
                    let _ = std::fs::remove_file(p);
                }
                std::process::exit(130);
            }
        });
    }
    stop
}

/// Prints the one-line summary of a finished run.
pub fn report(out: &std::path::Path, summary: &kinsynth::optimize::RunSummary) {
    let robust = summary.robust_reachability.as_ref().map_or_else(
        || "no re-check".to_string(),
        |r| {
            format!(
                "re-checked with {} seeds: R min {:.3}, mean {:.3}, max {:.3}, {:.1} s",
                r.seeds, r.min, r.mean, r.max, summary.recheck_s
            )
        },
    );
    say!(
        "{}: {} + {} (L_max {:.4}), seed {}: R = {:.3} ({robust}), cost {:.4}, {} links and {} joints kept, total length {:.3} m; {} evaluation{} in {:.1} s ({})",
        out.display(),
        summary.optimizer,
        summary.checker,
        summary.l_max,
        summary.seed,
        summary.reachability,
        summary.cost,
        summary.links_kept,
        summary.joints_kept,
        summary.design.total_length(),
        summary.evaluations,
        if summary.evaluations == 1 { "" } else { "s" },
        summary.elapsed_s,
        summary.stopped
    );
}
