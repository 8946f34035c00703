//! Existing serial robots from URDF, as kinsynth [`Chain`]s that the planner can evaluate.
//!
//! Rules (see also the README's "URDF" section):
//!
//! - The URDF's root link is the scenario's world frame. The chain runs from the base frame
//!   (`--base-frame`, default the root) to the tip frame (`--tip-frame`, default the one leaf
//!   below the base; a link with two child joints on the way is an error). The chain's base pose
//!   `F_0` is the base frame's pose in the root (joints above the base taken at zero), moved on
//!   through the leading fixed joints whose child link has no `<collision>`.
//! - Supported joints: `revolute`, `prismatic` (limits from `<limit>`, which must be present,
//!   finite and with `lower < upper`), `continuous` (range `[−π, π]`) and `fixed`. `floating`,
//!   `planar`, `spherical` and `mimic` joints are errors. Link names and joint names are unique.
//! - Each moving joint is a link of the chain: a fixed transform (the fixed joints since the
//!   previous moving joint, folded together, then the joint's origin) and one free axis. An axis
//!   along +x, +y or +z maps to that axis (`Rx`…`Tz`); any other axis is turned onto local z by
//!   a rotation `A` appended to the fixed transform (free axis `Rz` or `Tz`), and `A⁻¹` is
//!   prepended to the next fixed transform. A moving joint whose origin is the identity, directly
//!   after another one, with both axes along +x, +y or +z and in the order of paper Eq. 2, joins
//!   that joint's link instead (so a kinsynth export imports with the design's own links).
//! - A last fixed joint whose child is the tip link `tool0` (as kinsynth exports write it) is
//!   the chain's tool centre point ([`Chain::with_tool`]): its origin becomes the tool transform.
//! - Other trailing fixed joints up to the tip become a last link without axes (the tip's
//!   origin is the end effector), unless they are the identity.
//! - Body (this chain's capsule segments, `reach --body capsules`; the default body is the
//!   links' `<collision>` elements, see [`super::body`]): each link is the polyline from the previous frame's origin to its joint origin. When
//!   the `<collision>` cylinders (or capsules) of the links rigidly attached to the previous
//!   frame form such a polyline (within [`POLYLINE_TOLERANCE`]), that is the body (a kinsynth
//!   export carries its DH bodies this way); otherwise it is the straight segment between the
//!   two origins ([`LinkGeometry::from_transform`]). Prismatic joints get the chain's slider
//!   segment.
//! - Radius: the caller's, else the largest radius of the `<collision>` cylinders, capsules and
//!   spheres between base and tip, else [`DEFAULT_RADIUS`].
//!
//! Joint names are the URDF joint names, in the order of the actuation vector.

use crate::error::{Error, Num, Result};
use crate::export::urdf::{isometry_of, z_to};
use crate::kinematics::{Axis, Chain, Link, LinkGeometry, Range};
use crate::limits::{within, MAX_ANGLE, MAX_LENGTH, MAX_LINKS};
use nalgebra::{IsometryMatrix3, Point3, Translation3, Vector3};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::Path;

/// Capsule radius when neither the caller nor the URDF's collision geometry gives one (m).
pub const DEFAULT_RADIUS: f64 = 0.05;
/// Distance under which collision segment ends count as joined (m).
pub const POLYLINE_TOLERANCE: f64 = 1e-9;
/// Most steps of the search for a body polyline among a link's collision segments; beyond it
/// the body is the straight segment.
pub const POLYLINE_SEARCH_STEPS: usize = 10_000;

/// A URDF robot as a chain.
#[derive(Clone, Debug)]
pub struct UrdfChain {
    /// The URDF's robot name (`<robot name="…">`): an SRDF written for this robot names it so,
    /// as MoveIt requires.
    pub robot: String,
    /// The chain, one link per moving joint (merged as the module documentation says).
    pub chain: Chain,
    /// URDF names of the moving joints, in actuation-vector order.
    pub joint_names: Vec<String>,
    /// The base frame used.
    pub base: String,
    /// The tip frame used.
    pub tip: String,
    /// The capsule radius used.
    pub radius: f64,
    /// Every URDF link from the base to the tip, with the frame that carries it (see
    /// [`CarriedLink`]), in chain order.
    pub carried: Vec<CarriedLink>,
}

/// A URDF link between base and tip and the chain frame that carries it: the frame right
/// after free axis `level − 1` ([`crate::kinematics::Frames::axis_frames`]), or the base `F_0`
/// when `level` is 0.
#[derive(Clone, Debug, PartialEq)]
pub struct CarriedLink {
    /// The URDF link name.
    pub name: String,
    /// Free axes moving it: the carrier is the frame after the last of them.
    pub level: usize,
    /// The link's frame in its carrier frame.
    pub pose: IsometryMatrix3<f64>,
}

fn urdf_err(element: impl Into<String>, reason: impl Into<String>) -> Error {
    Error::Urdf {
        element: element.into(),
        reason: reason.into(),
    }
}

fn describe(j: &urdf_rs::Joint) -> String {
    format!(
        "joint '{}' (parent '{}', child '{}')",
        j.name, j.parent.link, j.child.link
    )
}

