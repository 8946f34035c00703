//! Forward kinematics against hand-computed poses and an independent product of 4×4 matrices.

use approx::assert_relative_eq;
use kinsynth::design::{AxisRanges, Design, LinkDesign};
use kinsynth::kinematics::{Axis, Chain, Placement, Range};
use kinsynth::scenario::preset::{generate, Preset};
use kinsynth::Scenario;
use nalgebra::{Matrix4, Point3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, PI};

fn link(theta: f64, d: f64, a: f64, alpha: f64, axes: &[(Axis, f64, f64)]) -> LinkDesign {
    let mut r = AxisRanges::default();
    for &(ax, lo, hi) in axes {
        *r.get_mut(ax) = Range::new(lo, hi);
    }
    LinkDesign {
        theta,
        d,
        a,
        alpha,
        axes: r,
    }
}

fn design(links: Vec<LinkDesign>) -> Design {
    Design {
        base: Placement::default(),
        link_radius: 0.01,
        colliders_per_link: 2,
        links,
        tool: None,
    }
}

fn ee(chain: &Chain, a: &[f64]) -> Point3<f64> {
    chain.end_effector(a)
}

#[test]
fn planar_two_link_arm_matches_hand_computation() {
    // Joint 1 at the base (link 1 has no body), then links of 1.0 and 0.5 about z.
    let d = design(vec![
        link(0.0, 0.0, 0.0, 0.0, &[(Axis::Rz, -PI, PI)]),
        link(0.0, 0.0, 1.0, 0.0, &[(Axis::Rz, -PI, PI)]),
        link(0.0, 0.0, 0.5, 0.0, &[]),
    ]);
    let c = d.chain();
    assert_eq!(c.dof(), 2);
    assert_relative_eq!(
        ee(&c, &[0.0, 0.0]),
        Point3::new(1.5, 0.0, 0.0),
        epsilon = 1e-12
    );
    assert_relative_eq!(
        ee(&c, &[FRAC_PI_2, 0.0]),
        Point3::new(0.0, 1.5, 0.0),
        epsilon = 1e-12
    );
    assert_relative_eq!(
        ee(&c, &[FRAC_PI_2, -FRAC_PI_2]),
        Point3::new(0.5, 1.0, 0.0),
        epsilon = 1e-12
    );
    let (q1, q2) = (0.3_f64, 1.1_f64);
    assert_relative_eq!(
        ee(&c, &[q1, q2]),
        Point3::new(
            q1.cos() + 0.5 * (q1 + q2).cos(),
            q1.sin() + 0.5 * (q1 + q2).sin(),
            0.0
        ),
        epsilon = 1e-12
    );
}

#[test]
fn twist_and_offset_chain_matches_hand_computation() {
    // Link 1: up 0.5 along z, twisted by α = π/2 (its z becomes world −y); joint about that z.
    let d = design(vec![
        link(0.0, 0.5, 0.0, FRAC_PI_2, &[(Axis::Rz, -PI, PI)]),
        link(0.0, 0.0, 0.4, 0.0, &[]),
    ]);
    let c = d.chain();
    assert_relative_eq!(ee(&c, &[0.0]), Point3::new(0.4, 0.0, 0.5), epsilon = 1e-12);
    // Rotating about world −y by +90° turns x into +z.
    assert_relative_eq!(
        ee(&c, &[FRAC_PI_2]),
        Point3::new(0.0, 0.0, 0.9),
        epsilon = 1e-12
    );
    // θ rotates the link's x direction about the previous z before `a` is applied.
    let d = design(vec![link(FRAC_PI_2, 0.2, 0.3, 0.0, &[])]);
    assert_relative_eq!(
        d.chain().end_effector(&[]),
        Point3::new(0.0, 0.3, 0.2),
        epsilon = 1e-12
    );
}

