//! The scenario file as written (TOML), before validation. See the README for the format.

use super::config::{ObjectiveWeights, OptimizerConfig};
use crate::kinematics::Placement;
use crate::planning::PlannerConfig;
use serde::de::{self, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A design parameter in a scenario: a number fixes it, `[lower, upper]` makes it a free design
/// variable with those bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamSpec {
    /// A fixed value.
    Fixed(f64),
    /// A free variable with bounds `[lower, upper]`.
    Free(f64, f64),
}

impl Default for ParamSpec {
    fn default() -> Self {
        ParamSpec::Fixed(0.0)
    }
}

impl Serialize for ParamSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match *self {
            ParamSpec::Fixed(v) => s.serialize_f64(v),
            ParamSpec::Free(lo, hi) => [lo, hi].serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for ParamSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ParamSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number (fixed) or [lower, upper] (a free design variable)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<ParamSpec, E> {
                Ok(ParamSpec::Fixed(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ParamSpec, E> {
                Ok(ParamSpec::Fixed(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ParamSpec, E> {
                Ok(ParamSpec::Fixed(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<ParamSpec, A::Error> {
                let lo: f64 = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(0, &self))?;
                let hi: f64 = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(1, &self))?;
                if seq.next_element::<f64>()?.is_some() {
                    return Err(de::Error::invalid_length(3, &self));
                }
                Ok(ParamSpec::Free(lo, hi))
            }
        }
        d.deserialize_any(V)
    }
}

/// One actuation axis in a link template: its lower and upper limit, each fixed or free.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisSpec {
    /// The lower limit (paper Eq. 20).
    pub min: ParamSpec,
    /// The upper limit (paper Eq. 21).
    pub max: ParamSpec,
}

/// The actuated axes of a link template; an axis left out is not a joint.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct AxesSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rx: Option<AxisSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ry: Option<AxisSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rz: Option<AxisSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tx: Option<AxisSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ty: Option<AxisSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tz: Option<AxisSpec>,
}

impl AxesSpec {
    /// The six entries in the order of paper Eq. 2.
    pub fn entries(&self) -> [Option<AxisSpec>; 6] {
        [self.rx, self.ry, self.rz, self.tx, self.ty, self.tz]
    }
}

/// A link template: the uniform one (`[robot.uniform]`) or a per-link override
/// (`[[robot.link]]` with `index`). Anything left out falls back to the uniform template, and
/// from there to 0 (fixed) and no joints.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    /// Link index (from 1) in an override; absent in the uniform template.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub index: Option<usize>,
    /// DH θ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub theta: Option<ParamSpec>,
    /// DH d.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub d: Option<ParamSpec>,
    /// DH a, the link length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<ParamSpec>,
    /// DH α.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<ParamSpec>,
    /// Actuated axes. In an override, each listed axis replaces the uniform one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<AxesSpec>,
}

fn default_link_radius() -> f64 {
    0.02
}
fn default_colliders() -> usize {
    4
}
fn default_snap() -> f64 {
    1e-3
}

/// The `[robot]` section: the robot template.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Number of links `n` of the generic chain (paper Eq. 1).
    pub links: usize,
    /// Capsule radius of every link (metres). Default 0.02.
    #[serde(default = "default_link_radius")]
    pub link_radius: f64,
    /// Point colliders per link `s_i` (paper Eq. 6). Default 4.
    #[serde(default = "default_colliders")]
    pub colliders_per_link: usize,
    /// Values closer to zero than this become zero when decoding a design, removing links and
    /// joints. Default 0.001.
    #[serde(default = "default_snap")]
    pub snap: f64,
    /// Base placement. Default: the origin.
    #[serde(default)]
    pub base: Placement,
    /// The tool centre point in the last link's frame. Default: the identity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<Placement>,
    /// Template for every link.
    #[serde(default)]
    pub uniform: LinkSpec,
    /// Per-link overrides.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub link: Vec<LinkSpec>,
    /// Check the arm's bodies against each other. Default true.
    #[serde(default = "default_true")]
    pub self_collision: bool,
    /// Pairs of links (from 1; 0 is the base) never checked against each other, on top of
    /// the computed allowed-collision matrix. Default none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub allowed_collisions: Vec<[usize; 2]>,
    /// Random configurations sampled for the "Always in collision" rule of the
    /// allowed-collision matrix. Default 1000.
    #[serde(default = "default_self_samples")]
    pub self_collision_samples: usize,
}

fn default_true() -> bool {
    true
}

fn default_self_samples() -> usize {
    1000
}

/// Obstacle shape kinds accepted in `[[obstacle]] shape = …`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShapeKind {
    /// Needs `radius`.
    Sphere,
    /// Needs `radius` and `length` (along local z).
    Capsule,
    /// Needs `size` (full side lengths).
    Cuboid,
    /// Needs `radius` and `length` (along local z).
    Cylinder,
    /// Needs `file` (STL or OBJ, relative to the scenario file); optional `representation`
    /// and `scale`.
    Mesh,
}

