//! URDF export and import: an independent forward-kinematics cross-check with the `k` crate,
//! the exported structure read back with urdf-rs, import rules and errors, the round trip
//! through `kinsynth reach`, trajectories, and the bundled UR5.

use k::nalgebra as kna;
use kinsynth::design::{Design, LinkDesign, Param};
use kinsynth::export::urdf::{design_to_urdf, design_to_urdf_string, EFFORT, VELOCITY};
use kinsynth::import::urdf::{chain_from_urdf, load_chain};
use kinsynth::kinematics::{Axis, Chain, Placement, Range};
use kinsynth::planning::ReachReport;
use kinsynth::Scenario;
use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Unit, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{ranges, ur5};

const CONFIGS: usize = 1000;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scenario(name: &str) -> Scenario {
    Scenario::load(&root().join("examples/scenarios").join(name)).unwrap()
}

fn largest(name: &str) -> Design {
    scenario(name).space.largest()
}

/// A random design of the paper-3d space with some links and joints removed (zeros), standing
/// in for an optimiser's result.
fn optimised() -> Design {
    let space = scenario("paper-3d.toml").space;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let x: Vec<f64> = space
        .variables()
        .iter()
        .map(|v| {
            let zero = match v.param {
                Param::A => v.link == 3 || v.link == 6,
                Param::Min(Axis::Rx) | Param::Max(Axis::Rx) => v.link % 2 == 0,
                Param::Min(Axis::Tx) | Param::Max(Axis::Tx) => v.link != 4,
                _ => false,
            };
            if zero {
                0.0
            } else if v.param == Param::A {
                // Long enough links to reach something.
                rng.random_range(0.2..=v.upper)
            } else {
                rng.random_range(v.lower..=v.upper)
            }
        })
        .collect();
    let d = space.decode(&x);
    assert_eq!(d.links[2].a, 0.0);
    assert!(d.joints_kept() < space.largest().joints_kept());
    d
}

/// Everything at once: a tilted base, every DH parameter, all six axes free, constant axes
/// (folded into fixed transforms), a rigid link in the middle and one with constants only.
fn everything() -> Design {
    Design {
        base: Placement {
            position: [0.1, -0.2, 0.3],
            rpy: [0.2, -0.3, 0.4],
        },
        link_radius: 0.03,
        colliders_per_link: 3,
        links: vec![
            LinkDesign {
                theta: 0.3,
                d: 0.2,
                a: 0.25,
                alpha: 0.7,
                axes: ranges(&[
                    (Axis::Rx, -1.0, 1.0),
                    (Axis::Ry, -2.0, 0.5),
                    (Axis::Rz, -3.0, 3.0),
                    (Axis::Tx, -0.1, 0.2),
                    (Axis::Ty, 0.0, 0.1),
                    (Axis::Tz, -0.05, 0.0),
                ]),
            },
            LinkDesign {
                theta: -0.4,
                d: 0.1,
                a: -0.2,
                alpha: -1.2,
                axes: ranges(&[
                    (Axis::Ry, -1.5, 1.5),
                    (Axis::Rz, 0.4, 0.4),
                    (Axis::Tx, -0.1, 0.2),
                    (Axis::Tz, 0.05, 0.05),
                ]),
            },
            LinkDesign {
                a: 0.3,
                alpha: 0.5,
                ..LinkDesign::default()
            },
            LinkDesign {
                d: 0.15,
                alpha: 1.0,
                axes: ranges(&[(Axis::Rz, -PI, PI)]),
                ..LinkDesign::default()
            },
            LinkDesign {
                a: 0.1,
                axes: ranges(&[(Axis::Rx, 0.2, 0.2)]),
                ..LinkDesign::default()
            },
        ],
        tool: None,
    }
}

fn random_config(chain: &Chain, rng: &mut ChaCha8Rng) -> Vec<f64> {
    chain
        .free_axes()
        .iter()
        .map(|f| rng.random_range(f.range.min..=f.range.max))
        .collect()
}

fn from_k(t: &kna::Isometry3<f64>) -> IsometryMatrix3<f64> {
    let m = t.rotation.to_rotation_matrix();
    let m = m.matrix();
    let r = nalgebra::Matrix3::from_fn(|i, j| m[(i, j)]);
    IsometryMatrix3::from_parts(
        Translation3::new(t.translation.x, t.translation.y, t.translation.z),
        Rotation3::from_matrix_unchecked(r),
    )
}

fn iso_err(a: &IsometryMatrix3<f64>, b: &IsometryMatrix3<f64>) -> f64 {
    let dt = (a.translation.vector - b.translation.vector).amax();
    let dr = (a.rotation.matrix() - b.rotation.matrix()).amax();
    dt.max(dr)
}

