//! `certified`: conservative advancement for the articulated chain (Schwarzer, Saha, Latombe,
//! "Adaptive dynamic collision checking for single and multiple articulated robots in complex
//! environments", IEEE T-RO 21(3), 2005). An edge is declared free only when that is proven.
//!
//! # The argument
//!
//! Along the straight motion `a(t) = a + t·(a' − a)`, a point `p` of body segment `s` moves with
//! velocity `ṗ = Σ_j v_j(p)·Δa_j`, where for a rotation axis `j` through the point `o_j`,
//! `|v_j(p)| = |ω̂_j × (p − o_j)| ≤ |p − o_j|`, and for a translation axis `|v_j(p)| = 1`. Every
//! rotation axis of link `j` passes through that link's joint origin (rotations come before
//! translations in paper Eq. 2), and the distance from it to any point of a later segment is at
//! most their arc-length difference along the chain ([`Chain::arc_layout`]), which holds in every
//! configuration within the ranges. Adding the link radius gives `R_js`, an upper bound on the
//! distance from axis `j` to any point of capsule `s`. Hence over `[t0, t1]` no point of the
//! capsule moves farther than `(t1 − t0)·D_s`, with `D_s = Σ_j R_js·|Δa_j|` (rotations) plus
//! `Σ_j |Δa_j|` (translations), the sum running over the axes that move `s`.
//!
//! The distance from a capsule to an obstacle changes no faster than its points move, so with
//! `c(t)` = distance − `ε`, `c(t) ≥ c(t0) − (t − t0)·D_s` and `c(t) ≥ c(t1) − (t1 − t)·D_s`. If
//! `c(t) ≤ 0` somewhere in the interval, both give `c(t0) + c(t1) ≤ (t1 − t0)·D_s`. So the
//! pair (segment, obstacle) is proven free on `[t0, t1]` when `c(t0) > 0`, `c(t1) > 0` and
//! `c(t0) + c(t1) > (t1 − t0)·D_s`. Pairs not proven free are bisected; a negative clearance at a
//! bisection point is a real collision (the edge is blocked), and an interval still unproven
//! after [`MAX_DEPTH`] halvings (a grazing contact) counts as blocked too. Every answer "free"
//! is therefore a proof, up to the accuracy of the distance queries (closed forms for spheres
//! and capsules, parry's GJK otherwise).

use super::{EdgeChecker, Scratch};
use crate::collision::body::{enclosing_ball, BodyModel};
use crate::collision::scene::CollisionScene;
use crate::kinematics::Chain;
use std::sync::Arc;

/// Bisection depth after which an unproven interval (length `2^-MAX_DEPTH`) counts as blocked.
pub const MAX_DEPTH: u32 = 30;

/// Per-chain motion bounds: for every body segment `s` and free axis `j`, the factor `w_sj`
/// such that segment `s` moves at most `Σ_j w_sj·|Δa_j|` along a straight actuation-space
/// motion (`R_js` for rotations, 1 for translations, 0 for axes that do not move it).
#[derive(Clone, Debug, Default)]
pub struct MotionBounds {
    segments: usize,
    dof: usize,
    w: Vec<f64>,
    slider: Vec<bool>,
}

impl MotionBounds {
    /// The bounds of `chain`, with its link radius included in every `R_js`.
    pub fn new(chain: &Chain) -> Self {
        let layout = chain.arc_layout();
        let dof = chain.dof();
        let segments = chain.segment_count();
        let mut w = vec![0.0; segments * dof];
        for (j, axis) in chain.free_axes().iter().enumerate() {
            let l = axis.link;
            for s in 0..segments {
                let k = layout.segment_link[s];
                let moves = k > l || (k == l && layout.segment_slider[s]);
                if !moves {
                    continue;
                }
                w[s * dof + j] = if axis.axis.is_rotation() {
                    (layout.segment_end[s] - layout.joint[l - 1]).max(0.0) + chain.radius()
                } else {
                    1.0
                };
            }
        }
        MotionBounds {
            segments,
            dof,
            w,
            slider: layout.segment_slider,
        }
    }

    /// True when segment `s` is a slider (a link's prismatic extension).
    pub fn is_slider(&self, s: usize) -> bool {
        self.slider[s]
    }

    /// Bound on how far any point of segment `s`'s capsule moves for the step `delta`
    /// (absolute values are taken).
    pub fn displacement(&self, s: usize, delta: &[f64]) -> f64 {
        let row = &self.w[s * self.dof..(s + 1) * self.dof];
        row.iter().zip(delta).map(|(w, d)| w * d.abs()).sum()
    }

    /// Number of segments covered.
    pub fn segments(&self) -> usize {
        self.segments
    }
}

/// An unproven (segment, obstacle) pair with the clearances at both ends of its interval.
#[derive(Clone, Copy, Debug)]
struct Pair {
    segment: u32,
    obstacle: u32,
    c0: f64,
    c1: f64,
}

#[derive(Clone, Copy, Debug)]
struct Interval {
    t0: f64,
    t1: f64,
    start: usize,
    len: usize,
    depth: u32,
}

/// Reused buffers of the certified checker (inside [`Scratch`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct Work {
    pub(crate) delta: Vec<f64>,
    pub(crate) reach: Vec<f64>,
    pairs: Vec<Pair>,
    mid: Vec<f64>,
    stack: Vec<Interval>,
}

