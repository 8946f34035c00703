//! The one robot body model: the exported URDF carries exactly the bodies the planner checks,
//! self-collision is checked by `certified` without a false "free" against the oracle, a design
//! folded through itself at home gets R = 0, and the SRDF lists the excluded pairs.

use k::nalgebra as kna;
use kinsynth::collision::body::{Reason, RobotBody, SelfCollisionConfig};
use kinsynth::collision::oracle::{judge_edge, sample_edges, ORACLE_SUBSTEPS};
use kinsynth::collision::{make_checker, BodyModel, CheckerKind, CollisionScene, Scratch};
use kinsynth::design::{AxisRanges, Design, LinkDesign};
use kinsynth::kinematics::{Axis, Placement, Range};
use kinsynth::planning::{reachability, PlannerConfig};
use kinsynth::world::{Obstacle, Workspace};
use kinsynth::Scenario;
use nalgebra::{IsometryMatrix3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::PathBuf;
use std::sync::Arc;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn axes(list: &[(Axis, f64, f64)]) -> AxisRanges {
    let mut r = AxisRanges::default();
    for &(a, lo, hi) in list {
        *r.get_mut(a) = Range::new(lo, hi);
    }
    r
}

/// Prismatic axes everywhere: one, two and three translation axes on a link, a constant
/// translation between joints and one after the last joint, and negative strokes.
fn sliders() -> Design {
    Design {
        base: Placement {
            position: [0.0, 0.1, 0.2],
            rpy: [0.1, 0.2, -0.3],
        },
        link_radius: 0.025,
        colliders_per_link: 2,
        links: vec![
            LinkDesign {
                d: 0.2,
                axes: axes(&[(Axis::Rz, -PI, PI), (Axis::Tz, 0.1, 0.4)]),
                ..LinkDesign::default()
            },
            LinkDesign {
                a: 0.3,
                alpha: FRAC_PI_2,
                axes: axes(&[
                    (Axis::Ry, -1.0, 1.0),
                    (Axis::Tx, -0.2, 0.3),
                    (Axis::Ty, 0.05, 0.05),
                    (Axis::Tz, -0.15, 0.0),
                ]),
                ..LinkDesign::default()
            },
            LinkDesign {
                a: 0.2,
                theta: 0.4,
                axes: axes(&[
                    (Axis::Rx, -2.0, 2.0),
                    (Axis::Tx, 0.0, 0.2),
                    (Axis::Ty, -0.1, 0.1),
                    (Axis::Tz, 0.3, 0.3),
                ]),
                ..LinkDesign::default()
            },
        ],
        tool: None,
    }
}

fn from_k(t: &kna::Isometry3<f64>) -> IsometryMatrix3<f64> {
    let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        t.rotation.w,
        t.rotation.i,
        t.rotation.j,
        t.rotation.k,
    ));
    let v = t.translation.vector;
    IsometryMatrix3::from_parts(Translation3::new(v.x, v.y, v.z), q.to_rotation_matrix())
}

/// The end points of a URDF `<cylinder>` collision in its link's frame.
fn cylinder_ends(c: &urdf_rs::Collision) -> Option<([Point3<f64>; 2], f64)> {
    let urdf_rs::Geometry::Cylinder { radius, length } = c.geometry else {
        return None;
    };
    let t = kinsynth::export::urdf::isometry_of(&c.origin);
    let h = t.rotation * Vector3::new(0.0, 0.0, 0.5 * length);
    let m = Point3::from(t.translation.vector);
    Some(([m - h, m + h], radius))
}

fn same_segment(a: &[Point3<f64>; 2], b: &[Point3<f64>; 2], tol: f64) -> bool {
    let d = |p: &Point3<f64>, q: &Point3<f64>| (p - q).norm();
    (d(&a[0], &b[0]) < tol && d(&a[1], &b[1]) < tol)
        || (d(&a[0], &b[1]) < tol && d(&a[1], &b[0]) < tol)
}