fn elementary(axis: Axis, v: f64) -> IsometryMatrix3<f64> {
    let dir = axis.direction();
    if axis.is_rotation() {
        IsometryMatrix3::from_parts(
            Translation3::identity(),
            Rotation3::from_axis_angle(&Unit::new_normalize(dir), v),
        )
    } else {
        IsometryMatrix3::from_parts(Translation3::from(dir * v), Rotation3::identity())
    }
}

/// Largest difference between k's frames of the exported URDF and ours over `CONFIGS` random
/// configurations: `link0` (F_0), every `link{i}` (F_i), `tool0`, every joint origin
/// (`link{i}_dh`), and the frame after every joint.
fn k_cross_check(design: &Design) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("robot.urdf");
    kinsynth::export::write_urdf(design, &path).unwrap();
    let kc = k::Chain::<f64>::from_urdf_file(&path).unwrap();
    let chain = design.chain();
    let names = chain.joint_names();
    assert_eq!(kc.dof(), chain.dof(), "k sees the same number of joints");
    let n = design.links.len();
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let mut frames = chain.frames();
    let mut worst = 0.0f64;
    let world = |name: &str| -> IsometryMatrix3<f64> {
        let node = kc
            .find_link(name)
            .unwrap_or_else(|| panic!("link {name} in k"));
        from_k(&node.world_transform().unwrap())
    };
    for _ in 0..CONFIGS {
        let a = random_config(&chain, &mut rng);
        chain.fk(&a, &mut frames);
        for (name, v) in names.iter().zip(&a) {
            kc.find(name).unwrap().set_joint_position(*v).unwrap();
        }
        kc.update_transforms();
        worst = worst.max(iso_err(&world("link0"), &frames.frames[0]));
        worst = worst.max(iso_err(&world("tool0"), &frames.frames[n]));
        let mut k_free = 0;
        for (i, l) in design.links.iter().enumerate() {
            worst = worst.max(iso_err(
                &world(&format!("link{}", i + 1)),
                &frames.frames[i + 1],
            ));
            let joint_frame = frames.frames[i] * l.dh().transform();
            let has_axes = l.axes.0.iter().any(|r| *r != Range::ZERO);
            if has_axes {
                let o = world(&format!("link{}_dh", i + 1));
                worst = worst.max((o.translation.vector - frames.joints[i].coords).amax());
                worst = worst.max(iso_err(&o, &joint_frame));
            }
            // The frame after each joint, from the design's own numbers.
            let mut f = joint_frame;
            for axis in Axis::ALL {
                let r = l.axes.get(axis);
                if r.is_joint() {
                    f *= elementary(axis, a[k_free]);
                    let node = kc.find(&names[k_free]).unwrap();
                    worst = worst.max(iso_err(&from_k(&node.world_transform().unwrap()), &f));
                    k_free += 1;
                } else if r.min != 0.0 {
                    f *= elementary(axis, r.min);
                }
            }
        }
    }
    worst
}

#[test]
fn k_agrees_with_our_forward_kinematics() {
    for (label, design) in [
        ("paper-2d largest", largest("paper-2d.toml")),
        ("paper-3d largest", largest("paper-3d.toml")),
        ("paper-3d optimised", optimised()),
        ("everything", everything()),
        ("ur5", ur5()),
    ] {
        let err = k_cross_check(&design);
        eprintln!("k cross-check {label}: max error {err:.3e} over {CONFIGS} configurations");
        assert!(err < 1e-9, "{label}: k and kinsynth differ by {err}");
    }
}

#[test]
fn exported_urdf_parses_back_with_the_design_joints() {
    for design in [largest("paper-3d.toml"), optimised(), everything()] {
        let text = design_to_urdf_string(&design, "robot");
        let robot = urdf_rs::read_from_string(&text).unwrap();
        assert_eq!(robot.name, "robot");
        let chain = design.chain();
        let moving: Vec<&urdf_rs::Joint> = robot
            .joints
            .iter()
            .filter(|j| j.joint_type != urdf_rs::JointType::Fixed)
            .collect();
        assert_eq!(moving.len(), chain.dof());
        for (j, f) in moving.iter().zip(chain.free_axes()) {
            assert_eq!(j.name, f.joint_name());
            let expected = if f.axis.is_rotation() {
                urdf_rs::JointType::Revolute
            } else {
                urdf_rs::JointType::Prismatic
            };
            assert_eq!(j.joint_type, expected, "{}", j.name);
            assert_eq!(j.limit.lower, f.range.min, "{}", j.name);
            assert_eq!(j.limit.upper, f.range.max, "{}", j.name);
            assert_eq!(j.limit.effort, EFFORT);
            assert_eq!(j.limit.velocity, VELOCITY);
            let d = f.axis.direction();
            assert_eq!(j.axis.xyz.0, [d.x, d.y, d.z], "{}", j.name);
        }
        // Fixed joints: base, one geometry joint per link, the tool.
        let fixed: Vec<&str> = robot
            .joints
            .iter()
            .filter(|j| j.joint_type == urdf_rs::JointType::Fixed)
            .map(|j| j.name.as_str())
            .collect();
        assert_eq!(fixed[0], "base_joint");
        assert_eq!(*fixed.last().unwrap(), "tool0_joint");
        for i in 1..=design.links.len() {
            assert!(fixed.contains(&format!("link{i}_geometry").as_str()));
            assert!(robot.links.iter().any(|l| l.name == format!("link{i}")));
        }
        assert_eq!(robot.links[0].name, "base_link");
        assert!(robot.links.iter().any(|l| l.name == "tool0"));
        // Every link is light but has a valid inertia; every capsule has the design radius.
        for l in &robot.links {
            assert!(l.inertial.mass.value > 0.0 && l.inertial.inertia.ixx > 0.0);
            for c in &l.collision {
                match c.geometry {
                    urdf_rs::Geometry::Cylinder { radius, .. }
                    | urdf_rs::Geometry::Sphere { radius } => {
                        assert_eq!(radius, design.link_radius)
                    }
                    ref g => panic!("unexpected geometry {g:?}"),
                }
            }
            assert_eq!(l.collision.len(), l.visual.len());
        }
    }
}