/// A scale: one factor for all axes, or `[sx, sy, sz]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum ScaleSpec {
    /// The same factor on every axis.
    Uniform(f64),
    /// One factor per axis.
    PerAxis(#[serde(deserialize_with = "crate::limits::exact::array")] [f64; 3]),
}

impl ScaleSpec {
    /// The three factors.
    pub fn factors(&self) -> [f64; 3] {
        match *self {
            ScaleSpec::Uniform(s) => [s; 3],
            ScaleSpec::PerAxis(v) => v,
        }
    }
}

/// One `[[obstacle]]` entry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    /// Optional name for messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The shape kind.
    pub shape: ShapeKind,
    /// Position of the shape's centre.
    #[serde(deserialize_with = "crate::limits::exact::array")]
    pub position: [f64; 3],
    /// Orientation as roll, pitch, yaw (fixed axes x, y, z, as URDF). Default 0.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    pub rpy: Option<[f64; 3]>,
    /// Orientation as a unit quaternion `[x, y, z, w]` (ROS order), instead of `rpy`.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    pub quaternion: Option<[f64; 4]>,
    /// Radius (sphere, capsule, cylinder).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Length along local z (capsule: between the cap centres; cylinder: full height).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<f64>,
    /// Full side lengths (cuboid).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    pub size: Option<[f64; 3]>,
    /// Mesh file, relative to the scenario file (mesh).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// `hull`, `decomposition` or `trimesh` (mesh). Default `hull`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub representation: Option<crate::world::MeshRepresentation>,
    /// Scale of the mesh in its own frame (mesh). Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<ScaleSpec>,
}

/// One `[[task]]` entry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSpec {
    /// Optional name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The point the tool centre point must reach.
    #[serde(deserialize_with = "crate::limits::exact::array")]
    pub point: [f64; 3],
    /// A full orientation of the TCP frame (`rpy` or `quaternion`), with
    /// `orientation_tolerance`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<OrientationSpec>,
    /// Largest rotation angle (radians, in `[0, π]`) between the TCP frame and `orientation`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation_tolerance: Option<f64>,
    /// The direction the tool's z axis must point along (non-zero; normalised), with
    /// `approach_tolerance`; rotation about it is free.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    pub approach: Option<[f64; 3]>,
    /// Half-angle (radians, in `[0, π]`) of the cone about `approach` the tool's z axis must
    /// lie in.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub approach_tolerance: Option<f64>,
}

/// A task's orientation: roll, pitch, yaw (fixed axes, as URDF) or a unit quaternion
/// `[x, y, z, w]` (ROS order).
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrientationSpec {
    /// Roll, pitch, yaw (radians).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    pub rpy: Option<[f64; 3]>,
    /// A unit quaternion `[x, y, z, w]` (norm within 1e-6 of 1; normalised).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    pub quaternion: Option<[f64; 4]>,
}

/// The whole scenario file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioSpec {
    /// Optional name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Seed of every random stream. Default 0.
    #[serde(default)]
    pub seed: u64,
    /// Clearance `ε` (metres) the body keeps from obstacles (paper Eq. 15). Default 0.
    #[serde(default)]
    pub clearance: f64,
    /// The robot template.
    pub robot: RobotSpec,
    /// Planner settings.
    #[serde(default)]
    pub planner: PlannerConfig,
    /// Objective weights.
    #[serde(default)]
    pub objective: ObjectiveWeights,
    /// Optimiser settings.
    #[serde(default)]
    pub optimizer: OptimizerConfig,
    /// Obstacles.
    #[serde(default)]
    pub obstacle: Vec<ObstacleSpec>,
    /// Task points.
    #[serde(default)]
    pub task: Vec<TaskSpec>,
}
