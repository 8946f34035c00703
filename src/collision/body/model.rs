//! The one robot body model: every rigid collision body of a chain, as the node checks, the four
//! edge checkers, the oracle, the motion bounds of `certified` and the URDF/SRDF export see it.
//!
//! A body is either
//! - a **capsule segment** of the chain ([`crate::kinematics::Frames::segments`]): the DH body
//!   polyline of a link, a constant translation piece, or the fixed-length rod of a prismatic
//!   axis ([`Chain::slider_rod`]), with its own radius; or
//! - a **solid**: a convex polyhedron (a URDF mesh's convex hull), a box, a cylinder or a
//!   sphere, rigidly attached to the frame right after some free axis (or to the base).
//!
//! Bodies are numbered segments first (in [`crate::kinematics::Frames::segments`] order), then
//! solids. Each one knows the free axes that move it (a prefix of the actuation vector, its
//! *level*), the chain link that owns it, and the URDF link that carries it (its *frame*), which
//! is what the allowed-collision matrix and the SRDF speak of.

use super::super::scene::CollisionScene;
use super::acm::{AllowedCollisions, SelfCollisionConfig};
use crate::kinematics::{Chain, Frames};
use crate::world::convert::{from_parry_point, to_parry_point, to_parry_pose};
use nalgebra::{IsometryMatrix3, Point3};
use parry3d_f64::math::Pose;
use parry3d_f64::query;
use parry3d_f64::shape::{Capsule, SharedShape};

/// A rigid body other than a capsule segment, attached to a frame of the chain.
#[derive(Clone)]
pub struct Solid {
    /// Moved by the first `level` free axes: it rides on the frame right after free axis
    /// `level − 1` ([`Frames::axis_frames`]), or on the base `F_0` when `level` is 0.
    pub level: usize,
    /// Its pose in that carrier frame.
    pub local: IsometryMatrix3<f64>,
    /// The shape (parry): convex polyhedron, cuboid, cylinder or ball.
    pub shape: SharedShape,
    /// Chain link (from 1; 0 for the base) that owns it, for messages.
    pub link: usize,
    /// Name of the URDF link that carries it.
    pub frame: String,
    /// Centre of its bounding sphere, in the carrier frame.
    pub center: Point3<f64>,
    /// Radius of its bounding sphere.
    pub radius: f64,
}

impl std::fmt::Debug for Solid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Solid")
            .field("level", &self.level)
            .field("link", &self.link)
            .field("frame", &self.frame)
            .field("shape", &self.shape.shape_type())
            .field("radius", &self.radius)
            .finish()
    }
}

impl Solid {
    /// A solid of `shape` at `local` in the carrier frame of `level`, owned by chain link
    /// `link` and carried by the URDF link `frame`.
    pub fn new(
        level: usize,
        local: IsometryMatrix3<f64>,
        shape: SharedShape,
        link: usize,
        frame: String,
    ) -> Self {
        let bs = shape.compute_bounding_sphere(&to_parry_pose(&local));
        Solid {
            level,
            local,
            shape,
            link,
            frame,
            center: from_parry_point(bs.center()),
            radius: bs.radius(),
        }
    }

    /// Largest distance from the carrier frame's origin to a point of the solid.
    pub fn reach_from_origin(&self) -> f64 {
        self.center.coords.norm() + self.radius
    }
}

/// The robot body of a chain: capsule radii, solids, and the self-collision pairs to check.
#[derive(Clone, Debug)]
pub struct RobotBody {
    radii: Vec<f64>,
    solids: Vec<Solid>,
    levels: Vec<usize>,
    links: Vec<usize>,
    /// Per body, the chain links forward kinematics must evaluate to place it.
    fk_links: Vec<usize>,
    frames: Vec<String>,
    acm: AllowedCollisions,
    /// How the self pairs are measured ([`RobotBody::measure_block`]), and each pair's block.
    pair_blocks: Vec<PairBlock>,
    block_of_pair: Vec<u32>,
}

/// A block of self pairs measured at once by [`RobotBody::measure_block`], as indices into
/// [`RobotBody::self_pairs`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PairBlock {
    /// Four pairs of two capsules, measured on vector lanes (a last block of fewer pairs is
    /// filled up with copies of its last one).
    Capsules([u32; 4]),
    /// One pair with a solid.
    Other(u32),
}