/// Largest difference of every frame, joint origin, joint position and body segment between two
/// chains over random configurations.
fn fk_difference(a: &Chain, b: &Chain, configs: usize) -> f64 {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let (mut fa, mut fb) = (a.frames(), b.frames());
    let mut worst = 0.0f64;
    for _ in 0..configs {
        let q = random_config(a, &mut rng);
        a.fk(&q, &mut fa);
        b.fk(&q, &mut fb);
        for (x, y) in fa.frames.iter().zip(&fb.frames).skip(1) {
            worst = worst.max(iso_err(x, y));
        }
        for (x, y) in fa.positions.iter().zip(&fb.positions) {
            worst = worst.max((x - y).amax());
        }
        for (x, y) in fa.joints.iter().zip(&fb.joints) {
            worst = worst.max((x - y).amax());
        }
        for (x, y) in fa.segments.iter().zip(&fb.segments) {
            worst = worst.max((x[0] - y[0]).amax()).max((x[1] - y[1]).amax());
        }
    }
    worst
}

#[test]
fn an_exported_design_imports_as_the_same_chain() {
    for design in [
        largest("paper-2d.toml"),
        largest("paper-3d.toml"),
        optimised(),
        ur5(),
    ] {
        let robot = design_to_urdf(&design, "robot");
        let imported =
            chain_from_urdf(&robot, None, None, None, design.colliders_per_link).unwrap();
        let chain = design.chain();
        assert_eq!(imported.base, "base_link");
        assert_eq!(imported.tip, "tool0");
        assert_eq!(imported.joint_names, chain.joint_names());
        assert_eq!(
            imported.radius, design.link_radius,
            "radius from the capsules"
        );
        let c = &imported.chain;
        assert_eq!(c.dof(), chain.dof());
        assert_eq!(c.link_count(), chain.link_count());
        assert_eq!(c.segment_count(), chain.segment_count());
        assert_eq!(c.home(), chain.home());
        assert_eq!(c.arc_layout(), chain.arc_layout());
        let err = fk_difference(&chain, c, 200);
        assert!(err < 1e-12, "imported chain differs by {err}");
    }
}

#[test]
fn constants_and_rigid_links_import_with_the_same_tip() {
    // A rigid link folds into the next one, so the chain differs in links but not in motion.
    let design = everything();
    let robot = design_to_urdf(&design, "robot");
    let imported = chain_from_urdf(&robot, None, None, Some(0.07), 2).unwrap();
    let chain = design.chain();
    assert_eq!(imported.joint_names, chain.joint_names());
    assert_eq!(imported.radius, 0.07, "an explicit radius wins");
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (mut fa, mut fb) = (chain.frames(), imported.chain.frames());
    for _ in 0..200 {
        let q = random_config(&chain, &mut rng);
        chain.fk(&q, &mut fa);
        imported.chain.fk(&q, &mut fb);
        let err = iso_err(fa.frames.last().unwrap(), fb.frames.last().unwrap());
        assert!(err < 1e-12, "tip differs by {err}");
    }
}

