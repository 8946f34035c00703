//! Reachability through the public API and the CLI.

use kinsynth::collision::oracle::{judge_edge, ORACLE_SUBSTEPS};
use kinsynth::collision::{CheckerKind, CollisionScene};
use kinsynth::design::{AxisRanges, Design, LinkDesign};
use kinsynth::kinematics::{Axis, Placement, Range};
use kinsynth::planning::{reachability, PlannerConfig, ReachReport};
use kinsynth::world::{Obstacle, ObstacleShape, Workspace};
use kinsynth::Scenario;
use nalgebra::{IsometryMatrix3, Point3};
use std::f64::consts::PI;
use std::path::Path;
use std::process::Command;
use std::sync::Arc;

/// A planar arm turning about z: a joint at the base, then links of the given lengths, each
/// with a joint at its end (the last joint moves nothing).
fn planar_arm(lengths: &[f64]) -> Design {
    let mut joint = AxisRanges::default();
    *joint.get_mut(Axis::Rz) = Range::new(-PI, PI);
    let mut links = vec![LinkDesign {
        axes: joint,
        ..LinkDesign::default()
    }];
    for &a in lengths {
        links.push(LinkDesign {
            a,
            axes: joint,
            ..LinkDesign::default()
        });
    }
    Design {
        base: Placement::default(),
        link_radius: 0.02,
        colliders_per_link: 4,
        links,
    }
}

fn run(
    design: &Design,
    obstacles: Vec<Obstacle>,
    tasks: Vec<Point3<f64>>,
    checker: CheckerKind,
    iterations: usize,
) -> (ReachReport, Arc<CollisionScene>) {
    let w = Workspace::new(obstacles, tasks, 0.0).unwrap();
    let scene = Arc::new(CollisionScene::new(&w));
    let config = PlannerConfig {
        checker,
        max_iterations: iterations,
        ..PlannerConfig::default()
    };
    let chain = design.chain();
    let report = reachability(&chain, &scene, &w.tasks, &config, 11, 0);
    (report, scene)
}

/// Every reached task: the path starts at home, ends within tolerance, and every edge obeys
/// the step bound of paper Eq. 10.
fn check_paths(design: &Design, report: &ReachReport, config: &PlannerConfig) {
    let chain = design.chain();
    let (mut fa, mut fb) = (chain.frames(), chain.frames());
    for t in report.targets.iter().filter(|t| t.reached) {
        let path = t.path.as_ref().unwrap();
        assert_eq!(path.joint_names, chain.joint_names());
        assert_eq!(
            path.points[0],
            chain.home(),
            "task {}: path starts at home",
            t.index
        );
        let last = path.points.last().unwrap();
        let ee = chain.end_effector(last);
        let p = Point3::from(t.point);
        assert!(
            (ee - p).norm() <= config.goal_tolerance,
            "task {}: last point ends {} m away",
            t.index,
            (ee - p).norm()
        );
        for w in path.points.windows(2) {
            assert!(chain.within_ranges(&w[1]));
            chain.fk(&w[0], &mut fa);
            chain.fk(&w[1], &mut fb);
            let l = kinsynth::kinematics::step_length(&fa, &fb, &w[0], &w[1], config.lambda);
            assert!(l <= config.l_max + 1e-9, "step {l} above L_max");
        }
    }
}

#[test]
fn a_target_on_the_reach_circle_is_reached_and_one_beyond_is_not() {
    let design = planar_arm(&[1.0, 0.5]);
    let on_circle = Point3::new(1.5 * 0.6, 1.5 * 0.8, 0.0);
    let beyond = Point3::new(0.0, -1.7, 0.0);
    let (report, _) = run(
        &design,
        vec![],
        vec![on_circle, beyond],
        CheckerKind::Certified,
        2000,
    );
    assert!(report.targets[0].reached, "{:?}", report.targets[0]);
    assert!(!report.targets[1].reached);
    assert!(
        (report.targets[1].error - 0.2).abs() < 0.05,
        "closest approach ≈ 0.2 m"
    );
    assert_eq!(report.reachability, 0.5);
    assert!(report.targets[1].path.is_none());
    check_paths(&design, &report, &PlannerConfig::default());
}

