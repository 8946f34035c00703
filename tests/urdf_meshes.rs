//! URDF import with the links' collision meshes as bodies: the generated mesh arm, its hulls
//! and carriers, `certified` against the oracle with the meshes, a path that capsules call
//! free but the meshes block, named errors, SRDF pairs, and the design → URDF → reach round
//! trip in collision mode.

use kinsynth::collision::body::Placed;
use kinsynth::collision::oracle::{judge_edge, sample_edges, ORACLE_SUBSTEPS};
use kinsynth::collision::{
    make_checker, BodyModel, CheckerKind, CollisionScene, RobotBody, Scratch,
};
use kinsynth::import::body::{load_hull, resolve_mesh};
use kinsynth::import::{load_robot, BodyChoice, BodyKind, ImportOptions, ImportedRobot};
use kinsynth::planning::ReachReport;
use kinsynth::world::{Obstacle, ObstacleShape, Workspace};
use nalgebra::Point3;
use parry3d_f64::shape::ShapeType;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The mesh arm's URDF text with every mesh reference (relative, or `package://meshes/`) made
/// absolute (`abs`: the repository's `meshes/` folder, with its slash), for a copy written
/// outside the repository: no folder above it need hold the meshes.
fn absolute_meshes(text: &str, abs: &str) -> String {
    text.replace("../../meshes/", abs)
        .replace("package://meshes/", abs)
}

fn arm_urdf() -> PathBuf {
    root().join("examples/robots/mesh_arm.urdf")
}

fn import(path: &Path, options: &ImportOptions) -> ImportedRobot {
    load_robot(path, None, None, None, 3, options).unwrap()
}

/// The robot of `path` imported with the pairs of the SRDF `srdf` left unchecked.
fn import_with_srdf(path: &Path, srdf: PathBuf) -> ImportedRobot {
    let options = ImportOptions {
        srdf: Some(srdf),
        ..ImportOptions::default()
    };
    import(path, &options)
}

fn arm() -> ImportedRobot {
    import(&arm_urdf(), &ImportOptions::default())
}

