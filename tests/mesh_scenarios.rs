//! Mesh obstacles through `kinsynth check`: STL (binary and ASCII) and OBJ files in every
//! representation, scale and orientation; task points inside meshes; every bad mesh file and
//! bad mesh field fails with a one-line message naming the scenario, the field, the mesh file
//! and what is wrong; and the bundled mesh scenarios.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_kinsynth");

const REPRESENTATIONS: [&str; 3] = ["hull", "decomposition", "trimesh"];

/// Half the side of the test cubes (metres).
const H: f64 = 0.1;

/// A two-link planar arm; its largest design lies along x from the origin to (0.8, 0, 0) at
/// home, well clear of every obstacle below (all at y ≥ 0.5).
const ROBOT: &str = r#"
clearance = 0.01

[robot]
links = 2
link_radius = 0.02
uniform = { a = [0.0, 0.4], axes = { ry = { min = -3.0, max = 3.0 } } }
"#;

/// A task point clear of every obstacle used here.
const FREE: [f64; 3] = [0.3, 0.0, 0.4];

// ---------------------------------------------------------------------------------------------
// Mesh files

/// A closed cube of side `2 H` centred on the origin: 8 vertices, 12 triangles,
/// counter-clockwise seen from outside.
fn cube() -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let vertices: Vec<[f64; 3]> = (0..8)
        .map(|i| [0, 1, 2].map(|k| if i >> k & 1 == 1 { H } else { -H }))
        .collect();
    let index = |v: [f64; 3]| vertices.iter().position(|w| *w == v).unwrap();
    let mut triangles = Vec::new();
    for axis in 0..3 {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [-H, H] {
            let corner = |sb: f64, sc: f64| {
                let mut v = [0.0; 3];
                v[axis] = side;
                v[b] = sb;
                v[c] = sc;
                index(v)
            };
            // Counter-clockwise in the (b, c) plane faces +axis.
            let quad = [corner(-H, -H), corner(H, -H), corner(H, H), corner(-H, H)];
            for t in [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]] {
                triangles.push(if side > 0.0 { t } else { [t[0], t[2], t[1]] });
            }
        }
    }
    (vertices, triangles)
}

/// A U (the unit test's shape in `world::mesh`): a 3 × 1 bar (z ∈ [0, 1]) with two 1-wide
/// pillars up to z = 3, extruded 1 along y. The notch is x ∈ [1, 2], z ∈ [1, 3].
fn u_shape() -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let profile = [
        [0.0, 0.0],
        [3.0, 0.0],
        [3.0, 3.0],
        [2.0, 3.0],
        [2.0, 1.0],
        [1.0, 1.0],
        [1.0, 3.0],
        [0.0, 3.0],
    ];
    let caps = [
        [0, 1, 4],
        [1, 2, 4],
        [2, 3, 4],
        [0, 4, 5],
        [0, 5, 6],
        [0, 6, 7],
    ];
    let n = profile.len();
    let mut vertices: Vec<[f64; 3]> = profile.iter().map(|q| [q[0], 0.0, q[1]]).collect();
    vertices.extend(profile.iter().map(|q| [q[0], 1.0, q[1]]));
    // Counter-clockwise in (x, z) faces -y: right for the front cap.
    let mut triangles: Vec<[usize; 3]> = caps.to_vec();
    triangles.extend(caps.iter().map(|&[a, b, c]| [a + n, c + n, b + n]));
    for i in 0..n {
        let j = (i + 1) % n;
        triangles.push([i, i + n, j + n]);
        triangles.push([i, j + n, j]);
    }
    (vertices, triangles)
}

/// Signed volume: positive for a closed, outward-oriented mesh.
fn signed_volume((vertices, triangles): &(Vec<[f64; 3]>, Vec<[usize; 3]>)) -> f64 {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| vertices[i]);
            a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0])
        })
        .sum::<f64>()
        / 6.0
}

fn normal(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    n.map(|x| x / l)
}

