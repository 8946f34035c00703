//! The immutable serial chain and its forward kinematics (paper Eq. 1, 2, 6).

use super::axis::{Axis, Range};
use super::link::Link;
use super::trig::sincos_at;
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
    /// Rotation about a local axis by the free variable `k`, the chain's rotation number `r`
    /// (rotations counted from the base, see `Chain::rotations`).
    RotFree { axis: Axis, k: usize, r: usize },
    /// Translation along a local axis by a constant.
    TransConst { axis: Axis, v: f64 },
    /// Translation along a local axis by the free variable `k`; its rod runs from `lo` to `hi`
    /// along the axis in the frame after it (see [`Chain::slider_rod`]).
    TransFree {
        axis: Axis,
        k: usize,
        lo: f64,
        hi: f64,
    },
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
    segments: std::ops::Range<usize>,
}

/// Where one body segment of a chain sits, as the URDF export names it, and what moves it.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentInfo {
    /// Link (from 1) that owns the segment.
    pub link: usize,
    /// The segment is moved by the first `level` free axes of the actuation vector (and by no
    /// other): free axes are ordered along the chain, so this is always a prefix.
    pub level: usize,
    /// True for a slider rod or a constant translation piece (not part of the DH body).
    pub slider: bool,
    /// Name of the exported URDF link that carries it (see [`crate::kinematics::Chain`]).
    pub frame: String,
    /// End points in that URDF link's frame.
    pub local: [Point3<f64>; 2],
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
    /// The free axes that are rotations, from the base: forward kinematics takes the sines and
    /// cosines of those of the links it evaluates at once, in this order.
    rotations: Vec<usize>,
    /// `rotations_upto[l]`: how many of `rotations` belong to the first `l` links.
    rotations_upto: Vec<usize>,
    free: Vec<FreeAxis>,
    home: Vec<f64>,
    radius: f64,
    colliders_per_link: usize,
    segment_count: usize,
    segment_info: Vec<SegmentInfo>,
    /// For each free axis, the [`SegmentInfo::frame`]-style name of the URDF link right after
    /// it (the joint's child link).
    axis_frames: Vec<String>,
    layout: ArcLayout,
    /// No body segments ([`Chain::without_segments`]): forward kinematics writes none.
    bare: bool,
    /// The tool centre point in the last frame `F_n` ([`Chain::with_tool`]); `None` is the
    /// identity (the TCP is `F_n`).
    tool: Option<IsometryMatrix3<f64>>,
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
    /// Arc position of the origin of the frame right after each free axis (actuation-vector
    /// order): a bound on its distance along the chain from the base.
    pub axis: Vec<f64>,
}

/// Caller-owned output of [`Chain::fk`]; allocate once with [`Chain::frames`] and reuse.
#[derive(Clone, Debug, PartialEq)]
pub struct Frames {
    /// `F_0 … F_n`: the base frame, then each link's frame after its actuation.
    pub frames: Vec<IsometryMatrix3<f64>>,
    /// Origin of each link's joint frame `F_{i−1}·T_i` (where its actuation applies), `n` entries.
    pub joints: Vec<Point3<f64>>,
    /// `f(a)` of paper Eq. 10: the origins of `F_1 … F_n`, then the tool centre point when the
    /// chain has a tool ([`Chain::with_tool`]); see [`Chain::position_count`].
    pub positions: Vec<Point3<f64>>,
    /// Body segments of all links in world coordinates; see [`Chain::link_segments`].
    pub segments: Vec<[Point3<f64>; 2]>,
    /// The frame right after each free axis (actuation-vector order): the pose of that joint's
    /// child link, which carries the bodies attached there.
    pub axis_frames: Vec<IsometryMatrix3<f64>>,
    /// The tool centre point frame `F_n · T_tool` (`F_n` itself without a tool).
    pub tcp: IsometryMatrix3<f64>,
}

impl Frames {
    /// Makes `self` a copy of `other` (both from [`Chain::frames`] of the same chain), without
    /// allocating.
    pub fn copy_from(&mut self, other: &Frames) {
        fn copy<T: Copy>(to: &mut Vec<T>, from: &[T]) {
            if to.len() == from.len() {
                to.copy_from_slice(from);
            } else {
                to.clear();
                to.extend_from_slice(from);
            }
        }
        copy(&mut self.frames, &other.frames);
        copy(&mut self.joints, &other.joints);
        copy(&mut self.positions, &other.positions);
        copy(&mut self.segments, &other.segments);
        copy(&mut self.axis_frames, &other.axis_frames);
        self.tcp = other.tcp;
    }

