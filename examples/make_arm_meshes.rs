//! Generates `meshes/arm/`, the collision meshes of a six-joint test arm, and its URDF
//! `examples/robots/mesh_arm.urdf`.
//!
//! Every link is a chamfered block (an octagonal prism along its z axis, so a convex
//! polyhedron), written as binary STL or as COLLADA (`.dae`). The arm stands upright at home:
//! base, shoulder (joint 1 about z), a wide upper arm (joint 2 about y), forearm (joint 3
//! about y), and a wrist (joints 4 about z, 5 about y, 6 about z) with a flange and a box
//! gripper (a URDF `<box>`). The URDF refers to half of the meshes as `package://meshes/arm/…`
//! (found by searching the folders above the URDF) and to the other half by relative paths.
//! Units are metres. All of it is generated here: no third-party mesh is used.
//!
//! Run with `cargo run --example make_arm_meshes`.

use std::fmt::Write as _;
use std::path::Path;

/// A chamfered block: `x ∈ [−wx, wx]`, `y ∈ [−wy, wy]`, `z ∈ [z0, z1]`, with corners cut by `c`.
struct Block {
    name: &'static str,
    wx: f64,
    wy: f64,
    z0: f64,
    z1: f64,
    c: f64,
    dae: bool,
}

/// The octagon of a block, counter-clockwise seen from +z.
fn octagon(b: &Block) -> Vec<[f64; 2]> {
    let (x, y, c) = (b.wx, b.wy, b.c);
    vec![
        [x, -y + c],
        [x, y - c],
        [x - c, y],
        [-x + c, y],
        [-x, y - c],
        [-x, -y + c],
        [-x + c, -y],
        [x - c, -y],
    ]
}

/// Vertices and outward (counter-clockwise) triangles of a block.
fn mesh(b: &Block) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let o = octagon(b);
    let n = o.len() as u32;
    let mut v: Vec<[f64; 3]> = o.iter().map(|p| [p[0], p[1], b.z0]).collect();
    v.extend(o.iter().map(|p| [p[0], p[1], b.z1]));
    let mut t = Vec::new();
    for k in 0..n {
        let j = (k + 1) % n;
        // Side quad: bottom k, bottom j, top j, top k (outward for a ccw octagon).
        t.push([k, j, n + j]);
        t.push([k, n + j, n + k]);
    }
    for k in 1..n - 1 {
        t.push([0, k + 1, k]); // bottom, facing −z
        t.push([n, n + k, n + k + 1]); // top, facing +z
    }
    (v, t)
}

/// Volume of a closed, outward-oriented triangle mesh.
fn volume(v: &[[f64; 3]], t: &[[u32; 3]]) -> f64 {
    t.iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| v[i as usize]);
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

fn write_stl(path: &Path, v: &[[f64; 3]], t: &[[u32; 3]]) -> std::io::Result<()> {
    let tris: Vec<stl_io::Triangle> = t
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| v[i as usize]);
            let (u, w) = (
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
            );
            let n = [
                u[1] * w[2] - u[2] * w[1],
                u[2] * w[0] - u[0] * w[2],
                u[0] * w[1] - u[1] * w[0],
            ];
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            stl_io::Triangle {
                normal: stl_io::Normal::new(n.map(|x| (x / l) as f32)),
                vertices: [a, b, c].map(|p| stl_io::Vertex::new(p.map(|x| x as f32))),
            }
        })
        .collect();
    let mut file = std::fs::File::create(path)?;
    stl_io::write_stl(&mut file, tris.iter())
}

fn write_dae(path: &Path, name: &str, v: &[[f64; 3]], t: &[[u32; 3]]) -> std::io::Result<()> {
    let mut pos = String::new();
    for p in v {
        let _ = write!(pos, "{} {} {} ", p[0], p[1], p[2]);
    }
    let mut idx = String::new();
    for f in t {
        let _ = write!(idx, "{} {} {} ", f[0], f[1], f[2]);
    }
    let text = format!(
        r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>
    <contributor><authoring_tool>kinsynth make_arm_meshes</authoring_tool></contributor>
    <created>2026-01-01T00:00:00</created>
    <modified>2026-01-01T00:00:00</modified>
    <unit name="meter" meter="1"/>
    <up_axis>Z_UP</up_axis>
  </asset>
  <library_geometries>
    <geometry id="{name}-mesh" name="{name}">
      <mesh>
        <source id="{name}-positions">
          <float_array id="{name}-positions-array" count="{nf}">{pos}</float_array>
          <technique_common>
            <accessor source="#{name}-positions-array" count="{nv}" stride="3">
              <param name="X" type="float"/>
              <param name="Y" type="float"/>
              <param name="Z" type="float"/>
            </accessor>
          </technique_common>
        </source>
        <vertices id="{name}-vertices">
          <input semantic="POSITION" source="#{name}-positions"/>
        </vertices>
        <triangles count="{nt}">
          <input semantic="VERTEX" source="#{name}-vertices" offset="0"/>
          <p>{idx}</p>
        </triangles>
      </mesh>
    </geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="Scene" name="Scene">
      <node id="{name}" name="{name}" type="NODE">
        <instance_geometry url="#{name}-mesh"/>
      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene>
    <instance_visual_scene url="#Scene"/>
  </scene>
</COLLADA>
"##,
        nf = 3 * v.len(),
        nv = v.len(),
        nt = t.len(),
        pos = pos.trim_end(),
        idx = idx.trim_end(),
    );
    std::fs::write(path, text)
}

