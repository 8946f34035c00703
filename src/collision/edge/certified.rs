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
//! The bound is tightened from the configurations themselves. At an evaluated configuration
//! the velocity field of every link is known exactly: the prefix sums of the axes' twists
//! `Δa_j·(ω̂_j, o_j × ω̂_j)` (or `Δa_j·(0, ŝ_j)` for a translation) give the twist of the link
//! moved by the first `k` axes, and the difference of two prefixes the motion of one link in
//! the frame of another. A body's speed `u` (largest at a capsule core's end points, since
//! velocity is affine along a segment; a solid's bounding-sphere centre plus `|ω|·r`) is then
//! exact at the ends of an interval. Between them it changes no faster than
//! `A = Σ_j |Δa_j|·((Ω_j − Ω_l)·w_bj + [j rotates]·S_j)` (relative to level `l`), where `Ω_j`
//! sums the rotation rates of the axes before `j` and `S_j = Σ_{k ≥ j} w_bk·|Δa_k|`: the
//! derivative of `Δa_j·ω̂_j × (p − o_j)` is `ω_{<j} × (Δa_j·ω̂_j × (p − o_j))` (the axes before
//! `j` turn axis and lever arm together) plus `Δa_j·ω̂_j × v_{≥j}(p)` (the body moving relative
//! to the axis). So over an interval of length `s` with end speeds `u0`, `u1` no point moves
//! farther than the integral of `min(D, u0 + A·τ, u1 + A·(s − τ))`, which bisection shrinks
//! towards the true path length (the acceleration term falls with `s²`).
//!
//! A body's clearance from the environment, `c(t)` = (distance to the nearest obstacle) − `ε`,
//! and the distance between the two bodies of a self pair, change no faster than the bodies'
//! (relative) motion `D`, so `c(t) ≥ c(t0) − (t − t0)·D` and `c(t) ≥ c(t1) − (t1 − t)·D`. If
//! `c(t) ≤ 0` somewhere in the interval, both give `c(t0) + c(t1) ≤ (t1 − t0)·D`. So the item is
//! proven free on `[t0, t1]` when `c(t0) > 0`, `c(t1) > 0` and `c(t0) + c(t1) > (t1 − t0)·D`.
//! Items not proven free are bisected; a clearance `≤ 0` at a bisection point is a real
//! collision (the edge is blocked), and an interval still unproven after [`MAX_DEPTH`] halvings
//! (a grazing contact), or an edge still unproven after [`MAX_MIDPOINTS`] bisection points (a
//! body moving along an obstacle at a tiny distance), counts as blocked too. Every answer "free" is therefore a proof, up to
//! the accuracy of the distance queries (closed forms for spheres and capsules, parry's GJK
//! otherwise).
//!
//! The clearance from the environment is one best-first query of the scene's bounding-volume
//! hierarchy ([`CollisionScene::nearest`]), capped at the value that would prove the interval
//! (anything farther is as good), and started from the obstacle found nearest at the previous
//! configuration: its cost follows the obstacles near the body, not their number. In a scene of
//! a few spheres a capsule is measured against all of them at once instead, on vector lanes
//! ([`CollisionScene::sphere_nearest`]), skipping only blocks of spheres beyond the cap. The
//! distances of self pairs of two capsules are measured four pairs at a time, in fixed blocks
//! ([`RobotBody::measure_block`]) kept with the configuration once a step needs one of them;
//! at a bisection point, the interval's unproven pairs are measured four at a time as well.
//!
//! Three things keep the work to what the proof needs. A body's clearance is queried at the
//! step's end first (in a planner, the new configuration, where a collision is likeliest) and
//! at its start only if the end alone does not prove the step. The scratch keeps the last
//! [`KEPT`] configurations it evaluated with their frames, placement and clearances, and a
//! step that starts (or ends) at one of them (a planner extends the nodes it has just added)
//! takes them from there: an exact clearance is that end's `c`, a lower bound (a capped
//! query's cap, or `c0 − D` at the end of a body proven from its start) proves the body when
//! it exceeds `D`, and nothing is taken across scenes ([`CollisionScene::id`]). And a
//! bisection point evaluates the kinematics only of the links that carry its interval's
//! unproven items ([`Chain::fk_links`]).

use super::{EdgeChecker, Scratch};
use crate::collision::body::{BodyModel, MotionBounds, Placed, RobotBody};
use crate::collision::scene::CollisionScene;
use crate::kinematics::{Chain, Frames};
use nalgebra::{Point3, Vector3};
use std::sync::Arc;

/// Bisection depth after which an unproven interval (length `2^-MAX_DEPTH`) counts as blocked.
pub const MAX_DEPTH: u32 = 30;

/// Bisection points after which an edge still unproven counts as blocked: a body that moves
/// along an obstacle at a tiny constant distance needs about its path length over that
/// distance of them (0.6 m at a gap of 1e-7 m: six million), each an evaluation of the
/// kinematics. Planner edges need a few (about 5 at π/4 on paper-3d); a run's evaluations
/// are capped too ([`crate::limits::MAX_CHECK_FK`]).
pub const MAX_MIDPOINTS: u32 = 1_000_000;

/// `Item::other` of a body's clearance from the whole environment.
const ENV: u32 = u32::MAX;

/// An unproven item with the clearances and speeds at both ends of its interval: a body
/// against the whole environment (`other == ENV`; the clearance is the distance to the nearest
/// obstacle minus `ε`), or a self pair of two bodies (`other` is then the second body).
#[derive(Clone, Copy, Debug)]
struct Item {
    body: u32,
    other: u32,
    /// For a body against the environment: the obstacle found nearest last (`u32::MAX` if
    /// none), tried first at the next configuration.
    hint: u32,
    /// Bound on the (relative) speed of the item's moving body over the whole edge.
    reach: f64,
    /// Bound on the rate of change of that speed over the whole edge (`> 0`), and its inverse.
    accel: f64,
    inv_accel: f64,
    c0: f64,
    c1: f64,
    /// The (relative) speed of the moving body at the interval's two ends.
    u0: f64,
    u1: f64,
}

/// What the bisection point of an interval gives an item: its clearance and speed there, the
/// children's motion bounds and the nearest obstacle found.
#[derive(Clone, Copy, Debug)]
struct Mid {
    c: f64,
    u: f64,
    left: f64,
    right: f64,
    hint: u32,
}

