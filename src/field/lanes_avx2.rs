//! [`super::cull`] and [`super::crossings`] with AVX2 intrinsics, eight rays per step: the
//! directions are loaded and transposed to structure-of-arrays form in registers, the cull runs
//! as 8 × f32 and the crossing as 2 × 4 × f64. Every lane performs the scalar code's IEEE
//! operations in its order (multiplications and additions kept apart, no fused multiply-add),
//! so the answers are the scalar ones bit for bit. Callers guarantee the CPU has AVX2.

use super::super::lookup::{SphereCrossing, SphereOrigin};
use super::{MayMeetFrom, LANES};
use crate::simd::x86::load3x8 as load_transposed;
use glam::{DVec3, Vec3};
use std::arch::x86_64::*;

/// [`super::cull`].
///
/// # Safety
/// The CPU must have AVX2; `idx` at least as long as `dirs`, `skip` as long as `dirs`.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn cull(
    meet: &MayMeetFrom,
    dirs: &[Vec3],
    tmin: f32,
    skip: &[bool],
    idx: &mut [u32],
) -> usize {
    let (f, reach) = (meet.f, meet.reach);
    let (fx, fy, fz) = (
        _mm256_set1_ps(f.x),
        _mm256_set1_ps(f.y),
        _mm256_set1_ps(f.z),
    );
    let reach_v = _mm256_set1_ps(reach);
    let reach2 = _mm256_set1_ps(reach * reach);
    let tmin_v = _mm256_set1_ps(tmin);
    let whole = dirs.len() / LANES * LANES;
    let mut n = 0;
    for base in (0..whole).step_by(LANES) {
        let (x, y, z) = load_transposed(dirs.as_ptr().add(base).cast());
        // MayMeetFrom::test: b = f·d; l = f − b d; |l|² ≤ reach² and b + reach ≥ tmin.
        let b = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(fx, x), _mm256_mul_ps(fy, y)),
            _mm256_mul_ps(fz, z),
        );
        let lx = _mm256_sub_ps(fx, _mm256_mul_ps(b, x));
        let ly = _mm256_sub_ps(fy, _mm256_mul_ps(b, y));
        let lz = _mm256_sub_ps(fz, _mm256_mul_ps(b, z));
        let l2 = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(lx, lx), _mm256_mul_ps(ly, ly)),
            _mm256_mul_ps(lz, lz),
        );
        let near = _mm256_cmp_ps::<_CMP_LE_OQ>(l2, reach2);
        let ahead = _mm256_cmp_ps::<_CMP_GE_OQ>(_mm256_add_ps(b, reach_v), tmin_v);
        let pass = _mm256_movemask_ps(_mm256_and_ps(near, ahead)) as u32;
        // Skip flags are bytes 0 or 1: the lanes whose flag is 0.
        let flags = _mm_loadl_epi64(skip.as_ptr().add(base).cast());
        let free = _mm_movemask_epi8(_mm_cmpeq_epi8(flags, _mm_setzero_si128())) as u32 & 0xff;
        let mut keep = pass & free;
        while keep != 0 {
            *idx.get_unchecked_mut(n) = (base as u32) + keep.trailing_zeros();
            n += 1;
            keep &= keep - 1;
        }
    }
    for i in whole..dirs.len() {
        idx[n] = i as u32;
        n += (!skip[i] && meet.test(dirs[i], tmin)) as usize;
    }
    n
}

/// [`super::crossings`].
///
/// # Safety
/// The CPU must have AVX2; `out` as long as `dirs`.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn crossings(
    from: &SphereOrigin,
    dirs: &[Vec3],
    out: &mut [Option<SphereCrossing>],
) {
    let (f, r, c) = from.terms();
    let (fx, fy, fz) = (
        _mm256_set1_pd(f.x),
        _mm256_set1_pd(f.y),
        _mm256_set1_pd(f.z),
    );
    let rr = _mm256_set1_pd(r * r);
    let c_v = _mm256_set1_pd(c);
    let whole = dirs.len() / LANES * LANES;
    for base in (0..whole).step_by(LANES) {
        let (x, y, z) = load_transposed(dirs.as_ptr().add(base).cast());
        for half in 0..2 {
            let widen = |v: __m256| {
                _mm256_cvtps_pd(if half == 0 {
                    _mm256_castps256_ps128(v)
                } else {
                    _mm256_extractf128_ps::<1>(v)
                })
            };
            let crossed = crossing4(fx, fy, fz, rr, c_v, widen(x), widen(y), widen(z));
            out[base + 4 * half..base + 4 * half + 4].copy_from_slice(&crossed);
        }
    }
    for i in whole..dirs.len() {
        out[i] = from.crossing(dirs[i]);
    }
}