/// A hand-written robot with a world root, fixed offsets, a continuous joint, skewed and
/// negative axes and a prismatic joint, and a tool offset.
const GENERAL: &str = r#"<?xml version="1.0"?>
<robot name="general">
  <link name="world"/>
  <link name="base">
    <collision><geometry><cylinder radius="0.04" length="0.1"/></geometry></collision>
  </link>
  <link name="l1"/><link name="l2"/><link name="l3"/><link name="l4"/><link name="l5"/>
  <link name="tip"/>
  <joint name="mount" type="fixed">
    <origin xyz="0 0 0.1" rpy="0 0 0.5"/><parent link="world"/><child link="base"/>
  </joint>
  <joint name="turn" type="continuous">
    <origin xyz="0 0 0.05"/><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="skew" type="revolute">
    <origin xyz="0.1 0.0 0.2" rpy="0.3 -0.2 0.1"/><parent link="l1"/><child link="l2"/>
    <axis xyz="0 0.6 0.8"/><limit lower="-1.5" upper="2.0" effort="1" velocity="1"/>
  </joint>
  <joint name="slide" type="prismatic">
    <origin xyz="0.3 0 0"/><parent link="l2"/><child link="l3"/>
    <axis xyz="-1 0 0"/><limit lower="-0.1" upper="0.25" effort="1" velocity="1"/>
  </joint>
  <joint name="offset" type="fixed">
    <origin xyz="0 0.05 0" rpy="0.2 0 0"/><parent link="l3"/><child link="l4"/>
  </joint>
  <joint name="wrist" type="revolute">
    <origin xyz="0.1 0 0"/><parent link="l4"/><child link="l5"/>
    <axis xyz="0 -1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/>
  </joint>
  <joint name="tool" type="fixed">
    <origin xyz="0 0 0.12" rpy="0 0.4 0"/><parent link="l5"/><child link="tip"/>
  </joint>
</robot>
"#;

#[test]
fn a_general_robot_imports_with_k_s_kinematics() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("general.urdf");
    std::fs::write(&path, GENERAL).unwrap();
    let imported = load_chain(&path, None, None, None, 4).unwrap();
    assert_eq!(imported.joint_names, ["turn", "skew", "slide", "wrist"]);
    assert_eq!(imported.radius, 0.04, "radius from the collision cylinder");
    assert_eq!(
        (imported.base.as_str(), imported.tip.as_str()),
        ("world", "tip")
    );
    let chain = &imported.chain;
    let turn = chain.free_axes()[0];
    assert_eq!(turn.range, Range::new(-PI, PI), "continuous is ±π");
    let kc = k::Chain::<f64>::from_urdf_file(&path).unwrap();
    let tip = kc.find_link("tip").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut frames = chain.frames();
    let mut worst = 0.0f64;
    for _ in 0..CONFIGS {
        let q = random_config(chain, &mut rng);
        chain.fk(&q, &mut frames);
        for (n, v) in imported.joint_names.iter().zip(&q) {
            kc.find(n).unwrap().set_joint_position_unchecked(*v);
        }
        kc.update_transforms();
        let t = from_k(&tip.world_transform().unwrap());
        worst = worst.max(iso_err(&t, frames.frames.last().unwrap()));
        // Every moving joint's origin is a joint origin of the chain.
        for (k, n) in imported.joint_names.iter().enumerate() {
            let node = kc.find(n).unwrap();
            let o = from_k(&node.world_transform().unwrap());
            if !n.starts_with("slide") {
                worst = worst.max((o.translation.vector - frames.joints[k].coords).amax());
            }
        }
    }
    eprintln!("k cross-check general import: max error {worst:.3e}");
    assert!(worst < 1e-9, "imported chain and k differ by {worst}");
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn robot(joints: &str) -> String {
    let mut names: Vec<String> = Vec::new();
    for part in joints.split("link=\"").skip(1) {
        let n = part.split('"').next().unwrap().to_string();
        if !names.contains(&n) {
            names.push(n);
        }
    }
    let links: String = names
        .iter()
        .map(|n| format!("<link name=\"{n}\"/>"))
        .collect();
    format!("<robot name=\"r\">{links}{joints}</robot>")
}

fn rev(name: &str, parent: &str, child: &str) -> String {
    format!(
        r#"<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/><origin xyz="0.1 0 0"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"#
    )
}

