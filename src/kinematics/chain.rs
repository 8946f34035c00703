//! The immutable serial chain and its forward kinematics (paper Eq. 1, 2, 6).

use super::axis::{Axis, Range};
use super::link::Link;
use nalgebra::{IsometryMatrix3, Matrix3, Point3, Rotation3, Vector3};
use rand::RngExt;

/// An actuation axis that moves: a joint of the chain, with the link it belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeAxis {
    /// Link index, from 1 as in the paper.
    pub link: usize,
    /// Which of the six axes.
    pub axis: Axis,
    /// Its range `[min, max]` (non-zero width).
    pub range: Range,
}

impl FreeAxis {
    /// The joint name used in URDF files and trajectories: `j{link}_{axis}` (e.g. `j3_ry`).
    pub fn joint_name(&self) -> String {
        format!("j{}_{}", self.link, self.axis.name())
    }
}

/// One elementary step of the actuation product, prepared at construction.
#[derive(Clone, Copy, Debug)]
enum Op {
    /// Rotation about a local axis by a constant angle (sin, cos precomputed).
    RotConst { axis: Axis, s: f64, c: f64 },
    /// Rotation about a local axis by the free variable `k`.
    RotFree { axis: Axis, k: usize },
    /// Translation along a local axis by a constant.
    TransConst { axis: Axis, v: f64 },
    /// Translation along a local axis by the free variable `k`.
    TransFree { axis: Axis, k: usize },
}

#[derive(Clone, Debug)]
struct ChainLink {
    transform: IsometryMatrix3<f64>,
    /// The fixed rotation is the identity (θ = α = 0): skip the matrix product.
    identity_rotation: bool,
    /// Interior points of the body polyline (its ends are the two frame origins).
    knees: Vec<Point3<f64>>,
    /// The link has at least one body segment.
    has_body: bool,
    ops: std::ops::Range<usize>,
    slider: bool,
    segments: std::ops::Range<usize>,
}

/// A serial chain ready for forward kinematics: base pose, links, and the list of free axes that
/// make up the actuation vector `a`.
///
/// Frame convention: `F_0` is the base; `F_i = F_{i−1} · T_i · T_act,i` (paper Eq. 1), where
/// `T_i` is the link's fixed geometry and `T_act,i = Rx(φ)·Ry(γ)·Rz(ψ)·Trans(x, y, z)` its
/// actuation (Eq. 2). The joint of link `i` sits at the origin of `F_{i−1}·T_i`, at the distal
/// end of the link's body, so it moves every link after it.
///
/// The actuation vector holds only the free axes (non-zero range), ordered by link, then in the
/// order of Eq. 2. Axes with a zero-width range at a non-zero value are constants of the
/// geometry; at zero they are skipped.
///
/// Body: link `i` spans from the origin of `F_{i−1}` to the origin of `F_{i−1}·T_i` along its
/// geometry's polyline (for DH: `d` along z, then `a` along x, so up to two segments). A link with
/// any translation axis adds one more segment, its slider, from the joint origin to the origin of
/// `F_i`, so a prismatic joint never opens a gap in the body. Segments may have zero length (a
/// slider at zero extension); they are kept so every configuration has the same segment count.
#[derive(Clone, Debug)]
pub struct Chain {
    base: IsometryMatrix3<f64>,
    links: Vec<ChainLink>,
    ops: Vec<Op>,
    free: Vec<FreeAxis>,
    home: Vec<f64>,
    radius: f64,
    colliders_per_link: usize,
    segment_count: usize,
}

/// See [`Chain::arc_layout`].
#[derive(Clone, Debug, PartialEq)]
pub struct ArcLayout {
    /// Arc position of each link's joint origin (link `i` at index `i − 1`).
    pub joint: Vec<f64>,
    /// Arc position of the far end of each body segment.
    pub segment_end: Vec<f64>,
    /// Link (from 1) owning each segment.
    pub segment_link: Vec<usize>,
    /// True for slider segments (moved by their own link's axes too).
    pub segment_slider: Vec<bool>,
}

