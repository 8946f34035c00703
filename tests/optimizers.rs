//! The optimisers on standard test functions, and their determinism.

use kinsynth::optimize::asa::{Asa, AsaParams};
use kinsynth::optimize::ga::{Ga, GaParams};
use kinsynth::optimize::pso::{Pso, PsoParams};
use kinsynth::optimize::testfn::{Rastrigin, Sphere};
use kinsynth::optimize::{Cutoff, Evaluated, Optimizer, Problem, StepContext};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Steps `opt` until `budget` evaluations are spent; returns the best point.
fn drive(opt: &mut dyn Optimizer, problem: &dyn Problem, budget: u64, seed: u64) -> Evaluated {
    let mut evaluations = 0;
    let mut generation = 0;
    while evaluations < budget {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(generation);
        let r = opt.step(StepContext {
            problem,
            rng: &mut rng,
            first_stream: evaluations,
            stride: 1,
            progress: evaluations as f64 / budget as f64,
            cutoff: Cutoff::default(),
        });
        evaluations += r.evaluations;
        generation += 1;
    }
    opt.best().unwrap().clone()
}

fn ga() -> Box<dyn Optimizer> {
    Box::new(Ga::new(GaParams::default(), vec![]))
}
fn pso() -> Box<dyn Optimizer> {
    Box::new(Pso::new(PsoParams::default(), vec![]))
}
fn asa(budget: u64) -> Box<dyn Optimizer> {
    Box::new(Asa::new(
        AsaParams {
            expected_evaluations: budget,
            ..AsaParams::default()
        },
        vec![],
    ))
}

/// Budgets: 20,000 evaluations on the sphere, 40,000 on Rastrigin (8 dimensions, shifted
/// optimum). Tolerances: sphere below 1e-3; Rastrigin below 0.02, i.e. in the global basin
/// (the nearest local minimum costs about 0.995).
const SPHERE_BUDGET: u64 = 20_000;
const RASTRIGIN_BUDGET: u64 = 40_000;

fn check(make: impl Fn(u64) -> Box<dyn Optimizer>, name: &str) {
    for seed in 0..3 {
        let s = drive(
            make(SPHERE_BUDGET).as_mut(),
            &Sphere::new(8),
            SPHERE_BUDGET,
            seed,
        );
        assert!(s.cost < 1e-3, "{name} seed {seed}: sphere {}", s.cost);
        let r = drive(
            make(RASTRIGIN_BUDGET).as_mut(),
            &Rastrigin::new(8),
            RASTRIGIN_BUDGET,
            seed,
        );
        assert!(r.cost < 0.02, "{name} seed {seed}: rastrigin {}", r.cost);
        for (i, x) in r.x.iter().enumerate() {
            let o = kinsynth::optimize::testfn::shift(i);
            assert!(
                (x - o).abs() < 0.05,
                "{name}: coordinate {i} at {x}, optimum {o}"
            );
        }
    }
}

#[test]
fn ga_minimises_sphere_and_rastrigin() {
    check(|_| ga(), "ga");
}

#[test]
fn pso_minimises_sphere_and_rastrigin() {
    check(|_| pso(), "pso");
}

#[test]
fn asa_minimises_sphere_and_rastrigin() {
    check(asa, "asa");
}

#[test]
fn the_classic_gbest_swarm_stalls_on_rastrigin() {
    // Why the comprehensive-learning variant is the default: the gbest swarm collapses onto a
    // local minimum of Rastrigin within the same budget.
    use kinsynth::optimize::pso::Learning;
    let worst = (0..3)
        .map(|seed| {
            let mut p = Pso::new(
                PsoParams {
                    learning: Learning::Global,
                    ..PsoParams::default()
                },
                vec![],
            );
            drive(&mut p, &Rastrigin::new(8), RASTRIGIN_BUDGET, seed).cost
        })
        .fold(0.0, f64::max);
    assert!(worst > 0.5, "{worst}");
}

#[test]
fn design_optimisation_is_the_same_on_one_thread_and_on_two() {
    use kinsynth::optimize::Objective;
    use kinsynth::Scenario;
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios/paper-2d.toml");
    let s = Scenario::load(&path).unwrap();
    let objective = Objective::new(&s, s.planner.clone(), 9);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut opt = Ga::new(
                    GaParams {
                        population: 8,
                        ..GaParams::default()
                    },
                    vec![],
                );
                drive(&mut opt, &objective, 24, 4)
            })
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one, two);
    assert!(one.cost.is_finite());
}

type Make = fn() -> Box<dyn Optimizer>;