/// Binary STL; the header starts with "solid", as many exporters write it.
fn binary_stl((vertices, triangles): &(Vec<[f64; 3]>, Vec<[usize; 3]>)) -> Vec<u8> {
    let mut bytes = b"solid cube, binary, written by kinsynth's tests".to_vec();
    bytes.resize(80, b' ');
    bytes.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for t in triangles {
        let [a, b, c] = t.map(|i| vertices[i]);
        for v in [normal(a, b, c), a, b, c] {
            for x in v {
                bytes.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0, 0]);
    }
    bytes
}

fn ascii_stl((vertices, triangles): &(Vec<[f64; 3]>, Vec<[usize; 3]>)) -> String {
    let mut s = String::from("solid cube\n");
    for t in triangles {
        let [a, b, c] = t.map(|i| vertices[i]);
        let n = normal(a, b, c);
        s += &format!(
            "  facet normal {} {} {}\n    outer loop\n",
            n[0], n[1], n[2]
        );
        for v in [a, b, c] {
            s += &format!("      vertex {} {} {}\n", v[0], v[1], v[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid cube\n"
}

fn obj((vertices, triangles): &(Vec<[f64; 3]>, Vec<[usize; 3]>)) -> String {
    let mut s = String::from("# written by kinsynth's tests\no mesh\n");
    for v in vertices {
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for t in triangles {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

// ---------------------------------------------------------------------------------------------
// Scenarios and the command line

/// A temporary folder holding a scenario and its mesh files.
struct Dir(tempfile::TempDir);

impl Dir {
    fn new() -> Self {
        Dir(tempfile::tempdir().unwrap())
    }

    fn path(&self) -> &Path {
        self.0.path()
    }

    fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let p = self.path().join(name);
        std::fs::write(&p, contents).unwrap();
        p
    }

    /// The three cube files: binary STL, ASCII STL, OBJ.
    fn with_cubes(self) -> Self {
        let cube = cube();
        self.write("cube_binary.stl", binary_stl(&cube));
        self.write("cube_ascii.stl", ascii_stl(&cube));
        self.write("cube.obj", obj(&cube));
        self
    }

    fn check(&self, text: &str) -> (PathBuf, Output) {
        let p = self.write("scenario.toml", text);
        let out = Command::new(BIN).arg("check").arg(&p).output().unwrap();
        (p, out)
    }

    /// Runs `check`, expects success without warnings, and returns stdout.
    fn accepted(&self, text: &str) -> String {
        let (_, out) = self.check(text);
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert!(out.status.success(), "rejected: {stderr}\n{text}");
        assert!(stderr.is_empty(), "unexpected warning: {stderr}");
        String::from_utf8(out.stdout).unwrap()
    }

    /// Runs `check`, expects failure with a one-line error naming the scenario file, and
    /// returns it.
    fn rejected(&self, text: &str) -> String {
        let (p, out) = self.check(text);
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert!(!out.status.success(), "accepted:\n{text}");
        assert_eq!(out.status.code(), Some(1));
        assert_eq!(
            stderr.lines().count(),
            1,
            "one-line error expected: {stderr}"
        );
        assert!(
            stderr.starts_with(&format!("error: {}: ", p.display())),
            "error must name the scenario file: {stderr}"
        );
        stderr
    }
}

fn assert_mentions(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "`{p}` missing from: {msg}");
    }
}

fn fmt3(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// One `[[obstacle]]` table for a mesh; `extra` holds further `key = value` lines.
fn mesh(name: &str, file: &str, representation: &str, position: [f64; 3], extra: &str) -> String {
    format!(
        "\n[[obstacle]]\nname = \"{name}\"\nshape = \"mesh\"\nfile = \"{file}\"\n\
         representation = \"{representation}\"\nposition = {}\n{extra}\n",
        fmt3(position)
    )
}

/// The robot, the obstacles and the task points.
fn scenario(obstacles: &[String], tasks: &[[f64; 3]]) -> String {
    let mut s = ROBOT.to_string();
    for o in obstacles {
        s += o;
    }
    for t in tasks {
        s += &format!("\n[[task]]\npoint = {}\n", fmt3(*t));
    }
    s
}

/// Where the three cubes stand, with their names and files.
const CUBES: [(&str, &str, [f64; 3]); 3] = [
    ("binary cube", "cube_binary.stl", [0.0, 0.6, 0.5]),
    ("ascii cube", "cube_ascii.stl", [0.5, 0.6, 0.5]),
    ("obj cube", "cube.obj", [-0.5, 0.6, 0.5]),
];

fn three_cubes(representation: &str) -> Vec<String> {
    CUBES
        .iter()
        .map(|&(name, file, at)| mesh(name, file, representation, at, ""))
        .collect()
}

// ---------------------------------------------------------------------------------------------
// 1. Valid mesh obstacles

#[test]
fn test_meshes_are_closed_and_outward() {
    for (mesh, volume) in [(cube(), 8.0 * H * H * H), (u_shape(), 7.0)] {
        // Closed and consistently oriented: every directed edge once, and its reverse once.
        let mut edges = std::collections::HashMap::new();
        for t in &mesh.1 {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!((n, edges.get(&(b, a))), (1, Some(&1)), "edge {a}->{b}");
        }
        // Outward: positive volume.
        assert!((signed_volume(&mesh) - volume).abs() < 1e-12);
    }
    assert_eq!(cube().1.len(), 12);
}

#[test]
fn cubes_in_every_format_pass_in_every_representation() {
    let dir = Dir::new().with_cubes();
    // Tasks 2 cm off a face of each cube: outside it whatever the representation.
    let mut tasks = vec![FREE];
    for (_, _, at) in CUBES {
        tasks.push(add(at, [0.0, 0.0, H + 0.02]));
        tasks.push(add(at, [H + 0.02, 0.0, 0.0]));
        tasks.push(add(at, [0.0, -H - 0.02, 0.05]));
    }
    for rep in REPRESENTATIONS {
        let out = dir.accepted(&scenario(&three_cubes(rep), &tasks));
        assert_mentions(&out, &["obstacles       3", "tasks           10"]);
    }
    // Without `representation`: the hull.
    let text = scenario(&three_cubes("hull"), &tasks).replace("representation = \"hull\"\n", "");
    assert!(!text.contains("representation"));
    dir.accepted(&text);
}

#[test]
fn task_inside_a_cube_names_task_and_obstacle() {
    let dir = Dir::new().with_cubes();
    for rep in REPRESENTATIONS {
        for (k, (name, _, at)) in CUBES.iter().enumerate() {
            // Off-centre, 2 cm inside the top face.
            let inside = add(*at, [0.05, -0.06, H - 0.02]);
            let m = dir.rejected(&scenario(&three_cubes(rep), &[FREE, inside]));
            assert_mentions(
                &m,
                &[
                    &format!("task[1] = [{}, {}, {}]", inside[0], inside[1], inside[2]),
                    &format!("lies inside obstacle[{k}] ({name})"),
                ],
            );
        }
    }
}

#[test]
fn uniform_scale_grows_the_mesh() {
    let dir = Dir::new().with_cubes();
    let at = [0.0, 0.6, 0.5];
    // 1.5 H from the centre: outside the cube, inside it scaled by 2.
    let near = add(at, [1.5 * H, 0.0, 0.0]);
    let far = add(at, [2.5 * H, 0.0, 0.0]);
    for rep in REPRESENTATIONS {
        for file in ["cube_binary.stl", "cube_ascii.stl", "cube.obj"] {
            let o = |extra: &str| vec![mesh("box", file, rep, at, extra)];
            dir.accepted(&scenario(&o(""), &[near]));
            dir.accepted(&scenario(&o("scale = 1.0"), &[near]));
            let m = dir.rejected(&scenario(&o("scale = 2.0"), &[near]));
            assert_mentions(&m, &["task[0]", "obstacle[0] (box)"]);
            dir.accepted(&scenario(&o("scale = 2.0"), &[far]));
        }
    }
}

#[test]
fn per_axis_scale_stretches_each_axis() {
    let dir = Dir::new().with_cubes();
    let at = [0.0, 0.6, 0.5];
    let o = |rep: &str| vec![mesh("post", "cube.obj", rep, at, "scale = [1, 1, 3]")];
    for rep in REPRESENTATIONS {
        // Along z the cube reaches 3 H, along x still H.
        let m = dir.rejected(&scenario(&o(rep), &[add(at, [0.0, 0.0, 2.5 * H])]));
        assert_mentions(&m, &["task[0]", "obstacle[0] (post)"]);
        dir.accepted(&scenario(&o(rep), &[add(at, [1.5 * H, 0.0, 0.0])]));
        dir.accepted(&scenario(&o(rep), &[add(at, [0.0, 1.5 * H, 0.0])]));
    }
}

#[test]
fn quaternion_turns_the_scaled_mesh() {
    let dir = Dir::new().with_cubes();
    let at = [0.0, 0.6, 0.5];
    // A post 6 H tall along its local z, turned 90° about x ([x, y, z, w]): its local z
    // points along world -y. Read as [w, x, y, z] it would turn about z and stay upright.
    let along_y = add(at, [0.0, -2.5 * H, 0.0]);
    let along_z = add(at, [0.0, 0.0, 2.5 * H]);
    for orientation in [
        "quaternion = [0.7071067811865476, 0.0, 0.0, 0.7071067811865476]",
        "rpy = [1.5707963267948966, 0.0, 0.0]",
    ] {
        for rep in REPRESENTATIONS {
            let extra = format!("scale = [1.0, 1.0, 3.0]\n{orientation}");
            let o = vec![mesh("post", "cube_binary.stl", rep, at, &extra)];
            let m = dir.rejected(&scenario(&o, &[FREE, along_y]));
            assert_mentions(&m, &["task[1]", "obstacle[0] (post)"]);
            dir.accepted(&scenario(&o, &[FREE, along_z]));
        }
    }
    // A quaternion that is not of unit length is normalised.
    let extra = "scale = [1.0, 1.0, 3.0]\nquaternion = [2.0, 0.0, 0.0, 2.0]";
    let o = vec![mesh("post", "cube.obj", "trimesh", at, extra)];
    dir.rejected(&scenario(&o, &[along_y]));
    dir.accepted(&scenario(&o, &[along_z]));
}

// ---------------------------------------------------------------------------------------------
// 2. Non-convex meshes: the hull fills the notch of a U, the triangle mesh does not

#[test]
fn u_notch_is_inside_the_hull_only() {
    let dir = Dir::new();
    dir.write("u.obj", obj(&u_shape()));
    // Scaled to 0.3 m × 0.1 m × 0.3 m, at the origin of its frame.
    let at = [0.0, 0.6, 0.2];
    let o = |rep: &str| vec![mesh("U", "u.obj", rep, at, "scale = 0.1")];
    let notch = add(at, [0.15, 0.05, 0.2]);
    let bar = add(at, [0.15, 0.05, 0.05]);
    let pillar = add(at, [0.05, 0.05, 0.25]);
    let beside = add(at, [0.15, 0.15, 0.2]);

    let m = dir.rejected(&scenario(&o("hull"), &[FREE, notch]));
    assert_mentions(&m, &["task[1]", "obstacle[0] (U)"]);
    dir.accepted(&scenario(&o("trimesh"), &[FREE, notch]));
    // The convex decomposition (V-HACD, deterministic) keeps the notch open too.
    dir.accepted(&scenario(&o("decomposition"), &[FREE, notch]));

    for rep in REPRESENTATIONS {
        dir.accepted(&scenario(&o(rep), &[FREE, beside]));
        for p in [bar, pillar] {
            let m = dir.rejected(&scenario(&o(rep), &[FREE, p]));
            assert_mentions(&m, &["task[1]", "obstacle[0] (U)"]);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Bad mesh files

/// One mesh obstacle reading `file` (hull), and a free task.
fn one_mesh(file: &str) -> String {
    scenario(&[mesh("m", file, "hull", [0.0, 0.6, 0.5], "")], &[FREE])
}

/// Rejects a scenario whose only obstacle reads `file` from `dir`; the message must name the
/// field, then the mesh file, then what is wrong.
fn bad_mesh(dir: &Dir, file: &str, what: &[&str]) -> String {
    let m = dir.rejected(&one_mesh(file));
    let mesh_path = dir.path().join(file);
    assert_mentions(
        &m,
        &[&format!("obstacle[0].file: {}: ", mesh_path.display())],
    );
    assert_mentions(&m, what);
    m
}

#[test]
fn missing_mesh_file() {
    let dir = Dir::new();
    bad_mesh(&dir, "nowhere.stl", &["cannot read file", "No such file"]);
}

#[test]
fn unknown_mesh_extension() {
    let dir = Dir::new();
    dir.write("cube.ply", "ply\nformat ascii 1.0\nend_header\n");
    bad_mesh(
        &dir,
        "cube.ply",
        &["unsupported mesh format", "\".ply\"", ".stl or .obj"],
    );
}

#[test]
fn unparseable_mesh_content() {
    let dir = Dir::new();
    dir.write("garbage.stl", "this is no mesh\n");
    bad_mesh(
        &dir,
        "garbage.stl",
        &["cannot parse as binary STL", "84-byte header"],
    );
    let ascii = ascii_stl(&cube()).replacen("vertex", "vertex one", 1);
    dir.write("garbage_ascii.stl", ascii);
    bad_mesh(&dir, "garbage_ascii.stl", &["cannot parse as ASCII STL"]);
    dir.write("garbage.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
    bad_mesh(&dir, "garbage.obj", &["cannot parse as OBJ"]);
}

#[test]
fn empty_mesh() {
    let dir = Dir::new();
    dir.write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    bad_mesh(&dir, "points.obj", &["mesh has no triangles"]);
    dir.write("nothing.stl", "solid nothing\nendsolid nothing\n");
    bad_mesh(&dir, "nothing.stl", &["mesh has no triangles"]);
}

#[test]
fn non_finite_vertex() {
    let dir = Dir::new();
    let (mut vertices, triangles) = cube();
    vertices[5][1] = f64::NAN;
    dir.write("nan.stl", binary_stl(&(vertices, triangles)));
    bad_mesh(&dir, "nan.stl", &["is not finite", "NaN"]);
}

#[test]
fn truncated_binary_stl() {
    let dir = Dir::new();
    let mut bytes = binary_stl(&cube());
    assert_eq!(bytes.len(), 84 + 12 * 50);
    bytes.truncate(bytes.len() - 20);
    dir.write("cut.stl", bytes);
    bad_mesh(
        &dir,
        "cut.stl",
        &[
            "cannot parse as binary STL",
            "declares 12 triangles",
            "684 bytes",
            "only 664 bytes",
        ],
    );
}

#[test]
fn degenerate_mesh() {
    let dir = Dir::new();
    dir.write("line.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n");
    bad_mesh(&dir, "line.obj", &["degenerate", "zero area"]);
}

// ---------------------------------------------------------------------------------------------
// 4. Bad mesh fields

fn with_extra(extra: &str) -> String {
    scenario(
        &[mesh("m", "cube.obj", "hull", [0.0, 0.6, 0.5], extra)],
        &[FREE],
    )
}

#[test]
fn zero_scale() {
    let dir = Dir::new().with_cubes();
    let m = dir.rejected(&with_extra("scale = 0.0"));
    assert_mentions(
        &m,
        &["obstacle[0].scale = [0.0, 0.0, 0.0]", "positive and finite"],
    );
}

#[test]
fn negative_scale_factor() {
    let dir = Dir::new().with_cubes();
    let m = dir.rejected(&with_extra("scale = [1, -1, 1]"));
    assert_mentions(
        &m,
        &[
            "obstacle[0].scale = [1.0, -1.0, 1.0]",
            "positive and finite",
        ],
    );
}

#[test]
fn zero_quaternion() {
    let dir = Dir::new().with_cubes();
    let m = dir.rejected(&with_extra("quaternion = [0, 0, 0, 0]"));
    assert_mentions(
        &m,
        &["obstacle[0].quaternion = [0.0, 0.0, 0.0, 0.0]", "non-zero"],
    );
}

#[test]
fn rpy_and_quaternion_together() {
    let dir = Dir::new().with_cubes();
    let m = dir.rejected(&with_extra(
        "rpy = [0.0, 0.0, 1.0]\nquaternion = [0.0, 0.0, 0.0, 1.0]",
    ));
    assert_mentions(
        &m,
        &[
            "obstacle[0].quaternion = [0.0, 0.0, 0.0, 1.0]",
            "either `rpy` or `quaternion`, not both",
        ],
    );
}

#[test]
fn mesh_without_file() {
    let dir = Dir::new().with_cubes();
    let text = with_extra("").replace("file = \"cube.obj\"\n", "");
    assert!(!text.contains("file"));
    let m = dir.rejected(&text);
    assert_mentions(&m, &["obstacle[0].file = missing", "a mesh needs `file`"]);
}

#[test]
fn file_on_a_sphere() {
    let dir = Dir::new().with_cubes();
    let sphere = "\n[[obstacle]]\nshape = \"sphere\"\nposition = [0.0, 0.6, 0.5]\nradius = 0.1\n\
                  file = \"cube.obj\"\n"
        .to_string();
    let m = dir.rejected(&scenario(std::slice::from_ref(&sphere), &[FREE]));
    assert_mentions(&m, &["obstacle[0].file = given", "a sphere has no `file`"]);
    // Without `file` the sphere is fine.
    dir.accepted(&scenario(
        &[sphere.replace("file = \"cube.obj\"\n", "")],
        &[FREE],
    ));
}

// ---------------------------------------------------------------------------------------------
// 5. The bundled mesh scenarios

fn manifest_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn bundled_mesh_scenarios_pass_without_warnings() {
    for name in ["glovebox.toml", "pipework.toml"] {
        let p = manifest_dir().join("examples/scenarios").join(name);
        let out = Command::new(BIN).arg("check").arg(&p).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{name}: {stderr}");
        assert!(stderr.is_empty(), "{name}: unexpected warning: {stderr}");
        let stdout = String::from_utf8(out.stdout).unwrap();
        assert!(stdout.contains(": ok"), "{stdout}");
    }
}

#[test]
fn glovebox_task_inside_the_front_wall_is_rejected() {
    // The same layout as the repository, so `../../meshes/glovebox.stl` resolves.
    let dir = Dir::new();
    let scenarios = dir.path().join("examples/scenarios");
    std::fs::create_dir_all(&scenarios).unwrap();
    std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
    std::fs::copy(
        manifest_dir().join("meshes/glovebox.stl"),
        dir.path().join("meshes/glovebox.stl"),
    )
    .unwrap();
    let original =
        std::fs::read_to_string(manifest_dir().join("examples/scenarios/glovebox.toml")).unwrap();
    let p = scenarios.join("glovebox.toml");
    let check = |text: &str| {
        std::fs::write(&p, text).unwrap();
        Command::new(BIN).arg("check").arg(&p).output().unwrap()
    };

    // The copy itself passes.
    let out = check(&original);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // The box stands at y = 0.6: its front wall spans world y ∈ [0.30, 0.32]. The ports are
    // at x = ±0.25, z = 0.35 (radius 0.1): x = 0, z = 0.15 is solid wall.
    let task = "point = [-0.15, 0.62, 0.45]";
    assert!(original.contains(task));
    let index = original[..original.find(task).unwrap()]
        .matches("[[task]]")
        .count()
        - 1;
    for (point, inside) in [
        ("[0.0, 0.31, 0.15]", true),
        ("[0.0, 0.29, 0.15]", false),
        ("[0.0, 0.33, 0.15]", false),
    ] {
        let out = check(&original.replace(task, &format!("point = {point}")));
        let stderr = String::from_utf8(out.stderr).unwrap();
        if inside {
            assert_eq!(out.status.code(), Some(1));
            assert_eq!(stderr.lines().count(), 1, "{stderr}");
            assert!(stderr.starts_with(&format!("error: {}: ", p.display())));
            assert_mentions(
                &stderr,
                &[
                    &format!("task[{index}] = [0, 0.31, 0.15]"),
                    "lies inside obstacle[0] (glovebox)",
                ],
            );
        } else {
            assert!(out.status.success(), "{point}: {stderr}");
        }
    }
}