/// Caller-owned output of [`Chain::fk`]; allocate once with [`Chain::frames`] and reuse.
#[derive(Clone, Debug, PartialEq)]
pub struct Frames {
    /// `F_0 … F_n`: the base frame, then each link's frame after its actuation.
    pub frames: Vec<IsometryMatrix3<f64>>,
    /// Origin of each link's joint frame `F_{i−1}·T_i` (where its actuation applies), `n` entries.
    pub joints: Vec<Point3<f64>>,
    /// `f(a)` of paper Eq. 10: the origins of `F_1 … F_n` (the last one is the end effector).
    pub positions: Vec<Point3<f64>>,
    /// Body segments of all links in world coordinates; see [`Chain::link_segments`].
    pub segments: Vec<[Point3<f64>; 2]>,
}

impl Frames {
    /// The end-effector position: the origin of the last frame.
    pub fn end_effector(&self) -> Point3<f64> {
        Point3::from(self.frames[self.frames.len() - 1].translation.vector)
    }

    /// `f(a)` flattened: `3n` coordinates of all joint positions (paper Eq. 10).
    pub fn position_coords(&self) -> impl Iterator<Item = f64> + '_ {
        self.positions.iter().flat_map(|p| p.coords.iter().copied())
    }
}

/// The step length of paper Eq. 10 between configurations `a` and `b` with frames `fa`, `fb`:
/// `‖f(b) − f(a)‖ + λ‖b − a‖`, where `f` stacks all joint positions ([`Frames::positions`],
/// `3n` values).
pub fn step_length(fa: &Frames, fb: &Frames, a: &[f64], b: &[f64], lambda: f64) -> f64 {
    let df: f64 = fa
        .positions
        .iter()
        .zip(&fb.positions)
        .map(|(p, q)| (q - p).norm_squared())
        .sum();
    let da: f64 = a.iter().zip(b).map(|(x, y)| (y - x) * (y - x)).sum();
    df.sqrt() + lambda * da.sqrt()
}

/// Right-multiplies `r` by the elementary rotation about `axis` given `sin` and `cos`; only two
/// columns change.
#[inline(always)]
fn rotate_local(r: &mut Matrix3<f64>, axis: Axis, s: f64, c: f64) {
    let (i, j) = match axis {
        // R·Rx: col1' = c·col1 + s·col2, col2' = −s·col1 + c·col2
        Axis::Rx => (1, 2),
        // R·Ry: col0' = c·col0 − s·col2, col2' = s·col0 + c·col2
        Axis::Ry => (2, 0),
        // R·Rz: col0' = c·col0 + s·col1, col1' = −s·col0 + c·col1
        Axis::Rz => (0, 1),
        _ => unreachable!("translation axis in rotate_local"),
    };
    for row in 0..3 {
        let ci = r[(row, i)];
        let cj = r[(row, j)];
        r[(row, i)] = c * ci + s * cj;
        r[(row, j)] = -s * ci + c * cj;
    }
}

impl Chain {
    /// Builds a chain from a base pose and links. `radius` is the link (capsule) radius and
    /// `colliders_per_link` the number `s_i` of point colliders per link (paper Eq. 6).
    pub fn new(
        base: IsometryMatrix3<f64>,
        links: &[Link],
        radius: f64,
        colliders_per_link: usize,
    ) -> Self {
        let mut ops = Vec::new();
        let mut free = Vec::new();
        let mut home = Vec::new();
        let mut chain_links = Vec::with_capacity(links.len());
        let mut segment_count = 0;
        for (i, link) in links.iter().enumerate() {
            let start = ops.len();
            let mut slider = false;
            for axis in Axis::ALL {
                let range = link.range(axis);
                let op = if range.is_joint() {
                    let k = free.len();
                    free.push(FreeAxis {
                        link: i + 1,
                        axis,
                        range,
                    });
                    home.push(range.home());
                    if axis.is_rotation() {
                        Op::RotFree { axis, k }
                    } else {
                        Op::TransFree { axis, k }
                    }
                } else if range.min == 0.0 {
                    continue;
                } else if axis.is_rotation() {
                    let (s, c) = range.min.sin_cos();
                    Op::RotConst { axis, s, c }
                } else {
                    Op::TransConst { axis, v: range.min }
                };
                slider |= !axis.is_rotation();
                ops.push(op);
            }
            let body = &link.geometry.body;
            let n_seg = body.len().saturating_sub(1) + usize::from(slider);
            chain_links.push(ChainLink {
                transform: link.geometry.transform,
                identity_rotation: link.geometry.transform.rotation == Rotation3::identity(),
                knees: body[1..body.len().saturating_sub(1).max(1)].to_vec(),
                has_body: body.len() > 1,
                ops: start..ops.len(),
                slider,
                segments: segment_count..segment_count + n_seg,
            });
            segment_count += n_seg;
        }
        Chain {
            base,
            links: chain_links,
            ops,
            free,
            home,
            radius,
            colliders_per_link,
            segment_count,
        }
    }

