//! Export of a [`Design`] as a URDF robot (with urdf-rs).
//!
//! Structure, base to tip (see also the README's "URDF" section):
//!
//! - `base_link`: the root, the scenario's world frame. A fixed joint `base_joint` whose origin is
//!   the design's base pose leads to `link0`, the chain's base frame `F_0`.
//! - Per link `i`, a fixed joint `link{i}_geometry` whose origin is the DH transform `T_i`, from
//!   `link{i−1}` to `link{i}_dh` (the joint frame `F_{i−1}·T_i`), then one joint per free axis in
//!   the order of paper Eq. 2 (`rx, ry, rz, tx, ty, tz`): `revolute` about or `prismatic` along
//!   the local x, y or z axis, named `j{i}_{axis}`, with `<limit>` from the axis range and the
//!   documented [`EFFORT`] and [`VELOCITY`]. Each joint's child is `link{i}_{axis}`, except the
//!   last one, whose child is `link{i}` (the frame `F_i` after the link's actuation).
//! - An axis with a zero-width range at a non-zero value is a constant: it folds into the origin
//!   of the next joint of the link, or into a fixed joint `link{i}_fixed` that ends the link. A
//!   link without any axis goes straight from `link{i}_geometry` to `link{i}`.
//! - A fixed joint `tool0_joint` from `link{n}` to `tool0`, the tool centre point: its origin
//!   is the design's tool (`[robot] tool`, the identity by default).
//!
//! Every link has the negligible mass [`LINK_MASS`] and inertia [`LINK_INERTIA`]·I (massless for
//! kinematics, but valid for simulators that reject zero masses).
//!
//! Geometry: every body segment the planner uses is a capsule of the design's link radius, written
//! as a `<cylinder>` along the segment plus a `<sphere>` at each end, in both `<collision>` and
//! `<visual>`. The DH body of link `i` (`d` along z, then `a` along x: [`crate::kinematics::Dh::body`])
//! sits on `link{i}_dh`. The slider segment of a link with translation axes (from the joint
//! origin to `F_i`'s origin) changes length with the prismatic joint, which a URDF link cannot do:
//! each translation axis gets its own capsule on the child link of its joint, covering every
//! position the segment can take over the joint's range, from `−max` to `−min` along the axis
//! (and always the joint origin). It is exact at the end of the stroke and conservative (a
//! superset of the planner's body) elsewhere. A link with several translation axes gets one such
//! capsule per axis, a polyline where the planner has one straight slider.

use crate::design::Design;
use crate::error::Result;
use crate::kinematics::{Axis, Range};
use nalgebra::{IsometryMatrix3, Point3, Rotation3, Translation3, Unit, Vector3};
use std::path::Path;

/// `<limit effort>` of every exported joint (N·m for revolute, N for prismatic joints): a
/// placeholder, since kinsynth designs kinematics only.
pub const EFFORT: f64 = 100.0;
/// `<limit velocity>` of every exported joint (rad/s or m/s): a placeholder, as [`EFFORT`].
pub const VELOCITY: f64 = 1.0;
/// Mass of every exported link (kg): negligible, but valid.
pub const LINK_MASS: f64 = 1e-6;
/// Diagonal of the inertia tensor of every exported link (kg·m²): negligible, but valid.
pub const LINK_INERTIA: f64 = 1e-9;
/// Name of the root link.
pub const BASE_LINK: &str = "base_link";
/// Name of the end-effector link.
pub const TOOL_LINK: &str = "tool0";

/// Name of the link after link `i`'s actuation (`link{i}`; `link0` is the base frame `F_0`).
pub fn link_name(i: usize) -> String {
    format!("link{i}")
}

/// A URDF pose from a rigid transform (`rpy` as in [`crate::kinematics::Placement`]).
pub fn pose_of(t: &IsometryMatrix3<f64>) -> urdf_rs::Pose {
    let (r, p, y) = t.rotation.euler_angles();
    let v = t.translation.vector;
    urdf_rs::Pose {
        xyz: urdf_rs::Vec3([v.x, v.y, v.z]),
        rpy: urdf_rs::Vec3([r, p, y]),
    }
}

