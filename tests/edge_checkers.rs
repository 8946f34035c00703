//! The edge checkers against analytic cases and against the dense-sampling oracle.

use kinsynth::collision::oracle::{judge_edge, sample_edges, ORACLE_SUBSTEPS};
use kinsynth::collision::{make_checker, BodyModel, CheckerKind, CollisionScene, Scratch};
use kinsynth::design::{AxisRanges, Design, LinkDesign};
use kinsynth::kinematics::{Axis, Placement, Range};
use kinsynth::scenario::preset::{generate, Preset};
use kinsynth::world::{Obstacle, Workspace};
use kinsynth::Scenario;
use nalgebra::Point3;
use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::Arc;

/// One link of length 1 turning about z at the base (link 0 has no body).
fn sweeping_arm() -> Design {
    let mut joint = AxisRanges::default();
    *joint.get_mut(Axis::Rz) = Range::new(-PI, PI);
    Design {
        base: Placement::default(),
        link_radius: 0.02,
        colliders_per_link: 3,
        links: vec![
            LinkDesign {
                axes: joint,
                ..LinkDesign::default()
            },
            LinkDesign {
                a: 1.0,
                ..LinkDesign::default()
            },
        ],
        tool: None,
    }
}

fn scene(obstacles: Vec<Obstacle>, clearance: f64) -> Arc<CollisionScene> {
    let w = Workspace::new(obstacles, vec![Point3::new(0.0, 0.0, 5.0)], clearance).unwrap();
    Arc::new(CollisionScene::new(&w))
}

#[test]
fn a_sweep_through_a_small_ball_is_caught_by_all_but_discrete() {
    // The arm turns from +x to +y (90°); a small ball sits at 45° on its way, mid-link.
    let ball = Obstacle::sphere(
        "ball",
        Point3::new(0.5 * (PI / 4.0).cos(), 0.5 * (PI / 4.0).sin(), 0.0),
        0.05,
    )
    .unwrap();
    let s = scene(vec![ball], 0.0);
    let chain = sweeping_arm().chain();
    let (from, to) = (vec![0.0], vec![FRAC_PI_2]);
    assert!(
        !judge_edge(
            &s,
            &chain,
            &kinsynth::collision::RobotBody::of_chain(&chain),
            &from,
            &to,
            ORACLE_SUBSTEPS
        )
        .free
    );
    let mut scratch = Scratch::new(&chain);
    for kind in CheckerKind::ALL {
        let c = make_checker(kind, s.clone(), BodyModel::Capsules);
        assert!(
            c.node_free(&chain, &from, &mut scratch),
            "{kind}: start is free"
        );
        assert!(
            c.node_free(&chain, &to, &mut scratch),
            "{kind}: end is free"
        );
        let free = c.edge_free(&chain, &from, &to, &mut scratch);
        assert_eq!(free, kind == CheckerKind::Discrete, "{kind}");
    }
}

#[test]
fn the_chord_misses_what_the_arc_hits() {
    // Segment checks the chord of each point's arc: a ball just outside the chords but inside
    // the swept arc is missed by `segment`, caught by `certified`, `ccd` and the oracle.
    // The tip's chord from 0° to 90° passes at distance cos(45°) = 0.707 from the base; a ball
    // centred at 0.95 on the 45° ray with radius 0.1 touches the arc but not the chords.
    let c = Point3::new(0.95 * (PI / 4.0).cos(), 0.95 * (PI / 4.0).sin(), 0.0);
    let ball = Obstacle::sphere("ball", c, 0.1).unwrap();
    let s = scene(vec![ball], 0.0);
    let chain = sweeping_arm().chain();
    let (from, to) = (vec![0.0], vec![FRAC_PI_2]);
    assert!(
        !judge_edge(
            &s,
            &chain,
            &kinsynth::collision::RobotBody::of_chain(&chain),
            &from,
            &to,
            ORACLE_SUBSTEPS
        )
        .free
    );
    let mut scratch = Scratch::new(&chain);
    let verdict = |kind: CheckerKind, scratch: &mut Scratch| {
        make_checker(kind, s.clone(), BodyModel::Capsules).edge_free(&chain, &from, &to, scratch)
    };
    assert!(
        verdict(CheckerKind::Segment, &mut scratch),
        "segment sees only chords"
    );
    assert!(!verdict(CheckerKind::Certified, &mut scratch));
    assert!(!verdict(CheckerKind::Ccd, &mut scratch));
}

