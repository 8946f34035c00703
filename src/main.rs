//! The `kinsynth` command line: a thin shell over the library.

use clap::{Parser, Subcommand};
use kinsynth::scenario::preset::{self, Preset};
use kinsynth::Scenario;
use std::path::PathBuf;
use std::process::ExitCode;

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

fn run(cli: Cli) -> Result<(), kinsynth::Error> {
    match cli.command {
        Command::Scenario {
            preset: p,
            seed,
            output,
        } => {
            let spec = preset::generate(p, seed);
            kinsynth::io::write_atomic(&output, preset::to_toml(p, &spec).as_bytes())?;
            println!(
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
            println!("{}: ok", file.display());
            println!("  name            {}", s.name);
            println!(
                "  links           {} (largest design: {} joints, reach {:.3} m)",
                largest.links.len(),
                chain.dof(),
                largest.total_length()
            );
            println!("  free variables  {}", s.space.dim());
            println!("  obstacles       {}", s.workspace.obstacles.len());
            println!("  tasks           {}", s.workspace.tasks.len());
            println!("  clearance       {} m", s.workspace.clearance);
            println!(
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
        Command::Reach {
            file,
            design,
            checker,
            lmax,
            seed,
            json,
        } => {
            let s = Scenario::load(&file)?;
            let design = match design {
                Some(p) => kinsynth::Design::load(&p)?,
                None => s.space.largest(),
            };
            let mut planner = s.planner.clone();
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
            }
            let seed = seed.unwrap_or(s.seed);
            let chain = design.chain();
            let scene = std::sync::Arc::new(kinsynth::collision::CollisionScene::new(&s.workspace));
            let start = std::time::Instant::now();
            let report = kinsynth::planning::reachability(
                &chain,
                &scene,
                &s.workspace.tasks,
                &planner,
                seed,
                0,
            );
            let elapsed = start.elapsed();
            println!(
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
                println!("  {why}");
            }
            for t in &report.targets {
                println!(
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
            let scene = std::sync::Arc::new(CollisionScene::new(&s.workspace));
            let lmax = if lmax.is_empty() {
                vec![PI / 40.0, PI / 8.0, PI / 4.0]
            } else {
                lmax
            };
            println!(
                "{}: largest design, {} edges per L_max, oracle {} sub-steps, body model {}",
                file.display(),
                count,
                substeps,
                s.planner.body.name()
            );
            println!(
                "{:>8} {:>10} {:>8} {:>12} {:>14} {:>9} {:>8}",
                "L_max", "checker", "blocked", "false-free", "false-blocked", "µs/edge", "FK/edge"
            );
            for l in lmax {
                let edges = oracle::sample_edges(&scene, &chain, l, s.planner.lambda, count, seed);
                let verdicts: Vec<_> = edges
                    .iter()
                    .map(|(a, b)| oracle::judge_edge(&scene, &chain, a, b, substeps))
                    .collect();
                for kind in CheckerKind::ALL {
                    let checker = make_checker(kind, scene.clone(), s.planner.body);
                    let r = oracle::agreement(checker.as_ref(), &chain, &edges, &verdicts);
                    println!(
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