/// Bound on how far a body moves over an interval of length `s` whose end speeds are `u0` and
/// `u1`, when its speed never exceeds `reach` and changes no faster than `accel` (`> 0`, with
/// `inv_accel = 1/accel`, which an item keeps so that no step divides): the integral of
/// `min(reach, u0 + accel·τ, u1 + accel·(s − τ))`, bounded above by the integral without
/// `reach` and by `s·reach`. The two ramps meet inside the interval when `|u1 − u0| < accel·s`,
/// and then enclose `s·(u0 + u1)/2 + accel·s²/4 − (u1 − u0)²/(4·accel)`; otherwise the lower
/// ramp alone counts, `s·min(u0, u1) + accel·s²/2`.
#[inline]
fn motion(s: f64, reach: f64, u0: f64, u1: f64, accel: f64, inv_accel: f64) -> f64 {
    let d = u1 - u0;
    let ramps = if d.abs() < accel * s {
        0.5 * s * (u0 + u1) + 0.25 * accel * s * s - 0.25 * d * d * inv_accel
    } else {
        s * u0.min(u1) + 0.5 * accel * s * s
    };
    (s * reach).min(ramps * (1.0 + 1e-12))
}

/// Appends, for each item of `parent` still unproven on one child of the interval (the left
/// `[t0, tm]` when `left`, else the right `[tm, t1]`), that item on the child, with the
/// clearances and speeds at its two ends.
fn push_children(items: &mut Vec<Item>, parent: std::ops::Range<usize>, mid: &[Mid], left: bool) {
    for (i, m) in parent.zip(mid) {
        let it = items[i];
        let child = if left {
            Item {
                c1: m.c,
                u1: m.u,
                ..it
            }
        } else {
            Item {
                c0: m.c,
                u0: m.u,
                ..it
            }
        };
        let bound = if left { m.left } else { m.right };
        if child.c0 + child.c1 <= bound {
            items.push(Item {
                hint: m.hint,
                ..child
            });
        }
    }
}

