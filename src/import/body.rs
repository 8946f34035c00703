//! The robot body of an imported URDF arm: its links' `<collision>` elements as bodies.
//!
//! Rules (see also the README's "URDF" section):
//!
//! - Every URDF link from the base to the tip ([`super::urdf::UrdfChain::carried`]) rides on
//!   the frame right after the last moving joint above it (or on the base), also inside merged
//!   chain links. Links off the base–tip path carry no body.
//! - `<mesh>` (STL, OBJ or COLLADA `.dae`, read by the `mesh-loader` crate, scaled by `scale`)
//!   becomes its convex hull (a parry `ConvexPolyhedron`); `<box>`, `<cylinder>` (along z),
//!   `<sphere>` and `<capsule>` become themselves. A `<cylinder>` with a `<sphere>` of the same
//!   radius at each end centre (as `kinsynth urdf` writes every capsule) is one capsule.
//! - When every body is such a capsule and together they are exactly the chain's capsule
//!   segments (same carrier, same ends within [`MATCH_TOLERANCE`], same radius), the body *is*
//!   the chain's capsule body: a kinsynth export imports with the very body it was planned with.
//!   Otherwise the bodies are solids on a chain without capsule segments
//!   ([`Chain::without_segments`]).
//! - Without any `<collision>` between base and tip, the links are capsules between joint
//!   origins, as with `--body capsules`, and [`ImportedRobot::note`] says so.
//! - `package://NAME/…` resolves against the given packages, else against the folders above
//!   the URDF (a folder named `NAME`, or one holding a folder `NAME`); `file://` and plain
//!   paths resolve relative to the URDF's folder.
//! - An SRDF's `<disable_collisions link1 link2 reason/>` pairs are never checked.

use super::urdf::{chain_from_urdf, read_urdf, UrdfChain};
use crate::collision::body::{DisabledPair, Reason, RobotBody, SelfCollisionConfig, Solid};
use crate::error::{fmt_list, Error, Num, Result};
use crate::export::urdf::isometry_of;
use crate::kinematics::Chain;
use crate::limits::{within, MAX_ANGLE, MAX_LENGTH, MAX_SETTING};
use crate::world::mesh::hull_of_points;
use nalgebra::{IsometryMatrix3, Point3, Rotation3, Translation3, Vector3};
use parry3d_f64::shape::SharedShape;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Distance (m) within which a capsule's ends count as a chain segment's ends, and a sphere's
/// centre as a cylinder's end centre.
pub const MATCH_TOLERANCE: f64 = 1e-9;

/// Which geometry stands for an imported robot's links (`reach --body`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BodyChoice {
    /// The links' `<collision>` elements (the default).
    #[default]
    Collision,
    /// Capsules along the polyline between joint origins (the importer's chain segments).
    Capsules,
}

impl BodyChoice {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            BodyChoice::Collision => "collision",
            BodyChoice::Capsules => "capsules",
        }
    }
}

impl std::str::FromStr for BodyChoice {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "collision" => Ok(BodyChoice::Collision),
            "capsules" => Ok(BodyChoice::Capsules),
            _ => Err(format!(
                "unknown body `{s}` (expected collision or capsules)"
            )),
        }
    }
}

impl std::fmt::Display for BodyChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What an imported robot's body is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BodyKind {
    /// The chain's capsule segments, one radius for all (`--body capsules`, or no collision
    /// geometry at all).
    Capsules,
    /// The chain's capsule segments, recognised in the `<collision>` elements (a kinsynth
    /// export), each with its own radius.
    CollisionCapsules,
    /// Solids from the `<collision>` elements on a chain without capsule segments.
    Solids,
}

/// How to import a robot's body.
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    /// Collision elements or capsules.
    pub body: BodyChoice,
    /// `package://` roots: `(NAME, DIR)`.
    pub packages: Vec<(String, PathBuf)>,
    /// An SRDF whose `<disable_collisions>` pairs are never checked.
    pub srdf: Option<PathBuf>,
    /// Self-collision settings for the allowed-collision matrix.
    pub self_collision: SelfCollisionConfig,
}

/// A URDF robot with its body.
#[derive(Clone, Debug)]
pub struct ImportedRobot {
    /// The chain (without capsule segments when the body is made of solids) and its names.
    pub urdf: UrdfChain,
    /// The robot body the checkers use.
    pub body: RobotBody,
    /// What the body is made of.
    pub kind: BodyKind,
    /// A remark for the user (for example: no collision geometry, capsules used).
    pub note: Option<String>,
}

impl ImportedRobot {
    /// A frame carrying a body that is not one of the URDF's links between base and tip, if
    /// any: with `--body capsules`, an arm whose links are not named like kinsynth's has its
    /// capsules on frames of kinsynth's own (`link1_dh`, …), which no SRDF of the URDF can name.
    pub fn frame_not_in_urdf(&self) -> Option<&str> {
        (0..self.body.len())
            .map(|b| self.body.frame(b))
            .find(|f| !self.urdf.carried.iter().any(|c| c.name == *f))
    }

    /// Why an SRDF cannot name this robot's bodies, when it cannot ([`Self::frame_not_in_urdf`]),
    /// with what to do about it: `--body capsules` was asked for, or the URDF has no collision
    /// geometry to use instead.
    pub fn srdf_cannot_name(&self) -> Option<String> {
        let frame = self.frame_not_in_urdf()?;
        Some(if self.note.is_some() {
            format!(
                "the robot's bodies lie on frames the URDF does not have (such as '{frame}': the URDF has no <collision> geometry between base and tip, so capsules between joint origins stand in for it); give the URDF's links <collision> elements"
            )
        } else {
            format!(
                "the robot's bodies lie on frames the URDF does not have (such as '{frame}', with --body capsules); use --body collision"
            )
        })
    }
}

/// One collision element, in its carrier frame.
enum Piece {
    /// A capsule from `a` to `b` of radius `r`; `local` has the axis along z, `half` its half
    /// length.
    Capsule {
        a: Point3<f64>,
        b: Point3<f64>,
        r: f64,
        local: IsometryMatrix3<f64>,
        half: f64,
    },
    /// A primitive shape at `local`.
    Shape {
        local: IsometryMatrix3<f64>,
        shape: SharedShape,
    },
    /// A mesh file at `local`, scaled.
    Mesh {
        local: IsometryMatrix3<f64>,
        filename: String,
        scale: [f64; 3],
    },
}

struct Element {
    /// Index into [`UrdfChain::carried`].
    carried: usize,
    piece: Piece,
}

fn link_err(link: &str, reason: impl Into<String>) -> Error {
    Error::Urdf {
        element: format!("link '{link}'"),
        reason: reason.into(),
    }
}

/// Collision element `k` of `link`, checked: its origin finite and within the limits
/// ([`MAX_LENGTH`] m, [`MAX_ANGLE`] rad), every length of its geometry finite, not negative
/// and at most [`MAX_LENGTH`] m (a `-0` becomes `0`), every mesh scale factor finite, not zero
/// and at most [`MAX_SETTING`] in magnitude. The error names the link, the element, the
/// attribute and its value.
/// What makes two box or mesh `<collision>` elements the same body: the box size or the mesh
/// file and scale, and the origin.
type RepeatKey = ([f64; 3], Option<String>, [f64; 3], [f64; 3]);

/// The [`RepeatKey`] of a (checked) box or mesh collision element; `None` for the others.
fn repeat_key(c: &urdf_rs::Collision) -> Option<RepeatKey> {
    use urdf_rs::Geometry as G;
    let (numbers, file) = match &c.geometry {
        G::Box { size } => (size.0, None),
        G::Mesh { filename, scale } => (scale.map_or([1.0; 3], |s| s.0), Some(filename.clone())),
        _ => return None,
    };
    Some((numbers, file, c.origin.xyz.0, c.origin.rpy.0))
}

