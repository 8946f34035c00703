//! Sines and cosines of joint angles four at a time.
//!
//! Forward kinematics takes the sine and cosine of every rotation axis; `libm::sincos` (the FreeBSD
//! `msun` algorithm: argument reduction by `π/2`, then the `k_sin` / `k_cos` polynomials) makes the
//! results the same on every platform. [`sincos_many`] gives exactly the values of `libm::sincos`,
//! bit for bit, for any number of angles in one call, and [`sincos_at`] for the angles at given
//! places of a vector (forward kinematics passes all the rotation axes it is about to evaluate,
//! read straight from the actuation vector), four at a time: on AVX2 lanes (detected at run time)
//! the small-argument path and the one-step reduction are computed for all four with the same
//! operations in the same order (no fused multiply-add), and any lane that `libm` would treat
//! otherwise (a tiny angle, one within rounding of a multiple of `π/2` that needs a second
//! reduction step, a huge or non-finite one) is recomputed by `libm` itself. Elsewhere the angles
//! are `libm::sincos` one by one.

/// `out[i] = (sin x[i], cos x[i])` for every angle of `x` (as many as `out` holds, which must
/// not exceed `x.len()`), exactly as `libm::sincos` gives them, four at a time, in one call so
/// that the blocks (independent of each other) overlap in the processor.
///
/// # Panics
/// When `out` is longer than `x`.
#[inline]
pub fn sincos_many(x: &[f64], out: &mut [(f64, f64)]) {
    let x = &x[..out.len()];
    sincos_by(|k| x[k], out);
}

/// The sines and cosines of `a[idx[k]]` into `out[k]`, for every `k` below `out.len()` (which
/// must not exceed `idx.len()`), exactly as `libm::sincos` gives them: [`sincos_many`] of the
/// angles at the indices `idx` of `a`, each lane read straight from `a` (no copy of the angles
/// into a buffer first, whose narrow writes a vector read could not take from the store buffer).
///
/// # Panics
/// When `out` is longer than `idx`, or an index is out of `a`.
#[inline]
pub fn sincos_at(a: &[f64], idx: &[usize], out: &mut [(f64, f64)]) {
    let idx = &idx[..out.len()];
    sincos_by(|k| a[idx[k]], out);
}

/// `out[k]` = the sine and cosine of `x(k)`, four lanes at a time on AVX2 when the processor
/// has it, else one by one with `libm`.
#[inline(always)]
fn sincos_by(x: impl Fn(usize) -> f64, out: &mut [(f64, f64)]) {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor supports AVX2 (just checked).
        unsafe { sincos_by_avx2(&x, out) };
        return;
    }
    for (k, o) in out.iter_mut().enumerate() {
        *o = libm::sincos(x(k));
    }
}

/// [`sincos_by`] on AVX2 lanes: blocks of four, the last block padded with zeros.
///
/// # Safety
/// The processor must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sincos_by_avx2<F: Fn(usize) -> f64>(x: &F, out: &mut [(f64, f64)]) {
    use std::arch::x86_64::_mm256_set_pd;
    for (b, os) in out.chunks_mut(4).enumerate() {
        let k = 4 * b;
        let m = os.len();
        let lane = |i: usize| if i < m { x(k + i) } else { 0.0 };
        let xv = _mm256_set_pd(lane(3), lane(2), lane(1), lane(0));
        // SAFETY: the processor supports AVX2 (the caller's contract).
        let sc = unsafe { sincos4_avx2(xv) };
        for (o, v) in os.iter_mut().zip(sc) {
            *o = v;
        }
    }
}

