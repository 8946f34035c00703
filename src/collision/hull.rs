//! Convex polyhedra (obstacle hulls and the parts of a convex decomposition) whose support
//! point is found by hill climbing over the vertex graph instead of a scan of every vertex.
//!
//! GJK asks a shape for its support point (the point farthest along a direction) a few times per
//! distance query. parry's [`ConvexPolyhedron`] scans all its vertices for it, so a hull of a
//! few hundred vertices makes every query cost a few hundred dot products per GJK iteration.
//! On a convex polytope, a vertex that no neighbour along an edge improves on is a farthest
//! vertex (the simplex method's argument), so climbing along improving edges, from the
//! vertex farthest along a nearby fixed direction (a cube map of 384 cells), finds the same
//! support value in a step or two. The distances are then parry's GJK distances with the same
//! support values (where several vertices tie as the farthest, GJK may take another of them and
//! stop at another point within its tolerance, about 5e-8 relative).

use crate::world::convert::to_parry_point;
use nalgebra::Point3;
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry3d_f64::shape::{ConvexPolyhedron, Segment, SupportMap};

/// Cells per side of each face of the cube map that picks the climb's start vertex.
const GRID: usize = 8;

/// The cube-map cell of a direction: its dominant axis and sign pick the face, the other two
/// coordinates (divided by the dominant one, in `[-1, 1]`) the cell on it.
#[inline]
fn cell(dir: Vector) -> usize {
    let (ax, ay, az) = (dir.x.abs(), dir.y.abs(), dir.z.abs());
    let (face, m, u, v) = if ax >= ay && ax >= az {
        (usize::from(dir.x < 0.0), ax, dir.y, dir.z)
    } else if ay >= az {
        (2 + usize::from(dir.y < 0.0), ay, dir.z, dir.x)
    } else {
        (4 + usize::from(dir.z < 0.0), az, dir.x, dir.y)
    };
    if m.is_nan() || m <= 0.0 {
        return 0; // a zero or non-finite direction: any start will do
    }
    let g = |t: f64| (((t / m + 1.0) * 0.5 * GRID as f64) as usize).min(GRID - 1);
    (face * GRID + g(u)) * GRID + g(v)
}

/// The direction through the centre of cube-map cell `c` (see [`cell`]).
fn cell_center(c: usize) -> Vector {
    let (face, rest) = (c / (GRID * GRID), c % (GRID * GRID));
    let t = |i: usize| (i as f64 + 0.5) / GRID as f64 * 2.0 - 1.0;
    let (u, v) = (t(rest / GRID), t(rest % GRID));
    let sign = if face % 2 == 0 { 1.0 } else { -1.0 };
    match face / 2 {
        0 => Vector::new(sign, u, v),
        1 => Vector::new(v, sign, u),
        _ => Vector::new(u, v, sign),
    }
}

/// A convex polyhedron with its vertex graph, for fast support points (see the module
/// documentation).
#[derive(Clone, Debug)]
pub struct ClimbingHull {
    points: Vec<Vector>,
    /// Neighbours of vertex `i`: `adjacent[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<u32>,
    adjacent: Vec<u32>,
    /// Per cube-map cell ([`cell`]), the start vertex of the climb: the farthest vertex along
    /// the cell's centre direction.
    seeds: Vec<u32>,
}

