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

/// A pair of segments, each as its two end points.
pub type SegmentPair<'a> = (&'a [Point3<f64>; 2], &'a [Point3<f64>; 2]);

/// [`segment_segment_squared`] of four pairs of segments at once (`pairs[i]` = `([p1, q1],
/// [p2, q2])`), on AVX2 vector lanes: every branch of the scalar version computed and the
/// right one selected per lane, with the same operations in the same order (no fused
/// multiply-add), so the same values bit for bit.
///
/// # Safety
/// The processor must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub unsafe fn segment_segment_squared_x4(pairs: [SegmentPair<'_>; 4]) -> [f64; 4] {
    use std::arch::x86_64::*;
    const EPS: f64 = 1e-300;
    // Lane i holds pair i.
    macro_rules! lanes {
        ($side:tt, $end:expr, $c:expr) => {
            _mm256_set_pd(
                pairs[3].$side[$end][$c],
                pairs[2].$side[$end][$c],
                pairs[1].$side[$end][$c],
                pairs[0].$side[$end][$c],
            )
        };
    }
    let (p1x, p1y, p1z) = (lanes!(0, 0, 0), lanes!(0, 0, 1), lanes!(0, 0, 2));
    let (q1x, q1y, q1z) = (lanes!(0, 1, 0), lanes!(0, 1, 1), lanes!(0, 1, 2));
    let (p2x, p2y, p2z) = (lanes!(1, 0, 0), lanes!(1, 0, 1), lanes!(1, 0, 2));
    let (q2x, q2y, q2z) = (lanes!(1, 1, 0), lanes!(1, 1, 1), lanes!(1, 1, 2));
    let add = |x, y| _mm256_add_pd(x, y);
    let sub = |x, y| _mm256_sub_pd(x, y);
    let mul = |x, y| _mm256_mul_pd(x, y);
    let div = |x, y| _mm256_div_pd(x, y);
    let dot = |x: [__m256d; 3], y: [__m256d; 3]| {
        add(add(mul(x[0], y[0]), mul(x[1], y[1])), mul(x[2], y[2]))
    };
    let (zero, one, eps) = (
        _mm256_setzero_pd(),
        _mm256_set1_pd(1.0),
        _mm256_set1_pd(EPS),
    );
    let clamp = |x| _mm256_min_pd(_mm256_max_pd(x, zero), one);
    let select = |mask, yes, no| _mm256_blendv_pd(no, yes, mask);
    let d1 = [sub(q1x, p1x), sub(q1y, p1y), sub(q1z, p1z)];
    let d2 = [sub(q2x, p2x), sub(q2y, p2y), sub(q2z, p2z)];
    let r = [sub(p1x, p2x), sub(p1y, p2y), sub(p1z, p2z)];
    let a = dot(d1, d1);
    let e = dot(d2, d2);
    let f = dot(d2, r);
    let c = dot(d1, r);
    let b = dot(d1, d2);
    let a_small = _mm256_cmp_pd::<_CMP_LE_OQ>(a, eps);
    let e_small = _mm256_cmp_pd::<_CMP_LE_OQ>(e, eps);
    // Neither is short.
    let denom = sub(mul(a, e), mul(b, b));
    let s0 = select(
        _mm256_cmp_pd::<_CMP_GT_OQ>(denom, zero),
        clamp(div(sub(mul(b, f), mul(c, e)), denom)),
        zero,
    );
    let t0 = div(add(mul(b, s0), f), e);
    let below = _mm256_cmp_pd::<_CMP_LT_OQ>(t0, zero);
    let above = _mm256_cmp_pd::<_CMP_GT_OQ>(t0, one);
    let neg_c = _mm256_xor_pd(c, _mm256_set1_pd(-0.0));
    let s_c = clamp(div(neg_c, a));
    let s_general = select(below, s_c, select(above, clamp(div(sub(b, c), a)), s0));
    let t_general = select(below, zero, select(above, one, t0));
    // The first segment short: s = 0, t = clamp(f / e); the second short: t = 0, s = clamp(−c
    // / a); both: s = t = 0 (the difference is then `r`, up to the sign of a zero).
    let s = select(a_small, zero, select(e_small, s_c, s_general));
    let t = select(
        a_small,
        select(e_small, zero, clamp(div(f, e))),
        select(e_small, zero, t_general),
    );
    let w = [
        sub(add(p1x, mul(d1[0], s)), add(p2x, mul(d2[0], t))),
        sub(add(p1y, mul(d1[1], s)), add(p2y, mul(d2[1], t))),
        sub(add(p1z, mul(d1[2], s)), add(p2z, mul(d2[2], t))),
    ];
    let mut out = [0.0; 4];
    // SAFETY: `out` holds four lanes.
    unsafe { _mm256_storeu_pd(out.as_mut_ptr(), dot(w, w)) };
    out
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

