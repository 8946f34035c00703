//! Configuration-independent motion bounds of the robot bodies (the basis of `certified`).
//!
//! Along a straight actuation-space motion, a point `p` of a body moves with velocity
//! `Σ_j v_j(p)·Δa_j`, where `|v_j(p)| ≤ |p − o_j|` for a rotation axis `j` through `o_j` and
//! `|v_j(p)| = 1` for a translation. [`Chain::arc_layout`] bounds `|p − o_j|` by arc lengths
//! along the chain, in every configuration within the ranges; adding the body's own extent gives
//! the factor `w_bj`, and no point of body `b` moves farther than `Σ_j w_bj·|Δa_j|`.
//!
//! Two bodies move relative to each other only through the joints between them: in the frame
//! of the proximal body `p`, the distal body `q` moves at most `Σ_{level(p) ≤ j < level(q)}
//! w_qj·|Δa_j|` ([`MotionBounds::relative`]).

use super::model::RobotBody;
use crate::kinematics::Chain;

/// Per-body motion factors `w_bj` (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct MotionBounds {
    bodies: usize,
    dof: usize,
    w: Vec<f64>,
    /// Per free axis: the column of its frame's rotation that is the axis direction, and
    /// whether it is a rotation.
    column: Vec<(usize, bool)>,
    /// The free axes in runs of one link each, as ranges of axis indices (a body's level is
    /// the end of a run, or 0).
    groups: Vec<(usize, usize)>,
    /// Per body and run: the factor `w_bj` of the run's rotation axes (equal within a link;
    /// 0 for the runs that do not move the body).
    group_w: Vec<f64>,
    /// Per body: how many runs move it, or `None` when its level splits a run or the links
    /// have one free axis each on average (then its bounds are computed axis by axis).
    body_runs: Vec<Option<usize>>,
    /// True when some body's bounds are computed link by link ([`MotionBounds::body_runs`]).
    grouped: bool,
    /// Per level `0 ..= dof`: its row among [`MotionBounds::slots`] (see there).
    slot: Vec<usize>,
    /// Per run: the row of its first axis's level.
    run_slots: Vec<usize>,
    slots: usize,
}

impl MotionBounds {
    /// The bounds of `body` on `chain`.
    pub fn new(chain: &Chain, body: &RobotBody) -> Self {
        let layout = chain.layout();
        let dof = chain.dof();
        let n = body.len();
        let mut w = vec![0.0; n * dof];
        let ns = body.segments();
        for b in 0..n {
            // Farthest arc position of the body, and its extent beyond that position.
            let (end, extent) = if b < ns {
                (layout.segment_end[b], body.radius(b))
            } else {
                let s = &body.solids()[b - ns];
                let origin = if s.level == 0 {
                    0.0
                } else {
                    layout.axis[s.level - 1]
                };
                (origin, s.reach_from_origin())
            };
            for (j, axis) in chain.free_axes().iter().enumerate().take(body.level(b)) {
                w[b * dof + j] = if axis.axis.is_rotation() {
                    (end - layout.joint[axis.link - 1]).max(0.0) + extent
                } else {
                    1.0
                };
            }
        }
        let column = chain
            .free_axes()
            .iter()
            .map(|a| (a.axis.index() % 3, a.axis.is_rotation()))
            .collect();
        let mut groups: Vec<(usize, usize)> = Vec::new();
        for (j, axis) in chain.free_axes().iter().enumerate() {
            match groups.last_mut() {
                Some(g) if chain.free_axes()[g.0].link == axis.link => g.1 = j + 1,
                _ => groups.push((j, j + 1)),
            }
        }
        let mut group_w = vec![0.0; n * groups.len()];
        for b in 0..n {
            for (g, &(start, end)) in groups.iter().enumerate() {
                // The rotation factors of one link are equal (they depend on the link only).
                let rot = (start..end).filter(|&j| chain.free_axes()[j].axis.is_rotation());
                group_w[b * groups.len() + g] = rot.map(|j| w[b * dof + j]).fold(0.0, f64::max);
            }
        }
        // Link by link pays where links have several free axes; with one per link the
        // bounds are computed axis by axis (`None` for every body).
        let grouped = dof >= 2 * groups.len();
        let body_runs: Vec<Option<usize>> = (0..n)
            .map(|b| {
                let level = body.level(b).min(dof);
                let whole = groups.iter().take_while(|g| g.1 <= level).count();
                let split = groups.get(whole).is_some_and(|g| g.0 < level);
                (!split).then_some(whole)
            })
            .collect();
        // Bounds are asked for at level 0 and at the levels of bodies: the runs' first axes and
        // `dof`, unless some body's level splits a run (then at every level).
        let body_runs = if grouped { body_runs } else { vec![None; n] };
        let (slot, slots) = if body_runs.iter().all(Option::is_some) {
            let mut slot = vec![usize::MAX; dof + 1];
            for (r, g) in groups.iter().enumerate() {
                slot[g.0] = r;
            }
            slot[dof] = groups.len();
            (slot, groups.len() + 1)
        } else {
            ((0..=dof).collect(), dof + 1)
        };
        let run_slots = groups.iter().map(|g| slot[g.0]).collect();
        MotionBounds {
            bodies: n,
            dof,
            w,
            column,
            groups,
            group_w,
            grouped: body_runs.iter().any(Option::is_some),
            body_runs,
            slot,
            run_slots,
            slots,
        }
    }

