//! The obstacles as the edge checkers see them: exact distances with closed forms where the
//! shape allows (spheres, capsules, boxes), fast paths for meshes (convex hulls and the parts of a
//! convex decomposition through GJK with hill-climbing support points, [`ClimbingHull`];
//! triangle meshes through a best-first search of their triangle hierarchy with the closed-form
//! segment–triangle distance), parry's queries elsewhere; and a bounding-volume hierarchy
//! (parry's [`Bvh`] over the obstacles' bounding boxes) as the broad phase, so that a query
//! costs what the obstacles near the body cost, not what all of them cost. A capped query
//! ([`CollisionScene::distance_below`]) stops as soon as an obstacle is proven beyond the cap.

use super::distance::{point_segment, segment_box, segment_segment, segment_triangle};
use super::hull::ClimbingHull;
use crate::world::convert::{from_parry_point, to_parry_point};
use crate::world::{Obstacle, ObstacleShape, Workspace};
use nalgebra::Point3;
use parry3d_f64::math::Pose;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhNode, TraversalAction};
use parry3d_f64::query;
use parry3d_f64::shape::{Ball, Segment, SharedShape};
use std::sync::Arc;

/// How the distance to one obstacle is computed.
#[derive(Clone, Debug)]
enum Exact {
    /// Closed form: a ball.
    Sphere { center: Point3<f64>, radius: f64 },
    /// Closed form: a capsule (segment `a`–`b` swept by `radius`).
    Capsule {
        a: Point3<f64>,
        b: Point3<f64>,
        radius: f64,
    },
    /// A convex hull, through its vertex graph ([`ClimbingHull`]), at its world pose.
    Hull { pose: Pose, hull: Arc<ClimbingHull> },
    /// A convex decomposition: the distance to the nearest part.
    Parts(Arc<[Part]>),
    /// A triangle mesh (a surface) at its world pose: a best-first search of its triangle
    /// hierarchy with the closed-form segment–triangle distance.
    Mesh { pose: Pose },
    /// A box at its world pose, with its half extents: the closed-form segment–box distance.
    Cuboid {
        pose: Pose,
        half: nalgebra::Vector3<f64>,
    },
    /// parry's distance query on the obstacle's shape.
    General,
}

/// One convex part of a decomposition, at its world pose, with its bounding sphere.
#[derive(Clone, Debug)]
struct Part {
    pose: Pose,
    hull: Arc<ClimbingHull>,
    center: Point3<f64>,
    radius: f64,
}

/// The vertex graphs ([`ClimbingHull`]) of a convex hull (one) or of a decomposition's parts,
/// by the address of the shape they were built for: obstacles that share a shape (a mesh
/// placed many times, [`crate::world::MeshCache`]) share them; `None` when a part is not a
/// convex polyhedron. The addresses are unique while the scene is built: every shape is held
/// by an obstacle until then.
type Climbers = std::collections::HashMap<usize, Option<Arc<[Arc<ClimbingHull>]>>>;

/// The vertex graphs of `shape`'s convex hull or parts, from `climbers` when built before.
fn climbers(shape: &SharedShape, climbers: &mut Climbers) -> Option<Arc<[Arc<ClimbingHull>]>> {
    let key = Arc::as_ptr(&shape.0) as *const () as usize;
    climbers
        .entry(key)
        .or_insert_with(|| {
            if let Some(poly) = shape.as_convex_polyhedron() {
                return Some(Arc::from([Arc::new(ClimbingHull::new(poly)?)]));
            }
            shape
                .as_compound()?
                .shapes()
                .iter()
                .map(|(_, part)| Some(Arc::new(ClimbingHull::new(part.as_convex_polyhedron()?)?)))
                .collect::<Option<Arc<[_]>>>()
        })
        .clone()
}

/// The fast path of a shape: a box ([`Exact::Cuboid`]), a triangle mesh ([`Exact::Mesh`]), a
/// convex hull or convex parts ([`Exact::Hull`], [`Exact::Parts`]); `None` otherwise, or when a
/// part is not a convex polyhedron. The hulls' vertex graphs come from `cache`.
fn fast_path(shape: &SharedShape, pose: &Pose, cache: &mut Climbers) -> Option<Exact> {
    if let Some(c) = shape.as_cuboid() {
        let h = c.half_extents;
        return Some(Exact::Cuboid {
            pose: *pose,
            half: nalgebra::Vector3::new(h.x, h.y, h.z),
        });
    }
    if shape.as_trimesh().is_some() {
        return Some(Exact::Mesh { pose: *pose });
    }
    if shape.as_convex_polyhedron().is_some() {
        return Some(Exact::Hull {
            pose: *pose,
            hull: climbers(shape, cache)?[0].clone(),
        });
    }
    let compound = shape.as_compound()?;
    let hulls = climbers(shape, cache)?;
    let parts: Vec<Part> = compound
        .shapes()
        .iter()
        .zip(hulls.iter())
        .map(|((local, part), hull)| {
            let world = *pose * *local;
            let bs = part.compute_bounding_sphere(&world);
            Part {
                pose: world,
                hull: hull.clone(),
                center: from_parry_point(bs.center()),
                radius: bs.radius(),
            }
        })
        .collect();
    Some(Exact::Parts(parts.into()))
}

/// Obstacles, clearance, a per-obstacle bounding sphere and a hierarchy of their bounding boxes
/// for culling.
///
/// Distances between the robot's parts (capsules: a segment and a radius; point colliders are
/// zero-length capsules) and the obstacles are *signed* where the closed forms allow (negative
/// when overlapping) and clamped at 0 for parry's shapes; either way `distance ≤ clearance`
/// means a collision.
#[derive(Clone, Debug)]
pub struct CollisionScene {
    obstacles: Vec<Obstacle>,
    exact: Vec<Exact>,
    bounds: Vec<(Point3<f64>, f64)>,
    bvh: Bvh,
    clearance: f64,
    /// Few obstacles, all with closed-form distances: searched by one linear pass.
    linear: bool,
    /// The bounding spheres of `bounds` in blocks, for the linear pass.
    blocks: Vec<Block>,
    /// When every obstacle is a sphere and they are few: the spheres by coordinate, for
    /// [`CollisionScene::sphere_nearest`].
    spheres: Option<Spheres>,
    /// Distinct for every scene built ([`CollisionScene::id`]).
    id: u64,
}