fn checked_collision(
    link: &urdf_rs::Link,
    k: usize,
    c: &urdf_rs::Collision,
) -> Result<urdf_rs::Collision> {
    use urdf_rs::Geometry as G;
    let element = match &c.name {
        Some(name) => format!("<collision name=\"{name}\">"),
        None => format!("<collision> #{}", k + 1),
    };
    let fail = |what: String| link_err(&link.name, format!("{element} {what}"));
    for (name, v, bound, unit) in [
        ("xyz", c.origin.xyz.0, MAX_LENGTH, "m"),
        ("rpy", c.origin.rpy.0, MAX_ANGLE, "rad"),
    ] {
        if !v.iter().all(|&x| within(x, bound)) {
            return Err(fail(format!(
                "<origin {name}=\"{} {} {}\">: every value must be finite and within ±{bound} {unit}",
                Num(v[0]),
                Num(v[1]),
                Num(v[2])
            )));
        }
    }
    let length = |shape: &str, attr: &str, v: f64| -> Result<f64> {
        if v >= 0.0 && within(v, MAX_LENGTH) {
            Ok(v.abs())
        } else {
            Err(fail(format!(
                "<{shape} {attr}=\"{}\">: must be finite, not negative and at most {MAX_LENGTH} m",
                Num(v)
            )))
        }
    };
    let geometry = match &c.geometry {
        G::Box { size } => {
            let mut size = *size;
            for v in size.0.iter_mut() {
                *v = length("box", "size", *v)?;
            }
            G::Box { size }
        }
        G::Cylinder { radius, length: l } => G::Cylinder {
            radius: length("cylinder", "radius", *radius)?,
            length: length("cylinder", "length", *l)?,
        },
        G::Capsule { radius, length: l } => G::Capsule {
            radius: length("capsule", "radius", *radius)?,
            length: length("capsule", "length", *l)?,
        },
        G::Sphere { radius } => G::Sphere {
            radius: length("sphere", "radius", *radius)?,
        },
        G::Mesh { filename, scale } => {
            if let Some(s) = scale {
                if !s.0.iter().all(|&x| x != 0.0 && within(x, MAX_SETTING)) {
                    return Err(fail(format!(
                        "<mesh scale=\"{} {} {}\">: every factor must be finite, not zero and within ±{MAX_SETTING}",
                        Num(s.0[0]),
                        Num(s.0[1]),
                        Num(s.0[2])
                    )));
                }
            }
            G::Mesh {
                filename: filename.clone(),
                scale: *scale,
            }
        }
    };
    Ok(urdf_rs::Collision {
        name: c.name.clone(),
        origin: c.origin.clone(),
        geometry,
    })
}

/// The collision elements of one URDF link at `pose` in its carrier, with capsule triples
/// (cylinder + end spheres of the same radius) joined; an element with a bad value is an error
/// ([`checked_collision`]).
fn link_pieces(link: &urdf_rs::Link, pose: &IsometryMatrix3<f64>) -> Result<Vec<Piece>> {
    use urdf_rs::Geometry as G;
    let mut collision = link
        .collision
        .iter()
        .enumerate()
        .map(|(k, c)| checked_collision(link, k, c))
        .collect::<Result<Vec<_>>>()?;
    // A mesh or box element repeated exactly (the same geometry at the same origin) adds no
    // body: only the first is kept (hundreds of copies of one mesh made every self pair
    // hundreds squared, each a GJK query). Spheres stay, even repeated: a capsule exported as a
    // cylinder and two spheres may share an end sphere's place with the next one's.
    let mut seen: Vec<RepeatKey> = Vec::new();
    collision.retain(|c| match repeat_key(c) {
        Some(key) if seen.contains(&key) => false,
        Some(key) => {
            seen.push(key);
            true
        }
        None => true,
    });
    let poses: Vec<IsometryMatrix3<f64>> = collision
        .iter()
        .map(|c| pose * isometry_of(&c.origin))
        .collect();
    let mut used = vec![false; collision.len()];
    let mut out = Vec::new();
    let sphere_at = |used: &[bool], r: f64, p: &Point3<f64>| -> Option<usize> {
        collision.iter().enumerate().position(|(k, c)| {
            !used[k]
                && matches!(c.geometry, G::Sphere { radius } if radius == r)
                && (Point3::from(poses[k].translation.vector) - p).norm() <= MATCH_TOLERANCE
        })
    };
    // Cylinders first claim their end spheres.
    let mut capsules = vec![None; collision.len()];
    for (k, c) in collision.iter().enumerate() {
        if let G::Cylinder { radius, length } = c.geometry {
            let t = &poses[k];
            let h = t.rotation * Vector3::new(0.0, 0.0, 0.5 * length);
            let m = Point3::from(t.translation.vector);
            let (a, b) = (m - h, m + h);
            if let Some(s1) = sphere_at(&used, radius, &a) {
                used[s1] = true;
                if let Some(s2) = sphere_at(&used, radius, &b) {
                    used[s2] = true;
                    capsules[k] = Some((a, b));
                } else {
                    used[s1] = false;
                }
            }
        }
    }
    for (k, c) in collision.iter().enumerate() {
        if used[k] {
            continue;
        }
        let local = poses[k];
        out.push(match &c.geometry {
            G::Cylinder { radius, length } => match capsules[k] {
                Some((a, b)) => Piece::Capsule {
                    a,
                    b,
                    r: *radius,
                    local,
                    half: 0.5 * length,
                },
                None => Piece::Shape {
                    // parry's cylinder runs along y, URDF's along z.
                    local: local
                        * IsometryMatrix3::from_parts(
                            Translation3::identity(),
                            Rotation3::from_axis_angle(
                                &Vector3::x_axis(),
                                std::f64::consts::FRAC_PI_2,
                            ),
                        ),
                    shape: SharedShape::cylinder(0.5 * length, *radius),
                },
            },
            G::Capsule { radius, length } => {
                let h = local.rotation * Vector3::new(0.0, 0.0, 0.5 * length);
                let m = Point3::from(local.translation.vector);
                Piece::Capsule {
                    a: m - h,
                    b: m + h,
                    r: *radius,
                    local,
                    half: 0.5 * length,
                }
            }
            G::Sphere { radius } => Piece::Shape {
                local,
                shape: SharedShape::ball(*radius),
            },
            G::Box { size } => Piece::Shape {
                local,
                shape: SharedShape::cuboid(0.5 * size.0[0], 0.5 * size.0[1], 0.5 * size.0[2]),
            },
            G::Mesh { filename, scale } => Piece::Mesh {
                local,
                filename: filename.clone(),
                scale: scale.as_ref().map_or([1.0; 3], |s| s.0),
            },
        });
    }
    Ok(out)
}

/// Where a mesh URI points: `package://NAME/rest` against `packages`, else against the folders
/// above `urdf` (a folder named `NAME`, or one holding a folder `NAME`); `file://` and plain
/// paths relative to the URDF's folder. The error says what could not be resolved.
pub fn resolve_mesh(
    uri: &str,
    urdf: &Path,
    packages: &[(String, PathBuf)],
) -> std::result::Result<PathBuf, String> {
    let dir = match urdf.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if let Some(rest) = uri.strip_prefix("package://") {
        let (name, rel) = rest.split_once('/').unwrap_or((rest, ""));
        if name.is_empty() {
            return Err("a package:// URI without a package name".into());
        }
        if let Some((_, root)) = packages.iter().find(|(n, _)| n == name) {
            return Ok(root.join(rel));
        }
        let start = std::fs::canonicalize(&dir).unwrap_or(dir);
        for up in start.ancestors() {
            if up.file_name().is_some_and(|f| f == name) {
                return Ok(up.join(rel));
            }
            let inside = up.join(name);
            if inside.is_dir() {
                return Ok(inside.join(rel));
            }
        }
        return Err(format!(
            "package '{name}' not found in the folders above the URDF; give --package {name}=DIR"
        ));
    }
    let path = uri.strip_prefix("file://").unwrap_or(uri);
    if path.is_empty() {
        return Err("an empty file name".into());
    }
    let p = Path::new(path);
    Ok(if p.is_absolute() {
        p.to_path_buf()
    } else {
        dir.join(p)
    })
}