/// `SphereOrigin::crossing` of four directions, in its order of operations; both
/// normalisation branches are computed and the scalar code's one selected per lane.
#[allow(clippy::too_many_arguments)]
#[inline]
#[target_feature(enable = "avx2")]
fn crossing4(
    fx: __m256d,
    fy: __m256d,
    fz: __m256d,
    rr: __m256d,
    c: __m256d,
    dx: __m256d,
    dy: __m256d,
    dz: __m256d,
) -> [Option<SphereCrossing>; 4] {
    let (mul, add, sub) = (_mm256_mul_pd, _mm256_add_pd, _mm256_sub_pd);
    let zero = _mm256_setzero_pd();
    let sign = _mm256_set1_pd(-0.0);
    // a = |d|²; |d|² ≈ 1: one Newton step d (1.5 − 0.5 a), else d / √a.
    let a = add(add(mul(dx, dx), mul(dy, dy)), mul(dz, dz));
    let off = _mm256_andnot_pd(sign, sub(a, _mm256_set1_pd(1.0)));
    let near = _mm256_cmp_pd::<_CMP_LT_OQ>(off, _mm256_set1_pd(1e-6));
    let newton = sub(_mm256_set1_pd(1.5), mul(_mm256_set1_pd(0.5), a));
    let root = _mm256_sqrt_pd(a);
    let unit = |d: __m256d| _mm256_blendv_pd(_mm256_div_pd(d, root), mul(d, newton), near);
    let (dx, dy, dz) = (unit(dx), unit(dy), unit(dz));
    // b = −f·d; l = f + b d; disc = r² − |l|².
    let b = _mm256_xor_pd(add(add(mul(fx, dx), mul(fy, dy)), mul(fz, dz)), sign);
    let (lx, ly, lz) = (
        add(fx, mul(b, dx)),
        add(fy, mul(b, dy)),
        add(fz, mul(b, dz)),
    );
    let disc = sub(rr, add(add(mul(lx, lx), mul(ly, ly)), mul(lz, lz)));
    let hit = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_GE_OQ>(disc, zero));
    let s = _mm256_sqrt_pd(disc);
    let q = _mm256_blendv_pd(sub(b, s), add(b, s), _mm256_cmp_pd::<_CMP_GE_OQ>(b, zero));
    let q_zero = _mm256_cmp_pd::<_CMP_EQ_OQ>(q, zero);
    let t0 = _mm256_blendv_pd(_mm256_div_pd(c, q), zero, q_zero);
    let t1 = _mm256_blendv_pd(q, zero, q_zero);
    let ordered = _mm256_cmp_pd::<_CMP_LE_OQ>(t0, t1);
    let (t0, t1) = (
        _mm256_blendv_pd(t1, t0, ordered),
        _mm256_blendv_pd(t0, t1, ordered),
    );
    let store = |v: __m256d| {
        let mut a = [0.0f64; 4];
        // SAFETY: `a` holds four f64.
        unsafe { _mm256_storeu_pd(a.as_mut_ptr(), v) };
        a
    };
    let store_f32 = |v: __m256d| {
        let mut a = [0.0f32; 4];
        // SAFETY: `a` holds four f32.
        unsafe { _mm_storeu_ps(a.as_mut_ptr(), _mm256_cvtpd_ps(v)) };
        a
    };
    let (t0, t1) = (store_f32(t0), store_f32(t1));
    let (ex, ey, ez) = (
        store(sub(lx, mul(s, dx))),
        store(sub(ly, mul(s, dy))),
        store(sub(lz, mul(s, dz))),
    );
    std::array::from_fn(|k| {
        (hit >> k & 1 == 1).then(|| SphereCrossing {
            t0: t0[k],
            t1: t1[k],
            entry: DVec3::new(ex[k], ey[k], ez[k]),
        })
    })
}
