//! The allowed-collision matrix: which pairs of robot bodies are never checked against each
//! other, computed the way MoveIt's setup assistant fills an SRDF
//! (`compute_default_collisions.cpp`), with one difference: pairs that merely never collided in
//! random samples stay enabled (sampling proves nothing, and such pairs are cheap to bound).
//!
//! The unit is the URDF link that carries bodies (its *frame*, see
//! [`super::model::RobotBody::frame`]). Two frames are
//! - **Adjacent** when no other body-carrying frame lies between them along the chain (they
//!   share a joint, possibly through links without geometry), or when no free axis lies between
//!   them (they are rigidly connected);
//! - **Default** when their bodies are in contact at the home pose;
//! - **Always** when their bodies are in contact in at least [`ALWAYS_FRACTION`] of
//!   [`SelfCollisionConfig::samples`] random configurations (drawn with
//!   [`SelfCollisionConfig::seed`]; a sampling that reaches
//!   [`crate::limits::MAX_SELF_COLLISION_WORK`] stops, and the pairs it has not decided stay
//!   checked: a few samples cannot tell a pair always in contact from one often in contact);
//! - **User** when the scenario lists their links in `allowed_collisions`.
//!
//! Every other pair of bodies on frames moved by different free axes is checked at nodes and
//! along edges. Bodies on frames that never move relative to each other and are apart at home
//! can never collide and are not checked. A capsule pair of links at least two apart whose
//! *cores* (the segments themselves) meet at home is a real fold of the arm through itself,
//! not a joint housing: its frames are never disabled (neither Default nor Always), so the SRDF
//! leaves the pair enabled and MoveIt, or any checker that loads it, sees the home pose in
//! collision as the planner does; [`AllowedCollisions::home_fold`] reports it, and the planner
//! gives such a design `R = 0`.

use super::model::{Placed, RobotBody};
use crate::kinematics::{Chain, Frames};
use nalgebra::Point3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Share of random configurations in contact above which a pair is "Always" in collision
/// (MoveIt's default threshold).
pub const ALWAYS_FRACTION: f64 = 0.95;

/// Core distance (m) at or below which two capsule cores count as crossing.
pub const FOLD_TOLERANCE: f64 = 1e-9;

/// Self-collision settings (the `[robot]` keys `self_collision`, `allowed_collisions` and
/// `self_collision_samples`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SelfCollisionConfig {
    /// Check self-collision at all. Default true.
    pub enabled: bool,
    /// Pairs of chain links (from 1; 0 is the base) never checked against each other.
    pub allowed: Vec<[usize; 2]>,
    /// Random configurations sampled for the "Always" rule. Default 1000.
    pub samples: usize,
    /// Seed of those samples. Default 0.
    pub seed: u64,
}

impl Default for SelfCollisionConfig {
    fn default() -> Self {
        SelfCollisionConfig {
            enabled: true,
            allowed: Vec::new(),
            samples: 1000,
            seed: 0,
        }
    }
}

impl SelfCollisionConfig {
    /// Self-collision switched off.
    pub fn off() -> Self {
        SelfCollisionConfig {
            enabled: false,
            ..Self::default()
        }
    }
}

/// Why a pair of frames is never checked (the SRDF's `reason` attribute).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Reason {
    /// The frames share a joint, or are rigidly connected.
    Adjacent,
    /// In contact at the home pose.
    Default,
    /// In contact in at least [`ALWAYS_FRACTION`] of the random samples.
    Always,
    /// Listed by the user (`allowed_collisions`, an SRDF, or self-collision off).
    User,
}

impl Reason {
    /// The SRDF spelling.
    pub fn name(self) -> &'static str {
        match self {
            Reason::Adjacent => "Adjacent",
            Reason::Default => "Default",
            Reason::Always => "Always",
            Reason::User => "User",
        }
    }
}

/// A pair of frames (URDF links) never checked against each other.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DisabledPair {
    /// First URDF link (the one nearer the base).
    pub link1: String,
    /// Second URDF link.
    pub link2: String,
    /// Why.
    pub reason: Reason,
}

/// The allowed-collision matrix of a robot body and the body pairs left to check.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AllowedCollisions {
    disabled: Vec<DisabledPair>,
    pairs: Vec<(u32, u32)>,
    home_fold: Option<(usize, usize)>,
    /// Random configurations sampled for the "Always" rule, and whether sampling stopped
    /// before [`SelfCollisionConfig::samples`] at [`crate::limits::MAX_SELF_COLLISION_WORK`].
    sampled: usize,
    work_limited: bool,
}

/// One body-carrying frame: its name, the free axes moving it, its bodies.
struct Group {
    name: String,
    level: usize,
    bodies: Vec<usize>,
}