/// Volume and bounding box of a mesh file, straight from its triangles.
fn mesh_volume_and_box(path: &Path) -> (f64, [f64; 3], [f64; 3]) {
    let scene = mesh_loader::Loader::default().load(path).unwrap();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let mut vol = 0.0;
    for m in &scene.meshes {
        for f in &m.faces {
            let [a, b, c] = f.map(|i| m.vertices[i as usize].map(f64::from));
            for p in [a, b, c] {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0;
        }
    }
    (vol, lo, hi)
}

#[test]
fn the_mesh_arm_imports_with_its_meshes_as_bodies() {
    let r = arm();
    assert_eq!(r.kind, BodyKind::Solids);
    assert!(r.note.is_none());
    let chain = &r.urdf.chain;
    assert_eq!(chain.dof(), 6);
    assert_eq!(chain.segment_count(), 0, "no capsule segments");
    assert_eq!(chain.colliders_per_link(), 0);
    let body = &r.body;
    assert_eq!(body.segments(), 0);
    // Seven meshes (base and six links) and the gripper box on link6.
    let kinds: Vec<(String, usize, ShapeType)> = body
        .solids()
        .iter()
        .map(|s| (s.frame.clone(), s.level, s.shape.shape_type()))
        .collect();
    let mut expected: Vec<(String, usize, ShapeType)> = ["base_link", "link1", "link2", "link3"]
        .iter()
        .chain(&["link4", "link5", "link6"])
        .enumerate()
        .map(|(k, n)| (n.to_string(), k, ShapeType::ConvexPolyhedron))
        .collect();
    expected.push(("link6".into(), 6, ShapeType::Cuboid));
    assert_eq!(kinds, expected);
    // Each hull has the mesh's volume and extents (the meshes are convex).
    let files = [
        "base_link.stl",
        "link1.stl",
        "link2.dae",
        "link3.dae",
        "link4.stl",
        "link5.dae",
        "link6.stl",
    ];
    for (s, f) in body.solids().iter().zip(files) {
        let (vol, lo, hi) = mesh_volume_and_box(&root().join("meshes/arm").join(f));
        assert!(vol > 1e-5, "{f}: volume {vol}");
        let hull_vol = s.shape.mass_properties(1.0).mass();
        assert!(
            (hull_vol - vol).abs() < 1e-6 * vol.max(1.0) + 1e-9,
            "{f}: hull volume {hull_vol} vs mesh {vol}"
        );
        let aabb = s.shape.compute_local_aabb();
        let (mn, mx) = (aabb.mins, aabb.maxs);
        for k in 0..3 {
            assert!(
                (mn[k] - lo[k]).abs() < 1e-6,
                "{f}: min {k} {} {}",
                mn[k],
                lo[k]
            );
            assert!(
                (mx[k] - hi[k]).abs() < 1e-6,
                "{f}: max {k} {} {}",
                mx[k],
                hi[k]
            );
        }
    }
    // Carriers: at home the arm stands upright; link2's block spans z 0.17 … 0.67 (joint 2 at
    // 0.22) and rotates with joints 1 and 2.
    let mut frames = chain.frames();
    let mut placed = kinsynth::collision::body::Placed::default();
    let world_box = |placed: &kinsynth::collision::body::Placed, s: usize| {
        let a = body.solids()[s].shape.compute_aabb(&placed.poses[s]);
        (a.mins, a.maxs)
    };
    chain.fk(chain.home(), &mut frames);
    body.place(&frames, &mut placed);
    let (mn, mx) = world_box(&placed, 2);
    assert!(
        (mn.z - 0.17).abs() < 1e-6 && (mx.z - 0.67).abs() < 1e-6,
        "{mn:?} {mx:?}"
    );
    assert!((mn.x + 0.09).abs() < 1e-6 && (mx.y - 0.06).abs() < 1e-6);
    let mut q = chain.home().to_vec();
    q[0] = FRAC_PI_2; // joint 1 turns the wide block: x and y extents swap
    q[1] = FRAC_PI_2; // joint 2 lays it along +x, pivoting at z = 0.22
    chain.fk(&q, &mut frames);
    body.place(&frames, &mut placed);
    let (mn, mx) = world_box(&placed, 2);
    assert!((mn.z - (0.22 - 0.09)).abs() < 1e-6, "{mn:?}");
    assert!((mx.z - (0.22 + 0.09)).abs() < 1e-6, "{mx:?}");
    assert!(
        (mn.y + 0.45).abs() < 1e-6 || (mx.y - 0.45).abs() < 1e-6,
        "{mn:?} {mx:?}"
    );
    // The same kinematics as the capsule import.
    let caps = import(
        &arm_urdf(),
        &ImportOptions {
            body: BodyChoice::Capsules,
            ..ImportOptions::default()
        },
    );
    assert_eq!(caps.kind, BodyKind::Capsules);
    assert!(caps.urdf.chain.segment_count() > 0);
    let mut fc = caps.urdf.chain.frames();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..100 {
        chain.sample_config(&mut rng, &mut q);
        chain.fk(&q, &mut frames);
        caps.urdf.chain.fk(&q, &mut fc);
        assert_eq!(frames.frames, fc.frames);
        assert_eq!(frames.axis_frames, fc.axis_frames);
    }
    assert_eq!(caps.urdf.chain.layout().joint, chain.layout().joint);
    assert_eq!(caps.urdf.chain.layout().axis, chain.layout().axis);
}

#[test]
fn package_and_relative_mesh_paths_resolve() {
    let urdf = arm_urdf();
    let by_search = resolve_mesh("package://meshes/arm/link2.dae", &urdf, &[]).unwrap();
    assert_eq!(
        std::fs::canonicalize(by_search).unwrap(),
        std::fs::canonicalize(root().join("meshes/arm/link2.dae")).unwrap()
    );
    let given = resolve_mesh(
        "package://robot_description/meshes/a.stl",
        &urdf,
        &[("robot_description".into(), PathBuf::from("/opt/rd"))],
    )
    .unwrap();
    assert_eq!(given, PathBuf::from("/opt/rd/meshes/a.stl"));
    let rel = resolve_mesh("../../meshes/arm/link1.stl", &urdf, &[]).unwrap();
    assert_eq!(
        rel,
        root().join("examples/robots/../../meshes/arm/link1.stl")
    );
    let file = resolve_mesh("file://m/x.obj", &urdf, &[]).unwrap();
    assert_eq!(file, root().join("examples/robots/m/x.obj"));
    assert_eq!(
        resolve_mesh("file:///abs/x.obj", &urdf, &[]).unwrap(),
        PathBuf::from("/abs/x.obj")
    );
    let e = resolve_mesh("package://no_such_pkg/x.stl", &urdf, &[]).unwrap_err();
    assert!(e.contains("no_such_pkg") && e.contains("--package"), "{e}");
    // OBJ reads too, with its scale.
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("t.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let (hull, _) = load_hull(&obj, [2.0, 2.0, 2.0]).unwrap();
    let v = hull.mass_properties(1.0).mass();
    assert!((v - 8.0 / 6.0).abs() < 1e-9, "{v}");
}

/// A cluttered cell around the mesh arm: spheres and boxes, none touching the arm at home.
fn cluttered(body: &RobotBody, chain: &kinsynth::kinematics::Chain) -> Arc<CollisionScene> {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut frames = chain.frames();
    let mut placed = Default::default();
    chain.fk(chain.home(), &mut frames);
    body.place(&frames, &mut placed);
    let mut obstacles = Vec::new();
    while obstacles.len() < 24 {
        let c = Point3::new(
            rng.random_range(-0.9..0.9),
            rng.random_range(-0.9..0.9),
            rng.random_range(0.0..1.3),
        );
        let o = if obstacles.len() % 3 == 0 {
            let h = rng.random_range(0.06..0.2);
            Obstacle::new(
                "box",
                ObstacleShape::Cuboid { size: [h, h, h] },
                nalgebra::IsometryMatrix3::translation(c.x, c.y, c.z),
            )
        } else {
            Obstacle::sphere("ball", c, rng.random_range(0.03..0.12))
        }
        .unwrap();
        let w = Workspace::new(vec![o.clone()], vec![Point3::new(0.0, 0.0, 5.0)], 0.0).unwrap();
        let s = CollisionScene::new(&w);
        if body.min_obstacle_distance(&s, &frames, &placed) > 0.05 {
            obstacles.push(o);
        }
    }
    let w = Workspace::new(obstacles, vec![Point3::new(0.0, 0.0, 5.0)], 0.005).unwrap();
    Arc::new(CollisionScene::new(&w))
}

#[test]
fn certified_has_no_false_free_edge_with_the_mesh_arm() {
    let r = arm();
    let chain = &r.urdf.chain;
    let body = Arc::new(r.body);
    assert!(
        body.self_pairs().len() >= 5,
        "self pairs checked: {}",
        body.self_pairs().len()
    );
    let scene = cluttered(&body, chain);
    let certified = make_checker(CheckerKind::Certified, scene.clone(), BodyModel::Capsules);
    let mut scratch = Scratch::with_body(chain, body.clone());
    let start = std::time::Instant::now();
    let (mut edges, mut blocked, mut self_blocked, mut proven) = (0, 0, 0, 0);
    for (l_max, seed) in [(PI / 8.0, 1), (PI / 4.0, 2)] {
        for (a, b) in sample_edges(&scene, chain, &body, l_max, 0.1, 1000, seed) {
            let oracle = judge_edge(&scene, chain, &body, &a, &b, ORACLE_SUBSTEPS);
            let free = certified.edge_free(chain, &a, &b, &mut scratch);
            assert!(
                !free || oracle.free,
                "certified called a colliding edge free: {a:?} → {b:?}, hit at t = {:?}",
                oracle.first_hit
            );
            edges += 1;
            blocked += usize::from(!oracle.free);
            self_blocked += usize::from(!oracle.free && oracle.min_self_distance <= 0.0);
            proven += usize::from(free);
        }
    }
    eprintln!(
        "mesh arm: {edges} edges, {blocked} blocked ({self_blocked} by self-collision), {proven} proven free, 0 false free, {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert!(edges >= 2000, "{edges} edges");
    assert!(blocked >= 50, "too few colliding edges: {blocked}");
    assert!(self_blocked >= 1, "no edge blocked by self-collision");
    assert!(proven >= 500, "certified proves too little: {proven}");
}

#[test]
fn capsules_call_free_a_path_that_the_meshes_block() {
    // A small ball beside the upper arm, 0.1 m from the joint-1 axis at 45°: the capsule of
    // the default radius (0.05) around the axis never comes near it, but turning joint 1 by
    // 90° sweeps the wide block's corner (0.0985 m from the axis) through it.
    let ball = Obstacle::sphere(
        "ball",
        Point3::new(0.1 * (PI / 4.0).cos(), 0.1 * (PI / 4.0).sin(), 0.45),
        0.01,
    )
    .unwrap();
    let w = Workspace::new(vec![ball], vec![Point3::new(0.0, 0.0, 5.0)], 0.0).unwrap();
    let scene = Arc::new(CollisionScene::new(&w));
    let meshes = arm();
    let caps = import(
        &arm_urdf(),
        &ImportOptions {
            body: BodyChoice::Capsules,
            ..ImportOptions::default()
        },
    );
    let from = meshes.urdf.chain.home().to_vec();
    let mut to = from.clone();
    to[0] = FRAC_PI_2;
    for (r, hits) in [(&caps, false), (&meshes, true)] {
        let chain = &r.urdf.chain;
        let body = Arc::new(r.body.clone());
        let oracle = judge_edge(&scene, chain, &body, &from, &to, ORACLE_SUBSTEPS);
        assert_eq!(!oracle.free, hits, "{:?}: oracle {oracle:?}", r.kind);
        let mut scratch = Scratch::with_body(chain, body);
        let c = make_checker(CheckerKind::Certified, scene.clone(), BodyModel::Capsules);
        assert!(c.node_free(chain, &from, &mut scratch), "home is free");
        assert!(c.node_free(chain, &to, &mut scratch), "end is free");
        assert_eq!(
            c.edge_free(chain, &from, &to, &mut scratch),
            !hits,
            "certified with {:?}",
            r.kind
        );
    }
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

/// The mesh arm's URDF with `from` replaced by `to`, written into `dir`.
fn variant(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(arm_urdf()).unwrap();
    assert!(text.contains(from), "{from}");
    let p = dir.join(name);
    let abs = format!("{}/meshes/", root().display());
    std::fs::write(&p, absolute_meshes(&text.replace(from, to), &abs)).unwrap();
    p
}

fn reach_err(args: &[&str]) -> String {
    let mut all = vec!["reach", "examples/scenarios/ur5-cell.toml"];
    all.extend_from_slice(args);
    let (ok, out, err) = kinsynth(&all);
    assert!(!ok, "should fail: {out}");
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    err
}

#[test]
fn mesh_errors_name_the_urdf_the_link_and_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let meshes = format!("meshes={}", root().join("meshes").display());
    let check = |err: &str, urdf: &Path, needles: &[&str]| {
        assert!(err.contains(&urdf.display().to_string()), "{err}");
        for n in needles {
            assert!(err.contains(n), "missing {n:?} in {err}");
        }
    };
    // Relative paths in the copies point into the temporary folder; package:// goes through
    // --package.
    let missing = variant(
        d,
        "missing.urdf",
        "../../meshes/arm/link3.dae",
        "no_such_mesh.stl",
    );
    let err = reach_err(&["--urdf", missing.to_str().unwrap(), "--package", &meshes]);
    check(
        &err,
        &missing,
        &["link 'link3'", "no_such_mesh.stl", "cannot read"],
    );

    // A COLLADA file above its 64 MiB limit (sparse) is refused by its size, not read.
    std::fs::File::create(d.join("big.dae"))
        .unwrap()
        .set_len((64 << 20) + 1)
        .unwrap();
    let big = variant(d, "big.urdf", "../../meshes/arm/link3.dae", "big.dae");
    let err = reach_err(&["--urdf", big.to_str().unwrap(), "--package", &meshes]);
    check(
        &err,
        &big,
        &[
            "link 'link3'",
            "big.dae",
            "67108865 bytes",
            "limit of 67108864",
        ],
    );

    std::fs::write(d.join("empty.stl"), b"").unwrap();
    let empty = variant(d, "empty.urdf", "../../meshes/arm/link1.stl", "empty.stl");
    let err = reach_err(&["--urdf", empty.to_str().unwrap(), "--package", &meshes]);
    check(&err, &empty, &["link 'link1'", "empty.stl", "empty"]);

    std::fs::write(d.join("link1.ply"), b"ply\n").unwrap();
    let ply = variant(d, "ply.urdf", "../../meshes/arm/link1.stl", "link1.ply");
    let err = reach_err(&["--urdf", ply.to_str().unwrap(), "--package", &meshes]);
    check(
        &err,
        &ply,
        &[
            "link 'link1'",
            "link1.ply",
            "unknown file extension \"ply\" (expected .stl, .obj or .dae)",
        ],
    );

    std::fs::write(d.join("none.stl"), b"solid none\nendsolid none\n").unwrap();
    let none = variant(d, "none.urdf", "../../meshes/arm/link5.dae", "none.stl");
    let err = reach_err(&["--urdf", none.to_str().unwrap(), "--package", &meshes]);
    check(&err, &none, &["link 'link5'", "none.stl", "no triangles"]);

    // Triangles of zero area are refused, as in a scenario; a flat mesh is a two-sided plate
    // and is read.
    std::fs::write(
        d.join("line.obj"),
        b"v 0 0 0\nv 0.1 0 0\nv 0.2 0 0\nf 1 2 3\n",
    )
    .unwrap();
    let line = variant(d, "line.urdf", "../../meshes/arm/link5.dae", "line.obj");
    let err = reach_err(&["--urdf", line.to_str().unwrap(), "--package", &meshes]);
    check(
        &err,
        &line,
        &[
            "link 'link5'",
            "line.obj",
            "mesh is degenerate: every triangle has zero area",
        ],
    );
    let plate = b"v 0 0 0\nv 0.04 0 0\nv 0.04 0.04 0\nv 0 0.04 0\nf 1 2 3\nf 1 3 4\n";
    std::fs::write(d.join("plate.obj"), plate).unwrap();
    let plate = variant(d, "plate.urdf", "../../meshes/arm/link5.dae", "plate.obj");
    let options = kinsynth::import::ImportOptions::default();
    let robot = kinsynth::import::load_robot(&plate, None, None, None, 4, &options).unwrap();
    assert!(!robot.body.is_empty());

    // Outside the repository no folder named `meshes` lies above the copy.
    let pkg = variant(
        d,
        "pkg.urdf",
        "package://meshes/arm/link2.dae",
        "package://no_such_pkg/link2.dae",
    );
    let err = reach_err(&["--urdf", pkg.to_str().unwrap(), "--package", &meshes]);
    check(
        &err,
        &pkg,
        &[
            "link 'link2'",
            "package://no_such_pkg/link2.dae",
            "no_such_pkg",
        ],
    );

    let srdf = d.join("arm.srdf");
    std::fs::write(
        &srdf,
        "<robot name=\"mesh_arm\">\n<disable_collisions link1=\"link2\" link2=\"link9\" reason=\"Never\"/>\n</robot>\n",
    )
    .unwrap();
    let urdf = arm_urdf();
    let err = reach_err(&[
        "--urdf",
        urdf.to_str().unwrap(),
        "--srdf",
        srdf.to_str().unwrap(),
    ]);
    check(&err, &urdf, &["arm.srdf", "link9", "line 2"]);

    let (ok, _, err) = kinsynth(&[
        "reach",
        "examples/scenarios/ur5-cell.toml",
        "--urdf",
        urdf.to_str().unwrap(),
        "--package",
        "nodir",
    ]);
    assert!(!ok && err.contains("NAME=DIR"), "{err}");
}

/// An OBJ of four vertices and one polygon fanned into `triangles` triangles (a small file
/// that builds a large mesh).
fn fan_obj(path: &Path, triangles: usize) {
    let corners = ["1", "2", "3", "4"];
    let face: Vec<&str> = (0..triangles + 2).map(|i| corners[i % 4]).collect();
    let text = format!(
        "v 0 0 0\nv 0.1 0 0\nv 0.1 0.1 0\nv 0 0.1 0.1\nf {}\n",
        face.join(" ")
    );
    std::fs::write(path, text).unwrap();
}

/// A URDF's STL and OBJ collision meshes are read as a scenario's: a binary STL's count is
/// checked, an OBJ's material library is never opened, a file holds at most
/// `MAX_MESH_TRIANGLES` triangles and all the hulls built (each file at each scale) as many.
#[test]
fn urdf_meshes_are_read_with_the_scenario_limits() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let with = |name: &str, mesh: &str| variant(d, name, "../../meshes/arm/link5.dae", mesh);
    // A material library that cannot be read as one: never opened, the mesh is read.
    std::fs::write(d.join("bad.mtl"), "newmtl\nKd x y z\n").unwrap();
    std::fs::write(
        d.join("tet.obj"),
        "mtllib bad.mtl\nv 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n",
    )
    .unwrap();
    let tet = with("tet.urdf", "tet.obj");
    let (ok, _, err) = kinsynth(&[
        "reach",
        "examples/scenarios/ur5-cell.toml",
        "--urdf",
        tet.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");

    // A binary STL whose header declares fewer triangles than it holds.
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&1u32.to_le_bytes());
    for t in 0..2 {
        stl.extend_from_slice(&[0u8; 12]);
        for v in [
            [0.0f32, 0.0, 0.0],
            [0.05, 0.0, t as f32 * 0.05],
            [0.0, 0.05, 0.0],
        ] {
            for x in v {
                stl.extend_from_slice(&x.to_le_bytes());
            }
        }
        stl.extend_from_slice(&[0u8; 2]);
    }
    std::fs::write(d.join("count.stl"), stl).unwrap();
    let count = with("count.urdf", "count.stl");
    let err = reach_err(&["--urdf", count.to_str().unwrap()]);
    assert!(
        err.contains("count.stl") && err.contains("the count is wrong"),
        "{err}"
    );

    // One file beyond the limit: refused before its triangles are built.
    let limit = kinsynth::limits::MAX_MESH_TRIANGLES;
    fan_obj(&d.join("huge.obj"), limit + 1);
    let huge = with("huge.urdf", "huge.obj");
    let err = reach_err(&["--urdf", huge.to_str().unwrap()]);
    assert!(
        err.contains("huge.obj") && err.contains(&format!("more than the limit of {limit}")),
        "{err}"
    );

    // Two scales of a file of 3/5 of the limit: the second hull is refused.
    fan_obj(&d.join("big.obj"), 3 * limit / 5);
    let text = std::fs::read_to_string(with("big1.urdf", "big.obj")).unwrap();
    let twice = text.replacen(
        &format!(
            "{}/meshes/arm/link3.dae\" scale=\"1 1 1\"",
            root().display()
        ),
        &format!("{}\" scale=\"2 2 2\"", d.join("big.obj").display()),
        1,
    );
    assert_ne!(twice, text);
    std::fs::write(d.join("twice.urdf"), twice).unwrap();
    let err = reach_err(&["--urdf", d.join("twice.urdf").to_str().unwrap()]);
    assert!(
        err.contains("collision meshes (each file at each scale) hold"),
        "{err}"
    );
}

#[test]
fn srdf_pairs_are_never_checked() {
    let r = arm();
    let find = |body: &RobotBody, a: &str, b: &str| {
        body.self_pairs().iter().any(|&(p, q)| {
            let (x, y) = (body.frame(p as usize), body.frame(q as usize));
            (x == a && y == b) || (x == b && y == a)
        })
    };
    assert!(find(&r.body, "link1", "link3"), "link1–link3 is checked");
    assert!(find(&r.body, "base_link", "link4"));
    let dir = tempfile::tempdir().unwrap();
    let srdf = dir.path().join("arm.srdf");
    std::fs::write(
        &srdf,
        r#"<?xml version="1.0"?>
<robot name="mesh_arm">
  <group name="arm"><chain base_link="base_link" tip_link="tool0"/></group>
  <disable_collisions link1="link1" link2="link3" reason="Never"/>
  <disable_collisions link1="link4" link2="base_link" reason="Always"/>
  <disable_collisions link1="tool0" link2="base_link" reason="Never"/>
</robot>
"#,
    )
    .unwrap();
    let s = import_with_srdf(&arm_urdf(), srdf);
    assert!(!find(&s.body, "link1", "link3"));
    assert!(!find(&s.body, "base_link", "link4"));
    assert_eq!(
        s.body.self_pairs().len(),
        r.body.self_pairs().len() - 2,
        "only those two pairs go"
    );
    assert!(s
        .body
        .acm()
        .disabled()
        .iter()
        .any(|d| d.link1 == "link1" && d.link2 == "link3"));
}

#[test]
fn a_robot_without_collision_geometry_falls_back_to_capsules() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(arm_urdf()).unwrap();
    let stripped: String = text
        .lines()
        .filter(|l| !l.contains("<collision"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(!stripped.contains("<collision"));
    let p = dir.path().join("bare.urdf");
    std::fs::write(&p, stripped).unwrap();
    let r = import(&p, &ImportOptions::default());
    assert_eq!(r.kind, BodyKind::Capsules);
    assert!(r.note.as_deref().unwrap().contains("no <collision>"));
    assert_eq!(r.body.segments(), r.urdf.chain.segment_count());
    let (ok, _, err) = kinsynth(&[
        "reach",
        "examples/scenarios/ur5-cell.toml",
        "--urdf",
        p.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(err.contains("note:") && err.contains("capsules"), "{err}");
}

fn read_report(p: &Path) -> ReachReport {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn design_urdf_reach_round_trip_gives_the_same_bodies_and_paths() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scn3 = d.join("p3.toml");
    let (ok, _, err) = kinsynth(&[
        "scenario",
        "--preset",
        "paper-3d",
        "--seed",
        "2",
        "-o",
        scn3.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let scn2 = root().join("examples/scenarios/paper-2d.toml");
    for scn in [scn3, scn2] {
        let s = kinsynth::Scenario::load(&scn).unwrap();
        let design = s.space.largest();
        let dj = d.join("design.json");
        std::fs::write(&dj, design.to_json()).unwrap();
        let urdf = d.join("robot.urdf");
        kinsynth::export::write_urdf(&design, &urdf).unwrap();
        // The imported body is the design's, pair for pair.
        let r = import(
            &urdf,
            &ImportOptions {
                self_collision: s.planner.self_collision.clone(),
                ..ImportOptions::default()
            },
        );
        assert_eq!(r.kind, BodyKind::CollisionCapsules, "{}", scn.display());
        let chain = design.chain();
        let own = RobotBody::new(&chain, Vec::new(), &s.planner.self_collision);
        assert_eq!(r.body.len(), own.len());
        for b in 0..own.len() {
            assert_eq!(r.body.radius(b), own.radius(b));
            assert_eq!(r.body.level(b), own.level(b));
            assert_eq!(r.body.frame(b), own.frame(b));
        }
        assert_eq!(r.body.self_pairs(), own.self_pairs());
        assert_eq!(r.body.acm().disabled(), own.acm().disabled());
        let mut reports = Vec::new();
        for (k, extra) in [
            vec!["--design", dj.to_str().unwrap()],
            vec!["--urdf", urdf.to_str().unwrap()],
            vec!["--urdf", urdf.to_str().unwrap(), "--body", "capsules"],
        ]
        .into_iter()
        .enumerate()
        {
            let json = d.join(format!("r{k}.json"));
            let mut args = vec![
                "reach",
                scn.to_str().unwrap(),
                "--json",
                json.to_str().unwrap(),
            ];
            args.extend(extra);
            let (ok, _, err) = kinsynth(&args);
            assert!(ok, "{err}");
            reports.push(read_report(&json));
        }
        let a = &reports[0];
        eprintln!(
            "round trip on {}: R = {} ({} nodes, {} edge checks)",
            scn.display(),
            a.reachability,
            a.nodes,
            a.edge_checks
        );
        assert!(a.reached() > 0, "the test needs reached tasks");
        for b in &reports[1..] {
            assert_eq!(a.reachability, b.reachability);
            assert_eq!(a.nodes, b.nodes);
            assert_eq!(a.edge_checks, b.edge_checks);
            for (x, y) in a.targets.iter().zip(&b.targets) {
                assert_eq!(x.reached, y.reached);
                assert_eq!(
                    x.path.as_ref().map(|p| &p.points),
                    y.path.as_ref().map(|p| &p.points),
                    "task {}",
                    x.index
                );
            }
        }
    }
}

#[test]
fn merged_co_located_joints_carry_their_intermediate_links() {
    // Joints a (about x) and b (about y, identity origin) merge into one chain link; the
    // intermediate link `mid` turns with a only, `tip_link` with a and b.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("merged.urdf");
    let boxed = |name: &str| {
        format!("<link name=\"{name}\"><collision><origin xyz=\"0 0 0.2\" rpy=\"0 0 0\"/><geometry><box size=\"0.02 0.02 0.02\"/></geometry></collision></link>")
    };
    let joint = |name: &str, parent: &str, child: &str, z: f64, axis: &str| {
        format!("<joint name=\"{name}\" type=\"revolute\"><parent link=\"{parent}\"/><child link=\"{child}\"/><origin xyz=\"0 0 {z}\" rpy=\"0 0 0\"/><axis xyz=\"{axis}\"/><limit lower=\"-2\" upper=\"2\" effort=\"1\" velocity=\"1\"/></joint>")
    };
    let text = format!(
        "<robot name=\"m\"><link name=\"base\"/>{}{}<link name=\"tool\"/>{}{}<joint name=\"t\" type=\"fixed\"><parent link=\"tip_link\"/><child link=\"tool\"/><origin xyz=\"0 0 0.3\" rpy=\"0 0 0\"/></joint></robot>",
        boxed("mid"),
        boxed("tip_link"),
        joint("a", "base", "mid", 0.5, "1 0 0"),
        joint("b", "mid", "tip_link", 0.0, "0 1 0"),
    );
    std::fs::write(&p, text).unwrap();
    let r = import(&p, &ImportOptions::default());
    assert_eq!(r.kind, BodyKind::Solids);
    let chain = &r.urdf.chain;
    assert_eq!(chain.dof(), 2);
    assert_eq!(
        chain.free_axes()[0].link,
        chain.free_axes()[1].link,
        "merged"
    );
    let levels: Vec<(String, usize)> = r
        .body
        .solids()
        .iter()
        .map(|s| (s.frame.clone(), s.level))
        .collect();
    assert_eq!(
        levels,
        [("mid".to_string(), 1), ("tip_link".to_string(), 2)]
    );
    let (qa, qb) = (0.7, -1.1);
    let mut frames = chain.frames();
    let mut placed = kinsynth::collision::body::Placed::default();
    chain.fk(&[qa, qb], &mut frames);
    r.body.place(&frames, &mut placed);
    let rx = nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::x_axis(), qa);
    let ry = nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::y_axis(), qb);
    let o = nalgebra::Vector3::new(0.0, 0.0, 0.5);
    let mid = o + rx * nalgebra::Vector3::new(0.0, 0.0, 0.2);
    let tip = o + rx * (ry * nalgebra::Vector3::new(0.0, 0.0, 0.2));
    for (k, want) in [mid, tip].into_iter().enumerate() {
        let c = placed.centers[k];
        assert!((c.coords - want).norm() < 1e-12, "solid {k}: {c} vs {want}");
    }
}

/// Forward kinematics of the first links only (`Chain::fk_links`, which `certified` evaluates
/// at a bisection point when its remaining items are near the base) places every body within
/// them, segments and solids, exactly as the full evaluation does, whatever the buffers held
/// before; with every link it is the full evaluation, the TCP included.
#[test]
fn forward_kinematics_of_the_first_links_places_their_bodies_as_the_full_one() {
    let paper = kinsynth::Scenario::load(&root().join("examples/scenarios/paper-3d.toml")).unwrap();
    let paper_chain = paper.space.largest().chain();
    let robots = [
        (paper_chain.clone(), RobotBody::of_chain(&paper_chain)),
        (arm().urdf.chain, arm().body),
        {
            let ur5 = import(
                &root().join("examples/robots/ur5.urdf"),
                &ImportOptions::default(),
            );
            (ur5.urdf.chain, ur5.body)
        },
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut solids_seen = 0;
    for (chain, body) in &robots {
        let n = chain.link_count();
        let dof = chain.dof();
        let (mut a, mut other) = (vec![0.0; dof], vec![0.0; dof]);
        let (mut full, mut part) = (chain.frames(), chain.frames());
        let (mut pf, mut pp) = (Placed::default(), Placed::default());
        let (mut partial_bodies, mut stale) = (0, 0);
        for _ in 0..20 {
            chain.sample_config(&mut rng, &mut a);
            chain.sample_config(&mut rng, &mut other);
            chain.fk(&a, &mut full);
            body.place(&full, &mut pf);
            for links in 0..=n {
                // Stale buffers: those of another configuration.
                chain.fk(&other, &mut part);
                body.place(&part, &mut pp);
                chain.fk_links(&a, &mut part, links);
                body.place_links(&part, &mut pp, links);
                for b in 0..body.len() {
                    let ns = body.segments();
                    let same = body.ball(&full, &pf, b) == body.ball(&part, &pp, b)
                        && if b < ns {
                            full.segments[b] == part.segments[b]
                        } else {
                            pf.poses[b - ns] == pp.poses[b - ns]
                        };
                    if body.fk_links(b) <= links {
                        assert!(same, "body {b} with {links} of {n} links");
                        solids_seen += usize::from(b >= ns);
                        partial_bodies += usize::from(links < n);
                    } else {
                        // Left as the other configuration placed it (a body turning about
                        // its own axis stays put, so only counted).
                        stale += usize::from(!same);
                    }
                }
            }
            assert_eq!(full.tcp, part.tcp, "all links: the TCP too");
            assert_eq!(full.axis_frames, part.axis_frames);
        }
        assert!(partial_bodies > 0 && stale > 0, "{partial_bodies} {stale}");
    }
    assert!(solids_seen > 0, "the imported arms carry solids");
}

/// A mesh or box element repeated exactly adds no body: 300 copies each of link 1's mesh and of
/// the gripper box import as the arm itself, with the same self pairs; a copy at another origin
/// is another body.
#[test]
fn repeated_collision_elements_add_no_body() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = r#"<collision><geometry><mesh filename="../../meshes/arm/link1.stl" scale="1 1 1"/></geometry></collision>"#;
    let gripper = r#"<collision name="gripper"><origin xyz="0 0 0.08" rpy="0 0 0"/><geometry><box size="0.06 0.02 0.08"/></geometry></collision>"#;
    let text = std::fs::read_to_string(arm_urdf()).unwrap();
    assert!(text.contains(mesh) && text.contains(gripper));
    let abs = format!("{}/meshes/", root().display());
    let write = |name: &str, text: String| {
        let p = dir.path().join(name);
        std::fs::write(&p, absolute_meshes(&text, &abs)).unwrap();
        p
    };
    let base = import(&write("base.urdf", text.clone()), &ImportOptions::default());
    let many = text
        .replace(mesh, &mesh.repeat(300))
        .replace(gripper, &gripper.repeat(300));
    let many = import(&write("many.urdf", many), &ImportOptions::default());
    assert_eq!(many.body.len(), base.body.len());
    assert_eq!(many.body.self_pairs(), base.body.self_pairs());
    let moved = mesh.replace("<geometry>", r#"<origin xyz="0 0 0.001"/><geometry>"#);
    let shifted = text.replace(mesh, &format!("{mesh}{moved}"));
    let shifted = import(&write("shifted.urdf", shifted), &ImportOptions::default());
    assert_eq!(shifted.body.len(), base.body.len() + 1);
}

/// A binary STL of a UV sphere of `radius` with `around × (around / 2)` quads (two triangles
/// each, one at each pole).
fn uv_sphere_stl(path: &Path, radius: f64, around: usize) {
    let rings = around / 2;
    let at = |i: usize, j: usize| -> [f32; 3] {
        let (theta, phi) = (
            PI * j as f64 / rings as f64,
            2.0 * PI * i as f64 / around as f64,
        );
        [
            (radius * theta.sin() * phi.cos()) as f32,
            (radius * theta.sin() * phi.sin()) as f32,
            (radius * theta.cos()) as f32,
        ]
    };
    let mut triangles = Vec::new();
    for i in 0..around {
        for j in 0..rings {
            let (a, b) = (at(i, j), at(i + 1, j));
            let (c, d) = (at(i, j + 1), at(i + 1, j + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    let mut bytes = vec![0u8; 80];
    bytes.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for t in &triangles {
        bytes.extend_from_slice(&[0u8; 12]);
        for v in t {
            for c in v {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0u8; 2]);
    }
    std::fs::write(path, bytes).unwrap();
}

/// A finely tessellated mesh becomes a hull of its distinct points, and elements naming the
/// same file at the same scale share that hull: 40 elements of a 19,600-triangle sphere import
/// as one shape (each read its file and built its hull: 100 elements of a 1M-triangle mesh
/// exhausted 4 GB).
#[test]
fn mesh_elements_share_one_hull_of_distinct_points() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = dir.path().join("sphere.stl");
    uv_sphere_stl(&sphere, 0.02, 140);
    let (hull, points) = load_hull(&sphere, [1.0, 1.0, 1.0]).unwrap();
    // The 140 triangles at the north pole have two corners there: lines, dropped (as by
    // Assimp-based readers); at the south pole sin π is not exactly 0, so its corners differ.
    assert_eq!(
        points,
        3 * (140 * 70 * 2 - 140),
        "points read, three per triangle"
    );
    let kept = hull.as_convex_polyhedron().unwrap().points().len();
    assert!(
        kept <= 140 * 69 + 2,
        "{kept} hull vertices for 9,662 distinct points"
    );
    let mesh = r#"<collision><geometry><mesh filename="../../meshes/arm/link1.stl" scale="1 1 1"/></geometry></collision>"#;
    let text = std::fs::read_to_string(arm_urdf()).unwrap();
    assert!(text.contains(mesh));
    let copies: String = (0..40)
        .map(|k| {
            format!(
                r#"<collision><origin xyz="0 0 {}"/><geometry><mesh filename="{}" scale="1 1 1"/></geometry></collision>"#,
                0.01 * k as f64,
                sphere.display()
            )
        })
        .collect();
    let text = absolute_meshes(
        &text.replace(mesh, &format!("{mesh}{copies}")),
        &format!("{}/meshes/", root().display()),
    );
    let p = dir.path().join("many.urdf");
    std::fs::write(&p, text).unwrap();
    let robot = import(&p, &ImportOptions::default());
    let spheres: Vec<_> = robot
        .body
        .solids()
        .iter()
        .filter(|s| {
            s.shape
                .as_convex_polyhedron()
                .is_some_and(|c| c.points().len() == kept)
        })
        .collect();
    assert_eq!(spheres.len(), 40);
    assert!(spheres
        .iter()
        .all(|s| Arc::ptr_eq(&s.shape.0, &spheres[0].shape.0)));
}

/// `reach --write-srdf` writes the pairs the run did not check, for the imported arm under its
/// own frame names: the computed matrix plus the pairs of `--srdf`, with the URDF's base and tip
/// as the planning group and its robot name; reading it back (as `--srdf`) checks exactly the same pairs. A path
/// shared with `--json`, and capsule bodies on frames the URDF does not have, fail before
/// anything is written.
#[test]
fn reach_writes_the_srdf_of_the_pairs_it_checked() {
    let dir = tempfile::tempdir().unwrap();
    let given = dir.path().join("given.srdf");
    std::fs::write(
        &given,
        "<robot name=\"mesh_arm\">\n<disable_collisions link1=\"link1\" link2=\"link3\" reason=\"Never\"/>\n</robot>\n",
    )
    .unwrap();
    let out = dir.path().join("checked.srdf");
    let urdf = arm_urdf();
    let (ok, stdout, err) = kinsynth(&[
        "reach",
        "examples/scenarios/ur5-cell.toml",
        "--urdf",
        urdf.to_str().unwrap(),
        "--srdf",
        given.to_str().unwrap(),
        "--write-srdf",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("checked.srdf"), "{stdout}");
    let text = std::fs::read_to_string(&out).unwrap();
    // Named as the URDF names its robot, not after the file (MoveIt requires the same name).
    assert!(text.contains("<robot name=\"mesh_arm\">"), "{text}");
    let body = import_with_srdf(&urdf, given);
    assert!(text.contains(&format!(
        "<chain base_link=\"{}\" tip_link=\"{}\"/>",
        body.urdf.base, body.urdf.tip
    )));
    assert!(text.contains("<disable_collisions link1=\"link1\" link2=\"link3\""));
    assert_eq!(
        text.matches("<disable_collisions").count(),
        body.body.acm().disabled().len()
    );
    // Read back, the written SRDF leaves exactly the pairs the run checked.
    let again = import_with_srdf(&urdf, out.clone());
    assert_eq!(again.body.self_pairs(), body.body.self_pairs());
    assert!(body.body.self_pairs().len() < arm().body.self_pairs().len());

    let json = dir.path().join("r.json");
    let (ok, _, err) = kinsynth(&[
        "reach",
        "examples/scenarios/ur5-cell.toml",
        "--json",
        json.to_str().unwrap(),
        "--write-srdf",
        json.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("--write-srdf") && err.lines().count() == 1,
        "{err}"
    );
    assert!(!json.exists());

    // Capsules between joint origins lie on frames the mesh arm's URDF does not have: no SRDF
    // can name them. Writing one is refused before any work, and an SRDF given for them is
    // refused, not ignored.
    let caps = dir.path().join("caps.srdf");
    // `reach` of the cell with the robot of `urdf`, its body `body`, and `flag file`.
    let reach_with = |urdf: &Path, body: &str, flag: &str, file: &Path| {
        kinsynth(&[
            "reach",
            "examples/scenarios/ur5-cell.toml",
            "--urdf",
            urdf.to_str().unwrap(),
            "--body",
            body,
            flag,
            file.to_str().unwrap(),
        ])
    };
    for (flag, file, name) in [
        ("--write-srdf", &caps, "caps.srdf"),
        ("--srdf", &out, "checked.srdf"),
    ] {
        let (ok, _, err) = reach_with(&urdf, "capsules", flag, file);
        assert!(
            !ok && err.lines().count() == 1
                && err.contains(flag)
                && err.contains(name)
                && err.contains("link1_dh")
                && err.contains("with --body capsules"),
            "{flag}: {err}"
        );
    }
    assert!(!caps.exists());
    // Without <collision> elements the capsules stand in for the geometry under the default
    // --body collision: the refusal says so, not that capsules were asked for.
    let text = std::fs::read_to_string(&urdf).unwrap();
    let mut bare = String::new();
    let mut rest = text.as_str();
    while let Some(i) = rest.find("<collision") {
        bare.push_str(&rest[..i]);
        let end = rest[i..].find("</collision>").unwrap() + i + "</collision>".len();
        rest = &rest[end..];
    }
    bare.push_str(rest);
    let bare_urdf = dir.path().join("bare.urdf");
    std::fs::write(&bare_urdf, bare).unwrap();
    let (ok, _, err) = reach_with(&bare_urdf, "collision", "--write-srdf", &caps);
    assert!(
        !ok && err.lines().count() == 1
            && err.contains("no <collision> geometry")
            && !err.contains("--body capsules"),
        "{err}"
    );
    assert!(!caps.exists());
}
