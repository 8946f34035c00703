//! The browser report: one self-contained HTML file that shows a scenario, a robot and its
//! reachability paths in 3D (three.js, vendored under `vendor/` with its licence and embedded
//! into the binary), with the design, the run's convergence, its Eq. 23 cost breakdown and its
//! settings beside the view.
//!
//! Geometry is drawn as the checker sees it: every mesh obstacle's parry shape (hull, convex
//! decomposition or triangle mesh) turned into triangles, written once per shape however many
//! obstacles share it; primitives (spheres, capsules, boxes, cylinders) by their dimensions,
//! which the page tessellates itself (a cell of 100,000 spheres stays a page of megabytes, not
//! gigabytes); and the robot's bodies from
//! the one body model ([`RobotBody`]: capsule segments and solids). The page does no kinematics:
//! every animation sample carries the poses the chain's own forward kinematics gives there, the
//! same as the checker's, sampled along the straight actuation-space edges of each path.
//!
//! Large arrays (vertices, indices, samples) travel as base64 of little-endian `f32` / `u32`,
//! so a 100,000-triangle mesh costs about 2 MB of page.

use crate::collision::body::{Placed, RobotBody};
use crate::design::Design;
use crate::error::Result;
use crate::kinematics::{Chain, Frames};
use crate::optimize::output::{HistoryRow, RunSummary};
use crate::planning::ReachReport;
use crate::world::Workspace;
use base64::Engine as _;
use nalgebra::{IsometryMatrix3, UnitQuaternion};
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::Shape;
use serde_json::{json, Value};
use std::path::Path;

/// three.js (r170, MIT), the module build.
const THREE_JS: &str = include_str!("vendor/three.module.min.js");
/// three.js's orbit controls (r170, MIT).
const ORBIT_CONTROLS_JS: &str = include_str!("vendor/OrbitControls.js");
/// The page: markup, style and the viewer script, with placeholders for the data and libraries.
const PAGE: &str = include_str!("page.html");

/// Most animation samples along one path (the path's own points are always among them).
pub const MAX_SAMPLES_PER_PATH: usize = 400;
/// Most animation samples over all paths of a page (a report of thousands of reached tasks gets
/// fewer samples per path, down to its points alone).
pub const MAX_SAMPLES_TOTAL: usize = 20_000;
/// Samples per straight edge of a path before the per-path cap applies.
pub const SAMPLES_PER_EDGE: usize = 8;
/// Subdivisions of round primitives (balls, capsules, cylinders) around their axis.
const ROUND_SUBDIVISIONS: u32 = 32;

/// The results of an optimisation run, for the report's convergence curve, cost breakdown and
/// settings.
#[derive(Clone, Copy)]
pub struct RunView<'a> {
    /// The run's summary (`best.json`).
    pub summary: &'a RunSummary,
    /// Its history rows (`history.csv`).
    pub history: &'a [HistoryRow],
    /// The convergence plot (`convergence.svg`), shown as it is.
    pub convergence_svg: Option<&'a str>,
}

/// What one report page shows.
pub struct ViewInput<'a> {
    /// Title of the page (scenario name and what is shown).
    pub title: String,
    /// The obstacles and tasks.
    pub workspace: &'a Workspace,
    /// The robot's kinematics.
    pub chain: &'a Chain,
    /// The robot's bodies as the checker sees them.
    pub body: &'a RobotBody,
    /// URDF joint names of the chain's free axes, when it came from a URDF (else `j{i}_{axis}`).
    pub joint_names: Option<Vec<String>>,
    /// The design, for the design table (absent for a URDF robot).
    pub design: Option<&'a Design>,
    /// The reachability report whose paths are animated (absent: the robot stands at home).
    pub report: Option<&'a ReachReport>,
    /// The optimisation run, when the report belongs to one.
    pub run: Option<RunView<'a>>,
}

