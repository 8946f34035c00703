//! A concrete design: DH geometry, axis ranges and body size of every link (paper Eq. 19–21).

use crate::error::{fmt_list, Error, Num, Result};
use crate::kinematics::{Axis, Chain, Dh, Link, Placement, Range};
use crate::limits::{within, MAX_ANGLE, MAX_COLLIDERS_PER_LINK, MAX_LENGTH, MAX_LINKS};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::path::Path;

/// The six axis ranges of a link. In files it is a table of the axes that are present, each as
/// `[min, max]`; an axis left out is `[0, 0]` (absent).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct AxisRanges(pub [Range; 6]);

#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct AxisRangesFile {
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    rx: Option<[f64; 2]>,
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    ry: Option<[f64; 2]>,
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    rz: Option<[f64; 2]>,
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    tx: Option<[f64; 2]>,
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    ty: Option<[f64; 2]>,
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::limits::exact::option"
    )]
    tz: Option<[f64; 2]>,
}

impl AxisRangesFile {
    fn slots(&mut self) -> [&mut Option<[f64; 2]>; 6] {
        [
            &mut self.rx,
            &mut self.ry,
            &mut self.rz,
            &mut self.tx,
            &mut self.ty,
            &mut self.tz,
        ]
    }
}

impl Serialize for AxisRanges {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut f = AxisRangesFile::default();
        for (slot, r) in f.slots().into_iter().zip(self.0) {
            if r != Range::ZERO {
                *slot = Some([r.min, r.max]);
            }
        }
        f.serialize(s)
    }
}

impl<'de> Deserialize<'de> for AxisRanges {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let mut f = AxisRangesFile::deserialize(d)?;
        let mut out = [Range::ZERO; 6];
        for (r, slot) in out.iter_mut().zip(f.slots()) {
            if let Some([min, max]) = *slot {
                *r = Range::new(min, max);
            }
        }
        Ok(AxisRanges(out))
    }
}

impl AxisRanges {
    /// The range of one axis.
    pub fn get(&self, axis: Axis) -> Range {
        self.0[axis.index()]
    }

    /// Mutable access to one axis's range.
    pub fn get_mut(&mut self, axis: Axis) -> &mut Range {
        &mut self.0[axis.index()]
    }
}

/// One link of a design: its DH geometry (paper Eq. 19) and its axis ranges (Eq. 20–21).
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkDesign {
    /// DH θ (radians): a constant of the geometry.
    #[serde(default)]
    pub theta: f64,
    /// DH d (metres).
    #[serde(default)]
    pub d: f64,
    /// DH a (metres): the link length `a_i`.
    #[serde(default)]
    pub a: f64,
    /// DH α (radians).
    #[serde(default)]
    pub alpha: f64,
    /// Ranges of the six actuation axes.
    #[serde(default)]
    pub axes: AxisRanges,
}

impl LinkDesign {
    /// The DH parameters of this link.
    pub fn dh(&self) -> Dh {
        Dh {
            theta: self.theta,
            d: self.d,
            a: self.a,
            alpha: self.alpha,
        }
    }

    /// True when the link has a body (`a ≠ 0` or `d ≠ 0`): it is kept (paper Eq. 28 counts `a`).
    pub fn has_length(&self) -> bool {
        self.a != 0.0 || self.d != 0.0
    }

    /// Number of joints: axes with a non-zero range.
    pub fn joint_count(&self) -> usize {
        self.axes.0.iter().filter(|r| r.is_joint()).count()
    }
}

/// A concrete design: everything needed to build a [`Chain`]. Serialises to the design JSON
/// documented in the README.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Design {
    /// Pose of the robot base in the world.
    #[serde(default)]
    pub base: Placement,
    /// Radius of the capsule around every link segment (metres).
    pub link_radius: f64,
    /// Number `s_i` of point colliders per link (paper Eq. 6).
    pub colliders_per_link: usize,
    /// The links, base to tip.
    pub links: Vec<LinkDesign>,
    /// The tool centre point (TCP) in the last link's frame `F_n`. Default (and `None`): the
    /// identity, the TCP is `F_n`. Exported as the fixed joint `tool0_joint`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<Placement>,
}

