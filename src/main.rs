//! The `kinsynth` command line: a thin shell over the library.

use clap::{Parser, Subcommand};
use kinsynth::scenario::preset::{self, Preset};
use kinsynth::Scenario;
use std::path::PathBuf;
use std::process::ExitCode;

/// The output-directory lock file of a running `optimize`, removed by the Ctrl-C handler when
/// a second Ctrl-C ends the process at once.
static LOCK_PATH: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();

/// `println!` that ends the process quietly when stdout is closed (e.g. piped into `head`).
macro_rules! say {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if writeln!(std::io::stdout(), $($t)*).is_err() {
            std::process::exit(0);
        }
    }};
}

/// Task-based kinematic design of serial manipulators in cluttered environments.
#[derive(Parser)]
#[command(name = "kinsynth", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Write a random scenario like the paper's experiments (paper-2d, paper-3d).
    ///
    /// Writes the file given by -o.
    Scenario {
        /// Which preset: paper-2d (§IV-A) or paper-3d (§IV-B).
        #[arg(long)]
        preset: Preset,
        /// Seed: the same seed gives the same file.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output file (written atomically).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Validate a scenario file and print a short summary.
    ///
    /// Writes no files.
    Check {
        /// The scenario file (TOML).
        file: PathBuf,
    },
    /// Optimise a design for a scenario (the main job): GA, PSO or ASA over the design space.
    ///
    /// Writes into --out (or the --resume directory): best.json (the best design and its
    /// figures), history.csv (one row per generation), reach.json (the best design's
    /// reachability report), convergence.svg (best R and cost against time), robot.urdf (the
    /// best design as URDF), robot.srdf (its planning group and allowed-collision matrix),
    /// trajectories/ (task_{i}.csv and task_{i}.json per reached task)
    /// and checkpoint.json (the state for --resume); .kinsynth.lock exists while the run lasts.
    #[command(allow_negative_numbers = true)]
    Optimize {
        /// The scenario file (TOML). With --resume: default the checkpoint's, and if given it
        /// must be the scenario the run started with.
        file: Option<PathBuf>,
        /// Optimiser. Default: the scenario's.
        #[arg(long, conflicts_with = "resume")]
        optimizer: Option<kinsynth::scenario::Algorithm>,
        /// Edge checker. Default: the scenario's.
        #[arg(long, conflicts_with = "resume")]
        checker: Option<kinsynth::collision::CheckerKind>,
        /// Step bound L_max. Default: the scenario's.
        #[arg(long, conflicts_with = "resume")]
        lmax: Option<f64>,
        /// The paper's baseline: ASA with node-only (discrete) checks at L_max = π/40.
        #[arg(long, conflicts_with_all = ["optimizer", "checker", "lmax", "resume"])]
        baseline: bool,
        /// Seed. Default: the scenario's.
        #[arg(long, conflicts_with = "resume")]
        seed: Option<u64>,
        /// Wall-clock budget in seconds, over the whole run (with --resume: a new total, which
        /// extends the run). Default: the scenario's.
        #[arg(long)]
        time_limit: Option<f64>,
        /// Budget in objective evaluations, over the whole run (with --resume: a new total).
        /// Default: the scenario's.
        #[arg(long)]
        evaluations: Option<f64>,
        /// Seconds between checkpoints. Default: the scenario's.
        #[arg(long)]
        checkpoint_interval: Option<f64>,
        /// Fresh planner seeds the final candidates are re-checked with (0: none). Default:
        /// the scenario's optimizer.recheck_seeds.
        #[arg(long)]
        recheck_seeds: Option<f64>,
        /// Extra planner runs that confirm every R = 1 an evaluation claims. Default: the
        /// scenario's optimizer.confirm_seeds.
        #[arg(long, conflicts_with = "resume")]
        confirm_seeds: Option<f64>,
        /// Output directory.
        #[arg(long, required_unless_present = "resume", conflicts_with = "resume")]
        out: Option<PathBuf>,
        /// Continue the run whose checkpoint is in this directory (results go there too).
        #[arg(long)]
        resume: Option<PathBuf>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Reproduce the paper's experiments: §IV-A (paper-2d: GA, PSO, ASA with segment at π/4
    /// against the ASA + discrete π/40 baseline) or §IV-B (paper-3d: GA), averaged over random
    /// workspaces.
    ///
    /// Writes into --out: runs.csv (one row per run), curves.csv and curves.svg (average
    /// reachability against time), and per workspace w: workspace{w}/scenario.toml and, per
    /// method k, workspace{w}/method{k}/ with every file `optimize` writes.
    #[command(allow_negative_numbers = true)]
    Experiment {
        /// paper-2d or paper-3d.
        preset: Preset,
        /// Number of random workspaces.
        #[arg(long, default_value_t = 10)]
        runs: usize,
        /// Seconds per run (runs that converge stop earlier).
        #[arg(long, default_value_t = 60.0)]
        time_limit: f64,
        /// Seed of the first workspace (the others follow).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
    },
    /// Reachability of a design: the share of task points an RRT from home reaches.
    ///
    /// A best.json is replayed: without --seed, the planner seed, random stream and settings
    /// of the evaluation that produced it give the same R and paths. Writes the report to
    /// --json FILE and task_{i}.csv and task_{i}.json per reached task into --trajectories
    /// DIR, when given; nothing otherwise.
    #[command(allow_negative_numbers = true)]
    Reach {
        /// The scenario file (TOML).
        file: PathBuf,
        /// A design JSON or an optimiser's best.json. Default: the scenario's largest design.
        #[arg(long)]
        design: Option<PathBuf>,
        /// Edge checker: discrete, segment, ccd or certified. Default: the scenario's.
        #[arg(long)]
        checker: Option<kinsynth::collision::CheckerKind>,
        /// Step bound L_max. Default: the scenario's.
        #[arg(long)]
        lmax: Option<f64>,
        /// Seed of the planner. Default: the scenario's (for a best.json: its own, replayed).
        #[arg(long)]
        seed: Option<u64>,
        /// Plan with N planner seeds (--seed and the N − 1 after it) and report the spread of
        /// R: min, mean and max. The report and trajectories are those of the first seed.
        #[arg(long)]
        seeds: Option<f64>,
        /// Write the report as JSON to this file (atomically).
        #[arg(long)]
        json: Option<PathBuf>,
        #[command(flatten)]
        urdf: UrdfReach,
    },
    /// Export a design (design JSON or best.json) as a URDF robot and its SRDF.
    ///
    /// Writes the file given by -o and, beside it, the same name with the extension .srdf
    /// (planning group and allowed-collision matrix).
    Urdf {
        /// The design JSON, or an optimiser's best.json.
        design: PathBuf,
        /// Output URDF file (written atomically); the robot is named after its stem.
        #[arg(short, long)]
        output: PathBuf,
        /// Scenario whose [robot] self-collision settings (self_collision, allowed_collisions,
        /// self_collision_samples, seed) fill the SRDF. Default: self-collision on, 1000
        /// samples, seed 0.
        #[arg(long)]
        scenario: Option<PathBuf>,
    },
    /// Compare the four edge checkers with the dense-sampling oracle on random edges.
    ///
    /// Prints a table; writes no files.
    #[command(allow_negative_numbers = true)]
    Edges {
        /// The scenario file (TOML).
        file: PathBuf,
        /// Step bounds L_max to test (comma-separated). Default: π/40, π/8, π/4.
        #[arg(long, value_delimiter = ',')]
        lmax: Vec<f64>,
        /// Edges per L_max.
        #[arg(long, default_value_t = 2000)]
        count: usize,
        /// Seed of the random edges.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Oracle sub-steps per edge.
        #[arg(long, default_value_t = kinsynth::collision::oracle::ORACLE_SUBSTEPS)]
        substeps: usize,
    },
}

/// Applies `--checker` and `--lmax` to the scenario's planner settings (a given `L_max`
/// replaces any schedule).
fn override_planner(
    planner: &mut kinsynth::planning::PlannerConfig,
    checker: Option<kinsynth::collision::CheckerKind>,
    lmax: Option<f64>,
) -> Result<(), kinsynth::Error> {
    if let Some(c) = checker {
        planner.checker = c;
    }
    if let Some(l) = lmax {
        if !(l.is_finite() && l > 0.0) {
            return Err(kinsynth::Error::invalid(
                "--lmax",
                l,
                "must be positive and finite",
            ));
        }
        planner.l_max = l;
        planner.schedule = None;
    }
    Ok(())
}

/// The largest evaluation budget `--evaluations` accepts.
const MAX_EVALUATIONS: u64 = 1_000_000_000_000;

/// A whole number given as `flag`: refused, naming the flag and the value, unless it is an
/// integer in `min..=max`.
fn whole(flag: &str, v: Option<f64>, min: u64, max: u64) -> Result<Option<u64>, kinsynth::Error> {
    match v {
        None => Ok(None),
        Some(x) if x.fract() == 0.0 && x >= min as f64 && x <= max as f64 => Ok(Some(x as u64)),
        Some(x) => Err(kinsynth::Error::invalid(
            flag,
            x,
            format!("must be a whole number from {min} to {max}"),
        )),
    }
}

/// `reach` options for evaluating an existing URDF robot and writing trajectories.
#[derive(clap::Args)]
struct UrdfReach {
    /// Evaluate this URDF robot instead of a design (see the README's "URDF" section).
    #[arg(long, conflicts_with = "design")]
    urdf: Option<PathBuf>,
    /// URDF link where the chain starts. Default: the root link.
    #[arg(long, requires = "urdf")]
    base_frame: Option<String>,
    /// URDF link whose origin is the end effector. Default: the leaf below the base.
    #[arg(long, requires = "urdf")]
    tip_frame: Option<String>,
    /// Capsule radius of the URDF robot's links (m). Default: the largest radius of its
    /// collision cylinders and spheres, else 0.05.
    #[arg(long, requires = "urdf")]
    radius: Option<f64>,
    /// Bodies of the URDF robot's links: `collision` (their <collision> meshes, boxes,
    /// cylinders, spheres and capsules) or `capsules` (capsules between joint origins).
    #[arg(long, requires = "urdf", default_value_t = kinsynth::import::BodyChoice::Collision)]
    body: kinsynth::import::BodyChoice,
    /// Where `package://NAME/…` mesh URIs point: NAME=DIR (repeatable). Default: a folder
    /// NAME above the URDF.
    #[arg(long, requires = "urdf", value_parser = package_arg)]
    package: Vec<(String, PathBuf)>,
    /// An SRDF whose <disable_collisions> link pairs are never checked for self-collision.
    #[arg(long, requires = "urdf")]
    srdf: Option<PathBuf>,
    /// Write task_{index}.csv and task_{index}.json for every reached task into this directory.
    #[arg(long)]
    trajectories: Option<PathBuf>,
}

/// Parses `--package NAME=DIR`.
fn package_arg(s: &str) -> Result<(String, PathBuf), String> {
    match s.split_once('=') {
        Some((n, d)) if !n.is_empty() && !d.is_empty() => Ok((n.to_string(), PathBuf::from(d))),
        _ => Err(format!("`{s}`: expected NAME=DIR")),
    }
}

fn run(cli: Cli) -> Result<(), kinsynth::Error> {
    match cli.command {
        Command::Scenario {
            preset: p,
            seed,
            output,
        } => {
            let spec = preset::generate(p, seed);
            kinsynth::io::write_atomic(&output, preset::to_toml(p, &spec).as_bytes())?;
            say!(
                "wrote {} ({}, seed {seed}: {} obstacles, {} tasks)",
                output.display(),
                p.name(),
                spec.obstacle.len(),
                spec.task.len()
            );
        }
        Command::Check { file } => {
            let s = Scenario::load(&file)?;
            let largest = s.space.largest();
            let chain = largest.chain();
            say!("{}: ok", file.display());
            say!("  name            {}", s.name);
            say!(
                "  links           {} (largest design: {} joints, reach {:.3} m)",
                largest.links.len(),
                chain.dof(),
                largest.total_length()
            );
            say!("  free variables  {}", s.space.dim());
            say!("  obstacles       {}", s.workspace.obstacles.len());
            say!("  tasks           {}", s.workspace.tasks.len());
            say!("  clearance       {} m", s.workspace.clearance);
            say!(
                "  planner         {} checker, l_max {:.4}, {} iterations",
                s.planner.checker.name(),
                s.planner.l_max,
                s.planner.max_iterations
            );
            for c in s.home_contacts() {
                let o = &s.workspace.obstacles[c.obstacle];
                eprintln!(
                    "warning: {}: the largest design's home pose has link {} touching obstacle[{}] ({}): distance {:.4} m, clearance {} m",
                    file.display(),
                    c.link,
                    c.obstacle,
                    o.name,
                    c.distance,
                    s.workspace.clearance
                );
            }
        }
        Command::Optimize {
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
            quiet,
        } => {
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
            let recheck_seeds =
                whole("--recheck-seeds", recheck_seeds, 0, max_seeds)?.map(|n| n as usize);
            let confirm_seeds =
                whole("--confirm-seeds", confirm_seeds, 0, max_seeds)?.map(|n| n as usize);
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
            let s = Scenario::load(&scenario_path)?;
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
                    }
                    if let Some(a) = optimizer {
                        algorithm = a;
                    }
                    override_planner(&mut planner, checker, lmax)?;
                    let options = RunOptions {
                        algorithm,
                        seed: seed.unwrap_or(s.seed),
                        time_limit: time_limit.or(s.optimizer.time_limit),
                        evaluations: evaluations.or(s.optimizer.evaluations),
                        patience: s.optimizer.patience,
                        checkpoint_interval: checkpoint_interval
                            .unwrap_or(s.optimizer.checkpoint_interval),
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
            let (lock, acquired) = OutputLock::acquire(&out)?;
            if let Some(o) = &acquired.took_over {
                eprintln!(
                    "warning: {}: taking over the lock of pid {} on host {} ({}), which is no longer running",
                    lock.path().display(),
                    o.pid,
                    o.host,
                    o.command
                );
            }
            if !acquired.removed.is_empty() {
                eprintln!(
                    "warning: {}: removed {} temporary file(s) left by a killed run",
                    out.display(),
                    acquired.removed.len()
                );
            }
            let _ = LOCK_PATH.set(lock.path().to_path_buf());
            // Read again under the lock: the state the last run left.
            let checkpoint = match &resume {
                Some(dir) => Some(Runner::read_checkpoint(dir)?),
                None => None,
            };
            let (planner, options) = settings(&checkpoint)?;
            let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
            {
                let stop = stop.clone();
                // A second Ctrl-C while results are written ends the process at once (and
                // removes the lock file; the operating system releases the lock itself).
                let _ = ctrlc::set_handler(move || {
                    if stop.swap(true, std::sync::atomic::Ordering::SeqCst) {
                        if let Some(p) = LOCK_PATH.get() {
                            let _ = std::fs::remove_file(p);
                        }
                        std::process::exit(130);
                    }
                });
            }
            let runner = Runner::new(&s, &scenario_path, planner.clone(), options.clone(), &out);
            let mut observer = progress::Bar::new(&options, quiet);
            let summary = runner.run(checkpoint, &stop, &mut observer)?;
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
                "{}: {} + {} (L_max {:.4}), seed {}: R = {:.3} ({robust}), cost {:.4}, {} links and {} joints kept, total length {:.3} m; {} evaluations in {:.1} s ({})",
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
                summary.elapsed_s,
                summary.stopped
            );
            drop(lock);
        }
        Command::Experiment {
            preset: p,
            runs,
            time_limit,
            seed,
            out,
        } => {
            use kinsynth::optimize::experiment::{
                median, methods, run_experiment, ExperimentSpec, Shard,
            };
            let spec = ExperimentSpec {
                preset: p,
                runs,
                time_limit,
                evaluations: None,
                seed,
            };
            let records =
                run_experiment(&spec, Shard::WHOLE, &out, &mut |line| eprintln!("{line}"))?;
            say!(
                "{} runs of {} s written to {}",
                records.len(),
                time_limit,
                out.display()
            );
            for (k, m) in methods(p).iter().enumerate() {
                let mine: Vec<_> = records.iter().filter(|r| r.method == k).collect();
                let times: Vec<f64> = mine.iter().filter_map(|r| r.time_to_full_reach()).collect();
                let reached = times.len();
                let med = |f: fn(&kinsynth::optimize::RunSummary) -> f64| {
                    median(mine.iter().map(|r| f(&r.summary)).collect()).unwrap_or(f64::NAN)
                };
                say!(
                    "  {:<32} R = 1 in {reached}/{} runs, median time to R = 1: {}; median final R {:.2}, links {:.1}, joints {:.1}",
                    m.label,
                    mine.len(),
                    if reached * 2 > mine.len() {
                        // The median over all runs exists when more than half reached R = 1
                        // (the others count as later than the budget).
                        let mut all: Vec<f64> = times.clone();
                        all.extend(std::iter::repeat_n(f64::INFINITY, mine.len() - reached));
                        format!("{:.2} s", median(all).unwrap_or(f64::NAN))
                    } else {
                        format!("> {time_limit} s")
                    },
                    med(|s| s.reachability),
                    med(|s| s.links_kept as f64),
                    med(|s| s.joints_kept as f64),
                );
            }
        }
        Command::Reach {
            file,
            design,
            checker,
            lmax,
            seed,
            seeds,
            json,
            urdf,
        } => {
            use rayon::prelude::*;
            let s = Scenario::load(&file)?;
            let max_seeds = kinsynth::optimize::runner::MAX_SEEDS as u64;
            let seeds = whole("--seeds", seeds, 1, max_seeds)?;
            // A best.json without --seed or --seeds replays the evaluation that produced it.
            let replay = match (&design, seed, seeds) {
                (Some(p), None, None) => kinsynth::optimize::runner::Replay::from_best(p)?,
                _ => None,
            };
            let (chain, urdf_names, body) = match &urdf.urdf {
                Some(p) => {
                    let options = kinsynth::import::ImportOptions {
                        body: urdf.body,
                        packages: urdf.package.clone(),
                        srdf: urdf.srdf.clone(),
                        self_collision: s.planner.self_collision.clone(),
                    };
                    let r = kinsynth::import::load_robot(
                        p,
                        urdf.base_frame.as_deref(),
                        urdf.tip_frame.as_deref(),
                        urdf.radius,
                        s.space.template().colliders_per_link,
                        &options,
                    )?;
                    if let Some(note) = &r.note {
                        eprintln!("note: {}: {note}", p.display());
                    }
                    let body = std::sync::Arc::new(r.body);
                    (r.urdf.chain, Some(r.urdf.joint_names), Some(body))
                }
                None => match &design {
                    Some(p) => (kinsynth::Design::load(p)?.chain(), None, None),
                    None => (s.space.largest().chain(), None, None),
                },
            };
            let mut planner = replay
                .as_ref()
                .map_or_else(|| s.planner.clone(), |r| r.planner.clone());
            override_planner(&mut planner, checker, lmax)?;
            let (first_seed, stream) = match &replay {
                Some(r) => {
                    say!(
                        "replaying the evaluation that produced {}: planner seed {}, stream {}",
                        design
                            .as_ref()
                            .map_or(String::new(), |p| p.display().to_string()),
                        r.seed,
                        r.stream
                    );
                    (r.seed, r.stream)
                }
                None => (seed.unwrap_or(s.seed), 0),
            };
            let n = seeds.unwrap_or(1);
            let scene = std::sync::Arc::new(kinsynth::collision::CollisionScene::new(&s.workspace));
            let start = std::time::Instant::now();
            let mut reports: Vec<kinsynth::planning::ReachReport> = (0..n)
                .into_par_iter()
                .map(|k| {
                    let seed = first_seed.wrapping_add(k);
                    match &body {
                        Some(body) => kinsynth::planning::reach::reachability_of(
                            &chain,
                            body.clone(),
                            &scene,
                            &s.workspace.tasks,
                            &planner,
                            seed,
                            stream,
                        ),
                        None => kinsynth::planning::reachability(
                            &chain,
                            &scene,
                            &s.workspace.tasks,
                            &planner,
                            seed,
                            stream,
                        ),
                    }
                })
                .collect();
            let elapsed = start.elapsed();
            let spread = (n > 1).then(|| {
                let r: Vec<f64> = reports.iter().map(|r| r.reachability).collect();
                let min = r.iter().copied().fold(f64::INFINITY, f64::min);
                let max = r.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let mean = r.iter().sum::<f64>() / r.len() as f64;
                for (k, rep) in reports.iter().enumerate() {
                    say!(
                        "seed {}: R = {:.3} ({} of {} tasks)",
                        first_seed.wrapping_add(k as u64),
                        rep.reachability,
                        rep.reached(),
                        rep.targets.len()
                    );
                }
                say!(
                    "R over {n} seeds ({}–{}): min {min:.3}, mean {mean:.3}, max {max:.3}",
                    first_seed,
                    first_seed.wrapping_add(n - 1)
                );
                serde_json::json!({
                    "seeds": (0..n).map(|k| first_seed.wrapping_add(k)).collect::<Vec<_>>(),
                    "reachability": r,
                    "min": min,
                    "mean": mean,
                    "max": max,
                })
            });
            let mut report = reports.swap_remove(0);
            if let Some(names) = &urdf_names {
                kinsynth::import::urdf::rename_joints(&mut report, names);
            }
            say!(
                "R = {:.3} ({} of {} tasks) with {} at L_max {:.4}, seed {first_seed}{}: {} iterations, {} nodes, {} edge checks, {:.1} ms",
                report.reachability,
                report.reached(),
                report.targets.len(),
                report.checker,
                report.l_max,
                if stream == 0 { String::new() } else { format!(" stream {stream}") },
                report.iterations,
                report.nodes,
                report.edge_checks,
                elapsed.as_secs_f64() * 1e3
            );
            if let Some(why) = &report.home_blocked {
                say!("  {why}");
            }
            for t in &report.targets {
                say!(
                    "  task {:>3} {:<11} error {:.4} m  path {}",
                    t.index,
                    if t.reached { "reached" } else { "not reached" },
                    t.error,
                    t.path
                        .as_ref()
                        .map_or("-".to_string(), |p| format!("{} nodes", p.points.len()))
                );
            }
            if let Some(path) = json {
                let mut v = serde_json::to_value(&report).expect("a report serialises");
                v["stream"] = stream.into();
                if let Some(spread) = spread {
                    v["spread"] = spread;
                }
                let text = serde_json::to_string_pretty(&v).expect("a report serialises");
                kinsynth::io::write_atomic(&path, text.as_bytes())?;
            }
            if let Some(dir) = &urdf.trajectories {
                let files = kinsynth::export::trajectory::write_trajectories(&report, dir)?;
                say!(
                    "wrote {} trajectory files to {}",
                    files.len(),
                    dir.display()
                );
            }
        }
        Command::Urdf {
            design,
            output,
            scenario,
        } => {
            let d = kinsynth::Design::load(&design)?;
            let config = match &scenario {
                Some(p) => Scenario::load(p)?.planner.self_collision,
                None => kinsynth::collision::SelfCollisionConfig::default(),
            };
            let srdf = output.with_extension("srdf");
            kinsynth::export::write_urdf(&d, &output)?;
            kinsynth::export::write_srdf(&d, &config, &srdf)?;
            say!(
                "wrote {} ({} links, {} joints) and {}",
                output.display(),
                d.links.len(),
                d.joints_kept(),
                srdf.display()
            );
        }
        Command::Edges {
            file,
            lmax,
            count,
            seed,
            substeps,
        } => {
            use kinsynth::collision::{make_checker, oracle, CheckerKind, CollisionScene};
            use std::f64::consts::PI;
            let s = Scenario::load(&file)?;
            let chain = s.space.largest().chain();
            let body =
                kinsynth::collision::RobotBody::new(&chain, Vec::new(), &s.planner.self_collision);
            let scene = std::sync::Arc::new(CollisionScene::new(&s.workspace));
            let lmax = if lmax.is_empty() {
                vec![PI / 40.0, PI / 8.0, PI / 4.0]
            } else {
                lmax
            };
            say!(
                "{}: largest design, {} edges per L_max, oracle {} sub-steps, body model {}, {} self pairs",
                file.display(),
                count,
                substeps,
                s.planner.body.name(),
                body.self_pairs().len()
            );
            say!(
                "{:>8} {:>10} {:>8} {:>12} {:>14} {:>9} {:>8}",
                "L_max",
                "checker",
                "blocked",
                "false-free",
                "false-blocked",
                "µs/edge",
                "FK/edge"
            );
            for l in lmax {
                let edges =
                    oracle::sample_edges(&scene, &chain, &body, l, s.planner.lambda, count, seed);
                let verdicts: Vec<_> = edges
                    .iter()
                    .map(|(a, b)| oracle::judge_edge(&scene, &chain, &body, a, b, substeps))
                    .collect();
                for kind in CheckerKind::ALL {
                    let checker = make_checker(kind, scene.clone(), s.planner.body);
                    let r = oracle::agreement(checker.as_ref(), &chain, &body, &edges, &verdicts);
                    say!(
                        "{:>8.4} {:>10} {:>8} {:>5} ({:>4.1}%) {:>6} ({:>4.1}%) {:>9.2} {:>8.1}",
                        l,
                        r.checker,
                        r.blocked,
                        r.false_free,
                        100.0 * r.false_free_rate(),
                        r.false_blocked,
                        100.0 * r.false_blocked_rate(),
                        1e6 * r.seconds_per_edge,
                        r.fk_per_edge
                    );
                }
            }
        }
    }
    Ok(())
}