/// Checks what the mesh reader trusts in a COLLADA file before it reads it: every size it
/// reserves memory for must fit in the text that holds the values (an array's `count`, a
/// primitive's `count` times its vertices and inputs against its `<p>` indices, input offsets
/// at most `MAX_OFFSET`), and a mesh source holds numbers (the reader never ends on a
/// `<Name_array>` or `<IDREF_array>` with values there). And what the reader panics on: every
/// `source="#id"` in a geometry names an element of the kind it expects, an accessor's stride
/// is not 0, positions and normals are three floats per vertex within their array, and every
/// vertex index names a position; a position accessor reads X, Y, Z first (the reader takes
/// them by place, the format by name). Anything else is left to the reader. Returns an upper bound
/// of the triangles the reader will build (exact for `<triangles>` and `<polylist>`), with the
/// geometries the scene places ([`collada_instances`]).
fn check_collada(text: &str) -> std::result::Result<Collada, String> {
    /// Largest `<input offset>` of a primitive (real files use a handful of inputs).
    const MAX_OFFSET: u64 = 1024;
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("not a readable mesh: {e}"))?;
    // The asset's unit and up axis are not applied (see `collada_instances`), so they are not
    // checked either (the reader needs the unit to be a number and says so).
    let Some(geometries) = doc
        .root_element()
        .children()
        .find(|n| n.has_tag_name("library_geometries"))
    else {
        // Nothing to read (the caller says the file has no triangles).
        return Ok(Collada {
            triangles: 0,
            instances: Vec::new(),
            ids: Vec::new(),
            cut: Vec::new(),
        });
    };
    let number = |n: roxmltree::Node, attr: &str| -> std::result::Result<u64, String> {
        match n.attribute(attr) {
            None => Ok(0),
            Some(v) => v.trim().parse::<u64>().map_err(|_| {
                format!(
                    "<{} {attr}=\"{v}\">: not a whole number",
                    n.tag_name().name()
                )
            }),
        }
    };
    let text_len = |n: roxmltree::Node| n.text().map_or(0, |t| t.trim().len()) as u64;
    let mut triangles = 0u64;
    // Per geometry id, the triangles of its primitives.
    let mut per_geometry: std::collections::HashMap<&str, u64> = Default::default();
    for n in geometries.descendants().filter(|n| n.is_element()) {
        let before = triangles;
        let name = n.tag_name().name();
        if name.ends_with("_array") {
            let count = number(n, "count")?;
            if count > 0 && matches!(name, "Name_array" | "IDREF_array") && text_len(n) > 0 {
                return Err(format!(
                    "<{name}> with values in a geometry: a mesh source must hold numbers"
                ));
            }
            if count > text_len(n) + 1 {
                return Err(format!(
                    "<{name} count=\"{count}\">: more values than the element holds"
                ));
            }
            continue;
        }
        let per_face = match name {
            "triangles" => Some(3),
            "lines" => Some(2),
            "polylist" | "polygons" | "trifans" | "tristrips" | "linestrips" => None,
            _ => continue,
        };
        let count = number(n, "count")?;
        let mut stride = 1;
        let (mut indices, mut vcount) = (0, None);
        for c in n.children().filter(|c| c.is_element()) {
            match c.tag_name().name() {
                "input" => {
                    let offset = number(c, "offset")?;
                    if offset > MAX_OFFSET {
                        return Err(format!(
                            "<input offset=\"{offset}\"> in <{name}>: at most {MAX_OFFSET}"
                        ));
                    }
                    stride = stride.max(offset + 1);
                }
                "p" => indices += text_len(c) + 1,
                "vcount" => vcount = Some(c),
                _ => {}
            }
        }
        let vertices = match (per_face, vcount) {
            (Some(k), _) => count.saturating_mul(k),
            (None, Some(v)) if name == "polylist" => {
                if count > text_len(v) + 1 {
                    return Err(format!(
                        "<polylist count=\"{count}\">: more polygons than its <vcount> holds"
                    ));
                }
                let values = v.text().unwrap_or("").split_ascii_whitespace();
                let sizes = values
                    .take(count as usize)
                    .map(|x| x.parse::<u64>().unwrap_or(0));
                let (vertices, fanned) = sizes.fold((0u64, 0u64), |(v, t), k| {
                    (v.saturating_add(k), t.saturating_add(k.saturating_sub(2)))
                });
                triangles = triangles.saturating_add(fanned);
                vertices
            }
            (None, _) => count,
        };
        if vertices.saturating_mul(stride) > indices {
            return Err(format!(
                "<{name} count=\"{count}\">: more indices than its <p> elements hold"
            ));
        }
        triangles = triangles.saturating_add(match name {
            "triangles" => count,
            "lines" | "linestrips" | "polylist" => 0, // polylist: counted above
            // Polygons, fans and strips: at most one triangle per index (each index takes
            // two characters of <p> at least).
            _ => indices / 2 / stride,
        });
        let geometry = n.ancestors().find(|a| a.has_tag_name("geometry"));
        if let Some(id) = geometry.and_then(|g| g.attribute("id")) {
            let t = per_geometry.entry(id).or_insert(0);
            *t = t.saturating_add(triangles - before);
        }
    }
    // References inside the geometries resolve to the kind of element the reader expects,
    // accessors step forward, and positions and normals are three floats (the reader panics
    // on each of these instead of returning an error).
    // The number of positions of each <vertices> (by node).
    let mut positions: std::collections::HashMap<roxmltree::NodeId, u64> = Default::default();
    let ids: std::collections::HashMap<&str, roxmltree::Node> = doc
        .descendants()
        .filter_map(|n| Some((n.attribute("id")?, n)))
        .collect();
    for n in geometries.descendants().filter(|n| n.is_element()) {
        let name = n.tag_name().name();
        if name == "accessor" && n.attribute("stride").is_some() && number(n, "stride")? == 0 {
            return Err("<accessor stride=\"0\">: the stride must be at least 1".into());
        }
        let Some(id) = n.attribute("source").and_then(|s| s.strip_prefix('#')) else {
            continue;
        };
        let said = || format!("<{name} source=\"#{}\">", crate::error::shorten(id));
        let Some(target) = ids.get(id) else {
            return Err(format!("{}: no element has that id", said()));
        };
        let kind = target.tag_name().name();
        let semantic = n.attribute("semantic").unwrap_or("");
        let parent = n.parent_element().map_or("", |p| p.tag_name().name());
        let expected = match (name, parent, semantic) {
            ("accessor", _, _) if !kind.ends_with("_array") => "an array such as <float_array>",
            ("input", "vertices", _) if kind != "source" => "a <source>",
            ("input", _, "VERTEX") => {
                // The primitive's own mesh's <vertices>.
                let own = n
                    .parent_element()
                    .and_then(|p| p.parent_element())
                    .and_then(|m| m.children().find(|c| c.has_tag_name("vertices")));
                if own.is_some_and(|v| v == *target) {
                    continue;
                }
                "the <vertices> of its own <mesh>"
            }
            ("input", _, _) if parent != "vertices" && kind != "source" => "a <source>",
            _ => "",
        };
        if !expected.is_empty() {
            return Err(format!("{}: names a <{kind}>, expected {expected}", said()));
        }
        if name == "input" && matches!(semantic, "POSITION" | "NORMAL") {
            // The reader takes X, Y, Z floats from a <float_array> and nothing else.
            let bad = || {
                format!(
                    "<source id=\"{}\"> ({semantic}): needs an <accessor> of stride 3 or more \
                     with three <param type=\"float\"> over a <float_array>",
                    crate::error::shorten(id)
                )
            };
            let accessor = target
                .descendants()
                .find(|c| c.has_tag_name("accessor"))
                .ok_or_else(bad)?;
            let array = accessor
                .attribute("source")
                .and_then(|s| ids.get(s.strip_prefix('#')?))
                .filter(|x| x.has_tag_name("float_array"))
                .ok_or_else(bad)?;
            let params: Vec<_> = accessor
                .children()
                .filter(|c| c.has_tag_name("param"))
                .collect();
            // A missing stride is 1 (COLLADA's default).
            let stride = number(accessor, "stride")?.max(1);
            let floats = params.iter().all(|p| p.attribute("type") == Some("float"));
            if params.len() < 3 || !floats || stride < 3 {
                return Err(bad());
            }
            // The reader takes the first three values of each vertex as X, Y, Z, where the
            // format (and Assimp) reads the params by name from the accessor's offset.
            let names: Vec<_> = params[..3].iter().map(|p| p.attribute("name")).collect();
            let offset = number(accessor, "offset")?;
            if semantic == "POSITION" && (offset != 0 || names != [Some("X"), Some("Y"), Some("Z")])
            {
                return Err(format!(
                    "<source id=\"{}\"> (POSITION): its accessor must read X, Y, Z first: \
                     offset 0 and params named X, Y, Z in that order (other layouts are not \
                     supported)",
                    crate::error::shorten(id)
                ));
            }
            let count = number(accessor, "count")?;
            let values = array
                .text()
                .map_or(0, |t| t.split_ascii_whitespace().count()) as u64;
            if count.saturating_mul(stride) > values {
                return Err(format!(
                    "<source id=\"{}\"> ({semantic}): its accessor reads {count} × {stride} \
                     values, its array holds {values}",
                    crate::error::shorten(id)
                ));
            }
            if semantic == "POSITION" && parent == "vertices" {
                if let Some(v) = n.parent_element() {
                    positions.insert(v.id(), count);
                }
            }
        }
    }
    // Every vertex index of a primitive names one of its positions.
    for n in geometries.descendants().filter(|n| n.is_element()) {
        let name = n.tag_name().name();
        if !matches!(
            name,
            "triangles"
                | "lines"
                | "polylist"
                | "polygons"
                | "trifans"
                | "tristrips"
                | "linestrips"
        ) {
            continue;
        }
        let mut stride = 1;
        for c in n.children().filter(|c| c.has_tag_name("input")) {
            stride = stride.max(number(c, "offset")? + 1);
        }
        let vertex = n
            .children()
            .find(|c| c.has_tag_name("input") && c.attribute("semantic") == Some("VERTEX"));
        let target = vertex
            .and_then(|v| v.attribute("source"))
            .and_then(|s| ids.get(s.strip_prefix('#')?));
        if let (Some(v), Some(t)) = (vertex, target) {
            let offset = number(v, "offset")?;
            let available = positions.get(&t.id()).copied().unwrap_or(0);
            let lists = n.children().filter(|c| c.has_tag_name("p"));
            let values = lists.flat_map(|p| p.text().unwrap_or("").split_ascii_whitespace());
            for (k, x) in values.enumerate() {
                if k as u64 % stride != offset {
                    continue;
                }
                let index = x.parse::<u64>().unwrap_or(0);
                if index >= available {
                    return Err(format!(
                        "<{name}>: vertex index {index}, but its <vertices> has {available} \
                         positions"
                    ));
                }
            }
        }
    }
    let (instances, names) = collada_instances(&doc, &ids)?;
    let mut placements = vec![0u64; names.len()];
    for &(k, _) in &instances {
        placements[k] += 1;
    }
    let placed = names.iter().zip(&placements).fold(0u64, |sum, (id, &n)| {
        let each = per_geometry.get(id.as_str()).copied().unwrap_or(0);
        sum.saturating_add(each.saturating_mul(n))
    });
    // The reader is given the file without its visual scenes: it then builds every geometry
    // once, untransformed, and the instances place them.
    let cut = doc
        .root_element()
        .children()
        .filter(|n| n.has_tag_name("library_visual_scenes"))
        .map(|n| n.range())
        .collect();
    Ok(Collada {
        triangles: triangles.max(placed),
        instances,
        ids: names,
        cut,
    })
}