/// Reads and parses a URDF file; errors name the file.
pub fn read_urdf(path: &Path) -> Result<urdf_rs::Robot> {
    let text =
        crate::limits::read_text(path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(|source| {
            Error::Read {
                path: path.to_path_buf(),
                source,
            }
        })?;
    crate::limits::check_xml_depth(&text, crate::limits::MAX_XML_DEPTH).map_err(|message| {
        Error::Parse {
            file: path.to_path_buf(),
            message,
        }
    })?;
    let robot = urdf_rs::read_from_string(&text).map_err(|e| Error::Parse {
        file: path.to_path_buf(),
        message: format!(
            "not a valid URDF: {}",
            locate_fault(&text, &e.to_string()).unwrap_or_else(|| e.to_string())
        ),
    })?;
    let fault = roxmltree::Document::parse(&text).ok().and_then(|doc| {
        non_finite(&doc)
            .or_else(|| repeated_name(&doc))
            .or_else(|| missing_limit(&doc))
    });
    match fault {
        Some(fault) => Err(Error::Parse {
            file: path.to_path_buf(),
            message: format!("not a valid URDF: {fault}"),
        }),
        None => Ok(robot),
    }
}

/// The first `<link>` or `<joint>` whose name an earlier one of its kind has, placed on both
/// lines: the parser keeps both, and the chain, paths, trajectories and SRDF pairs are keyed
/// by these names.
fn repeated_name(doc: &roxmltree::Document) -> Option<String> {
    let line = |n: roxmltree::Node| doc.text_pos_at(n.range().start).row;
    let mut seen: HashMap<(&str, &str), roxmltree::Node> = HashMap::new();
    for node in doc.descendants().filter(|n| n.is_element()) {
        let kind = node.tag_name().name();
        if !matches!(kind, "link" | "joint") || schema_of(node).is_none() {
            continue;
        }
        let Some(name) = node.attribute("name") else {
            continue;
        };
        if let Some(first) = seen.insert((kind, name), node) {
            return Some(format!(
                "lines {} and {}: two <{kind}> elements are named '{}'; {kind} names must be unique",
                line(first),
                line(node),
                crate::error::shorten(name)
            ));
        }
    }
    None
}

/// The first revolute or prismatic `<joint>` without a `<limit>` element, placed on its line.
/// The URDF format requires one; the parser would give such a joint the range `[0, 0]`.
fn missing_limit(doc: &roxmltree::Document) -> Option<String> {
    for node in doc.descendants().filter(|n| n.is_element()) {
        if node.tag_name().name() != "joint" || schema_of(node).is_none() {
            continue;
        }
        let Some(kind @ ("revolute" | "prismatic")) = node.attribute("type") else {
            continue;
        };
        let has_limit = node
            .children()
            .any(|c| c.is_element() && c.tag_name().name() == "limit");
        if !has_limit {
            return Some(format!(
                "line {}: joint '{}' is {kind} but has no <limit> element; a {kind} joint needs \
                 one, with lower < upper",
                doc.text_pos_at(node.range().start).row,
                crate::error::shorten(node.attribute("name").unwrap_or(""))
            ));
        }
    }
    None
}

/// The first number attribute ([`NUMERIC`]) of an element the parser reads whose value is not
/// finite (the parser takes `nan`, `inf` and `1e400`), placed on its line.
fn non_finite(doc: &roxmltree::Document) -> Option<String> {
    for node in doc.descendants().filter(|n| n.is_element()) {
        let tag = node.tag_name().name();
        for &(element, attr, _) in &NUMERIC {
            if tag != element || schema_of(node).is_none() {
                continue;
            }
            let Some(value) = node.attribute(attr) else {
                continue;
            };
            let finite = |w: &str| w.parse::<f64>().is_ok_and(f64::is_finite);
            if !value.split_whitespace().all(finite) {
                // The link or joint, and the visual or collision element, that hold it.
                let mut within = String::new();
                for a in node.ancestors().filter(|a| a.is_element()) {
                    let name = a.attribute("name").map(crate::error::shorten);
                    let part = match (a.tag_name().name(), name) {
                        ("link" | "joint", Some(n)) => format!("{} '{n}'", a.tag_name().name()),
                        ("visual" | "collision", Some(n)) => {
                            format!("<{} name=\"{n}\">", a.tag_name().name())
                        }
                        ("visual" | "collision" | "inertial", None) => {
                            format!("<{}>", a.tag_name().name())
                        }
                        _ => continue,
                    };
                    within = if within.is_empty() {
                        part
                    } else {
                        format!("{part}, {within}")
                    };
                }
                return Some(format!(
                    "line {}: {within}: <{tag} {attr}=\"{}\">: every value must be a finite number",
                    doc.text_pos_at(node.range().start).row,
                    crate::error::shorten(value)
                ));
            }
        }
    }
    None
}

/// Numeric attributes of URDF elements, with how many numbers each holds (0: one number).
const NUMERIC: [(&str, &str, usize); 22] = [
    ("origin", "xyz", 3),
    ("origin", "rpy", 3),
    ("axis", "xyz", 3),
    ("box", "size", 3),
    ("mesh", "scale", 3),
    ("cylinder", "radius", 0),
    ("cylinder", "length", 0),
    ("capsule", "radius", 0),
    ("capsule", "length", 0),
    ("sphere", "radius", 0),
    ("limit", "lower", 0),
    ("limit", "upper", 0),
    ("limit", "effort", 0),
    ("limit", "velocity", 0),
    ("mass", "value", 0),
    ("inertia", "ixx", 0),
    ("inertia", "ixy", 0),
    ("inertia", "ixz", 0),
    ("inertia", "iyy", 0),
    ("inertia", "iyz", 0),
    ("inertia", "izz", 0),
    ("color", "rgba", 4),
];

/// Where a URDF that the parser refused goes wrong, when it is one of the common faults the
/// parser's own message does not place: malformed XML (with its line and column), a number
/// attribute that is not a number or has the wrong count of numbers, a `<geometry>` without
/// exactly one shape, or (from the parser's `message`) a missing or repeated attribute or
/// element and an unknown joint type or shape ([`locate_schema_fault`]). `None` when none is
/// found (the parser's message is then shown).
fn locate_fault(text: &str, message: &str) -> Option<String> {
    let doc = match roxmltree::Document::parse(text) {
        Ok(doc) => doc,
        // Malformed XML: the XML reader's message has the true line and column.
        Err(e) => return Some(e.to_string()),
    };
    let line = |n: roxmltree::Node| doc.text_pos_at(n.range().start).row;
    for node in doc.descendants().filter(|n| n.is_element()) {
        let tag = node.tag_name().name();
        for &(element, attr, count) in &NUMERIC {
            if tag != element {
                continue;
            }
            let Some(value) = node.attribute(attr) else {
                continue;
            };
            let words: Vec<&str> = value.split_whitespace().collect();
            // The line is found only for the fault (each lookup scans the text).
            let at = || format!("line {}: <{tag} {attr}=\"{value}\">", line(node));
            if let Some(bad) = words.iter().find(|w| w.parse::<f64>().is_err()) {
                return Some(format!("{}: \"{bad}\" is not a number", at()));
            }
            let expected = count.max(1);
            if words.len() != expected {
                return Some(format!(
                    "{}: {} numbers, expected {expected}",
                    at(),
                    words.len()
                ));
            }
        }
        if tag == "geometry" {
            let shapes: Vec<&str> = node
                .children()
                .filter(|c| c.is_element())
                .map(|c| c.tag_name().name())
                .collect();
            if shapes.len() != 1 {
                return Some(format!(
                    "line {}: <geometry> holds {} shapes ({}); it must hold exactly one",
                    line(node),
                    shapes.len(),
                    shapes.join(", ")
                ));
            }
        }
    }
    locate_schema_fault(&doc, message)
}

/// The URDF elements the parser reads, as `parent/element` (the root is `<robot>`), with their
/// required attributes, required child elements, and child elements allowed at most once.
/// Elements elsewhere (such as `<gazebo>` extensions) are not read, so not checked.
#[allow(clippy::type_complexity)]
const SCHEMA: [(&str, &[&str], &[&str], &[&str]); 30] = [
    ("robot/link", &["name"], &[], &["inertial"]),
    (
        "robot/joint",
        &["name", "type"],
        &["parent", "child"],
        &[
            "origin",
            "parent",
            "child",
            "axis",
            "limit",
            "calibration",
            "dynamics",
            "mimic",
            "safety_controller",
        ],
    ),
    ("robot/material", &["name"], &[], &["color", "texture"]),
    ("material/color", &["rgba"], &[], &[]),
    ("material/texture", &["filename"], &[], &[]),
    (
        "link/inertial",
        &[],
        &["mass", "inertia"],
        &["origin", "mass", "inertia"],
    ),
    ("inertial/origin", &[], &[], &[]),
    ("inertial/mass", &["value"], &[], &[]),
    (
        "inertial/inertia",
        &["ixx", "ixy", "ixz", "iyy", "iyz", "izz"],
        &[],
        &[],
    ),
    (
        "link/visual",
        &[],
        &["geometry"],
        &["origin", "geometry", "material"],
    ),
    (
        "link/collision",
        &[],
        &["geometry"],
        &["origin", "geometry"],
    ),
    ("visual/origin", &[], &[], &[]),
    ("collision/origin", &[], &[], &[]),
    ("visual/geometry", &[], &[], &[]),
    ("collision/geometry", &[], &[], &[]),
    ("visual/material", &[], &[], &["color", "texture"]),
    ("geometry/box", &["size"], &[], &[]),
    ("geometry/cylinder", &["radius", "length"], &[], &[]),
    ("geometry/capsule", &["radius", "length"], &[], &[]),
    ("geometry/sphere", &["radius"], &[], &[]),
    ("geometry/mesh", &["filename"], &[], &[]),
    ("joint/origin", &[], &[], &[]),
    ("joint/parent", &["link"], &[], &[]),
    ("joint/child", &["link"], &[], &[]),
    ("joint/axis", &["xyz"], &[], &[]),
    ("joint/limit", &["velocity"], &[], &[]),
    ("joint/mimic", &["joint"], &[], &[]),
    ("joint/safety_controller", &["k_velocity"], &[], &[]),
    ("joint/calibration", &[], &[], &[]),
    ("joint/dynamics", &[], &[], &[]),
];

/// The schema entry of an element the parser reads (every ancestor read too), if any.
#[allow(clippy::type_complexity)]
fn schema_of(
    node: roxmltree::Node,
) -> Option<&'static (
    &'static str,
    &'static [&'static str],
    &'static [&'static str],
    &'static [&'static str],
)> {
    let parent = node.parent_element()?;
    let key = format!("{}/{}", parent.tag_name().name(), node.tag_name().name());
    let entry = SCHEMA.iter().find(|e| e.0 == key)?;
    if parent.tag_name().name() == "robot" {
        return parent.parent_element().is_none().then_some(entry);
    }
    schema_of(parent).map(|_| entry)
}