#[test]
fn an_obstacle_forces_a_detour_that_certified_finds_and_the_oracle_confirms() {
    let design = planar_arm(&[0.8, 0.8]);
    // A block in the way of the stretched arm turning from +x to +y: the arm has to fold its
    // elbow to pass it, then stretch again toward a target on the far side.
    let block = Obstacle::new(
        "block",
        ObstacleShape::Cuboid {
            size: [0.4, 0.4, 1.0],
        },
        IsometryMatrix3::translation(1.3, 0.6, 0.0),
    )
    .unwrap();
    let target = Point3::new(0.0, 1.4, 0.0);
    let (report, scene) = run(
        &design,
        vec![block],
        vec![target],
        CheckerKind::Certified,
        5000,
    );
    assert!(report.targets[0].reached, "{:?}", report.targets[0]);
    let chain = design.chain();
    let path = &report.targets[0].path.as_ref().unwrap().points;
    for w in path.windows(2) {
        let v = judge_edge(
            &scene,
            &chain,
            &kinsynth::collision::RobotBody::of_chain(&chain),
            &w[0],
            &w[1],
            ORACLE_SUBSTEPS,
        );
        assert!(v.free, "path edge collides at t = {:?}", v.first_hit);
    }
    // The straight motion from home to the final configuration would cross the wall.
    let direct = judge_edge(
        &scene,
        &chain,
        &kinsynth::collision::RobotBody::of_chain(&chain),
        &path[0],
        path.last().unwrap(),
        ORACLE_SUBSTEPS,
    );
    assert!(!direct.free, "the task needs a detour");
    check_paths(&design, &report, &PlannerConfig::default());
}

#[test]
fn a_colliding_home_pose_gives_zero_and_says_why() {
    let design = planar_arm(&[1.0, 0.5]);
    let ball = Obstacle::sphere("post", Point3::new(1.2, 0.0, 0.0), 0.1).unwrap();
    let (report, _) = run(
        &design,
        vec![ball],
        vec![Point3::new(0.0, 1.0, 0.0)],
        CheckerKind::Segment,
        100,
    );
    assert_eq!(report.reachability, 0.0);
    let why = report.home_blocked.as_deref().unwrap();
    assert!(why.contains("link 3") && why.contains("post"), "{why}");
}

/// A scenario from `examples/scenarios/`.
fn bundled(name: &str) -> Scenario {
    Scenario::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios")
            .join(name),
    )
    .unwrap()
}

#[test]
fn bundled_scenarios_give_replayable_paths() {
    for name in ["paper-3d.toml", "pipework.toml"] {
        let s = bundled(name);
        let design = s.space.largest();
        let scene = Arc::new(CollisionScene::new(&s.workspace));
        for checker in [CheckerKind::Segment, CheckerKind::Certified] {
            let config = PlannerConfig {
                checker,
                ..s.planner.clone()
            };
            let r = reachability(&design.chain(), &scene, &s.workspace.tasks, &config, 1, 0);
            assert!(r.reached() > 0, "{name} {checker}");
            check_paths(&design, &r, &config);
        }
    }
}

/// The largest designs of paper-2d and paper-3d can reach all their tasks (the optimiser starts
/// from there): the planner must find every one within the scenario's budget, for every seed.
/// A planner that keeps retrying the same IK start for a task behind an obstacle fails this.
#[test]
fn the_largest_bundled_designs_reach_every_task_for_every_seed() {
    for name in ["paper-2d.toml", "paper-3d.toml"] {
        let s = bundled(name);
        let chain = s.space.largest().chain();
        let scene = Arc::new(CollisionScene::new(&s.workspace));
        let config = PlannerConfig {
            checker: CheckerKind::Segment,
            l_max: std::f64::consts::FRAC_PI_4,
            ..s.planner.clone()
        };
        for seed in 0..10 {
            let r = reachability(&chain, &scene, &s.workspace.tasks, &config, seed, 0);
            assert_eq!(
                r.reachability, 1.0,
                "{name} seed {seed}: {} iterations",
                r.iterations
            );
        }
    }
}

fn reach_json(threads: &str, dir: &Path) -> String {
    let out = dir.join(format!("reach-{threads}.json"));
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios/paper-2d.toml");
    let status = Command::new(env!("CARGO_BIN_EXE_kinsynth"))
        .env("RAYON_NUM_THREADS", threads)
        .args(["reach", "--checker", "certified", "--seed", "5", "--json"])
        .arg(&out)
        .arg(&scenario)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    std::fs::read_to_string(out).unwrap()
}

#[test]
fn same_seed_same_json_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let one = reach_json("1", dir.path());
    let two = reach_json("2", dir.path());
    assert_eq!(one, two);
    let v: serde_json::Value = serde_json::from_str(&one).unwrap();
    assert_eq!(v["checker"], "certified");
    assert!(v["reachability"].as_f64().unwrap() > 0.0);
    let targets = v["targets"].as_array().unwrap();
    assert_eq!(targets.len(), 10);
    for t in targets {
        if t["reached"].as_bool().unwrap() {
            assert_eq!(t["path"]["joint_names"][0], "j1_ry");
        } else {
            assert!(t["path"].is_null());
        }
    }
}
