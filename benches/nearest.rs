//! Nearest neighbour in actuation space: the linear scan, the planner's scan of four nodes at a
//! time (`blocked`, the same answers) and a k-d tree (kiddo), at the dimensions of the paper's
//! chains (8 and 24 axes) and tree sizes an RRT reaches.
//! Each measurement is one query on a tree of the given size (the k-d tree's insertions, which
//! an RRT also pays for, come on top).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use kiddo::{KdTree, SquaredEuclidean};
use kinsynth::planning::rrt::{block_push, nearest_blocked, nearest_linear};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

fn points<const K: usize>(n: usize, rng: &mut ChaCha8Rng) -> Vec<[f64; K]> {
    (0..n)
        .map(|_| {
            std::array::from_fn(|_| rng.random_range(-std::f64::consts::PI..std::f64::consts::PI))
        })
        .collect()
}

fn compare<const K: usize>(c: &mut Criterion) {
    let mut group = c.benchmark_group(format!("nearest/{K}-dof"));
    for n in [100usize, 500, 2000, 5000] {
        let mut rng = ChaCha8Rng::seed_from_u64(n as u64);
        let pts = points::<K>(n, &mut rng);
        let queries = points::<K>(256, &mut rng);
        let flat: Vec<f64> = pts.iter().flatten().copied().collect();
        let mut i = 0;
        group.bench_with_input(BenchmarkId::new("linear", n), &n, |b, _| {
            b.iter(|| {
                i = (i + 1) % queries.len();
                black_box(nearest_linear(&flat, &queries[i]))
            })
        });
        let mut blocks = Vec::new();
        for (k, p) in pts.iter().enumerate() {
            block_push(&mut blocks, k, p);
        }
        group.bench_with_input(BenchmarkId::new("blocked", n), &n, |b, _| {
            b.iter(|| {
                i = (i + 1) % queries.len();
                black_box(nearest_blocked(&blocks, &queries[i]))
            })
        });
        let mut tree: KdTree<f64, K> = KdTree::new();
        for (k, p) in pts.iter().enumerate() {
            tree.add(p, k as u64);
        }
        group.bench_with_input(BenchmarkId::new("kiddo", n), &n, |b, _| {
            b.iter(|| {
                i = (i + 1) % queries.len();
                black_box(tree.nearest_one::<SquaredEuclidean>(&queries[i]).item)
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(std::time::Duration::from_millis(300))
        .measurement_time(std::time::Duration::from_secs(1));
    targets = compare::<8>, compare::<24>
}
criterion_main!(benches);