/// Writes to `out`, per item of `items`, the distance of its self pair at the configuration of
/// `frames` (NaN for an item against the environment): pairs of capsules four at a time on
/// vector lanes ([`RobotBody::capsule_pair_distances`], the same values as one by one).
fn pair_distances(
    body: &RobotBody,
    frames: &Frames,
    placed: &Placed,
    items: &[Item],
    out: &mut Vec<f64>,
) {
    out.clear();
    out.resize(items.len(), f64::NAN);
    let mut batch = [(0u32, 0u32); 4];
    let mut at = [0usize; 4];
    let mut n = 0;
    let flush = |batch: &mut [(u32, u32); 4], at: &[usize; 4], n: usize, out: &mut [f64]| {
        if n > 1 {
            for k in n..4 {
                batch[k] = batch[0];
            }
            if let Some(d) = body.capsule_pair_distances(frames, *batch) {
                for (&i, d) in at[..n].iter().zip(d) {
                    out[i] = d;
                }
                return;
            }
        }
        for (&i, &(p, q)) in at[..n].iter().zip(batch.iter()) {
            out[i] = body.pair_distance(frames, placed, p as usize, q as usize);
        }
    };
    for (i, it) in items.iter().enumerate() {
        if it.other == ENV {
            continue;
        }
        batch[n] = (it.body, it.other);
        at[n] = i;
        n += 1;
        if n == 4 {
            flush(&mut batch, &at, n, out);
            n = 0;
        }
    }
    if n > 0 {
        flush(&mut batch, &at, n, out);
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

/// The velocity field of a rigid motion, `v(x) = v + ω × x` (world coordinates), per unit of
/// the edge parameter `t`.
#[derive(Clone, Copy, Debug, Default)]
struct Twist {
    w: Vector3<f64>,
    v: Vector3<f64>,
}

impl Twist {
    #[inline]
    fn minus(&self, o: &Twist) -> Twist {
        Twist {
            w: self.w - o.w,
            v: self.v - o.v,
        }
    }

    /// The velocity of the point `x`.
    #[inline]
    fn velocity(&self, x: &Point3<f64>) -> Vector3<f64> {
        self.v + self.w.cross(&x.coords)
    }
}

/// Writes to `out` the `dof + 1` prefix sums of the axes' twists at the configuration of
/// `frames`, for the step `delta`: entry `k` is the motion of the link carried by the first
/// `k` axes (a body of level `k` moves with entry `k`; relative to a body of level `l`, with
/// entry `k` minus entry `l`).
#[inline]
fn twists(bounds: &MotionBounds, frames: &Frames, delta: &[f64], out: &mut Vec<Twist>) {
    twists_upto(bounds, frames, delta, out, delta.len());
}

/// As [`twists`], for the first `levels` axes only: entries `0 ..= levels` are written, the
/// later ones left as they were (`out` is sized for every axis).
#[inline]
fn twists_upto(
    bounds: &MotionBounds,
    frames: &Frames,
    delta: &[f64],
    out: &mut Vec<Twist>,
    levels: usize,
) {
    out.resize(delta.len() + 1, Twist::default());
    let mut acc = Twist::default();
    out[0] = acc;
    for (j, ((f, d), o)) in frames
        .axis_frames
        .iter()
        .zip(&delta[..levels])
        .zip(&mut out[1..])
        .enumerate()
    {
        let (col, rot) = bounds.axis_column(j);
        let m = f.rotation.matrix();
        let axis = Vector3::new(m[(0, col)], m[(1, col)], m[(2, col)]);
        if rot {
            acc.w += axis * *d;
            acc.v += f.translation.vector.cross(&axis) * *d;
        } else {
            acc.v += axis * *d;
        }
        *o = acc;
    }
}

/// Largest speed of a point of body `b` (a capsule's core, a solid) under the motion `t`.
#[inline(always)]
fn speed(body: &RobotBody, frames: &Frames, placed: &Placed, b: usize, t: &Twist) -> f64 {
    let ns = body.segments();
    if b < ns {
        let [p0, p1] = &frames.segments[b];
        let (v0, v1) = (t.velocity(p0), t.velocity(p1));
        v0.norm_squared().max(v1.norm_squared()).sqrt()
    } else {
        t.velocity(&placed.centers[b - ns]).norm() + t.w.norm() * body.solids()[b - ns].radius
    }
}

/// Largest speed of a point of body `q` relative to the link moved by the first `level` axes,
/// from the prefix sums of the twists (`twists`, see [`twists`]) at one configuration.
#[inline(always)]
fn relative_speed(
    body: &RobotBody,
    frames: &Frames,
    placed: &Placed,
    twists: &[Twist],
    q: usize,
    level: usize,
) -> f64 {
    let t = twists[body.level(q)].minus(&twists[level]);
    speed(body, frames, placed, q, &t)
}

/// The suffix sums `S_l` of body `b`'s motion bound and its acceleration bounds `A_l`, as
/// `rows[l] = [S_l, A_l]` for every level `l` below `level`, axis by axis from the factors
/// `w_bj` (`factors`) and, per axis, `(|Δa_j|, |Δa_j| for rotations else 0, Ω_j)` (`terms`).
fn rows_by_axis(
    factors: &[f64],
    level: usize,
    terms: (&[f64], &[f64], &[f64]),
    rows: &mut [[f64; 2]],
) {
    let (abs_delta, rot_delta, omega) = terms;
    let (mut sum, mut g, mut h) = (0.0, 0.0, 0.0);
    let terms = factors[..level]
        .iter()
        .zip(&abs_delta[..level])
        .zip(&rot_delta[..level])
        .zip(&omega[..level])
        .zip(&mut rows[..level])
        .rev();
    for ((((w, d), r), omega_j), row) in terms {
        sum += w * d;
        g += d * w * omega_j;
        h += r * sum;
        let x = (g - omega_j * sum).max(0.0) + h;
        *row = [sum, x * (1.0 + 1e-9) + 1e-12];
    }
}

/// What one link's run of free axes contributes to the motion and acceleration bounds of a
/// step, for any body it moves (whose factor for the run's rotations is `w`).
#[derive(Clone, Copy, Debug, Default)]
struct Run {
    /// `Ω` at the run's first axis.
    omega: f64,
    /// `Σ |Δa_j|` over its rotation axes and over its translation axes.
    rot: f64,
    trans: f64,
    /// `Σ |Δa_j|·Ω_j` over its rotations and over its translations.
    g_rot: f64,
    g_trans: f64,
    /// `Σ |Δa_j|·R_j` and `Σ |Δa_j|·T_j` over its rotations `j`, where `R_j` (`T_j`) sums
    /// `|Δa_k|` over the run's rotations `k ≥ j` (translations `k > j`).
    h_rot: f64,
    h_trans: f64,
}

/// Reused buffers of the certified checker (inside [`Scratch`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct Work {
    pub(crate) delta: Vec<f64>,
    /// Per body, [`MotionBounds::slots`] rows, one per level a bound is asked for (row
    /// [`MotionBounds::slot`] of level `l`): `[S_l, A_l]`, the suffix sum `Σ_{j ≥ l} w_bj·|Δa_j|`
    /// of its motion bound ([`MotionBounds::relative`] from level `l`) and the bound on how
    /// fast the body's speed relative to a body of level `l` changes along the edge. Kept
    /// together and compact: a step writes them all and reads few.
    rows: Vec<[f64; 2]>,
    /// `Ω_j`: the sum of `|Δa_k|` over the rotation axes `k < j`, for `j = 0 … dof`.
    omega: Vec<f64>,
    /// `|Δa_j|`, and the same for rotation axes only (0 for translations).
    abs_delta: Vec<f64>,
    rot_delta: Vec<f64>,
    /// Per run of one link's free axes ([`MotionBounds::groups`]), the sums the bounds need.
    runs: Vec<Run>,
    /// Per body `q`, the motion bound of the step relative to the level of the self pairs
    /// checked last and the relative speeds at its two ends (NaN until computed).
    bounds_at: Vec<[f64; 3]>,
    /// The keys of the kept configurations' slots, one per slot.
    keys: Vec<Key>,
    /// Counts the steps checked (the age of the kept configurations).
    clock: u64,
    twist_a: Vec<Twist>,
    twist_b: Vec<Twist>,
    twist_m: Vec<Twist>,
    items: Vec<Item>,
    mid: Vec<Mid>,
    /// The distances of an interval's self pairs at its bisection point, per item (NaN for
    /// the items against the environment).
    pd: Vec<f64>,

    stack: Vec<Interval>,
}

impl Work {
    /// Fills `delta` with `to − from`, and per body the suffix sums of its motion bound and
    /// the acceleration bounds.
    pub(crate) fn prepare(
        &mut self,
        bounds: &MotionBounds,
        body: &RobotBody,
        from: &[f64],
        to: &[f64],
    ) {
        let dof = bounds.dof();
        if self.delta.len() != dof {
            // Sized once per scratch (whose chain is fixed), then overwritten per step.
            self.delta.resize(dof, 0.0);
            self.abs_delta.resize(dof, 0.0);
            self.rot_delta.resize(dof, 0.0);
            self.omega.resize(dof + 1, 0.0);
            self.runs.resize(bounds.groups().len(), Run::default());
        }
        // Ω_j = Σ_{k<j, rotations} |Δa_k|, for j = 0 … dof.
        let mut omega = 0.0;
        self.omega[0] = omega;
        let axes = to
            .iter()
            .zip(from)
            .zip(self.delta.iter_mut().zip(&mut self.abs_delta))
            .zip(self.rot_delta.iter_mut().zip(&mut self.omega[1..]));
        for (j, (((b, a), (delta, abs)), (rot, om))) in axes.enumerate() {
            *delta = b - a;
            *abs = delta.abs();
            *rot = if bounds.axis_column(j).1 { *abs } else { 0.0 };
            omega += *rot;
            *om = omega;
        }
        let n = bounds.bodies();
        let slots = bounds.slots();
        if self.rows.len() != n * slots {
            // Sized once per scratch (whose chain and body are fixed); entries from a body's
            // level on stay 0, only those below it are rewritten per step.
            self.rows.clear();
            self.rows.resize(n * slots, [0.0; 2]);
        }
        // Per run of one link's axes (whose rotation factors are equal for every body): the
        // sums a body's bounds need from it, so that a body's row costs one term per link.
        let runs = if bounds.grouped() {
            &mut self.runs[..]
        } else {
            &mut []
        };
        for (&(start, end), run) in bounds.groups().iter().zip(runs) {
            *run = Run {
                omega: self.omega[start],
                ..Run::default()
            };
            let (mut rot_after, mut trans_after) = (0.0, 0.0);
            for j in (start..end).rev() {
                let (d, omega_j) = (self.abs_delta[j], self.omega[j]);
                if bounds.axis_column(j).1 {
                    rot_after += d;
                    run.rot += d;
                    run.g_rot += d * omega_j;
                    run.h_rot += d * rot_after;
                    run.h_trans += d * trans_after;
                } else {
                    trans_after += d;
                    run.trans += d;
                    run.g_trans += d * omega_j;
                }
            }
        }
        for b in 0..n {
            let rows = &mut self.rows[b * slots..(b + 1) * slots];
            // With S_j the suffix sums of w_bj·|Δa_j|, the bound relative to level l is
            // Σ_{j≥l} |Δa_j|·((Ω_j − Ω_l)·w_bj + [j rotates]·S_j) = G_l − Ω_l·S_l + H_l, with
            // G_l = Σ_{j≥l} |Δa_j|·w_bj·Ω_j and H_l = Σ_{j≥l, rotations} |Δa_j|·S_j. Entries
            // from the body's level on are 0.
            let (mut sum, mut g, mut h) = (0.0, 0.0, 0.0);
            let Some(whole) = bounds.body_runs(b) else {
                // The body's level splits a link's axes: axis by axis.
                let level = body.level(b).min(dof);
                let terms = (&self.abs_delta[..], &self.rot_delta[..], &self.omega[..]);
                rows_by_axis(bounds.factors(b), level, terms, rows);
                continue;
            };
            // Link by link, entries at the links' first axes (the levels of bodies): within a
            // run, Σ w_bj·|Δa_j| = w·rot + trans, G gains w·g_rot + g_trans, and H gains
            // rot·S_after + w·h_rot + h_trans (S_after: the sum over the later links).
            let runs = self.runs[..whole]
                .iter()
                .zip(&bounds.group_factors(b)[..whole])
                .zip(&bounds.run_slots()[..whole])
                .rev();
            for ((run, w), &at) in runs {
                h += run.rot * sum + w * run.h_rot + run.h_trans;
                sum += w * run.rot + run.trans;
                g += w * run.g_rot + run.g_trans;
                let x = (g - run.omega * sum).max(0.0) + h;
                rows[at] = [sum, x * (1.0 + 1e-9) + 1e-12];
            }
        }
    }

    /// Bound on how far body `q` moves over the whole step relative to bodies moved by the
    /// first `level` axes (level 0: how far it moves), as [`MotionBounds::relative`].
    #[inline]
    pub(crate) fn relative(&self, bounds: &MotionBounds, q: usize, level: usize) -> f64 {
        self.rows[q * bounds.slots() + bounds.slot(level.min(bounds.dof()))][0]
    }

    /// Bound on how fast the speed of body `q` relative to bodies moved by the first `level`
    /// axes changes along the edge.
    #[inline]
    fn accel(&self, bounds: &MotionBounds, q: usize, level: usize) -> f64 {
        self.rows[q * bounds.slots() + bounds.slot(level.min(bounds.dof()))][1]
    }
}

/// How many recent configurations `certified` keeps per scratch (with their frames, placement
/// and clearances) for the steps that start or end there: a planner extends the nodes it has
/// just added, and most steps start at one of the last few steps' ends.
pub const KEPT: usize = 16;

/// A configuration `certified` has evaluated, with what it computed there.
#[derive(Clone, Debug)]
pub(crate) struct Kept {
    config: Vec<f64>,
    /// The scene the clearances are against ([`CollisionScene::id`]; 0: an empty slot).
    scene: u64,
    frames: Frames,
    placed: Placed,
    balls: Vec<(Point3<f64>, f64)>,
    /// Per body, a lower bound of its clearance and whether it is the exact clearance
    /// (`-∞`, false when unknown).
    clear: Vec<(f64, bool)>,
    /// Per body, the obstacle found nearest there (`u32::MAX` when none is known): the first
    /// one tried at a configuration close by.
    near: Vec<u32>,
    /// The distance of every self pair measured there, per block of pairs
    /// ([`RobotBody::measure_block`]) once `known` for that block.
    pairs: Vec<f64>,
    known: Vec<bool>,
}

/// Records in `clear` what is now known of body `b`'s clearance: an exact value replaces
/// anything, a lower bound raises a lower bound.
#[inline]
fn learn(clear: &mut [(f64, bool)], b: usize, value: f64, exact: bool) {
    let k = &mut clear[b];
    if exact {
        *k = (value, true);
    } else if !k.1 && value > k.0 {
        k.0 = value;
    }
}

impl Kept {
    /// With its frames just evaluated: the bodies placed, their balls, and nothing known of
    /// their clearances yet.
    fn evaluated(&mut self, body: &RobotBody) {
        let n = body.len();
        body.place(&self.frames, &mut self.placed);
        body.balls(&self.frames, &self.placed, &mut self.balls);
        self.clear.clear();
        self.clear.resize(n, (f64::NEG_INFINITY, false));
        self.near.clear();
        self.near.resize(n, u32::MAX);
        self.pairs.resize(body.self_pairs().len(), f64::NAN);
        self.known.clear();
        self.known.resize(body.pair_blocks().len(), false);
    }

    fn new(chain: &Chain) -> Self {
        Kept {
            config: Vec::new(),
            scene: 0,
            frames: chain.frames(),
            placed: Placed::default(),
            balls: Vec::new(),
            clear: Vec::new(),
            near: Vec::new(),
            pairs: Vec::new(),
            known: Vec::new(),
        }
    }
}

/// What finds a kept configuration's slot: its scene, its last use and its first value, kept
/// apart from the slots themselves so that a lookup reads a few cache lines.
#[derive(Clone, Copy, Debug, Default)]
struct Key {
    scene: u64,
    used: u64,
    first: f64,
}

/// The slot of `kept` (with their `keys`) that holds `config` for the scene `scene` (not
/// `avoid`), and true; or else the least recently used other slot, emptied and set to
/// `config`, and false.
fn slot(
    keys: &mut Vec<Key>,
    kept: &mut [Kept],
    scene: u64,
    config: &[f64],
    avoid: usize,
    clock: u64,
) -> (usize, bool) {
    if keys.len() != kept.len() {
        keys.clear();
        keys.extend(kept.iter().map(|k| Key {
            scene: k.scene,
            used: 0,
            first: k.config.first().copied().unwrap_or(0.0),
        }));
    }
    let first = config.first().copied().unwrap_or(0.0);
    let found = keys.iter().enumerate().position(|(i, k)| {
        i != avoid && k.scene == scene && k.first == first && kept[i].config == config
    });
    if let Some(i) = found {
        keys[i].used = clock;
        return (i, true);
    }
    let i = keys
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != avoid)
        .min_by_key(|(_, k)| k.used)
        .map_or(0, |(i, _)| i);
    keys[i] = Key {
        scene,
        used: clock,
        first,
    };
    let k = &mut kept[i];
    k.config.clear();
    k.config.extend_from_slice(config);
    k.scene = scene;
    (i, false)
}