#[test]
fn free_sweeps_are_free_and_clearance_counts() {
    let ball = Obstacle::sphere("ball", Point3::new(0.0, 0.0, 0.5), 0.1).unwrap();
    let chain = sweeping_arm().chain();
    let (from, to) = (vec![-1.0], vec![2.0]);
    let mut scratch = Scratch::new(&chain);
    // The arm turns in z = 0; the ball floats 0.38 m above its capsule.
    let s = scene(vec![ball.clone()], 0.0);
    for kind in CheckerKind::ALL {
        let c = make_checker(kind, s.clone(), BodyModel::Capsules);
        assert!(c.edge_free(&chain, &from, &to, &mut scratch), "{kind}");
    }
    // A clearance larger than the gap blocks every configuration.
    let s = scene(vec![ball], 0.4);
    for kind in CheckerKind::ALL {
        let c = make_checker(kind, s.clone(), BodyModel::Capsules);
        assert!(!c.node_free(&chain, &from, &mut scratch), "{kind}");
        assert!(!c.edge_free(&chain, &from, &to, &mut scratch), "{kind}");
    }
}

fn check_certified_against_oracle(s: &Scenario, count: usize, seed: u64) {
    let chain = s.space.largest().chain();
    let scene = Arc::new(CollisionScene::new(&s.workspace));
    let certified = make_checker(CheckerKind::Certified, scene.clone(), BodyModel::Capsules);
    let mut scratch = Scratch::new(&chain);
    let mut blocked = 0;
    let mut proven_free = 0;
    for l_max in [PI / 8.0, PI / 4.0] {
        for (a, b) in sample_edges(
            &scene,
            &chain,
            &kinsynth::collision::RobotBody::of_chain(&chain),
            l_max,
            s.planner.lambda,
            count / 2,
            seed,
        ) {
            let oracle = judge_edge(
                &scene,
                &chain,
                &kinsynth::collision::RobotBody::of_chain(&chain),
                &a,
                &b,
                ORACLE_SUBSTEPS,
            );
            let free = certified.edge_free(&chain, &a, &b, &mut scratch);
            assert!(
                !free || oracle.free,
                "certified called a colliding edge free: {a:?} → {b:?}, oracle hit at t = {:?}",
                oracle.first_hit
            );
            blocked += usize::from(!oracle.free);
            proven_free += usize::from(free);
        }
    }
    // The test means something only if the edges include collisions and free motions.
    assert!(blocked >= 20, "too few colliding edges: {blocked}");
    assert!(
        proven_free >= count / 2,
        "certified proves too little: {proven_free}"
    );
}

#[test]
fn certified_has_no_false_free_edge_on_the_paper_3d_scene() {
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 1)).unwrap();
    check_certified_against_oracle(&s, 2000, 17);
}

#[test]
fn sampled_edges_respect_the_step_bound() {
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 4)).unwrap();
    let chain = s.space.largest().chain();
    let scene = CollisionScene::new(&s.workspace);
    let (mut fa, mut fb) = (chain.frames(), chain.frames());
    for (a, b) in sample_edges(
        &scene,
        &chain,
        &kinsynth::collision::RobotBody::of_chain(&chain),
        PI / 4.0,
        0.1,
        50,
        3,
    ) {
        assert!(chain.within_ranges(&a) && chain.within_ranges(&b));
        chain.fk(&a, &mut fa);
        chain.fk(&b, &mut fb);
        let l = kinsynth::kinematics::step_length(&fa, &fb, &a, &b, 0.1);
        assert!(l <= PI / 4.0 + 1e-9, "{l}");
    }
}

#[test]
fn certified_step_bounds_hold_along_dense_steps() {
    // Every bound `certified` starts a step with covers the path the moving body's core ends
    // really travel (relative to the pair's other body for a self pair), measured densely; a
    // step that does not move has bounds of 0.
    use kinsynth::collision::edge::certified::step_bounds;
    use kinsynth::collision::oracle::travel;
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 6)).unwrap();
    let chain = s.space.largest().chain();
    let scene = CollisionScene::new(&s.workspace);
    let body = kinsynth::collision::RobotBody::of_chain(&chain);
    let (mut pairs, mut tightest) = (0, 0.0f64);
    for (a, b) in sample_edges(&scene, &chain, &body, PI / 4.0, 0.1, 12, 5) {
        let items = step_bounds(&chain, &body, &a, &b);
        assert_eq!(items.len(), body.len() + body.self_pairs().len());
        assert!(step_bounds(&chain, &body, &a, &a)
            .iter()
            .all(|it| it.bound == 0.0));
        let length = travel(&chain, &body, &a, &b, &items, 300);
        for (it, len) in items.iter().zip(length) {
            let len = len.expect("a capsule");
            assert!(
                len <= it.bound * (1.0 + 1e-9),
                "{it:?}: the core travels {len}"
            );
            pairs += usize::from(it.relative_to.is_some());
            tightest = tightest.max(len / it.bound);
        }
    }
    assert!(pairs > 0);
    // The bounds are not vacuous: some come within a factor 2 of the measured path.
    assert!(
        tightest > 0.5,
        "the tightest bound is {tightest} of the path"
    );
}

