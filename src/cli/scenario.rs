//! `kinsynth scenario`: writes a random scenario like the paper's experiments.

use kinsynth::scenario::preset::{self, Preset};
use std::path::PathBuf;

/// Write a random scenario like the paper's experiments (paper-2d, paper-3d).
///
/// Writes the file given by -o.
#[derive(clap::Args)]
pub struct Args {
    /// Which preset: paper-2d (§IV-A) or paper-3d (§IV-B).
    #[arg(long)]
    pub preset: Preset,
    /// Seed: the same seed gives the same file.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output file (written atomically).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Give every task an approach cone of 15° about a random direction within 60° of the
    /// outward direction from the base (deterministic in --seed; the points stay the same).
    #[arg(long)]
    pub oriented: bool,
}

/// Runs the command.
pub fn run(args: Args) -> Result<(), kinsynth::Error> {
    let Args {
        preset: p,
        seed,
        output,
        oriented,
    } = args;
    super::output_file(&output)?;
    let mut spec = preset::generate(p, seed);
    if oriented {
        preset::orient(p, &mut spec, seed);
    }
    kinsynth::io::write_atomic(&output, preset::to_toml(p, &spec).as_bytes())?;
    say!(
        "wrote {} ({}, seed {seed}: {} obstacles, {} tasks)",
        output.display(),
        p.name(),
        spec.obstacle.len(),
        spec.task.len()
    );
    Ok(())
}