/// The rigid transform of a URDF pose.
pub fn isometry_of(p: &urdf_rs::Pose) -> IsometryMatrix3<f64> {
    let [x, y, z] = p.xyz.0;
    let [r, pi, ya] = p.rpy.0;
    IsometryMatrix3::from_parts(
        Translation3::new(x, y, z),
        Rotation3::from_euler_angles(r, pi, ya),
    )
}

/// The elementary transform of one axis at value `v`: a rotation about, or a translation along,
/// a local coordinate axis.
pub fn axis_transform(axis: Axis, v: f64) -> IsometryMatrix3<f64> {
    if axis.is_rotation() {
        let rot = Rotation3::from_axis_angle(&Unit::new_unchecked(axis.direction()), v);
        IsometryMatrix3::from_parts(Translation3::identity(), rot)
    } else {
        IsometryMatrix3::from_parts(
            Translation3::from(axis.direction() * v),
            Rotation3::identity(),
        )
    }
}

/// A rotation that maps local z onto the unit vector `d`.
pub(crate) fn z_to(d: &Vector3<f64>) -> Rotation3<f64> {
    Rotation3::rotation_between(&Vector3::z(), d).unwrap_or_else(|| {
        // `d` is −z: any half turn about an axis normal to z.
        Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    })
}

fn inertial() -> urdf_rs::Inertial {
    urdf_rs::Inertial {
        origin: urdf_rs::Pose::default(),
        mass: urdf_rs::Mass { value: LINK_MASS },
        inertia: urdf_rs::Inertia {
            ixx: LINK_INERTIA,
            ixy: 0.0,
            ixz: 0.0,
            iyy: LINK_INERTIA,
            iyz: 0.0,
            izz: LINK_INERTIA,
        },
    }
}

/// The robot-level material of every visual: defined once, referred to by name.
fn material(defined: bool) -> urdf_rs::Material {
    urdf_rs::Material {
        name: "kinsynth_body".into(),
        color: defined.then_some(urdf_rs::Color {
            rgba: urdf_rs::Vec4([0.9, 0.55, 0.1, 1.0]),
        }),
        texture: None,
    }
}

/// Builds the URDF link by link.
struct Builder {
    links: Vec<urdf_rs::Link>,
    joints: Vec<urdf_rs::Joint>,
    radius: f64,
}

impl Builder {
    fn link(&mut self, name: String) {
        self.links.push(urdf_rs::Link {
            name,
            inertial: inertial(),
            visual: Vec::new(),
            collision: Vec::new(),
        });
    }

    /// Adds the capsule `p → q` (in `link`'s frame) as a cylinder and two spheres, in both
    /// collision and visual. Zero-length segments are left out.
    fn capsule(&mut self, link: &str, tag: &str, p: Point3<f64>, q: Point3<f64>) {
        let v = q - p;
        let len = v.norm();
        if len == 0.0 {
            return;
        }
        let mid = nalgebra::center(&p, &q);
        let cyl = IsometryMatrix3::from_parts(Translation3::from(mid.coords), z_to(&(v / len)));
        let radius = self.radius;
        let mut parts = vec![(
            tag.to_string(),
            pose_of(&cyl),
            urdf_rs::Geometry::Cylinder {
                radius,
                length: len,
            },
        )];
        for (end, at) in [("start", p), ("end", q)] {
            let t =
                IsometryMatrix3::from_parts(Translation3::from(at.coords), Rotation3::identity());
            parts.push((
                format!("{tag}_{end}"),
                pose_of(&t),
                urdf_rs::Geometry::Sphere { radius },
            ));
        }
        let l = self
            .links
            .iter_mut()
            .find(|l| l.name == link)
            .expect("capsule on an existing link");
        for (name, origin, geometry) in parts {
            l.collision.push(urdf_rs::Collision {
                name: Some(name.clone()),
                origin: origin.clone(),
                geometry: geometry.clone(),
            });
            l.visual.push(urdf_rs::Visual {
                name: Some(name),
                origin,
                geometry,
                material: Some(material(false)),
            });
        }
    }

    fn fixed(&mut self, name: String, parent: &str, child: &str, origin: &IsometryMatrix3<f64>) {
        self.joints.push(joint(
            name,
            urdf_rs::JointType::Fixed,
            parent,
            child,
            origin,
            [1.0, 0.0, 0.0],
            urdf_rs::JointLimit::default(),
        ));
    }
}