// The constants of FreeBSD msun's `e_rem_pio2.c`, `k_sin.c` and `k_cos.c` (as in `libm`), by
// their bits: 2/π, π/2 in two parts, and the polynomials' coefficients.
#[cfg(target_arch = "x86_64")]
const TO_INT: f64 = 1.5 / f64::EPSILON;
#[cfg(target_arch = "x86_64")]
const INV_PIO2: f64 = f64::from_bits(0x3fe4_5f30_6dc9_c883);
#[cfg(target_arch = "x86_64")]
const PIO2_1: f64 = f64::from_bits(0x3ff9_21fb_5440_0000);
#[cfg(target_arch = "x86_64")]
const PIO2_1T: f64 = f64::from_bits(0x3dd0_b461_1a62_6331);
#[cfg(target_arch = "x86_64")]
const S1: f64 = f64::from_bits(0xbfc5_5555_5555_5549);
#[cfg(target_arch = "x86_64")]
const S2: f64 = f64::from_bits(0x3f81_1111_1110_f8a6);
#[cfg(target_arch = "x86_64")]
const S3: f64 = f64::from_bits(0xbf2a_01a0_19c1_61d5);
#[cfg(target_arch = "x86_64")]
const S4: f64 = f64::from_bits(0x3ec7_1de3_57b1_fe7d);
#[cfg(target_arch = "x86_64")]
const S5: f64 = f64::from_bits(0xbe5a_e5e6_8a2b_9ceb);
#[cfg(target_arch = "x86_64")]
const S6: f64 = f64::from_bits(0x3de5_d93a_5acf_d57c);
#[cfg(target_arch = "x86_64")]
const C1: f64 = f64::from_bits(0x3fa5_5555_5555_554c);
#[cfg(target_arch = "x86_64")]
const C2: f64 = f64::from_bits(0xbf56_c16c_16c1_5177);
#[cfg(target_arch = "x86_64")]
const C3: f64 = f64::from_bits(0x3efa_01a0_19cb_1590);
#[cfg(target_arch = "x86_64")]
const C4: f64 = f64::from_bits(0xbe92_7e4f_809c_52ad);
#[cfg(target_arch = "x86_64")]
const C5: f64 = f64::from_bits(0x3e21_ee9e_bdb4_b1c4);
#[cfg(target_arch = "x86_64")]
const C6: f64 = f64::from_bits(0xbda8_fae9_be88_38d4);