/// Places the parser's "missing field", "duplicate field" and "unknown variant" faults (whose
/// messages have no line) on the first element read by the parser that has them.
fn locate_schema_fault(doc: &roxmltree::Document, message: &str) -> Option<String> {
    let quoted = |key: &str| -> Option<String> {
        let rest = &message[message.find(key)? + key.len()..];
        let rest = rest.strip_prefix('`')?;
        Some(rest[..rest.find('`')?].to_string())
    };
    let said = message.trim_start_matches("custom: ");
    let name_of = |n: roxmltree::Node| match n.attribute("name") {
        Some(v) => format!(
            "<{} name=\"{}\">",
            n.tag_name().name(),
            crate::error::shorten(v)
        ),
        None => format!("<{}>", n.tag_name().name()),
    };
    let line = |n: roxmltree::Node| doc.text_pos_at(n.range().start).row;
    let children = |n: roxmltree::Node, tag: &str| {
        n.children()
            .filter(|c| c.is_element() && c.tag_name().name() == tag)
            .count()
    };
    let read = doc
        .descendants()
        .filter(|n| n.is_element())
        .filter_map(|n| schema_of(n).map(|e| (n, e)));
    if let Some(field) = quoted("missing field ") {
        for (n, (_, attrs, required, _)) in read {
            if attrs.contains(&field.as_str()) && n.attribute(field.as_str()).is_none() {
                return Some(format!(
                    "line {}: {} has no {field}=\"…\" attribute; it is required",
                    line(n),
                    name_of(n)
                ));
            }
            if required.contains(&field.as_str()) && children(n, &field) == 0 {
                return Some(format!(
                    "line {}: {} has no <{field}> element; it is required",
                    line(n),
                    name_of(n)
                ));
            }
        }
    } else if let Some(field) = quoted("duplicate field ") {
        for (n, (_, _, _, single)) in read {
            let count = children(n, &field);
            if single.contains(&field.as_str()) && count > 1 {
                return Some(format!(
                    "line {}: {} holds {count} <{field}> elements; at most one is allowed",
                    line(n),
                    name_of(n)
                ));
            }
        }
    } else if let Some(value) = quoted("unknown variant ") {
        for (n, (key, _, _, _)) in read {
            let joint_type = *key == "robot/joint" && n.attribute("type") == Some(value.as_str());
            let shape = key.ends_with("/geometry") && children(n, &value) > 0;
            if joint_type || shape {
                return Some(format!("line {}: {}: {said}", line(n), name_of(n)));
            }
        }
    }
    None
}