mod progress {
    //! The progress bar of `kinsynth optimize` (indicatif, on stderr; hidden when stderr is
    //! not a terminal or with `--quiet`).
    use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
    use kinsynth::optimize::runner::{HistoryRow, Observer, RunOptions};

    pub struct Bar {
        bar: ProgressBar,
        by_evaluations: bool,
    }

    impl Bar {
        pub fn new(options: &RunOptions, quiet: bool) -> Self {
            let (len, by_evaluations) = match (options.evaluations, options.time_limit) {
                (Some(n), _) => (n, true),
                (None, Some(t)) => ((t * 10.0) as u64, false),
                (None, None) => (0, false),
            };
            let bar = ProgressBar::new(len);
            if quiet {
                bar.set_draw_target(ProgressDrawTarget::hidden());
            }
            bar.set_style(
                ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {percent:>3}% {msg}")
                    .expect("valid template")
                    .progress_chars("=> "),
            );
            Bar {
                bar,
                by_evaluations,
            }
        }
    }

    impl Observer for Bar {
        fn generation(&mut self, row: &HistoryRow) {
            let rate = if row.elapsed_s > 0.0 {
                row.evaluations as f64 / row.elapsed_s
            } else {
                0.0
            };
            self.bar.set_position(if self.by_evaluations {
                row.evaluations
            } else {
                (row.elapsed_s * 10.0) as u64
            });
            self.bar.set_message(format!(
                "{} evals ({rate:.0}/s)  best cost {:.4}  best R {:.2}",
                row.evaluations, row.best_cost, row.best_reachability
            ));
        }
        fn finish(&mut self) {
            self.bar.finish_and_clear();
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