/// Every planned capsule is a cylinder of the exported URDF (and nothing else is), on the link
/// the chain names, at the place forward kinematics of the URDF (by the `k` crate) puts it.
fn exported_bodies_are_the_planned_ones(design: &Design) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("robot.urdf");
    kinsynth::export::write_urdf(design, &path).unwrap();
    let robot = urdf_rs::read_file(&path).unwrap();
    let chain = design.chain();
    let mut planned = 0;
    for s in 0..chain.segment_count() {
        let info = chain.segment_info(s);
        if (info.local[1] - info.local[0]).norm() == 0.0 {
            continue;
        }
        planned += 1;
        let link = robot
            .links
            .iter()
            .find(|l| l.name == info.frame)
            .unwrap_or_else(|| panic!("no link {}", info.frame));
        let found = link
            .collision
            .iter()
            .filter_map(cylinder_ends)
            .any(|(ends, r)| same_segment(&ends, &info.local, 1e-12) && r == design.link_radius);
        assert!(
            found,
            "segment {s} ({info:?}) not exported on {}",
            info.frame
        );
    }
    let exported: usize = robot
        .links
        .iter()
        .map(|l| l.collision.iter().filter_map(cylinder_ends).count())
        .sum();
    assert_eq!(
        exported, planned,
        "the URDF carries exactly the planned capsules"
    );
    let kc = k::Chain::<f64>::from_urdf_file(&path).unwrap();
    let names = chain.joint_names();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut frames = chain.frames();
    let mut q = vec![0.0; chain.dof()];
    let mut worst = 0.0f64;
    for _ in 0..300 {
        chain.sample_config(&mut rng, &mut q);
        chain.fk(&q, &mut frames);
        for (n, v) in names.iter().zip(&q) {
            kc.find(n).unwrap().set_joint_position(*v).unwrap();
        }
        kc.update_transforms();
        for s in 0..chain.segment_count() {
            let info = chain.segment_info(s);
            let w = from_k(
                &kc.find_link(&info.frame)
                    .unwrap()
                    .world_transform()
                    .unwrap(),
            );
            for e in 0..2 {
                worst = worst.max((w * info.local[e] - frames.segments[s][e]).norm());
            }
        }
    }
    worst
}

#[test]
fn the_exported_urdf_carries_exactly_the_planned_bodies() {
    let paper3d = Scenario::load(&root().join("examples/scenarios/paper-3d.toml")).unwrap();
    for (name, d) in [
        ("sliders", sliders()),
        ("paper-3d", paper3d.space.largest()),
    ] {
        let worst = exported_bodies_are_the_planned_ones(&d);
        assert!(worst < 1e-12, "{name}: {worst}");
    }
}

#[test]
fn sliders_are_fixed_length_rods_that_span_joint_and_child() {
    let chain = sliders().chain();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut frames = chain.frames();
    let mut q = vec![0.0; chain.dof()];
    let rods: Vec<usize> = (0..chain.segment_count())
        .filter(|&s| chain.segment_info(s).slider)
        .collect();
    // tz of link 1; tx, ty (constant), tz of link 2; tx, ty, tz (constant) of link 3.
    assert_eq!(rods.len(), 7);
    let mut lengths: Vec<Option<f64>> = vec![None; chain.segment_count()];
    for _ in 0..200 {
        chain.sample_config(&mut rng, &mut q);
        chain.fk(&q, &mut frames);
        for &s in &rods {
            let [a, b] = frames.segments[s];
            let l = (b - a).norm();
            let fixed = *lengths[s].get_or_insert(l);
            assert!((l - fixed).abs() < 1e-12, "segment {s} changes length");
        }
    }
}

/// A planar arm of four links turning about z, long enough to fold onto itself.
fn folding_arm() -> Design {
    let joint = axes(&[(Axis::Rz, -3.0, 3.0)]);
    Design {
        base: Placement::default(),
        link_radius: 0.03,
        colliders_per_link: 2,
        links: (0..5)
            .map(|i| LinkDesign {
                a: if i == 0 { 0.0 } else { 0.3 },
                axes: if i < 4 { joint } else { AxisRanges::default() },
                ..LinkDesign::default()
            })
            .collect(),
        tool: None,
    }
}