    /// Number of links `n`.
    pub fn link_count(&self) -> usize {
        self.links.len()
    }

    /// Number of free axes: the length of an actuation vector.
    pub fn dof(&self) -> usize {
        self.free.len()
    }

    /// The free axes, in actuation-vector order.
    pub fn free_axes(&self) -> &[FreeAxis] {
        &self.free
    }

    /// Fills `q` (length [`Chain::dof`]) with a configuration drawn uniformly from the free
    /// axes' ranges, one draw per axis in actuation-vector order.
    pub fn sample_config(&self, rng: &mut impl RngExt, q: &mut [f64]) {
        for (q, f) in q.iter_mut().zip(&self.free) {
            *q = rng.random_range(f.range.min..=f.range.max);
        }
    }

    /// Joint names of the free axes (`j{link}_{axis}`), in actuation-vector order.
    pub fn joint_names(&self) -> Vec<String> {
        self.free.iter().map(FreeAxis::joint_name).collect()
    }

    /// The home configuration `a_0`: every free axis at 0, clamped into its range (paper §II-D).
    pub fn home(&self) -> &[f64] {
        &self.home
    }

    /// The base pose `F_0`.
    pub fn base(&self) -> &IsometryMatrix3<f64> {
        &self.base
    }

    /// Link (capsule) radius.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Number `s_i` of point colliders per link (paper Eq. 6).
    pub fn colliders_per_link(&self) -> usize {
        self.colliders_per_link
    }

    /// Total number of body segments in [`Frames::segments`].
    pub fn segment_count(&self) -> usize {
        self.segment_count
    }

    /// Indices into [`Frames::segments`] of link `i`'s body (`i` from 1).
    pub fn link_segments(&self, link: usize) -> std::ops::Range<usize> {
        self.links[link - 1].segments.clone()
    }

    /// Link index (from 1) that owns segment `s`.
    pub fn segment_link(&self, s: usize) -> usize {
        self.links
            .iter()
            .position(|l| l.segments.contains(&s))
            .map_or(0, |i| i + 1)
    }

    /// Arc-length layout of the body, the basis of configuration-independent motion bounds:
    /// walking the chain from the base, every body segment adds its (fixed) length and every
    /// slider its largest possible extension `sqrt(Σ max(|min|, |max|)²)` over the link's
    /// translation axes. Any two points of the body are at most their arc-length difference
    /// apart, in every configuration (triangle inequality along the chain).
    pub fn arc_layout(&self) -> ArcLayout {
        let mut pos = 0.0;
        let mut joint = Vec::with_capacity(self.links.len());
        let mut segment_end = Vec::with_capacity(self.segment_count);
        let mut segment_link = Vec::with_capacity(self.segment_count);
        let mut segment_slider = Vec::with_capacity(self.segment_count);
        for (i, link) in self.links.iter().enumerate() {
            let end = Point3::from(link.transform.translation.vector);
            let mut prev = Point3::origin();
            for p in link
                .knees
                .iter()
                .copied()
                .chain(link.has_body.then_some(end))
            {
                pos += (p - prev).norm();
                prev = p;
                segment_end.push(pos);
                segment_link.push(i + 1);
                segment_slider.push(false);
            }
            joint.push(pos);
            if link.slider {
                let mut ext2 = 0.0;
                for op in &self.ops[link.ops.clone()] {
                    match *op {
                        Op::TransConst { v, .. } => ext2 += v * v,
                        Op::TransFree { k, .. } => {
                            let r = self.free[k].range;
                            ext2 += r.min.abs().max(r.max.abs()).powi(2);
                        }
                        _ => {}
                    }
                }
                pos += ext2.sqrt();
                segment_end.push(pos);
                segment_link.push(i + 1);
                segment_slider.push(true);
            }
        }
        ArcLayout {
            joint,
            segment_end,
            segment_link,
            segment_slider,
        }
    }