impl Design {
    /// The chain for forward kinematics.
    pub fn chain(&self) -> Chain {
        let links: Vec<Link> = self
            .links
            .iter()
            .map(|l| Link::from_dh(&l.dh(), l.axes.0))
            .collect();
        let chain = Chain::new(
            self.base.isometry(),
            &links,
            self.link_radius,
            self.colliders_per_link,
        );
        match &self.tool {
            Some(t) => chain.with_tool(t.isometry()),
            None => chain,
        }
    }

    /// The tool centre point in `F_n` as a rigid transform (the identity without a tool).
    pub fn tool_isometry(&self) -> nalgebra::IsometryMatrix3<f64> {
        self.tool
            .map_or_else(nalgebra::IsometryMatrix3::identity, |t| t.isometry())
    }

    /// Total body length `Σ (|a_i| + |d_i|)`.
    pub fn total_length(&self) -> f64 {
        self.links.iter().map(|l| l.a.abs() + l.d.abs()).sum()
    }

    /// Number of links with a body.
    pub fn links_kept(&self) -> usize {
        self.links.iter().filter(|l| l.has_length()).count()
    }

    /// Number of joints (axes with a non-zero range) over all links.
    pub fn joints_kept(&self) -> usize {
        self.links.iter().map(LinkDesign::joint_count).sum()
    }