    /// The end-effector position: the tool centre point (the origin of the last frame when
    /// the chain has no tool).
    pub fn end_effector(&self) -> Point3<f64> {
        Point3::from(self.tcp.translation.vector)
    }

    /// The rotation of the tool centre point frame in the world.
    pub fn tcp_rotation(&self) -> &Matrix3<f64> {
        self.tcp.rotation.matrix()
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
    // Columns `I` and `J` (compile-time indices into the column-major storage, so that the
    // matrix can live in registers): col_I' = c·col_I + s·col_J, col_J' = −s·col_I + c·col_J.
    #[inline(always)]
    fn mix<const I: usize, const J: usize>(m: &mut [[f64; 3]; 3], s: f64, c: f64) {
        let (ci, cj) = (m[I], m[J]);
        m[I] = [
            c * ci[0] + s * cj[0],
            c * ci[1] + s * cj[1],
            c * ci[2] + s * cj[2],
        ];
        m[J] = [
            -s * ci[0] + c * cj[0],
            -s * ci[1] + c * cj[1],
            -s * ci[2] + c * cj[2],
        ];
    }
    let m = &mut r.data.0;
    match axis {
        // R·Rx: col1' = c·col1 + s·col2, col2' = −s·col1 + c·col2
        Axis::Rx => mix::<1, 2>(m, s, c),
        // R·Ry: col0' = c·col0 − s·col2, col2' = s·col0 + c·col2
        Axis::Ry => mix::<2, 0>(m, s, c),
        // R·Rz: col0' = c·col0 + s·col1, col1' = −s·col0 + c·col1
        Axis::Rz => mix::<0, 1>(m, s, c),
        _ => unreachable!("translation axis in rotate_local"),
    }
}

/// Column `k` of `r`, selected among three compile-time indices (a runtime index into the
/// matrix's storage would keep it in memory, where the stores of [`rotate_local`] and the wider
/// loads of a copy of the whole matrix stall).
#[inline(always)]
fn column(r: &Matrix3<f64>, k: usize) -> Vector3<f64> {
    let m = &r.data.0;
    match k {
        0 => Vector3::from(m[0]),
        1 => Vector3::from(m[1]),
        _ => Vector3::from(m[2]),
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
        let mut rotations = Vec::new();
        let mut rotations_upto = vec![0];
        let mut free = Vec::new();
        let mut home = Vec::new();
        let mut chain_links = Vec::with_capacity(links.len());
        let mut info: Vec<SegmentInfo> = Vec::new();
        let mut axis_frames = Vec::new();
        let mut layout = ArcLayout {
            joint: Vec::with_capacity(links.len()),
            segment_end: Vec::new(),
            segment_link: Vec::new(),
            segment_slider: Vec::new(),
            axis: Vec::new(),
        };
        let mut arc = 0.0;
        for (i, link) in links.iter().enumerate() {
            let n = i + 1;
            let start = ops.len();
            let level0 = free.len();
            let present: Vec<(Axis, Range)> = Axis::ALL
                .into_iter()
                .map(|a| (a, link.range(a)))
                .filter(|(_, r)| r.is_joint() || r.min != 0.0)
                .collect();
            let dh_frame = if present.is_empty() {
                format!("link{n}")
            } else {
                format!("link{n}_dh")
            };
            // The body polyline (in F_{i-1}), carried by the joint frame F_{i-1}·T_i.
            let body = &link.geometry.body;
            let inv = link.geometry.transform.inverse();
            let mut prev = Point3::origin();
            for w in body.windows(2) {
                arc += (w[1] - w[0]).norm();
                layout.segment_end.push(arc);
                layout.segment_link.push(n);
                layout.segment_slider.push(false);
                info.push(SegmentInfo {
                    link: n,
                    level: level0,
                    slider: false,
                    frame: dh_frame.clone(),
                    local: [inv * w[0], inv * w[1]],
                });
                prev = w[1];
            }
            let _ = prev;
            let joint_arc = arc;
            layout.joint.push(joint_arc);
            // Actuation: walk the axes as the URDF export does, to name the carrier of every
            // translation piece.
            let last_free = present.iter().rposition(|(_, r)| r.is_joint());
            let mut current = dh_frame.clone();
            let mut pending = IsometryMatrix3::identity();
            let mut t_sum = 0.0; // largest travel of the translations so far in this link
            let mut ext2 = 0.0;
            for (m, &(axis, range)) in present.iter().enumerate() {
                if !range.is_joint() {
                    let v = range.min;
                    if axis.is_rotation() {
                        let (s, c) = v.sin_cos();
                        ops.push(Op::RotConst { axis, s, c });
                        pending *= IsometryMatrix3::from_parts(
                            nalgebra::Translation3::identity(),
                            Rotation3::from_axis_angle(
                                &nalgebra::Unit::new_unchecked(axis.direction()),
                                v,
                            ),
                        );
                    } else {
                        ops.push(Op::TransConst { axis, v });
                        let from = Point3::from(pending.translation.vector);
                        pending *= nalgebra::Translation3::from(axis.direction() * v);
                        let to = Point3::from(pending.translation.vector);
                        t_sum += v.abs();
                        ext2 += v * v;
                        layout.segment_end.push(joint_arc + t_sum);
                        layout.segment_link.push(n);
                        layout.segment_slider.push(true);
                        info.push(SegmentInfo {
                            link: n,
                            level: free.len(),
                            slider: true,
                            frame: current.clone(),
                            local: [from, to],
                        });
                    }
                    continue;
                }
                let k = free.len();
                free.push(FreeAxis {
                    link: n,
                    axis,
                    range,
                });
                home.push(range.home());
                let child = if Some(m) == last_free && m + 1 == present.len() {
                    format!("link{n}")
                } else {
                    format!("link{n}_{}", axis.name())
                };
                if axis.is_rotation() {
                    ops.push(Op::RotFree {
                        axis,
                        k,
                        r: rotations.len(),
                    });
                    rotations.push(k);
                    layout.axis.push(joint_arc + t_sum);
                } else {
                    let (lo, hi) = Self::slider_rod(range);
                    ops.push(Op::TransFree { axis, k, lo, hi });
                    let reach = [
                        range.min + lo,
                        range.min + hi,
                        range.max + lo,
                        range.max + hi,
                    ]
                    .into_iter()
                    .fold(0.0, |m: f64, x| m.max(x.abs()));
                    layout.segment_end.push(joint_arc + t_sum + reach);
                    layout.segment_link.push(n);
                    layout.segment_slider.push(true);
                    let travel = range.min.abs().max(range.max.abs());
                    t_sum += travel;
                    ext2 += travel * travel;
                    layout.axis.push(joint_arc + t_sum);
                    let dir = axis.direction();
                    info.push(SegmentInfo {
                        link: n,
                        level: k + 1,
                        slider: true,
                        frame: child.clone(),
                        local: [Point3::from(dir * lo), Point3::from(dir * hi)],
                    });
                }
                axis_frames.push(child.clone());
                pending = IsometryMatrix3::identity();
                current = child;
            }
            arc = joint_arc + ext2.sqrt();
            let n_seg = info.len()
                - chain_links
                    .iter()
                    .map(|l: &ChainLink| l.segments.len())
                    .sum::<usize>();
            let seg_start = info.len() - n_seg;
            chain_links.push(ChainLink {
                transform: link.geometry.transform,
                identity_rotation: link.geometry.transform.rotation == Rotation3::identity(),
                knees: body[1..body.len().saturating_sub(1).max(1)].to_vec(),
                has_body: body.len() > 1,
                ops: start..ops.len(),
                segments: seg_start..info.len(),
            });
            rotations_upto.push(rotations.len());
        }
        Chain {
            base,
            links: chain_links,
            ops,
            rotations,
            rotations_upto,
            free,
            home,
            radius,
            colliders_per_link,
            segment_count: info.len(),
            segment_info: info,
            axis_frames,
            layout,
            bare: false,
            tool: None,
        }
    }

    /// The same chain with a tool: the tool centre point (TCP) is `tool` in the last frame
    /// `F_n`. Position and orientation errors, the Jacobians and the step metric of paper
    /// Eq. 10 then use the TCP ([`Frames::tcp`], the last entry of [`Frames::positions`]);
    /// [`Chain::reach_bound`] adds the tool's offset. The identity removes the tool, so a chain
    /// with an identity tool is exactly the chain without one.
    pub fn with_tool(mut self, tool: IsometryMatrix3<f64>) -> Self {
        self.tool = (tool != IsometryMatrix3::identity()).then_some(tool);
        self
    }

    /// The tool centre point in the last frame `F_n` (the identity without a tool).
    pub fn tool(&self) -> IsometryMatrix3<f64> {
        self.tool.unwrap_or_else(IsometryMatrix3::identity)
    }

    /// True when the chain has a (non-identity) tool.
    pub fn has_tool(&self) -> bool {
        self.tool.is_some()
    }

    /// Number of points in [`Frames::positions`]: the `n` frame origins, plus the TCP when the
    /// chain has a tool.
    pub fn position_count(&self) -> usize {
        self.links.len() + usize::from(self.tool.is_some())
    }

    /// The same kinematics without body segments, for a robot whose body is made of solids
    /// only (an imported arm's collision meshes). Frames, joint origins, axis frames and the
    /// arc positions of joints and axes ([`ArcLayout::joint`], [`ArcLayout::axis`], computed
    /// from the link geometry, which the motion bounds of solids rely on) are unchanged;
    /// [`Chain::segment_count`] becomes 0, [`Chain::fk`] writes no segment, and the point
    /// colliders, which lie on the segments, go too ([`Chain::colliders_per_link`] is 0).
    pub fn without_segments(mut self) -> Self {
        for l in &mut self.links {
            l.knees.clear();
            l.has_body = false;
            l.segments = 0..0;
        }
        self.segment_count = 0;
        self.segment_info.clear();
        self.colliders_per_link = 0;
        self.layout.segment_end.clear();
        self.layout.segment_link.clear();
        self.layout.segment_slider.clear();
        self.bare = true;
        self
    }

    /// True for a chain from [`Chain::without_segments`].
    pub fn is_bare(&self) -> bool {
        self.bare
    }

    /// The rod of a prismatic axis with range `[min, max]`: a fixed-length body on the joint's
    /// child link, from `lo` to `hi` along the axis in the child's frame, with
    /// `lo = min(−max, 0)` and `hi = max(−min, 0)`. Whatever the joint value `q`, it covers the
    /// stretch from the joint origin (at `−q` in the child's frame) to the child's origin, and it
    /// is exactly what the URDF export writes, so the planner checks the exported body.
    pub fn slider_rod(range: Range) -> (f64, f64) {
        ((-range.max).min(0.0), (-range.min).max(0.0))
    }

    /// Where body segment `s` sits and what moves it.
    pub fn segment_info(&self, s: usize) -> &SegmentInfo {
        &self.segment_info[s]
    }

    /// The URDF link names of the frames right after each free axis (actuation-vector order).
    pub fn axis_frame_names(&self) -> &[String] {
        &self.axis_frames
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

    /// An upper bound on the distance of the end effector (the TCP) from the base origin over
    /// every configuration within the ranges: the sum of the fixed translations (DH `d`, `a`,
    /// constant prismatic offsets and the tool's offset) and of each free prismatic axis's
    /// largest travel. Rotations keep lengths, so `‖p_ee(a) − p_0‖ ≤ reach_bound()` for every
    /// `a` (triangle inequality along the chain); a task farther than this plus the goal
    /// tolerance cannot be reached.
    pub fn reach_bound(&self) -> f64 {
        let mut r = self.tool.map_or(0.0, |t| t.translation.vector.norm());
        for link in &self.links {
            r += link.transform.translation.vector.norm();
            for op in &self.ops[link.ops.clone()] {
                r += match *op {
                    Op::TransConst { v, .. } => v.abs(),
                    Op::TransFree { k, .. } => {
                        let range = self.free[k].range;
                        range.min.abs().max(range.max.abs())
                    }
                    Op::RotConst { .. } | Op::RotFree { .. } => 0.0,
                };
            }
        }
        r
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
        self.segment_info.get(s).map_or(0, |i| i.link)
    }

    /// Arc-length layout of the body, the basis of configuration-independent motion bounds:
    /// walking the chain from the base, every body segment adds its (fixed) length and every
    /// slider its largest possible extension `sqrt(Σ max(|min|, |max|)²)` over the link's
    /// translation axes. Any two points of the body are at most their arc-length difference
    /// apart, in every configuration (triangle inequality along the chain).
    pub fn arc_layout(&self) -> ArcLayout {
        self.layout.clone()
    }

    /// The arc layout without a copy (see [`Chain::arc_layout`]).
    pub fn layout(&self) -> &ArcLayout {
        &self.layout
    }

    /// A frame buffer sized for this chain, to pass to [`Chain::fk`].
    pub fn frames(&self) -> Frames {
        let n = self.links.len();
        Frames {
            frames: vec![self.base; n + 1],
            joints: vec![Point3::origin(); n],
            positions: vec![Point3::origin(); self.position_count()],
            segments: vec![[Point3::origin(); 2]; self.segment_count],
            axis_frames: vec![self.base; self.free.len()],
            tcp: self.base,
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
        self.fk_links(a, out, usize::MAX);
    }

    /// Forward kinematics of the first `links` links only (all of them when `links` is at
    /// least [`Chain::link_count`]): writes the base frame, the frames `F_1 … F_links`, their
    /// joint origins and positions, the body segments of those links and the frames of their
    /// free axes, exactly as [`Chain::fk`] does; everything of the later links (and the TCP,
    /// unless every link is evaluated) is left as it was. A checker that needs only the bodies
    /// near the base saves the rest of the chain.
    ///
    /// # Panics
    /// In debug builds, when `a` or `out` do not match the chain's sizes.
    #[inline(always)]
    pub fn fk_links(&self, a: &[f64], out: &mut Frames, links: usize) {
        debug_assert_eq!(a.len(), self.free.len(), "actuation vector length");
        debug_assert_eq!(out.frames.len(), self.links.len() + 1, "frame buffer size");
        let mut rot: Matrix3<f64> = *self.base.rotation.matrix();
        let mut pos: Vector3<f64> = self.base.translation.vector;
        out.frames[0] = self.base;
        let n = self.links.len();
        // Sines and cosines of the rotation axes of the evaluated links, up to `TRIG` at a
        // time and all before they are needed (`trig[i]` belongs to rotation
        // `TRIG·⌊r/TRIG⌋ + i`), so that their computations overlap.
        const TRIG: usize = 32;
        let mut trig = [(0.0, 1.0); TRIG];
        let rotations = &self.rotations[..self.rotations_upto[links.min(n)]];
        for (i, link) in self.links.iter().enumerate().take(links) {
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
            // Actuation T_act,i; every translation adds its piece of the body.
            for op in &self.ops[link.ops.clone()] {
                match *op {
                    Op::RotConst { axis, s, c } => rotate_local(&mut rot, axis, s, c),
                    Op::RotFree { axis, k, r } => {
                        if r % TRIG == 0 {
                            let block = &rotations[r..rotations.len().min(r + TRIG)];
                            sincos_at(a, block, &mut trig[..block.len()]);
                        }
                        let (s, c) = trig[r % TRIG];
                        rotate_local(&mut rot, axis, s, c);
                        let f = &mut out.axis_frames[k];
                        f.translation.vector = pos;
                        *f.rotation.matrix_mut_unchecked() = rot;
                    }
                    Op::TransConst { axis, v } => {
                        let from = Point3::from(pos);
                        pos += column(&rot, axis.index() - 3) * v;
                        if !self.bare {
                            out.segments[seg] = [from, Point3::from(pos)];
                            seg += 1;
                        }
                    }
                    Op::TransFree { axis, k, lo, hi } => {
                        let dir = column(&rot, axis.index() - 3);
                        pos += dir * a[k];
                        if !self.bare {
                            out.segments[seg] =
                                [Point3::from(pos + dir * lo), Point3::from(pos + dir * hi)];
                            seg += 1;
                        }
                        let f = &mut out.axis_frames[k];
                        f.translation.vector = pos;
                        *f.rotation.matrix_mut_unchecked() = rot;
                    }
                }
            }
            let origin = Point3::from(pos);
            out.positions[i] = origin;
            let f = &mut out.frames[i + 1];
            f.translation.vector = pos;
            // `rot` is a product of rotations, so it stays orthonormal.
            *f.rotation.matrix_mut_unchecked() = rot;
        }
        if links < n {
            return;
        }
        match &self.tool {
            None => out.tcp = out.frames[n],
            Some(t) => {
                out.tcp = out.frames[n] * t;
                out.positions[n] = Point3::from(out.tcp.translation.vector);
            }
        }
    }

    /// The position Jacobian of the end effector (the TCP), `∂p_ee/∂a` (3 × dof, column-major:
    /// column `k` at `out[3k..3k+3]`), at the configuration whose frames are in `frames` (from
    /// [`Chain::fk`]). For a rotation axis the column is `ω̂ × (p_ee − o)` with `ω̂` the axis
    /// direction after the link's earlier rotations and `o` the joint origin; for a translation
    /// axis it is the axis direction. Both directions are read from the frame right after the
    /// axis ([`Frames::axis_frames`]: a rotation leaves its own axis unchanged, a translation
    /// every axis), so no angle is evaluated again. Allocation-free.
    pub fn jacobian(&self, frames: &Frames, out: &mut [f64]) {
        debug_assert_eq!(out.len(), 3 * self.free.len());
        let ee = frames.end_effector().coords;
        for (i, link) in self.links.iter().enumerate() {
            let origin = frames.joints[i].coords;
            for op in &self.ops[link.ops.clone()] {
                match *op {
                    Op::RotFree { axis, k, .. } => {
                        let w = frames.axis_frames[k].rotation.matrix().column(axis.index());
                        let col = w.cross(&(ee - origin));
                        out[3 * k..3 * k + 3].copy_from_slice(col.as_slice());
                    }
                    Op::TransFree { axis, k, .. } => {
                        let d = frames.axis_frames[k]
                            .rotation
                            .matrix()
                            .column(axis.index() - 3);
                        out[3 * k..3 * k + 3].copy_from_slice(d.as_slice());
                    }
                    Op::RotConst { .. } | Op::TransConst { .. } => {}
                }
            }
        }
    }

    /// The angular Jacobian of the tool frame (3 × dof, column-major as [`Chain::jacobian`]):
    /// the world angular velocity per unit of each free axis, `ω̂` for a rotation axis and zero
    /// for a translation axis, at the configuration whose frames are in `frames` (from
    /// [`Chain::fk`]), read from the axis frames as in [`Chain::jacobian`]. Allocation-free.
    pub fn angular_jacobian(&self, frames: &Frames, out: &mut [f64]) {
        debug_assert_eq!(out.len(), 3 * self.free.len());
        for op in &self.ops {
            match *op {
                Op::RotFree { axis, k, .. } => {
                    let w = frames.axis_frames[k].rotation.matrix().column(axis.index());
                    out[3 * k..3 * k + 3].copy_from_slice(w.as_slice());
                }
                Op::TransFree { k, .. } => out[3 * k..3 * k + 3].fill(0.0),
                Op::RotConst { .. } | Op::TransConst { .. } => {}
            }
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
        chain.jacobian(&f, &mut jac);
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
    fn slider_rod_is_fixed_length_and_covers_the_extension() {
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
        // The rod is the stroke (0.5 m) long and ends at F_1's origin: it reaches back past
        // the joint origin (1.0) and never changes length.
        assert_relative_eq!(
            f.segments[1][0],
            Point3::new(0.9, 0.0, 0.0),
            epsilon = 1e-15
        );
        assert_relative_eq!(f.segments[1][1], Point3::new(1.4, 0.0, 0.0));
        assert_relative_eq!(f.end_effector(), Point3::new(1.4, 0.0, 0.0));
        assert_eq!(chain.segment_link(1), 1);
        for q in [0.0, 0.25, 0.5] {
            chain.fk(&[q], &mut f);
            let [a, b] = f.segments[1];
            assert_relative_eq!((b - a).norm(), 0.5, epsilon = 1e-15);
            assert!(a.x <= 1.0 + 1e-15 && b.x >= 1.0 + q - 1e-15);
        }
        let info = chain.segment_info(1);
        assert_eq!(
            (info.level, info.slider, info.frame.as_str()),
            (1, true, "link1")
        );
        assert_eq!(info.local, [Point3::new(-0.5, 0.0, 0.0), Point3::origin()]);
    }
}