#[test]
fn certified_has_no_false_free_edge_on_a_mesh_scene() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios/pipework.toml");
    let s = Scenario::load(&path).unwrap();
    assert!(s
        .workspace
        .obstacles
        .iter()
        .any(|o| matches!(o.geometry, kinsynth::world::ObstacleShape::Mesh { .. })));
    check_certified_against_oracle(&s, 2000, 23);
}

/// A checker that says it checks a step's end ([`EdgeChecker::edge_checks_end`], so that the
/// planner skips the node check there) never passes a step whose end is blocked. `segment`
/// does not say so, and indeed passes such steps: the check can fail.
#[test]
fn a_checker_that_checks_the_end_never_passes_a_blocked_end() {
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 2)).unwrap();
    let chain = s.space.largest().chain();
    let scene = Arc::new(CollisionScene::new(&s.workspace));
    let body = kinsynth::collision::RobotBody::of_chain(&chain);
    let edges = sample_edges(&scene, &chain, &body, PI / 4.0, s.planner.lambda, 1500, 5);
    for kind in CheckerKind::ALL {
        let c = make_checker(kind, scene.clone(), BodyModel::Capsules);
        let mut scratch = Scratch::new(&chain);
        let (mut blocked_ends, mut passed) = (0, 0);
        for (a, b) in &edges {
            if c.node_free(&chain, b, &mut scratch) {
                continue;
            }
            blocked_ends += 1;
            passed += usize::from(c.edge_free(&chain, a, b, &mut scratch));
        }
        assert!(blocked_ends >= 50, "{kind}: {blocked_ends} blocked ends");
        if c.edge_checks_end() {
            assert_eq!(passed, 0, "{kind} passed {passed} steps with a blocked end");
        } else if kind == CheckerKind::Segment {
            assert!(passed > 0, "segment checked every end after all");
        }
    }
}

/// Given the kinematics of a step's end (as a planner has them from steering), every checker
/// answers as without them, and `discrete`, `segment` and `certified` use them instead of
/// evaluating the end again (one forward kinematics fewer; none at all for a node check given
/// its frames): the frames of another configuration change their answers.
#[test]
fn checkers_given_the_end_frames_answer_as_without_them() {
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 2)).unwrap();
    let chain = s.space.largest().chain();
    let scene = Arc::new(CollisionScene::new(&s.workspace));
    let body = Arc::new(kinsynth::collision::RobotBody::of_chain(&chain));
    let edges = sample_edges(&scene, &chain, &body, PI / 4.0, s.planner.lambda, 300, 9);
    let mut frames = chain.frames();
    let mut other = chain.frames();
    for kind in CheckerKind::ALL {
        let c = make_checker(kind, scene.clone(), BodyModel::Capsules);
        let (mut blocked, mut changed) = (0, 0);
        for (i, (a, b)) in edges.iter().enumerate() {
            // A fresh scratch for each check: `certified` keeps the configurations it has
            // evaluated, and would take this edge's ends from the check before.
            let mut scratch = Scratch::with_body(&chain, body.clone());
            chain.fk(b, &mut frames);
            let plain = c.edge_free(&chain, a, b, &mut scratch);
            let fk_plain = scratch.stats.fk;
            let mut scratch = Scratch::with_body(&chain, body.clone());
            let given = c.check_edge(&chain, a, b, Some(&frames), &mut scratch);
            let fk_given = scratch.stats.fk;
            assert_eq!(plain, given, "{kind}: edge {i}");
            if kind != CheckerKind::Ccd {
                assert_eq!(fk_given + 1, fk_plain, "{kind}: edge {i} evaluated its end");
            }
            let node_plain = c.node_free(&chain, b, &mut scratch);
            let fk = scratch.stats.fk;
            assert_eq!(
                node_plain,
                c.check_node(&chain, b, Some(&frames), &mut scratch),
                "{kind}: node {i}"
            );
            assert_eq!(
                scratch.stats.fk, fk,
                "{kind}: node {i} evaluated its frames"
            );
            blocked += usize::from(!plain);
            // The frames of the start in place of the end's: the checker sees another step.
            chain.fk(a, &mut other);
            let mut scratch = Scratch::with_body(&chain, body.clone());
            if kind != CheckerKind::Ccd
                && c.check_edge(&chain, a, b, Some(&other), &mut scratch) != plain
            {
                changed += 1;
            }
        }
        assert!(blocked >= 20, "{kind}: only {blocked} blocked edges");
        if kind != CheckerKind::Ccd {
            assert!(changed > 0, "{kind} ignored the frames it was given");
        }
    }
}