/// Which pairs of body groups are in contact at a configuration: every body pair of the
/// groups listed ([`Contacts::list`]), culled by bounding balls, then measured exactly, pairs
/// of capsules four at a time on vector lanes (the same values as one by one). Buffers reused
/// from one configuration to the next.
#[derive(Default)]
struct Contacts {
    /// Per body pair of the listed group pairs: (group pair, body, body).
    pairs: Vec<(usize, u32, u32)>,
    /// Those whose balls meet at the configuration measured last.
    near: Vec<(usize, u32, u32)>,
    /// Per listed group pair: in contact at the configuration measured last.
    hit: Vec<bool>,
    /// Work done so far, in the units of [`crate::limits::MAX_SELF_COLLISION_WORK`].
    work: u64,
}

impl Contacts {
    /// Lists the body pairs of the group pairs `(i, j)` of `groups`, numbered in order.
    fn list(&mut self, groups: &[Group], group_pairs: impl Iterator<Item = (usize, usize)>) {
        self.pairs.clear();
        for (k, (i, j)) in group_pairs.enumerate() {
            for &p in &groups[i].bodies {
                for &q in &groups[j].bodies {
                    self.pairs.push((k, p as u32, q as u32));
                }
            }
        }
    }

    /// Fills `hit` for the `count` listed group pairs at the configuration of `frames`,
    /// `placed` and `balls`: a group pair is in contact when one of its body pairs' balls meet
    /// and their distance is `≤ 0`.
    fn measure(
        &mut self,
        body: &RobotBody,
        frames: &Frames,
        placed: &Placed,
        balls: &[(Point3<f64>, f64)],
        count: usize,
    ) {
        // Without a branch per pair: every pair is written, and kept when its balls meet.
        self.near.resize(self.pairs.len(), (0, 0, 0));
        let mut kept = 0;
        for &(k, p, q) in &self.pairs {
            let ((cp, rp), (cq, rq)) = (balls[p as usize], balls[q as usize]);
            let gap = rp + rq;
            self.near[kept] = (k, p, q);
            kept += usize::from((cp - cq).norm_squared() <= gap * gap);
        }
        self.near.truncate(kept);
        self.work += self.pairs.len() as u64 + 64 * kept as u64;
        self.hit.clear();
        self.hit.resize(count, false);
        for block in self.near.chunks(4) {
            let pair = |i: usize| {
                let (_, p, q) = block[i.min(block.len() - 1)];
                (p, q)
            };
            let batch = [pair(0), pair(1), pair(2), pair(3)];
            let d = body
                .capsule_pair_distances(frames, batch)
                .unwrap_or_else(|| {
                    batch.map(|(p, q)| body.pair_distance(frames, placed, p as usize, q as usize))
                });
            for (&(k, _, _), d) in block.iter().zip(d) {
                self.hit[k] |= d <= 0.0;
            }
        }
    }
}

impl AllowedCollisions {
    /// The frame pairs never checked, with their reasons, in chain order.
    pub fn disabled(&self) -> &[DisabledPair] {
        &self.disabled
    }

    /// Body pairs `(p, q)` checked for self-collision, `level(p) ≤ level(q)`.
    pub fn pairs(&self) -> &[(u32, u32)] {
        &self.pairs
    }

    /// The chain links of a capsule pair whose cores cross at home (a fold of the arm through
    /// itself), if any.
    pub fn home_fold(&self) -> Option<(usize, usize)> {
        self.home_fold
    }

    /// How many random configurations the "Always" rule sampled (at most
    /// [`SelfCollisionConfig::samples`]; none when no pair was in question).
    pub fn samples_taken(&self) -> usize {
        self.sampled
    }

    /// Whether the sampling stopped before its configured count, at
    /// [`crate::limits::MAX_SELF_COLLISION_WORK`], after [`Self::samples_taken`] samples: the
    /// pairs it had not decided then stay checked (none of them is "Always").
    pub fn work_limited(&self) -> bool {
        self.work_limited
    }