impl Work {
    /// Fills `delta` with `to − from` and `reach` with each segment's displacement bound for
    /// the whole step.
    pub(crate) fn prepare(&mut self, bounds: &MotionBounds, from: &[f64], to: &[f64]) {
        self.delta.clear();
        self.delta.extend(to.iter().zip(from).map(|(b, a)| b - a));
        self.reach.clear();
        let delta = &self.delta;
        self.reach
            .extend((0..bounds.segments()).map(|s| bounds.displacement(s, delta)));
    }
}

/// The certified checker: conservative advancement over the link capsules.
#[derive(Clone, Debug)]
pub struct Certified {
    scene: Arc<CollisionScene>,
}

impl Certified {
    /// A certified checker over `scene`.
    pub fn new(scene: Arc<CollisionScene>) -> Self {
        Certified { scene }
    }
}

impl EdgeChecker for Certified {
    fn name(&self) -> &'static str {
        "certified"
    }

    fn node_free(&self, chain: &Chain, a: &[f64], scratch: &mut Scratch) -> bool {
        super::node_free_with(&self.scene, BodyModel::Capsules, chain, a, scratch)
    }

    fn edge_free(&self, chain: &Chain, from: &[f64], to: &[f64], scratch: &mut Scratch) -> bool {
        scratch.stats.edges += 1;
        let scene = &*self.scene;
        let eps = scene.clearance();
        let r = chain.radius();
        let Scratch {
            fa,
            fb,
            fm,
            q,
            bounds,
            certified: work,
            stats,
            near,
            ..
        } = scratch;
        work.prepare(bounds, from, to);
        work.pairs.clear();
        work.stack.clear();

        stats.fk += 2;
        chain.fk(from, fa);
        chain.fk(to, fb);
        for link in 1..=chain.link_count() {
            let segs = chain.link_segments(link);
            if segs.is_empty() {
                continue;
            }
            // Broad phase: the link's enclosing ball at the start, grown by how far the link
            // can move during the whole edge.
            let link_reach = work.reach[segs.clone()].iter().copied().fold(0.0, f64::max);
            let (c, rad) = enclosing_ball(fa.segments[segs.clone()].iter().flatten());
            scene.near(&c, rad + r, eps + link_reach, near);
            for &k in near.iter() {
                let k = k as usize;
                for s in segs.clone() {
                    let (sa, sb) = (&fa.segments[s], &fb.segments[s]);
                    let reach = work.reach[s];
                    let c0 = scene.distance(k, &sa[0], &sa[1], r) - eps;
                    if c0 <= 0.0 {
                        return false;
                    }
                    if c0 > reach {
                        continue;
                    }
                    let c1 = scene.distance(k, &sb[0], &sb[1], r) - eps;
                    if c1 <= 0.0 {
                        return false;
                    }
                    if c0 + c1 > reach {
                        continue;
                    }
                    work.pairs.push(Pair {
                        segment: s as u32,
                        obstacle: k as u32,
                        c0,
                        c1,
                    });
                }
            }
        }
        if work.pairs.is_empty() {
            return true;
        }
        work.stack.push(Interval {
            t0: 0.0,
            t1: 1.0,
            start: 0,
            len: work.pairs.len(),
            depth: 0,
        });
        while let Some(iv) = work.stack.pop() {
            if iv.depth >= MAX_DEPTH {
                return false; // cannot be proven: count as blocked
            }
            let tm = 0.5 * (iv.t0 + iv.t1);
            for ((qi, a), d) in q.iter_mut().zip(from).zip(&work.delta) {
                *qi = a + tm * d;
            }
            stats.fk += 1;
            chain.fk(q, fm);
            let half = 0.5 * (iv.t1 - iv.t0);
            // Children: left [t0, tm] then right [tm, t1], appended after the parent's pairs.
            work.mid.clear();
            for i in iv.start..iv.start + iv.len {
                let p = work.pairs[i];
                let seg = &fm.segments[p.segment as usize];
                let cm = scene.distance(p.obstacle as usize, &seg[0], &seg[1], r) - eps;
                if cm <= 0.0 {
                    return false;
                }
                work.mid.push(cm);
            }
            let left_start = work.pairs.len();
            for (i, &cm) in (iv.start..iv.start + iv.len).zip(&work.mid) {
                let p = work.pairs[i];
                if p.c0 + cm <= half * work.reach[p.segment as usize] {
                    work.pairs.push(Pair { c1: cm, ..p });
                }
            }
            let right_start = work.pairs.len();
            for (i, &cm) in (iv.start..iv.start + iv.len).zip(&work.mid) {
                let p = work.pairs[i];
                if cm + p.c1 <= half * work.reach[p.segment as usize] {
                    work.pairs.push(Pair { c0: cm, ..p });
                }
            }
            let end = work.pairs.len();
            if end > right_start {
                work.stack.push(Interval {
                    t0: tm,
                    t1: iv.t1,
                    start: right_start,
                    len: end - right_start,
                    depth: iv.depth + 1,
                });
            }
            if right_start > left_start {
                work.stack.push(Interval {
                    t0: iv.t0,
                    t1: tm,
                    start: left_start,
                    len: right_start - left_start,
                    depth: iv.depth + 1,
                });
            }
        }
        true
    }
}