/// Scenes with at most this many obstacles, all spheres or capsules, are searched by one pass
/// over their bounding spheres in [`CollisionScene::nearest`] instead of through the hierarchy
/// (a mesh's distance costs too much to leave to its bounding sphere's pruning).
const LINEAR_SCAN: usize = 48;

/// Bounding spheres per [`Block`].
const LANES: usize = 4;

/// [`LANES`] bounding spheres, centres and radii by coordinate (structure of arrays), so that
/// the linear pass of [`CollisionScene::nearest`] tests them at once on the processor's vector
/// lanes. The last block of a scene is filled up with copies of its last sphere, which the
/// pass never reaches.
#[derive(Clone, Debug, Default)]
struct Block {
    x: [f64; LANES],
    y: [f64; LANES],
    z: [f64; LANES],
    r: [f64; LANES],
}

/// The blocks of the spheres `(centre, radius)`.
fn blocks(spheres: &[(Point3<f64>, f64)]) -> Vec<Block> {
    spheres
        .chunks(LANES)
        .map(|block| {
            let at = |i: usize| block[i.min(block.len() - 1)];
            Block {
                x: std::array::from_fn(|i| at(i).0.x),
                y: std::array::from_fn(|i| at(i).0.y),
                z: std::array::from_fn(|i| at(i).0.z),
                r: std::array::from_fn(|i| at(i).1),
            }
        })
        .collect()
}

/// Bit `i` is set when sphere `i` of `block` lies beyond `best` from the ball (`center`,
/// `radius`): `reach > 0 and |c − center|² ≥ reach²` with `reach = best + r + radius`,
/// evaluated in this order (the scalar test's rounding).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "sse2")]
#[inline]
fn skipped(block: &Block, center: &Point3<f64>, best: f64, radius: f64) -> u32 {
    use std::arch::x86_64::*;
    let Block { x, y, z, r } = block;
    let (cx, cy, cz) = (
        _mm_set1_pd(center.x),
        _mm_set1_pd(center.y),
        _mm_set1_pd(center.z),
    );
    let (best, radius, zero) = (_mm_set1_pd(best), _mm_set1_pd(radius), _mm_setzero_pd());
    let mut mask = 0;
    for h in 0..LANES / 2 {
        let (i, j) = (2 * h, 2 * h + 1);
        let dx = _mm_sub_pd(_mm_set_pd(x[j], x[i]), cx);
        let dy = _mm_sub_pd(_mm_set_pd(y[j], y[i]), cy);
        let dz = _mm_sub_pd(_mm_set_pd(z[j], z[i]), cz);
        let d2 = _mm_add_pd(
            _mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)),
            _mm_mul_pd(dz, dz),
        );
        let reach = _mm_add_pd(_mm_add_pd(best, _mm_set_pd(r[j], r[i])), radius);
        let skip = _mm_and_pd(
            _mm_cmpgt_pd(reach, zero),
            _mm_cmpge_pd(d2, _mm_mul_pd(reach, reach)),
        );
        mask |= (_mm_movemask_pd(skip) as u32) << (2 * h);
    }
    mask
}

/// As the vector version: the same test, one sphere at a time.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn skipped(block: &Block, center: &Point3<f64>, best: f64, radius: f64) -> u32 {
    let Block { x, y, z, r } = block;
    let mut mask = 0;
    for i in 0..LANES {
        let (dx, dy, dz) = (x[i] - center.x, y[i] - center.y, z[i] - center.z);
        let reach = best + r[i] + radius;
        let skip = reach > 0.0 && dx * dx + dy * dy + dz * dz >= reach * reach;
        mask |= u32::from(skip) << i;
    }
    mask
}

/// Spheres per step of [`Spheres`]' vector pass.
const WIDE: usize = 4;

/// Margin (in the scene's length unit) by which a block of spheres must lie beyond the cap
/// for [`Spheres::nearest_avx2`] to skip it: far above the rounding of a distance (about 1e-16
/// of the scene's extent, which [`crate::limits::MAX_LENGTH`] keeps within 1e3), so skipping
/// changes no answer.
const SKIP_MARGIN: f64 = 1e-9;

/// The obstacles of a scene of few spheres, centres and radii by coordinate (structure of
/// arrays), padded to a multiple of [`WIDE`] with copies of the last sphere, so that
/// [`CollisionScene::sphere_nearest`] measures a capsule against all of them at once.
#[derive(Clone, Debug)]
struct Spheres {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    r: Vec<f64>,
}

impl Spheres {
    fn new(spheres: &[(Point3<f64>, f64)]) -> Self {
        let padded = spheres.len().div_ceil(WIDE) * WIDE;
        let at = |i: usize| spheres[i.min(spheres.len() - 1)];
        Spheres {
            x: (0..padded).map(|i| at(i).0.x).collect(),
            y: (0..padded).map(|i| at(i).0.y).collect(),
            z: (0..padded).map(|i| at(i).0.z).collect(),
            r: (0..padded).map(|i| at(i).1).collect(),
        }
    }

    /// The smallest `point_segment(c_k, a, b) − r_k − radius` over the spheres `k` and the
    /// first `k` that gives it, when it is below `cap`; otherwise `(cap, u32::MAX)`. One
    /// sphere at a time.
    fn nearest_plain(&self, a: &Point3<f64>, b: &Point3<f64>, radius: f64, cap: f64) -> (f64, u32) {
        let (mut best, mut nearest) = (f64::INFINITY, u32::MAX);
        for k in 0..self.x.len() {
            let c = Point3::new(self.x[k], self.y[k], self.z[k]);
            let d = point_segment(&c, a, b) - self.r[k] - radius;
            if d < best {
                (best, nearest) = (d, k as u32);
            }
        }
        if best < cap {
            (best, nearest)
        } else {
            (cap, u32::MAX)
        }
    }