/// Distance between the segment `p`–`q` and the box `[-h, h]` (half extents `h ≥ 0`, the
/// box's own frame); 0 when they meet. The squared distance of the point `p + t·(q − p)` to the
/// box is convex and piecewise quadratic in `t`, with pieces split where a coordinate crosses
/// a face plane: each piece's quadratic is minimised in closed form.
#[inline]
pub fn segment_box(p: &Point3<f64>, q: &Point3<f64>, h: &Vector3<f64>) -> f64 {
    let d = q - p;
    // Breakpoints in (0, 1): where a coordinate reaches ±h.
    let mut ts = [0.0f64; 8];
    let mut n = 0;
    ts[n] = 0.0;
    n += 1;
    for i in 0..3 {
        if d[i] != 0.0 {
            for face in [-h[i], h[i]] {
                let t = (face - p[i]) / d[i];
                if t > 0.0 && t < 1.0 {
                    ts[n] = t;
                    n += 1;
                }
            }
        }
    }
    ts[n] = 1.0;
    n += 1;
    let ts = &mut ts[..n];
    ts.sort_unstable_by(f64::total_cmp);
    let outside = |t: f64| {
        let x = p + d * t;
        Vector3::from_fn(|i, _| (x[i].abs() - h[i]).max(0.0)).norm_squared()
    };
    let mut best = outside(0.0).min(outside(1.0));
    for w in ts.windows(2) {
        let (t0, t1) = (w[0], w[1]);
        if t1 <= t0 {
            continue;
        }
        // On this piece every coordinate stays on one side of each face: the squared
        // distance is Σ (p_i + t·d_i − s_i)² over the coordinates outside (s_i = ±h_i).
        let mid = p + d * (0.5 * (t0 + t1));
        let (mut a, mut b) = (0.0, 0.0);
        for i in 0..3 {
            let s = if mid[i] > h[i] {
                h[i]
            } else if mid[i] < -h[i] {
                -h[i]
            } else {
                continue;
            };
            a += d[i] * d[i];
            b += d[i] * (p[i] - s);
        }
        let t = if a > 0.0 { (-b / a).clamp(t0, t1) } else { t0 };
        best = best.min(outside(t));
    }
    best.sqrt()
}

/// Squared distance from `p` to the triangle `a`, `b`, `c` (Ericson, *Real-Time Collision
/// Detection*, §5.1.5: the closest point by Voronoi regions). A degenerate triangle falls back
/// to its edges.
#[inline]
pub fn point_triangle_squared(
    p: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.norm_squared();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.norm_squared();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (ap - ab * v).norm_squared();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.norm_squared();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (ap - ac * w).norm_squared();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (bp - (c - b) * w).norm_squared();
    }
    let sum = va + vb + vc;
    if sum.is_nan() || sum.abs() <= f64::MIN_POSITIVE || !sum.is_finite() {
        // Degenerate (collinear or repeated corners): the nearest edge.
        return point_segment(p, a, b)
            .min(point_segment(p, b, c))
            .min(point_segment(p, c, a))
            .powi(2);
    }
    let (v, w) = (vb / sum, vc / sum);
    (ap - ab * v - ac * w).norm_squared()
}