fn joint(
    name: String,
    joint_type: urdf_rs::JointType,
    parent: &str,
    child: &str,
    origin: &IsometryMatrix3<f64>,
    axis: [f64; 3],
    limit: urdf_rs::JointLimit,
) -> urdf_rs::Joint {
    urdf_rs::Joint {
        name,
        joint_type,
        origin: pose_of(origin),
        parent: urdf_rs::LinkName {
            link: parent.to_string(),
        },
        child: urdf_rs::LinkName {
            link: child.to_string(),
        },
        axis: urdf_rs::Axis {
            xyz: urdf_rs::Vec3(axis),
        },
        limit,
        calibration: None,
        dynamics: None,
        mimic: None,
        safety_controller: None,
    }
}

/// The limit of a free axis with the documented effort and velocity.
fn limit(range: Range) -> urdf_rs::JointLimit {
    urdf_rs::JointLimit {
        lower: range.min,
        upper: range.max,
        effort: EFFORT,
        velocity: VELOCITY,
        ..urdf_rs::JointLimit::default()
    }
}

/// The URDF robot of a design, named `name`; see the module documentation for its structure.
/// Its joints are named as [`crate::kinematics::Chain::joint_names`] and come in the same
/// order, so a path of the design's chain replays on it.
pub fn design_to_urdf(design: &Design, name: &str) -> urdf_rs::Robot {
    let mut b = Builder {
        links: Vec::new(),
        joints: Vec::new(),
        radius: design.link_radius,
    };
    b.link(BASE_LINK.into());
    b.link(link_name(0));
    b.fixed(
        "base_joint".into(),
        BASE_LINK,
        &link_name(0),
        &design.base.isometry(),
    );
    for (k, l) in design.links.iter().enumerate() {
        let i = k + 1;
        let parent = link_name(k);
        let this = link_name(i);
        // Axes present (free or constant), in the order of paper Eq. 2.
        let ops: Vec<(Axis, Range)> = Axis::ALL
            .into_iter()
            .map(|a| (a, l.axes.get(a)))
            .filter(|(_, r)| r.is_joint() || r.min != 0.0)
            .collect();
        let dh_link = if ops.is_empty() {
            this.clone()
        } else {
            format!("{this}_dh")
        };
        let t = l.dh().transform();
        b.link(dh_link.clone());
        b.fixed(format!("{this}_geometry"), &parent, &dh_link, &t);
        // The DH body, from F_{i-1}'s origin to the joint origin, in the frame F_{i-1}·T_i.
        let inv = t.inverse();
        let body: Vec<Point3<f64>> = l.dh().body().iter().map(|p| inv * p).collect();
        for (s, w) in body.windows(2).enumerate() {
            b.capsule(&dh_link, &format!("{this}_body{s}"), w[0], w[1]);
        }
        let last_free = ops.iter().rposition(|(_, r)| r.is_joint());
        let mut current = dh_link;
        // Constants since the last emitted joint, as a transform from `current`'s frame.
        let mut pending = IsometryMatrix3::identity();
        for (n, &(axis, range)) in ops.iter().enumerate() {
            if !range.is_joint() {
                let next = pending * axis_transform(axis, range.min);
                if !axis.is_rotation() {
                    // A constant slider piece is exact: it is fixed to `current`.
                    let from = Point3::from(pending.translation.vector);
                    let to = Point3::from(next.translation.vector);
                    b.capsule(&current, &format!("{this}_{axis}_slider"), from, to);
                }
                pending = next;
                continue;
            }
            let child = if Some(n) == last_free && n + 1 == ops.len() {
                this.clone()
            } else {
                format!("{this}_{axis}")
            };
            b.link(child.clone());
            let kind = if axis.is_rotation() {
                urdf_rs::JointType::Revolute
            } else {
                urdf_rs::JointType::Prismatic
            };
            let dir = axis.direction();
            b.joints.push(joint(
                format!("j{i}_{}", axis.name()),
                kind,
                &current,
                &child,
                &pending,
                [dir.x, dir.y, dir.z],
                limit(range),
            ));
            if !axis.is_rotation() {
                // Every position of the slider over the range, in the child's frame: the
                // joint origin sits at −q along the axis.
                let lo = (-range.max).min(0.0);
                let hi = (-range.min).max(0.0);
                b.capsule(
                    &child,
                    &format!("{this}_{axis}_slider"),
                    Point3::from(dir * lo),
                    Point3::from(dir * hi),
                );
            }
            pending = IsometryMatrix3::identity();
            current = child;
        }
        if current != this {
            b.link(this.clone());
            b.fixed(format!("{this}_fixed"), &current, &this, &pending);
        }
    }
    b.link(TOOL_LINK.into());
    b.fixed(
        "tool0_joint".into(),
        &link_name(design.links.len()),
        TOOL_LINK,
        &design.tool_isometry(),
    );
    urdf_rs::Robot {
        name: name.to_string(),
        version: None,
        links: b.links,
        joints: b.joints,
        materials: vec![material(true)],
    }
}