impl ClimbingHull {
    /// The hull of `poly`: its vertices that lie on a face, linked along the faces' edges.
    /// `None` when no face has three vertices (a degenerate polyhedron).
    pub fn new(poly: &ConvexPolyhedron) -> Option<Self> {
        let n = poly.points().len();
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let ring = poly.vertices_adj_to_face();
        for face in poly.faces() {
            let start = face.first_vertex_or_edge as usize;
            let count = face.num_vertices_or_edges as usize;
            if count < 3 {
                continue;
            }
            let cycle = &ring[start..start + count];
            for (k, &a) in cycle.iter().enumerate() {
                let b = cycle[(k + 1) % count];
                if a != b {
                    pairs.push((a, b));
                    pairs.push((b, a));
                }
            }
        }
        if pairs.is_empty() {
            return None;
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut offsets = vec![0u32; n + 1];
        for &(a, _) in &pairs {
            offsets[a as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let adjacent: Vec<u32> = pairs.iter().map(|&(_, b)| b).collect();
        let on_face = |i: usize| offsets[i + 1] > offsets[i];
        let points = poly.points().to_vec();
        let seeds: Vec<u32> = (0..6 * GRID * GRID)
            .map(|c| {
                let dir = cell_center(c);
                (0..n)
                    .filter(|&i| on_face(i))
                    .max_by(|&i, &j| points[i].dot(dir).total_cmp(&points[j].dot(dir)))
                    .map_or(0, |i| i as u32)
            })
            .collect();
        Some(ClimbingHull {
            points,
            offsets,
            adjacent,
            seeds,
        })
    }

    /// GJK distance between the segment `a`–`b` (world coordinates) and this hull placed at
    /// `pose` (0 when they touch or overlap).
    #[inline]
    pub fn segment_distance(&self, pose: &Pose, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
        self.segment_distance_below(pose, a, b, f64::INFINITY)
            .unwrap_or(0.0)
    }

    /// As [`ClimbingHull::segment_distance`] when the distance is below `max`; otherwise
    /// `None` (GJK stops as soon as it proves the distance larger). Below `max` the answer is
    /// the one without the limit, bit for bit (the iterations are the same).
    #[inline]
    pub fn segment_distance_below(
        &self,
        pose: &Pose,
        a: &Point3<f64>,
        b: &Point3<f64>,
        max: f64,
    ) -> Option<f64> {
        let seg = Segment::new(to_parry_point(a), to_parry_point(b));
        // parry's `distance_support_map_support_map`, with the limit passed on to GJK.
        let dir = -pose.translation;
        let eps = parry3d_f64::math::DEFAULT_EPSILON;
        let dir = if dir.length_squared() > eps * eps {
            dir.normalize()
        } else {
            Vector::X
        };
        let mut simplex = VoronoiSimplex::new();
        simplex.reset(CsoPoint::from_shapes(pose, &seg, self, dir));
        match gjk::closest_points(pose, &seg, self, max, true, &mut simplex) {
            GJKResult::Intersection => Some(0.0),
            GJKResult::ClosestPoints(p1, p2, _) => Some((p1 - p2).length()),
            GJKResult::NoIntersection(_) if max.is_finite() => None,
            // As parry: GJK did not converge.
            GJKResult::NoIntersection(_) | GJKResult::Proximity(_) => Some(0.0),
        }
    }
}

impl SupportMap for ClimbingHull {
    #[inline]
    fn local_support_point(&self, dir: Vector) -> Vector {
        let mut best = self.seeds[cell(dir)] as usize;
        let mut best_dot = self.points[best].dot(dir);
        loop {
            let at = best;
            let (lo, hi) = (self.offsets[at] as usize, self.offsets[at + 1] as usize);
            for &k in &self.adjacent[lo..hi] {
                let d = self.points[k as usize].dot(dir);
                if d > best_dot {
                    best = k as usize;
                    best_dot = d;
                }
            }
            if best == at {
                return self.points[best];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d_f64::query;
    use rand::{RngExt, SeedableRng};

    fn random_hull(rng: &mut rand_chacha::ChaCha8Rng, n: usize) -> ConvexPolyhedron {
        let pts: Vec<Vector> = (0..n)
            .map(|_| {
                Vector::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-0.5..0.5),
                    rng.random_range(-2.0..2.0),
                )
            })
            .collect();
        ConvexPolyhedron::from_convex_hull(&pts).unwrap()
    }

    /// The climb finds the farthest vertex of the scan along random directions, on random
    /// hulls of 8 to 400 points (rounded boxes and near-coplanar clouds included).
    #[test]
    fn climbing_matches_the_scan() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for case in 0..60 {
            let n = 8 + case * 7;
            let poly = random_hull(&mut rng, n);
            let hull = ClimbingHull::new(&poly).unwrap();
            for _ in 0..300 {
                let dir = Vector::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                let want = poly.local_support_point(dir).dot(dir);
                let got = hull.local_support_point(dir).dot(dir);
                assert!(
                    (want - got).abs() <= 1e-12 * (1.0 + want.abs()),
                    "case {case}: climb {got} vs scan {want}"
                );
            }
        }
    }

    /// Segment distances agree with parry's query on the polyhedron itself.
    #[test]
    fn distances_match_parry() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for case in 0..40 {
            let poly = random_hull(&mut rng, 20 + case * 5);
            let hull = ClimbingHull::new(&poly).unwrap();
            let pose = Pose::from_translation(Vector::new(0.3, -0.2, 0.1));
            for _ in 0..50 {
                let mut p = || {
                    Point3::new(
                        rng.random_range(-3.0..3.0),
                        rng.random_range(-3.0..3.0),
                        rng.random_range(-3.0..3.0),
                    )
                };
                let (a, b) = (p(), p());
                let seg = Segment::new(Vector::new(a.x, a.y, a.z), Vector::new(b.x, b.y, b.z));
                let want = query::distance(&Pose::IDENTITY, &seg, &pose, &poly)
                    .unwrap()
                    .distance;
                let got = hull.segment_distance(&pose, &a, &b);
                assert!(
                    (want - got).abs() <= 2e-7 * (1.0 + want),
                    "case {case}: {got} vs parry {want}"
                );
            }
        }
    }
}