/// [`read_urdf`] then [`chain_from_urdf`]; every error names the file.
pub fn load_chain(
    path: &Path,
    base: Option<&str>,
    tip: Option<&str>,
    radius: Option<f64>,
    colliders_per_link: usize,
) -> Result<UrdfChain> {
    let robot = read_urdf(path)?;
    chain_from_urdf(&robot, base, tip, radius, colliders_per_link).map_err(|e| e.in_file(path))
}

/// Segments of the `<collision>` cylinders and capsules of a link, in its frame.
fn collision_segments(link: &urdf_rs::Link) -> Vec<[Point3<f64>; 2]> {
    link.collision
        .iter()
        .filter_map(|c| match c.geometry {
            urdf_rs::Geometry::Cylinder { length, .. }
            | urdf_rs::Geometry::Capsule { length, .. } => {
                let t = isometry_of(&c.origin);
                let h = t.rotation * Vector3::new(0.0, 0.0, 0.5 * length);
                let m = Point3::from(t.translation.vector);
                Some([m - h, m + h])
            }
            _ => None,
        })
        .collect()
}

/// Largest radius of a link's collision cylinders, capsules and spheres.
fn collision_radius(link: &urdf_rs::Link) -> Option<f64> {
    link.collision
        .iter()
        .filter_map(|c| match c.geometry {
            urdf_rs::Geometry::Cylinder { radius, .. }
            | urdf_rs::Geometry::Capsule { radius, .. }
            | urdf_rs::Geometry::Sphere { radius } => Some(radius),
            _ => None,
        })
        // A NaN radius wins, so that it is reported.
        .reduce(|a, b| {
            if a.is_nan() || b.is_nan() {
                f64::NAN
            } else {
                a.max(b)
            }
        })
}