/// Two distinct elements of `v`, mutably.
fn two<T>(v: &mut [T], i: usize, j: usize) -> (&mut T, &mut T) {
    assert_ne!(i, j);
    if i < j {
        let (x, y) = v.split_at_mut(j);
        (&mut x[i], &mut y[0])
    } else {
        let (x, y) = v.split_at_mut(i);
        (&mut y[0], &mut x[j])
    }
}

/// Body `b`'s bound on how far it moves over the whole step, from the prepared `work` (with
/// the twists of both ends) and the frames and placement of the step's ends: `(S, A, u0, u1,
/// bound)`, its speed cap, acceleration bound, end speeds and the motion bound.
#[inline(always)]
fn env_bound(
    work: &Work,
    bounds: &MotionBounds,
    body: &RobotBody,
    (fa, pa): (&Frames, &Placed),
    (fb, pb): (&Frames, &Placed),
    b: usize,
) -> (f64, f64, f64, f64, f64) {
    let plain = work.relative(bounds, b, 0);
    let level = body.level(b);
    let accel = work.accel(bounds, b, 0);
    let u0 = speed(body, fa, pa, b, &work.twist_a[level]);
    let u1 = speed(body, fb, pb, b, &work.twist_b[level]);
    (
        plain,
        accel,
        u0,
        u1,
        motion(1.0, plain, u0, u1, accel, 1.0 / accel),
    )
}