/// The URDF: `(link, parent joint origin z, joint axis, limit)` per moving joint.
fn urdf(blocks: &[Block]) -> String {
    let joints: [(&str, f64, &str, f64); 6] = [
        ("joint1", 0.10, "0 0 1", std::f64::consts::PI),
        ("joint2", 0.12, "0 1 0", 2.0),
        ("joint3", 0.40, "0 1 0", 2.5),
        ("joint4", 0.35, "0 0 1", std::f64::consts::PI),
        ("joint5", 0.08, "0 1 0", 2.0),
        ("joint6", 0.08, "0 0 1", std::f64::consts::PI),
    ];
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<!-- Generated by the make_arm_meshes example (examples/make_arm_meshes.rs). -->\n<robot name=\"mesh_arm\">\n",
    );
    for (k, b) in blocks.iter().enumerate() {
        let ext = if b.dae { "dae" } else { "stl" };
        // Even links by package URI, odd ones by relative path.
        let file = if k % 2 == 0 {
            format!("package://meshes/arm/{}.{ext}", b.name)
        } else {
            format!("../../meshes/arm/{}.{ext}", b.name)
        };
        let _ = writeln!(
            s,
            "  <link name=\"{n}\">\n    <visual><geometry><mesh filename=\"{file}\"/></geometry></visual>\n    <collision><geometry><mesh filename=\"{file}\" scale=\"1 1 1\"/></geometry></collision>",
            n = b.name
        );
        if b.name == "link6" {
            s.push_str("    <collision name=\"gripper\"><origin xyz=\"0 0 0.08\" rpy=\"0 0 0\"/><geometry><box size=\"0.06 0.02 0.08\"/></geometry></collision>\n");
        }
        s.push_str("  </link>\n");
    }
    s.push_str("  <link name=\"tool0\"/>\n");
    for (k, (name, z, axis, lim)) in joints.iter().enumerate() {
        let _ = writeln!(
            s,
            "  <joint name=\"{name}\" type=\"revolute\">\n    <parent link=\"{p}\"/><child link=\"{c}\"/>\n    <origin xyz=\"0 0 {z}\" rpy=\"0 0 0\"/><axis xyz=\"{axis}\"/>\n    <limit lower=\"{lo}\" upper=\"{lim}\" effort=\"10\" velocity=\"1\"/>\n  </joint>",
            p = blocks[k].name,
            c = blocks[k + 1].name,
            lo = -lim,
        );
    }
    s.push_str("  <joint name=\"tool0_joint\" type=\"fixed\">\n    <parent link=\"link6\"/><child link=\"tool0\"/>\n    <origin xyz=\"0 0 0.12\" rpy=\"0 0 0\"/>\n  </joint>\n</robot>\n");
    s
}

fn main() -> std::io::Result<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let blocks = [
        ("base_link", 0.08, 0.08, 0.0, 0.10, 0.03, false),
        ("link1", 0.06, 0.06, 0.0, 0.12, 0.02, false),
        ("link2", 0.09, 0.06, -0.05, 0.45, 0.02, true),
        ("link3", 0.045, 0.045, -0.04, 0.36, 0.015, true),
        ("link4", 0.04, 0.04, 0.0, 0.08, 0.012, false),
        ("link5", 0.035, 0.035, -0.03, 0.08, 0.01, true),
        ("link6", 0.03, 0.03, 0.0, 0.04, 0.008, false),
    ]
    .map(|(name, wx, wy, z0, z1, c, dae)| Block {
        name,
        wx,
        wy,
        z0,
        z1,
        c,
        dae,
    });
    let dir = root.join("meshes/arm");
    std::fs::create_dir_all(&dir)?;
    for b in &blocks {
        let (v, t) = mesh(b);
        let vol = volume(&v, &t);
        assert!(vol > 0.0, "{}: triangles face outward", b.name);
        if b.dae {
            write_dae(&dir.join(format!("{}.dae", b.name)), b.name, &v, &t)?;
        } else {
            write_stl(&dir.join(format!("{}.stl", b.name)), &v, &t)?;
        }
        println!(
            "{}.{}: {} vertices, {} triangles, volume {:.6} m³",
            b.name,
            if b.dae { "dae" } else { "stl" },
            v.len(),
            t.len(),
            vol
        );
    }
    let path = root.join("examples/robots/mesh_arm.urdf");
    std::fs::write(&path, urdf(&blocks))?;
    println!("wrote {}", path.display());
    Ok(())
}
