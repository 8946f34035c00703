//! The cost of the `segment` and `certified` edge checkers, per edge and per reachability run,
//! in a form that can be counted in instructions (which do not depend on the machine).
//!
//! ```sh
//! cargo run --release --example check_cost -- edges [SCENARIO] [REPS]
//! cargo run --release --example check_cost -- reach [SCENARIO] [REPS]
//! cargo run --release --example check_cost -- bounds [SCENARIO] [SUBSTEPS]
//! ```
//!
//! `edges` checks the same 256 planner-like edges at `L_max` = π/4 (`oracle::sample_edges`,
//! edge seed 7, the largest design, self-collision on) `REPS` times (default 200) with each
//! checker and prints the time and forward-kinematics evaluations per edge; the scenario
//! defaults to the generated paper-3d preset of seed 11 (the one of `benches/edge_check.rs`).
//! `reach` runs the reachability of the largest design with planner seeds 0–9 in turn, `REPS`
//! runs (default 100) per checker at π/4, and prints the mean time per run and the median over
//! the seeds of each seed's mean time (the issue's "median" figure); the scenario
//! defaults to the bundled paper-3d. Set `CHECKER=segment` or `CHECKER=certified` to run only
//! one, `AIMED_STEERING=on` to plan with `planner.aimed_steering`, and `IK_CLAMP=on` to plan
//! without `planner.ik_hold_limits` (the paper's clamped inverse-kinematics steps), and
//! `SELF_COLLISION=off` to check `edges` without self pairs (what they cost). `bounds` takes
//! the edges of `edges` and compares, per item `certified` first tests on a step (a body
//! against the environment, a self pair), its motion bound with the path the body really
//! travels, measured with `SUBSTEPS` steps (default 400): how loose the bounds are, and how
//! many items and steps the end clearances prove at once with them and would prove with the
//! measured paths. Under
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
                // Seconds and runs per planner seed, for the median over the seeds.
                let mut per_seed = [(0.0, 0usize); 10];
                for i in 0..reps {
                    let t = Instant::now();
                    let r = reachability(
                        &chain,
                        &scene,
                        &s.workspace.tasks,
                        &config,
                        i as u64 % 10,
                        0,
                    );
                    let seed = &mut per_seed[i % 10];
                    seed.0 += t.elapsed().as_secs_f64();
                    seed.1 += 1;
                    reached += r.reachability;
                }
                let n = reps.max(1) as f64;
                let mut means: Vec<f64> = per_seed
                    .iter()
                    .filter(|s| s.1 > 0)
                    .map(|s| s.0 / s.1 as f64 * 1e3)
                    .collect();
                means.sort_by(f64::total_cmp);
                let m = means.len();
                let median = match m {
                    0 => f64::NAN,
                    _ if m % 2 == 1 => means[m / 2],
                    _ => 0.5 * (means[m / 2 - 1] + means[m / 2]),
                };
                println!(
                    "{:>10}: {:.3} ms per reachability run (median over the planner seeds {median:.3} ms), mean R {:.3}",
                    kind.name(),
                    start.elapsed().as_secs_f64() / n * 1e3,
                    reached / n
                );
            }
        }
        "bounds" => {
            let s = match file {
                Some(f) => load(f),
                None => Scenario::from_spec(&generate(Preset::Paper3d, 11)).expect("preset"),
            };
            bounds(&s, reps(400));
        }
        other => {
            eprintln!("check_cost: unknown mode {other:?} (edges, reach or bounds)");
            std::process::exit(2);
        }
    }
}

/// `bounds`: per item `certified` first tests on a step (each body against the environment,
/// each checked self pair; [`step_bounds`]), its motion bound against the path length of the
/// moving body's capsule core ends measured with `substeps` steps (relative to the other body's
/// links for a self pair), on the 256 edges of `edges`, and how many items the clearances at
/// the step's two ends prove with that bound and would prove with the measured length.
fn bounds(s: &Scenario, substeps: usize) {
    use kinsynth::collision::edge::certified::step_bounds;
    use kinsynth::collision::oracle::travel;
    let chain = s.space.largest().chain();
    let scene = Arc::new(CollisionScene::new(&s.workspace));
    let body = kinsynth::collision::RobotBody::of_chain(&chain);
    let l_max = std::f64::consts::FRAC_PI_4;
    let edges = sample_edges(&scene, &chain, &body, l_max, s.planner.lambda, 256, 7);
    let (mut fa, mut fb) = (chain.frames(), chain.frames());
    let mut pa = kinsynth::collision::body::Placed::default();
    let mut pb = pa.clone();
    // Per kind (against the environment, self pair): items, the sum of bound / length, items
    // proven by the bound, items the measured length would prove.
    let mut rows = [[0.0f64; 4]; 2];
    // The largest length / bound seen (above 1 would mean a bound that does not hold).
    let mut worst: f64 = 0.0;
    // Steps whose two ends are free, and of them those proven at once by the bounds and those
    // the measured lengths would prove at once.
    let mut steps = [0usize; 3];
    let clearance = |frames: &kinsynth::kinematics::Frames,
                     placed: &kinsynth::collision::body::Placed,
                     b: usize| {
        let ball = body.ball(frames, placed, b);
        body.clearance(&scene, frames, placed, b, &ball, f64::INFINITY, u32::MAX)
            .0
    };
    for (a, b) in &edges {
        chain.fk(a, &mut fa);
        chain.fk(b, &mut fb);
        body.place(&fa, &mut pa);
        body.place(&fb, &mut pb);
        let items = step_bounds(&chain, &body, a, b);
        let length = travel(&chain, &body, a, b, &items, substeps);
        let mut whole = [true; 3];
        for (it, len) in items.iter().zip(length) {
            let Some(len) = len else {
                continue; // a solid: no core to follow
            };
            let (c0, c1) = match it.relative_to {
                None => (clearance(&fa, &pa, it.body), clearance(&fb, &pb, it.body)),
                Some(p) => (
                    body.pair_distance(&fa, &pa, p, it.body),
                    body.pair_distance(&fb, &pb, p, it.body),
                ),
            };
            if c0 <= 0.0 || c1 <= 0.0 {
                whole[0] = false;
                continue; // an end in collision: nothing to prove
            }
            whole[1] &= c0 + c1 > it.bound;
            whole[2] &= c0 + c1 > len;
            let row = &mut rows[usize::from(it.relative_to.is_some())];
            row[0] += 1.0;
            row[1] += it.bound / len.max(1e-12);
            row[2] += f64::from(u8::from(c0 + c1 > it.bound));
            row[3] += f64::from(u8::from(c0 + c1 > len));
            worst = worst.max(len / it.bound);
        }
        if whole[0] {
            steps[0] += 1;
            steps[1] += usize::from(whole[1]);
            steps[2] += usize::from(whole[2]);
        }
    }
    for (name, [n, ratio, by_bound, by_length]) in ["environment", "self pairs"].iter().zip(rows) {
        println!(
            "{name:>12}: {n} items, bound {:.2}× the path length on average; proven at once {:.1} % (with the path length: {:.1} %)",
            ratio / n.max(1.0),
            100.0 * by_bound / n.max(1.0),
            100.0 * by_length / n.max(1.0)
        );
    }
    println!(
        "steps with both ends free: {}; proven at once: {} (with the path lengths: {})",
        steps[0], steps[1], steps[2]
    );
    println!("largest path length / bound: {worst:.4} (at most 1 when the bounds hold)");
}
