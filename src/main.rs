//! The `kinsynth` command line: a thin shell over the library.

use clap::{Parser, Subcommand};
use kinsynth::scenario::preset::{self, Preset};
use kinsynth::Scenario;
use std::path::PathBuf;
use std::process::ExitCode;

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
    Check {
        /// The scenario file (TOML).
        file: PathBuf,
    },
    /// Optimise a design for a scenario (the main job): GA, PSO or ASA over the design space,
    /// writing best.json, history.csv, reach.json and convergence.svg into --out.
    Optimize {
        /// The scenario file (TOML). Not needed with --resume.
        file: Option<PathBuf>,
        /// Optimiser. Default: the scenario's.
        #[arg(long)]
        optimizer: Option<kinsynth::scenario::Algorithm>,
        /// Edge checker. Default: the scenario's.
        #[arg(long)]
        checker: Option<kinsynth::collision::CheckerKind>,
        /// Step bound L_max. Default: the scenario's.
        #[arg(long)]
        lmax: Option<f64>,
        /// The paper's baseline: ASA with node-only (discrete) checks at L_max = π/40.
        #[arg(long, conflicts_with_all = ["optimizer", "checker", "lmax"])]
        baseline: bool,
        /// Seed. Default: the scenario's.
        #[arg(long)]
        seed: Option<u64>,
        /// Wall-clock budget in seconds. Default: the scenario's.
        #[arg(long)]
        time_limit: Option<f64>,
        /// Budget in objective evaluations. Default: the scenario's.
        #[arg(long)]
        evaluations: Option<u64>,
        /// Seconds between checkpoints. Default: the scenario's.
        #[arg(long)]
        checkpoint_interval: Option<f64>,
        /// Output directory.
        #[arg(long, required_unless_present = "resume")]
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
        /// Seed of the planner. Default: the scenario's.
        #[arg(long)]
        seed: Option<u64>,
        /// Write the report as JSON to this file (atomically).
        #[arg(long)]
        json: Option<PathBuf>,
        #[command(flatten)]
        urdf: UrdfReach,
    },
    /// Export a design (design JSON or best.json) as a URDF robot.
    Urdf {
        /// The design JSON, or an optimiser's best.json.
        design: PathBuf,
        /// Output URDF file (written atomically); the robot is named after its stem.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Compare the four edge checkers with the dense-sampling oracle on random edges.
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
            out,
            resume,
            quiet,
        } => {
            use kinsynth::optimize::runner::{Checkpoint, RunOptions, Runner};
            let (scenario_path, out, checkpoint): (PathBuf, PathBuf, Option<Checkpoint>) =
                match resume {
                    Some(dir) => {
                        let c = Runner::read_checkpoint(&dir)?;
                        (c.scenario.clone(), dir, Some(c))
                    }
                    None => {
                        let Some(f) = file else {
                            return Err(kinsynth::Error::invalid(
                                "SCENARIO",
                                "missing",
                                "give a scenario file (or --resume DIR)",
                            ));
                        };
                        (f, out.expect("clap requires --out without --resume"), None)
                    }
                };
            let s = Scenario::load(&scenario_path)?;
            let (planner, options) = match &checkpoint {
                Some(c) => (c.planner.clone(), c.options.clone()),
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
                    };
                    if options.time_limit.is_none() && options.evaluations.is_none() {
                        return Err(kinsynth::Error::invalid(
                            "budget",
                            "none",
                            "give --time-limit or --evaluations (or set them in [optimizer])",
                        ));
                    }
                    (planner, options)
                }
            };
            let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
            {
                let stop = stop.clone();
                // A second Ctrl-C while results are written ends the process at once.
                let _ = ctrlc::set_handler(move || {
                    if stop.swap(true, std::sync::atomic::Ordering::SeqCst) {
                        std::process::exit(130);
                    }
                });
            }
            let runner = Runner::new(&s, &scenario_path, planner.clone(), options.clone(), &out);
            let mut observer = progress::Bar::new(&options, quiet);
            let summary = runner.run(checkpoint, &stop, &mut observer)?;
            say!(
                "{}: {} + {} (L_max {:.4}), seed {}: R = {:.3}, cost {:.4}, {} links and {} joints kept, total length {:.3} m; {} evaluations in {:.1} s ({})",
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
        }
        Command::Experiment {
            preset: p,
            runs,
            time_limit,
            seed,
            out,
        } => {
            use kinsynth::optimize::experiment::{median, methods, run_experiment};
            if !(time_limit.is_finite() && time_limit > 0.0) {
                return Err(kinsynth::Error::invalid(
                    "--time-limit",
                    time_limit,
                    "must be positive and finite",
                ));
            }
            let records = run_experiment(p, runs, time_limit, seed, &out, &mut |line| {
                eprintln!("{line}")
            })?;
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
            json,
            urdf,
        } => {
            let s = Scenario::load(&file)?;
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
                None => match design {
                    Some(p) => (kinsynth::Design::load(&p)?.chain(), None, None),
                    None => (s.space.largest().chain(), None, None),
                },
            };
            let mut planner = s.planner.clone();
            override_planner(&mut planner, checker, lmax)?;
            let seed = seed.unwrap_or(s.seed);
            let scene = std::sync::Arc::new(kinsynth::collision::CollisionScene::new(&s.workspace));
            let start = std::time::Instant::now();
            let mut report = match body {
                Some(body) => kinsynth::planning::reach::reachability_of(
                    &chain,
                    body,
                    &scene,
                    &s.workspace.tasks,
                    &planner,
                    seed,
                    0,
                ),
                None => kinsynth::planning::reachability(
                    &chain,
                    &scene,
                    &s.workspace.tasks,
                    &planner,
                    seed,
                    0,
                ),
            };
            let elapsed = start.elapsed();
            if let Some(names) = &urdf_names {
                kinsynth::import::urdf::rename_joints(&mut report, names);
            }
            say!(
                "R = {:.3} ({} of {} tasks) with {} at L_max {:.4}, seed {seed}: {} iterations, {} nodes, {} edge checks, {:.1} ms",
                report.reachability,
                report.reached(),
                report.targets.len(),
                report.checker,
                report.l_max,
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
                kinsynth::io::write_atomic(&path, report.to_json().as_bytes())?;
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
        Command::Urdf { design, output } => {
            let d = kinsynth::Design::load(&design)?;
            kinsynth::export::write_urdf(&d, &output)?;
            say!(
                "wrote {} ({} links, {} joints)",
                output.display(),
                d.links.len(),
                d.joints_kept()
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
