//! Closed-form distances for the hot loops: point–segment and segment–segment.
//!
//! The paper's Eq. 14, `‖(c2 − c1) × (c1 − o)‖ / ‖c2 − c1‖`, is the distance from `o` to the
//! infinite *line* through `c1` and `c2`: it under-reports the distance to an obstacle beside the
//! line but beyond either end of the segment (a false hit), and divides by zero when the collider
//! did not move. We use the true distance to the *segment* (the projection parameter clamped to
//! `[0, 1]`), which equals Eq. 14 whenever the projection falls inside the segment and is
//! well-defined for a zero-length segment.

use nalgebra::{Point3, Vector3};

/// Distance from `p` to the segment `a`–`b` (clamped projection; a zero-length segment is the
/// point `a`). Corrects paper Eq. 14, see the module documentation.
#[inline]
pub fn point_segment(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let ap = p - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        (ap.dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (ap - ab * t).norm()
}

/// Signed distance between the segment `a`–`b` and the sphere (`center`, `radius`): negative
/// when they overlap. This is the paper's test of a collider's path against an obstacle
/// (Eq. 14–15) with the segment distance in place of the line distance.
#[inline]
pub fn segment_sphere(a: &Point3<f64>, b: &Point3<f64>, center: &Point3<f64>, radius: f64) -> f64 {
    point_segment(center, a, b) - radius
}

/// The paper's Eq. 14 as printed: distance from `o` to the infinite line through `c1`, `c2`.
/// Kept only to document (and test) how it differs from [`point_segment`]; NaN when `c1 = c2`.
pub fn paper_eq14_line_distance(o: &Point3<f64>, c1: &Point3<f64>, c2: &Point3<f64>) -> f64 {
    (c2 - c1).cross(&(c1 - o)).norm() / (c2 - c1).norm()
}

/// Squared distance between segments `p1`–`q1` and `p2`–`q2` (Ericson, *Real-Time Collision
/// Detection*, §5.1.9), robust to zero-length and parallel segments.
#[inline]
pub fn segment_segment_squared(
    p1: &Point3<f64>,
    q1: &Point3<f64>,
    p2: &Point3<f64>,
    q2: &Point3<f64>,
) -> f64 {
    const EPS: f64 = 1e-300;
    let d1: Vector3<f64> = q1 - p1;
    let d2: Vector3<f64> = q2 - p2;
    let r = p1 - p2;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let f = d2.dot(&r);
    let (s, t);
    if a <= EPS && e <= EPS {
        return r.norm_squared();
    }
    if a <= EPS {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(&r);
        if e <= EPS {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s0 = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t0 = 0.0;
                s0 = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t0 = 1.0;
                s0 = ((b - c) / a).clamp(0.0, 1.0);
            }
            s = s0;
            t = t0;
        }
    }
    let c1 = p1 + d1 * s;
    let c2 = p2 + d2 * t;
    (c1 - c2).norm_squared()
}