/// Little-endian bytes of `values` as base64.
fn b64_f32(values: &[f32]) -> String {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// Little-endian bytes of `values` as base64.
fn b64_u32(values: &[u32]) -> String {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A triangle mesh in some local frame: flat `xyz` vertex coordinates and triangle indices.
#[derive(Default)]
struct Mesh {
    vertices: Vec<f32>,
    indices: Vec<u32>,
}

impl Mesh {
    /// Appends `vertices` (moved by `pose`) and `triangles`.
    fn append(&mut self, pose: &Pose, vertices: &[Vector], triangles: &[[u32; 3]]) {
        let base = (self.vertices.len() / 3) as u32;
        for v in vertices {
            let p = pose.transform_point(*v);
            self.vertices
                .extend_from_slice(&[p.x as f32, p.y as f32, p.z as f32]);
        }
        for t in triangles {
            self.indices
                .extend_from_slice(&[base + t[0], base + t[1], base + t[2]]);
        }
    }

    /// Number of triangles.
    fn triangles(&self) -> usize {
        self.indices.len() / 3
    }

    /// The mesh as page data.
    fn to_json(&self) -> Value {
        json!({
            "vertices": b64_f32(&self.vertices),
            "indices": b64_u32(&self.indices),
            "triangles": self.triangles(),
        })
    }
}

/// Adds the triangles of `shape` (placed at `pose` in the mesh's frame) to `mesh`, and returns
/// false for a shape kind the page cannot draw (it then gets its bounding box).
fn add_shape(mesh: &mut Mesh, pose: &Pose, shape: &dyn Shape) -> bool {
    let n = ROUND_SUBDIVISIONS;
    let (v, t) = if let Some(s) = shape.as_trimesh() {
        mesh.append(pose, s.vertices(), s.indices());
        return true;
    } else if let Some(c) = shape.as_compound() {
        let mut known = true;
        for (part_pose, part) in c.shapes() {
            known &= add_shape(mesh, &(*pose * *part_pose), part.as_ref());
        }
        return known;
    } else if let Some(s) = shape.as_convex_polyhedron() {
        s.to_trimesh()
    } else if let Some(s) = shape.as_ball() {
        s.to_trimesh(n, n / 2)
    } else if let Some(s) = shape.as_capsule() {
        s.to_trimesh(n, n / 4)
    } else if let Some(s) = shape.as_cuboid() {
        s.to_trimesh()
    } else if let Some(s) = shape.as_cylinder() {
        s.to_trimesh(n)
    } else {
        let aabb = shape.compute_local_aabb();
        let centre = Pose::from_translation(aabb.center());
        let (v, t) = parry3d_f64::shape::Cuboid::new(aabb.half_extents()).to_trimesh();
        mesh.append(&(*pose * centre), &v, &t);
        return false;
    };
    mesh.append(pose, &v, &t);
    true
}

/// Position and quaternion (`x y z w`) of a parry pose, as `f32`.
fn pose7(p: &Pose) -> [f32; 7] {
    let (t, q) = (p.translation, p.rotation);
    [
        t.x as f32, t.y as f32, t.z as f32, q.x as f32, q.y as f32, q.z as f32, q.w as f32,
    ]
}

/// Position and quaternion (`x y z w`) of a frame, as `f32`.
fn iso7(iso: &IsometryMatrix3<f64>) -> [f32; 7] {
    let q = UnitQuaternion::from_rotation_matrix(&iso.rotation);
    let t = iso.translation.vector;
    [
        t.x as f32, t.y as f32, t.z as f32, q.i as f32, q.j as f32, q.k as f32, q.w as f32,
    ]
}

/// Floats per animation sample: the end effector (3), each capsule segment's two ends (6
/// each), each solid's pose (7 each) and each frame `F_0 … F_n`'s pose (7 each).
fn sample_stride(chain: &Chain, body: &RobotBody) -> usize {
    3 + 6 * body.segments() + 7 * body.solids().len() + 7 * (chain.link_count() + 1)
}

/// Appends one animation sample of configuration `a` to `out` (see [`sample_stride`]).
fn push_sample(
    chain: &Chain,
    body: &RobotBody,
    a: &[f64],
    frames: &mut Frames,
    placed: &mut Placed,
    out: &mut Vec<f32>,
) {
    chain.fk(a, frames);
    body.place(frames, placed);
    let ee = frames.end_effector();
    out.extend_from_slice(&[ee.x as f32, ee.y as f32, ee.z as f32]);
    for [p, q] in &frames.segments[..body.segments()] {
        out.extend([p.x, p.y, p.z, q.x, q.y, q.z].iter().map(|&c| c as f32));
    }
    for pose in &placed.poses {
        out.extend_from_slice(&pose7(pose));
    }
    for f in &frames.frames {
        out.extend_from_slice(&iso7(f));
    }
}

/// The configurations shown along a path: its points, and between each two of them samples
/// on the straight actuation-space edge the planner checked, at most `cap` in all (or the
/// points alone when they are more), spread by edge length.
fn path_configurations(points: &[Vec<f64>], cap: usize) -> Vec<Vec<f64>> {
    let edges = points.len().saturating_sub(1);
    if edges == 0 || cap <= points.len() {
        return points.to_vec();
    }
    let lengths: Vec<f64> = points
        .windows(2)
        .map(|w| {
            w[0].iter()
                .zip(&w[1])
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let total: f64 = lengths.iter().sum();
    let budget = (SAMPLES_PER_EDGE * edges).min(cap - 1);
    let mut out = vec![points[0].clone()];
    for (k, w) in points.windows(2).enumerate() {
        let steps = if total > 0.0 {
            ((lengths[k] / total) * budget as f64).round().max(1.0) as usize
        } else {
            1
        };
        for s in 1..=steps {
            let t = s as f64 / steps as f64;
            out.push(
                w[0].iter()
                    .zip(&w[1])
                    .map(|(a, b)| a + t * (b - a))
                    .collect(),
            );
        }
    }
    out
}

/// Most path values (points times joints) a report may carry over all its paths: as many as a
/// planner run keeps ([`crate::limits::MAX_REPORT_PATH_VALUES`]).
pub const MAX_PATH_VALUES: usize = crate::limits::MAX_REPORT_PATH_VALUES;

/// Most tree nodes a report may carry for the page to draw.
pub const MAX_TREE_NODES: usize = 1_000_000;

/// Largest magnitude of a coordinate in a report (an end effector, a tree node), in metres:
/// farther than any design reaches (its base within ±[`crate::limits::MAX_LENGTH`] m, at most
/// [`crate::limits::MAX_LINKS`] links whose `a`, `d` and three prismatic axes each reach at
/// most that far, and its tool as far again).
pub const MAX_COORDINATE: f64 = 1e6;

/// Checks the figures of a report: `R` in [0, 1] and the share of its targets reached,
/// `l_max` positive and at most [`crate::limits::MAX_SETTING`], errors finite and not negative
/// (angles at most π), end effectors and tree nodes within ±[`MAX_COORDINATE`] m, tool
/// rotations with entries in [−1, 1].
fn check_figures(report: &ReachReport) -> Result<()> {
    use crate::error::{fmt_list, Error, Num};
    use std::f64::consts::PI;
    let n = report.targets.len();
    let share = if n == 0 {
        0.0
    } else {
        report.reached() as f64 / n as f64
    };
    if !(0.0..=1.0).contains(&report.reachability) {
        return Err(Error::invalid(
            "reachability",
            Num(report.reachability),
            "must lie in [0, 1]",
        ));
    }
    if (report.reachability - share).abs() > 1e-9 {
        return Err(Error::invalid(
            "reachability",
            Num(report.reachability),
            format!("{} of its {n} targets are reached", report.reached()),
        ));
    }
    let max_setting = crate::limits::MAX_SETTING;
    if !(report.l_max > 0.0 && crate::limits::within(report.l_max, max_setting)) {
        return Err(Error::invalid(
            "l_max",
            Num(report.l_max),
            format!("must be positive and at most {max_setting}"),
        ));
    }
    let point = |p: &[f64; 3]| p.iter().all(|&v| crate::limits::within(v, MAX_COORDINATE));
    let within_m = format!("must be three finite coordinates within ±{MAX_COORDINATE} m");
    for (i, t) in report.targets.iter().enumerate() {
        let field = |f: &str| format!("targets[{i}].{f}");
        if !point(&t.end_effector) {
            return Err(Error::invalid(
                field("end_effector"),
                fmt_list(&t.end_effector),
                within_m,
            ));
        }
        for (name, v, max) in [
            ("error", Some(t.error), 2.0 * MAX_COORDINATE),
            (
                "position_error",
                Some(t.position_error),
                2.0 * MAX_COORDINATE,
            ),
            ("orientation_error", t.orientation_error, PI + 1e-9),
            ("approach_error", t.approach_error, PI + 1e-9),
            ("orientation_tolerance", t.orientation_tolerance, PI + 1e-9),
        ] {
            if let Some(v) = v.filter(|v| !(0.0..=max).contains(v)) {
                return Err(Error::invalid(
                    field(name),
                    Num(v),
                    format!("must be finite, not negative and at most {}", Num(max)),
                ));
            }
        }
        if let Some(r) = &t.tool_rotation {
            if !r
                .iter()
                .flatten()
                .all(|v| (-1.0 - 1e-9..=1.0 + 1e-9).contains(v))
            {
                let flat: Vec<f64> = r.iter().flatten().copied().collect();
                return Err(Error::invalid(
                    field("tool_rotation"),
                    fmt_list(&flat),
                    "must be a rotation matrix (every entry in [-1, 1])",
                ));
            }
        }
    }
    if let Some(tree) = &report.tree {
        if let Some(j) = tree.end_effectors.iter().position(|e| !point(e)) {
            return Err(Error::invalid(
                format!("tree.end_effectors[{j}]"),
                fmt_list(&tree.end_effectors[j]),
                within_m,
            ));
        }
    }
    Ok(())
}

/// Reads a reachability report (`kinsynth reach --json`, or a run's `reach.json`) to show with
/// a robot of `dof` free axes among `tasks`, checking that it belongs to them: one target per
/// task, at the task's point, each path point with `dof` values, all finite; and that its
/// figures are in range (`R`, `l_max`, errors, end effectors and tree nodes). Errors name the
/// file, the field (`targets[2].path.points[5]`) and the value.
pub fn load_reach(path: &Path, tasks: &[nalgebra::Point3<f64>], dof: usize) -> Result<ReachReport> {
    use crate::error::Error;
    let text =
        crate::limits::read_text(path, crate::limits::MAX_REPORT_FILE_BYTES).map_err(|source| {
            Error::Read {
                path: path.to_path_buf(),
                source,
            }
        })?;
    let mut de = serde_json::Deserializer::from_str(&text);
    let report: ReachReport = crate::strict::deserialize(&mut de).map_err(|e| {
        // An optimiser's best.json (which holds a design) is the likeliest wrong file.
        let best = serde_json::from_str::<serde_json::Value>(&text)
            .is_ok_and(|v| v.get("design").is_some());
        let hint = if best {
            " (an optimiser's best.json: --reach takes the report of `reach --json`)"
        } else {
            ""
        };
        Error::Parse {
            file: path.to_path_buf(),
            message: format!("{}{hint}", crate::strict::message(&e)),
        }
    })?;
    let bad = |field: String, value: String, reason: String| {
        Error::invalid(field, value, reason).in_file(path)
    };
    if report.targets.len() != tasks.len() {
        return Err(bad(
            "targets".into(),
            format!("{} entries", report.targets.len()),
            format!("the scenario has {} tasks", tasks.len()),
        ));
    }
    check_figures(&report).map_err(|e| e.in_file(path))?;
    let mut total = 0usize;
    for (i, t) in report.targets.iter().enumerate() {
        if t.index != i {
            return Err(bad(
                format!("targets[{i}].index"),
                t.index.to_string(),
                format!("must be {i} (one target per task, in scenario order)"),
            ));
        }
        let p = tasks[i];
        let d =
            ((t.point[0] - p.x).powi(2) + (t.point[1] - p.y).powi(2) + (t.point[2] - p.z).powi(2))
                .sqrt();
        if d.is_nan() || d > 1e-9 {
            return Err(bad(
                format!("targets[{i}].point"),
                format!("{:?}", t.point),
                format!("is not task {i} of the scenario, {:?}", [p.x, p.y, p.z]),
            ));
        }
        let Some(path) = &t.path else { continue };
        let cost = crate::planning::reach::path_cost(path.points.len(), &path.joint_names);
        total = total.saturating_add(cost);
        if total > MAX_PATH_VALUES {
            return Err(bad(
                format!("targets[{i}].path.points"),
                format!("{total} values so far"),
                format!(
                    "a report may carry at most {MAX_PATH_VALUES} path values (points times joints, and the joint names at one value per 8 bytes)"
                ),
            ));
        }
        for (j, q) in path.points.iter().enumerate() {
            // No axis range reaches beyond ±1000 (rad or m, `crate::limits`).
            let limit = crate::limits::MAX_ANGLE.max(crate::limits::MAX_LENGTH);
            if q.len() != dof || !q.iter().all(|v| v.is_finite() && v.abs() <= limit) {
                return Err(bad(
                    format!("targets[{i}].path.points[{j}]"),
                    crate::error::fmt_list(q),
                    format!(
                        "must be {dof} joint values (the robot has {dof} joints), each within \
                         ±{limit}"
                    ),
                ));
            }
        }
    }
    if let Some(tree) = &report.tree {
        let n = tree.end_effectors.len();
        if n > MAX_TREE_NODES {
            return Err(bad(
                "tree.end_effectors".into(),
                format!("{n} nodes"),
                format!("a report may carry at most {MAX_TREE_NODES} tree nodes"),
            ));
        }
        if tree.parents.len() != n {
            return Err(bad(
                "tree.parents".into(),
                format!("{} entries", tree.parents.len()),
                format!("must have one entry per node ({n})"),
            ));
        }
        if let Some(j) = tree
            .end_effectors
            .iter()
            .position(|e| !e.iter().all(|v| v.is_finite()))
        {
            return Err(bad(
                format!("tree.end_effectors[{j}]"),
                format!("{:?}", tree.end_effectors[j]),
                "must be three finite coordinates".into(),
            ));
        }
        if let Some(j) = tree.parents.iter().position(|&p| p as usize >= n) {
            return Err(bad(
                format!("tree.parents[{j}]"),
                tree.parents[j].to_string(),
                format!("must name a node (below {n})"),
            ));
        }
    }
    Ok(report)
}

/// The page data of `input` (what the page's script reads), as JSON.
pub fn view_data(input: &ViewInput) -> Value {
    let ws = input.workspace;
    // Obstacles that share one shape (a mesh placed many times, read once: see
    // `world::MeshCache`) carry its triangles once; the others name the first (`same_as`).
    let mut first_of: std::collections::HashMap<usize, usize> = Default::default();
    let obstacles: Vec<Value> = ws
        .obstacles
        .iter()
        .enumerate()
        .map(|(k, o)| {
            let representation = match &o.geometry {
                crate::world::obstacle::ObstacleShape::Mesh { representation, .. } => {
                    representation.name()
                }
                g => g.kind(),
            };
            use crate::world::ObstacleShape as S;
            let primitive = match o.geometry {
                S::Sphere { radius } => Some(json!({ "shape": "sphere", "radius": radius })),
                S::Capsule { length, radius } => {
                    Some(json!({ "shape": "capsule", "radius": radius, "length": length }))
                }
                S::Cylinder { length, radius } => {
                    Some(json!({ "shape": "cylinder", "radius": radius, "length": length }))
                }
                S::Cuboid { size } => Some(json!({ "shape": "cuboid", "size": size })),
                S::Mesh { .. } => None,
            };
            // The shapes live in `ws` throughout: their addresses are unique.
            let ptr = std::sync::Arc::as_ptr(&o.shape().0) as *const () as usize;
            let mut v = match first_of.get(&ptr) {
                _ if primitive.is_some() => json!({ "primitive": primitive, "exact": true }),
                Some(&first) => json!({ "same_as": first }),
                None => {
                    first_of.insert(ptr, k);
                    let mut mesh = Mesh::default();
                    let drawn = add_shape(&mut mesh, &Pose::IDENTITY, o.shape().as_ref());
                    let mut v = mesh.to_json();
                    v["exact"] = drawn.into();
                    v
                }
            };
            v["name"] = o.name.clone().into();
            v["kind"] = o.geometry.kind().into();
            v["representation"] = representation.into();
            // Each value as its shortest `f32` decimal: the page reads `f32` (and a cell of
            // many obstacles pays for every digit).
            let pose: Vec<f64> = pose7(o.pose())
                .iter()
                .map(|x| x.to_string().parse().unwrap_or(0.0))
                .collect();
            v["pose"] = pose.into();
            v
        })
        .collect();
    let chain = input.chain;
    let body = input.body;
    let mut frames = chain.frames();
    let mut placed = Placed::default();
    let mut home = Vec::new();
    push_sample(
        chain,
        body,
        chain.home(),
        &mut frames,
        &mut placed,
        &mut home,
    );
    let segments: Vec<Value> = (0..body.segments())
        .map(|s| {
            json!({
                "radius": body.radius(s),
                "link": body.link(s),
                "frame": body.frame(s),
            })
        })
        .collect();
    let solids: Vec<Value> = body
        .solids()
        .iter()
        .enumerate()
        .map(|(k, s)| {
            // Local to the solid: its placed world pose is sampled per frame.
            let mut mesh = Mesh::default();
            add_shape(&mut mesh, &Pose::IDENTITY, s.shape.as_ref());
            let mut v = mesh.to_json();
            v["link"] = body.link(body.segments() + k).into();
            v["frame"] = s.frame.clone().into();
            v
        })
        .collect();
    let reached: Vec<Option<&crate::planning::reach::TargetReport>> = (0..ws.tasks.len())
        .map(|i| {
            input
                .report
                .and_then(|r| r.targets.iter().find(|t| t.index == i))
        })
        .collect();
    let tasks: Vec<Value> = ws
        .tasks
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let t = reached[i];
            // The direction the tool's z axis must point along: the approach, or the target
            // rotation's z axis for a full pose.
            let approach = match ws.orientations.get(i) {
                Some(crate::world::TaskOrientation::Approach { axis, .. }) => {
                    Some([axis.x, axis.y, axis.z])
                }
                Some(crate::world::TaskOrientation::Pose { rotation, .. }) => {
                    let z = rotation.matrix().column(2);
                    Some([z[0], z[1], z[2]])
                }
                _ => None,
            };
            let mut v = json!({
                "index": i,
                "point": [p.x, p.y, p.z],
                "reached": t.is_some_and(|t| t.reached),
                "error": t.map(|t| t.error),
                "end_effector": t.map(|t| t.end_effector),
            });
            if let Some(a) = approach {
                v["approach"] = json!(a);
                v["angle_error"] = json!(t.and_then(|t| t.approach_error.or(t.orientation_error)));
            }
            v
        })
        .collect();
    let mut paths = Vec::new();
    if let Some(report) = input.report {
        let reached = report.targets.iter().filter(|t| t.reached).count().max(1);
        let cap = (MAX_SAMPLES_TOTAL / reached).min(MAX_SAMPLES_PER_PATH);
        for t in &report.targets {
            let Some(path) = t.path.as_ref().filter(|_| t.reached) else {
                continue;
            };
            if path.points.iter().any(|p| p.len() != chain.dof()) {
                continue;
            }
            let configs = path_configurations(&path.points, cap);
            let mut data = Vec::with_capacity(configs.len() * sample_stride(chain, body));
            for a in &configs {
                push_sample(chain, body, a, &mut frames, &mut placed, &mut data);
            }
            paths.push(json!({
                "task": t.index,
                "points": path.points.len(),
                "samples": configs.len(),
                "data": b64_f32(&data),
            }));
        }
    }
    let joint_names = input
        .joint_names
        .clone()
        .unwrap_or_else(|| chain.joint_names());
    let design = input.design.map(|d| {
        let links: Vec<Value> = d
            .links
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let axes: Vec<Value> = crate::kinematics::Axis::ALL
                    .iter()
                    .zip(l.axes.0.iter())
                    .filter(|(_, r)| r.max > r.min || r.min != 0.0)
                    .map(|(axis, r)| json!({"axis": axis.name(), "min": r.min, "max": r.max}))
                    .collect();
                json!({
                    "link": i + 1,
                    "a": l.a,
                    "d": l.d,
                    "alpha": l.alpha,
                    "theta": l.theta,
                    "length": l.a.abs() + l.d.abs(),
                    "axes": axes,
                })
            })
            .collect();
        json!({
            "links": links,
            "total_length": d.total_length(),
            "links_kept": d.links_kept(),
            "joints_kept": d.joints_kept(),
            "link_radius": d.link_radius,
        })
    });
    let run = input.run.map(|r| {
        let s = r.summary;
        json!({
            "seed": s.seed,
            "optimizer": s.optimizer,
            "checker": s.checker,
            "l_max": s.l_max,
            "elapsed_s": s.elapsed_s,
            "evaluations": s.evaluations,
            "generations": s.generations,
            "stopped": s.stopped,
            "cost": s.cost,
            "reachability": s.reachability,
            "breakdown": s.breakdown,
            "robust_reachability": s.robust_reachability,
            "history": r.history.iter().map(|h| [h.elapsed_s, h.best_reachability, h.best_cost]).collect::<Vec<_>>(),
            "convergence_svg": r.convergence_svg.map(|svg| base64::engine::general_purpose::STANDARD.encode(svg)),
        })
    });
    let reach = input.report.map(|r| {
        json!({
            "reachability": r.reachability,
            "checker": r.checker,
            "l_max": r.l_max,
            "seed": r.seed,
            "iterations": r.iterations,
            "nodes": r.nodes,
            "edge_checks": r.edge_checks,
            "home_blocked": r.home_blocked,
        })
    });
    // The tree as line segments between each node's end effector and its parent's.
    let tree = input.report.and_then(|r| r.tree.as_ref()).map(|t| {
        let mut points: Vec<f32> = Vec::with_capacity(t.end_effectors.len() * 6);
        for (i, &p) in t.parents.iter().enumerate() {
            let p = p as usize;
            if p == i || p >= t.end_effectors.len() {
                continue;
            }
            for e in [t.end_effectors[p], t.end_effectors[i]] {
                points.extend(e.iter().map(|&v| v as f32));
            }
        }
        json!({
            "nodes": t.end_effectors.len(),
            "edges": points.len() / 6,
            "segments": b64_f32(&points),
        })
    });
    json!({
        "format": "kinsynth-view 1",
        "title": input.title,
        "clearance": ws.clearance,
        "obstacles": obstacles,
        "tasks": tasks,
        "robot": {
            "links": chain.link_count(),
            "dof": chain.dof(),
            "joint_names": joint_names,
            "segments": segments,
            "solids": solids,
            "frames": chain.link_count() + 1,
            "stride": sample_stride(chain, body),
            "home": b64_f32(&home),
        },
        "paths": paths,
        "tree": tree,
        "design": design,
        "reach": reach,
        "run": run,
    })
}

