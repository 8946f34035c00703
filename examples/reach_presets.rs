//! Measures how many tasks the planner reaches on generated preset scenarios, and how long it
//! takes.
//!
//! For each preset seed (default 1–10) the scenario is generated in memory and
//! `kinsynth::planning::reachability` runs with several planner seeds (default 1–5) on one
//! design of the scenario's space (default the largest), with the scenario's planner settings
//! and the chosen checker (default `certified`). The runs are sequential, so the times are the
//! single-thread cost of the planner. Prints a line per preset (mean tasks reached, the count
//! for each planner seed, mean iterations and tree nodes, time), then the overall mean and the
//! number of node and edge checks (a measure of the work that does not depend on the machine) and
//! the total wall and CPU time.
//!
//! ```sh
//! cargo run --release --example reach_presets -- [--checker certified|segment|discrete|ccd]
//!     [--design largest|middle|smallest|random] [--iterations N] [--postures N]
//!     [--budget-growth N] [--presets A-B] [--seeds A-B] [--preset paper-2d|paper-3d]
//!     [--repeat N] [--aimed-steering] [--ik-clamp] [--verbose]
//! ```
//!
//! `--design middle` decodes the middle of every variable's bounds, `smallest` their lower
//! bounds, `random` a design drawn uniformly from the bounds for each preset and planner seed
//! (as in an optimiser's first generation). `--iterations`, `--postures` and `--budget-growth`
//! override `planner.max_iterations`, `planner.postures` and `planner.budget_growth`.
//! `--repeat N` runs everything N times and reports the smallest time of each preset (the
//! results are the same every time), which is steadier on a busy machine. `--aimed-steering`
//! turns on `planner.aimed_steering`; `--ik-clamp` turns off `planner.ik_hold_limits` (the
//! inverse kinematics then clamps its steps into the ranges, as the paper's planner does).
//! `--verbose` adds a line per unreached task with the tree's closest approach.

use kinsynth::collision::{CheckerKind, CollisionScene};
use kinsynth::planning::reachability;
use kinsynth::scenario::preset::{generate, Preset};
use kinsynth::{Design, Scenario};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::ops::RangeInclusive;
use std::sync::Arc;
use std::time::Instant;

/// CPU time of the calling thread in seconds, from `/proc/thread-self/schedstat` (Linux); `None`
/// elsewhere.
fn thread_cpu() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// Parses `A-B` (inclusive) or a single `A`.
fn range(s: &str) -> RangeInclusive<u64> {
    let (a, b) = s.split_once('-').unwrap_or((s, s));
    let a: u64 = a
        .parse()
        .unwrap_or_else(|_| die(format!("{s:?} is not a range A-B of integers")));
    let b: u64 = b
        .parse()
        .unwrap_or_else(|_| die(format!("{s:?} is not a range A-B of integers")));
    a..=b
}

/// The design named `which` of scenario `s` (preset seed `preset`) for planner seed `seed`.
fn design(s: &Scenario, which: &str, preset: u64, seed: u64) -> Design {
    let (lower, upper) = (s.space.lower(), s.space.upper());
    match which {
        "largest" => s.space.largest(),
        "middle" => {
            let x: Vec<f64> = lower
                .iter()
                .zip(&upper)
                .map(|(a, b)| 0.5 * (a + b))
                .collect();
            s.space.decode(&x)
        }
        "smallest" => s.space.decode(&lower),
        "random" => {
            let mut rng = ChaCha8Rng::seed_from_u64(preset.wrapping_mul(1000).wrapping_add(seed));
            let x: Vec<f64> = lower
                .iter()
                .zip(&upper)
                .map(|(&a, &b)| if b > a { rng.random_range(a..=b) } else { a })
                .collect();
            s.space.decode(&x)
        }
        other => die(format!(
            "unknown design {other:?} (largest, middle, smallest or random)"
        )),
    }
}

/// Planner settings that replace the scenario's.
struct Settings {
    checker: CheckerKind,
    iterations: Option<usize>,
    postures: Option<usize>,
    budget_growth: Option<usize>,
    /// `planner.aimed_steering` on.
    aimed: bool,
    /// `planner.ik_hold_limits` off.
    clamp: bool,
}

/// What the planner seeds gave on one preset.
struct PresetRuns {
    tasks: usize,
    reached: Vec<usize>,
    iterations: usize,
    nodes: usize,
    checks: u64,
    wall: f64,
    cpu: f64,
}