    /// The matrix of `body` on `chain` (see the module documentation).
    pub fn compute(chain: &Chain, body: &RobotBody, config: &SelfCollisionConfig) -> Self {
        let mut groups: Vec<Group> = Vec::new();
        for b in 0..body.len() {
            match groups.iter_mut().find(|g| g.name == body.frame(b)) {
                Some(g) => {
                    g.level = g.level.min(body.level(b));
                    g.bodies.push(b);
                }
                None => groups.push(Group {
                    name: body.frame(b).to_string(),
                    level: body.level(b),
                    bodies: vec![b],
                }),
            }
        }
        // Chain order: by level, stable in body order.
        groups.sort_by_key(|g| g.level);
        let n = groups.len();
        let mut reason: Vec<Option<Reason>> = vec![None; n * n];
        let idx = |i: usize, j: usize| i.min(j) * n + i.max(j);
        if !config.enabled {
            for i in 0..n {
                for j in i + 1..n {
                    reason[idx(i, j)] = Some(Reason::User);
                }
            }
        }
        for i in 0..n {
            for j in i + 1..n {
                if reason[idx(i, j)].is_none() && (j == i + 1 || groups[i].level == groups[j].level)
                {
                    reason[idx(i, j)] = Some(Reason::Adjacent);
                }
            }
        }
        for &[a, b] in &config.allowed {
            for i in 0..n {
                for j in i + 1..n {
                    let has = |g: &Group, l: usize| g.bodies.iter().any(|&x| body.link(x) == l);
                    let hit = (has(&groups[i], a) && has(&groups[j], b))
                        || (has(&groups[i], b) && has(&groups[j], a));
                    if hit && reason[idx(i, j)].is_none() {
                        reason[idx(i, j)] = Some(Reason::User);
                    }
                }
            }
        }
        let mut frames = chain.frames();
        let mut placed = Placed::default();
        let mut balls = Vec::with_capacity(body.len());
        chain.fk(chain.home(), &mut frames);
        body.place(&frames, &mut placed);
        body.balls(&frames, &placed, &mut balls);
        let mut contacts = Contacts::default();
        // A contact at home disables the pair ("Default"), unless it is a fold: then the pair
        // stays enabled (and out of "Always"), so that the SRDF and every checker see the home
        // pose in collision, as the planner does.
        let mut home_fold = None;
        let mut folded = vec![false; n * n];
        let open: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .filter(|&(i, j)| reason[idx(i, j)].is_none())
            .collect();
        contacts.list(&groups, open.iter().copied());
        contacts.measure(body, &frames, &placed, &balls, open.len());
        for (&(i, j), _) in open.iter().zip(&contacts.hit).filter(|(_, &h)| h) {
            let fold = groups[i].bodies.iter().find_map(|&p| {
                groups[j].bodies.iter().find_map(|&q| {
                    let apart = body.link(p).abs_diff(body.link(q)) >= 2;
                    (apart
                        && body
                            .core_distance(&frames, p, q)
                            .is_some_and(|d| d <= FOLD_TOLERANCE))
                    .then(|| (body.link(p), body.link(q)))
                })
            });
            match fold {
                Some(links) => {
                    folded[idx(i, j)] = true;
                    home_fold.get_or_insert(links);
                }
                None => reason[idx(i, j)] = Some(Reason::Default),
            }
        }
        // "Always": candidates are the pairs still enabled and moving relative to each other.
        let mut candidates: Vec<(usize, usize, usize, usize)> = Vec::new(); // i, j, hits, misses
        for i in 0..n {
            for j in i + 1..n {
                if reason[idx(i, j)].is_none()
                    && !folded[idx(i, j)]
                    && groups[i].level != groups[j].level
                {
                    candidates.push((i, j, 0, 0));
                }
            }
        }
        let samples = config.samples;
        let max_misses = ((1.0 - ALWAYS_FRACTION) * samples as f64).floor() as usize;
        let (mut sampled, mut work_limited) = (0, false);
        if samples > 0 && chain.dof() > 0 && !candidates.is_empty() {
            let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
            let mut q = vec![0.0; chain.dof()];
            // The candidates' body pairs are listed again only when a candidate drops out.
            let mut listed = usize::MAX;
            // The home pose's measure does not count against the sampling's work.
            contacts.work = 0;
            for _ in 0..samples {
                if candidates.is_empty() {
                    break;
                }
                if contacts.work >= crate::limits::MAX_SELF_COLLISION_WORK {
                    work_limited = true;
                    break;
                }
                sampled += 1;
                if listed != candidates.len() {
                    listed = candidates.len();
                    contacts.list(&groups, candidates.iter().map(|c| (c.0, c.1)));
                }
                chain.sample_config(&mut rng, &mut q);
                chain.fk(&q, &mut frames);
                body.place(&frames, &mut placed);
                body.balls(&frames, &placed, &mut balls);
                contacts.measure(body, &frames, &placed, &balls, candidates.len());
                for (c, &h) in candidates.iter_mut().zip(&contacts.hit) {
                    if h {
                        c.2 += 1;
                    } else {
                        c.3 += 1;
                    }
                }
                candidates.retain(|c| c.3 <= max_misses);
            }
            // "Always" only from every sample asked for: when the work limit stopped the
            // sampling, the pairs still in question stay checked (19 samples all in contact
            // would disable a pair in contact in 90 % of configurations one time in seven).
            for c in candidates {
                if c.2 as f64 >= ALWAYS_FRACTION * samples as f64 {
                    reason[idx(c.0, c.1)] = Some(Reason::Always);
                }
            }
        }
        let mut disabled = Vec::new();
        let mut pairs = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                match reason[idx(i, j)] {
                    Some(r) => disabled.push(DisabledPair {
                        link1: groups[i].name.clone(),
                        link2: groups[j].name.clone(),
                        reason: r,
                    }),
                    None if groups[i].level == groups[j].level => {}
                    None => {
                        for &p in &groups[i].bodies {
                            for &q in &groups[j].bodies {
                                let (p, q) = if body.level(p) <= body.level(q) {
                                    (p, q)
                                } else {
                                    (q, p)
                                };
                                if body.level(p) != body.level(q) {
                                    pairs.push((p as u32, q as u32));
                                }
                            }
                        }
                    }
                }
            }
        }
        pairs.sort_unstable();
        AllowedCollisions {
            disabled,
            pairs,
            home_fold,
            sampled,
            work_limited,
        }
    }

    /// Disables every pair of frames named in `extra` (for example from an SRDF), with its
    /// reason, and drops the body pairs between them from the checked list. A pair already
    /// disabled (in either order) keeps its first reason. Linear in the pairs: an SRDF may
    /// list hundreds of thousands.
    pub fn disable(&mut self, body: &RobotBody, extra: &[DisabledPair]) {
        use std::collections::HashSet;
        fn key<'a>(a: &'a str, b: &'a str) -> (&'a str, &'a str) {
            if a <= b {
                (a, b)
            } else {
                (b, a)
            }
        }
        let mut known: HashSet<(String, String)> = self
            .disabled
            .iter()
            .map(|e| {
                let (a, b) = key(&e.link1, &e.link2);
                (a.to_string(), b.to_string())
            })
            .collect();
        let mut off: HashSet<(&str, &str)> = HashSet::with_capacity(extra.len());
        for d in extra {
            let (a, b) = key(&d.link1, &d.link2);
            off.insert((a, b));
            if known.insert((a.to_string(), b.to_string())) {
                self.disabled.push(d.clone());
            }
        }
        self.pairs.retain(|&(p, q)| {
            let k = key(body.frame(p as usize), body.frame(q as usize));
            !off.contains(&k)
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::preset::{generate, Preset};
    use crate::Scenario;

    /// Disabling pairs from a list (an SRDF's) drops exactly the body pairs between the named
    /// frames, in either order, adds each frame pair once with its first reason, and a list
    /// that repeats its pairs thousands of times gives the same matrix as the list once.
    #[test]
    fn disabling_pairs_drops_them_once_whatever_the_repeats() {
        let s = Scenario::from_spec(&generate(Preset::Paper3d, 2)).unwrap();
        let chain = s.space.largest().chain();
        let body = RobotBody::of_chain(&chain);
        let acm = body.acm().clone();
        let &(p, q) = acm.pairs().last().unwrap();
        let (a, b) = (body.frame(p as usize), body.frame(q as usize));
        let &(p2, q2) = acm.pairs().first().unwrap();
        let (c, d) = (body.frame(p2 as usize), body.frame(q2 as usize));
        assert!((a, b) != (c, d));
        let pair = |l1: &str, l2: &str, reason| DisabledPair {
            link1: l1.to_string(),
            link2: l2.to_string(),
            reason,
        };
        let once = vec![pair(b, a, Reason::User), pair(c, d, Reason::Default)];
        let mut repeated = Vec::new();
        for _ in 0..5000 {
            repeated.push(pair(a, b, Reason::Always));
            repeated.extend(once.iter().cloned());
        }
        let mut x = acm.clone();
        x.disable(&body, &once);
        let mut y = acm.clone();
        y.disable(&body, &repeated);
        assert_eq!(x.pairs(), y.pairs());
        assert_eq!(x.disabled().len(), acm.disabled().len() + 2);
        assert_eq!(y.disabled().len(), acm.disabled().len() + 2);
        let reason = |m: &AllowedCollisions| {
            let e = m
                .disabled()
                .iter()
                .find(|e| (e.link1 == a && e.link2 == b) || (e.link1 == b && e.link2 == a));
            e.unwrap().reason
        };
        // The first mention of a frame pair gives its reason.
        assert_eq!(reason(&x), Reason::User);
        assert_eq!(reason(&y), Reason::Always);
        let between = |m: &AllowedCollisions, f: &str, g: &str| {
            m.pairs().iter().any(|&(p, q)| {
                let (p, q) = (body.frame(p as usize), body.frame(q as usize));
                (p, q) == (f, g) || (p, q) == (g, f)
            })
        };
        assert!(between(&acm, a, b) && between(&acm, c, d));
        assert!(!between(&y, a, b) && !between(&y, c, d));
        let kept: Vec<_> = acm
            .pairs()
            .iter()
            .filter(|&&(p, q)| {
                let k = (body.frame(p as usize), body.frame(q as usize));
                ![(a, b), (b, a), (c, d), (d, c)].contains(&k)
            })
            .copied()
            .collect();
        assert_eq!(y.pairs(), &kept[..]);
    }
}
