//! `kinsynth experiment`: the paper's §IV experiments over random workspaces.

use kinsynth::scenario::preset::Preset;
use std::path::PathBuf;

/// Reproduce the paper's experiments: §IV-A (paper-2d: GA, PSO and ASA with certified at π/4,
/// GA with segment at π/4, against the paper's baseline, ASA + discrete π/40 with the paper's
/// planner, also run with this planner) or §IV-B (paper-3d: GA with certified at π/4), averaged
/// over random workspaces.
///
/// Writes into --out: runs.csv (one row per run), curves.csv and curves.svg (average
/// reachability against time), experiment.json (the settings and the workspaces held, for
/// `kinsynth merge`), and per workspace w: workspace{w}/scenario.toml and, per method k,
/// workspace{w}/method{k}/ with every file `optimize` writes. With --shard K/N only the K-th
/// of N slices of the workspaces (e.g. one task of a Slurm job array).
#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// paper-2d or paper-3d.
    pub preset: Preset,
    /// Number of random workspaces.
    #[arg(long, default_value_t = 10)]
    pub runs: usize,
    /// Seconds per run (runs that converge stop earlier).
    #[arg(long, default_value_t = 60.0)]
    pub time_limit: f64,
    /// Seed of the first workspace (the others follow).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Evaluations per run at most (with a time limit that is not reached, every result but
    /// the times then depends on the seeds only).
    #[arg(long)]
    pub evaluations: Option<f64>,
    /// Run only the K-th (from 1) of N slices of the workspaces; `kinsynth merge` combines
    /// the slices' folders.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the command.
pub fn run(args: Args) -> Result<(), kinsynth::Error> {
    let Args {
        preset: p,
        runs,
        time_limit,
        seed,
        evaluations,
        shard,
        out,
    } = args;
    use kinsynth::optimize::experiment::{run_experiment, ExperimentSpec, Shard};
    let shard = match shard {
        Some(s) => s.parse::<Shard>()?,
        None => Shard::WHOLE,
    };
    let spec = ExperimentSpec {
        preset: p,
        runs,
        time_limit,
        evaluations: super::whole("--evaluations", evaluations, 1, u64::MAX >> 12)?,
        seed,
    };
    spec.validate()?;
    let records = run_experiment(&spec, shard, &out, &mut |line| eprintln!("{line}"))?;
    let cap = spec
        .evaluations
        .map_or(String::new(), |n| format!(" or {n} evaluations"));
    say!(
        "{} runs of at most {} s{cap} (workspaces {:?} of {}, shard {shard}) written to {}",
        records.len(),
        time_limit,
        shard.workspaces(runs),
        runs,
        out.display()
    );
    print_table(p, &records, time_limit);
    Ok(())
}

/// Prints a line per method: how often and how fast it reached R = 1, and its median design.
pub fn print_table(
    p: Preset,
    records: &[kinsynth::optimize::experiment::RunRecord],
    time_limit: f64,
) {
    use kinsynth::optimize::experiment::{median, methods};
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