#[test]
fn certified_never_calls_a_self_colliding_edge_free() {
    // No obstacle near the arm: every blocked edge is a self-collision.
    let far = Obstacle::sphere("far", Point3::new(10.0, 0.0, 0.0), 0.1).unwrap();
    let w = Workspace::new(vec![far], vec![Point3::new(0.5, 0.5, 0.0)], 0.0).unwrap();
    let scene = Arc::new(CollisionScene::new(&w));
    let design = folding_arm();
    let chain = design.chain();
    let body = RobotBody::new(&chain, Vec::new(), &SelfCollisionConfig::default());
    assert!(!body.self_pairs().is_empty());
    let body = Arc::new(body);
    let certified = make_checker(CheckerKind::Certified, scene.clone(), BodyModel::Capsules);
    let mut scratch = Scratch::with_body(&chain, body.clone());
    let (mut blocked, mut free, mut proven) = (0, 0, 0);
    for l_max in [PI / 8.0, PI / 4.0, PI / 2.0] {
        for (a, b) in sample_edges(&scene, &chain, &body, l_max, 0.1, 700, 3) {
            let v = judge_edge(&scene, &chain, &body, &a, &b, ORACLE_SUBSTEPS);
            let c = certified.edge_free(&chain, &a, &b, &mut scratch);
            assert!(
                !c || v.free,
                "certified passed a self-colliding edge {a:?} → {b:?}"
            );
            blocked += usize::from(!v.free);
            free += usize::from(v.free);
            proven += usize::from(c);
        }
    }
    assert!(blocked >= 50, "too few self-colliding edges: {blocked}");
    assert!(
        proven * 10 >= free * 8,
        "certified proves too little: {proven} of {free}"
    );
    // Without self-collision the same edges are all free: the blocks were self-collisions.
    let off = Arc::new(RobotBody::new(
        &chain,
        Vec::new(),
        &SelfCollisionConfig::off(),
    ));
    let (a, b) = (vec![0.0, 0.0, 0.0, 0.0], vec![0.0, 2.9, 2.9, 0.0]);
    assert!(!judge_edge(&scene, &chain, &body, &a, &b, ORACLE_SUBSTEPS).free);
    assert!(judge_edge(&scene, &chain, &off, &a, &b, ORACLE_SUBSTEPS).free);
    let mut s_off = Scratch::with_body(&chain, off);
    assert!(certified.edge_free(&chain, &a, &b, &mut s_off));
    for kind in CheckerKind::ALL {
        let c = make_checker(kind, scene.clone(), BodyModel::Capsules);
        assert!(
            !c.node_free(&chain, &b, &mut scratch),
            "{kind} misses the fold"
        );
        assert!(
            !c.edge_free(&chain, &a, &b, &mut scratch),
            "{kind} passes the fold"
        );
    }
}

/// Base → (0.4, 0) → turn left (0.4, 0.2) → left (0.2, 0.2) → left, down through link 2's
/// body at (0.2, 0): the last link crosses the first at home.
fn folded_arm() -> Design {
    let joint = axes(&[(Axis::Rz, -0.5, 0.5)]);
    let link = |a: f64, theta: f64| LinkDesign {
        a,
        theta,
        axes: joint,
        ..LinkDesign::default()
    };
    Design {
        base: Placement::default(),
        link_radius: 0.02,
        colliders_per_link: 2,
        links: vec![
            link(0.0, 0.0),
            link(0.4, 0.0),
            link(0.2, FRAC_PI_2),
            link(0.2, FRAC_PI_2),
            link(0.4, FRAC_PI_2),
        ],
        tool: None,
    }
}