#[test]
fn prismatic_chain_matches_hand_computation() {
    let d = design(vec![
        link(
            0.0,
            0.2,
            0.0,
            0.0,
            &[(Axis::Rz, -PI, PI), (Axis::Tz, 0.0, 1.0)],
        ),
        link(0.0, 0.0, 0.3, 0.0, &[(Axis::Tx, 0.0, 0.5)]),
    ]);
    let c = d.chain();
    assert_eq!(c.joint_names(), vec!["j1_rz", "j1_tz", "j2_tx"]);
    assert_relative_eq!(
        ee(&c, &[0.0, 0.4, 0.0]),
        Point3::new(0.3, 0.0, 0.6),
        epsilon = 1e-12
    );
    assert_relative_eq!(
        ee(&c, &[FRAC_PI_2, 0.4, 0.25]),
        Point3::new(0.0, 0.55, 0.6),
        epsilon = 1e-12
    );
    let mut f = c.frames();
    c.fk(&[FRAC_PI_2, 0.4, 0.25], &mut f);
    // Link 1: body (0,0,0)→(0,0,0.2), rod (0,0,−0.4)→(0,0,0.6) (the 1 m stroke, ending at F_1);
    // link 2: body, rod of the 0.5 m stroke ending at F_2.
    assert_eq!(c.segment_count(), 4);
    assert_relative_eq!(
        f.segments[1][1],
        Point3::new(0.0, 0.0, 0.6),
        epsilon = 1e-12
    );
    assert_relative_eq!(
        f.segments[1][0],
        Point3::new(0.0, 0.0, -0.4),
        epsilon = 1e-12
    );
    assert_relative_eq!(
        f.segments[3][0],
        Point3::new(0.0, 0.05, 0.6),
        epsilon = 1e-12
    );
    assert_relative_eq!(
        f.segments[3][1],
        Point3::new(0.0, 0.55, 0.6),
        epsilon = 1e-12
    );
    assert_relative_eq!(f.joints[1], Point3::new(0.0, 0.3, 0.6), epsilon = 1e-12);
}

// ---- independent reference: a plain product of 4×4 homogeneous matrices ----

fn rot(axis: usize, q: f64) -> Matrix4<f64> {
    let (s, c) = q.sin_cos();
    let mut m = Matrix4::identity();
    let (i, j) = match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    m[(i, i)] = c;
    m[(i, j)] = -s;
    m[(j, i)] = s;
    m[(j, j)] = c;
    m
}

fn trans(x: f64, y: f64, z: f64) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m[(0, 3)] = x;
    m[(1, 3)] = y;
    m[(2, 3)] = z;
    m
}

/// All frames F_0..F_n by the textbook product T_1·T_act,1·…·T_n·T_act,n.
fn reference_frames(d: &Design, a: &[f64]) -> Vec<Matrix4<f64>> {
    let [r, p, y] = d.base.rpy;
    let [bx, by, bz] = d.base.position;
    let mut m = trans(bx, by, bz) * rot(2, y) * rot(1, p) * rot(0, r);
    let mut out = vec![m];
    let mut k = 0;
    for l in &d.links {
        m = m * rot(2, l.theta) * trans(0.0, 0.0, l.d) * trans(l.a, 0.0, 0.0) * rot(0, l.alpha);
        let mut v = [0.0; 6];
        for (j, axis) in Axis::ALL.into_iter().enumerate() {
            let range = l.axes.get(axis);
            v[j] = if range.is_joint() {
                k += 1;
                a[k - 1]
            } else {
                range.min
            };
        }
        m = m * rot(0, v[0]) * rot(1, v[1]) * rot(2, v[2]) * trans(v[3], v[4], v[5]);
        out.push(m);
    }
    assert_eq!(k, a.len());
    out
}

fn compare_at_random_configurations(d: &Design, seed: u64) {
    let chain = d.chain();
    let mut frames = chain.frames();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for _ in 0..1000 {
        let a: Vec<f64> = chain
            .free_axes()
            .iter()
            .map(|f| rng.random_range(f.range.min..=f.range.max))
            .collect();
        chain.fk(&a, &mut frames);
        let reference = reference_frames(d, &a);
        for (ours, theirs) in frames.frames.iter().zip(&reference) {
            assert_relative_eq!(ours.to_homogeneous(), *theirs, epsilon = 1e-12);
        }
        for (i, p) in frames.positions.iter().enumerate() {
            let t = reference[i + 1].column(3);
            assert_relative_eq!(p.coords, t.xyz(), epsilon = 1e-12);
        }
    }
}

/// A link with random DH parameters whose axes are each absent, free over `range(rng)`, or a
/// random constant (folded into the geometry).
fn random_link(
    rng: &mut ChaCha8Rng,
    range: &mut dyn FnMut(&mut ChaCha8Rng) -> (f64, f64),
) -> LinkDesign {
    let mut axes = Vec::new();
    for axis in Axis::ALL {
        match rng.random_range(0..3) {
            0 => {}
            1 => {
                let (lo, hi) = range(rng);
                axes.push((axis, lo, hi));
            }
            _ => {
                let v = rng.random_range(-0.5..0.5);
                axes.push((axis, v, v));
            }
        }
    }
    link(
        rng.random_range(-PI..PI),
        rng.random_range(-0.5..0.5),
        rng.random_range(0.0..0.6),
        rng.random_range(-PI..PI),
        &axes,
    )
}

