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