/// What [`check_collada`] finds in a COLLADA file.
#[derive(Debug)]
struct Collada {
    /// Upper bound of the triangles the reader builds and the scene places.
    triangles: u64,
    /// The geometries placed by the scene: the index of its id in `ids` and its transform,
    /// one per instance.
    instances: Vec<(usize, nalgebra::Matrix4<f64>)>,
    /// The ids of the placed geometries, each once.
    ids: Vec<String>,
    /// Byte ranges of the `<library_visual_scenes>` elements.
    cut: Vec<Range<usize>>,
}

/// Most geometry instances a COLLADA file's scene may place.
const MAX_COLLADA_INSTANCES: usize = 100_000;

/// Most child elements of placed nodes a COLLADA scene walk reads (each node's children
/// counted once per placement).
const MAX_COLLADA_WORK: usize = 10_000_000;

/// The geometries the scene of a COLLADA document places, as coal, MoveIt and tesseract take
/// them from Assimp: from the visual scene that `<scene><instance_visual_scene>` names, every
/// `<instance_geometry>` under its nodes (and under the nodes an `<instance_node>` names), once
/// per instance (as index into the returned ids, each id kept once per element naming it),
/// with the product of its nodes' transforms (`<matrix>`, `<translate>`, `<rotate>`, `<scale>`,
/// `<lookat>`, composed in document order; `<skew>` ignored, as by Assimp); neither the asset's
/// unit nor its up axis (Assimp's root transform, which they drop). The walk is bounded
/// ([`MAX_COLLADA_INSTANCES`] nodes, [`MAX_COLLADA_WORK`] child elements read).
#[allow(clippy::type_complexity)]
fn collada_instances(
    doc: &roxmltree::Document,
    ids: &std::collections::HashMap<&str, roxmltree::Node>,
) -> std::result::Result<(Vec<(usize, nalgebra::Matrix4<f64>)>, Vec<String>), String> {
    use nalgebra::Matrix4;
    let line = |n: roxmltree::Node| doc.text_pos_at(n.range().start).row;
    let root = doc.root_element();
    let scene = root
        .children()
        .find(|n| n.has_tag_name("scene"))
        .and_then(|s| {
            s.children()
                .find(|c| c.has_tag_name("instance_visual_scene"))
        })
        .ok_or("no <scene> with an <instance_visual_scene>: the file places no geometry")?;
    let url = scene.attribute("url").unwrap_or("");
    let visual = url
        .strip_prefix('#')
        .and_then(|id| ids.get(id))
        .filter(|n| n.has_tag_name("visual_scene"))
        .ok_or_else(|| {
            format!(
                "line {}: <instance_visual_scene url=\"{}\">: names no <visual_scene>",
                line(scene),
                crate::error::shorten(url)
            )
        })?;
    // The transform of one node: its transform elements multiplied in order, as Assimp
    // composes them (a `<skew>` is ignored, as Assimp ignores it).
    let transform = |node: roxmltree::Node| -> std::result::Result<Matrix4<f64>, String> {
        let mut m = Matrix4::identity();
        for c in node.children().filter(|c| c.is_element()) {
            let name = c.tag_name().name();
            let wanted = match name {
                "matrix" => 16,
                "translate" | "scale" => 3,
                "rotate" => 4,
                "lookat" => 9,
                _ => continue,
            };
            // The element's first text that is not blank (as Assimp's XML reader takes it:
            // a comment before the numbers is skipped, one among them ends them).
            let text = c
                .children()
                .filter_map(|t| t.is_text().then(|| t.text()).flatten())
                .find(|t| !t.trim().is_empty())
                .unwrap_or("");
            let values: Vec<f64> = text
                .split_ascii_whitespace()
                .map(|v| v.parse::<f64>())
                .collect::<std::result::Result<_, _>>()
                .ok()
                .filter(|v: &Vec<f64>| v.len() == wanted && v.iter().all(|x| x.is_finite()))
                .ok_or_else(|| {
                    format!(
                        "line {}: <{name}>{}</{name}>: needs {wanted} finite numbers",
                        line(c),
                        crate::error::shorten(text.trim())
                    )
                })?;
            let v = &values;
            let step = match name {
                "matrix" => Matrix4::from_row_slice(v),
                "translate" => Matrix4::new_translation(&Vector3::new(v[0], v[1], v[2])),
                "scale" => Matrix4::new_nonuniform_scaling(&Vector3::new(v[0], v[1], v[2])),
                "lookat" => {
                    // Assimp's: the eye at the first point looking at the second, its y
                    // axis the up vector as given, its x axis their cross product.
                    let eye = Vector3::new(v[0], v[1], v[2]);
                    let unit = |x: Vector3<f64>| {
                        let n = x.norm();
                        if n > 0.0 {
                            x / n
                        } else {
                            x
                        }
                    };
                    let dir = unit(Vector3::new(v[3], v[4], v[5]) - eye);
                    let up = unit(Vector3::new(v[6], v[7], v[8]));
                    let right = unit(dir.cross(&up));
                    Matrix4::new(
                        right.x, up.x, -dir.x, eye.x, right.y, up.y, -dir.y, eye.y, right.z, up.z,
                        -dir.z, eye.z, 0.0, 0.0, 0.0, 1.0,
                    )
                }
                _ => {
                    // Assimp's rotation about the axis as written (not normalised), by
                    // degrees.
                    let (x, y, z) = (v[0], v[1], v[2]);
                    let (s, c) = v[3].to_radians().sin_cos();
                    let t = 1.0 - c;
                    Matrix4::new(
                        t * x * x + c,
                        t * x * y - s * z,
                        t * x * z + s * y,
                        0.0,
                        t * x * y + s * z,
                        t * y * y + c,
                        t * y * z - s * x,
                        0.0,
                        t * x * z - s * y,
                        t * y * z + s * x,
                        t * z * z + c,
                        0.0,
                        0.0,
                        0.0,
                        0.0,
                        1.0,
                    )
                }
            };
            m *= step;
        }
        Ok(m)
    };
    // The node an `<instance_node url="#x">` places, found as Assimp finds it: among the top
    // nodes of the `<library_nodes>` and the visual scenes by id (the last of a repeated id),
    // else the first node of the placed visual scene (depth first) whose name or id is `x`;
    // none (the instance is dropped) otherwise.
    let mut library: std::collections::HashMap<&str, roxmltree::Node> = Default::default();
    for lib in root.children() {
        let top = if lib.has_tag_name("library_nodes") {
            "node"
        } else if lib.has_tag_name("library_visual_scenes") {
            "visual_scene"
        } else {
            continue;
        };
        for n in lib.children().filter(|n| n.has_tag_name(top)) {
            library.insert(n.attribute("id").unwrap_or(""), n);
        }
    }
    // The placed visual scene's nodes (itself, then its nodes and theirs, depth first) by
    // name and by id, the first of each.
    let mut by_name: std::collections::HashMap<&str, roxmltree::Node> = Default::default();
    let mut walk = vec![*visual];
    while let Some(n) = walk.pop() {
        for key in [n.attribute("name"), n.attribute("id")]
            .into_iter()
            .flatten()
        {
            by_name.entry(key).or_insert(n);
        }
        let inner = n.children().filter(|c| c.has_tag_name("node"));
        let at = walk.len();
        walk.extend(inner);
        walk[at..].reverse();
    }
    let resolve = |x: &str| library.get(x).or_else(|| by_name.get(x)).copied();
    // Assimp would place an instance outside every node with the root transform it drops
    // elsewhere (the unit and up axis): the format puts instances in nodes, and so must a file.
    if let Some(c) = visual
        .children()
        .find(|c| c.tag_name().name().starts_with("instance_"))
    {
        return Err(format!(
            "line {}: <{}> directly in the <visual_scene>: instances belong in a <node>",
            line(c),
            c.tag_name().name()
        ));
    }
    let mut out = Vec::new();
    let mut names: Vec<String> = Vec::new();
    let mut interned: std::collections::HashMap<(usize, usize), usize> = Default::default();
    // Depth-first over (node, transform of its parent, depth); the visual scene's own
    // children first.
    let mut stack: Vec<(roxmltree::Node, Matrix4<f64>, usize)> = visual
        .children()
        .filter(|c| c.has_tag_name("node"))
        .map(|c| (c, Matrix4::identity(), 0))
        .collect();
    stack.reverse();
    // Nodes visited or waiting (counted when they are found, so the stack stays within the
    // limit too).
    let mut visits = stack.len();
    let mut work = 0usize;
    let mut children = Vec::new();
    while let Some((node, parent, depth)) = stack.pop() {
        if visits > MAX_COLLADA_INSTANCES || depth > crate::limits::MAX_MESH_XML_DEPTH {
            return Err(format!(
                "the scene places more than {MAX_COLLADA_INSTANCES} nodes (or nests them too deep)"
            ));
        }
        // Every element a visit reads counts, so that a large node placed many times is
        // refused instead of read for minutes.
        work += node.children().count();
        if work > MAX_COLLADA_WORK {
            return Err(format!(
                "the scene's nodes hold more than {MAX_COLLADA_WORK} elements where they are \
                 placed (a large node placed many times)"
            ));
        }
        let m = parent * transform(node)?;
        children.clear();
        for c in node.children().filter(|c| c.is_element()) {
            if children.len() + visits > MAX_COLLADA_INSTANCES {
                break; // refused when the next node is taken
            }
            let name = c.tag_name().name();
            let url = || {
                let url = c.attribute("url").unwrap_or("");
                url.strip_prefix('#').ok_or_else(|| {
                    format!(
                        "line {}: <{name} url=\"{}\">: not a reference within the file",
                        line(c),
                        crate::error::shorten(url)
                    )
                })
            };
            match name {
                "node" => children.push(c),
                "instance_node" => children.extend(resolve(url()?)),
                "instance_geometry" => {
                    if out.len() >= MAX_COLLADA_INSTANCES {
                        return Err(format!(
                            "the scene places more than {MAX_COLLADA_INSTANCES} geometries"
                        ));
                    }
                    // Each id is kept once per element that names it, however often that
                    // is placed (known by where its text lies, so that a long id is neither
                    // copied nor hashed again).
                    let id = url()?;
                    let next = names.len();
                    let k = *interned
                        .entry((id.as_ptr() as usize, id.len()))
                        .or_insert(next);
                    if k == next {
                        names.push(id.to_string());
                    }
                    out.push((k, m));
                }
                "instance_controller" => {
                    return Err(format!(
                        "line {}: <instance_controller>: a skinned mesh is not supported \
                         (export it as plain geometry)",
                        line(c)
                    ))
                }
                _ => {}
            }
        }
        visits += children.len();
        stack.extend(children.drain(..).rev().map(|c| (c, m, depth + 1)));
    }
    if out.is_empty() {
        return Err("the scene places no geometry (no <instance_geometry> in its nodes)".into());
    }
    Ok((out, names))
}

