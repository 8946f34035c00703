//! One link of the generic serial chain: fixed geometry followed by a six-axis actuation
//! (paper Eq. 1–2).

use super::axis::{Axis, Range};
use nalgebra::{IsometryMatrix3, Point3, Rotation3, Translation3, Vector3};
use serde::{Deserialize, Serialize};

/// Denavit–Hartenberg geometry of a link, `T_i = Rz(θ)·Tz(d)·Tx(a)·Rx(α)` (paper Eq. 1). Here θ
/// and d are constants of the geometry, not joint variables: the actuation comes after, in
/// [`Link::ranges`].
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dh {
    /// Rotation about the previous z axis (radians).
    #[serde(default)]
    pub theta: f64,
    /// Offset along the previous z axis (metres).
    #[serde(default)]
    pub d: f64,
    /// Length along the rotated x axis (metres): the link length `a_i`.
    #[serde(default)]
    pub a: f64,
    /// Twist about the new x axis (radians).
    #[serde(default)]
    pub alpha: f64,
}

impl Dh {
    /// The fixed transform `Rz(θ)·Tz(d)·Tx(a)·Rx(α)`.
    pub fn transform(&self) -> IsometryMatrix3<f64> {
        let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), self.theta);
        let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), self.alpha);
        let t = Vector3::new(0.0, 0.0, self.d) + rz * Vector3::new(self.a, 0.0, 0.0);
        IsometryMatrix3::from_parts(Translation3::from(t), rz * rx)
    }

    /// The link body as a polyline in the previous frame: from the origin, `d` along z, then `a`
    /// along the x axis rotated by θ. Zero-length pieces are left out, so a link with `a = d = 0`
    /// has no body.
    pub fn body(&self) -> Vec<Point3<f64>> {
        let mut pts = vec![Point3::origin()];
        let knee = Point3::new(0.0, 0.0, self.d);
        if self.d != 0.0 {
            pts.push(knee);
        }
        if self.a != 0.0 {
            let (s, c) = self.theta.sin_cos();
            pts.push(knee + Vector3::new(c * self.a, s * self.a, 0.0));
        }
        pts
    }
}

/// The fixed part of a link: a rigid transform from the previous link's actuated frame to this
/// link's joint frame, and the body polyline that joins them (in the previous frame).
///
/// Built from DH parameters for designs, or from a general transform (e.g. a URDF joint origin),
/// where the body is the straight line between the two frame origins.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkGeometry {
    /// Transform from frame `i−1` to the joint frame of link `i`, before actuation.
    pub transform: IsometryMatrix3<f64>,
    /// Body polyline, starting at the origin of frame `i−1` and ending at the origin of
    /// `transform`. A single point means the link has no body.
    pub body: Vec<Point3<f64>>,
}

impl LinkGeometry {
    /// Geometry of a DH link (paper Eq. 1).
    pub fn from_dh(dh: &Dh) -> Self {
        LinkGeometry {
            transform: dh.transform(),
            body: dh.body(),
        }
    }

    /// Geometry of a general fixed transform; the body is the straight segment between the
    /// origins (none when they coincide).
    pub fn from_transform(transform: IsometryMatrix3<f64>) -> Self {
        let end = Point3::from(transform.translation.vector);
        let body = if end.coords.norm() > 0.0 {
            vec![Point3::origin(), end]
        } else {
            vec![Point3::origin()]
        };
        LinkGeometry { transform, body }
    }

    /// Length of the body polyline.
    pub fn body_length(&self) -> f64 {
        self.body.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
    }
}

/// A link of the chain: fixed geometry, then the six actuation axes with their ranges.
#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    /// The fixed geometry `T_i`.
    pub geometry: LinkGeometry,
    /// Range of each axis, indexed by [`Axis::index`]; zero width means "not a joint".
    pub ranges: [Range; 6],
}

impl Link {
    /// A link from DH parameters and ranges.
    pub fn from_dh(dh: &Dh, ranges: [Range; 6]) -> Self {
        Link {
            geometry: LinkGeometry::from_dh(dh),
            ranges,
        }
    }

    /// The range of one axis.
    pub fn range(&self, axis: Axis) -> Range {
        self.ranges[axis.index()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn dh_body_ends_at_the_transform_origin() {
        let dh = Dh {
            theta: 0.7,
            d: 0.3,
            a: 0.5,
            alpha: 1.1,
        };
        let g = LinkGeometry::from_dh(&dh);
        assert_eq!(g.body.len(), 3);
        let end = g.body.last().unwrap();
        assert_relative_eq!(end.coords, g.transform.translation.vector, epsilon = 1e-15);
        assert_relative_eq!(g.body_length(), 0.8, epsilon = 1e-15);
    }

    #[test]
    fn zero_link_has_no_body() {
        let g = LinkGeometry::from_dh(&Dh::default());
        assert_eq!(g.body.len(), 1);
        assert_eq!(g.body_length(), 0.0);
        let g = LinkGeometry::from_transform(IsometryMatrix3::identity());
        assert_eq!(g.body.len(), 1);
    }
}