/// Body `q`'s bound on how far it moves relative to the bodies of level `level` over the whole
/// step, with its speed cap `plain` and acceleration bound `accel` for that level: `[bound, u0,
/// u1]`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn pair_bound(
    work: &Work,
    body: &RobotBody,
    (fa, pa): (&Frames, &Placed),
    (fb, pb): (&Frames, &Placed),
    q: usize,
    level: usize,
    plain: f64,
    accel: f64,
) -> [f64; 3] {
    let u0 = relative_speed(body, fa, pa, &work.twist_a, q, level);
    let u1 = relative_speed(body, fb, pb, &work.twist_b, q, level);
    [motion(1.0, plain, u0, u1, accel, 1.0 / accel), u0, u1]
}

/// What `certified` first tests of a step: a body against the environment, or a self pair,
/// with the bound on how far the moving body can move over the whole step ([`step_bounds`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepBound {
    /// The moving body.
    pub body: usize,
    /// For a self pair, its other body (at a level no deeper than `body`'s): the bound is on
    /// `body`'s motion relative to the links of that body's level. `None` for `body` against
    /// the environment (the bound is on its motion in the world).
    pub relative_to: Option<usize>,
    /// Bound on the path length of every point of `body` over the step.
    pub bound: f64,
}

/// The motion bounds `certified` proves a whole step `from → to` with before it bisects: one
/// per robot body (against the environment) and one per checked self pair. The step is proven
/// at once for an item whose clearances at the two ends add up to more than its bound, and
/// bisected otherwise. A diagnostic: comparing these bounds with path lengths measured densely
/// along the step shows how much room the proof leaves (`examples/check_cost.rs`, mode
/// `bounds`). Allocates; not for a hot loop.
pub fn step_bounds(chain: &Chain, body: &RobotBody, from: &[f64], to: &[f64]) -> Vec<StepBound> {
    let bounds = MotionBounds::new(chain, body);
    let mut work = Work::default();
    work.prepare(&bounds, body, from, to);
    let (mut fa, mut fb) = (chain.frames(), chain.frames());
    let (mut pa, mut pb) = (Placed::default(), Placed::default());
    chain.fk(from, &mut fa);
    chain.fk(to, &mut fb);
    body.place(&fa, &mut pa);
    body.place(&fb, &mut pb);
    twists(&bounds, &fa, &work.delta, &mut work.twist_a);
    twists(&bounds, &fb, &work.delta, &mut work.twist_b);
    let (a, b) = ((&fa, &pa), (&fb, &pb));
    let mut out: Vec<StepBound> = (0..body.len())
        .map(|k| StepBound {
            body: k,
            relative_to: None,
            bound: env_bound(&work, &bounds, body, a, b, k).4,
        })
        .collect();
    for &(p, q) in body.self_pairs() {
        let (p, q) = (p as usize, q as usize);
        let level = body.level(p);
        let plain = work.relative(&bounds, q, level);
        let accel = work.accel(&bounds, q, level);
        out.push(StepBound {
            body: q,
            relative_to: Some(p),
            bound: pair_bound(&work, body, a, b, q, level, plain, accel)[0],
        });
    }
    out
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

    fn check_node(
        &self,
        chain: &Chain,
        a: &[f64],
        frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool {
        super::node_free_with(&self.scene, BodyModel::Capsules, chain, a, frames, scratch)
    }

    fn edge_checks_end(&self) -> bool {
        true // a free answer is a proof over the whole step, its end included
    }

    fn check_edge(
        &self,
        chain: &Chain,
        from: &[f64],
        to: &[f64],
        to_frames: Option<&Frames>,
        scratch: &mut Scratch,
    ) -> bool {
        scratch.stats.edges += 1;
        let scene = &*self.scene;
        let Scratch {
            fm,
            q,
            bounds,
            certified: work,
            stats,
            body,
            pm,
            kept,
            ..
        } = scratch;
        let body = &**body;
        work.prepare(bounds, body, from, to);
        work.items.clear();
        work.stack.clear();

        let n = body.len();
        if kept.is_empty() {
            kept.resize_with(KEPT, || Kept::new(chain));
        }
        work.clock += 1;
        let id = scene.id();
        // A configuration evaluated by a recent step (the planner extends the nodes it has
        // just added) comes with its frames, placement and clearances.
        let (ia, hit_a) = slot(&mut work.keys, kept, id, from, usize::MAX, work.clock);
        let (ib, hit_b) = slot(&mut work.keys, kept, id, to, ia, work.clock);
        let (ka, kb) = two(kept, ia, ib);
        if !hit_a {
            stats.fk += 1;
            chain.fk(from, &mut ka.frames);
            ka.evaluated(body);
        }
        if !hit_b {
            super::fk_or_copy(chain, to, to_frames, &mut kb.frames, stats);
            kb.evaluated(body);
        }
        let (fa, fb) = (&ka.frames, &kb.frames);
        let (pa, pb) = (&ka.placed, &kb.placed);
        twists(bounds, fa, &work.delta, &mut work.twist_a);
        twists(bounds, fb, &work.delta, &mut work.twist_b);
        // Each body against the environment: c(t) = clearance − ε moves no faster than the
        // body. c1 > D proves the whole step; otherwise c0 > D − c1 does. From the tip: the
        // bodies that move most are the likeliest to block the step.
        for b in (0..body.len()).rev() {
            let (plain, accel, u0, u1, bound) =
                env_bound(work, bounds, body, (fa, pa), (fb, pb), b);
            let (known0, exact0) = ka.clear[b];
            let (known1, exact1) = kb.clear[b];
            if known0 > bound {
                // Proven from the start's clearance alone; c1 ≥ c0 − D at the end.
                learn(&mut kb.clear, b, known0 - bound, false);
                continue;
            }
            if known1 > bound {
                learn(&mut ka.clear, b, known1 - bound, false);
                continue;
            }
            // The step's end first: in a planner it is the new configuration, where a
            // collision is most likely.
            let (c1, hint) = if exact1 {
                (known1, u32::MAX)
            } else {
                // The obstacle nearest at the start, when known, is likely nearest here.
                let (c1, hint) = body.clearance(
                    scene,
                    fb,
                    pb,
                    b,
                    &kb.balls[b],
                    bound + CAP_MARGIN,
                    ka.near[b],
                );
                // Exact when an obstacle was found below the cap, else a lower bound.
                learn(&mut kb.clear, b, c1, hint != u32::MAX);
                if hint != u32::MAX {
                    kb.near[b] = hint;
                }
                (c1, hint)
            };
            if c1 <= 0.0 {
                return false;
            }
            if c1 > bound {
                continue;
            }
            let need = (bound - c1).max(0.0) + CAP_MARGIN;
            let (c0, hint) = if exact0 {
                (known0, hint)
            } else {
                let (c0, h) = body.clearance(scene, fa, pa, b, &ka.balls[b], need, hint);
                learn(&mut ka.clear, b, c0, h != u32::MAX);
                if h != u32::MAX {
                    ka.near[b] = h;
                }
                (c0, h)
            };
            if c0 <= 0.0 {
                return false;
            }
            if c0 + c1 > bound {
                continue;
            }
            work.items.push(Item {
                body: b as u32,
                other: ENV,
                hint,
                reach: plain,
                accel,
                inv_accel: 1.0 / accel,
                c0,
                c1,
                u0,
                u1,
            });
        }
        // The motion bound of body q relative to level l serves every pair (p, q) with p at
        // level l; the pairs come ordered by p, so by level: kept per q for the current level.
        work.bounds_at.clear();
        work.bounds_at.resize(n, [f64::NAN; 3]);
        let mut bounds_level = usize::MAX;
        for (i, &(p, qb)) in body.self_pairs().iter().enumerate() {
            let (p, qb) = (p as usize, qb as usize);
            let level = body.level(p);
            if level != bounds_level {
                work.bounds_at.fill([f64::NAN; 3]);
                bounds_level = level;
            }
            let plain = work.relative(bounds, qb, level);
            // Lower bounds of the distance at both ends from the bounding balls (a proof
            // from lower bounds holds as one from the distances). The start's alone proves
            // most pairs: |cp − cq| > plain + rp + rq, compared squared (both sides are ≥ 0),
            // so that no square root is taken for them.
            let ((cp, rp), (cq, rq)) = (ka.balls[p], ka.balls[qb]);
            let gap = plain + rp + rq;
            if (cp - cq).norm_squared() > gap * gap {
                continue;
            }
            // Both ends' balls against the speed cap (at least the bound) prove about half of
            // the rest without the end speeds the bound needs.
            let ball0 = (cp - cq).norm() - rp - rq;
            let ((cp, rp), (cq, rq)) = (kb.balls[p], kb.balls[qb]);
            let ball1 = (cp - cq).norm() - rp - rq;
            if ball0 + ball1 > plain {
                continue;
            }
            let accel = work.accel(bounds, qb, level);
            let [mut bound, mut u0, mut u1] = work.bounds_at[qb];
            if bound.is_nan() {
                [bound, u0, u1] =
                    pair_bound(work, body, (fa, pa), (fb, pb), qb, level, plain, accel);
                work.bounds_at[qb] = [bound, u0, u1];
            }
            if ball0 > bound || ball0 + ball1 > bound {
                continue;
            }
            // The distances of the pair's block of self pairs, measured at once the first
            // time a step needs one of them at a configuration (and kept with it).
            let block = body.block_of_pair(i);
            if !ka.known[block] {
                body.measure_block(fa, pa, block, &mut ka.pairs);
                ka.known[block] = true;
            }
            let c0 = ka.pairs[i];
            if c0 <= 0.0 {
                return false;
            }
            if c0 > bound {
                continue;
            }
            if !kb.known[block] {
                body.measure_block(fb, pb, block, &mut kb.pairs);
                kb.known[block] = true;
            }
            let c1 = kb.pairs[i];
            if c1 <= 0.0 {
                return false;
            }
            if c0 + c1 > bound {
                continue;
            }
            work.items.push(Item {
                body: p as u32,
                other: qb as u32,
                hint: u32::MAX,
                reach: plain,
                accel,
                inv_accel: 1.0 / accel,
                c0,
                c1,
                u0,
                u1,
            });
        }
        if work.items.is_empty() {
            return true;
        }
        work.stack.push(Interval {
            t0: 0.0,
            t1: 1.0,
            start: 0,
            len: work.items.len(),
            depth: 0,
        });
        let mut midpoints = 0;
        while let Some(iv) = work.stack.pop() {
            if iv.depth >= MAX_DEPTH || midpoints >= MAX_MIDPOINTS {
                return false; // cannot be proven: count as blocked
            }
            midpoints += 1;
            // The items past this interval's belong to intervals already done (the stack's
            // ranges rise towards its top): dropped, so that memory stays bounded by the
            // depth however many intervals an edge takes.
            work.items.truncate(iv.start + iv.len);
            let tm = 0.5 * (iv.t0 + iv.t1);
            for ((qi, a), d) in q.iter_mut().zip(from).zip(&work.delta) {
                *qi = a + tm * d;
            }
            // Only the links and axes that move the interval's items are evaluated.
            let (mut links, mut levels) = (0, 0);
            for it in &work.items[iv.start..iv.start + iv.len] {
                let b = it.body as usize;
                links = links.max(body.fk_links(b));
                let q = if it.other == ENV {
                    b
                } else {
                    let o = it.other as usize;
                    links = links.max(body.fk_links(o));
                    o
                };
                levels = levels.max(body.level(q));
            }
            stats.fk += 1;
            chain.fk_links(q, fm, links);
            body.place_links(fm, pm, links);
            twists_upto(bounds, fm, &work.delta, &mut work.twist_m, levels);
            let half = 0.5 * (iv.t1 - iv.t0);
            // Children: left [t0, tm] and right [tm, t1], appended after the parent's items.
            // Per item: the clearance and speed at tm, and the children's motion bounds.
            work.mid.clear();
            pair_distances(
                body,
                fm,
                pm,
                &work.items[iv.start..iv.start + iv.len],
                &mut work.pd,
            );
            for i in iv.start..iv.start + iv.len {
                let it = work.items[i];
                let b = it.body as usize;
                let (q, twist) = if it.other == ENV {
                    (b, work.twist_m[body.level(b)])
                } else {
                    let (l0, l1) = (body.level(b), body.level(it.other as usize));
                    (it.other as usize, work.twist_m[l1].minus(&work.twist_m[l0]))
                };
                let um = speed(body, fm, pm, q, &twist);
                let left = motion(half, it.reach, it.u0, um, it.accel, it.inv_accel);
                let right = motion(half, it.reach, um, it.u1, it.accel, it.inv_accel);
                let (cm, hint) = if it.other != ENV {
                    (work.pd[i - iv.start], u32::MAX)
                } else {
                    // Both children are proven once cm exceeds `need`; below it the
                    // clearance is exact (the decision is the same as with no cap).
                    let need = (left - it.c0).max(right - it.c1).max(0.0) + CAP_MARGIN;
                    let ball = body.ball(fm, pm, b);
                    body.clearance(scene, fm, pm, b, &ball, need, it.hint)
                };
                if cm <= 0.0 {
                    return false;
                }
                work.mid.push(Mid {
                    c: cm,
                    u: um,
                    left,
                    right,
                    hint,
                });
            }
            // The right child's items first, then the left's, which is checked first: the
            // stack's item ranges rise towards its top.
            let parent = iv.start..iv.start + iv.len;
            let right_start = work.items.len();
            push_children(&mut work.items, parent.clone(), &work.mid, false);
            let left_start = work.items.len();
            push_children(&mut work.items, parent, &work.mid, true);
            let end = work.items.len();
            if left_start > right_start {
                work.stack.push(Interval {
                    t0: tm,
                    t1: iv.t1,
                    start: right_start,
                    len: left_start - right_start,
                    depth: iv.depth + 1,
                });
            }
            if end > left_start {
                work.stack.push(Interval {
                    t0: iv.t0,
                    t1: tm,
                    start: left_start,
                    len: end - left_start,
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

    /// A link turning along a sphere at a constant gap of 1e-8 m (its capsule tangent to a
    /// sphere centred on the joint's axis) needs about a hundred million bisection points to
    /// be proven free: the edge counts as blocked after [`MAX_MIDPOINTS`] of them, and the
    /// items kept while bisecting stay within two children per level of depth (they grew with
    /// every interval before: 2.4 GB for a run of 7 such edges).
    #[test]
    fn an_edge_along_an_obstacle_at_a_tiny_gap_is_bounded() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tangent.toml");
        let gap = 1e-8;
        std::fs::write(
            &path,
            format!(
                "[robot]\nlinks = 2\n[robot.uniform]\na = 0.5\n[[robot.link]]\nindex = 1\naxes.ry = {{ min = -3.1416, max = 3.1416 }}\n[[obstacle]]\nshape = \"sphere\"\nposition = [0.5, {}, 0.0]\nradius = 0.1\n[[task]]\npoint = [0.5, 0.0, 0.5]\n",
                0.1 + 0.02 + gap
            ),
        )
        .unwrap();
        let s = Scenario::load(&path).unwrap();
        let chain = s.space.largest().chain();
        let scene = Arc::new(CollisionScene::new(&s.workspace));
        let checker = Certified::new(scene);
        let mut scratch = Scratch::new(&chain);
        let (from, to) = (vec![0.0; chain.dof()], vec![3.0; chain.dof()]);
        assert!(!checker.check_edge(&chain, &from, &to, None, &mut scratch));
        let fk = scratch.stats.fk;
        assert!(
            fk > u64::from(MAX_MIDPOINTS) / 2 && fk <= u64::from(MAX_MIDPOINTS) + 2,
            "{fk}"
        );
        let per_interval = scratch.body.len() + scratch.body.self_pairs().len();
        let items = scratch.certified.items.len();
        assert!(
            items <= 2 * (MAX_DEPTH as usize + 1) * per_interval,
            "{items} items"
        );
        // The same motion farther away (1 cm) is proven free in a few bisection points.
        let far = path.with_file_name("far.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&far, text.replace(&format!("{}", 0.1 + 0.02 + gap), "0.13")).unwrap();
        let s = Scenario::load(&far).unwrap();
        let checker = Certified::new(Arc::new(CollisionScene::new(&s.workspace)));
        let mut scratch = Scratch::new(&chain);
        assert!(checker.check_edge(&chain, &from, &to, None, &mut scratch));
        assert!(scratch.stats.fk < 1_000, "{}", scratch.stats.fk);
    }

    /// The motion bound holds: over a sub-interval `[t0, t1]` of a step, with the speeds at
    /// its two ends from the twists of the full configuration, no point of a body's core moves
    /// (relative to any level of the chain) farther than `motion`, and from `t0` to `t` no
    /// farther than the one-sided ramp `u0·τ + accel·τ²/2`.
    #[test]
    fn motion_bound_covers_the_real_motion() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios/paper-3d.toml");
        let s = Scenario::load(&path).unwrap();
        let chain = s.space.largest().chain();
        let body = RobotBody::of_chain(&chain);
        let bounds = MotionBounds::new(&chain, &body);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (mut f0, mut f1, mut ft) = (chain.frames(), chain.frames(), chain.frames());
        let (mut p0, mut p1) = (Placed::default(), Placed::default());
        let dof = chain.dof();
        let (mut a, mut b, mut q) = (vec![0.0; dof], vec![0.0; dof], vec![0.0; dof]);
        let mut work = Work::default();
        let (mut tw0, mut tw1) = (Vec::new(), Vec::new());
        let (mut tight, mut cases) = (0, 0);
        for case in 0..300 {
            chain.sample_config(&mut rng, &mut a);
            if case % 2 == 0 {
                for (bj, aj) in b.iter_mut().zip(&a) {
                    *bj = aj + rng.random_range(-0.8..0.8);
                }
            } else {
                // Two axes with large steps.
                b.copy_from_slice(&a);
                for _ in 0..2 {
                    let j = rng.random_range(0..dof);
                    b[j] += rng.random_range(-2.5..2.5);
                }
            }
            // The bounds hold within the ranges (a box, so along the whole step).
            for (bj, f) in b.iter_mut().zip(chain.free_axes()) {
                *bj = bj.clamp(f.range.min, f.range.max);
            }
            work.prepare(&bounds, &body, &a, &b);
            // The link-by-link rows are the axis-by-axis ones at the levels of bodies.
            for p in 0..body.len() {
                let level = body.level(p).min(dof);
                let mut want = vec![[0.0; 2]; dof + 1];
                let terms = (&work.abs_delta[..], &work.rot_delta[..], &work.omega[..]);
                rows_by_axis(bounds.factors(p), level, terms, &mut want);
                for l in std::iter::once(0).chain((0..body.len()).map(|o| body.level(o))) {
                    let [s_ref, a_ref] = want[l.min(dof)];
                    let (s_got, a_got) = (work.relative(&bounds, p, l), work.accel(&bounds, p, l));
                    assert!((s_got - s_ref).abs() <= 1e-12 * (1.0 + s_ref), "{s_got}");
                    assert!((a_got - a_ref).abs() <= 1e-9 * (1.0 + a_ref), "{a_got}");
                }
            }
            let t0: f64 = rng.random_range(0.0..0.9);
            let t1: f64 = rng.random_range(t0 + 0.01..=1.0);
            let at = |t: f64, out: &mut Vec<f64>| {
                for ((o, x), d) in out.iter_mut().zip(&a).zip(&work.delta) {
                    *o = x + t * d;
                }
            };
            at(t0, &mut q);
            chain.fk(&q, &mut f0);
            body.place(&f0, &mut p0);
            twists(&bounds, &f0, &work.delta, &mut tw0);
            at(t1, &mut q);
            chain.fk(&q, &mut f1);
            body.place(&f1, &mut p1);
            twists(&bounds, &f1, &work.delta, &mut tw1);
            let span = t1 - t0;
            for qb in 0..body.segments() {
                let lq = body.level(qb);
                // A level the checker asks for: 0 or a body's (the first axis of a link).
                let levels: Vec<usize> = std::iter::once(0)
                    .chain((0..body.len()).map(|p| body.level(p)))
                    .filter(|&l| l <= lq)
                    .collect();
                let from = levels[rng.random_range(0..levels.len())];
                let plain = work.relative(&bounds, qb, from);
                assert!((plain - bounds.relative(qb, from, &work.delta)).abs() < 1e-12);
                let accel = work.accel(&bounds, qb, from);
                let u0 = speed(&body, &f0, &p0, qb, &tw0[lq].minus(&tw0[from]));
                let u1 = speed(&body, &f1, &p1, qb, &tw1[lq].minus(&tw1[from]));
                let bound = motion(span, plain, u0, u1, accel, 1.0 / accel);
                assert!(bound <= span * plain + 1e-12);
                cases += 1;
                if bound < 0.5 * span * plain {
                    tight += 1;
                }
                // Relative motion: the axes before `from` held still; the bound covers the
                // length of the path each end point travels.
                let mut prev = f0.segments[qb];
                let mut travelled = [0.0; 2];
                let steps = 400;
                for k in 1..=steps {
                    let tau = span * k as f64 / steps as f64;
                    for j in 0..dof {
                        let t = if j < from { t0 } else { t0 + tau };
                        q[j] = a[j] + t * work.delta[j];
                    }
                    chain.fk(&q, &mut ft);
                    for e in 0..2 {
                        travelled[e] += (ft.segments[qb][e] - prev[e]).norm();
                        let ramp = u0 * tau + 0.5 * accel * tau * tau;
                        assert!(
                            travelled[e] <= ramp + 1e-9,
                            "body {qb}: travelled {} > ramp {ramp} at τ = {tau}",
                            travelled[e]
                        );
                    }
                    prev = ft.segments[qb];
                }
                for e in travelled {
                    assert!(
                        e <= bound + 1e-9,
                        "body {qb} travelled {e} > bound {bound} over {span}"
                    );
                }
            }
        }
        assert!(
            tight * 4 > cases,
            "the speeds halved only {tight} of {cases} bounds"
        );
    }

    /// What `certified` keeps of recent configurations holds: after every step of a walk that
    /// revisits recent configurations, each kept slot's frames are those of its configuration,
    /// and each clearance it records is the exact clearance there (to rounding) when marked
    /// exact, and at most that otherwise; and steps do start from kept configurations.
    #[test]
    fn kept_clearances_are_exact_or_lower_bounds() {
        let s = Scenario::from_spec(&crate::scenario::preset::generate(
            crate::scenario::preset::Preset::Paper3d,
            2,
        ))
        .unwrap();
        let chain = s.space.largest().chain();
        let scene = Arc::new(CollisionScene::new(&s.workspace));
        let checker = Certified::new(scene.clone());
        let mut scratch = Scratch::new(&chain);
        let body = scratch.body.clone();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let dof = chain.dof();
        let mut a = vec![0.0; dof];
        chain.sample_config(&mut rng, &mut a);
        let mut ends: Vec<Vec<f64>> = Vec::new();
        let mut frames = chain.frames();
        let (mut exact, mut bounds) = (0, 0);
        for step in 0..400 {
            if rng.random_range(0..4) == 0 && !ends.is_empty() {
                let back = rng.random_range(1..=ends.len().min(20));
                a.clone_from(&ends[ends.len() - back]);
            }
            let b: Vec<f64> = a
                .iter()
                .zip(chain.free_axes())
                .map(|(x, f)| (x + rng.random_range(-0.4..=0.4)).clamp(f.range.min, f.range.max))
                .collect();
            checker.edge_free(&chain, &a, &b, &mut scratch);
            for k in scratch.kept.iter().filter(|k| k.scene != 0) {
                chain.fk(&k.config, &mut frames);
                assert_eq!(frames.segments, k.frames.segments, "step {step}");
                for (i, &(value, is_exact)) in k.clear.iter().enumerate() {
                    if value == f64::NEG_INFINITY {
                        continue;
                    }
                    let ball = body.ball(&k.frames, &k.placed, i);
                    let (truth, _) = body.clearance(
                        &scene,
                        &k.frames,
                        &k.placed,
                        i,
                        &ball,
                        f64::INFINITY,
                        u32::MAX,
                    );
                    if is_exact {
                        assert!(
                            (value - truth).abs() < 1e-12,
                            "step {step}: {value} ≠ {truth}"
                        );
                        exact += 1;
                    } else {
                        assert!(value <= truth + 1e-12, "step {step}: {value} > {truth}");
                        bounds += 1;
                    }
                }
            }
            ends.push(b.clone());
            a = b;
        }
        assert!(
            exact > 1000 && bounds > 1000,
            "{exact} exact, {bounds} bounds"
        );
        assert!(
            scratch.stats.fk < scratch.stats.edges * 5,
            "{:?}",
            scratch.stats
        );
    }

    /// The motion integral: exact for constant speed, symmetric, capped by `s·reach`, and the
    /// integral of the lower ramp where one end is much faster.
    #[test]
    fn motion_integral_cases() {
        let m = |s: f64, reach: f64, u0: f64, u1: f64, accel: f64| {
            motion(s, reach, u0, u1, accel, 1.0 / accel)
        };
        assert!((m(2.0, 10.0, 1.0, 1.0, 1e-12) - 2.0).abs() < 1e-9);
        assert!((m(1.0, 10.0, 0.5, 3.0, 1e-12) - 0.5).abs() < 1e-9);
        let (x, y) = (m(0.5, 10.0, 0.2, 0.7, 3.0), m(0.5, 10.0, 0.7, 0.2, 3.0));
        assert!((x - y).abs() < 1e-12);
        assert_eq!(m(1.0, 0.1, 1.0, 1.0, 5.0), 0.1);
        // u1 far above the ramp from u0: the integral of u0 + a·τ.
        let v = m(1.0, 100.0, 0.0, 50.0, 2.0);
        assert!((v - 1.0).abs() < 1e-9, "{v}");
        // Equal end speeds: the two ramps meet in the middle.
        let v = m(2.0, 100.0, 1.0, 1.0, 1.0);
        assert!((v - (2.0 + 2.0 * 0.5 * 1.0)).abs() < 1e-9, "{v}");
        // The closed form is the integral of the lower envelope, from where the ramps meet
        // (and never below it): random cases against the integral summed on a fine grid.
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        for _ in 0..2000 {
            let s = rng.random_range(1e-6..1.0);
            let (u0, u1) = (rng.random_range(0.0..3.0), rng.random_range(0.0..3.0));
            let accel = 10f64.powf(rng.random_range(-6.0..2.0));
            let got = m(s, f64::INFINITY, u0, u1, accel);
            let tau = (0.5 * ((u1 - u0) / accel + s)).clamp(0.0, s);
            let rest = s - tau;
            let want = u0 * tau + 0.5 * accel * tau * tau + u1 * rest + 0.5 * accel * rest * rest;
            assert!(got >= want, "{got} < {want}");
            assert!(got <= want * (1.0 + 1e-9) + 1e-15, "{got} ≫ {want}");
        }
    }
}
