//! `certified`: conservative advancement for the articulated chain (Schwarzer, Saha, Latombe,
//! "Adaptive dynamic collision checking for single and multiple articulated robots in complex
//! environments", IEEE T-RO 21(3), 2005). An edge is declared free only when that is proven.
//!
//! # The argument
//!
//! Along the straight motion `a(t) = a + t·(a' − a)`, a point `p` of a robot body moves with
//! velocity `ṗ = Σ_j v_j(p)·Δa_j`, where for a rotation axis `j` through the point `o_j`,
//! `|v_j(p)| = |ω̂_j × (p − o_j)| ≤ |p − o_j|`, and for a translation axis `|v_j(p)| = 1`. Every
//! rotation axis of link `j` passes through that link's joint origin (rotations come before
//! translations in paper Eq. 2), and the distance from it to any point of a later body is at
//! most their arc-length difference along the chain plus the body's extent
//! ([`crate::collision::body::MotionBounds`]), in every configuration within the ranges. Hence
//! over `[t0, t1]` no point of body `b` moves farther than `(t1 − t0)·D_b`, with
//! `D_b = Σ_j w_bj·|Δa_j|` over the axes that move `b`. Two bodies move relative to each other
//! only through the joints between them, so a self pair `(p, q)` uses the relative bound
//! `D_pq = Σ_{level(p) ≤ j < level(q)} w_qj·|Δa_j|`.
//!
//! The bound is tightened from the configuration itself: a rotation axis `j` moves a point at
//! speed `|ω̂_j × (p − o_j)|·|Δa_j|`, the point's distance from the axis *line*. At an evaluated
//! configuration that distance `ρ_bj` is known (largest at a capsule's end points), and it
//! changes no faster than the axes after `j` move the body, so over an interval of length `s`
//! with that configuration at one end the factor `w_bj` may be replaced by
//! `min(w_bj, ρ_bj + s·Σ_{k > j} w_bk·|Δa_k|)`. Deep in the bisection, where `s` is small, this
//! is close to the true lever arm.
//!
//! A body's clearance from the environment, `c(t)` = (distance to the nearest obstacle) − `ε`,
//! and the distance between the two bodies of a self pair, change no faster than the bodies'
//! (relative) motion `D`, so `c(t) ≥ c(t0) − (t − t0)·D` and `c(t) ≥ c(t1) − (t1 − t)·D`. If
//! `c(t) ≤ 0` somewhere in the interval, both give `c(t0) + c(t1) ≤ (t1 − t0)·D`. So the item is
//! proven free on `[t0, t1]` when `c(t0) > 0`, `c(t1) > 0` and `c(t0) + c(t1) > (t1 − t0)·D`.
//! Items not proven free are bisected; a clearance `≤ 0` at a bisection point is a real
//! collision (the edge is blocked), and an interval still unproven after [`MAX_DEPTH`] halvings
//! (a grazing contact) counts as blocked too. Every answer "free" is therefore a proof, up to
//! the accuracy of the distance queries (closed forms for spheres and capsules, parry's GJK
//! otherwise).
//!
//! The clearance from the environment is one best-first query of the scene's bounding-volume
//! hierarchy ([`CollisionScene::nearest`]), capped at the value that would prove the interval
//! (anything farther is as good), and started from the obstacle found nearest at the previous
//! configuration: its cost follows the obstacles near the body, not their number.

use super::{EdgeChecker, Scratch};
use crate::collision::body::{BodyModel, MotionBounds, Placed, RobotBody};
use crate::collision::scene::CollisionScene;
use crate::kinematics::{Chain, Frames};
use nalgebra::Point3;
use std::sync::Arc;

/// Bisection depth after which an unproven interval (length `2^-MAX_DEPTH`) counts as blocked.
pub const MAX_DEPTH: u32 = 30;

/// `Item::other` of a body's clearance from the whole environment.
const ENV: u32 = u32::MAX;

/// An unproven item with the clearances at both ends of its interval: a body against the whole
/// environment (`other == ENV`; the clearance is the distance to the nearest obstacle minus
/// `ε`), or a self pair of two bodies (`other` is then the second body).
#[derive(Clone, Copy, Debug)]
struct Item {
    body: u32,
    other: u32,
    /// For a body against the environment: the obstacle found nearest last (`u32::MAX` if
    /// none), tried first at the next configuration.
    hint: u32,
    reach: f64,
    c0: f64,
    c1: f64,
}