    /// Checks every number: finite values within the bounds of [`crate::limits`] (lengths and
    /// translation limits within ±[`MAX_LENGTH`] m, angles and rotation limits within
    /// ±[`MAX_ANGLE`] rad), `min ≤ max`, non-negative radius, 1 to [`MAX_LINKS`] links and at
    /// most [`MAX_COLLIDERS_PER_LINK`] colliders per link. Field paths look like
    /// `links[2].axes.ry`.
    pub fn validate(&self) -> Result<()> {
        if self.links.is_empty() {
            return Err(Error::invalid(
                "links",
                "[]",
                "a design needs at least one link",
            ));
        }
        if self.links.len() > MAX_LINKS {
            return Err(Error::invalid(
                "links",
                format!("[{} links]", self.links.len()),
                format!("a design has at most {MAX_LINKS} links"),
            ));
        }
        if self.colliders_per_link > MAX_COLLIDERS_PER_LINK {
            return Err(Error::invalid(
                "colliders_per_link",
                self.colliders_per_link,
                format!("must be at most {MAX_COLLIDERS_PER_LINK}"),
            ));
        }
        if !(self.link_radius >= 0.0 && within(self.link_radius, MAX_LENGTH)) {
            return Err(Error::invalid(
                "link_radius",
                Num(self.link_radius),
                format!("must be finite, not negative and at most {MAX_LENGTH} m"),
            ));
        }
        let tool = self.tool.unwrap_or_default();
        for (name, v, bound, unit) in [
            ("base.position", self.base.position, MAX_LENGTH, "m"),
            ("base.rpy", self.base.rpy, MAX_ANGLE, "rad"),
            ("tool.position", tool.position, MAX_LENGTH, "m"),
            ("tool.rpy", tool.rpy, MAX_ANGLE, "rad"),
        ] {
            if !v.iter().all(|&c| within(c, bound)) {
                return Err(Error::invalid(
                    name.to_string(),
                    fmt_list(&v),
                    format!("every value must be finite and within ±{bound} {unit}"),
                ));
            }
        }
        for (i, l) in self.links.iter().enumerate() {
            for (name, v, bound, unit) in [
                ("theta", l.theta, MAX_ANGLE, "rad"),
                ("d", l.d, MAX_LENGTH, "m"),
                ("a", l.a, MAX_LENGTH, "m"),
                ("alpha", l.alpha, MAX_ANGLE, "rad"),
            ] {
                if !within(v, bound) {
                    return Err(Error::invalid(
                        format!("links[{i}].{name}"),
                        Num(v),
                        format!("must be finite and within ±{bound} {unit}"),
                    ));
                }
            }
            for axis in Axis::ALL {
                let r = l.axes.get(axis);
                let field = format!("links[{i}].axes.{axis}");
                let (bound, unit) = if axis.is_rotation() {
                    (MAX_ANGLE, "rad")
                } else {
                    (MAX_LENGTH, "m")
                };
                if !(within(r.min, bound) && within(r.max, bound)) {
                    return Err(Error::invalid(
                        field,
                        fmt_list(&[r.min, r.max]),
                        format!("limits must be finite and within ±{bound} {unit}"),
                    ));
                }
                if r.min > r.max {
                    return Err(Error::invalid(
                        field,
                        fmt_list(&[r.min, r.max]),
                        "min must not exceed max",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Reads a design JSON file, or the `design` member of an optimiser's `best.json`, and
    /// validates it. Errors name the file.
    pub fn load(path: &Path) -> Result<Design> {
        let text = crate::limits::read_text(path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(
            |source| Error::Read {
                path: path.to_path_buf(),
                source,
            },
        )?;
        // A file that does not start as a JSON object is no design at all: say what it is.
        let hint = match text.trim_start().chars().next() {
            Some('{') => "",
            Some('<') => " (an XML file such as a URDF; a design is a JSON object)",
            _ => " (not a JSON object; a design is one, as optimize writes in best.json)",
        };
        let parse_err = |e: serde_json::Error| Error::Parse {
            file: path.to_path_buf(),
            message: format!("{e}{hint}"),
        };
        // A best.json holds its design under `design`. The text is read once more as what it
        // holds (rather than from a parsed value, which keeps the last of two equal keys), so
        // that a key given twice is refused.
        let value: serde_json::Value = serde_json::from_str(&text).map_err(parse_err)?;
        let wrapped = matches!(&value, serde_json::Value::Object(m) if m.contains_key("design"));
        /// A best.json: the design and whatever else it holds.
        #[derive(Deserialize)]
        struct Wrapped {
            design: Design,
        }
        let mut de = serde_json::Deserializer::from_str(&text);
        let parsed = if wrapped {
            crate::strict::deserialize(&mut de).map(|w: Wrapped| w.design)
        } else {
            crate::strict::deserialize(&mut de)
        };
        let design: Design = parsed.map_err(|e| Error::Parse {
            file: path.to_path_buf(),
            message: crate::strict::message(&e),
        })?;
        // A best.json's fields are named from the file's top, as its parse errors are.
        design
            .validate()
            .map_err(|e| if wrapped { e.under("design") } else { e })
            .map_err(|e| e.in_file(path))?;
        Ok(design)
    }

    /// The design as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a design always serialises")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Design {
        let mut axes = AxisRanges::default();
        *axes.get_mut(Axis::Ry) = Range::new(-1.5, 1.5);
        *axes.get_mut(Axis::Tz) = Range::new(0.1, 0.1);
        Design {
            base: Placement::default(),
            link_radius: 0.05,
            colliders_per_link: 4,
            links: vec![
                LinkDesign {
                    a: 0.4,
                    axes,
                    ..LinkDesign::default()
                },
                LinkDesign::default(),
            ],
            tool: None,
        }
    }

    #[test]
    fn json_round_trip_lists_only_present_axes() {
        let d = sample();
        let json = d.to_json();
        assert!(json.contains("\"ry\""));
        assert!(json.contains("\"tz\""));
        assert!(!json.contains("\"rx\""));
        let back: Design = serde_json::from_str(&json).unwrap();
        assert_eq!(back, d);
        assert_eq!(d.links_kept(), 1);
        assert_eq!(d.joints_kept(), 1);
        assert_eq!(d.chain().dof(), 1);
    }

    #[test]
    fn unknown_axis_is_rejected() {
        let e = serde_json::from_str::<Design>(
            r#"{"link_radius":0.1,"colliders_per_link":2,"links":[{"axes":{"rw":[0,1]}}]}"#,
        )
        .unwrap_err();
        assert!(e.to_string().contains("rw"), "{e}");
    }

    #[test]
    fn validate_names_the_bad_range() {
        let mut d = sample();
        *d.links[1].axes.get_mut(Axis::Rx) = Range::new(1.0, -1.0);
        let e = d.validate().unwrap_err().to_string();
        assert!(e.contains("links[1].axes.rx"), "{e}");
        assert!(e.contains("[1, -1]"), "{e}");
    }
}