/// World placement of the solids at one configuration (reused buffer).
#[derive(Clone, Debug, Default)]
pub struct Placed {
    /// World pose of each solid.
    pub poses: Vec<Pose>,
    /// World centre of each solid's bounding sphere.
    pub centers: Vec<Point3<f64>>,
}

impl RobotBody {
    /// The body of `chain`: a capsule of the chain's radius around every segment, then
    /// `solids`, with the allowed-collision matrix computed by `self_collision`.
    pub fn new(chain: &Chain, solids: Vec<Solid>, self_collision: &SelfCollisionConfig) -> Self {
        let radii = vec![chain.radius(); chain.segment_count()];
        Self::with_radii(chain, radii, solids, self_collision)
    }

    /// As [`RobotBody::new`] with one radius per segment.
    pub fn with_radii(
        chain: &Chain,
        radii: Vec<f64>,
        solids: Vec<Solid>,
        self_collision: &SelfCollisionConfig,
    ) -> Self {
        let mut levels = Vec::new();
        let mut links = Vec::new();
        let mut frames = Vec::new();
        for s in 0..chain.segment_count() {
            let i = chain.segment_info(s);
            levels.push(i.level);
            links.push(i.link);
            frames.push(i.frame.clone());
        }
        let mut fk_links = links.clone();
        for s in &solids {
            levels.push(s.level);
            links.push(s.link);
            // The carrier frame of a solid is that of free axis `level − 1`.
            let carrier = match s.level {
                0 => 0,
                l => chain
                    .free_axes()
                    .get(l - 1)
                    .map_or(chain.link_count(), |f| f.link),
            };
            fk_links.push(s.link.max(carrier).min(chain.link_count()));
            frames.push(s.frame.clone());
        }
        let mut body = RobotBody {
            radii,
            solids,
            levels,
            links,
            fk_links,
            frames,
            acm: AllowedCollisions::default(),
            pair_blocks: Vec::new(),
            block_of_pair: Vec::new(),
        };
        body.acm = AllowedCollisions::compute(chain, &body, self_collision);
        body.index_pairs();
        body
    }

    /// Sorts the self pairs into blocks: four pairs of capsules, in their order, or one
    /// other pair.
    fn index_pairs(&mut self) {
        let ns = self.radii.len();
        let pairs = self.acm.pairs();
        self.pair_blocks.clear();
        self.block_of_pair = vec![0; pairs.len()];
        let mut held: Vec<u32> = Vec::with_capacity(4);
        let close = |held: &mut Vec<u32>, blocks: &mut Vec<PairBlock>, of: &mut [u32]| {
            if let Some(&last) = held.last() {
                for &i in held.iter() {
                    of[i as usize] = blocks.len() as u32;
                }
                let at = |k: usize| held.get(k).copied().unwrap_or(last);
                blocks.push(PairBlock::Capsules(std::array::from_fn(at)));
                held.clear();
            }
        };
        for (i, &(p, q)) in pairs.iter().enumerate() {
            if (p as usize) < ns && (q as usize) < ns {
                held.push(i as u32);
                if held.len() == 4 {
                    close(&mut held, &mut self.pair_blocks, &mut self.block_of_pair);
                }
            } else {
                self.block_of_pair[i] = self.pair_blocks.len() as u32;
                self.pair_blocks.push(PairBlock::Other(i as u32));
            }
        }
        close(&mut held, &mut self.pair_blocks, &mut self.block_of_pair);
    }

    /// The blocks in which [`RobotBody::measure_block`] measures the self pairs.
    pub fn pair_blocks(&self) -> &[PairBlock] {
        &self.pair_blocks
    }

    /// The block of self pair `i` (an index into [`RobotBody::self_pairs`]).
    #[inline]
    pub fn block_of_pair(&self, i: usize) -> usize {
        self.block_of_pair[i] as usize
    }

    /// The capsule body of `chain` with the default self-collision settings.
    pub fn of_chain(chain: &Chain) -> Self {
        Self::capsules(chain, &SelfCollisionConfig::default())
    }

    /// The capsule body of `chain` (its links' segments, no solids) with the self-collision
    /// settings `config`: the body a planner run of a design checks, and the one its SRDF and
    /// report describe (also an imported arm's body under `--body capsules`).
    pub fn capsules(chain: &Chain, config: &SelfCollisionConfig) -> Self {
        Self::new(chain, Vec::new(), config)
    }