/// Runs `f` and returns its value, or the panic's message (shortened) if it panicked, without
/// printing it: for a third-party reader that panics on some malformed input instead of
/// returning an error. Other panics, on any thread, are reported as before.
fn catch_quietly<T>(f: impl FnOnce() -> T) -> std::result::Result<T, String> {
    use std::cell::Cell;
    thread_local! {
        static QUIET: Cell<bool> = const { Cell::new(false) };
    }
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                previous(info);
            }
        }));
    });
    let was = QUIET.with(|q| q.replace(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(was));
    result.map_err(|payload| {
        let said = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        crate::error::shorten(said.lines().next().unwrap_or("").trim()).into_owned()
    })
}

/// The corners of every triangle of the COLLADA file `path` (vertex index, position), after
/// [`check_collada`] and a count of its triangles against
/// [`crate::limits::MAX_MESH_TRIANGLES`]; the reader is given no way to open another file.
fn collada_corners(path: &Path) -> std::result::Result<Vec<(u32, [f64; 3])>, String> {
    let bytes = crate::limits::read_file(path, crate::limits::MAX_COLLADA_FILE_BYTES)
        .map_err(|e| format!("cannot read: {e}"))?;
    if bytes.is_empty() {
        return Err("empty file".into());
    }
    let text = String::from_utf8_lossy(&bytes);
    crate::limits::check_xml_depth(&text, crate::limits::MAX_MESH_XML_DEPTH)?;
    let Collada {
        triangles,
        instances,
        ids,
        cut,
    } = check_collada(&text)?;
    let limit = crate::limits::MAX_MESH_TRIANGLES as u64;
    if triangles > limit {
        return Err(format!(
            "{triangles} triangles: more than the limit of {limit}"
        ));
    }
    let refuse = |other: &Path| -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::new(
            std::io::ErrorKind::Unsupported,
            format!(
                "{} is not read (a mesh is read from one file)",
                other.display()
            ),
        ))
    };
    // The reader builds every geometry once, untransformed, from the file without its visual
    // scenes; the scene's instances then place them ([`collada_instances`]).
    let plain = match &text {
        std::borrow::Cow::Borrowed(text) => {
            let mut plain = String::with_capacity(text.len());
            let mut at = 0;
            for r in &cut {
                plain.push_str(&text[at..r.start]);
                // Its line ends stay, so that the reader's messages name the file's lines.
                let lines = text[r.clone()].matches('\n').count();
                plain.extend(std::iter::repeat_n('\n', lines));
                at = r.end;
            }
            plain.push_str(&text[at..]);
            Some(plain.into_bytes())
        }
        std::borrow::Cow::Owned(_) => None,
    };
    let input: &[u8] = plain.as_deref().unwrap_or(&bytes);
    // The COLLADA reader panics on some malformed files (a missing source, a short array)
    // instead of returning an error: such a panic is this file's error too.
    let scene = catch_quietly(|| {
        mesh_loader::Loader::default().load_from_slice_with_reader(input, path, refuse)
    })
    .map_err(|why| {
        let said = if why.is_empty() {
            why
        } else {
            format!(" ({why})")
        };
        format!("not a readable mesh: the mesh reader failed on it{said}")
    })?
    .map_err(|e| format!("not a readable mesh: {e}"))?;
    let meshes: std::collections::HashMap<&str, &mesh_loader::Mesh> =
        scene.meshes.iter().map(|m| (m.name.as_str(), m)).collect();
    let mut corners = Vec::new();
    let mesh_of: Vec<Option<&&mesh_loader::Mesh>> =
        ids.iter().map(|id| meshes.get(id.as_str())).collect();
    for &(k, ref transform) in &instances {
        // A geometry of another kind than <mesh>, or an id that names no geometry, builds
        // nothing, as in Assimp.
        let Some(m) = mesh_of[k] else {
            continue;
        };
        for f in &m.faces {
            let corner = |i: u32| {
                m.vertices
                    .get(i as usize)
                    .ok_or_else(|| format!("a triangle refers to vertex {i}, which does not exist"))
            };
            let [a, b, c] = [corner(f[0])?, corner(f[1])?, corner(f[2])?];
            // Two equal corners: a line, which Assimp drops (before the node transforms).
            if a == b || b == c || a == c {
                continue;
            }
            for &i in f {
                let v = corner(i)?;
                // As Assimp applies a node transform to a vertex: its bottom row is not used.
                let v = Vector3::from(v.map(f64::from));
                let p = transform.fixed_view::<3, 3>(0, 0) * v + transform.fixed_view::<3, 1>(0, 3);
                corners.push((i, [p.x, p.y, p.z]));
            }
        }
    }
    Ok(corners)
}

/// The convex hull of the mesh file `path` (STL, OBJ or COLLADA), each vertex scaled by
/// `scale`, with its number of points (three per triangle). Scaled vertices must lie within
/// [`MAX_LENGTH`] of the mesh origin, as a scenario's mesh obstacles. STL and OBJ files are read
/// as a scenario's meshes are ([`crate::world::mesh::load_mesh`]: the same limits, checks and
/// messages; an OBJ's material libraries are never opened); a COLLADA file is checked, its
/// triangles counted against [`crate::limits::MAX_MESH_TRIANGLES`], and read without opening any
/// other file. The error says what is wrong with the file.
pub fn load_hull(
    path: &Path,
    scale: [f64; 3],
) -> std::result::Result<(SharedShape, usize), String> {
    let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !["stl", "obj", "dae"]
        .iter()
        .any(|e| extension.eq_ignore_ascii_case(e))
    {
        return Err(format!(
            "unknown file extension \"{extension}\" (expected .stl, .obj or .dae)"
        ));
    }
    // Each triangle's corners, unscaled (with the vertex index a message names).
    let corners: Vec<(u32, [f64; 3])> = if extension.eq_ignore_ascii_case("dae") {
        collada_corners(path)?
    } else {
        let mesh = crate::world::mesh::load_mesh(path).map_err(|e| {
            // The caller names the file.
            let said = e.to_string();
            let prefix = format!("{}: ", path.display());
            said.strip_prefix(&prefix).unwrap_or(&said).to_string()
        })?;
        // A triangle with two equal corners is a line, which Assimp-based readers (coal,
        // MoveIt) drop: so is it here, so that a stray vertex of one does not grow the hull.
        let at = |i: u32| mesh.vertices[i as usize];
        mesh.triangles
            .iter()
            .filter(|t| at(t[0]) != at(t[1]) && at(t[1]) != at(t[2]) && at(t[0]) != at(t[2]))
            .flatten()
            .map(|&i| (i, at(i)))
            .collect()
    };
    let mut points: Vec<[f64; 3]> = Vec::with_capacity(corners.len());
    for (i, v) in corners {
        let p = Point3::new(v[0] * scale[0], v[1] * scale[1], v[2] * scale[2]);
        if !p.coords.iter().all(|x| x.is_finite()) {
            return Err(format!(
                "vertex {i} scaled by {} is not finite: {}",
                fmt_list(&scale),
                fmt_list(&[p.x, p.y, p.z])
            ));
        }
        // As a scene's mesh obstacle: a body kilometres across is a wrong scale.
        if !p.coords.iter().all(|&x| within(x, MAX_LENGTH)) {
            return Err(format!(
                "vertex {i} scaled by {} is {}, more than {MAX_LENGTH} m from the mesh origin",
                fmt_list(&scale),
                fmt_list(&[p.x, p.y, p.z])
            ));
        }
        points.push([p.x, p.y, p.z]);
    }
    if points.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    let n = points.len();
    // As a scene's `hull` obstacle (the exact hull of 15M points on a sphere took 22 s and
    // 3 GB).
    hull_of_points(&points)
        .map(|h| (h, n))
        .ok_or_else(|| "the mesh is degenerate (its points lie on a line or at one point): it has no convex hull".into())
}