#[test]
fn a_design_folded_through_itself_at_home_gets_zero() {
    let design = folded_arm();
    let w = Workspace::new(Vec::new(), vec![Point3::new(0.5, 0.0, 0.0)], 0.0).unwrap();
    let scene = Arc::new(CollisionScene::new(&w));
    let chain = design.chain();
    let r = reachability(&chain, &scene, &w.tasks, &PlannerConfig::default(), 1, 0);
    assert_eq!(r.reachability, 0.0);
    let why = r.home_blocked.expect("a reason");
    assert!(
        why.contains("link 2") && why.contains("link 5") && why.contains("self-collides"),
        "{why}"
    );
    // What is checked is what is shipped: the folded pair is in contact at home but stays
    // enabled (not "Default"), so the SRDF leaves it checked and a checker that loads it sees
    // the home pose in collision too; every other pair in contact at home is "Default".
    let body = RobotBody::new(&chain, Vec::new(), &SelfCollisionConfig::default());
    let acm = body.acm();
    let (p, q) = (0..body.len())
        .flat_map(|p| (0..body.len()).map(move |q| (p, q)))
        .find(|&(p, q)| body.link(p) == 2 && body.link(q) == 5)
        .expect("bodies on links 2 and 5");
    let (fp, fq) = (body.frame(p), body.frame(q));
    assert!(
        !acm.disabled()
            .iter()
            .any(|d| (d.link1 == fp && d.link2 == fq) || (d.link1 == fq && d.link2 == fp)),
        "{fp}-{fq} disabled: {:?}",
        acm.disabled()
    );
    assert!(acm
        .pairs()
        .iter()
        .any(|&(a, b)| (body.link(a as usize), body.link(b as usize)) == (2, 5)));
    let srdf = kinsynth::export::srdf::body_to_srdf(&body, "folded");
    assert!(
        !srdf.contains(&format!("link1=\"{fp}\" link2=\"{fq}\"")),
        "{srdf}"
    );
    let mut frames = chain.frames();
    let mut placed = kinsynth::collision::body::Placed::default();
    chain.fk(chain.home(), &mut frames);
    body.place(&frames, &mut placed);
    assert!(body.self_contact(&frames, &placed).is_some());
    // Switched off, the fold is not checked.
    let config = PlannerConfig {
        self_collision: SelfCollisionConfig::off(),
        ..PlannerConfig::default()
    };
    let r = reachability(&chain, &scene, &w.tasks, &config, 1, 0);
    assert!(r.home_blocked.is_none());
}

#[test]
fn the_allowed_collision_matrix_follows_moveit_rules() {
    let chain = folding_arm().chain();
    let body = RobotBody::new(&chain, Vec::new(), &SelfCollisionConfig::default());
    let acm = body.acm();
    let reason = |a: &str, b: &str| {
        acm.disabled()
            .iter()
            .find(|d| (d.link1 == a && d.link2 == b) || (d.link1 == b && d.link2 == a))
            .map(|d| d.reason)
    };
    // Links 2 and 3 share joint 3; 2 and 4 have link 3 between them and are apart at home.
    assert_eq!(reason("link2_dh", "link3_dh"), Some(Reason::Adjacent));
    assert_eq!(reason("link2_dh", "link4_dh"), None);
    assert!(acm.pairs().iter().any(|&(p, q)| {
        body.frame(p as usize) == "link2_dh" && body.frame(q as usize) == "link4_dh"
    }));
    // A user exclusion by link index.
    let user = RobotBody::new(
        &chain,
        Vec::new(),
        &SelfCollisionConfig {
            allowed: vec![[2, 4]],
            ..SelfCollisionConfig::default()
        },
    );
    assert!(user
        .acm()
        .disabled()
        .iter()
        .any(|d| d.link1 == "link2_dh" && d.link2 == "link4_dh" && d.reason == Reason::User));
    assert!(user.self_pairs().len() < body.self_pairs().len());
    // Two links with a short one (link 3, 1 cm) between them touch at home: "Default", not
    // checked.
    let mut short = folding_arm();
    short.links[2].a = 0.01;
    let b = RobotBody::new(&short.chain(), Vec::new(), &SelfCollisionConfig::default());
    assert!(b
        .acm()
        .disabled()
        .iter()
        .any(|d| d.link1 == "link2_dh" && d.link2 == "link4_dh" && d.reason == Reason::Default));
}

