//! `kinsynth edges`: the edge checkers against the dense-sampling oracle.

use kinsynth::Scenario;
use std::path::PathBuf;

/// Compare the four edge checkers with the dense-sampling oracle on random edges.
///
/// Prints a table; writes no files.
#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The scenario file (TOML).
    pub file: PathBuf,
    /// Step bounds L_max to test (comma-separated). Default: π/40, π/8, π/4.
    #[arg(long, value_delimiter = ',')]
    pub lmax: Vec<f64>,
    /// Edges per L_max.
    #[arg(long, default_value_t = 2000)]
    pub count: usize,
    /// Seed of the random edges.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Oracle sub-steps per edge.
    #[arg(long, default_value_t = kinsynth::collision::oracle::ORACLE_SUBSTEPS)]
    pub substeps: usize,
}

/// Most `L_max` values in one run.
pub const MAX_LMAX_VALUES: usize = 16;
/// Most edges per `L_max` (`--count`): they are all held in memory with the oracle's verdicts.
pub const MAX_EDGES: usize = 100_000;
/// Most oracle sub-steps per edge (`--substeps`).
pub const MAX_SUBSTEPS: usize = 100_000;
/// Most edges over all `L_max` values (`--count` times their number): `ccd` takes up to about
/// 15 ms per edge, so this stands for about 25 minutes.
pub const MAX_EDGES_TOTAL: usize = 100_000;
/// Most oracle sub-steps over all edges (`--count` times `--substeps` times the `L_max`
/// values), about 3 µs each: about 10 minutes.
pub const MAX_SUBSTEPS_TOTAL: usize = 200_000_000;

/// Runs the command.
pub fn run(args: Args) -> Result<(), kinsynth::Error> {
    let Args {
        file,
        lmax,
        count,
        seed,
        substeps,
    } = args;
    use kinsynth::collision::{make_checker, oracle, CheckerKind, CollisionScene};
    use std::f64::consts::PI;
    if lmax.len() > MAX_LMAX_VALUES {
        return Err(kinsynth::Error::invalid(
            "--lmax",
            format!("{} values", lmax.len()),
            format!("at most {MAX_LMAX_VALUES} values"),
        ));
    }
    for &l in &lmax {
        super::checked_lmax(l)?;
    }
    for (flag, v, max) in [
        ("--count", count, MAX_EDGES),
        ("--substeps", substeps, MAX_SUBSTEPS),
    ] {
        if !(1..=max).contains(&v) {
            return Err(kinsynth::Error::invalid(
                flag,
                v,
                format!("must be a whole number from 1 to {max}"),
            ));
        }
    }
    let values = if lmax.is_empty() { 3 } else { lmax.len() }; // no --lmax: three values
    let edges = count * values;
    if edges > MAX_EDGES_TOTAL {
        return Err(kinsynth::Error::invalid(
            "--count",
            count,
            format!(
                "{edges} edges over {values} L_max values, more than the limit of {MAX_EDGES_TOTAL} in one run"
            ),
        ));
    }
    if edges * substeps > MAX_SUBSTEPS_TOTAL {
        return Err(kinsynth::Error::invalid(
            "--substeps",
            substeps,
            format!(
                "{} oracle sub-steps over {edges} edges, more than the limit of {MAX_SUBSTEPS_TOTAL} in one run",
                edges * substeps
            ),
        ));
    }
    let s = Scenario::load(&file)?;
    let chain = s.space.largest().chain();
    let body = kinsynth::collision::RobotBody::capsules(&chain, &s.planner.self_collision);
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
        let edges = oracle::sample_edges(&scene, &chain, &body, l, s.planner.lambda, count, seed);
        if edges.is_empty() {
            return Err(kinsynth::Error::invalid(
                "robot",
                "its largest design",
                format!(
                    "no collision-free start in {} attempts (every sampled configuration \
                     collides with an obstacle or with itself): no edge to compare",
                    oracle::start_attempts(&body, count)
                ),
            )
            .in_file(&file));
        }
        if edges.len() < count {
            say!(
                "{:>8} only {} of {count} edges: collision-free starts are rare",
                label(l),
                edges.len()
            );
        }
        let verdicts: Vec<_> = edges
            .iter()
            .map(|(a, b)| oracle::judge_edge(&scene, &chain, &body, a, b, substeps))
            .collect();
        for kind in CheckerKind::ALL {
            let checker = make_checker(kind, scene.clone(), s.planner.body);
            let r = oracle::agreement(checker.as_ref(), &chain, &body, &edges, &verdicts);
            say!(
                "{:>8} {:>10} {:>8} {:>5} ({:>4.1}%) {:>6} ({:>4.1}%) {:>9.2} {:>8.1}",
                label(l),
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
    Ok(())
}

/// `L_max` for the table's first column: four decimals, or in exponent form where those would
/// not fit the column (below 0.001 or from 10,000 on).
fn label(l: f64) -> String {
    if (1e-3..1e4).contains(&l) {
        format!("{l:.4}")
    } else {
        format!("{l:.2e}")
    }
}