/// True when the segment `p`–`q` meets the triangle `a`, `b`, `c` (both closed).
#[inline]
fn segment_crosses_triangle(
    p: &Point3<f64>,
    q: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> bool {
    let n = (b - a).cross(&(c - a));
    let (sp, sq) = (n.dot(&(p - a)), n.dot(&(q - a)));
    if (sp > 0.0 && sq > 0.0) || (sp < 0.0 && sq < 0.0) || sp == sq {
        // Both ends strictly on one side, or the segment parallel to (or in) the plane: any
        // contact is then at an end point or with an edge, which the distance covers.
        return false;
    }
    let t = sp / (sp - sq);
    let x = p + (q - p) * t;
    let inside = |u: &Point3<f64>, v: &Point3<f64>| n.dot(&(v - u).cross(&(x - u))) >= 0.0;
    inside(a, b) && inside(b, c) && inside(c, a)
}

/// Distance between the segment `p`–`q` and the triangle `a`, `b`, `c`: 0 when they meet,
/// otherwise the smallest of the end points' distances to the triangle and the segment's
/// distances to the three edges (where a disjoint segment and triangle come closest).
#[inline]
pub fn segment_triangle(
    p: &Point3<f64>,
    q: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> f64 {
    if segment_crosses_triangle(p, q, a, b, c) {
        return 0.0;
    }
    point_triangle_squared(p, a, b, c)
        .min(point_triangle_squared(q, a, b, c))
        .min(segment_segment_squared(p, q, a, b))
        .min(segment_segment_squared(p, q, b, c))
        .min(segment_segment_squared(p, q, c, a))
        .sqrt()
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

    proptest! {
        /// The segment–box distance against parry's GJK on the same box and against a dense
        /// sample of the segment (the point–box distance is exact), for segments outside,
        /// grazing and through the box.
        #[test]
        fn segment_box_matches_parry_and_brute_force(
            p in pt(), q in pt(), hx in 0.0f64..1.0, hy in 0.0f64..1.0, hz in 0.0f64..1.0
        ) {
            let h = Vector3::new(hx, hy, hz);
            let exact = segment_box(&p, &q, &h);
            let n = 2000;
            let mut brute = f64::INFINITY;
            for i in 0..=n {
                let x = p + (q - p) * (i as f64 / n as f64);
                let out = Vector3::from_fn(|k, _| (x[k].abs() - h[k]).max(0.0));
                brute = brute.min(out.norm());
            }
            prop_assert!(exact <= brute + 1e-12, "exact {exact} brute {brute}");
            prop_assert!(brute - exact <= (q - p).norm() / n as f64 + 1e-12, "exact {exact} brute {brute}");
            let to = |x: &Point3<f64>| parry3d_f64::math::Vector::new(x.x, x.y, x.z);
            let seg = parry3d_f64::shape::Segment::new(to(&p), to(&q));
            let cuboid = parry3d_f64::shape::Cuboid::new(parry3d_f64::math::Vector::new(hx, hy, hz));
            let id = parry3d_f64::math::Pose::IDENTITY;
            let gjk = parry3d_f64::query::distance(&id, &seg, &id, &cuboid).unwrap().distance;
            prop_assert!((gjk - exact).abs() <= 2e-7 * (1.0 + exact), "exact {exact} parry {gjk}");
        }

        /// The point–triangle distance against a dense sample of the triangle, for points
        /// anywhere and for points just off the triangle's face.
        #[test]
        fn point_triangle_matches_brute_force(
            p in pt(), a in pt(), b in pt(), c in pt(), u in 0.0f64..1.0, v in 0.0f64..1.0,
            lift in -0.3f64..0.3
        ) {
            let n_hat = (b - a).cross(&(c - a)).try_normalize(1e-9);
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let over = n_hat.map(|n| a + (b - a) * u + (c - a) * v + n * lift);
            for x in std::iter::once(p).chain(over) {
                let exact = point_triangle_squared(&x, &a, &b, &c).sqrt();
                let n = 60;
                let mut brute = f64::INFINITY;
                for j in 0..=n {
                    for k in 0..=(n - j) {
                        let t = a + (b - a) * (j as f64 / n as f64) + (c - a) * (k as f64 / n as f64);
                        brute = brute.min((x - t).norm());
                    }
                }
                prop_assert!(exact <= brute + 1e-9, "exact {exact} brute {brute}");
                let step = ((b - a).norm() + (c - a).norm()) / n as f64;
                prop_assert!(brute - exact <= step + 1e-9, "exact {exact} brute {brute}");
            }
        }

        /// The segment–triangle distance against a dense sample of both (never above it, and
        /// within the sampling step of it), and 0 exactly when parry finds them intersecting.
        #[test]
        fn segment_triangle_matches_brute_force(
            p in pt(), q in pt(), a in pt(), b in pt(), c in pt()
        ) {
            let exact = segment_triangle(&p, &q, &a, &b, &c);
            let n = 40;
            let mut brute = f64::INFINITY;
            for i in 0..=n {
                let s = p + (q - p) * (i as f64 / n as f64);
                for j in 0..=n {
                    for k in 0..=(n - j) {
                        let (u, v) = (j as f64 / n as f64, k as f64 / n as f64);
                        let t = a + (b - a) * u + (c - a) * v;
                        brute = brute.min((s - t).norm());
                    }
                }
            }
            prop_assert!(exact <= brute + 1e-9, "exact {exact} brute {brute}");
            let step = (q - p).norm() / n as f64
                + ((b - a).norm() + (c - a).norm()) / n as f64;
            prop_assert!(brute - exact <= step + 1e-9, "exact {exact} brute {brute}");
            let to = |x: &Point3<f64>| parry3d_f64::math::Vector::new(x.x, x.y, x.z);
            let seg = parry3d_f64::shape::Segment::new(to(&p), to(&q));
            let tri = parry3d_f64::shape::Triangle::new(to(&a), to(&b), to(&c));
            let id = parry3d_f64::math::Pose::IDENTITY;
            let gjk = parry3d_f64::query::distance(&id, &seg, &id, &tri).unwrap().distance;
            prop_assert!((gjk - exact).abs() <= 1e-7 * (1.0 + exact), "exact {exact} parry {gjk}");
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

    /// Four pairs at once give [`segment_segment_squared`]'s values bit for bit: random
    /// pairs, zero-length and nearly zero-length segments, parallel and crossing ones, shared
    /// end points, in every lane.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn four_pairs_at_once_are_one_by_one() {
        use rand::{RngExt, SeedableRng};
        if !std::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let point = |rng: &mut rand_chacha::ChaCha8Rng| {
            Point3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
        };
        let mut segments = Vec::new();
        for i in 0..4000 {
            let p = point(&mut rng);
            let q = match i % 6 {
                0 => p,
                1 => p + Vector3::new(1e-160, 0.0, 0.0),
                _ => point(&mut rng),
            };
            segments.push([p, q]);
        }
        // Parallel, collinear and touching pairs.
        for k in 0..500 {
            let [p, q] = segments[k];
            let shift = point(&mut rng).coords * 0.3;
            segments.push([p + shift, q + shift]);
            segments.push([q, p]);
            segments.push([p, p + (q - p) * 2.0]);
        }
        let n = segments.len();
        let mut cases = 0;
        for _ in 0..20_000 {
            let pick: [(usize, usize); 4] =
                std::array::from_fn(|_| (rng.random_range(0..n), rng.random_range(0..n)));
            let mut pairs = pick.map(|(i, j)| (&segments[i], &segments[j]));
            if rng.random_range(0..8) == 0 {
                pairs[1] = (pairs[1].0, pairs[1].0); // a segment with itself
            }
            // SAFETY: AVX2 is present (checked above).
            let got = unsafe { segment_segment_squared_x4(pairs) };
            for (g, (s1, s2)) in got.iter().zip(pairs) {
                let want = segment_segment_squared(&s1[0], &s1[1], &s2[0], &s2[1]);
                assert_eq!(g.to_bits(), want.to_bits(), "{s1:?} {s2:?}");
                cases += 1;
            }
        }
        assert_eq!(cases, 80_000);
    }
}
