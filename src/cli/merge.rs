//! `kinsynth merge`: combines the folders of an experiment's slices (`experiment --shard K/N`).

use std::path::PathBuf;

/// Combine the slices of an experiment (`kinsynth experiment … --shard K/N`, e.g. the tasks of
/// a Slurm job array) into the tables one unsharded run writes.
///
/// Writes into --out: runs.csv, curves.csv and curves.svg (from the runs of every slice, as
/// `experiment` writes them) and experiment.json. The slices' folders are only read: every
/// workspace must be in exactly one of them, all of the same experiment.
#[derive(clap::Args)]
pub struct Args {
    /// The slices' output folders (each holds an experiment.json).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the command.
pub fn run(args: Args) -> Result<(), kinsynth::Error> {
    let records = kinsynth::optimize::experiment::merge(&args.dirs, &args.out)?;
    let spec = kinsynth::optimize::experiment::read_manifest(&args.out)?.spec;
    say!(
        "{} runs from {} folder(s) merged into {}",
        records.len(),
        args.dirs.len(),
        args.out.display()
    );
    super::experiment::print_table(spec.preset, &records, spec.time_limit);
    Ok(())
}