    /// A frame buffer sized for this chain, to pass to [`Chain::fk`].
    pub fn frames(&self) -> Frames {
        let n = self.links.len();
        Frames {
            frames: vec![self.base; n + 1],
            joints: vec![Point3::origin(); n],
            positions: vec![Point3::origin(); n],
            segments: vec![[Point3::origin(); 2]; self.segment_count],
        }
    }

    /// True when `a` has the right length and every value lies in its axis range.
    pub fn within_ranges(&self, a: &[f64]) -> bool {
        a.len() == self.free.len() && self.free.iter().zip(a).all(|(f, &v)| f.range.contains(v))
    }

    /// Forward kinematics (paper Eq. 1–2) for the actuation vector `a` (free axes only), written
    /// into `out` (from [`Chain::frames`]) without allocating: every frame, joint origin,
    /// joint position `f(a)` and body segment.
    ///
    /// # Panics
    /// In debug builds, when `a` or `out` do not match the chain's sizes.
    pub fn fk(&self, a: &[f64], out: &mut Frames) {
        debug_assert_eq!(a.len(), self.free.len(), "actuation vector length");
        debug_assert_eq!(out.frames.len(), self.links.len() + 1, "frame buffer size");
        let mut rot: Matrix3<f64> = *self.base.rotation.matrix();
        let mut pos: Vector3<f64> = self.base.translation.vector;
        out.frames[0] = self.base;
        for (i, link) in self.links.iter().enumerate() {
            // Body polyline, in the frame F_{i-1}: it starts at F_{i-1}'s origin and ends at the
            // joint origin, so only its interior points need transforming.
            let mut seg = link.segments.start;
            let mut prev = Point3::from(pos);
            for knee in &link.knees {
                let w = Point3::from(rot * knee.coords + pos);
                out.segments[seg] = [prev, w];
                prev = w;
                seg += 1;
            }
            // Fixed geometry T_i.
            pos += rot * link.transform.translation.vector;
            if !link.identity_rotation {
                rot *= link.transform.rotation.matrix();
            }
            let joint = Point3::from(pos);
            if link.has_body {
                out.segments[seg] = [prev, joint];
                seg += 1;
            }
            out.joints[i] = joint;
            // Actuation T_act,i.
            for op in &self.ops[link.ops.clone()] {
                match *op {
                    Op::RotConst { axis, s, c } => rotate_local(&mut rot, axis, s, c),
                    Op::RotFree { axis, k } => {
                        let (s, c) = libm::sincos(a[k]);
                        rotate_local(&mut rot, axis, s, c);
                    }
                    Op::TransConst { axis, v } => pos += rot.column(axis.index() - 3) * v,
                    Op::TransFree { axis, k } => pos += rot.column(axis.index() - 3) * a[k],
                }
            }
            let origin = Point3::from(pos);
            if link.slider {
                out.segments[seg] = [joint, origin];
            }
            out.positions[i] = origin;
            let f = &mut out.frames[i + 1];
            f.translation.vector = pos;
            // `rot` is a product of rotations, so it stays orthonormal.
            *f.rotation.matrix_mut_unchecked() = rot;
        }
    }

    /// The position Jacobian of the end effector, `∂p_ee/∂a` (3 × dof, column-major: column `k`
    /// at `out[3k..3k+3]`), at the configuration whose frames are in `frames` (from
    /// [`Chain::fk`] with the same `a`). For a rotation axis the column is `ω̂ × (p_ee − o)`
    /// with `ω̂` the axis direction after the link's earlier rotations and `o` the joint origin;
    /// for a translation axis it is the axis direction. Allocation-free.
    pub fn jacobian(&self, a: &[f64], frames: &Frames, out: &mut [f64]) {
        debug_assert_eq!(out.len(), 3 * self.free.len());
        let ee = frames.end_effector().coords;
        let mut rot: Matrix3<f64> = *self.base.rotation.matrix();
        for (i, link) in self.links.iter().enumerate() {
            if !link.identity_rotation {
                rot *= link.transform.rotation.matrix();
            }
            let origin = frames.joints[i].coords;
            for op in &self.ops[link.ops.clone()] {
                match *op {
                    Op::RotConst { axis, s, c } => rotate_local(&mut rot, axis, s, c),
                    Op::RotFree { axis, k } => {
                        let w = rot.column(axis.index()).into_owned();
                        let col = w.cross(&(ee - origin));
                        out[3 * k..3 * k + 3].copy_from_slice(col.as_slice());
                        let (s, c) = libm::sincos(a[k]);
                        rotate_local(&mut rot, axis, s, c);
                    }
                    Op::TransConst { .. } => {}
                    Op::TransFree { axis, k } => {
                        let d = rot.column(axis.index() - 3).into_owned();
                        out[3 * k..3 * k + 3].copy_from_slice(d.as_slice());
                    }
                }
            }
            // The next link starts from F_i, whose rotation is `rot` (translations do not
            // rotate); re-sync with the stored frame to avoid drift.
            rot = *frames.frames[i + 1].rotation.matrix();
        }
    }

