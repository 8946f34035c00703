//! The cost of the `segment` and `certified` edge checkers, per edge and per reachability run,
//! in a form that can be counted in instructions (which do not depend on the machine).
//!
//! ```sh
//! cargo run --release --example check_cost -- edges [SCENARIO] [REPS]
//! cargo run --release --example check_cost -- reach [SCENARIO] [REPS]
//! ```
//!
//! `edges` checks the same 256 planner-like edges at `L_max` = π/4 (`oracle::sample_edges`,
//! edge seed 7, the largest design, self-collision on) `REPS` times (default 200) with each
//! checker and prints the time and forward-kinematics evaluations per edge; the scenario
//! defaults to the generated paper-3d preset of seed 11 (the one of `benches/edge_check.rs`).
//! `reach` runs the reachability of the largest design with planner seeds 0–9 in turn, `REPS`
//! runs (default 100) per checker at π/4, and prints the mean time per run; the scenario
//! defaults to the bundled paper-3d. Set `CHECKER=segment` or `CHECKER=certified` to run only
//! one, `AIMED_STEERING=on` to plan with `planner.aimed_steering`, and `IK_CLAMP=on` to plan
//! without `planner.ik_hold_limits` (the paper's clamped inverse-kinematics steps), and
//! `SELF_COLLISION=off` to check `edges` without self pairs (what they cost). Under
//! `valgrind --tool=cachegrind`, the instruction count of a run with `REPS` minus that of a run
//! with 0 (the set-up alone), divided by the number of edges or runs, is the instruction cost
//! the README quotes.

use kinsynth::collision::oracle::sample_edges;
use kinsynth::collision::{make_checker, BodyModel, CheckerKind, CollisionScene, Scratch};
use kinsynth::planning::reachability;
use kinsynth::scenario::preset::{generate, Preset};
use kinsynth::Scenario;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mode = args.first().map(String::as_str).unwrap_or("edges");
    let file = args.get(1).filter(|a| a.as_str() != "-");
    let kinds: Vec<CheckerKind> = match std::env::var("CHECKER").as_deref() {
        Ok("segment") => vec![CheckerKind::Segment],
        Ok("certified") => vec![CheckerKind::Certified],
        _ => vec![CheckerKind::Segment, CheckerKind::Certified],
    };
    let reps = |default: usize| -> usize {
        match args.get(2).map(|r| r.parse::<usize>()) {
            None => default,
            Some(Ok(n)) => n,
            Some(Err(_)) => {
                eprintln!("check_cost: REPS {:?} is not a whole number", args[2]);
                std::process::exit(2);
            }
        }
    };
    let aimed = std::env::var("AIMED_STEERING").is_ok_and(|v| v == "on");
    let clamp = std::env::var("IK_CLAMP").is_ok_and(|v| v == "on");
    let self_off = std::env::var("SELF_COLLISION").is_ok_and(|v| v == "off");
    let load = |path: &str| Scenario::load(Path::new(path)).expect("scenario");
    match mode {
        "edges" => {
            let s = match file {
                Some(f) => load(f),
                None => Scenario::from_spec(&generate(Preset::Paper3d, 11)).expect("preset"),
            };
            let reps = reps(200);
            let chain = s.space.largest().chain();
            let scene = Arc::new(CollisionScene::new(&s.workspace));
            let body = kinsynth::collision::RobotBody::of_chain(&chain);
            let l_max = std::f64::consts::FRAC_PI_4;
            let edges = sample_edges(&scene, &chain, &body, l_max, s.planner.lambda, 256, 7);
            for kind in kinds {
                let checker = make_checker(kind, scene.clone(), BodyModel::Capsules);
                let mut scratch = if self_off {
                    let off = kinsynth::collision::SelfCollisionConfig::off();
                    let body = kinsynth::collision::RobotBody::new(&chain, Vec::new(), &off);
                    Scratch::with_body(&chain, Arc::new(body))
                } else {
                    Scratch::new(&chain)
                };
                let start = Instant::now();
                let mut free = 0usize;
                for _ in 0..reps {
                    for (a, b) in &edges {
                        free += usize::from(checker.edge_free(&chain, a, b, &mut scratch));
                    }
                }
                let n = (reps * edges.len()).max(1) as f64;
                println!(
                    "{:>10}: {:.2} µs per edge, {:.2} FK per edge, {:.1} % free",
                    kind.name(),
                    start.elapsed().as_secs_f64() / n * 1e6,
                    scratch.stats.fk as f64 / n,
                    100.0 * free as f64 / n
                );
            }
        }
        "reach" => {
            let s = load(file.map_or("examples/scenarios/paper-3d.toml", |f| f.as_str()));
            let reps = reps(100);
            let chain = s.space.largest().chain();
            let scene = Arc::new(CollisionScene::new(&s.workspace));
            for kind in kinds {
                let mut config = s.planner.clone();
                config.checker = kind;
                config.l_max = std::f64::consts::FRAC_PI_4;
                if aimed {
                    config.aimed_steering = true;
                }
                if clamp {
                    config.ik_hold_limits = false;
                }
                let start = Instant::now();
                let mut reached = 0.0;
                for i in 0..reps {
                    let r = reachability(
                        &chain,
                        &scene,
                        &s.workspace.tasks,
                        &config,
                        i as u64 % 10,
                        0,
                    );
                    reached += r.reachability;
                }
                let n = reps.max(1) as f64;
                println!(
                    "{:>10}: {:.3} ms per reachability run, mean R {:.3}",
                    kind.name(),
                    start.elapsed().as_secs_f64() / n * 1e3,
                    reached / n
                );
            }
        }
        other => {
            eprintln!("check_cost: unknown mode {other:?} (edges or reach)");
            std::process::exit(2);
        }
    }
}