#[test]
fn the_same_seed_gives_the_same_matrix() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut d = folding_arm();
    for l in &mut d.links {
        l.a = rng.random_range(0.05..0.3);
    }
    let chain = d.chain();
    let a = RobotBody::new(&chain, Vec::new(), &SelfCollisionConfig::default());
    let b = RobotBody::new(&chain, Vec::new(), &SelfCollisionConfig::default());
    assert_eq!(a.acm(), b.acm());
}

fn kinsynth(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_kinsynth"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs `kinsynth` and asserts that it succeeds (showing its stderr when it does not).
fn kinsynth_ok(args: &[&str]) {
    let out = kinsynth(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn urdf_writes_the_srdf_beside_the_urdf() {
    let dir = tempfile::tempdir().unwrap();
    let design = dir.path().join("d.json");
    std::fs::write(&design, serde_json::to_string(&folding_arm()).unwrap()).unwrap();
    let urdf = dir.path().join("arm.urdf");
    let out = kinsynth(&[
        "urdf",
        design.to_str().unwrap(),
        "-o",
        urdf.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    // Links and joints counted as `optimize` reports them: the first link has no length.
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("(4 links kept of 5, 4 joints kept)"),
        "{said}"
    );
    let srdf = std::fs::read_to_string(dir.path().join("arm.srdf")).unwrap();
    assert!(srdf.contains("<robot name=\"arm\">"));
    assert!(srdf.contains(
        "<disable_collisions link1=\"link2_dh\" link2=\"link3_dh\" reason=\"Adjacent\"/>"
    ));
    // With a scenario that switches self-collision off, every pair is disabled.
    let scenario = dir.path().join("s.toml");
    std::fs::write(
        &scenario,
        "[robot]\nlinks = 2\nself_collision = false\n[robot.uniform]\na = 0.3\n[[task]]\npoint = [0.5, 0, 0]\n",
    )
    .unwrap();
    kinsynth_ok(&[
        "urdf",
        design.to_str().unwrap(),
        "-o",
        urdf.to_str().unwrap(),
        "--scenario",
        scenario.to_str().unwrap(),
    ]);
    let srdf = std::fs::read_to_string(dir.path().join("arm.srdf")).unwrap();
    assert!(
        srdf.contains("link1=\"link2_dh\" link2=\"link4_dh\" reason=\"User\""),
        "{srdf}"
    );
    // `reach --write-srdf` on the design writes the same matrix as `urdf`.
    let written = dir.path().join("arm2.srdf");
    kinsynth_ok(&[
        "reach",
        scenario.to_str().unwrap(),
        "--design",
        design.to_str().unwrap(),
        "--write-srdf",
        written.to_str().unwrap(),
    ]);
    let again = std::fs::read_to_string(&written).unwrap();
    assert_eq!(again.replace("\"arm2\"", "\"arm\""), srdf);
}

#[test]
fn scenario_self_collision_keys_are_validated() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        "[robot]\nlinks = 3\nallowed_collisions = [[1, 7]]\n[robot.uniform]\na = 0.3\n[[task]]\npoint = [0.5, 0, 0]\n",
    )
    .unwrap();
    let out = kinsynth(&["check", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("robot.allowed_collisions[0]") && err.contains("[1, 7]"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

/// `kinsynth urdf` exports a design folded through itself at home, with a one-line warning
/// naming the links, and an SRDF that keeps the crossing pair enabled; a design that is not
/// folded gets no warning.
#[test]
fn urdf_warns_of_a_design_folded_at_home() {
    let dir = tempfile::tempdir().unwrap();
    for (name, design, folded) in [
        ("folded", folded_arm(), true),
        ("arm", folding_arm(), false),
    ] {
        let file = dir.path().join(format!("{name}.json"));
        std::fs::write(&file, serde_json::to_string(&design).unwrap()).unwrap();
        let urdf = dir.path().join(format!("{name}.urdf"));
        let out = kinsynth(&["urdf", file.to_str().unwrap(), "-o", urdf.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        assert!(urdf.exists());
        if folded {
            assert_eq!(stderr.lines().count(), 1, "{stderr}");
            assert!(
                stderr.contains("folded.json")
                    && stderr.contains("link 2 and link 5 cross each other"),
                "{stderr}"
            );
            let srdf = std::fs::read_to_string(dir.path().join("folded.srdf")).unwrap();
            assert!(!srdf.contains("link2_dh\" link2=\"link5_dh\""), "{srdf}");
        } else {
            assert!(stderr.is_empty(), "{stderr}");
        }
    }
}

/// Contacts of every pair of body frames over the samples `AllowedCollisions` draws (same seed,
/// same stream), counted one pair and one sample at a time with no culling: the brute force the
/// "Always" rule is checked against.
fn contact_counts(
    chain: &kinsynth::kinematics::Chain,
    body: &RobotBody,
    samples: usize,
    seed: u64,
) -> std::collections::HashMap<(String, String), usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut q = vec![0.0; chain.dof()];
    let mut frames = chain.frames();
    let mut placed = kinsynth::collision::body::Placed::default();
    let mut counts = std::collections::HashMap::new();
    let mut touching = std::collections::HashSet::new();
    for _ in 0..samples {
        chain.sample_config(&mut rng, &mut q);
        chain.fk(&q, &mut frames);
        body.place(&frames, &mut placed);
        touching.clear();
        for p in 0..body.len() {
            for r in p + 1..body.len() {
                let (a, b) = (body.frame(p).to_string(), body.frame(r).to_string());
                if a != b && body.pair_distance(&frames, &placed, p, r) <= 0.0 {
                    touching.insert(if a < b { (a, b) } else { (b, a) });
                }
            }
        }
        for k in touching.drain() {
            *counts.entry(k).or_insert(0) += 1;
        }
    }
    counts
}

#[test]
fn always_pairs_are_those_in_contact_in_most_samples() {
    // Link 3 slides back along link 2 (tx from -0.5 to 0): at home (tx = 0) links 2 and 4 are
    // apart, in most samples link 3 is short enough for them to touch.
    let mut found = 0;
    for (short, radius) in [(0.07, 0.03), (0.12, 0.05), (0.1, 0.06), (0.3, 0.03)] {
        let mut d = folding_arm();
        d.link_radius = radius;
        d.links[2].a = short;
        d.links[2].axes = axes(&[(Axis::Rz, -0.5, 0.5), (Axis::Tx, -0.5, 0.0)]);
        let chain = d.chain();
        let config = SelfCollisionConfig::default();
        let body = RobotBody::new(&chain, Vec::new(), &config);
        let counts = contact_counts(&chain, &body, config.samples, config.seed);
        let count = |a: &str, b: &str| {
            let key = if a < b { (a, b) } else { (b, a) };
            counts
                .get(&(key.0.to_string(), key.1.to_string()))
                .copied()
                .unwrap_or(0)
        };
        let most = (0.95 * config.samples as f64).ceil() as usize;
        for x in body.acm().disabled() {
            if x.reason == Reason::Always {
                found += 1;
                let n = count(&x.link1, &x.link2);
                assert!(n >= most, "{x:?}: in contact in only {n} samples");
            }
        }
        // A pair left enabled is in contact in fewer samples, or is a fold of the arm at home
        // (which stays enabled on purpose).
        let mut frames = chain.frames();
        let mut placed = kinsynth::collision::body::Placed::default();
        chain.fk(chain.home(), &mut frames);
        body.place(&frames, &mut placed);
        for &(p, q) in body.self_pairs() {
            let (p, q) = (p as usize, q as usize);
            let n = count(body.frame(p), body.frame(q));
            let at_home = body.pair_distance(&frames, &placed, p, q) <= 0.0;
            assert!(
                n < most || at_home,
                "{} and {} are in contact in {n} samples but checked",
                body.frame(p),
                body.frame(q)
            );
        }
    }
    assert!(found >= 2, "the designs give {found} Always pairs");
}