    /// The end-effector position for `a` (allocates a frame buffer; for one-off use).
    pub fn end_effector(&self, a: &[f64]) -> Point3<f64> {
        let mut f = self.frames();
        self.fk(a, &mut f);
        f.end_effector()
    }

    /// Point colliders `c_{i,ℓ}` (paper Eq. 6): `s_i` points per link, at arc-length fractions
    /// `ℓ/(s_i+1)`, `ℓ = 1…s_i`, along the link's body polyline (including its slider). The
    /// paper places them along `a_i` on the link's x axis; a polyline generalises that to links
    /// with offsets. A link without body length puts all its colliders at its start point.
    /// Output order: link by link, `ℓ` ascending; `out` is cleared and refilled (its capacity
    /// is reused).
    pub fn colliders(&self, frames: &Frames, out: &mut Vec<Point3<f64>>) {
        out.clear();
        let s = self.colliders_per_link;
        for (i, link) in self.links.iter().enumerate() {
            let segs = &frames.segments[link.segments.clone()];
            let total: f64 = segs.iter().map(|g| (g[1] - g[0]).norm()).sum();
            if total == 0.0 {
                // No body length: the link collapses to its joint origin.
                let p = segs.first().map_or(frames.joints[i], |g| g[0]);
                out.extend(std::iter::repeat_n(p, s));
                continue;
            }
            let mut k = 0; // current segment
            let mut walked = 0.0; // arc length before segment k
            for l in 1..=s {
                let target = total * l as f64 / (s + 1) as f64;
                loop {
                    let len = (segs[k][1] - segs[k][0]).norm();
                    if walked + len >= target || k + 1 == segs.len() {
                        let t = if len > 0.0 {
                            ((target - walked) / len).clamp(0.0, 1.0)
                        } else {
                            0.0
                        };
                        out.push(segs[k][0] + (segs[k][1] - segs[k][0]) * t);
                        break;
                    }
                    walked += len;
                    k += 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::link::Dh;
    use approx::assert_relative_eq;

    fn ranges(list: &[(Axis, f64, f64)]) -> [Range; 6] {
        let mut r = [Range::ZERO; 6];
        for &(a, lo, hi) in list {
            r[a.index()] = Range::new(lo, hi);
        }
        r
    }

    #[test]
    fn constant_axes_are_folded_and_zero_axes_skipped() {
        let link = Link::from_dh(
            &Dh {
                a: 1.0,
                ..Dh::default()
            },
            ranges(&[(Axis::Rz, 0.5, 0.5), (Axis::Ry, -1.0, 1.0)]),
        );
        let chain = Chain::new(IsometryMatrix3::identity(), &[link.clone(), link], 0.1, 3);
        assert_eq!(chain.dof(), 2);
        assert_eq!(chain.joint_names(), vec!["j1_ry", "j2_ry"]);
        let mut f = chain.frames();
        chain.fk(&[0.0, 0.0], &mut f);
        // Second link starts after a constant yaw of 0.5 rad.
        let p = f.end_effector();
        assert_relative_eq!(p.x, 1.0 + 0.5f64.cos(), epsilon = 1e-12);
        assert_relative_eq!(p.y, 0.5f64.sin(), epsilon = 1e-12);
    }

    #[test]
    fn sampled_configurations_fill_each_axis_range() {
        use rand::SeedableRng;
        let links = [
            Link::from_dh(&Dh::default(), ranges(&[(Axis::Rz, -1.0, 2.0)])),
            Link::from_dh(&Dh::default(), ranges(&[(Axis::Tx, 0.5, 0.75)])),
        ];
        let chain = Chain::new(IsometryMatrix3::identity(), &links, 0.1, 3);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut q = [0.0; 2];
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for _ in 0..2000 {
            chain.sample_config(&mut rng, &mut q);
            for k in 0..2 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        // Inside each range, and spread over it (2,000 uniform draws leave gaps < 1 %).
        for (k, (min, max)) in [(-1.0, 2.0), (0.5, 0.75)].into_iter().enumerate() {
            assert!(
                lo[k] >= min && hi[k] <= max,
                "axis {k}: [{}, {}]",
                lo[k],
                hi[k]
            );
            assert!(lo[k] - min < 0.01 * (max - min) && max - hi[k] < 0.01 * (max - min));
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let mut r = [Range::ZERO; 6];
        for (ax, lo, hi) in [
            (Axis::Rx, -1.0, 1.0),
            (Axis::Ry, -2.0, 2.0),
            (Axis::Rz, -1.5, 1.5),
            (Axis::Tx, 0.0, 0.3),
            (Axis::Tz, -0.2, 0.2),
        ] {
            r[ax.index()] = Range::new(lo, hi);
        }
        let l1 = Link::from_dh(
            &Dh {
                theta: 0.3,
                d: 0.2,
                a: 0.4,
                alpha: 0.7,
            },
            r,
        );
        let l2 = Link::from_dh(
            &Dh {
                a: 0.5,
                alpha: -0.4,
                ..Dh::default()
            },
            r,
        );
        let chain = Chain::new(IsometryMatrix3::identity(), &[l1, l2.clone(), l2], 0.1, 1);
        let a: Vec<f64> = (0..chain.dof()).map(|k| 0.1 * k as f64 - 0.3).collect();
        let mut f = chain.frames();
        chain.fk(&a, &mut f);
        let mut jac = vec![0.0; 3 * chain.dof()];
        chain.jacobian(&a, &f, &mut jac);
        let h = 1e-6;
        for k in 0..chain.dof() {
            let (mut ap, mut am) = (a.clone(), a.clone());
            ap[k] += h;
            am[k] -= h;
            let d = (chain.end_effector(&ap) - chain.end_effector(&am)) / (2.0 * h);
            for row in 0..3 {
                assert_relative_eq!(jac[3 * k + row], d[row], epsilon = 1e-7);
            }
        }
    }

    #[test]
    fn colliders_are_evenly_spaced_along_the_body() {
        let link = Link::from_dh(
            &Dh {
                d: 1.0,
                a: 1.0,
                ..Dh::default()
            },
            ranges(&[(Axis::Ry, -1.0, 1.0)]),
        );
        let chain = Chain::new(IsometryMatrix3::identity(), &[link], 0.1, 3);
        let mut f = chain.frames();
        chain.fk(&[0.3], &mut f);
        let mut c = Vec::new();
        chain.colliders(&f, &mut c);
        assert_eq!(c.len(), 3);
        assert_relative_eq!(c[0], Point3::new(0.0, 0.0, 0.5), epsilon = 1e-12);
        assert_relative_eq!(c[1], Point3::new(0.0, 0.0, 1.0), epsilon = 1e-12);
        assert_relative_eq!(c[2], Point3::new(0.5, 0.0, 1.0), epsilon = 1e-12);
    }

    #[test]
    fn slider_segment_covers_the_prismatic_extension() {
        let link = Link::from_dh(
            &Dh {
                a: 1.0,
                ..Dh::default()
            },
            ranges(&[(Axis::Tx, 0.0, 0.5)]),
        );
        let chain = Chain::new(IsometryMatrix3::identity(), &[link], 0.1, 1);
        assert_eq!(chain.segment_count(), 2);
        let mut f = chain.frames();
        chain.fk(&[0.4], &mut f);
        assert_relative_eq!(f.segments[1][0], Point3::new(1.0, 0.0, 0.0));
        assert_relative_eq!(f.segments[1][1], Point3::new(1.4, 0.0, 0.0));
        assert_relative_eq!(f.end_effector(), Point3::new(1.4, 0.0, 0.0));
        assert_eq!(chain.segment_link(1), 1);
    }
}