    /// Number of bodies (segments, then solids).
    pub fn len(&self) -> usize {
        self.levels.len()
    }

    /// True when the robot has no body at all.
    pub fn is_empty(&self) -> bool {
        self.levels.is_empty()
    }

    /// Number of capsule segments (bodies `0 … segments − 1`).
    pub fn segments(&self) -> usize {
        self.radii.len()
    }

    /// The solids (bodies `segments() …`).
    pub fn solids(&self) -> &[Solid] {
        &self.solids
    }

    /// Radius of capsule segment `s`.
    pub fn radius(&self, s: usize) -> f64 {
        self.radii[s]
    }

    /// Free axes moving body `b`: the first `level(b)` of the actuation vector.
    pub fn level(&self, b: usize) -> usize {
        self.levels[b]
    }

    /// Chain link (from 1; 0 for the base) owning body `b`.
    pub fn link(&self, b: usize) -> usize {
        self.links[b]
    }

    /// How many chain links forward kinematics must evaluate ([`Chain::fk_links`]) for body
    /// `b` to be placed: its segment or its carrier frame lies in them.
    pub fn fk_links(&self, b: usize) -> usize {
        self.fk_links[b]
    }

    /// URDF link carrying body `b`.
    pub fn frame(&self, b: usize) -> &str {
        &self.frames[b]
    }

    /// The allowed-collision matrix and the self pairs checked.
    pub fn acm(&self) -> &AllowedCollisions {
        &self.acm
    }

    /// Never checks the frame pairs of `extra` against each other (for example the
    /// `<disable_collisions>` of an SRDF), on top of the computed matrix.
    pub fn disable_pairs(&mut self, extra: &[super::acm::DisabledPair]) {
        let mut acm = std::mem::take(&mut self.acm);
        acm.disable(self, extra);
        self.acm = acm;
        self.index_pairs();
    }

    /// The self-collision pairs checked, as body indices `(p, q)` with `level(p) ≤ level(q)`.
    pub fn self_pairs(&self) -> &[(u32, u32)] {
        self.acm.pairs()
    }

    /// Places the solids at the configuration whose frames are in `frames`.
    pub fn place(&self, frames: &Frames, out: &mut Placed) {
        out.poses.clear();
        out.centers.clear();
        for s in &self.solids {
            let carrier = if s.level == 0 {
                &frames.frames[0]
            } else {
                &frames.axis_frames[s.level - 1]
            };
            let world = carrier * s.local;
            out.poses.push(to_parry_pose(&world));
            out.centers.push(carrier * s.center);
        }
    }

    /// As [`RobotBody::place`] for the solids within the first `links` chain links only
    /// ([`RobotBody::fk_links`], for frames from [`Chain::fk_links`]); the others keep their
    /// previous placement (or the identity, when `out` held none).
    pub fn place_links(&self, frames: &Frames, out: &mut Placed, links: usize) {
        let n = self.solids.len();
        if out.poses.len() != n {
            out.poses.clear();
            out.poses.resize(n, Pose::identity());
            out.centers.clear();
            out.centers.resize(n, Point3::origin());
        }
        let ns = self.radii.len();
        for (i, s) in self.solids.iter().enumerate() {
            if self.fk_links[ns + i] > links {
                continue;
            }
            let carrier = if s.level == 0 {
                &frames.frames[0]
            } else {
                &frames.axis_frames[s.level - 1]
            };
            out.poses[i] = to_parry_pose(&(carrier * s.local));
            out.centers[i] = carrier * s.center;
        }
    }

    /// Bounding ball of body `b` (centre, radius).
    #[inline]
    pub fn ball(&self, frames: &Frames, placed: &Placed, b: usize) -> (Point3<f64>, f64) {
        let ns = self.radii.len();
        if b < ns {
            let [p, q] = frames.segments[b];
            (
                nalgebra::center(&p, &q),
                0.5 * (q - p).norm() + self.radii[b],
            )
        } else {
            (placed.centers[b - ns], self.solids[b - ns].radius)
        }
    }

