//! Forward kinematics and point colliders allocate nothing once their buffers exist.

use kinsynth::scenario::preset::{generate, Preset};
use kinsynth::Scenario;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    /// Allocations made by this thread (tests run in parallel threads).
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn fk_and_colliders_do_not_allocate() {
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 2)).unwrap();
    let chain = s.space.largest().chain();
    let mut frames = chain.frames();
    let mut colliders = Vec::new();
    let a: Vec<f64> = chain
        .free_axes()
        .iter()
        .map(|f| 0.3 * f.range.max)
        .collect();
    chain.fk(&a, &mut frames);
    chain.colliders(&frames, &mut colliders); // sizes the buffer once
    let before = allocations();
    for _ in 0..100 {
        chain.fk(&a, &mut frames);
        chain.colliders(&frames, &mut colliders);
    }
    let after = allocations();
    assert_eq!(after - before, 0, "allocations inside fk/colliders");
    assert_eq!(colliders.len(), 8 * 4);
}

#[test]
fn edge_checks_do_not_allocate_once_warm() {
    use kinsynth::collision::oracle::sample_edges;
    use kinsynth::collision::{make_checker, BodyModel, CheckerKind, CollisionScene, Scratch};
    use std::sync::Arc;
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 2)).unwrap();
    let chain = s.space.largest().chain();
    let scene = Arc::new(CollisionScene::new(&s.workspace));
    let edges = sample_edges(
        &scene,
        &chain,
        &kinsynth::collision::RobotBody::of_chain(&chain),
        std::f64::consts::FRAC_PI_4,
        0.1,
        200,
        1,
    );
    for kind in [
        CheckerKind::Discrete,
        CheckerKind::Segment,
        CheckerKind::Certified,
    ] {
        for body in [BodyModel::Capsules, BodyModel::Points] {
            let checker = make_checker(kind, scene.clone(), body);
            let mut scratch = Scratch::new(&chain);
            // Warm-up: buffers grow to their working size. Each edge is also checked back
            // from its end, which `certified` has kept.
            for (a, b) in &edges {
                checker.node_free(&chain, a, &mut scratch);
                checker.edge_free(&chain, a, b, &mut scratch);
                checker.edge_free(&chain, b, a, &mut scratch);
            }
            let before = allocations();
            for (a, b) in &edges {
                checker.node_free(&chain, a, &mut scratch);
                checker.edge_free(&chain, a, b, &mut scratch);
                checker.edge_free(&chain, b, a, &mut scratch);
            }
            let after = allocations();
            assert_eq!(after - before, 0, "{kind} with {body:?} allocated");
        }
    }
}

#[test]
fn oriented_ik_does_not_allocate() {
    use kinsynth::planning::ik::{dls_oriented, IkWork};
    use kinsynth::world::TaskOrientation;
    let s = Scenario::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios/drill-fixture.toml"),
    )
    .unwrap();
    let chain = s.space.largest().chain();
    assert!(chain.has_tool());
    let mut work = IkWork::new(&chain);
    let pose = TaskOrientation::Pose {
        rotation: nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 1.0),
        tolerance: 0.01,
    };
    let before = allocations();
    for (j, p) in s.workspace.tasks.iter().enumerate() {
        for o in [s.workspace.orientations[j], pose] {
            dls_oriented(&chain, chain.home(), p, &o, 0.1, 50, 1e-4, &mut work);
        }
    }
    assert_eq!(allocations() - before, 0, "allocations inside dls_oriented");
}
