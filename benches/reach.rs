//! Reachability `R` of a fixed design (the scenario's largest) on the bundled paper-2d and
//! paper-3d scenarios, with `segment` at L_max = π/4 and with `certified`. Successive iterations
//! cycle through planner seeds 0–9, so the figure is typical of the seeds, not of one.

use criterion::{criterion_group, criterion_main, Criterion};
use kinsynth::collision::{CheckerKind, CollisionScene};
use kinsynth::planning::reachability;
use kinsynth::Scenario;
use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;

fn reach(c: &mut Criterion) {
    for name in ["paper-2d", "paper-3d"] {
        let s = Scenario::load(
            &Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("examples/scenarios")
                .join(format!("{name}.toml")),
        )
        .unwrap();
        let chain = s.space.largest().chain();
        let scene = Arc::new(CollisionScene::new(&s.workspace));
        // The robot body with its allowed-collision matrix, built once per reachability call.
        c.bench_function(&format!("body/{name}"), |b| {
            b.iter(|| black_box(kinsynth::collision::RobotBody::of_chain(&chain)))
        });
        for checker in [CheckerKind::Segment, CheckerKind::Certified] {
            let mut config = s.planner.clone();
            config.checker = checker;
            config.l_max = std::f64::consts::FRAC_PI_4;
            for seed in 0..10 {
                let r = reachability(&chain, &scene, &s.workspace.tasks, &config, seed, 0);
                eprintln!(
                    "{name}/{checker} seed {seed}: R = {:.2}, {} iterations, {} nodes, {} node checks, {} edge checks",
                    r.reachability, r.iterations, r.nodes, r.node_checks, r.edge_checks
                );
            }
            let mut seed = 0;
            c.bench_function(&format!("reach/{name}/{checker}"), |b| {
                b.iter(|| {
                    seed = (seed + 1) % 10;
                    black_box(reachability(
                        &chain,
                        &scene,
                        &s.workspace.tasks,
                        &config,
                        seed,
                        0,
                    ))
                })
            });
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(3));
    targets = reach
}
criterion_main!(benches);