/// The URDF text of a design (see [`design_to_urdf`]).
pub fn design_to_urdf_string(design: &Design, name: &str) -> String {
    let robot = design_to_urdf(design, name);
    let xml = urdf_rs::write_to_string(&robot).expect("a generated robot always serialises");
    format!("<?xml version=\"1.0\"?>\n{xml}\n")
}

/// Writes the URDF of `design` to `path` atomically; the robot is named after the file stem.
pub fn write_urdf(design: &Design, path: &Path) -> Result<()> {
    crate::io::write_atomic(path, urdf_text(design, path).as_bytes())
}

/// The text [`write_urdf`] writes to `path`, for a caller that writes it with others
/// ([`crate::io::Staged`]).
pub fn urdf_text(design: &Design, path: &Path) -> String {
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .filter(|s| !s.is_empty())
        .unwrap_or("kinsynth_robot");
    design_to_urdf_string(design, name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{AxisRanges, LinkDesign};
    use crate::kinematics::Placement;

    fn design() -> Design {
        let mut axes = AxisRanges::default();
        *axes.get_mut(Axis::Ry) = Range::new(-1.0, 1.0);
        *axes.get_mut(Axis::Rz) = Range::new(0.3, 0.3);
        *axes.get_mut(Axis::Tx) = Range::new(0.0, 0.2);
        Design {
            base: Placement::default(),
            link_radius: 0.03,
            colliders_per_link: 2,
            links: vec![
                LinkDesign {
                    d: 0.2,
                    a: 0.3,
                    axes,
                    ..LinkDesign::default()
                },
                LinkDesign::default(),
            ],
            tool: None,
        }
    }

    #[test]
    fn names_and_types_follow_the_convention() {
        let r = design_to_urdf(&design(), "t");
        let names: Vec<_> = r.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "base_joint",
                "link1_geometry",
                "j1_ry",
                "j1_tx",
                "link2_geometry",
                "tool0_joint"
            ]
        );
        // The constant yaw folds into the origin of the prismatic joint.
        let tx = &r.joints[3];
        assert_eq!(tx.joint_type, urdf_rs::JointType::Prismatic);
        assert!((tx.origin.rpy.0[2] - 0.3).abs() < 1e-15);
        assert_eq!(tx.child.link, "link1");
        assert_eq!(r.joints[2].child.link, "link1_ry");
        // The second link has no axis: its geometry joint leads to link2 directly.
        assert_eq!(r.joints[4].child.link, "link2");
    }

    #[test]
    fn bodies_are_cylinders_with_end_spheres() {
        let r = design_to_urdf(&design(), "t");
        let dh = r.links.iter().find(|l| l.name == "link1_dh").unwrap();
        // d and a: two capsules of three parts each.
        assert_eq!(dh.collision.len(), 6);
        assert_eq!(dh.visual.len(), 6);
        let lengths: Vec<f64> = dh
            .collision
            .iter()
            .filter_map(|c| match c.geometry {
                urdf_rs::Geometry::Cylinder { length, radius } => {
                    assert_eq!(radius, 0.03);
                    Some(length)
                }
                _ => None,
            })
            .collect();
        assert_eq!(lengths.len(), 2);
        assert!((lengths[0] - 0.2).abs() < 1e-15 && (lengths[1] - 0.3).abs() < 1e-15);
        // The slider covers the stroke behind link1's origin.
        let l1 = r.links.iter().find(|l| l.name == "link1").unwrap();
        let slider = l1
            .collision
            .iter()
            .find(|c| matches!(c.geometry, urdf_rs::Geometry::Cylinder { .. }))
            .unwrap();
        assert!((slider.origin.xyz.0[0] + 0.1).abs() < 1e-15);
    }
}