/// Distance between two segments; see [`segment_segment_squared`].
#[inline]
pub fn segment_segment(
    p1: &Point3<f64>,
    q1: &Point3<f64>,
    p2: &Point3<f64>,
    q2: &Point3<f64>,
) -> f64 {
    segment_segment_squared(p1, q1, p2, q2).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pt() -> impl Strategy<Value = Point3<f64>> {
        (-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
    }

    /// Brute force: minimum over `n + 1` evenly spaced points of the segment.
    fn brute_point_segment(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>, n: usize) -> f64 {
        (0..=n)
            .map(|i| (p - (a + (b - a) * (i as f64 / n as f64))).norm())
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn eq14_is_the_line_distance_and_fails_beyond_the_ends() {
        let a = Point3::new(0.0, 0.0, 0.0);
        let b = Point3::new(1.0, 0.0, 0.0);
        let o = Point3::new(3.0, 0.5, 0.0); // beside the line, past b
        assert!((paper_eq14_line_distance(&o, &a, &b) - 0.5).abs() < 1e-15);
        assert!((point_segment(&o, &a, &b) - (4.0f64 + 0.25).sqrt()).abs() < 1e-15);
        assert!(paper_eq14_line_distance(&o, &a, &a).is_nan());
        assert!((point_segment(&o, &a, &a) - (9.0f64 + 0.25).sqrt()).abs() < 1e-15);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn point_segment_matches_brute_force(p in pt(), a in pt(), b in pt()) {
            // The brute-force minimum over 10,000 points differs from the true one by at most
            // half the sample spacing squared over the distance; bound that error explicitly.
            let n = 10_000;
            let exact = point_segment(&p, &a, &b);
            let brute = brute_point_segment(&p, &a, &b, n);
            let h = (b - a).norm() / n as f64;
            let tol = 1e-9 + if exact > 0.0 { h * h / (8.0 * exact) } else { h };
            prop_assert!(exact <= brute + 1e-12, "exact {exact} above brute {brute}");
            prop_assert!(brute - exact <= tol, "exact {exact} brute {brute} tol {tol}");
        }

        #[test]
        fn segment_sphere_matches_brute_force(c in pt(), a in pt(), b in pt(), r in 0.0..1.0f64) {
            // Brute force over 10,000 points of the segment. Where the nearest point falls
            // between two samples the sampled minimum overshoots by at most h²/(8d) (h the
            // sample spacing, d the distance); the tolerance is 1e-9 plus that bound.
            let n = 10_000;
            let exact = segment_sphere(&a, &b, &c, r);
            let brute = brute_point_segment(&c, &a, &b, n) - r;
            let d = exact + r;
            let h = (b - a).norm() / n as f64;
            let tol = 1e-9 + if d > 0.0 { h * h / (8.0 * d) } else { h };
            prop_assert!(exact <= brute + 1e-12 && brute - exact <= tol,
                "exact {exact} brute {brute} tol {tol}");
        }

        #[test]
        fn segment_sphere_exact_cases(c in pt(), a in pt(), r in 0.0..1.0f64, s in 0.01..2.0f64) {
            // Zero-length segment: the point's distance, no NaN.
            let exact = segment_sphere(&a, &a, &c, r);
            prop_assert!(exact.is_finite());
            prop_assert!((exact - ((c - a).norm() - r)).abs() <= 1e-9);
            // Endpoint-nearest: the centre lies beyond b; brute force samples b exactly.
            let b = a + Vector3::new(0.3, -0.2, 0.5);
            let centre = b + (b - a).normalize() * s;
            let brute = brute_point_segment(&centre, &a, &b, 10_000) - r;
            prop_assert!((segment_sphere(&a, &b, &centre, r) - brute).abs() <= 1e-9);
        }

        #[test]
        fn point_segment_zero_length(p in pt(), a in pt()) {
            prop_assert!((point_segment(&p, &a, &a) - (p - a).norm()).abs() < 1e-12);
        }

        #[test]
        fn endpoint_nearest_cases(a in pt(), b in pt(), s in 0.01..2.0f64) {
            // A point beyond b along the segment direction: nearest to b.
            prop_assume!((b - a).norm() > 1e-3);
            let dir = (b - a).normalize();
            let p = b + dir * s;
            prop_assert!((point_segment(&p, &a, &b) - s).abs() < 1e-9);
            let p = a - dir * s;
            prop_assert!((point_segment(&p, &a, &b) - s).abs() < 1e-9);
        }

        #[test]
        fn segment_segment_matches_brute_force(p1 in pt(), q1 in pt(), p2 in pt(), q2 in pt()) {
            let exact = segment_segment(&p1, &q1, &p2, &q2);
            let n = 300;
            let mut brute = f64::INFINITY;
            for i in 0..=n {
                let x = p1 + (q1 - p1) * (i as f64 / n as f64);
                brute = brute.min(point_segment(&x, &p2, &q2));
            }
            prop_assert!(exact <= brute + 1e-9, "exact {exact} brute {brute}");
            let h = (q1 - p1).norm() / n as f64;
            prop_assert!(brute - exact <= h + 1e-9, "exact {exact} brute {brute}");
        }
    }

    #[test]
    fn segment_segment_degenerate_and_parallel() {
        let o = Point3::origin();
        let x = Point3::new(1.0, 0.0, 0.0);
        let y1 = Point3::new(0.0, 1.0, 0.0);
        let y2 = Point3::new(1.0, 1.0, 0.0);
        assert!((segment_segment(&o, &x, &y1, &y2) - 1.0).abs() < 1e-15);
        assert!((segment_segment(&o, &o, &y1, &y1) - 1.0).abs() < 1e-15);
        assert!((segment_segment(&o, &o, &y1, &y2) - 1.0).abs() < 1e-15);
        let z = Point3::new(0.5, -1.0, 1.0);
        let z2 = Point3::new(0.5, 1.0, 1.0);
        assert!((segment_segment(&o, &x, &z, &z2) - 1.0).abs() < 1e-15);
    }
}