/// The report page of `input`: one HTML file with everything inlined (three.js, the data, the
/// viewer), which opens from `file://` with no network.
pub fn report_html(input: &ViewInput) -> String {
    // `<` never appears outside JSON strings, where `\u003c` means the same: no `</script>`
    // can end the data block early.
    let data = serde_json::to_string(&view_data(input))
        .expect("page data serialises")
        .replace('<', "\\u003c");
    let title = html_escape(&input.title);
    PAGE.replacen("{{TITLE}}", &title, 1)
        .replacen("{{THREE}}", &script_text(THREE_JS), 1)
        .replacen("{{ORBIT}}", &script_text(ORBIT_CONTROLS_JS), 1)
        .replacen("{{DATA}}", &data, 1)
}

/// Writes the report page of `input` to `path` (atomically).
pub fn write_report(input: &ViewInput, path: &Path) -> Result<()> {
    crate::io::write_atomic(path, report_html(input).as_bytes())
}

/// Text for a non-executed `<script>` block: `</script` cannot occur in it (the vendored
/// files contain none; should one, `<\/` means the same in every JavaScript string and regex).
fn script_text(js: &str) -> String {
    js.replace("</script", "<\\/script")
}

/// `text` with the HTML special characters escaped.
fn html_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_configurations_keep_the_points_and_respect_the_cap() {
        let points = vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![1.0, 3.0]];
        let c = path_configurations(&points, MAX_SAMPLES_PER_PATH);
        assert_eq!(c.first(), points.first());
        assert_eq!(c.last(), points.last());
        assert!(c.contains(&points[1]));
        assert_eq!(c.len(), 1 + 2 * SAMPLES_PER_EDGE);
        let long: Vec<Vec<f64>> = (0..1000).map(|i| vec![i as f64]).collect();
        let c = path_configurations(&long, MAX_SAMPLES_PER_PATH);
        assert_eq!(
            c.len(),
            1000,
            "every point, nothing between, when over the cap"
        );
        assert_eq!(
            path_configurations(&[vec![1.0]], MAX_SAMPLES_PER_PATH),
            vec![vec![1.0]]
        );
        // A smaller cap (many paths on one page) keeps the points and fewer samples.
        let c = path_configurations(&points, 5);
        assert_eq!(c.len(), 5);
        assert!(c.contains(&points[1]) && c.last() == points.last());
        assert_eq!(path_configurations(&points, 1), points);
    }

    #[test]
    fn vendored_scripts_have_no_closing_script_tag() {
        assert!(!THREE_JS.contains("</script"));
        assert!(!ORBIT_CONTROLS_JS.contains("</script"));
        assert!(PAGE.contains("{{DATA}}") && PAGE.contains("{{THREE}}"));
    }
}