/// The three optimisers, ASA re-annealing at every step (so that its later steps include
/// its probes, a second batch).
fn cut_makers() -> [(&'static str, Make); 3] {
    [
        ("ga", ga),
        ("pso", pso),
        ("asa", || {
            Box::new(Asa::new(
                AsaParams {
                    reanneal_interval: 1,
                    ..AsaParams::default()
                },
                vec![],
            ))
        }),
    ]
}

/// Step `generation` of `opt` on `problem`, with `cutoff` (evaluation `j` on stream
/// `100·generation + j`).
fn step_of(
    problem: &dyn Problem,
    opt: &mut dyn Optimizer,
    generation: u64,
    cutoff: Cutoff<'_>,
) -> kinsynth::optimize::StepReport {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    rng.set_stream(generation);
    opt.step(StepContext {
        problem,
        rng: &mut rng,
        first_stream: 100 * generation,
        stride: 1,
        progress: 0.0,
        cutoff,
    })
}

/// A step whose deadline has passed evaluates its first point only and reports the step cut,
/// with that point; the snapshot taken before it is the state to go on from. Each optimiser,
/// at its first step and at a later one (ASA's later steps include its re-annealing probes).
#[test]
fn a_step_past_its_deadline_is_cut_with_the_points_it_evaluated() {
    let problem = Sphere::new(4);
    let makers = cut_makers();
    let step = |opt: &mut dyn Optimizer, generation: u64, cutoff: Cutoff<'_>| {
        step_of(&problem, opt, generation, cutoff)
    };
    let past = Cutoff {
        deadline: Some(std::time::Instant::now()),
        stop: None,
        budget: None,
        may_skip_all: false,
    };
    // A cutoff that allows it cuts a step begun past its deadline before any evaluation.
    for (name, make) in cut_makers() {
        let mut opt = make();
        let none = Cutoff {
            may_skip_all: true,
            ..past
        };
        let r = step(opt.as_mut(), 0, none);
        let cut = r.cut.unwrap_or_else(|| panic!("{name}: not cut"));
        assert!(cut.evaluated.is_empty() && r.evaluations == 0, "{name}");
    }
    for (name, make) in makers {
        let mut opt = make();
        for generation in 0..3u64 {
            let before = opt.snapshot();
            let saved = before.save();
            let r = step(opt.as_mut(), generation, past);
            let cut = r
                .cut
                .unwrap_or_else(|| panic!("{name}: step {generation} not cut"));
            assert!(!cut.evaluated.is_empty(), "{name}");
            assert_eq!(r.evaluations, cut.evaluated.len() as u64, "{name}");
            assert!(cut.evaluated.iter().all(|e| e.cost.is_finite()), "{name}");
            // Restored, the state is the one before the step; a whole step then goes on.
            opt = before;
            assert_eq!(opt.save(), saved, "{name}");
            let r = step(opt.as_mut(), generation, Cutoff::default());
            assert!(r.cut.is_none(), "{name}");
            // The cut step's first point is the whole step's first point.
            assert!(r.evaluations >= cut.evaluated.len() as u64, "{name}");
        }
    }
}

/// A step given fewer evaluations than it needs (what is left of a run's evaluation budget)
/// is cut after exactly that many, the first points of the step in order, on every run; none
/// left cuts it before any; enough left leaves it whole.
#[test]
fn a_step_past_its_evaluation_budget_is_cut_at_it() {
    let problem = Sphere::new(3);
    let makers = cut_makers();
    let step = |opt: &mut dyn Optimizer, generation: u64, budget: Option<u64>| {
        let cutoff = Cutoff {
            budget,
            ..Cutoff::default()
        };
        step_of(&problem, opt, generation, cutoff)
    };
    for (name, make) in makers {
        let mut opt = make();
        for generation in 0..4u64 {
            let before = opt.snapshot();
            let whole = step(before.snapshot().as_mut(), generation, None);
            assert!(whole.cut.is_none(), "{name}");
            let need = whole.evaluations;
            assert!(need >= 2, "{name}: a step of {need} evaluations");
            for budget in [0, 1, need - 1] {
                let r = step(before.snapshot().as_mut(), generation, Some(budget));
                let cut = r
                    .cut
                    .unwrap_or_else(|| panic!("{name}: step {generation} not cut at {budget}"));
                assert_eq!(r.evaluations, budget, "{name}");
                assert_eq!(cut.evaluated.len() as u64, budget, "{name}");
                let again = step(before.snapshot().as_mut(), generation, Some(budget));
                assert_eq!(again.cut, Some(cut.clone()), "{name}: not the same points");
                let streams: Vec<u64> = cut.evaluated.iter().map(|e| e.stream).collect();
                let first: Vec<u64> = (0..budget).map(|k| 100 * generation + k).collect();
                assert_eq!(streams, first, "{name}: not the step's first points");
            }
            let r = step(opt.as_mut(), generation, Some(need));
            assert!(r.cut.is_none(), "{name}: cut with all it needs");
            assert_eq!(r.evaluations, need, "{name}");
        }
    }
}