/// Plans on preset `p` for every planner seed.
fn run_preset(
    preset: Preset,
    p: u64,
    which: &str,
    settings: &Settings,
    seeds: &RangeInclusive<u64>,
    verbose: bool,
) -> PresetRuns {
    let s = Scenario::from_spec(&generate(preset, p)).expect("a valid preset");
    let scene = Arc::new(CollisionScene::new(&s.workspace));
    let mut config = s.planner.clone();
    config.checker = settings.checker;
    if let Some(n) = settings.iterations {
        config.max_iterations = n;
    }
    if let Some(n) = settings.postures {
        config.postures = n;
    }
    if let Some(n) = settings.budget_growth {
        config.budget_growth = n;
    }
    if settings.aimed {
        config.aimed_steering = true;
    }
    if settings.clamp {
        config.ik_hold_limits = false;
    }
    config.validate().expect("valid planner settings");
    let chains: Vec<_> = seeds
        .clone()
        .map(|seed| design(&s, which, p, seed).chain())
        .collect();
    let mut out = PresetRuns {
        tasks: s.workspace.tasks.len(),
        reached: Vec::new(),
        iterations: 0,
        nodes: 0,
        checks: 0,
        wall: 0.0,
        cpu: 0.0,
    };
    let start = Instant::now();
    let cpu_start = thread_cpu();
    for (seed, chain) in seeds.clone().zip(&chains) {
        let r = reachability(chain, &scene, &s.workspace.tasks, &config, seed, 0);
        out.reached.push(r.reached());
        out.iterations += r.iterations;
        out.nodes += r.nodes;
        out.checks += r.node_checks + r.edge_checks;
        if verbose {
            for t in r.targets.iter().filter(|t| !t.reached) {
                println!(
                    "  preset {p} seed {seed}: task {} at {:?} unreached, closest {:.3} m",
                    t.index, t.point, t.error
                );
            }
        }
    }
    out.wall = start.elapsed().as_secs_f64();
    if let (Some(a), Some(b)) = (cpu_start, thread_cpu()) {
        out.cpu = b - a;
    }
    out
}

/// Ends the program with a one-line error and exit code 2 (a malformed command line).
fn die(message: String) -> ! {
    eprintln!("reach_presets: {message}");
    std::process::exit(2)
}

fn main() {
    let mut settings = Settings {
        checker: CheckerKind::Certified,
        iterations: None,
        postures: None,
        budget_growth: None,
        aimed: false,
        clamp: false,
    };
    let mut which = "largest".to_string();
    let mut presets = 1..=10u64;
    let mut seeds = 1..=5u64;
    let mut preset = Preset::Paper2d;
    let mut repeat = 1usize;
    let mut verbose = false;
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        if flag == "--verbose" {
            verbose = true;
            continue;
        }
        if flag == "--aimed-steering" {
            settings.aimed = true;
            continue;
        }
        if flag == "--ik-clamp" {
            settings.clamp = true;
            continue;
        }
        let value = args
            .next()
            .unwrap_or_else(|| die(format!("{flag} needs a value")));
        let bad = |what: &str| -> ! { die(format!("{flag} {value:?}: expected {what}")) };
        match flag.as_str() {
            "--checker" => {
                settings.checker = value
                    .parse()
                    .unwrap_or_else(|_| bad("segment, certified, ccd or discrete"))
            }
            "--design" => which = value,
            "--iterations" => {
                settings.iterations = Some(value.parse().unwrap_or_else(|_| bad("a count")))
            }
            "--postures" => {
                settings.postures = Some(value.parse().unwrap_or_else(|_| bad("a count")))
            }
            "--budget-growth" => {
                settings.budget_growth = Some(value.parse().unwrap_or_else(|_| bad("a factor")))
            }
            "--presets" => presets = range(&value),
            "--seeds" => seeds = range(&value),
            "--preset" => {
                preset = value
                    .parse()
                    .unwrap_or_else(|_| bad("paper-2d or paper-3d"))
            }
            "--repeat" => {
                repeat = value
                    .parse::<usize>()
                    .unwrap_or_else(|_| bad("a count"))
                    .max(1)
            }
            _ => die(format!("unknown option {flag}")),
        }
    }
    println!(
        "{} presets {}-{}, planner seeds {}-{}, {which} design, checker {}",
        preset.name(),
        presets.start(),
        presets.end(),
        seeds.start(),
        seeds.end(),
        settings.checker
    );
    let (mut reached, mut runs, mut checks) = (0usize, 0usize, 0u64);
    let (mut wall, mut cpu) = (0.0, 0.0);
    for p in presets {
        let mut r = run_preset(preset, p, &which, &settings, &seeds, verbose);
        for _ in 1..repeat {
            let again = run_preset(preset, p, &which, &settings, &seeds, false);
            assert_eq!(
                again.reached, r.reached,
                "the same seeds give the same results"
            );
            r.wall = r.wall.min(again.wall);
            r.cpu = r.cpu.min(again.cpu);
        }
        let n = r.reached.len();
        let sum: usize = r.reached.iter().sum();
        reached += sum;
        runs += n;
        wall += r.wall;
        checks += r.checks;
        cpu += r.cpu;
        println!(
            "preset {p:2}: mean reached {:5.2} of {}  per seed {:?}  mean iterations {:6.0}  mean nodes {:6.0}  time {:.3} s",
            sum as f64 / n as f64,
            r.tasks,
            r.reached,
            r.iterations as f64 / n as f64,
            r.nodes as f64 / n as f64,
            r.wall
        );
    }
    println!(
        "overall: mean reached {:.3} over {runs} runs, {checks} node and edge checks, total time {wall:.3} s (CPU {cpu:.3} s)",
        reached as f64 / runs.max(1) as f64
    );
}