/// A polyline from `from` to `to` made of `segs` (each used once, either way round), by
/// depth-first search; its ends are exactly `from` and `to`.
fn find_polyline(
    segs: &[[Point3<f64>; 2]],
    from: Point3<f64>,
    to: Point3<f64>,
) -> Option<Vec<Point3<f64>>> {
    fn walk(
        segs: &[[Point3<f64>; 2]],
        used: &mut [bool],
        at: Point3<f64>,
        to: Point3<f64>,
        out: &mut Vec<Point3<f64>>,
        budget: &mut usize,
    ) -> bool {
        if (at - to).norm() <= POLYLINE_TOLERANCE && out.len() > 1 {
            return true;
        }
        // Many coincident segments would make the search exponential: give up (the body is
        // then the straight segment).
        if *budget == 0 {
            return false;
        }
        *budget -= 1;
        for k in 0..segs.len() {
            if used[k] {
                continue;
            }
            for (a, b) in [(0, 1), (1, 0)] {
                if (segs[k][a] - at).norm() <= POLYLINE_TOLERANCE {
                    used[k] = true;
                    out.push(segs[k][b]);
                    if walk(segs, used, segs[k][b], to, out, budget) {
                        return true;
                    }
                    out.pop();
                    used[k] = false;
                }
            }
        }
        false
    }
    if segs.len() > 64 {
        return None;
    }
    let mut used = vec![false; segs.len()];
    let mut out = vec![from];
    let mut budget = POLYLINE_SEARCH_STEPS;
    if walk(segs, &mut used, from, to, &mut out, &mut budget) {
        out[0] = from;
        let last = out.len() - 1;
        out[last] = to;
        Some(out)
    } else {
        None
    }
}

/// The body from the previous frame's origin to `transform`'s origin: a polyline of the
/// collision segments of `group` (links with their poses in the previous frame), if they form
/// one, else the straight segment.
fn link_geometry(
    transform: IsometryMatrix3<f64>,
    group: &[(&urdf_rs::Link, IsometryMatrix3<f64>)],
) -> LinkGeometry {
    let straight = LinkGeometry::from_transform(transform);
    let end = Point3::from(transform.translation.vector);
    if end.coords.norm() == 0.0 {
        return straight;
    }
    let segs: Vec<[Point3<f64>; 2]> = group
        .iter()
        .flat_map(|(l, pose)| {
            collision_segments(l)
                .into_iter()
                .map(move |[a, b]| [pose * a, pose * b])
        })
        .collect();
    match find_polyline(&segs, Point3::origin(), end) {
        Some(body) => LinkGeometry { transform, body },
        None => straight,
    }
}

fn is_identity(t: &IsometryMatrix3<f64>) -> bool {
    t.translation.vector == Vector3::zeros() && t.rotation == nalgebra::Rotation3::identity()
}

/// The chain axis of a URDF joint axis: `(axis, None)` for +x, +y, +z, else `Rz`/`Tz` with the
/// rotation that turns local z onto it.
fn chain_axis(
    j: &urdf_rs::Joint,
    rotation: bool,
) -> Result<(Axis, Option<nalgebra::Rotation3<f64>>)> {
    let v = Vector3::from(j.axis.xyz.0);
    let n = v.norm();
    if !(n.is_finite() && n > 0.0) {
        return Err(urdf_err(
            describe(j),
            format!("axis {:?} has no direction", j.axis.xyz.0),
        ));
    }
    let d = v / n;
    let unit = [Vector3::x(), Vector3::y(), Vector3::z()];
    if let Some(k) = unit.iter().position(|u| *u == d) {
        let axis = Axis::ALL[if rotation { k } else { k + 3 }];
        return Ok((axis, None));
    }
    let axis = if rotation { Axis::Rz } else { Axis::Tz };
    Ok((axis, Some(z_to(&d))))
}

/// The joint's `<origin>` must be finite, its `xyz` within ±[`MAX_LENGTH`] m and its `rpy`
/// within ±[`MAX_ANGLE`] rad.
fn check_origin(j: &urdf_rs::Joint) -> Result<()> {
    let (xyz, rpy) = (j.origin.xyz.0, j.origin.rpy.0);
    for (name, v, bound, unit) in [
        ("xyz", xyz, MAX_LENGTH, "m"),
        ("rpy", rpy, MAX_ANGLE, "rad"),
    ] {
        if !v.iter().all(|&c| within(c, bound)) {
            return Err(urdf_err(
                describe(j),
                format!(
                    "<origin {name}=\"{} {} {}\">: every value must be finite and within ±{bound} {unit}",
                    Num(v[0]),
                    Num(v[1]),
                    Num(v[2])
                ),
            ));
        }
    }
    Ok(())
}

fn joint_range(j: &urdf_rs::Joint) -> Result<Range> {
    if j.joint_type == urdf_rs::JointType::Continuous {
        return Ok(Range::new(-PI, PI));
    }
    let (lo, hi) = (j.limit.lower, j.limit.upper);
    let (bound, unit) = if j.joint_type == urdf_rs::JointType::Prismatic {
        (MAX_LENGTH, "m")
    } else {
        (MAX_ANGLE, "rad")
    };
    if lo.is_finite() && hi.is_finite() && lo < hi && !(within(lo, bound) && within(hi, bound)) {
        return Err(urdf_err(
            describe(j),
            format!(
                "<limit lower=\"{}\" upper=\"{}\">: limits must lie within ±{bound} {unit}",
                Num(lo),
                Num(hi)
            ),
        ));
    }
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(urdf_err(
            describe(j),
            format!(
                "<limit lower=\"{lo}\" upper=\"{hi}\">: a {} joint needs finite limits with lower < upper",
                if j.joint_type == urdf_rs::JointType::Revolute { "revolute" } else { "prismatic" }
            ),
        ));
    }
    Ok(Range::new(lo, hi))
}

