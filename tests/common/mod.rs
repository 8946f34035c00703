//! Designs shared by the integration tests.

use kinsynth::design::{AxisRanges, Design, LinkDesign};
use kinsynth::kinematics::{Axis, Placement, Range};
use std::f64::consts::PI;

/// Axis ranges from `(axis, min, max)`; every other axis is fixed at 0.
pub fn ranges(list: &[(Axis, f64, f64)]) -> AxisRanges {
    let mut r = AxisRanges::default();
    for &(a, lo, hi) in list {
        *r.get_mut(a) = Range::new(lo, hi);
    }
    r
}

/// A UR5 from its DH table, as `examples/make_ur5.rs` builds it.
pub fn ur5() -> Design {
    let d = [0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823];
    let a = [0.0, -0.425, -0.39225, 0.0, 0.0, 0.0];
    let alpha = [PI / 2.0, 0.0, 0.0, PI / 2.0, -PI / 2.0, 0.0];
    let joint = ranges(&[(Axis::Rz, -2.0 * PI, 2.0 * PI)]);
    let mut links = vec![LinkDesign {
        axes: joint,
        ..LinkDesign::default()
    }];
    for i in 0..6 {
        links.push(LinkDesign {
            theta: 0.0,
            d: d[i],
            a: a[i],
            alpha: alpha[i],
            axes: if i < 5 { joint } else { AxisRanges::default() },
        });
    }
    Design {
        base: Placement::default(),
        link_radius: 0.05,
        colliders_per_link: 4,
        links,
        tool: None,
    }
}
