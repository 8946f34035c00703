//! Forward kinematics of the 8-link paper-3d chain (24 actuated axes).

use criterion::{criterion_group, criterion_main, Criterion};
use kinsynth::scenario::preset::{generate, Preset};
use kinsynth::Scenario;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

fn fk(c: &mut Criterion) {
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 1)).unwrap();
    let chain = s.space.largest().chain();
    assert_eq!(chain.dof(), 24);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let configs: Vec<Vec<f64>> = (0..64)
        .map(|_| {
            chain
                .free_axes()
                .iter()
                .map(|f| rng.random_range(f.range.min..=f.range.max))
                .collect()
        })
        .collect();
    let mut frames = chain.frames();
    let mut k = 0;
    c.bench_function("fk/paper-3d 8 links 24 axes", |b| {
        b.iter(|| {
            k = (k + 1) & 63;
            chain.fk(black_box(&configs[k]), &mut frames);
            black_box(&frames);
        })
    });
    let mut colliders = Vec::new();
    c.bench_function("fk+colliders/paper-3d 8 links × 4", |b| {
        b.iter(|| {
            k = (k + 1) & 63;
            chain.fk(black_box(&configs[k]), &mut frames);
            chain.colliders(&frames, &mut colliders);
            black_box(&colliders);
        })
    });
}

criterion_group!(benches, fk);
criterion_main!(benches);
