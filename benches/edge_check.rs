//! Cost of one edge check for each strategy, at L_max = π/4 and π/40, on
//! - the paper-3d preset of seed 11 (8 links, 32 spheres, self-collision on),
//! - the bundled paper-3d scenario and the pipework mesh scene (vessel hull, pipe-bundle
//!   decomposition, floor), and the glove box (a triangle-mesh shell) at π/4,
//!
//! and the scaling of `segment`, `certified` and `ccd` with clutter: generated cells of 32, 512
//! and 2,048 random spheres around the same 8-link arm (fixed seed).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use kinsynth::collision::oracle::sample_edges;
use kinsynth::collision::{make_checker, BodyModel, CheckerKind, CollisionScene, Scratch};
use kinsynth::scenario::preset::{generate, Preset};
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

fn bench_scene(
    c: &mut Criterion,
    label: &str,
    s: &Scenario,
    kinds: &[CheckerKind],
    lmax: &[(&str, f64)],
) {
    let chain = s.space.largest().chain();
    let scene = Arc::new(CollisionScene::new(&s.workspace));
    let body = kinsynth::collision::RobotBody::of_chain(&chain);
    for &(lname, l_max) in lmax {
        let edges = sample_edges(&scene, &chain, &body, l_max, s.planner.lambda, 256, 7);
        let mut group = c.benchmark_group(format!("edge/{label}/{lname}"));
        for &kind in kinds {
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

const PI4: (&str, f64) = ("pi/4", std::f64::consts::FRAC_PI_4);
const PI40: (&str, f64) = ("pi/40", std::f64::consts::PI / 40.0);

fn edges(c: &mut Criterion) {
    let preset = Scenario::from_spec(&generate(Preset::Paper3d, 11)).unwrap();
    bench_scene(c, "paper-3d-seed11", &preset, &CheckerKind::ALL, &[PI4]);
    for (label, file) in [("paper-3d", "paper-3d.toml"), ("mesh", "pipework.toml")] {
        bench_scene(c, label, &scenario(file), &CheckerKind::ALL, &[PI4, PI40]);
    }
    bench_scene(
        c,
        "trimesh",
        &scenario("glovebox.toml"),
        &CheckerKind::ALL,
        &[PI4],
    );
}

/// The paper-3d preset of seed 11 with its spheres replaced by `n` random ones (radius
/// 0.02–0.05 m, centres uniform in a 4 m cube around the base, seed 5), dropping any that come
/// within 5 cm of the home pose's body or of a task point.
fn cluttered(n: usize) -> Scenario {
    use kinsynth::collision::distance::point_segment;
    use nalgebra::Point3;
    use rand::{RngExt, SeedableRng};
    let mut spec = generate(Preset::Paper3d, 11);
    let base = Scenario::from_spec(&spec).unwrap();
    let chain = base.space.largest().chain();
    let mut frames = chain.frames();
    chain.fk(chain.home(), &mut frames);
    let r_link = chain.radius();
    let template = spec.obstacle[0].clone();
    spec.obstacle.clear();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    while spec.obstacle.len() < n {
        let r: f64 = rng.random_range(0.02..0.05);
        let p = Point3::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
        );
        let clear_of_arm = frames
            .segments
            .iter()
            .all(|[a, b]| point_segment(&p, a, b) > r + r_link + 0.05);
        let clear_of_tasks = spec
            .task
            .iter()
            .all(|t| (Point3::from(t.point) - p).norm() > r + 0.05);
        if clear_of_arm && clear_of_tasks {
            let mut o = template.clone();
            o.position = [p.x, p.y, p.z];
            o.radius = Some(r);
            spec.obstacle.push(o);
        }
    }
    Scenario::from_spec(&spec).unwrap()
}

fn scaling(c: &mut Criterion) {
    for n in [32, 512, 2048] {
        let s = cluttered(n);
        bench_scene(
            c,
            &format!("spheres-{n}"),
            &s,
            &[
                CheckerKind::Segment,
                CheckerKind::Certified,
                CheckerKind::Ccd,
            ],
            &[PI4],
        );
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(30)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2));
    targets = edges, scaling
}
criterion_main!(benches);