/// A random walk of steps on `chain`, each within `±step` per axis and the ranges: mostly
/// from the last step's end, else from one of the last 40 ends (some of them beyond what a
/// checker keeps) or a fresh sample, and now and then back to one of the last ends (a planner
/// joining its trees): the steps a planner checks.
fn walk(
    chain: &kinsynth::kinematics::Chain,
    n: usize,
    step: f64,
    seed: u64,
) -> Vec<(Vec<f64>, Vec<f64>)> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut a = vec![0.0; chain.dof()];
    chain.sample_config(&mut rng, &mut a);
    let mut ends: Vec<Vec<f64>> = Vec::new();
    let mut out = Vec::new();
    for _ in 0..n {
        match rng.random_range(0..10) {
            0 => chain.sample_config(&mut rng, &mut a),
            1..=3 if !ends.is_empty() => {
                let back = rng.random_range(1..=ends.len().min(40));
                a.clone_from(&ends[ends.len() - back]);
            }
            _ => {}
        }
        let b: Vec<f64> = if rng.random_range(0..10) == 0 && ends.len() > 2 {
            ends[ends.len() - rng.random_range(2..=ends.len().min(20))].clone()
        } else {
            a.iter()
                .zip(chain.free_axes())
                .map(|(x, f)| (x + rng.random_range(-step..=step)).clamp(f.range.min, f.range.max))
                .collect()
        };
        out.push((a.clone(), b.clone()));
        ends.push(b.clone());
        a = b;
    }
    out
}

/// `certified` takes the frames, clearances and placement at a step's ends from the recent
/// steps that evaluated those configurations (a planner extends the nodes it has just added):
/// the answers are those of a fresh scratch for every step, with fewer evaluations of the
/// kinematics; and
/// what was computed against one scene is never taken for another's, even at the same
/// configuration (an empty cell's clearances would prove steps the cluttered cell blocks).
#[test]
fn certified_reuses_the_previous_end_only_where_it_holds() {
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 2)).unwrap();
    let chain = s.space.largest().chain();
    let cluttered = Arc::new(CollisionScene::new(&s.workspace));
    let empty = scene(Vec::new(), s.workspace.clearance);
    let on = |scene: &Arc<CollisionScene>| {
        make_checker(CheckerKind::Certified, scene.clone(), BodyModel::Capsules)
    };
    let (c, c_empty) = (on(&cluttered), on(&empty));
    let steps = walk(&chain, 600, 0.35, 4);
    let body = kinsynth::collision::RobotBody::of_chain(&chain);
    let mut chained = Scratch::new(&chain);
    let (mut fresh_fk, mut blocked) = (0, 0);
    for (i, (a, b)) in steps.iter().enumerate() {
        let mut fresh = Scratch::new(&chain);
        let want = c.edge_free(&chain, a, b, &mut fresh);
        fresh_fk += fresh.stats.fk;
        let got = c.edge_free(&chain, a, b, &mut chained);
        assert_eq!(got, want, "step {i}");
        blocked += usize::from(!want);
        if got && i % 3 == 0 {
            let oracle = judge_edge(&cluttered, &chain, &body, a, b, ORACLE_SUBSTEPS);
            assert!(
                oracle.free,
                "step {i} called free: oracle hit at {:?}",
                oracle.first_hit
            );
        }
    }
    assert!(
        blocked >= 60,
        "only {blocked} of {} steps blocked",
        steps.len()
    );
    assert!(
        chained.stats.fk + 300 < fresh_fk,
        "the chained steps evaluated {} configurations, fresh ones {fresh_fk}",
        chained.stats.fk
    );
    // Each step in the empty cell, then the next one (from its end) in the cluttered cell,
    // with the same scratch.
    let mut shared = Scratch::new(&chain);
    let (mut pairs, mut cluttered_blocked) = (0, 0);
    for (i, w) in steps.windows(2).enumerate() {
        let [(a, b), (next_a, next_b)] = [&w[0], &w[1]];
        if next_a != b {
            continue;
        }
        let mut fresh = Scratch::new(&chain);
        let want = c.edge_free(&chain, next_a, next_b, &mut fresh);
        c_empty.edge_free(&chain, a, b, &mut shared);
        let got = c.edge_free(&chain, next_a, next_b, &mut shared);
        assert_eq!(got, want, "step {} after the empty cell", i + 1);
        pairs += 1;
        cluttered_blocked += usize::from(!want);
    }
    assert!(
        pairs >= 300 && cluttered_blocked >= 30,
        "{pairs} chained pairs, {cluttered_blocked} blocked"
    );
}