/// The chain of a URDF robot from `base` (default: the root link) to `tip` (default: the leaf
/// below the base), with capsule `radius` (default: the URDF's collision radius, else
/// [`DEFAULT_RADIUS`]) and `colliders_per_link` point colliders per link. See the module
/// documentation for the mapping; errors name the joint or link and what is wrong.
pub fn chain_from_urdf(
    robot: &urdf_rs::Robot,
    base: Option<&str>,
    tip: Option<&str>,
    radius: Option<f64>,
    colliders_per_link: usize,
) -> Result<UrdfChain> {
    let links: HashMap<&str, &urdf_rs::Link> =
        robot.links.iter().map(|l| (l.name.as_str(), l)).collect();
    let mut parent_joint: HashMap<&str, &urdf_rs::Joint> = HashMap::new();
    let mut child_joints: HashMap<&str, Vec<&urdf_rs::Joint>> = HashMap::new();
    for j in &robot.joints {
        for (role, l) in [("parent", &j.parent.link), ("child", &j.child.link)] {
            if !links.contains_key(l.as_str()) {
                return Err(urdf_err(
                    describe(j),
                    format!("its {role} link '{l}' is not defined"),
                ));
            }
        }
        if let Some(other) = parent_joint.insert(&j.child.link, j) {
            return Err(urdf_err(
                format!("link '{}'", j.child.link),
                format!(
                    "not a tree: it is the child of two joints, '{}' and '{}'",
                    other.name, j.name
                ),
            ));
        }
        child_joints.entry(&j.parent.link).or_default().push(j);
    }
    let base = match base {
        Some(b) => {
            if !links.contains_key(b) {
                return Err(urdf_err(
                    format!("base frame '{b}'"),
                    "no link of that name",
                ));
            }
            b.to_string()
        }
        None => {
            let roots: Vec<&str> = robot
                .links
                .iter()
                .map(|l| l.name.as_str())
                .filter(|l| !parent_joint.contains_key(l))
                .collect();
            match roots.as_slice() {
                [r] => r.to_string(),
                [] if robot.links.is_empty() => {
                    return Err(urdf_err(
                        format!("robot '{}'", robot.name),
                        "no <link> elements: not a URDF robot (an SRDF goes to --srdf)",
                    ))
                }
                [] => {
                    // Every link is some joint's child: following the parents from any link
                    // comes back round; the joint that closes the loop is named.
                    let mut seen = std::collections::HashSet::new();
                    let mut at = robot.links[0].name.as_str();
                    let j = loop {
                        let j = parent_joint[at];
                        if !seen.insert(at) {
                            break j;
                        }
                        at = &j.parent.link;
                    };
                    return Err(urdf_err(
                        describe(j),
                        format!(
                            "not a tree: no root link (every link is some joint's child); the joints form a cycle through link '{at}'"
                        ),
                    ));
                }
                _ => {
                    return Err(urdf_err(
                        format!("robot '{}'", robot.name),
                        format!(
                            "not a tree: several root links ({}); pick one with --base-frame",
                            roots.join(", ")
                        ),
                    ))
                }
            }
        }
    };
    // Joints from the base down to the tip.
    let (path, tip) = match tip {
        Some(t) => {
            if !links.contains_key(t) {
                return Err(urdf_err(format!("tip frame '{t}'"), "no link of that name"));
            }
            let mut path = Vec::new();
            let mut at = t;
            while at != base {
                let Some(j) = parent_joint.get(at) else {
                    return Err(urdf_err(
                        format!("tip frame '{t}'"),
                        format!("not below the base frame '{base}'"),
                    ));
                };
                if path.len() > robot.joints.len() {
                    return Err(urdf_err(describe(j), "not a tree: the joints form a cycle"));
                }
                path.push(*j);
                at = &j.parent.link;
            }
            path.reverse();
            (path, t.to_string())
        }
        None => {
            let mut path = Vec::new();
            let mut at = base.as_str();
            loop {
                match child_joints.get(at).map(Vec::as_slice).unwrap_or(&[]) {
                    [] => break,
                    [j] => {
                        if path.len() > robot.joints.len() {
                            return Err(urdf_err(
                                describe(j),
                                "not a tree: the joints form a cycle",
                            ));
                        }
                        path.push(*j);
                        at = &j.child.link;
                    }
                    many => {
                        let names: Vec<&str> = many.iter().map(|j| j.name.as_str()).collect();
                        return Err(urdf_err(
                            format!("link '{at}'"),
                            format!(
                                "branch between base '{base}' and tip: child joints {}; pick a tip with --tip-frame",
                                names.join(", ")
                            ),
                        ));
                    }
                }
            }
            (path, at.to_string())
        }
    };
    for j in &path {
        use urdf_rs::JointType as T;
        let kind = match j.joint_type {
            T::Revolute | T::Continuous | T::Prismatic | T::Fixed => None,
            T::Floating => Some("floating"),
            T::Planar => Some("planar"),
            T::Spherical => Some("spherical"),
        };
        if let Some(kind) = kind {
            return Err(urdf_err(
                describe(j),
                format!("unsupported joint type '{kind}' (supported: revolute, continuous, prismatic, fixed)"),
            ));
        }
        if j.mimic.is_some() && j.joint_type != T::Fixed {
            return Err(urdf_err(describe(j), "mimic joints are not supported"));
        }
        check_origin(j)?;
    }
    let moving = path
        .iter()
        .filter(|j| j.joint_type != urdf_rs::JointType::Fixed)
        .count();
    if moving > MAX_LINKS {
        return Err(urdf_err(
            format!("chain '{base}' → '{tip}'"),
            format!("{moving} moving joints, more than the limit of {MAX_LINKS}"),
        ));
    }
    // The base frame's pose in the root.
    let mut base_pose = IsometryMatrix3::identity();
    {
        let mut at = base.as_str();
        let mut up = Vec::new();
        while let Some(j) = parent_joint.get(at) {
            if up.len() > robot.joints.len() {
                return Err(urdf_err(describe(j), "not a tree: the joints form a cycle"));
            }
            check_origin(j)?;
            up.push(isometry_of(&j.origin));
            at = &j.parent.link;
        }
        for t in up.iter().rev() {
            base_pose *= t;
        }
    }
    let radius = match radius {
        Some(r) => {
            if !(r >= 0.0 && within(r, MAX_LENGTH)) {
                return Err(Error::invalid(
                    "radius",
                    Num(r),
                    format!("must be finite, not negative and at most {MAX_LENGTH} m"),
                ));
            }
            r
        }
        None => {
            let mut radius: Option<f64> = None;
            for l in
                std::iter::once(base.as_str()).chain(path.iter().map(|j| j.child.link.as_str()))
            {
                if let Some(r) = collision_radius(links[l]) {
                    if !(r >= 0.0 && within(r, MAX_LENGTH)) {
                        return Err(urdf_err(
                            format!("link '{l}'"),
                            format!(
                                "<collision> radius {}: must be finite, not negative and at most {MAX_LENGTH} m",
                                Num(r)
                            ),
                        ));
                    }
                    radius = Some(radius.map_or(r, |best| best.max(r)));
                }
            }
            radius.unwrap_or(DEFAULT_RADIUS)
        }
    };

    // Links rigidly attached to the current chain frame, with their poses in it.
    let mut group: Vec<(&urdf_rs::Link, IsometryMatrix3<f64>)> =
        vec![(links[base.as_str()], IsometryMatrix3::identity())];
    let carry = |name: &str, level: usize, pose: IsometryMatrix3<f64>| CarriedLink {
        name: name.to_string(),
        level,
        pose,
    };
    let mut carried = vec![carry(&base, 0, IsometryMatrix3::identity())];
    // Pose of the current URDF link in the current chain frame.
    let mut pending = IsometryMatrix3::identity();
    let mut chain_links: Vec<Link> = Vec::new();
    let mut names = Vec::new();
    // The link being built: can it take more axes (identity origin, coordinate axes)?
    let mut open: Option<(Link, Axis, bool)> = None;
    let mut started = false;
    // The leading fixed joints' product so far: the links before the chain starts are kept
    // in the first base frame, and `start` moves them into the last.
    let mut lead = IsometryMatrix3::identity();
    let start = |started: &mut bool,
                 lead: &mut IsometryMatrix3<f64>,
                 group: &mut Vec<(&urdf_rs::Link, IsometryMatrix3<f64>)>,
                 carried: &mut Vec<CarriedLink>| {
        if !*started {
            let inv = lead.inverse();
            for (_, pose) in group.iter_mut() {
                *pose = inv * *pose;
            }
            for c in carried.iter_mut() {
                c.pose = inv * c.pose;
            }
            *lead = IsometryMatrix3::identity();
            *started = true;
        }
    };
    let mut tool = IsometryMatrix3::identity();
    let last = path.len().saturating_sub(1);
    for (k, j) in path.iter().enumerate() {
        let origin = isometry_of(&j.origin);
        let child = links[j.child.link.as_str()];
        if k == last
            && started
            && j.joint_type == urdf_rs::JointType::Fixed
            && j.child.link == crate::export::urdf::TOOL_LINK
        {
            // The tool centre point: carried by the last frame, not a link of its own.
            tool = origin;
            group.push((child, pending * origin));
            carried.push(carry(&child.name, names.len(), pending * origin));
            continue;
        }
        if j.joint_type == urdf_rs::JointType::Fixed {
            if !started && child.collision.is_empty() {
                // Leading fixed joint to a link without geometry: part of the base pose. The
                // links so far are kept in the first base frame and moved into the last one
                // once, when the chain starts (one pass, however many such joints).
                base_pose *= origin;
                lead *= origin;
                group.push((child, lead));
                carried.push(carry(&child.name, 0, lead));
                continue;
            }
            start(&mut started, &mut lead, &mut group, &mut carried);
            pending *= origin;
            group.push((child, pending));
            carried.push(carry(&child.name, names.len(), pending));
            continue;
        }
        start(&mut started, &mut lead, &mut group, &mut carried);
        let rotation = j.joint_type != urdf_rs::JointType::Prismatic;
        let (axis, align) = chain_axis(j, rotation)?;
        let range = joint_range(j)?;
        let full = pending * origin;
        if let Some((link, last, true)) = &mut open {
            if align.is_none() && is_identity(&full) && axis > *last {
                link.ranges[axis.index()] = range;
                *last = axis;
                names.push(j.name.clone());
                group = vec![(child, IsometryMatrix3::identity())];
                carried.push(carry(&child.name, names.len(), IsometryMatrix3::identity()));
                continue;
            }
        }
        if let Some((link, _, _)) = open.take() {
            chain_links.push(link);
        }
        let align_iso = align.map_or_else(IsometryMatrix3::identity, |r| {
            IsometryMatrix3::from_parts(Translation3::identity(), r)
        });
        let transform = full * align_iso;
        let mut ranges = [Range::ZERO; 6];
        ranges[axis.index()] = range;
        open = Some((
            Link {
                geometry: link_geometry(transform, &group),
                ranges,
            },
            axis,
            align.is_none(),
        ));
        names.push(j.name.clone());
        pending = align_iso.inverse();
        group = vec![(child, pending)];
        carried.push(carry(&child.name, names.len(), pending));
    }
    let Some((link, _, _)) = open else {
        return Err(urdf_err(
            format!("chain '{base}' → '{tip}'"),
            "no moving joint (revolute, continuous or prismatic) between base and tip",
        ));
    };
    chain_links.push(link);
    if !is_identity(&pending) {
        chain_links.push(Link {
            geometry: link_geometry(pending, &group),
            ranges: [Range::ZERO; 6],
        });
    }
    Ok(UrdfChain {
        robot: robot.name.clone(),
        chain: Chain::new(base_pose, &chain_links, radius, colliders_per_link).with_tool(tool),
        joint_names: names,
        base,
        tip,
        radius,
        carried,
    })
}