    /// As [`Spheres::nearest_plain`], [`WIDE`] spheres at a time on AVX vector lanes, with
    /// the same operations in the same order (no fused multiply-add), so the same answer bit
    /// for bit. A block of spheres that all lie beyond `cap` from the capsule's bounding ball
    /// (by more than [`SKIP_MARGIN`], which no rounding of a distance reaches) is skipped.
    ///
    /// # Safety
    /// The processor must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn nearest_avx2(
        &self,
        a: &Point3<f64>,
        b: &Point3<f64>,
        radius: f64,
        cap: f64,
    ) -> (f64, u32) {
        use std::arch::x86_64::*;
        let ab = b - a;
        let len2 = ab.norm_squared();
        let (abx, aby, abz) = (
            _mm256_set1_pd(ab.x),
            _mm256_set1_pd(ab.y),
            _mm256_set1_pd(ab.z),
        );
        let (ax, ay, az) = (
            _mm256_set1_pd(a.x),
            _mm256_set1_pd(a.y),
            _mm256_set1_pd(a.z),
        );
        let (l2, zero, one) = (
            _mm256_set1_pd(len2),
            _mm256_setzero_pd(),
            _mm256_set1_pd(1.0),
        );
        let rad = _mm256_set1_pd(radius);
        let m = nalgebra::center(a, b);
        let (mx, my, mz) = (
            _mm256_set1_pd(m.x),
            _mm256_set1_pd(m.y),
            _mm256_set1_pd(m.z),
        );
        // A sphere lies beyond the cap when |c − m| ≥ cap + r + (half length + radius).
        let reach = _mm256_set1_pd(cap + 0.5 * len2.sqrt() + radius + SKIP_MARGIN);
        let mut best = _mm256_set1_pd(f64::INFINITY);
        let mut at = _mm256_set1_epi64x(-1);
        let mut index = _mm256_set_epi64x(3, 2, 1, 0);
        let step = _mm256_set1_epi64x(WIDE as i64);
        let n = self.x.len();
        let mut k = 0;
        while k < n {
            // SAFETY: k + WIDE ≤ n, the arrays' common length (a multiple of WIDE).
            let (cx, cy, cz, r) = unsafe {
                (
                    _mm256_loadu_pd(self.x.as_ptr().add(k)),
                    _mm256_loadu_pd(self.y.as_ptr().add(k)),
                    _mm256_loadu_pd(self.z.as_ptr().add(k)),
                    _mm256_loadu_pd(self.r.as_ptr().add(k)),
                )
            };
            let (ex, ey, ez) = (
                _mm256_sub_pd(cx, mx),
                _mm256_sub_pd(cy, my),
                _mm256_sub_pd(cz, mz),
            );
            let e2 = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(ex, ex), _mm256_mul_pd(ey, ey)),
                _mm256_mul_pd(ez, ez),
            );
            let lanes_reach = _mm256_add_pd(reach, r);
            let beyond = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(lanes_reach, zero),
                _mm256_cmp_pd::<_CMP_GE_OQ>(e2, _mm256_mul_pd(lanes_reach, lanes_reach)),
            );
            if _mm256_movemask_pd(beyond) == (1 << WIDE) - 1 {
                index = _mm256_add_epi64(index, step);
                k += WIDE;
                continue;
            }
            let (px, py, pz) = (
                _mm256_sub_pd(cx, ax),
                _mm256_sub_pd(cy, ay),
                _mm256_sub_pd(cz, az),
            );
            let (qx, qy, qz) = if len2 > 0.0 {
                let dot = _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(px, abx), _mm256_mul_pd(py, aby)),
                    _mm256_mul_pd(pz, abz),
                );
                // clamp(0, 1): t < 0 gives 0, t > 1 gives 1 (no NaN: len2 > 0 and finite).
                let t = _mm256_min_pd(_mm256_max_pd(_mm256_div_pd(dot, l2), zero), one);
                (
                    _mm256_sub_pd(px, _mm256_mul_pd(abx, t)),
                    _mm256_sub_pd(py, _mm256_mul_pd(aby, t)),
                    _mm256_sub_pd(pz, _mm256_mul_pd(abz, t)),
                )
            } else {
                (px, py, pz)
            };
            let q2 = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(qx, qx), _mm256_mul_pd(qy, qy)),
                _mm256_mul_pd(qz, qz),
            );
            let d = _mm256_sub_pd(_mm256_sub_pd(_mm256_sqrt_pd(q2), r), rad);
            let less = _mm256_cmp_pd::<_CMP_LT_OQ>(d, best);
            best = _mm256_blendv_pd(best, d, less);
            at = _mm256_castpd_si256(_mm256_blendv_pd(
                _mm256_castsi256_pd(at),
                _mm256_castsi256_pd(index),
                less,
            ));
            index = _mm256_add_epi64(index, step);
            k += WIDE;
        }
        let mut values = [0.0; WIDE];
        let mut indices = [0i64; WIDE];
        // SAFETY: both arrays hold WIDE lanes.
        unsafe {
            _mm256_storeu_pd(values.as_mut_ptr(), best);
            _mm256_storeu_si256(indices.as_mut_ptr().cast(), at);
        }
        // Each lane holds its first smallest; across lanes the smallest, then the first.
        let (mut value, mut nearest) = (f64::INFINITY, u32::MAX);
        for (v, i) in values.into_iter().zip(indices) {
            if i >= 0 && (v < value || (v == value && (i as u32) < nearest)) {
                (value, nearest) = (v, i as u32);
            }
        }
        if value < cap {
            (value, nearest)
        } else {
            (cap, u32::MAX)
        }
    }
}

/// The point `p` (world coordinates) in the frame of `pose`.
#[inline]
fn local(pose: &Pose, p: &Point3<f64>) -> Point3<f64> {
    from_parry_point(pose.inverse_transform_point(to_parry_point(p)))
}

/// Squared distance from `p` to the bounding box of a hierarchy node (0 inside).
#[inline]
fn node_distance_squared(node: &BvhNode, p: &Point3<f64>) -> f64 {
    let (lo, hi) = (node.mins(), node.maxs());
    let dx = (lo.x - p.x).max(p.x - hi.x).max(0.0);
    let dy = (lo.y - p.y).max(p.y - hi.y).max(0.0);
    let dz = (lo.z - p.z).max(p.z - hi.z).max(0.0);
    dx * dx + dy * dy + dz * dz
}