    /// Distance between body `b` and obstacle `k` (signed for closed forms, 0 when touching
    /// for parry's shapes; `≤ ε` is a collision).
    #[inline]
    pub fn obstacle_distance(
        &self,
        scene: &CollisionScene,
        frames: &Frames,
        placed: &Placed,
        b: usize,
        k: usize,
    ) -> f64 {
        self.obstacle_distance_below(scene, frames, placed, b, k, f64::INFINITY)
    }

    /// Signed distance between body `b` and obstacle `k`: [`RobotBody::obstacle_distance`], and
    /// where that is 0 (parry's shapes do not say how deep they overlap), minus the penetration
    /// depth from parry's contact query. For reporting a collision, not for checking.
    pub fn obstacle_signed_distance(
        &self,
        scene: &CollisionScene,
        frames: &Frames,
        placed: &Placed,
        b: usize,
        k: usize,
    ) -> f64 {
        let d = self.obstacle_distance(scene, frames, placed, b, k);
        if d != 0.0 {
            return d;
        }
        let ns = self.radii.len();
        if b < ns {
            let [p, q] = &frames.segments[b];
            let capsule = Capsule::new(to_parry_point(p), to_parry_point(q), self.radii[b]);
            scene.shape_signed_distance(k, &Pose::IDENTITY, &capsule)
        } else {
            let m = b - ns;
            scene.shape_signed_distance(k, &placed.poses[m], self.solids[m].shape.as_ref())
        }
    }

    /// [`RobotBody::obstacle_distance`] when it is below `cap`, otherwise some value `≥ cap`
    /// ([`CollisionScene::distance_below`]).
    #[inline]
    pub fn obstacle_distance_below(
        &self,
        scene: &CollisionScene,
        frames: &Frames,
        placed: &Placed,
        b: usize,
        k: usize,
        cap: f64,
    ) -> f64 {
        let ns = self.radii.len();
        if b < ns {
            let [p, q] = &frames.segments[b];
            scene.distance_below(k, p, q, self.radii[b], cap)
        } else {
            let m = b - ns;
            scene.shape_distance(k, &placed.poses[m], self.solids[m].shape.as_ref())
        }
    }

    /// Bounding balls of every body at one configuration, written to `out` (cleared first).
    #[inline]
    pub fn balls(&self, frames: &Frames, placed: &Placed, out: &mut Vec<(Point3<f64>, f64)>) {
        out.clear();
        out.extend((0..self.len()).map(|b| self.ball(frames, placed, b)));
    }