#[test]
fn fk_matches_independent_matrix_product_on_a_general_chain() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let links = (0..6)
        .map(|_| random_link(&mut rng, &mut |_| (-1.2, 0.9)))
        .collect();
    let mut d = design(links);
    d.base = Placement {
        position: [0.1, -0.2, 0.3],
        rpy: [0.2, -0.4, 1.0],
    };
    compare_at_random_configurations(&d, 1);
}

/// A chain of more rotation axes than forward kinematics takes sines and cosines for at once
/// (14 links with all three rotations free: 42 rotations, so two blocks), over angles up to
/// ±7 rad (every quadrant and its reduction): the frames are the independent product's, and
/// evaluating only the first `l` links gives exactly (bit for bit) the full evaluation's first
/// `l` frames, so each link takes the sines of its own angles whatever the links evaluated.
#[test]
fn fk_of_a_long_chain_matches_the_product_and_its_prefixes() {
    let links = (0..14)
        .map(|i| {
            link(
                0.1 * i as f64,
                0.05,
                0.1,
                0.3,
                &[
                    (Axis::Rx, -7.0, 7.0),
                    (Axis::Ry, -7.0, 7.0),
                    (Axis::Rz, -7.0, 7.0),
                    (Axis::Tx, 0.0, 0.1),
                ],
            )
        })
        .collect();
    let d = design(links);
    compare_at_random_configurations(&d, 4);
    let chain = d.chain();
    assert_eq!(
        chain
            .free_axes()
            .iter()
            .filter(|f| f.axis.is_rotation())
            .count(),
        42
    );
    let (mut full, mut part) = (chain.frames(), chain.frames());
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut a = vec![0.0; chain.dof()];
    for _ in 0..200 {
        chain.sample_config(&mut rng, &mut a);
        chain.fk(&a, &mut full);
        for l in 1..=chain.link_count() {
            chain.fk_links(&a, &mut part, l);
            for (ours, theirs) in part.frames[..=l].iter().zip(&full.frames[..=l]) {
                assert_eq!(ours, theirs, "first {l} links");
            }
        }
    }
}

#[test]
fn fk_matches_independent_matrix_product_on_the_paper_chains() {
    for preset in [Preset::Paper2d, Preset::Paper3d] {
        let s = Scenario::from_spec(&generate(preset, 3)).unwrap();
        let d = s.space.largest();
        compare_at_random_configurations(&d, 2);
        // And on a random design of the space, with some links and joints removed.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let x: Vec<f64> = s
            .space
            .variables()
            .iter()
            .map(|v| {
                if rng.random_range(0..4) == 0 {
                    0.0
                } else {
                    rng.random_range(v.lower..=v.upper)
                }
            })
            .collect();
        compare_at_random_configurations(&s.space.decode(&x), 3);
    }
}

#[test]
fn the_reach_bound_covers_every_configuration_and_is_tight_for_a_stretched_arm() {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    for trial in 0..20 {
        let n = rng.random_range(1..7);
        let links = (0..n)
            .map(|_| {
                random_link(&mut rng, &mut |r| {
                    (r.random_range(-1.5..0.0), r.random_range(0.0..1.0))
                })
            })
            .collect();
        let mut d = design(links);
        d.base = Placement {
            position: [0.3, -0.2, 0.1],
            rpy: [0.5, 0.1, -0.7],
        };
        let chain = d.chain();
        let bound = chain.reach_bound();
        let origin = Point3::from(chain.base().translation.vector);
        let mut a = vec![0.0; chain.dof()];
        let mut frames = chain.frames();
        for _ in 0..2000 {
            chain.sample_config(&mut rng, &mut a);
            // Corners of the box too: prismatic axes at their extremes.
            if rng.random_range(0..2) == 0 {
                for (q, f) in a.iter_mut().zip(chain.free_axes()) {
                    *q = if rng.random_range(0..2) == 0 {
                        f.range.min
                    } else {
                        f.range.max
                    };
                }
            }
            chain.fk(&a, &mut frames);
            let r = (frames.end_effector() - origin).norm();
            assert!(
                r <= bound + 1e-12,
                "trial {trial}: {r} beyond the bound {bound}"
            );
        }
    }
    // A planar arm stretched straight attains it.
    let d = design(vec![
        link(0.0, 0.0, 0.7, 0.0, &[(Axis::Rz, -PI, PI)]),
        link(
            0.0,
            0.0,
            0.4,
            0.0,
            &[(Axis::Rz, -PI, PI), (Axis::Tx, -0.1, 0.25)],
        ),
    ]);
    let chain = d.chain();
    assert!(
        (chain.reach_bound() - 1.35).abs() < 1e-12,
        "{}",
        chain.reach_bound()
    );
    let r = (chain.end_effector(&[0.0, 0.0, 0.25]) - Point3::origin()).norm();
    assert!((r - 1.35).abs() < 1e-12, "{r}");
}