/// What the bisection point of an interval gives an item: its clearance there, the children's
/// motion bound and the nearest obstacle found.
#[derive(Clone, Copy, Debug)]
struct Mid {
    c: f64,
    reach: f64,
    hint: u32,
}

/// Appends, for each item of `parent` still unproven on one child of the interval (the left
/// `[t0, tm]` when `left`, else the right `[tm, t1]`, each of length `half`), that item on the
/// child, with the clearances at its two ends.
fn push_children(
    items: &mut Vec<Item>,
    parent: std::ops::Range<usize>,
    mid: &[Mid],
    half: f64,
    left: bool,
) {
    for (i, m) in parent.zip(mid) {
        let it = items[i];
        let (c0, c1) = if left { (it.c0, m.c) } else { (m.c, it.c1) };
        if c0 + c1 <= half * m.reach {
            items.push(Item {
                c0,
                c1,
                reach: m.reach,
                hint: m.hint,
                ..it
            });
        }
    }
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
    /// Per body, the `dof + 1` suffix sums of its motion bound ([`MotionBounds::suffix_sums`]).
    suffix: Vec<f64>,
    balls_a: Vec<(Point3<f64>, f64)>,
    balls_b: Vec<(Point3<f64>, f64)>,
    items: Vec<Item>,
    /// Lever arms `ρ_qj` per body and axis at the configuration numbered `lever_pose[q]`.
    lever: Vec<f64>,
    lever_pose: Vec<u32>,
    mid: Vec<Mid>,
    stack: Vec<Interval>,
}

impl Work {
    /// Fills `delta` with `to − from` and `reach` with each body's displacement bound for the
    /// whole step.
    pub(crate) fn prepare(&mut self, bounds: &MotionBounds, from: &[f64], to: &[f64]) {
        self.delta.clear();
        self.delta.extend(to.iter().zip(from).map(|(b, a)| b - a));
        self.reach.clear();
        self.suffix.clear();
        let stride = bounds.dof() + 1;
        for b in 0..bounds.bodies() {
            bounds.suffix_sums(b, &self.delta, &mut self.suffix);
            self.reach.push(self.suffix[b * stride]);
        }
        self.lever.resize(bounds.bodies() * bounds.dof(), 0.0);
        self.lever_pose.clear();
        self.lever_pose.resize(bounds.bodies(), u32::MAX);
    }

    /// Bound on how far body `q` moves relative to bodies moved by the first `level` axes.
    #[inline]
    fn relative(&self, dof: usize, q: usize, level: usize) -> f64 {
        self.suffix[q * (dof + 1) + level.min(dof)]
    }
}

impl Work {
    /// A tighter bound, over an interval of length `span` that has the configuration of
    /// `frames`/`placed` at one end, on how far body `q` moves relative to bodies moved by the
    /// first `from` axes. A rotation axis `j` moves a point `p` at speed `|ω̂_j × (p − o_j)|·|Δa_j|`,
    /// the point's distance from the axis line times the rate. That distance is known at the
    /// end of the interval (largest at a capsule's end points, plus its radius; a solid's
    /// bounding sphere), and changes no faster than the body moves relative to the axis line,
    /// that is by the axes after `j` (their suffix sum): so over the interval it stays below
    /// `ρ_j + span·Σ_{k > j} w_qk·|Δa_k|`, and below `w_qj` in any case.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn local_reach(
        &mut self,
        bounds: &MotionBounds,
        body: &RobotBody,
        frames: &Frames,
        placed: &Placed,
        pose: u32,
        q: usize,
        from: usize,
        span: f64,
    ) -> f64 {
        let dof = bounds.dof();
        let level = body.level(q).min(dof);
        if self.lever_pose[q] != pose {
            // The lever arms of body q about every axis moving it, at this configuration.
            self.lever_pose[q] = pose;
            let ns = body.segments();
            let (p0, p1, extent) = if q < ns {
                let [a, b] = frames.segments[q];
                (a, b, body.radius(q))
            } else {
                let c = placed.centers[q - ns];
                (c, c, body.solids()[q - ns].radius)
            };
            let levers = &mut self.lever[q * dof..q * dof + level];
            for (j, rho) in levers.iter_mut().enumerate() {
                *rho = match bounds.rotation_column(j) {
                    Some(col) => {
                        let f = &frames.axis_frames[j];
                        let o = Point3::from(f.translation.vector);
                        let axis = f.rotation.matrix().column(col);
                        let r0 = axis.cross(&(p0 - o)).norm_squared();
                        let r1 = axis.cross(&(p1 - o)).norm_squared();
                        r0.max(r1).sqrt() + extent
                    }
                    None => f64::INFINITY,
                };
            }
        }
        let w = bounds.factors(q);
        let suffix = &self.suffix[q * (dof + 1)..(q + 1) * (dof + 1)];
        let levers = &self.lever[q * dof..q * dof + level];
        let mut total = 0.0;
        for j in from..level {
            total += self.delta[j].abs() * w[j].min(levers[j] + span * suffix[j + 1]);
        }
        total
    }
}