/// Replaces the joint names of every path in `report` with `names` (the URDF joint names of an
/// imported chain, in actuation-vector order), so the paths replay on that URDF; the paths
/// stay within the report's limit with those names
/// ([`crate::planning::reach::rename_joints`]).
pub fn rename_joints(report: &mut crate::planning::ReachReport, names: &[String]) {
    crate::planning::reach::rename_joints(report, names);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Leading fixed joints to links without geometry become the base pose, and every link
    /// before the chain starts is carried by the base frame at its pose there: on a chain of
    /// 2,000 such joints (turned and moved) before a revolute one, the base pose times each
    /// carried pose is the product of the joints' origins up to that link.
    #[test]
    fn leading_fixed_joints_make_the_base_pose() {
        let n = 2_000;
        let mut xml = String::from("<robot name=\"r\">");
        for i in 0..=n + 1 {
            xml += &format!("<link name=\"l{i}\"/>");
        }
        let origin = |i: usize| {
            let f = i as f64;
            (
                [0.01 * (f * 0.7).sin(), 0.02, 0.001 * f.cos()],
                [0.3 * (f * 1.3).sin(), 0.2 * f.cos(), 0.1],
            )
        };
        for i in 0..n {
            let (xyz, rpy) = origin(i);
            xml += &format!(
                "<joint name=\"f{i}\" type=\"fixed\"><parent link=\"l{i}\"/><child link=\"l{}\"/><origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/></joint>",
                i + 1, xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]
            );
        }
        xml += &format!(
            "<joint name=\"j\" type=\"revolute\"><parent link=\"l{n}\"/><child link=\"l{}\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>",
            n + 1
        );
        let robot = urdf_rs::read_from_string(&xml).unwrap();
        let u = chain_from_urdf(&robot, None, None, None, 4).unwrap();
        let base = *u.chain.base();
        let mut world = IsometryMatrix3::identity();
        for i in 0..=n {
            if i > 0 {
                let (xyz, rpy) = origin(i - 1);
                world *= IsometryMatrix3::from_parts(
                    Translation3::new(xyz[0], xyz[1], xyz[2]),
                    nalgebra::Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]),
                );
            }
            let c = &u.carried[i];
            assert_eq!((c.name.as_str(), c.level), (format!("l{i}").as_str(), 0));
            let placed = base * c.pose;
            let moved = (placed.translation.vector - world.translation.vector).norm();
            let turned = (placed.rotation.matrix() - world.rotation.matrix()).norm();
            assert!(
                moved < 1e-9 && turned < 1e-9,
                "link {i}: {placed} against {world}"
            );
        }
        assert!((base.inverse() * world).translation.vector.norm() < 1e-9);
    }

    #[test]
    fn polyline_search_backtracks_and_orients_segments() {
        let p = |x, y| Point3::new(x, y, 0.0);
        let segs = [
            [p(-1.0, 0.0), p(0.0, 0.0)], // a dead end at the start
            [p(1.0, 1.0), p(1.0, 0.0)],  // reversed
            [p(0.0, 0.0), p(1.0, 0.0)],
        ];
        let poly = find_polyline(&segs, p(0.0, 0.0), p(1.0, 1.0)).unwrap();
        assert_eq!(poly, vec![p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)]);
        assert!(find_polyline(&segs, p(0.0, 0.0), p(2.0, 0.0)).is_none());
    }

    /// Many coincident collision segments used to make the search try every order of them
    /// (30! here): it now gives up after a bounded number of steps.
    #[test]
    fn polyline_search_of_coincident_segments_is_bounded() {
        let o = Point3::origin();
        let segs = vec![[o, o]; 30];
        assert!(find_polyline(&segs, o, Point3::new(1.0, 0.0, 0.0)).is_none());
    }
}