    /// Bound on how far body `q` moves relative to a body moved by the first `from_level`
    /// free axes only, for the step `delta` (from level 0: how far any point of it moves).
    #[inline]
    pub fn relative(&self, q: usize, from_level: usize, delta: &[f64]) -> f64 {
        let row = &self.w[q * self.dof..(q + 1) * self.dof];
        row[from_level.min(self.dof)..]
            .iter()
            .zip(&delta[from_level.min(self.dof)..])
            .map(|(w, d)| w * d.abs())
            .sum()
    }

    /// The factors `w_bj` of body `b`, one per free axis (0 for the axes that do not move it).
    #[inline]
    pub fn factors(&self, b: usize) -> &[f64] {
        &self.w[b * self.dof..(b + 1) * self.dof]
    }

    /// For free axis `j`: the column of the rotation of the frame after it
    /// ([`crate::kinematics::Frames::axis_frames`]) that is its direction, and whether the axis
    /// is a rotation (else a translation along it).
    #[inline]
    pub fn axis_column(&self, j: usize) -> (usize, bool) {
        self.column[j]
    }

    /// The free axes in runs of one link each (ranges of axis indices, in order).
    #[inline]
    pub fn groups(&self) -> &[(usize, usize)] {
        &self.groups
    }

    /// Per run of [`MotionBounds::groups`]: body `b`'s factor `w_bj` for the run's rotation
    /// axes (all equal; 0 for runs that do not move the body).
    #[inline]
    pub fn group_factors(&self, b: usize) -> &[f64] {
        let n = self.groups.len();
        &self.group_w[b * n..(b + 1) * n]
    }

    /// How many runs of [`MotionBounds::groups`] move body `b` (all before its level), or
    /// `None` when its level falls inside a run.
    #[inline]
    pub fn body_runs(&self, b: usize) -> Option<usize> {
        self.body_runs[b]
    }

    /// How many levels per body the bounds of a step are kept for: one per run of
    /// [`MotionBounds::groups`] and one for `dof` (every level `0 ..= dof` when some body's
    /// level splits a run).
    #[inline]
    pub fn slots(&self) -> usize {
        self.slots
    }

    /// The row among [`MotionBounds::slots`] of level `level` (0, a body's level or `dof`).
    #[inline]
    pub fn slot(&self, level: usize) -> usize {
        self.slot[level]
    }

    /// True when some body's bounds are computed link by link ([`MotionBounds::body_runs`]).
    #[inline]
    pub fn grouped(&self) -> bool {
        self.grouped
    }

    /// Per run of [`MotionBounds::groups`]: [`MotionBounds::slot`] of its first axis.
    #[inline]
    pub fn run_slots(&self) -> &[usize] {
        &self.run_slots
    }

    /// Number of free axes covered.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Number of bodies covered.
    pub fn bodies(&self) -> usize {
        self.bodies
    }
}