/// Margin added to the distance a capped clearance query must exceed, so that a capped answer
/// proves the strict inequality it is asked for.
const CAP_MARGIN: f64 = 1e-12;

/// The certified checker: conservative advancement over every robot body, against the
/// obstacles and over the checked self pairs.
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
        let Scratch {
            fa,
            fb,
            fm,
            q,
            bounds,
            certified: work,
            stats,
            body,
            pa,
            pb,
            pm,
            ..
        } = scratch;
        let body = &**body;
        let dof = bounds.dof();
        work.prepare(bounds, from, to);
        work.items.clear();
        work.stack.clear();

        stats.fk += 2;
        chain.fk(from, fa);
        chain.fk(to, fb);
        body.place(fa, pa);
        body.place(fb, pb);
        body.balls(fa, pa, &mut work.balls_a);
        body.balls(fb, pb, &mut work.balls_b);
        // Each body against the environment: c(t) = clearance − ε moves no faster than the
        // body. c0 > D proves the whole step; otherwise c1 > D − c0 does.
        for b in 0..body.len() {
            let plain = work.reach[b];
            let (c0, hint) = body.clearance(
                scene,
                fa,
                pa,
                b,
                &work.balls_a[b],
                plain + CAP_MARGIN,
                u32::MAX,
            );
            if c0 <= 0.0 {
                return false;
            }
            if c0 > plain {
                continue;
            }
            let reach = plain.min(work.local_reach(bounds, body, fa, pa, 0, b, 0, 1.0));
            if c0 > reach {
                continue;
            }
            let need = (reach - c0).max(0.0) + CAP_MARGIN;
            let (c1, hint) = body.clearance(scene, fb, pb, b, &work.balls_b[b], need, hint);
            if c1 <= 0.0 {
                return false;
            }
            if c0 + c1 > reach {
                continue;
            }
            work.items.push(Item {
                body: b as u32,
                other: ENV,
                hint,
                reach,
                c0,
                c1,
            });
        }
        for &(p, qb) in body.self_pairs() {
            let (p, qb) = (p as usize, qb as usize);
            let plain = work.relative(dof, qb, body.level(p));
            let (cp, rp) = work.balls_a[p];
            let (cq, rq) = work.balls_a[qb];
            if (cp - cq).norm() - rp - rq > plain {
                continue;
            }
            let c0 = body.pair_distance(fa, pa, p, qb);
            if c0 <= 0.0 {
                return false;
            }
            if c0 > plain {
                continue;
            }
            let reach =
                plain.min(work.local_reach(bounds, body, fa, pa, 0, qb, body.level(p), 1.0));
            if c0 > reach {
                continue;
            }
            let c1 = body.pair_distance(fb, pb, p, qb);
            if c1 <= 0.0 {
                return false;
            }
            if c0 + c1 > reach {
                continue;
            }
            work.items.push(Item {
                body: p as u32,
                other: qb as u32,
                hint: u32::MAX,
                reach,
                c0,
                c1,
            });
        }
        if work.items.is_empty() {
            return true;
        }
        let mut pose = 0u32;
        work.stack.push(Interval {
            t0: 0.0,
            t1: 1.0,
            start: 0,
            len: work.items.len(),
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
            pose += 1;
            chain.fk(q, fm);
            body.place(fm, pm);
            let half = 0.5 * (iv.t1 - iv.t0);
            // Children: left [t0, tm] then right [tm, t1], appended after the parent's items.
            // Per item: the clearance at tm and the children's motion bound, tightened with
            // the lever arms at tm.
            work.mid.clear();
            for i in iv.start..iv.start + iv.len {
                let it = work.items[i];
                let b = it.body as usize;
                let (q, from) = if it.other == ENV {
                    (b, 0)
                } else {
                    (it.other as usize, body.level(b))
                };
                if it.other != ENV {
                    // A self pair: its distance first; the lever arms at tm only when the
                    // children are not proven without them (the decision is the same).
                    let cm = body.pair_distance(fm, pm, b, it.other as usize);
                    if cm <= 0.0 {
                        return false;
                    }
                    let proven = |r: f64| it.c0.min(it.c1) + cm > half * r;
                    let reach = if proven(it.reach) {
                        it.reach
                    } else {
                        it.reach
                            .min(work.local_reach(bounds, body, fm, pm, pose, q, from, half))
                    };
                    work.mid.push(Mid {
                        c: cm,
                        reach,
                        hint: u32::MAX,
                    });
                    continue;
                }
                // Against the environment: both children are proven once cm exceeds `need`
                // for the parent's bound; below it the clearance is exact, and the lever arms
                // at tm tighten the bound (the decision is the same as with the tight cap).
                let need = (half * it.reach - it.c0.min(it.c1)).max(0.0) + CAP_MARGIN;
                let ball = body.ball(fm, pm, b);
                let (cm, hint) = body.clearance(scene, fm, pm, b, &ball, need, it.hint);
                if cm <= 0.0 {
                    return false;
                }
                let reach = if it.c0.min(it.c1) + cm > half * it.reach {
                    it.reach
                } else {
                    it.reach
                        .min(work.local_reach(bounds, body, fm, pm, pose, q, from, half))
                };
                work.mid.push(Mid { c: cm, reach, hint });
            }
            let parent = iv.start..iv.start + iv.len;
            let left_start = work.items.len();
            push_children(&mut work.items, parent.clone(), &work.mid, half, true);
            let right_start = work.items.len();
            push_children(&mut work.items, parent, &work.mid, half, false);
            let end = work.items.len();
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scenario;
    use rand::{RngExt, SeedableRng};

    /// The tightened bound holds: over an interval of length `s` that starts at an evaluated
    /// configuration, no end point of any body moves farther than `s · local_reach`.
    #[test]
    fn lever_arm_bound_covers_the_real_motion() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios/paper-3d.toml");
        let s = Scenario::load(&path).unwrap();
        let chain = s.space.largest().chain();
        let body = RobotBody::of_chain(&chain);
        let bounds = MotionBounds::new(&chain, &body);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (mut fa, mut ft) = (chain.frames(), chain.frames());
        let (mut pa, mut pt) = (Placed::default(), Placed::default());
        let dof = chain.dof();
        let (mut a, mut b, mut q) = (vec![0.0; dof], vec![0.0; dof], vec![0.0; dof]);
        let mut work = Work::default();
        let mut tightened = 0;
        for pose in 0..300u32 {
            chain.sample_config(&mut rng, &mut a);
            if pose % 2 == 0 {
                for (bj, aj) in b.iter_mut().zip(&a) {
                    *bj = aj + rng.random_range(-0.8..0.8);
                }
            } else {
                // Two axes with large steps: a distal axis swings the body away from (or
                // towards) a proximal axis line, the case the growth term covers.
                b.copy_from_slice(&a);
                for _ in 0..2 {
                    let j = rng.random_range(0..dof);
                    b[j] += rng.random_range(-2.5..2.5);
                }
            }
            work.prepare(&bounds, &a, &b);
            let span: f64 = rng.random_range(0.01..1.0);
            chain.fk(&a, &mut fa);
            body.place(&fa, &mut pa);
            for qb in 0..body.segments() {
                let from = rng.random_range(0..=body.level(qb));
                let plain = work.relative(dof, qb, from);
                let bound = work.local_reach(&bounds, &body, &fa, &pa, pose, qb, from, span);
                assert!(bound <= plain + 1e-12);
                if bound < 0.9 * plain {
                    tightened += 1;
                }
                // Relative motion: move only the axes from `from` on; the bound covers the
                // length of the path each end point travels.
                let mut prev = fa.segments[qb];
                let mut travelled = [0.0; 2];
                for k in 1..=200 {
                    let t = span * k as f64 / 200.0;
                    for j in 0..dof {
                        q[j] = if j < from {
                            a[j]
                        } else {
                            a[j] + t * (b[j] - a[j])
                        };
                    }
                    chain.fk(&q, &mut ft);
                    body.place(&ft, &mut pt);
                    for e in 0..2 {
                        travelled[e] += (ft.segments[qb][e] - prev[e]).norm();
                        assert!(
                            travelled[e] <= t * bound + 1e-9,
                            "body {qb} travelled {} > {t} × {bound}",
                            travelled[e]
                        );
                    }
                    prev = ft.segments[qb];
                }
            }
        }
        assert!(
            tightened > 100,
            "the lever arms tightened only {tightened} bounds"
        );
    }
}
