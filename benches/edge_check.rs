//! Cost of one edge check for each strategy, on the paper-3d scene (8 links, 32 spheres) and on
//! a mesh scene (vessel hull, pipe-bundle decomposition, floor), at L_max = π/4 and π/40.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use kinsynth::collision::oracle::sample_edges;
use kinsynth::collision::{make_checker, BodyModel, CheckerKind, CollisionScene, Scratch};
use kinsynth::Scenario;
use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;

fn scenario(name: &str) -> Scenario {
    Scenario::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios")
            .join(name),
    )
    .unwrap()
}

fn edges(c: &mut Criterion) {
    for (label, file) in [("paper-3d", "paper-3d.toml"), ("mesh", "pipework.toml")] {
        let s = scenario(file);
        let chain = s.space.largest().chain();
        let scene = Arc::new(CollisionScene::new(&s.workspace));
        for (lname, l_max) in [
            ("pi/4", std::f64::consts::FRAC_PI_4),
            ("pi/40", std::f64::consts::PI / 40.0),
        ] {
            let edges = sample_edges(
                &scene,
                &chain,
                &kinsynth::collision::RobotBody::of_chain(&chain),
                l_max,
                s.planner.lambda,
                256,
                7,
            );
            let mut group = c.benchmark_group(format!("edge/{label}/{lname}"));
            for kind in CheckerKind::ALL {
                let checker = make_checker(kind, scene.clone(), BodyModel::Capsules);
                let mut scratch = Scratch::new(&chain);
                let mut i = 0;
                group.bench_function(BenchmarkId::from_parameter(kind.name()), |b| {
                    b.iter(|| {
                        i = (i + 1) % edges.len();
                        let (from, to) = &edges[i];
                        black_box(checker.edge_free(&chain, from, to, &mut scratch))
                    })
                });
            }
            group.finish();
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(30)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2));
    targets = edges
}
criterion_main!(benches);