/// The identity of the next scene built.
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

impl CollisionScene {
    /// An identity distinct for every scene built in this process (a clone keeps it: it holds
    /// the same obstacles), so that what was computed against one scene is never taken for
    /// another's.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// The scene of a workspace.
    pub fn new(workspace: &Workspace) -> Self {
        let obstacles = workspace.obstacles.clone();
        let mut exact = Vec::with_capacity(obstacles.len());
        let mut bounds = Vec::with_capacity(obstacles.len());
        let boxes: Vec<_> = obstacles
            .iter()
            .map(|o| o.shape().compute_aabb(o.pose()))
            .collect();
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
        let mut cache = Climbers::new();
        for o in &obstacles {
            let bs = o.shape().compute_bounding_sphere(o.pose());
            bounds.push((from_parry_point(bs.center()), bs.radius()));
            exact.push(match o.geometry {
                ObstacleShape::Sphere { radius } => Exact::Sphere {
                    center: Point3::from(o.placement.translation.vector),
                    radius,
                },
                ObstacleShape::Capsule { length, radius } => {
                    let h = nalgebra::Vector3::new(0.0, 0.0, 0.5 * length);
                    Exact::Capsule {
                        a: o.placement * Point3::from(-h),
                        b: o.placement * Point3::from(h),
                        radius,
                    }
                }
                _ => fast_path(o.shape(), o.pose(), &mut cache).unwrap_or(Exact::General),
            });
        }
        let linear = obstacles.len() <= LINEAR_SCAN
            && exact
                .iter()
                .all(|e| matches!(e, Exact::Sphere { .. } | Exact::Capsule { .. }));
        let blocks = if linear { blocks(&bounds) } else { Vec::new() };
        let spheres = exact
            .iter()
            .map(|e| match e {
                Exact::Sphere { center, radius } => Some((*center, *radius)),
                _ => None,
            })
            .collect::<Option<Vec<_>>>()
            .filter(|s| linear && !s.is_empty())
            .map(|s| Spheres::new(&s));
        CollisionScene {
            obstacles,
            exact,
            blocks,
            spheres,
            bounds,
            bvh,
            clearance: workspace.clearance,
            linear,
            id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        }
    }

    /// The clearance `ε`: a part at distance `≤ ε` from an obstacle collides.
    pub fn clearance(&self) -> f64 {
        self.clearance
    }