    /// Clearance of body `b` (bounding ball `ball`) from the obstacles: `min(cap, min_k
    /// distance(b, k) − ε)`, exact when below `cap` and never above the true clearance
    /// ([`CollisionScene::nearest`]), with the nearest obstacle when it is below `cap`
    /// (`u32::MAX` otherwise). `hint` (an obstacle index, or `u32::MAX`) is tried first: the
    /// obstacle nearest at a close-by configuration prunes the search best. `≤ 0` is a
    /// collision.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub fn clearance(
        &self,
        scene: &CollisionScene,
        frames: &Frames,
        placed: &Placed,
        b: usize,
        ball: &(Point3<f64>, f64),
        cap: f64,
        hint: u32,
    ) -> (f64, u32) {
        let eps = scene.clearance();
        let ns = self.radii.len();
        if b < ns {
            // A scene of few spheres: every one measured at once, but those beyond the cap.
            let [p, q] = &frames.segments[b];
            if let Some((d, k)) = scene.sphere_nearest(p, q, self.radii[b], cap + eps) {
                return (d - eps, k);
            }
        }
        let mut cap = cap + eps;
        let mut best = u32::MAX;
        if (hint as usize) < scene.len() {
            let d = self.obstacle_distance(scene, frames, placed, b, hint as usize);
            if d < cap {
                cap = d;
                best = hint;
            }
        }
        let (d, k) = scene.nearest(&ball.0, ball.1, cap, hint, |k, below| {
            self.obstacle_distance_below(scene, frames, placed, b, k, below)
        });
        (d - eps, if k == u32::MAX { best } else { k })
    }

    /// A lower bound of the distance between body `b` and obstacle `k` from their bounding
    /// spheres.
    #[inline]
    pub fn obstacle_lower_bound(
        &self,
        scene: &CollisionScene,
        frames: &Frames,
        placed: &Placed,
        b: usize,
        k: usize,
    ) -> f64 {
        let ns = self.radii.len();
        if b < ns {
            let [p, q] = &frames.segments[b];
            scene.lower_bound(k, p, q, self.radii[b])
        } else {
            let c = placed.centers[b - ns];
            scene.lower_bound(k, &c, &c, self.solids[b - ns].radius)
        }
    }

    /// Distance between bodies `p` and `q` (signed for two capsules; 0 when touching
    /// otherwise; `≤ 0` is a self-collision).
    #[inline]
    pub fn pair_distance(&self, frames: &Frames, placed: &Placed, p: usize, q: usize) -> f64 {
        let ns = self.radii.len();
        match (p < ns, q < ns) {
            (true, true) => {
                let [a, b] = &frames.segments[p];
                let [c, d] = &frames.segments[q];
                super::super::distance::segment_segment(a, b, c, d) - self.radii[p] - self.radii[q]
            }
            (true, false) | (false, true) => {
                let (s, m) = if p < ns { (p, q - ns) } else { (q, p - ns) };
                let [a, b] = &frames.segments[s];
                let cap = Capsule::new(to_parry_point(a), to_parry_point(b), self.radii[s]);
                query::distance(
                    &Pose::IDENTITY,
                    &cap,
                    &placed.poses[m],
                    self.solids[m].shape.as_ref(),
                )
                .map_or(0.0, |d| d.distance)
            }
            (false, false) => {
                let (m, n) = (p - ns, q - ns);
                query::distance(
                    &placed.poses[m],
                    self.solids[m].shape.as_ref(),
                    &placed.poses[n],
                    self.solids[n].shape.as_ref(),
                )
                .map_or(0.0, |d| d.distance)
            }
        }
    }

    /// [`RobotBody::pair_distance`] of the self pairs of block `block`
    /// ([`RobotBody::pair_blocks`]), written to `out` at their indices in
    /// [`RobotBody::self_pairs`] (`out` holds one value per pair): four pairs of capsules at
    /// once on AVX2 vector lanes where the processor has them, with the same values bit for
    /// bit.
    #[inline]
    pub fn measure_block(&self, frames: &Frames, placed: &Placed, block: usize, out: &mut [f64]) {
        let pairs = self.self_pairs();
        match self.pair_blocks[block] {
            PairBlock::Capsules(ids) => {
                let four = ids.map(|i| pairs[i as usize]);
                if let Some(d) = self.capsule_pair_distances(frames, four) {
                    for (&i, d) in ids.iter().zip(d) {
                        out[i as usize] = d;
                    }
                    return;
                }
                for &i in &ids {
                    let (p, q) = pairs[i as usize];
                    out[i as usize] = self.pair_distance(frames, placed, p as usize, q as usize);
                }
            }
            PairBlock::Other(i) => {
                let (p, q) = pairs[i as usize];
                out[i as usize] = self.pair_distance(frames, placed, p as usize, q as usize);
            }
        }
    }

    /// [`RobotBody::pair_distance`] of four pairs of capsules `(p, q)` at once, on AVX2 vector
    /// lanes, with the same values bit for bit; `None` when the processor lacks AVX2 or a body
    /// is not a capsule.
    #[inline]
    pub fn capsule_pair_distances(
        &self,
        frames: &Frames,
        pairs: [(u32, u32); 4],
    ) -> Option<[f64; 4]> {
        let ns = self.radii.len();
        if pairs
            .iter()
            .any(|&(p, q)| p as usize >= ns || q as usize >= ns)
        {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            let segs = &frames.segments;
            let pick = |k: usize| (&segs[pairs[k].0 as usize], &segs[pairs[k].1 as usize]);
            // SAFETY: the processor supports AVX2 (just checked).
            let d2 = unsafe {
                super::super::distance::segment_segment_squared_x4([
                    pick(0),
                    pick(1),
                    pick(2),
                    pick(3),
                ])
            };
            return Some(std::array::from_fn(|k| {
                let (p, q) = pairs[k];
                d2[k].sqrt() - self.radii[p as usize] - self.radii[q as usize]
            }));
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = frames;
        None
    }

    /// Distance between the *cores* of two capsule segments (their segments, without radii);
    /// `None` when either body is a solid.
    pub fn core_distance(&self, frames: &Frames, p: usize, q: usize) -> Option<f64> {
        let ns = self.radii.len();
        (p < ns && q < ns).then(|| {
            let [a, b] = &frames.segments[p];
            let [c, d] = &frames.segments[q];
            super::super::distance::segment_segment(a, b, c, d)
        })
    }

    /// Smallest distance between any body and any obstacle (`+∞` without either).
    pub fn min_obstacle_distance(
        &self,
        scene: &CollisionScene,
        frames: &Frames,
        placed: &Placed,
    ) -> f64 {
        let mut best = f64::INFINITY;
        for b in 0..self.len() {
            for k in 0..scene.len() {
                if self.obstacle_lower_bound(scene, frames, placed, b, k) >= best {
                    continue;
                }
                best = best.min(self.obstacle_distance(scene, frames, placed, b, k));
            }
        }
        best
    }

    /// Smallest distance over the checked self pairs (`+∞` without pairs). Pairs whose
    /// bounding balls are farther apart than the best distance so far are skipped, so the
    /// result is exact.
    pub fn min_self_distance(&self, frames: &Frames, placed: &Placed) -> f64 {
        let mut best = f64::INFINITY;
        for &(p, q) in self.self_pairs() {
            let (p, q) = (p as usize, q as usize);
            let (cp, rp) = self.ball(frames, placed, p);
            let (cq, rq) = self.ball(frames, placed, q);
            if (cp - cq).norm() - rp - rq >= best {
                continue;
            }
            best = best.min(self.pair_distance(frames, placed, p, q));
        }
        best
    }

    /// The first checked self pair in contact at this configuration, if any.
    pub fn self_contact(&self, frames: &Frames, placed: &Placed) -> Option<(usize, usize, f64)> {
        self.self_pairs().iter().find_map(|&(p, q)| {
            let d = self.pair_distance(frames, placed, p as usize, q as usize);
            (d <= 0.0).then_some((p as usize, q as usize, d))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// Measured block by block, every self pair's distance is `pair_distance`'s bit for bit,
    /// with capsules only and with solids among them (pairs measured one by one); every pair
    /// lies in exactly the block `block_of_pair` names.
    #[test]
    fn pair_blocks_measure_every_pair_as_one_by_one() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios/paper-3d.toml");
        let s = crate::Scenario::load(&path).unwrap();
        let chain = s.space.largest().chain();
        let ball = SharedShape::ball(0.05);
        let solid = |level| {
            let local = IsometryMatrix3::translation(0.0, 0.02, 0.1);
            Solid::new(level, local, ball.clone(), 1, "s".into())
        };
        let config = SelfCollisionConfig::default();
        let bodies = [
            RobotBody::new(&chain, Vec::new(), &config),
            RobotBody::new(&chain, vec![solid(2), solid(5)], &config),
        ];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let mut frames = chain.frames();
        let mut placed = Placed::default();
        let mut a = vec![0.0; chain.dof()];
        let (mut out, mut others) = (Vec::new(), 0);
        for body in &bodies {
            let pairs = body.self_pairs();
            assert!(pairs.len() > 20);
            let mut seen = vec![0; pairs.len()];
            for (k, block) in body.pair_blocks().iter().enumerate() {
                let ids: Vec<u32> = match *block {
                    PairBlock::Capsules(ids) => ids.to_vec(),
                    PairBlock::Other(i) => {
                        others += 1;
                        vec![i]
                    }
                };
                let mut ids_once = ids.clone();
                ids_once.dedup();
                for i in ids_once {
                    seen[i as usize] += 1;
                    assert_eq!(body.block_of_pair(i as usize), k);
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
            for _ in 0..200 {
                chain.sample_config(&mut rng, &mut a);
                chain.fk(&a, &mut frames);
                body.place(&frames, &mut placed);
                out.clear();
                out.resize(pairs.len(), f64::NAN);
                for block in 0..body.pair_blocks().len() {
                    body.measure_block(&frames, &placed, block, &mut out);
                }
                for (&d, &(p, q)) in out.iter().zip(pairs) {
                    let want = body.pair_distance(&frames, &placed, p as usize, q as usize);
                    assert_eq!(d.to_bits(), want.to_bits(), "pair ({p}, {q})");
                }
            }
        }
        assert!(others > 0);
    }
}