/// Reads the `<disable_collisions link1 link2 reason/>` pairs of an SRDF file. Every link must
/// be one of `robot`'s; errors name the SRDF (and the URDF `urdf` for unknown links).
pub fn read_srdf(path: &Path, robot: &urdf_rs::Robot, urdf: &Path) -> Result<Vec<DisabledPair>> {
    let text =
        crate::limits::read_text(path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(|source| {
            Error::Read {
                path: path.to_path_buf(),
                source,
            }
        })?;
    let parse = |message: String| Error::Parse {
        file: path.to_path_buf(),
        message,
    };
    crate::limits::check_xml_depth(&text, crate::limits::MAX_XML_DEPTH).map_err(parse)?;
    let doc =
        roxmltree::Document::parse(&text).map_err(|e| parse(format!("not a valid SRDF: {e}")))?;
    // A URDF given as the SRDF would read as one without pairs.
    if let Some(n) = doc
        .root_element()
        .children()
        .find(|n| n.has_tag_name("link") || n.has_tag_name("joint"))
    {
        return Err(parse(format!(
            "line {}: <{}> elements: a URDF robot, not an SRDF (the URDF goes to --urdf)",
            doc.text_pos_at(n.range().start).row,
            n.tag_name().name()
        )));
    }
    let mut out = Vec::new();
    let links: std::collections::HashSet<&str> =
        robot.links.iter().map(|l| l.name.as_str()).collect();
    for n in doc
        .descendants()
        .filter(|n| n.has_tag_name("disable_collisions"))
    {
        // Found only for a message: finding it scans the text from its start.
        let line = || doc.text_pos_at(n.range().start).row;
        let mut names = [String::new(), String::new()];
        for (k, attr) in ["link1", "link2"].into_iter().enumerate() {
            let Some(v) = n.attribute(attr) else {
                return Err(parse(format!(
                    "line {}: <disable_collisions> has no {attr} attribute",
                    line()
                )));
            };
            if !links.contains(v) {
                return Err(parse(format!(
                    "line {}: <disable_collisions {attr}=\"{v}\">: the URDF {} has no link '{v}'",
                    line(),
                    urdf.display()
                )));
            }
            names[k] = v.to_string();
        }
        let reason = match n.attribute("reason") {
            Some("Adjacent") => Reason::Adjacent,
            Some("Default") => Reason::Default,
            Some("Always") => Reason::Always,
            _ => Reason::User,
        };
        let [link1, link2] = names;
        out.push(DisabledPair {
            link1,
            link2,
            reason,
        });
    }
    Ok(out)
}

/// Chain link (from 1; 0 for the base) owning a body carried after `level` free axes.
fn owner(chain: &Chain, level: usize) -> usize {
    if level == 0 {
        0
    } else {
        chain.free_axes()[level - 1].link
    }
}

/// The carrier frame of `level` in `frames`.
fn carrier(frames: &crate::kinematics::Frames, level: usize) -> IsometryMatrix3<f64> {
    if level == 0 {
        frames.frames[0]
    } else {
        frames.axis_frames[level - 1]
    }
}

/// The radius of each chain segment, when the capsule `elements` are exactly the chain's
/// segments (see the module documentation); `None` otherwise.
fn match_segments(chain: &Chain, carried: &UrdfChain, elements: &[Element]) -> Option<Vec<f64>> {
    let n = chain.segment_count();
    if elements.len() != n {
        return None;
    }
    let mut frames = chain.frames();
    chain.fk(chain.home(), &mut frames);
    let mut used = vec![false; n];
    let mut radii = vec![0.0; n];
    for (s, seg) in frames.segments.iter().enumerate() {
        let level = chain.segment_info(s).level;
        let close = |p: &Point3<f64>, q: &Point3<f64>| (p - q).norm() <= MATCH_TOLERANCE;
        let hit = elements.iter().enumerate().position(|(k, e)| {
            let c = &carried.carried[e.carried];
            match &e.piece {
                Piece::Capsule { a, b, .. } if !used[k] && c.level == level => {
                    let t = carrier(&frames, level);
                    let (a, b) = (t * a, t * b);
                    (close(&a, &seg[0]) && close(&b, &seg[1]))
                        || (close(&a, &seg[1]) && close(&b, &seg[0]))
                }
                _ => false,
            }
        })?;
        used[hit] = true;
        if let Piece::Capsule { r, .. } = elements[hit].piece {
            radii[s] = r;
        }
    }
    Some(radii)
}

/// The body of the imported chain `urdf` of `robot` (read from the file `path`) as `options`
/// say. Errors name the link and the file concerned (not yet the URDF: see [`load_robot`]).
pub fn robot_body(
    robot: &urdf_rs::Robot,
    urdf: UrdfChain,
    path: &Path,
    options: &ImportOptions,
) -> Result<ImportedRobot> {
    let cfg = &options.self_collision;
    let capsules = |urdf: UrdfChain, note: Option<String>| {
        let body = RobotBody::capsules(&urdf.chain, cfg);
        ImportedRobot {
            urdf,
            body,
            kind: BodyKind::Capsules,
            note,
        }
    };
    if options.body == BodyChoice::Capsules {
        return Ok(capsules(urdf, None));
    }
    let by_name: std::collections::HashMap<&str, &urdf_rs::Link> =
        robot.links.iter().map(|l| (l.name.as_str(), l)).collect();
    let links: Vec<&urdf_rs::Link> = urdf
        .carried
        .iter()
        .map(|c| by_name[c.name.as_str()])
        .collect();
    let count: usize = links.iter().map(|l| l.collision.len()).sum();
    let limit = crate::limits::MAX_COLLISION_ELEMENTS;
    if count > limit {
        return Err(Error::invalid(
            "<collision>",
            format!("{count} elements between base and tip"),
            format!("at most {limit} (the limit; each is a body, and self pairs grow with their square)"),
        ));
    }
    let mut elements = Vec::new();
    for (k, (c, link)) in urdf.carried.iter().zip(links).enumerate() {
        elements.extend(
            link_pieces(link, &c.pose)?
                .into_iter()
                .map(|piece| Element { carried: k, piece }),
        );
    }
    if elements.is_empty() {
        return Ok(capsules(
            urdf,
            Some(
                "no <collision> geometry between base and tip: the links are capsules between joint origins"
                    .into(),
            ),
        ));
    }
    if elements
        .iter()
        .all(|e| matches!(e.piece, Piece::Capsule { .. }))
    {
        if let Some(radii) = match_segments(&urdf.chain, &urdf, &elements) {
            let body = RobotBody::with_radii(&urdf.chain, radii, Vec::new(), cfg);
            return Ok(ImportedRobot {
                urdf,
                body,
                kind: BodyKind::CollisionCapsules,
                note: None,
            });
        }
    }
    let mut urdf = urdf;
    urdf.chain = urdf.chain.clone().without_segments();
    let chain = &urdf.chain;
    let mut solids = Vec::with_capacity(elements.len());
    // Elements naming the same file at the same scale share one hull.
    let mut hulls: std::collections::HashMap<(PathBuf, [u64; 3]), SharedShape> =
        std::collections::HashMap::new();
    // Triangles of the hulls built so far.
    let mut triangles = 0usize;
    for e in elements {
        let c = &urdf.carried[e.carried];
        let (local, shape) = match e.piece {
            Piece::Capsule { r, local, half, .. } => (local, SharedShape::capsule_z(half, r)),
            Piece::Shape { local, shape } => (local, shape),
            Piece::Mesh {
                local,
                filename,
                scale,
            } => {
                let file = resolve_mesh(&filename, path, &options.packages)
                    .map_err(|why| link_err(&c.name, format!("mesh '{filename}': {why}")))?;
                let key = (file, scale.map(f64::to_bits));
                let hull = match hulls.get(&key) {
                    Some(hull) => hull.clone(),
                    None => {
                        let what = || format!("mesh '{filename}' ({})", key.0.display());
                        // All the hulls built count together, as a scenario's meshes: counted
                        // before a file is built when its format allows, after otherwise.
                        let limit = crate::limits::MAX_SCENE_MESH_TRIANGLES;
                        let counted = crate::world::mesh::count_triangles(&key.0).unwrap_or(0);
                        let over = |total: usize| {
                            link_err(
                                &c.name,
                                format!(
                                    "{}: the robot's collision meshes (each file at each scale) hold {total} triangles or more in all, more than the limit of {limit}",
                                    what()
                                ),
                            )
                        };
                        if triangles.saturating_add(counted) > limit {
                            return Err(over(triangles.saturating_add(counted)));
                        }
                        let (hull, points) = load_hull(&key.0, scale)
                            .map_err(|why| link_err(&c.name, format!("{}: {why}", what())))?;
                        triangles = triangles.saturating_add(counted.max(points / 3));
                        if triangles > limit {
                            return Err(over(triangles));
                        }
                        hulls.insert(key, hull.clone());
                        hull
                    }
                };
                (local, hull)
            }
        };
        solids.push(Solid::new(
            c.level,
            local,
            shape,
            owner(chain, c.level),
            c.name.clone(),
        ));
    }
    let body = RobotBody::new(chain, solids, cfg);
    Ok(ImportedRobot {
        urdf,
        body,
        kind: BodyKind::Solids,
        note: None,
    })
}

/// Reads the URDF `path`, imports its chain ([`chain_from_urdf`]) and its body
/// ([`robot_body`]), and applies the SRDF of `options`. Every error names the URDF (or the
/// SRDF), the link and the file concerned.
pub fn load_robot(
    path: &Path,
    base: Option<&str>,
    tip: Option<&str>,
    radius: Option<f64>,
    colliders_per_link: usize,
    options: &ImportOptions,
) -> Result<ImportedRobot> {
    let robot = read_urdf(path)?;
    let urdf = chain_from_urdf(&robot, base, tip, radius, colliders_per_link)
        .map_err(|e| e.in_file(path))?;
    let mut out = robot_body(&robot, urdf, path, options).map_err(|e| e.in_file(path))?;
    if let Some(srdf) = &options.srdf {
        // An SRDF names URDF links; bodies on other frames (capsules between joint origins of
        // an arm whose links are named otherwise) would silently escape its pairs.
        if let Some(why) = out.srdf_cannot_name() {
            return Err(Error::invalid(
                "--srdf",
                srdf.display(),
                format!("its pairs name the URDF's links, but {why}"),
            ));
        }
        let pairs = read_srdf(srdf, &robot, path)?;
        out.body.disable_pairs(&pairs);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The triangles a COLLADA file will build are counted before it is read: those of
    /// `<triangles>`, and of `<polylist>` fanned (`k − 2` per polygon of `k` vertices).
    #[test]
    fn collada_triangles_are_counted_before_reading() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/arm/link2.dae");
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(check_collada(&text).map(|c| c.triangles), Ok(28));
        let start = text.find("<triangles").unwrap();
        let end = text.find("</triangles>").unwrap() + "</triangles>".len();
        // The same 28 triangles as quads and pentagons fanned: 7 polygons of 4 and 5 vertices.
        let inputs: String = text[start..end]
            .lines()
            .filter(|l| l.contains("<input"))
            .collect();
        let indices: Vec<&str> = text[start..end]
            .split("<p>")
            .nth(1)
            .unwrap()
            .split("</p>")
            .next()
            .unwrap()
            .split_whitespace()
            .collect();
        let polylist = format!(
            "<polylist count=\"3\">{inputs}<vcount>4 5 6</vcount><p>{}</p></polylist>",
            indices[..15].join(" ")
        );
        let edited = format!("{}{polylist}{}", &text[..start], &text[end..]);
        assert_eq!(check_collada(&edited).map(|c| c.triangles), Ok(2 + 3 + 4));
        // The asset's unit and up axis are not applied, so any value is read (as coal reads
        // them); a position accessor that does not read X, Y, Z first is refused.
        for (from, to) in [
            ("meter=\"1\"", "meter=\"-1\""),
            ("meter=\"1\"", "meter=\"0\""),
            ("meter=\"1\"", "meter=\"1e40\""),
            ("meter=\"1\"", "meter=\"0,001\""),
            ("Z_UP", "W_UP"),
        ] {
            assert!(text.contains(from), "{from}");
            assert!(check_collada(&text.replacen(from, to, 1)).is_ok(), "{to}");
        }
        let xyz =
            "<param name=\"X\" type=\"float\"/>\n              <param name=\"Y\" type=\"float\"/>";
        assert!(text.contains(xyz));
        let yx = xyz
            .replace("\"X\"", "\"T\"")
            .replace("\"Y\"", "\"X\"")
            .replace("\"T\"", "\"Y\"");
        let e = check_collada(&text.replacen(xyz, &yx, 1)).unwrap_err();
        assert!(
            e.contains("(POSITION): its accessor must read X, Y, Z first"),
            "{e}"
        );
        let shifted = text.replacen("<accessor source", "<accessor offset=\"1\" source", 1);
        let e = check_collada(&shifted).unwrap_err();
        assert!(
            e.contains("(POSITION): its accessor must read X, Y, Z first"),
            "{e}"
        );
    }

    /// A COLLADA file is read as coal, MoveIt and tesseract read it: its `<unit meter>` and
    /// `<up_axis>` are not applied, the transforms of its scene's nodes are, and a geometry is
    /// there once per instance (also through `<instance_node>`); vertices are then scaled by the
    /// URDF's `scale` alone. A file that places nothing, or places without end, is refused.
    #[test]
    fn collada_unit_and_up_axis_are_not_applied_but_node_transforms_are() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/arm/link2.dae");
        let text = std::fs::read_to_string(&path).unwrap();
        let dir = std::env::temp_dir().join(format!("kinsynth-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bounds = |name: &str, text: &str, scale: [f64; 3]| {
            let file = dir.join(name);
            std::fs::write(&file, text).unwrap();
            let (hull, _) = load_hull(&file, scale).unwrap();
            let points = hull.as_convex_polyhedron().unwrap().points().to_vec();
            let mut lo = [f64::MAX; 3];
            let mut hi = [f64::MIN; 3];
            for p in points {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (lo, hi)
        };
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-6);
        let (lo, hi) = bounds("plain.dae", &text, [1.0; 3]);
        assert!(
            close(lo, [-0.09, -0.06, -0.05]) && close(hi, [0.09, 0.06, 0.45]),
            "{lo:?} {hi:?}"
        );
        assert!(text.contains("meter=\"1\"") && text.contains("Z_UP"));
        let centimetres = text
            .replacen("meter=\"1\"", "meter=\"0.01\"", 1)
            .replacen("Z_UP", "Y_UP", 1);
        assert_eq!(bounds("cm.dae", &centimetres, [1.0; 3]), (lo, hi));
        let (lo2, hi2) = bounds("cm2.dae", &centimetres, [2.0; 3]);
        assert!(close(lo2, lo.map(|v| 2.0 * v)) && close(hi2, hi.map(|v| 2.0 * v)));
        // A node's translation moves the vertices (as every reader does).
        let node = "<node id=\"link2\" name=\"link2\" type=\"NODE\">";
        assert!(text.contains(node));
        let moved = centimetres.replacen(node, &format!("{node}<translate>1 2 3</translate>"), 1);
        let (lo3, hi3) = bounds("moved.dae", &moved, [1.0; 3]);
        assert!(
            close(lo3, [0.91, 1.94, 2.95]) && close(hi3, [1.09, 2.06, 3.45]),
            "{lo3:?}"
        );
        // A geometry placed twice (a second node, moved and turned a quarter about z) is
        // there twice.
        let end = text.find("</node>").unwrap() + "</node>".len();
        let second = "<node id=\"copy\"><translate>1 0 0</translate><rotate>0 0 1 90</rotate>\
                      <instance_geometry url=\"#link2-mesh\"/></node>";
        let twice = format!("{}{second}{}", &text[..end], &text[end..]);
        let (lo4, hi4) = bounds("twice.dae", &twice, [1.0; 3]);
        assert!(
            close(lo4, [-0.09, -0.09, -0.05]) && close(hi4, [1.06, 0.09, 0.45]),
            "{lo4:?} {hi4:?}"
        );
        // A node of the library placed by <instance_node> under a moved node.
        let start = text.find(node).unwrap();
        let part = text[start..end].replacen("id=\"link2\"", "id=\"part\"", 1);
        let holder =
            "<node id=\"holder\"><translate>0 7 0</translate><instance_node url=\"#part\"/></node>";
        let library = format!("<library_nodes>{part}</library_nodes><library_visual_scenes>");
        let by_reference = format!("{}{holder}{}", &text[..start], &text[end..]).replacen(
            "<library_visual_scenes>",
            &library,
            1,
        );
        let (lo5, hi5) = bounds("reference.dae", &by_reference, [1.0; 3]);
        assert!(
            close(lo5, [-0.09, 6.94, -0.05]) && close(hi5, [0.09, 7.06, 0.45]),
            "{lo5:?}"
        );
        // What places nothing, or too much, is refused with what is wrong.
        let refused = |name: &str, text: &str| {
            let file = dir.join(name);
            std::fs::write(&file, text).unwrap();
            load_hull(&file, [1.0; 3]).unwrap_err()
        };
        let scene = text.find("<scene>").unwrap();
        let scene_end = text.find("</scene>").unwrap() + "</scene>".len();
        let no_scene = format!("{}{}", &text[..scene], &text[scene_end..]);
        assert!(refused("no-scene.dae", &no_scene).contains("no <scene>"));
        let unplaced = format!("{}{}", &text[..start], &text[end..]);
        assert!(refused("unplaced.dae", &unplaced).contains("places no geometry"));
        let looped = by_reference.replacen(
            "<instance_geometry url=\"#link2-mesh\"/>",
            "<instance_geometry url=\"#link2-mesh\"/><instance_node url=\"#part\"/>",
            1,
        );
        assert!(refused("loop.dae", &looped).contains("more than 100000"));
        // The file with `nodes` as its library and the scene's node placing library node
        // `placed` too.
        let with_library = |nodes: String, placed: &str| {
            text.replacen(
                "<instance_geometry url=\"#link2-mesh\"/>",
                &format!(
                    "<instance_geometry url=\"#link2-mesh\"/><instance_node url=\"#{placed}\"/>"
                ),
                1,
            )
            .replacen(
                "<library_visual_scenes>",
                &format!("<library_nodes>{nodes}</library_nodes><library_visual_scenes>"),
                1,
            )
        };
        // A node of 200,000 references to another is refused at the limit.
        let wide = with_library(
            format!(
                "<node id=\"wide\">{}</node><node id=\"leaf\"/>",
                "<instance_node url=\"#leaf\"/>".repeat(200_000)
            ),
            "wide",
        );
        assert!(refused("wide.dae", &wide).contains("more than 100000 nodes"));
        // A large node placed many times is refused by the elements its placements read.
        let heavy = with_library(
            format!(
                "<node id=\"heavy\">{}</node><node id=\"many\">{}</node>",
                "<extra/>".repeat(200),
                "<instance_node url=\"#heavy\"/>".repeat(60_000)
            ),
            "many",
        );
        assert!(refused("heavy.dae", &heavy).contains("more than 10000000 elements"));
        // As Assimp composes a node: <lookat> (eye, target, up), <skew> ignored, a comment
        // before the numbers skipped, a <matrix>'s bottom row not used on the vertices.
        let lookat = moved.replacen(
            "<translate>1 2 3</translate>",
            "<lookat>1 2 3 1 2 2 0 1 0</lookat>",
            1,
        );
        assert_eq!(bounds("lookat.dae", &lookat, [1.0; 3]), (lo3, hi3));
        let skew = moved.replacen("<translate>", "<skew>45 0 1 0 1 0 0</skew><translate>", 1);
        assert_eq!(bounds("skew.dae", &skew, [1.0; 3]), (lo3, hi3));
        let comment = moved.replacen("<translate>", "<translate>\n  <!-- metres -->", 1);
        assert_eq!(bounds("comment.dae", &comment, [1.0; 3]), (lo3, hi3));
        // With the visual scenes first, the reader's messages still name the file's lines.
        let (vs0, vs1) = (
            text.find("<library_visual_scenes>").unwrap(),
            text.find("</library_visual_scenes>").unwrap() + "</library_visual_scenes>".len(),
        );
        let geometries = text.find("<library_geometries>").unwrap();
        let first = format!(
            "{}{}{}{}",
            &text[..geometries],
            &text[vs0..vs1],
            &text[geometries..vs0],
            &text[vs1..]
        );
        let p = first.find("<p>").unwrap() + "<p>".len();
        let broken = format!("{}x {}", &first[..p], &first[p..]);
        let line = broken[..p].matches('\n').count() + 1;
        let said = refused("first.dae", &broken);
        assert!(said.contains(&format!("({line}:")), "line {line}: {said}");
        let matrix = moved.replacen(
            "<translate>1 2 3</translate>",
            "<matrix>1 0 0 1 0 1 0 2 0 0 1 3 0 0 0 2</matrix>",
            1,
        );
        assert_eq!(bounds("matrix.dae", &matrix, [1.0; 3]), (lo3, hi3));
        // An <instance_node> names a library node by id, else a node of the scene by name.
        let holder = "<node id=\"holder\"><translate>0 7 0</translate>\
                      <instance_node url=\"#part\"/></node>";
        let by_name = format!("{}{holder}{}", &text[..end], &text[end..]).replacen(
            "id=\"link2\" name=\"link2\"",
            "id=\"link2\" name=\"part\"",
            1,
        );
        let (lo7, hi7) = bounds("by-name.dae", &by_name, [1.0; 3]);
        assert!(
            close(lo7, lo) && close(hi7, [0.09, 7.06, 0.45]),
            "{lo7:?} {hi7:?}"
        );
        let outside = text.replacen(
            "<node id=\"link2\"",
            "<instance_geometry url=\"#link2-mesh\"/><node id=\"link2\"",
            1,
        );
        assert!(refused("outside.dae", &outside).contains("directly in the <visual_scene>"));
        // A skinned mesh, a reference outside the file and a scene that names no visual scene.
        for (name, from, to, says) in [
            (
                "skin.dae",
                "<instance_geometry url=\"#link2-mesh\"/>",
                "<instance_controller url=\"#skin\"/>",
                "<instance_controller>: a skinned mesh is not supported",
            ),
            (
                "outer.dae",
                "<instance_geometry url=\"#link2-mesh\"/>",
                "<instance_geometry url=\"other.dae#link2-mesh\"/>",
                "<instance_geometry url=\"other.dae#link2-mesh\">: not a reference within the file",
            ),
            (
                "scene.dae",
                "<instance_visual_scene url=\"#Scene\"/>",
                "<instance_visual_scene url=\"#link2-mesh\"/>",
                "<instance_visual_scene url=\"#link2-mesh\">: names no <visual_scene>",
            ),
        ] {
            assert!(text.contains(from), "{from}");
            let said = refused(name, &text.replacen(from, to, 1));
            assert!(said.starts_with("line ") && said.contains(says), "{said}");
        }
        let short = moved.replacen("1 2 3", "1 2", 1);
        assert!(refused("short.dae", &short)
            .contains("<translate>1 2</translate>: needs 3 finite numbers"));
        // An instance of no geometry places nothing (as in Assimp).
        let nowhere = twice.replacen("url=\"#link2-mesh\"", "url=\"#nothing\"", 1);
        let (lo6, hi6) = bounds("nowhere.dae", &nowhere, [1.0; 3]);
        assert!(
            close(lo6, [0.94, -0.09, -0.05]) && close(hi6, [1.06, 0.09, 0.45]),
            "{lo6:?}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A triangle with two equal corners is a line, which Assimp-based readers (coal, MoveIt)
    /// drop: its stray vertex does not grow the hull.
    #[test]
    fn a_triangle_with_two_equal_corners_does_not_grow_the_hull() {
        let dir = tempfile::tempdir().unwrap();
        let tetra =
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 5 5 5\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
        let top = |text: &str| {
            let file = dir.path().join("m.obj");
            std::fs::write(&file, text).unwrap();
            let (hull, points) = load_hull(&file, [1.0; 3]).unwrap();
            let poly = hull.as_convex_polyhedron().unwrap().points().to_vec();
            let top = poly
                .iter()
                .map(|p| p.x.max(p.y).max(p.z))
                .fold(f64::MIN, f64::max);
            (top, points)
        };
        assert_eq!(top(tetra), (1.0, 12));
        assert_eq!(top(&format!("{tetra}f 1 5 5\n")), (1.0, 12));
        // A collinear triangle of three distinct corners is kept, as by Assimp.
        assert_eq!(top(&format!("{tetra}v 2 0 0\nf 1 2 6\n")).0, 2.0);
    }

    #[test]
    fn a_caught_panic_gives_its_first_line_and_no_panic_escapes() {
        assert_eq!(catch_quietly(|| 7), Ok(7));
        let e = catch_quietly(|| -> u8 { panic!("index out of bounds\nsecond line") });
        assert_eq!(e, Err("index out of bounds".to_string()));
        let formatted = catch_quietly(|| -> u8 { panic!("no entry for {}", "key") });
        assert_eq!(formatted, Err("no entry for key".to_string()));
        let silent = catch_quietly(|| -> u8 { std::panic::panic_any(3_u32) });
        assert_eq!(silent, Err(String::new()));
    }
}