    /// For a scene of few obstacles that are all spheres: the distance from the capsule
    /// (`a`–`b`, `radius`) to the nearest obstacle, exactly [`CollisionScene::distance`]'s
    /// smallest value, and the first obstacle that gives it, when it is below `cap`; otherwise
    /// `(cap, u32::MAX)`. Every sphere is measured at once (on AVX2 vector lanes where the
    /// processor has them, with the same answer bit for bit), except blocks of spheres that
    /// lie beyond the cap. `None` for any other scene.
    #[inline]
    pub fn sphere_nearest(
        &self,
        a: &Point3<f64>,
        b: &Point3<f64>,
        radius: f64,
        cap: f64,
    ) -> Option<(f64, u32)> {
        let spheres = self.spheres.as_ref()?;
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor supports AVX2 (just checked).
            return Some(unsafe { spheres.nearest_avx2(a, b, radius, cap) });
        }
        Some(spheres.nearest_plain(a, b, radius, cap))
    }

    /// The obstacles.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// Number of obstacles.
    pub fn len(&self) -> usize {
        self.obstacles.len()
    }

    /// True when there is no obstacle.
    pub fn is_empty(&self) -> bool {
        self.obstacles.is_empty()
    }

    /// The obstacles whose bounding box and bounding sphere come within `margin` of the ball
    /// (`center`, `radius`): the broad phase. Indices are written to `out` (cleared first), in
    /// a fixed order for a given scene.
    #[inline]
    pub fn near(&self, center: &Point3<f64>, radius: f64, margin: f64, out: &mut Vec<u32>) {
        out.clear();
        let reach = radius + margin;
        if reach.is_nan() {
            return;
        }
        let reach2 = reach * reach;
        self.bvh.traverse(|node| {
            if node_distance_squared(node, center) >= reach2 {
                return TraversalAction::Prune;
            }
            if let Some(k) = node.leaf_data() {
                let (c, r) = &self.bounds[k as usize];
                let rr = reach + r;
                if (c - center).norm_squared() < rr * rr {
                    out.push(k);
                }
            }
            TraversalAction::Continue
        });
    }

    /// `(min(cap, min_k dist(k)), nearest)` over the obstacles `k`, where `dist(k, c)` is a
    /// distance from a body inside the ball (`center`, `radius`) to obstacle `k`, exact when
    /// below `c` and otherwise any value `≥ c` (see [`CollisionScene::distance_below`]): a best-first
    /// search of the hierarchy that skips every obstacle whose bounding box is farther from the
    /// ball than the best distance so far. The distance is exact when it is below `cap`, and a
    /// lower bound of every obstacle's distance in any case; `nearest` is the obstacle found
    /// below `cap` (`u32::MAX` if none). Obstacle `skip` is left out (its distance is already
    /// in `cap`; pass `u32::MAX` to search all).
    #[inline]
    pub fn nearest(
        &self,
        center: &Point3<f64>,
        radius: f64,
        cap: f64,
        skip: u32,
        dist: impl Fn(usize, f64) -> f64,
    ) -> (f64, u32) {
        if self.obstacles.is_empty() || cap.is_nan() {
            return (cap, u32::MAX);
        }
        if self.linear {
            // Few obstacles: one pass over their bounding spheres beats the hierarchy. An
            // obstacle is skipped when its bounding sphere is no nearer than the best distance
            // so far; a block of spheres is tested at once with the best at its start, and
            // only its spheres that pass are tested again one by one, in order, with the best
            // of that moment (once the best has changed within a block, every later sphere of
            // the block is: a smaller best can only skip more, except where it turns the
            // reach negative).
            let (mut best, mut nearest) = (cap, u32::MAX);
            let n = self.bounds.len();
            // Obstacle k's bounding sphere lies beyond `best` from the ball.
            let beyond = |k: usize, best: f64| {
                let (c, r) = &self.bounds[k];
                let reach = best + r + radius;
                reach > 0.0 && (c - center).norm_squared() >= reach * reach
            };
            // Obstacle k's distance, when it is below the best.
            let below = |k: usize, best: f64| Some(dist(k, best)).filter(|d| *d < best);
            if n < 2 * LANES {
                // Fewer than two blocks: one by one.
                for k in 0..n {
                    if k as u32 == skip || beyond(k, best) {
                        continue;
                    }
                    if let Some(d) = below(k, best) {
                        (best, nearest) = (d, k as u32);
                    }
                }
                return (best, nearest);
            }
            for (block, spheres) in self.blocks.iter().enumerate() {
                // SAFETY: SSE2 is part of every x86_64 processor (the target's baseline).
                #[cfg(target_arch = "x86_64")]
                let skipped = unsafe { skipped(spheres, center, best, radius) };
                #[cfg(not(target_arch = "x86_64"))]
                let skipped = skipped(spheres, center, best, radius);
                if skipped == (1 << LANES) - 1 {
                    continue;
                }
                let start = best;
                for i in 0..LANES {
                    let pass = skipped & (1 << i) == 0;
                    let k = block * LANES + i;
                    if k >= n {
                        break;
                    }
                    if k as u32 == skip {
                        continue;
                    }
                    // The block's test holds while the best is the one it was made with.
                    let skip_it = if best == start {
                        !pass
                    } else {
                        beyond(k, best)
                    };
                    if skip_it {
                        continue;
                    }
                    if let Some(d) = below(k, best) {
                        (best, nearest) = (d, k as u32);
                    }
                }
            }
            return (best, nearest);
        }
        let box_cost =
            |node: &BvhNode, _best: f64| node_distance_squared(node, center).sqrt() - radius;
        let leaf_cost = |k: u32, best: f64| {
            if k == skip {
                return None;
            }
            let k = k as usize;
            let (c, r) = &self.bounds[k];
            if (c - center).norm() - r - radius >= best {
                return None;
            }
            Some(dist(k, best))
        };
        self.bvh
            .find_best(cap, box_cost, leaf_cost)
            .map_or((cap, u32::MAX), |(k, d)| (d.min(cap), k))
    }

    /// A lower bound of the distance between the capsule (`a`–`b`, `radius`) and obstacle `k`,
    /// from its bounding sphere; exact for spheres.
    #[inline]
    pub fn lower_bound(&self, k: usize, a: &Point3<f64>, b: &Point3<f64>, radius: f64) -> f64 {
        let (c, r) = &self.bounds[k];
        point_segment(c, a, b) - r - radius
    }

    /// Distance between the capsule (`a`–`b`, `radius`) and obstacle `k`.
    #[inline]
    pub fn distance(&self, k: usize, a: &Point3<f64>, b: &Point3<f64>, radius: f64) -> f64 {
        self.distance_below(k, a, b, radius, f64::INFINITY)
    }

    /// [`CollisionScene::distance`] when it is below `cap`; otherwise some value `≥ cap`. The
    /// convex hulls and decompositions stop their GJK iterations, and a triangle mesh its
    /// search, once the distance is proven larger; below `cap` the value is the uncapped one,
    /// bit for bit (`cap = ∞` is [`CollisionScene::distance`]).
    #[inline]
    pub fn distance_below(
        &self,
        k: usize,
        a: &Point3<f64>,
        b: &Point3<f64>,
        radius: f64,
        cap: f64,
    ) -> f64 {
        match &self.exact[k] {
            Exact::Sphere { center, radius: r } => point_segment(center, a, b) - r - radius,
            Exact::Capsule {
                a: p,
                b: q,
                radius: r,
            } => segment_segment(a, b, p, q) - r - radius,
            Exact::Hull { pose, hull } => hull
                .segment_distance_below(pose, a, b, cap + radius)
                .map_or(cap, |d| (d - radius).max(0.0)),
            Exact::Parts(parts) => {
                let mut best = f64::INFINITY;
                for part in parts.iter() {
                    let limit = best.min(cap);
                    if point_segment(&part.center, a, b) - part.radius - radius >= limit {
                        continue;
                    }
                    if let Some(d) =
                        part.hull
                            .segment_distance_below(&part.pose, a, b, limit + radius)
                    {
                        best = best.min((d - radius).max(0.0));
                    }
                }
                best
            }
            Exact::Mesh { pose } => self.mesh_distance(k, pose, a, b, radius, cap),
            Exact::Cuboid { pose, half } => {
                (segment_box(&local(pose, a), &local(pose, b), half) - radius).max(0.0)
            }
            Exact::General => {
                let o = &self.obstacles[k];
                let d = if a == b {
                    let ball = Ball::new(radius);
                    let pose = Pose::from_translation(to_parry_point(a));
                    query::distance(&pose, &ball, o.pose(), o.shape().as_ref())
                        .map_or(0.0, |d| d.distance)
                } else {
                    let seg = Segment::new(to_parry_point(a), to_parry_point(b));
                    query::distance(&Pose::IDENTITY, &seg, o.pose(), o.shape().as_ref())
                        .map_or(0.0, |d| (d.distance - radius).max(0.0))
                };
                d
            }
        }
    }

    /// Distance between the capsule (`a`–`b`, `radius`) and the triangle mesh of obstacle `k`
    /// placed at `pose`, when below `cap` (otherwise `cap`): the nearest triangle by a
    /// best-first search of the mesh's hierarchy, each box and triangle bounded from below
    /// through the segment's bounding ball and bounding box.
    fn mesh_distance(
        &self,
        k: usize,
        pose: &Pose,
        a: &Point3<f64>,
        b: &Point3<f64>,
        radius: f64,
        cap: f64,
    ) -> f64 {
        let Some(mesh) = self.obstacles[k].shape().as_trimesh() else {
            unreachable!("Exact::Mesh is built from a triangle mesh only");
        };
        let (a, b) = (local(pose, a), local(pose, b));
        let mid = nalgebra::center(&a, &b);
        let half = 0.5 * (b - a).norm();
        let (lo, hi) = (a.inf(&b), a.sup(&b));
        // The distance between the segment's bounding box and the box `[l, h]`: a lower
        // bound of the segment's distance to anything inside it.
        let box_gap = |l: &Point3<f64>, h: &Point3<f64>| {
            let g = (l - hi).sup(&(lo - h)).sup(&nalgebra::Vector3::zeros());
            g.norm()
        };
        let vertices = mesh.vertices();
        let indices = mesh.indices();
        let box_cost = |node: &BvhNode, _best: f64| {
            let ball = node_distance_squared(node, &mid).sqrt() - half;
            let (l, h) = (node.mins(), node.maxs());
            ball.max(box_gap(&from_parry_point(l), &from_parry_point(h)))
        };
        let leaf_cost = |t: u32, best: f64| {
            let [i, j, l] = indices[t as usize];
            let v = |i: u32| from_parry_point(vertices[i as usize]);
            let (p, q, r) = (v(i), v(j), v(l));
            if box_gap(&p.inf(&q).inf(&r), &p.sup(&q).sup(&r)) >= best {
                return None;
            }
            Some(segment_triangle(&a, &b, &p, &q, &r))
        };
        match mesh.bvh().find_best(cap + radius, box_cost, leaf_cost) {
            Some((_, d)) => (d - radius).max(0.0),
            None => cap,
        }
    }

    /// Distance between a parry `shape` at world pose `pose` and obstacle `k` (0 when they
    /// touch or overlap).
    #[inline]
    pub fn shape_distance(
        &self,
        k: usize,
        pose: &Pose,
        shape: &dyn parry3d_f64::shape::Shape,
    ) -> f64 {
        let o = &self.obstacles[k];
        query::distance(pose, shape, o.pose(), o.shape().as_ref()).map_or(0.0, |d| d.distance)
    }

    /// Signed distance between a parry `shape` at world pose `pose` and obstacle `k`: the
    /// distance when they are apart, minus the penetration depth when they overlap (parry's
    /// contact query; 0 when it cannot tell). Slower than [`Self::shape_distance`]: for
    /// reporting how deep a collision is, not for checking.
    pub fn shape_signed_distance(
        &self,
        k: usize,
        pose: &Pose,
        shape: &dyn parry3d_f64::shape::Shape,
    ) -> f64 {
        let d = self.shape_distance(k, pose, shape);
        if d > 0.0 {
            return d;
        }
        let o = &self.obstacles[k];
        match query::contact(pose, shape, o.pose(), o.shape().as_ref(), 0.0) {
            Ok(Some(c)) if c.dist.is_finite() => c.dist.min(0.0),
            _ => 0.0,
        }
    }

    /// Smallest distance between the capsule and any obstacle, culled: an obstacle whose
    /// bounding sphere is farther than the best distance so far (or than `stop`) is skipped.
    /// The result is exact when it is below `stop`; otherwise it is some value `≥ stop`.
    pub fn min_distance(&self, a: &Point3<f64>, b: &Point3<f64>, radius: f64, stop: f64) -> f64 {
        let mut best = f64::INFINITY;
        for k in 0..self.obstacles.len() {
            let cap = best.min(stop);
            if self.lower_bound(k, a, b, radius) >= cap {
                continue;
            }
            best = best.min(self.distance(k, a, b, radius));
        }
        best
    }

    /// True when the capsule is farther than the clearance from every obstacle.
    pub fn capsule_free(&self, a: &Point3<f64>, b: &Point3<f64>, radius: f64) -> bool {
        let eps = self.clearance;
        (0..self.obstacles.len()).all(|k| {
            self.lower_bound(k, a, b, radius) > eps || self.distance(k, a, b, radius) > eps
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scenario;
    use proptest::prelude::*;

    /// The bundled scenes of 32 spheres (searched by the linear pass) and of meshes (through
    /// the hierarchy), loaded once.
    fn scenes() -> &'static [CollisionScene; 2] {
        static SCENES: std::sync::OnceLock<[CollisionScene; 2]> = std::sync::OnceLock::new();
        SCENES.get_or_init(|| {
            let load = |name: &str| {
                let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("examples/scenarios")
                    .join(name);
                CollisionScene::new(&Scenario::load(&path).unwrap().workspace)
            };
            let scenes = [load("paper-3d.toml"), load("pipework.toml")];
            assert!(scenes[0].linear && !scenes[1].linear);
            scenes
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// The broad phase's answers (linear pass or hierarchy) equal a brute-force scan over
        /// every obstacle.
        #[test]
        fn near_and_nearest_match_brute_force(
            a in prop::array::uniform3(-2.5f64..2.5),
            b in prop::array::uniform3(-2.5f64..2.5),
            r in 0.0f64..0.2,
            margin in 0.0f64..1.0,
            cap in 0.0f64..3.0,
        ) {
            for s in scenes() {
            let (a, b) = (Point3::from(a), Point3::from(b));
            let center = nalgebra::center(&a, &b);
            let radius = 0.5 * (b - a).norm() + r;
            let mut got = Vec::new();
            s.near(&center, radius, margin, &mut got);
            got.sort_unstable();
            let want: Vec<u32> = (0..s.len() as u32)
                .filter(|&k| {
                    let (c, rk) = &s.bounds[k as usize];
                    (c - center).norm() < radius + rk + margin
                })
                .collect();
            // The hierarchy also culls by bounding box, so it may only drop obstacles whose box
            // is out of reach; none of them is within reach of the capsule itself.
            for k in &got {
                prop_assert!(want.contains(k));
            }
            for k in &want {
                if !got.contains(k) {
                    prop_assert!(s.distance(*k as usize, &a, &b, r) > margin);
                }
            }
            let brute = (0..s.len()).map(|k| s.distance(k, &a, &b, r)).fold(f64::INFINITY, f64::min);
            let (d, k) = s.nearest(&center, radius, cap, u32::MAX, |k, c| s.distance_below(k, &a, &b, r, c));
            prop_assert!((d - brute.min(cap)).abs() < 1e-12, "{d} vs {brute} (cap {cap})");
            if brute < cap {
                prop_assert!((s.distance(k as usize, &a, &b, r) - brute).abs() < 1e-12);
            } else {
                prop_assert_eq!(k, u32::MAX);
            }
            }
        }

        /// The hull and decomposition fast paths ([`ClimbingHull`]) give parry's distances on
        /// the obstacles' own shapes (the pipework vessel hull and pipe-bundle parts).
        #[test]
        fn hull_and_parts_match_parry(
            a in prop::array::uniform3(-1.5f64..1.5),
            d in prop::array::uniform3(-0.4f64..0.4),
            r in 0.0f64..0.1,
        ) {
            let s = &scenes()[1];
            let a = Point3::new(a[0] + 1.0, a[1], a[2] + 0.8);
            let b = a + nalgebra::Vector3::from(d);
            for (k, o) in s.obstacles.iter().enumerate() {
                let seg = Segment::new(to_parry_point(&a), to_parry_point(&b));
                let want = query::distance(&Pose::IDENTITY, &seg, o.pose(), o.shape().as_ref())
                    .map_or(0.0, |d| (d.distance - r).max(0.0));
                let got = s.distance(k, &a, &b, r);
                // Where several vertices tie as the farthest, the climb and parry's scan may
                // return different ones, and GJK then stops at another point within its own
                // tolerance (about 5e-8 relative).
                prop_assert!((got - want).abs() <= 2e-7 * (1.0 + want), "obstacle {k}: {got} vs {want}");
            }
        }
    }

    /// The triangle-mesh fast path gives parry's distances on the glovebox shell (a thin
    /// `trimesh`), for capsules around, inside and through its walls and ports, capped or not.
    #[test]
    fn trimesh_matches_parry() {
        use rand::{RngExt, SeedableRng};
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenarios/glovebox.toml");
        let s = CollisionScene::new(&Scenario::load(&path).unwrap().workspace);
        let k = (0..s.len())
            .find(|&k| matches!(s.exact[k], Exact::Mesh { .. }))
            .expect("the glovebox is a triangle mesh");
        let o = &s.obstacles[k];
        let (c, r) = s.bounds[k];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let (mut near, mut touching) = (0, 0);
        for _ in 0..3000 {
            let mut p =
                || c + nalgebra::Vector3::from_fn(|_, _| rng.random_range(-1.1 * r..1.1 * r));
            let a = p();
            let b = a + (p() - a) * 0.2;
            let radius = 0.02;
            let seg = Segment::new(to_parry_point(&a), to_parry_point(&b));
            let want = query::distance(&Pose::IDENTITY, &seg, o.pose(), o.shape().as_ref())
                .map_or(0.0, |d| (d.distance - radius).max(0.0));
            let got = s.distance(k, &a, &b, radius);
            assert!(
                (got - want).abs() <= 1e-7 * (1.0 + want),
                "{got} vs parry {want}"
            );
            let cap = 0.05;
            let below = s.distance_below(k, &a, &b, radius, cap);
            if want < cap {
                assert_eq!(below, got);
            } else {
                assert!(below >= cap);
            }
            near += usize::from(want < 0.1);
            touching += usize::from(want == 0.0);
        }
        assert!(
            near > 100 && touching > 30,
            "{near} near, {touching} touching"
        );
    }

    /// A point with coordinates uniform in `[-half, half]`.
    fn random_point(rng: &mut rand_chacha::ChaCha8Rng, half: f64) -> Point3<f64> {
        use rand::RngExt;
        Point3::from(nalgebra::Vector3::from_fn(|_, _| {
            rng.random_range(-half..half)
        }))
    }

    /// A scene of `n` random spheres (centres in the cube of half side 1, radii 0.01–0.4).
    fn random_spheres(rng: &mut rand_chacha::ChaCha8Rng, n: usize) -> CollisionScene {
        use rand::RngExt;
        let obstacles = (0..n)
            .map(|k| {
                let c = random_point(rng, 1.0);
                let r = rng.random_range(0.01..0.4);
                crate::world::Obstacle::sphere(format!("s{k}"), c, r).unwrap()
            })
            .collect();
        let tasks = vec![Point3::new(5.0, 5.0, 5.0)];
        CollisionScene::new(&Workspace::new(obstacles, tasks, 0.01).unwrap())
    }

    /// The blockwise linear pass gives what measuring every obstacle gives (the same distance,
    /// bit for bit, and the same nearest obstacle), for scenes whose last block is partly
    /// filled and scenes of fewer than two blocks (searched one by one), with and without an
    /// obstacle to skip, any cap, and balls that reach into the spheres (a best below `−r`
    /// turns the reach negative).
    #[test]
    fn blockwise_linear_pass_is_the_plain_one() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut checked = 0;
        for n in [1usize, 3, 4, 5, 7, 8, 9, 10, 11, 13, 32, 47] {
            let s = random_spheres(&mut rng, n);
            assert!(s.linear && s.blocks.len() == n.div_ceil(LANES));
            for _ in 0..2000 {
                let a = random_point(&mut rng, 1.2);
                let b = a + nalgebra::Vector3::from_fn(|_, _| rng.random_range(-0.5..0.5));
                let r = rng.random_range(0.0..0.3);
                let center = nalgebra::center(&a, &b);
                let radius = 0.5 * (b - a).norm() + r;
                let cap = [f64::INFINITY, rng.random_range(-0.3..1.0)][rng.random_range(0..2)];
                let skip = [u32::MAX, rng.random_range(0..n as u32)][rng.random_range(0..2)];
                let dist = |k: usize, c: f64| s.distance_below(k, &a, &b, r, c);
                let got = s.nearest(&center, radius, cap, skip, dist);
                // Every obstacle measured: the first nearest below the cap.
                let want = (0..n)
                    .filter(|&k| k as u32 != skip)
                    .map(|k| (s.distance(k, &a, &b, r), k as u32))
                    .fold((cap, u32::MAX), |m, x| if x.0 < m.0 { x } else { m });
                assert_eq!(got, want, "{n} spheres");
                checked += usize::from(want.1 != u32::MAX);
            }
        }
        assert!(checked > 5000, "{checked}");
    }

    /// The all-at-once pass over a scene of spheres gives, bit for bit, the smallest of the
    /// one-by-one distances and the first obstacle that gives it, on the vector lanes and
    /// without them; with zero-length segments, segments inside spheres, and every padding
    /// of the last block. Scenes with any other obstacle do not take it.
    #[test]
    fn all_spheres_at_once_is_one_by_one() {
        use crate::world::Obstacle;
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let (mut cases, mut capped) = (0, 0);
        for n in [1usize, 2, 3, 4, 5, 7, 8, 9, 32, 47, 48] {
            let s = random_spheres(&mut rng, n);
            let spheres = s.spheres.as_ref().expect("a scene of spheres");
            for i in 0..3000 {
                let a = random_point(&mut rng, 1.2);
                let b = match i % 4 {
                    0 => a,
                    1 => a + nalgebra::Vector3::from_fn(|_, _| rng.random_range(-1e-9..1e-9)),
                    _ => a + nalgebra::Vector3::from_fn(|_, _| rng.random_range(-0.8..0.8)),
                };
                let r = rng.random_range(0.0..0.3);
                let cap = [f64::INFINITY, rng.random_range(-0.3..1.5)][i % 2];
                // The first nearest below the cap, else the cap.
                let want = (0..n)
                    .map(|k| (s.distance(k, &a, &b, r), k as u32))
                    .fold((cap, u32::MAX), |m, x| if x.0 < m.0 { x } else { m });
                let got = s.sphere_nearest(&a, &b, r, cap).unwrap();
                assert_eq!(got.0.to_bits(), want.0.to_bits(), "{n} spheres");
                assert_eq!(got.1, want.1, "{n} spheres");
                assert_eq!(spheres.nearest_plain(&a, &b, r, cap), want);
                cases += usize::from(want.0 < 0.0);
                capped += usize::from(want.1 == u32::MAX);
            }
        }
        assert!(cases > 100, "{cases} overlapping cases");
        assert!(capped > 1000, "{capped} capped cases");
        // A capsule among the spheres, or too many spheres: the other passes.
        let mut obstacles = vec![Obstacle::sphere("s", Point3::origin(), 0.1).unwrap()];
        let tasks = vec![Point3::new(5.0, 5.0, 5.0)];
        let capsule = crate::world::ObstacleShape::Capsule {
            length: 0.5,
            radius: 0.1,
        };
        let placement = nalgebra::IsometryMatrix3::identity();
        obstacles.push(Obstacle::new("c", capsule, placement).unwrap());
        let s = CollisionScene::new(&Workspace::new(obstacles, tasks.clone(), 0.01).unwrap());
        assert!(s
            .sphere_nearest(&Point3::origin(), &Point3::origin(), 0.1, 1.0)
            .is_none());
        let many = (0..=LINEAR_SCAN)
            .map(|k| Obstacle::sphere(format!("s{k}"), Point3::new(k as f64, 0.0, 0.0), 0.1))
            .collect::<Result<Vec<_>, _>>()
            .unwrap();
        let s = CollisionScene::new(&Workspace::new(many, tasks, 0.01).unwrap());
        assert!(s
            .sphere_nearest(&Point3::origin(), &Point3::origin(), 0.1, 1.0)
            .is_none());
    }

    /// The pipework scene takes the hull, decomposition and box fast paths.
    #[test]
    fn pipework_meshes_take_the_fast_paths() {
        let s = &scenes()[1];
        assert!(matches!(s.exact[0], Exact::Hull { .. }));
        assert!(matches!(&s.exact[1], Exact::Parts(p) if p.len() == 9));
        assert!(matches!(s.exact[2], Exact::Cuboid { .. }));
    }

    /// Obstacles that share a mesh shape (a mesh placed many times) share its vertex graphs,
    /// each at its own pose, and their distances are those of obstacles built one by one.
    #[test]
    fn placed_copies_share_their_hulls() {
        use rand::{RngExt, SeedableRng};
        let pipework = &scenes()[1];
        let mut cache = crate::world::MeshCache::new();
        let (mut shared, mut alone) = (Vec::new(), Vec::new());
        for k in 0..3 {
            // The vessel hull and the pipe-bundle decomposition, moved along y.
            for o in &pipework.obstacles[..2] {
                let t = nalgebra::Translation3::new(0.0, 1.5 * k as f64, 0.0);
                let placement =
                    nalgebra::IsometryMatrix3::from_parts(t, Default::default()) * o.placement;
                let name = format!("{} {k}", o.name);
                let geometry = o.geometry.clone();
                shared.push(Obstacle::with_cache(
                    &name,
                    geometry.clone(),
                    placement,
                    &mut cache,
                ));
                alone.push(Obstacle::new(&name, geometry, placement));
            }
        }
        let shared: Vec<Obstacle> = shared.into_iter().map(Result::unwrap).collect();
        let alone: Vec<Obstacle> = alone.into_iter().map(Result::unwrap).collect();
        assert_eq!(cache.len(), 2);
        let tasks = vec![Point3::new(0.0, 0.0, 3.0)];
        let a = CollisionScene::new(&Workspace::new(shared, tasks.clone(), 0.01).unwrap());
        let b = CollisionScene::new(&Workspace::new(alone, tasks, 0.01).unwrap());
        let hulls = |s: &CollisionScene, k: usize| match &s.exact[k] {
            Exact::Hull { hull, .. } => vec![Arc::as_ptr(hull)],
            Exact::Parts(parts) => parts.iter().map(|p| Arc::as_ptr(&p.hull)).collect(),
            e => panic!("{e:?}"),
        };
        assert_eq!(hulls(&a, 1).len(), 9);
        for k in 2..6 {
            assert_eq!(hulls(&a, k), hulls(&a, k % 2), "copy {k} shares");
            assert_ne!(hulls(&b, k), hulls(&b, k % 2), "copy {k} built alone");
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut point = || {
            Point3::new(
                rng.random_range(-1.0..1.5),
                rng.random_range(-1.5..4.5),
                rng.random_range(-0.2..1.5),
            )
        };
        let mut near = 0;
        for _ in 0..3000 {
            let (p, q) = (point(), point());
            for k in 0..6 {
                let d = a.distance(k, &p, &q, 0.03);
                assert_eq!(d, b.distance(k, &p, &q, 0.03), "obstacle {k}, {p} – {q}");
                near += usize::from(d < 0.2);
            }
        }
        assert!(near > 100, "the segments come near the copies ({near})");
    }
}