#[test]
fn import_errors_name_the_file_the_element_and_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let err = |file: &Path, tip: Option<&str>| -> String {
        load_chain(file, None, tip, None, 4)
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let check = |msg: String, file: &Path, parts: &[&str]| {
        assert!(msg.contains(&file.display().to_string()), "{msg}");
        for p in parts {
            assert!(msg.contains(p), "{msg} should mention {p}");
        }
    };

    // A branch between base and tip.
    let branch = write(
        d,
        "branch.urdf",
        &robot(&format!(
            "{}{}{}",
            rev("j0", "b", "c"),
            rev("ja", "c", "l1"),
            rev("jb", "c", "l2")
        )),
    );
    check(
        err(&branch, None),
        &branch,
        &["link 'c'", "branch", "ja", "jb", "--tip-frame"],
    );
    // Naming a tip resolves it.
    let ok = load_chain(&branch, None, Some("l2"), None, 4).unwrap();
    assert_eq!(ok.joint_names, ["j0", "jb"]);

    // A link with two parents.
    let two = write(
        d,
        "two.urdf",
        &robot(&format!("{}{}", rev("ja", "a", "c"), rev("jb", "b", "c"))),
    );
    check(
        err(&two, None),
        &two,
        &["link 'c'", "not a tree", "ja", "jb"],
    );

    // Unsupported joint types.
    for kind in ["floating", "planar"] {
        let f = write(
            d,
            &format!("{kind}.urdf"),
            &robot(&format!(
                r#"{}<joint name="free" type="{kind}"><parent link="c"/><child link="e"/></joint>"#,
                rev("j0", "b", "c")
            )),
        );
        check(
            err(&f, None),
            &f,
            &[
                "joint 'free'",
                "parent 'c'",
                "child 'e'",
                kind,
                "unsupported",
            ],
        );
    }

    // A missing tip frame.
    let fine = write(d, "fine.urdf", &robot(&rev("j0", "b", "c")));
    check(
        err(&fine, Some("flange")),
        &fine,
        &["tip frame 'flange'", "no link"],
    );
    // A missing base frame.
    let msg = load_chain(&fine, Some("nowhere"), None, None, 4)
        .unwrap_err()
        .to_string();
    check(msg, &fine, &["base frame 'nowhere'"]);

    // A revolute joint without a usable limit.
    let bad = write(
        d,
        "limit.urdf",
        &robot(
            r#"<joint name="j0" type="revolute"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/><limit lower="1" upper="1" effort="1" velocity="1"/></joint>"#,
        ),
    );
    check(err(&bad, None), &bad, &["joint 'j0'", "lower < upper"]);

    // Only fixed joints.
    let rigid = write(
        d,
        "rigid.urdf",
        &robot(r#"<joint name="j0" type="fixed"><parent link="b"/><child link="c"/></joint>"#),
    );
    check(err(&rigid, None), &rigid, &["no moving joint"]);

    // Unreadable and malformed files.
    let missing = d.join("missing.urdf");
    check(err(&missing, None), &missing, &["cannot read"]);
    let broken = write(d, "broken.urdf", "<robot name=\"x\"><link name=");
    check(err(&broken, None), &broken, &["not a valid URDF"]);
}

fn kinsynth(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_kinsynth"))
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn read_report(p: &Path) -> ReachReport {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn reach_on_the_exported_urdf_equals_reach_on_the_design() {
    let dir = tempfile::tempdir().unwrap();
    for (label, scn, design) in [
        ("largest", "paper-3d.toml", largest("paper-3d.toml")),
        ("optimised", "paper-3d.toml", optimised()),
        ("largest", "paper-2d.toml", largest("paper-2d.toml")),
    ] {
        let scn = format!("examples/scenarios/{scn}");
        let scn = scn.as_str();
        let dj = dir.path().join("design.json");
        std::fs::write(&dj, design.to_json()).unwrap();
        let urdf = dir.path().join("robot.urdf");
        let (ok, out, err) =
            kinsynth(&["urdf", dj.to_str().unwrap(), "-o", urdf.to_str().unwrap()]);
        assert!(ok, "{err}");
        assert!(out.contains("wrote"), "{out}");
        let (a, b) = (dir.path().join("a.json"), dir.path().join("b.json"));
        let (ok, _, err) = kinsynth(&[
            "reach",
            scn,
            "--design",
            dj.to_str().unwrap(),
            "--json",
            a.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        let (ok, _, err) = kinsynth(&[
            "reach",
            scn,
            "--urdf",
            urdf.to_str().unwrap(),
            "--json",
            b.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        let (ra, rb) = (read_report(&a), read_report(&b));
        eprintln!(
            "round trip {label} on {scn}: R design {} / R urdf {} ({} tasks) {:?}",
            ra.reachability,
            rb.reachability,
            ra.targets.len(),
            ra.home_blocked
        );
        assert_eq!(ra.reachability, rb.reachability);
        assert_eq!(ra.nodes, rb.nodes);
        let chain = design.chain();
        for (x, y) in ra.targets.iter().zip(&rb.targets) {
            assert_eq!(x.reached, y.reached);
            for k in 0..3 {
                assert!((x.end_effector[k] - y.end_effector[k]).abs() < 1e-9);
            }
            if let (Some(p), Some(q)) = (&x.path, &y.path) {
                assert_eq!(
                    p.joint_names, q.joint_names,
                    "URDF names are j{{link}}_{{axis}}"
                );
                assert_eq!(p.points.len(), q.points.len());
                let last = q.points.last().unwrap();
                let ee = chain.end_effector(last);
                assert!((ee - nalgebra::Point3::from(x.end_effector)).norm() < 1e-9);
            }
        }
    }
}

#[test]
fn reach_writes_replayable_trajectories() {
    let dir = tempfile::tempdir().unwrap();
    let design = largest("paper-2d.toml");
    let dj = dir.path().join("design.json");
    std::fs::write(&dj, design.to_json()).unwrap();
    let urdf = dir.path().join("robot.urdf");
    kinsynth::export::write_urdf(&design, &urdf).unwrap();
    let (json, traj) = (dir.path().join("r.json"), dir.path().join("traj"));
    let (ok, out, err) = kinsynth(&[
        "reach",
        "examples/scenarios/paper-2d.toml",
        "--urdf",
        urdf.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
        "--trajectories",
        traj.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("trajectory files"), "{out}");
    let report = read_report(&json);
    assert!(report.reached() > 0);
    let kc = k::Chain::<f64>::from_urdf_file(&urdf).unwrap();
    let tool = kc.find_link("tool0").unwrap();
    for t in &report.targets {
        let csv = traj.join(format!("task_{}.csv", t.index));
        let js = traj.join(format!("task_{}.json", t.index));
        let Some(path) = &t.path else {
            assert!(!csv.exists() && !js.exists());
            continue;
        };
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        assert_eq!(
            lines.next().unwrap(),
            format!("t,{}", path.joint_names.join(","))
        );
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), path.points.len());
        assert_eq!(rows[0][0], 0.0);
        if rows.len() > 1 {
            assert_eq!(rows.last().unwrap()[0], 1.0);
        }
        for (r, p) in rows.iter().zip(&path.points) {
            // (serde_json reads the report's numbers to within an ulp; the CSV is exact.)
            for (x, y) in r[1..].iter().zip(p) {
                assert!(
                    (x - y).abs() <= 1e-15 * y.abs().max(1.0),
                    "positions are the path's"
                );
            }
        }
        assert!(rows.windows(2).all(|w| w[1][0] >= w[0][0]));
        // Replaying the last row on the URDF with k reaches the task.
        for (n, v) in path.joint_names.iter().zip(&rows.last().unwrap()[1..]) {
            kc.find(n).unwrap().set_joint_position(*v).unwrap();
        }
        kc.update_transforms();
        let p = from_k(&tool.world_transform().unwrap()).translation.vector;
        assert!((p - Vector3::from(t.point)).norm() <= 0.02 + 1e-9);
        // The JSON twin: ROS JointTrajectory, t = 1 at 1 s per unit of path length.
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&js).unwrap()).unwrap();
        assert_eq!(
            v["joint_names"].as_array().unwrap().len(),
            path.joint_names.len()
        );
        let pts = v["points"].as_array().unwrap();
        assert_eq!(pts.len(), path.points.len());
        let length: f64 = path
            .points
            .windows(2)
            .map(|w| {
                w[0].iter()
                    .zip(&w[1])
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
            })
            .sum();
        let last = &pts.last().unwrap()["time_from_start"];
        let secs = last["secs"].as_f64().unwrap() + last["nsecs"].as_f64().unwrap() * 1e-9;
        assert!((secs - length).abs() < 1e-8, "{secs} vs {length}");
        assert_eq!(
            pts[0]["positions"].as_array().unwrap().len(),
            path.joint_names.len()
        );
    }
}

#[test]
fn cli_rejects_bad_urdf_and_conflicting_options() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(
        dir.path(),
        "float.urdf",
        &robot(r#"<joint name="free" type="floating"><parent link="b"/><child link="c"/></joint>"#),
    );
    let (ok, _, err) = kinsynth(&[
        "reach",
        "examples/scenarios/paper-2d.toml",
        "--urdf",
        f.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("float.urdf") && err.contains("joint 'free'") && err.contains("floating"),
        "{err}"
    );
    let (ok, _, err) = kinsynth(&[
        "reach",
        "examples/scenarios/paper-2d.toml",
        "--urdf",
        f.to_str().unwrap(),
        "--design",
        "x.json",
    ]);
    assert!(!ok);
    assert!(err.contains("cannot be used with"), "{err}");
    let (ok, _, err) = kinsynth(&["urdf", "missing.json", "-o", "x.urdf"]);
    assert!(!ok);
    assert!(err.contains("missing.json"), "{err}");
}

/// Standard DH forward kinematics of the UR5: `Π Rz(q_i)·Tz(d_i)·Tx(a_i)·Rx(α_i)`.
fn ur5_standard_dh(q: &[f64]) -> IsometryMatrix3<f64> {
    let d = [0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823];
    let a = [0.0, -0.425, -0.39225, 0.0, 0.0, 0.0];
    let alpha = [PI / 2.0, 0.0, 0.0, PI / 2.0, -PI / 2.0, 0.0];
    let mut t = IsometryMatrix3::identity();
    for i in 0..6 {
        t = t
            * elementary(Axis::Rz, q[i])
            * elementary(Axis::Tz, d[i])
            * elementary(Axis::Tx, a[i])
            * elementary(Axis::Rx, alpha[i]);
    }
    t
}

#[test]
fn bundled_ur5_is_the_standard_dh_arm() {
    let path = root().join("examples/robots/ur5.urdf");
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(
        text,
        design_to_urdf_string(&ur5(), "ur5"),
        "examples/robots/ur5.urdf is what examples/make_ur5.rs writes"
    );
    let kc = k::Chain::<f64>::from_urdf_file(&path).unwrap();
    let tool = kc.find_link("tool0").unwrap();
    let names: Vec<String> = (1..=6).map(|i| format!("j{i}_rz")).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut worst = 0.0f64;
    for _ in 0..CONFIGS {
        let q: Vec<f64> = (0..6).map(|_| rng.random_range(-PI..PI)).collect();
        for (n, v) in names.iter().zip(&q) {
            kc.find(n).unwrap().set_joint_position(*v).unwrap();
        }
        kc.update_transforms();
        worst = worst.max(iso_err(
            &from_k(&tool.world_transform().unwrap()),
            &ur5_standard_dh(&q),
        ));
    }
    assert!(
        worst < 1e-9,
        "UR5 export differs from standard DH by {worst}"
    );
    // Home (all zeros): the arm stretched along −x.
    let home = ur5_standard_dh(&[0.0; 6]).translation.vector;
    assert!((home - Vector3::new(-0.81725, -0.19145, -0.005491)).norm() < 1e-9);
}

#[test]
fn ur5_cell_is_evaluated_through_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("ur5.json");
    let (ok, out, err) = kinsynth(&[
        "reach",
        "examples/scenarios/ur5-cell.toml",
        "--urdf",
        "examples/robots/ur5.urdf",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let r = read_report(&json);
    eprintln!("ur5-cell: UR5 {out}");
    assert!(r.home_blocked.is_none(), "the UR5's home pose is clear");
    assert!(r.reachability > 0.5, "R = {}", r.reachability);
    for t in r.targets.iter().filter_map(|t| t.path.as_ref()) {
        assert_eq!(t.joint_names[0], "j1_rz");
    }
    let (ok, out, err) = kinsynth(&["check", "examples/scenarios/ur5-cell.toml"]);
    assert!(ok, "{err}");
    assert!(!err.contains("warning"), "{err}");
    eprintln!("ur5-cell check: {out}");
}

#[test]
fn base_and_tip_frames_cut_the_chain() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "general.urdf", GENERAL);
    let imported = load_chain(&path, Some("base"), Some("l4"), Some(0.02), 4).unwrap();
    assert_eq!(imported.joint_names, ["turn", "skew", "slide"]);
    assert_eq!(imported.radius, 0.02);
    // The base frame keeps its pose in the root: the mount's offset and yaw.
    let mount = IsometryMatrix3::from_parts(
        Translation3::new(0.0, 0.0, 0.1),
        Rotation3::from_euler_angles(0.0, 0.0, 0.5),
    );
    assert!(iso_err(imported.chain.base(), &mount) < 1e-15);
    let kc = k::Chain::<f64>::from_urdf_file(&path).unwrap();
    let l4 = kc.find_link("l4").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    for _ in 0..100 {
        let q = random_config(&imported.chain, &mut rng);
        for (n, v) in imported.joint_names.iter().zip(&q) {
            kc.find(n).unwrap().set_joint_position_unchecked(*v);
        }
        kc.update_transforms();
        let t = from_k(&l4.world_transform().unwrap());
        let ee = imported.chain.end_effector(&q);
        assert!((t.translation.vector - ee.coords).amax() < 1e-12);
    }
    // A tip that is not below the base.
    let e = load_chain(&path, Some("l2"), Some("base"), None, 4)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("tip frame 'base'") && e.contains("not below the base frame 'l2'"),
        "{e}"
    );
    // Through the command line, on the bundled UR5 cut at its wrist.
    let (ok, out, err) = kinsynth(&[
        "reach",
        "examples/scenarios/ur5-cell.toml",
        "--urdf",
        "examples/robots/ur5.urdf",
        "--base-frame",
        "link0",
        "--tip-frame",
        "link5",
        "--radius",
        "0.04",
    ]);
    assert!(ok, "{err}");
    assert!(out.starts_with("R = "), "{out}");
    let (ok, _, err) = kinsynth(&[
        "reach",
        "examples/scenarios/ur5-cell.toml",
        "--tip-frame",
        "x",
    ]);
    assert!(!ok && err.contains("--urdf"), "{err}");
}

/// A URDF of two links of `plates` thin boxes each, interleaved (a prismatic joint slides the
/// second link's plates between the first's, 0.02 mm apart at home and touching over 98 % of
/// its travel), with a small link between them so that they are not adjacent.
fn interleaved_plates(plates: usize) -> String {
    let mut s = String::from(
        "<robot name=\"plates\">\n<link name=\"base\"><collision><geometry>\
         <box size=\"0.05 0.05 0.05\"/></geometry></collision></link>\n",
    );
    for (name, offset) in [("a", 0.0), ("b", 0.001)] {
        s.push_str(&format!("<link name=\"{name}\">\n"));
        for i in 0..plates {
            let z = 0.5 + i as f64 * 0.002 + offset;
            s.push_str(&format!(
                "<collision><origin xyz=\"0.3 0 {z:.6}\"/><geometry>\
                 <box size=\"0.3 0.3 0.00098\"/></geometry></collision>\n"
            ));
        }
        s.push_str("</link>\n");
    }
    s.push_str(
        "<link name=\"m\"><collision><origin xyz=\"-0.5 0 0\"/><geometry>\
         <box size=\"0.01 0.01 0.01\"/></geometry></collision></link>\n<link name=\"c\"/>\n\
         <joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"a\"/>\
         <axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/></joint>\n\
         <joint name=\"jm\" type=\"revolute\"><parent link=\"a\"/><child link=\"m\"/>\
         <axis xyz=\"0 0 1\"/><limit lower=\"-0.001\" upper=\"0.001\" effort=\"1\" velocity=\"1\"/></joint>\n\
         <joint name=\"j2\" type=\"prismatic\"><parent link=\"m\"/><child link=\"b\"/>\
         <axis xyz=\"0 0 1\"/><limit lower=\"-0.002\" upper=\"0\" effort=\"1\" velocity=\"1\"/></joint>\n\
         <joint name=\"j3\" type=\"revolute\"><parent link=\"b\"/><child link=\"c\"/>\
         <origin xyz=\"0.5 0 0\"/><axis xyz=\"0 0 1\"/>\
         <limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/></joint>\n</robot>\n",
    );
    s
}

/// The "Always" rule's sampling is bounded by its work, not by its sample count alone: two
/// links of 499 interleaved plates (249,001 body pairs measured per sample) took 68 s at the
/// default 1,000 samples and would have taken two hours at 100,000. The sampling stops at
/// `MAX_SELF_COLLISION_WORK`, and the pairs it has not decided stay checked (19 samples cannot
/// tell "always" from "often"); a few plates take every sample and are found "Always" in
/// contact.
#[test]
fn self_collision_sampling_is_bounded_by_its_work() {
    use kinsynth::collision::body::acm::Reason;
    let dir = tempfile::tempdir().unwrap();
    let options = |samples: usize| kinsynth::import::ImportOptions {
        self_collision: kinsynth::collision::SelfCollisionConfig {
            samples,
            ..Default::default()
        },
        ..Default::default()
    };
    let most = kinsynth::limits::MAX_SELF_COLLISION_SAMPLES;
    let import = |plates: usize, samples: usize| {
        let path = dir.path().join(format!("plates{plates}.urdf"));
        std::fs::write(&path, interleaved_plates(plates)).unwrap();
        kinsynth::import::load_robot(&path, None, None, None, 4, &options(samples)).unwrap()
    };
    let plates_pair = |acm: &kinsynth::collision::body::AllowedCollisions| {
        acm.disabled()
            .iter()
            .find(|d| (d.link1.as_str(), d.link2.as_str()) == ("a", "b"))
            .map(|d| d.reason)
    };
    let r = import(499, most);
    let acm = r.body.acm();
    let taken = acm.samples_taken();
    assert!(
        acm.work_limited(),
        "499 plates: {taken} samples, not limited"
    );
    assert!((1..1_000).contains(&taken), "499 plates: {taken} samples");
    // Undecided: the plates' pairs stay checked (all 249,001 of them).
    assert_eq!(plates_pair(acm), None);
    assert!(acm.pairs().len() >= 499 * 499, "{}", acm.pairs().len());
    // Through the binary: a note says so, and the SRDF in a comment, leaving the pair enabled.
    let srdf = dir.path().join("plates.srdf");
    let out = Command::new(env!("CARGO_BIN_EXE_kinsynth"))
        .arg("reach")
        .arg(root().join("examples/scenarios/ur5-cell.toml"))
        .arg("--urdf")
        .arg(dir.path().join("plates499.urdf"))
        .arg("--write-srdf")
        .arg(&srdf)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "the self-collision sampling stopped after {taken} random configurations"
        )) && stderr.contains("the pairs it had not decided stay checked"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(&srdf).unwrap();
    assert!(
        text.contains("the pairs it had not decided stay enabled -->"),
        "{text}"
    );
    assert!(!text.contains("link1=\"a\" link2=\"b\""), "{text}");
    // Three plates: every sample taken (they touch in about 98 % of them).
    let r = import(3, most);
    let acm = r.body.acm();
    assert!(!acm.work_limited());
    assert_eq!(acm.samples_taken(), most);
    assert_eq!(plates_pair(acm), Some(Reason::Always));
    // The bundled arms stay far below the limit at the largest sample count.
    for arm in ["ur5.urdf", "mesh_arm.urdf"] {
        let path = root().join("examples/robots").join(arm);
        let r = kinsynth::import::load_robot(&path, None, None, None, 4, &options(most)).unwrap();
        assert!(!r.body.acm().work_limited(), "{arm}");
    }
}