/// `libm::sincos` of four angles on AVX2 lanes.
///
/// `libm::sincos(x)` with `ix` the high word of `|x|`: for `ix < 0x3e46a09e` it returns
/// `(x, 1)`; up to `ix ≤ 0x3fe921fb` (`|x| ≲ π/4`) the polynomials of `x` itself
/// (`k_sin(x, 0, 0)`, `k_cos(x, 0)`); above, `rem_pio2` writes `x = n·π/2 + y0 + y1` and the
/// result is `k_sin(y0, y1, 1)`, `k_cos(y0, y1)` rotated by the quadrant `n mod 4`. Up to
/// `9π/4` `rem_pio2` takes `n` from thresholds on `ix` and subtracts `n·PIO2_1` and
/// `n·PIO2_1T` once, which is its "medium" path's first step with the same `n`; up to
/// `2^20·π/2` the medium path takes `n = rint(x·2/π)` and adds further steps only when the
/// first cancels more than 16 bits. Here every lane takes `n = rint(x·2/π)` and the first
/// step; lanes whose thresholds pick another `n`, that hit the medium path's special cases
/// near `π/2`, `π`, `3π/2` and `2π`, that need a second step, or that are tiny, huge or not
/// finite are recomputed by `libm::sincos`.
///
/// # Safety
/// The processor must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn sincos4_avx2(xv: std::arch::x86_64::__m256d) -> [(f64, f64); 4] {
    use std::arch::x86_64::*;
    let add = |a, b| _mm256_add_pd(a, b);
    let sub = |a, b| _mm256_sub_pd(a, b);
    let mul = |a, b| _mm256_mul_pd(a, b);
    let set = |v: f64| _mm256_set1_pd(v);
    let seti = |v: i64| _mm256_set1_epi64x(v);
    let gt = |a, b| _mm256_cmpgt_epi64(a, b);
    let eq = |a, b| _mm256_cmpeq_epi64(a, b);
    let or = |a, b| _mm256_or_si256(a, b);
    let and = |a, b| _mm256_and_si256(a, b);
    let bits = _mm256_castpd_si256(xv);
    // ix: the high word of |x|, per 64-bit lane.
    let ix = _mm256_srli_epi64::<32>(and(bits, seti(0x7fff_ffff_ffff_ffff)));
    // The reduction: n = rint(x·2/π), y0 + y1 = x − n·π/2 (first step).
    let tmp = add(mul(xv, set(INV_PIO2)), set(TO_INT));
    let f_n = sub(tmp, set(TO_INT));
    let r = sub(xv, mul(f_n, set(PIO2_1)));
    let w = mul(f_n, set(PIO2_1T));
    let y0r = sub(r, w);
    let y1r = sub(sub(r, y0r), w);
    // Lanes with |x| ≲ π/4 take x itself, no reduction, and quadrant 0.
    let small = _mm256_castsi256_pd(gt(seti(0x3fe9_21fc), ix));
    let y0 = _mm256_blendv_pd(y0r, xv, small);
    let y1 = _mm256_blendv_pd(y1r, _mm256_setzero_pd(), small);
    // k_sin(y0, y1, 1) (and k_sin(x, 0, 0) for the small lanes), k_cos(y0, y1).
    let z = mul(y0, y0);
    let ww = mul(z, z);
    let rs = add(
        add(set(S2), mul(z, add(set(S3), mul(z, set(S4))))),
        mul(mul(z, ww), add(set(S5), mul(z, set(S6)))),
    );
    let v = mul(z, y0);
    let sin_reduced = sub(
        y0,
        sub(
            sub(mul(z, sub(mul(set(0.5), y1), mul(v, rs))), y1),
            mul(v, set(S1)),
        ),
    );
    let sin_small = add(y0, mul(v, add(set(S1), mul(z, rs))));
    let s = _mm256_blendv_pd(sin_reduced, sin_small, small);
    let rc = add(
        mul(z, add(set(C1), mul(z, add(set(C2), mul(z, set(C3)))))),
        mul(
            mul(ww, ww),
            add(set(C4), mul(z, add(set(C5), mul(z, set(C6))))),
        ),
    );
    let hz = mul(set(0.5), z);
    let wc = sub(set(1.0), hz);
    let c = add(
        wc,
        add(sub(sub(set(1.0), wc), hz), sub(mul(z, rc), mul(y0, y1))),
    );
    // Quadrant n mod 4 from the low bits of tmp (2^51 + n in its mantissa), 0 when small.
    let q = _mm256_andnot_si256(
        _mm256_castpd_si256(small),
        and(_mm256_castpd_si256(tmp), seti(3)),
    );
    let odd = _mm256_castsi256_pd(eq(and(q, seti(1)), seti(1)));
    let neg_s = _mm256_castsi256_pd(_mm256_slli_epi64::<63>(_mm256_srli_epi64::<1>(q)));
    // Quadrants 0–3: sin = s, c, −s, −c; cos = c, −s, −c, s.
    let sin = _mm256_xor_pd(_mm256_blendv_pd(s, c, odd), neg_s);
    let q1 = _mm256_add_epi64(q, seti(1));
    let neg_c = _mm256_castsi256_pd(_mm256_slli_epi64::<63>(_mm256_srli_epi64::<1>(q1)));
    let cos = _mm256_xor_pd(_mm256_blendv_pd(c, s, odd), neg_c);
    // Lanes libm treats otherwise.
    let tiny = gt(seti(0x3e46_a09e), ix);
    let huge = gt(ix, seti(0x4139_21fa));
    let special = or(
        or(eq(ix, seti(0x3ff9_21fb)), eq(ix, seti(0x4009_21fb))),
        or(eq(ix, seti(0x4012_d97c)), eq(ix, seti(0x4019_21fb))),
    );
    // Up to 9π/4 (and above π/4): the n libm's thresholds give, |n| = 1 + the thresholds
    // passed, must be |rint(x·2/π)|.
    let fixed = and(gt(ix, seti(0x3fe9_21fb)), gt(seti(0x401c_463c), ix));
    let one_if = |m: __m256i| _mm256_and_pd(_mm256_castsi256_pd(m), set(1.0));
    let k = add(
        add(
            add(set(1.0), one_if(gt(ix, seti(0x4002_d97c)))),
            one_if(gt(ix, seti(0x400f_6a7a))),
        ),
        one_if(gt(ix, seti(0x4015_fdbc))),
    );
    let f_abs = _mm256_andnot_pd(set(-0.0), f_n);
    let k_f = _mm256_castpd_si256(_mm256_cmp_pd::<_CMP_NEQ_UQ>(f_abs, k));
    let mismatch = and(fixed, k_f);
    // Above 9π/4: the medium path adds a step when ex − ey > 16.
    let ex = _mm256_srli_epi64::<20>(ix);
    let ey = and(
        _mm256_srli_epi64::<52>(_mm256_castpd_si256(y0r)),
        seti(0x7ff),
    );
    let medium = gt(ix, seti(0x401c_463b));
    let second = and(medium, gt(_mm256_sub_epi64(ex, ey), seti(16)));
    let redo = or(or(tiny, huge), or(or(special, mismatch), second));
    let mut s_out = [0.0; 4];
    let mut c_out = [0.0; 4];
    _mm256_storeu_pd(s_out.as_mut_ptr(), sin);
    _mm256_storeu_pd(c_out.as_mut_ptr(), cos);
    let mut out = [(0.0, 0.0); 4];
    let redo = _mm256_movemask_pd(_mm256_castsi256_pd(redo));
    for (i, o) in out.iter_mut().enumerate() {
        *o = (s_out[i], c_out[i]);
    }
    if redo != 0 {
        let mut x = [0.0; 4];
        _mm256_storeu_pd(x.as_mut_ptr(), xv);
        for (i, o) in out.iter_mut().enumerate() {
            if redo & (1 << i) != 0 {
                *o = libm::sincos(x[i]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// [`sincos_many`] is `libm::sincos` bit for bit at every length (blocks of four and a
    /// partial last block) and writes exactly as many values as `out` holds.
    #[test]
    fn many_at_once_are_libm_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        for len in 0..40 {
            let x: Vec<f64> = (0..len + 3).map(|_| rng.random_range(-9.0..9.0)).collect();
            let mut out = vec![(f64::NAN, f64::NAN); len + 1];
            sincos_many(&x, &mut out[..len]);
            for (xi, oi) in x.iter().zip(&out[..len]) {
                same(*xi, *oi);
            }
            assert!(
                out[len].0.is_nan() && out[len].1.is_nan(),
                "wrote past {len}"
            );
        }
    }

    /// [`sincos_at`] gives `libm::sincos` of the angles at the given indices, bit for bit, in
    /// their order (indices out of order and repeated), at every length, and writes exactly as
    /// many values as `out` holds; special angles on any lane are recomputed by `libm`.
    #[test]
    fn gathered_angles_are_libm_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        let mut a: Vec<f64> = (0..50).map(|_| rng.random_range(-9.0..9.0)).collect();
        a[7] = 1e-300;
        a[11] = f64::NAN;
        a[19] = 1e22;
        a[23] = std::f64::consts::FRAC_PI_2;
        for len in 0..40 {
            let idx: Vec<usize> = (0..len + 2).map(|_| rng.random_range(0..a.len())).collect();
            let mut out = vec![(f64::NAN, f64::NAN); len + 1];
            sincos_at(&a, &idx, &mut out[..len]);
            for (&j, oi) in idx.iter().zip(&out[..len]) {
                same(a[j], *oi);
            }
            assert!(
                out[len].0.is_nan() && out[len].1.is_nan(),
                "wrote past {len}"
            );
        }
    }

    fn same(x: f64, got: (f64, f64)) {
        let want = libm::sincos(x);
        assert!(
            got.0.to_bits() == want.0.to_bits() && got.1.to_bits() == want.1.to_bits()
                || (got.0.is_nan() && want.0.is_nan() && got.1.is_nan() && want.1.is_nan()),
            "sincos({x:e} = {:#x}): {got:?}, libm {want:?}",
            x.to_bits()
        );
    }

    /// Every lane is `libm::sincos` bit for bit: random angles over the ranges joints use
    /// and far beyond, the neighbourhoods (from a few ulps to about 2^-7 relative, so that the reduction cancels every
    /// number of bits) of every threshold and
    /// special case of the reduction and of multiples of `π/4`, zeros, tiny and huge values,
    /// infinities and NaN, in every lane position.
    #[test]
    fn four_at_once_are_libm_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut xs: Vec<f64> = Vec::new();
        for _ in 0..200_000 {
            xs.push(rng.random_range(-7.0..7.0));
        }
        for _ in 0..50_000 {
            let e: f64 = rng.random_range(-40.0..25.0);
            let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
            xs.push(sign * 2f64.powf(e));
        }
        let mut edges: Vec<f64> = (1..=40)
            .map(|k| k as f64 * std::f64::consts::FRAC_PI_4)
            .collect();
        for hi in [
            0x3e46_a09e_u64,
            0x3fe9_21fb,
            0x3ff9_21fb,
            0x4002_d97c,
            0x4009_21fb,
            0x400f_6a7a,
            0x4012_d97c,
            0x4015_fdbc,
            0x4019_21fb,
            0x401c_463b,
            0x4139_21fb,
        ] {
            edges.push(f64::from_bits(hi << 32));
            edges.push(f64::from_bits((hi << 32) | 0xffff_ffff));
            edges.push(f64::from_bits(((hi + 1) << 32) - 1));
            edges.push(f64::from_bits((hi + 1) << 32));
        }
        for e in edges {
            for d in -16i64..=16 {
                for scale in (0..46).map(|s| 1i64 << s) {
                    let b = (e.to_bits() as i64 + d * scale) as u64;
                    xs.push(f64::from_bits(b));
                    xs.push(-f64::from_bits(b));
                }
            }
        }
        xs.extend([
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            5e-324,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ]);
        for (i, chunk) in xs.chunks(4).enumerate() {
            let mut x = [0.0; 4];
            // Rotate the lanes so that every value visits every lane position.
            for (j, v) in chunk.iter().enumerate() {
                x[(j + i) % 4] = *v;
            }
            let mut got = [(0.0, 0.0); 4];
            sincos_many(&x, &mut got);
            for (xi, gi) in x.iter().zip(got) {
                same(*xi, gi);
            }
        }
    }
}
