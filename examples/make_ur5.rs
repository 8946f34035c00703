//! Writes `examples/robots/ur5.urdf`: a UR5-like arm built from its published DH table
//! (Universal Robots' UR5 parameters, standard DH convention).
//!
//! Run with `cargo run --example make_ur5 [OUTPUT]`.
//!
//! Standard DH puts each joint *before* its link's geometry:
//! `F_i = F_{i−1} · Rz(θ_i + q_i) · Tz(d_i) · Tx(a_i) · Rx(α_i)`, so the whole arm is
//! `Rz(q_1)·A_1 · Rz(q_2)·A_2 · … · Rz(q_6)·A_6` with `A_i = Tz(d_i)·Tx(a_i)·Rx(α_i)` (θ_i = 0
//! for the UR5). kinsynth applies a link's actuation *after* its fixed geometry:
//! `F_i = F_{i−1} · T_i · Rz(ψ_i)`. Regrouping the same product as
//! `[I·Rz(q_1)] · [A_1·Rz(q_2)] · … · [A_5·Rz(q_6)] · [A_6]` gives seven kinsynth links: link 1
//! has no geometry and joint 1; link `k` (2…6) has the geometry `A_{k−1}` and joint `k`; link 7
//! has the geometry `A_6` (the flange offset) and no joint. Every joint is an `rz` with range
//! ±2π, as on the real arm.

use kinsynth::design::{AxisRanges, Design, LinkDesign};
use kinsynth::kinematics::{Axis, Placement, Range};
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::PathBuf;

/// UR5 standard DH parameters: d, a, α for joints 1…6.
pub const UR5_D: [f64; 6] = [0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823];
/// Link lengths a (m).
pub const UR5_A: [f64; 6] = [0.0, -0.425, -0.39225, 0.0, 0.0, 0.0];
/// Twists α (rad).
pub const UR5_ALPHA: [f64; 6] = [FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2, 0.0];

fn ur5() -> Design {
    let mut joint = AxisRanges::default();
    *joint.get_mut(Axis::Rz) = Range::new(-2.0 * PI, 2.0 * PI);
    let mut links = vec![LinkDesign {
        axes: joint,
        ..LinkDesign::default()
    }];
    for i in 0..6 {
        links.push(LinkDesign {
            theta: 0.0,
            d: UR5_D[i],
            a: UR5_A[i],
            alpha: UR5_ALPHA[i],
            // Joints 2…6 follow A_1…A_5; the flange (A_6) has none.
            axes: if i < 5 { joint } else { AxisRanges::default() },
        });
    }
    Design {
        base: Placement::default(),
        // About the radius of the UR5's link tubes.
        link_radius: 0.05,
        colliders_per_link: 4,
        links,
        tool: None,
    }
}

fn main() -> Result<(), kinsynth::Error> {
    let out = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("examples/robots/ur5.urdf"));
    let d = ur5();
    kinsynth::export::write_urdf(&d, &out)?;
    println!(
        "wrote {} ({} joints, total length {:.6} m)",
        out.display(),
        d.joints_kept(),
        d.total_length()
    );
    Ok(())
}
