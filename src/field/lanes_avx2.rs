//! [`super::cull`], [`super::crossings`] and [`super::nearest_reads`] with AVX2 intrinsics,
//! eight rays per step: the directions are loaded and transposed to structure-of-arrays form in
//! registers, the cull runs as 8 × f32, the crossing as 2 × 4 × f64, the table cells and the
//! rotation into a map's frame as 8 × f32. Every lane performs the scalar code's IEEE
//! operations in its order (multiplications and additions kept apart, no fused multiply-add),
//! so the answers are the scalar ones bit for bit. Callers guarantee the CPU has AVX2.

use super::super::lookup::{Crossed, NearestRead, SphereCrossing, SphereOrigin, STAGE};
use super::super::VisibilityField;
use super::{MayMeetFrom, LANES};
use crate::sampling::{certificate_margin, ATAN_F32_COEFFS, FOUR_OVER_PI};
use crate::sampling::{Frame, LayoutKind, OwnerCell};
use crate::simd::x86::{load3x8 as load_transposed, store3x8};
use glam::{DVec3, Quat, Vec3};
use std::arch::x86_64::*;
use std::mem::{offset_of, size_of};

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

/// [`super::rotate_normalize`]: glam's SSE2 `Quat::mul_vec3a` (r (w² − b·b) + b (2 r·b) +
/// (b × r)(2w), b the vector part) and `Vec3::normalize` (v · (1 / |v|)) per lane, in their
/// order of operations.
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn rotate_normalize(q: Quat, dirs: &mut [Vec3]) {
    let (mul, add, sub) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps);
    let (bx, by, bz, w) = (q.x, q.y, q.z, q.w);
    // The terms glam computes once per rotation, in its order.
    let b2 = bx * bx + by * by + bz * bz;
    let k1 = _mm256_set1_ps(w * w - b2);
    let w2 = _mm256_set1_ps(w * 2.0);
    let (bx, by, bz) = (_mm256_set1_ps(bx), _mm256_set1_ps(by), _mm256_set1_ps(bz));
    let two = _mm256_set1_ps(2.0);
    let whole = dirs.len() / LANES * LANES;
    for base in (0..whole).step_by(LANES) {
        let p: *mut f32 = dirs.as_mut_ptr().add(base).cast();
        let (rx, ry, rz) = load_transposed(p);
        let k2 = mul(add(add(mul(rx, bx), mul(ry, by)), mul(rz, bz)), two);
        // b × r as glam groups it: (b.zxy · r − r.zxy · b).zxy.
        let cx = sub(mul(by, rz), mul(ry, bz));
        let cy = sub(mul(bz, rx), mul(rz, bx));
        let cz = sub(mul(bx, ry), mul(rx, by));
        let turn = |r: __m256, b: __m256, c: __m256| add(add(mul(r, k1), mul(b, k2)), mul(c, w2));
        let (x, y, z) = (turn(rx, bx, cx), turn(ry, by, cy), turn(rz, bz, cz));
        let len = _mm256_sqrt_ps(add(add(mul(x, x), mul(y, y)), mul(z, z)));
        let recip = _mm256_div_ps(_mm256_set1_ps(1.0), len);
        store3x8(p, mul(x, recip), mul(y, recip), mul(z, recip));
    }
    for d in &mut dirs[whole..] {
        *d = (q * *d).normalize();
    }
}

/// [`super::nearest_reads`]: each stage of [`NearestRead::staged`] over a block of [`STAGE`]
/// crossings, its arithmetic eight crossings per instruction.
///
/// # Safety
/// The CPU must have AVX2; `out` as long as `at`.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn nearest_reads(
    field: &VisibilityField,
    at: &[Crossed],
    out: &mut [NearestRead],
) {
    const { assert!(STAGE.is_multiple_of(LANES)) };
    let points = &field.points;
    let (og, ohalf) = points.owner_cell_scale();
    let (concentric, res) = (
        field.layout.kind == LayoutKind::Concentric,
        field.layout.res,
    );
    for (at, out) in at.chunks(STAGE).zip(out.chunks_mut(STAGE)) {
        let n = at.len();
        // Table cells, u32::MAX where a lane has none.
        let mut cell = [0u32; STAGE];
        let some = |c: u32| (c != u32::MAX).then_some(c as usize);
        // Owner-table cells, requested before any is read.
        for g in 0..n.div_ceil(LANES) {
            let live = live_lanes(n - g * LANES);
            let (x, y, z) = gather_vec3(at, g * LANES, offset_of!(Crossed, u), live);
            let c = owner_cells(x, y, z, og, ohalf);
            _mm256_storeu_si256(cell.as_mut_ptr().add(g * LANES).cast(), c);
        }
        let mut owner = [OwnerCell::default(); STAGE];
        for (o, &c) in owner[..n].iter_mut().zip(&cell) {
            *o = OwnerCell::new(some(c));
            points.prefetch_owner_cell(*o);
        }
        // The maps, their frames requested.
        for ((r, c), &o) in out.iter_mut().zip(at).zip(&owner) {
            let m = points.nearest_at(o, c.u);
            r.map = m as u32;
            crate::hint::prefetch_value(field.frames.as_ptr().wrapping_add(m));
        }
        // Directions in the maps' frames and, for the concentric layout, their texels through
        // its fast path (`HemisphereLayout::to_cell`'s first, libm-free path).
        let mut local = [Vec3::ZERO; STAGE];
        let mut fast = [u32::MAX; STAGE];
        for g in 0..n.div_ceil(LANES) {
            let live = live_lanes(n - g * LANES);
            let (x, y, z) = gather_vec3(at, g * LANES, offset_of!(Crossed, dir), live);
            let (lx, ly, lz) = to_local(&field.frames, &out[g * LANES..n], x, y, z);
            store3x8(local.as_mut_ptr().add(g * LANES).cast(), lx, ly, lz);
            if concentric {
                let t = concentric_texels(lx, ly, lz, res);
                _mm256_storeu_si256(fast.as_mut_ptr().add(g * LANES).cast(), t);
            }
        }
        // The texels (the texel table or the exact path where the fast one defers), their
        // storage requested.
        for ((r, &d), &f) in out.iter_mut().zip(&local).zip(&fast) {
            r.texel = if f != u32::MAX {
                f
            } else {
                field.texels.texel(d)
            };
            field.storage.prefetch(r.map as usize, r.texel as usize);
        }
    }
}

/// The lane mask of the first `min(live, 8)` lanes.
#[inline]
#[target_feature(enable = "avx2")]
fn live_lanes(live: usize) -> __m256i {
    let k = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    _mm256_cmpgt_epi32(_mm256_set1_epi32(live.min(LANES) as i32), k)
}

/// The `Vec3` at byte offset `field` of crossings `at[first..first + 8]` transposed into x, y
/// and z registers; lanes outside `live` (past the end of `at`) read nothing and hold 0.
///
/// # Safety
/// `live` must mark only lanes with `first + lane < at.len()`.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn gather_vec3(
    at: &[Crossed],
    first: usize,
    field: usize,
    live: __m256i,
) -> (__m256, __m256, __m256) {
    const STRIDE: i32 = (size_of::<Crossed>() / 4) as i32;
    const { assert!(size_of::<Crossed>().is_multiple_of(4)) };
    let base: *const f32 = at
        .as_ptr()
        .wrapping_add(first)
        .cast::<f32>()
        .wrapping_add(field / 4);
    let idx = _mm256_mullo_epi32(
        _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        _mm256_set1_epi32(STRIDE),
    );
    let mask = _mm256_castsi256_ps(live);
    let zero = _mm256_setzero_ps();
    // SAFETY: every live lane reads a component of a `Vec3` field of a crossing in `at`.
    unsafe {
        (
            _mm256_mask_i32gather_ps::<4>(zero, base, idx, mask),
            _mm256_mask_i32gather_ps::<4>(zero, base.wrapping_add(1), idx, mask),
            _mm256_mask_i32gather_ps::<4>(zero, base.wrapping_add(2), idx, mask),
        )
    }
}

/// [`Frame::to_local`] of eight directions, lane k in the frame of map `reads[k].map` (lanes
/// past `reads.len()` in map 0's frame).
///
/// # Safety
/// Every `reads[k].map` (k < 8) must index `frames`, and `frames` must not be empty.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn to_local(
    frames: &[Frame],
    reads: &[NearestRead],
    x: __m256,
    y: __m256,
    z: __m256,
) -> (__m256, __m256, __m256) {
    const STRIDE: i32 = (size_of::<Frame>() / 4) as i32;
    const { assert!(size_of::<Frame>() == 36) };
    let mut maps = [0i32; LANES];
    for (m, r) in maps.iter_mut().zip(reads) {
        *m = r.map as i32;
    }
    let idx = _mm256_mullo_epi32(
        _mm256_loadu_si256(maps.as_ptr().cast()),
        _mm256_set1_epi32(STRIDE),
    );
    let base: *const f32 = frames.as_ptr().cast();
    // SAFETY: each index is map · 9 (+ 0..8) inside `frames` (`Frame` is `repr(C)`, nine f32).
    let axis = |k: usize| unsafe {
        let at = |c: usize| _mm256_i32gather_ps::<4>(base.wrapping_add(3 * k + c), idx);
        (at(0), at(1), at(2))
    };
    // Vec3::dot: (x · a.x + y · a.y) + z · a.z, per axis a of the frame.
    let dot = |(ax, ay, az): (__m256, __m256, __m256)| {
        _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(x, ax), _mm256_mul_ps(y, ay)),
            _mm256_mul_ps(z, az),
        )
    };
    (dot(axis(0)), dot(axis(1)), dot(axis(2)))
}

/// The owner-table cell of eight directions (`OwnerGrid::cell`, g cells per face edge),
/// u32::MAX in the lanes that have none.
#[inline]
#[target_feature(enable = "avx2")]
fn owner_cells(x: __m256, y: __m256, z: __m256, g: u32, half_g: f32) -> __m256i {
    let sign = _mm256_set1_ps(-0.0);
    let abs = |v: __m256| _mm256_andnot_ps(sign, v);
    let (ax, ay, az) = (abs(x), abs(y), abs(z));
    let x_wins = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GE_OQ>(ax, ay),
        _mm256_cmp_ps::<_CMP_GE_OQ>(ax, az),
    );
    let y_wins = _mm256_andnot_ps(x_wins, _mm256_cmp_ps::<_CMP_GE_OQ>(ay, az));
    let pick = |on_x: __m256, on_y: __m256, on_z: __m256| {
        _mm256_blendv_ps(_mm256_blendv_ps(on_z, on_y, y_wins), on_x, x_wins)
    };
    let (da, pb, pc) = (pick(x, y, z), pick(y, z, x), pick(z, x, y));
    let m = abs(da);
    let half = _mm256_set1_ps(half_g);
    let k = _mm256_div_ps(half, m);
    let fi = _mm256_add_ps(_mm256_mul_ps(pb, k), half);
    let fj = _mm256_add_ps(_mm256_mul_ps(pc, k), half);
    let (zero, gf) = (_mm256_setzero_ps(), _mm256_set1_ps(g as f32));
    let inside = |v: __m256| {
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(v, zero),
            _mm256_cmp_ps::<_CMP_LE_OQ>(v, gf),
        )
    };
    let ok = _mm256_and_ps(
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GT_OQ>(m, _mm256_set1_ps(1e-30)),
            _mm256_cmp_ps::<_CMP_LT_OQ>(m, _mm256_set1_ps(f32::INFINITY)),
        ),
        _mm256_and_ps(inside(fi), inside(fj)),
    );
    let last = _mm256_set1_epi32(g as i32 - 1);
    let i = _mm256_min_epu32(_mm256_cvttps_epi32(fi), last);
    let j = _mm256_min_epu32(_mm256_cvttps_epi32(fj), last);
    // Face 2a + (da < 0): a = 0, 1, 2 for x, y, z winning; a compare mask is −1.
    let a = _mm256_castps_si256(pick(
        _mm256_castsi256_ps(_mm256_set1_epi32(0)),
        _mm256_castsi256_ps(_mm256_set1_epi32(1)),
        _mm256_castsi256_ps(_mm256_set1_epi32(2)),
    ));
    let negative = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(da, zero));
    let face = _mm256_sub_epi32(_mm256_add_epi32(a, a), negative);
    let gv = _mm256_set1_epi32(g as i32);
    let cell = _mm256_add_epi32(
        _mm256_mullo_epi32(_mm256_add_epi32(_mm256_mullo_epi32(face, gv), j), gv),
        i,
    );
    _mm256_or_si256(
        cell,
        _mm256_castps_si256(_mm256_andnot_ps(
            ok,
            _mm256_castsi256_ps(_mm256_set1_epi32(-1)),
        )),
    )
}

/// The texel of eight local directions through the concentric layout's fast path
/// (`layout_fast::concentric_square`, then `certified_cell` at `res`, row · res + column), in
/// its order of operations; u32::MAX in the lanes where that path gives none (below the
/// horizon, on the axis, or too near a texel edge), which take the exact path.
#[inline]
#[target_feature(enable = "avx2")]
fn concentric_texels(x: __m256, y: __m256, z: __m256, res: u32) -> __m256i {
    let (mul, add) = (_mm256_mul_ps, _mm256_add_ps);
    let sign = _mm256_set1_ps(-0.0);
    let abs = |v: __m256| _mm256_andnot_ps(sign, v);
    let zero = _mm256_setzero_ps();
    let r = _mm256_sqrt_ps(add(mul(x, x), mul(y, y)));
    let valid = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GE_OQ>(z, zero),
        _mm256_cmp_ps::<_CMP_GT_OQ>(r, zero),
    );
    let x_wedge = _mm256_cmp_ps::<_CMP_GT_OQ>(abs(x), abs(y));
    let num = _mm256_blendv_ps(x, y, x_wedge);
    let den = _mm256_blendv_ps(abs(y), abs(x), x_wedge);
    let along = _mm256_blendv_ps(y, x, x_wedge);
    // atan_unit_f32(num / den), Estrin's scheme as there.
    let t = _mm256_div_ps(num, den);
    let c = ATAN_F32_COEFFS.map(|k| _mm256_set1_ps(k));
    let t2 = mul(t, t);
    let t4 = mul(t2, t2);
    let t8 = mul(t4, t4);
    let p01 = add(c[0], mul(t2, c[1]));
    let p23 = add(c[2], mul(t2, c[3]));
    let p45 = add(c[4], mul(t2, c[5]));
    let p67 = add(c[6], mul(t2, c[7]));
    let p = add(add(p01, mul(t4, p23)), mul(t8, add(p45, mul(t4, p67))));
    let atan = add(t, mul(mul(t, t2), p));
    let angular = mul(mul(r, _mm256_set1_ps(FOUR_OVER_PI)), atan);
    let radial = _mm256_or_ps(r, _mm256_and_ps(along, sign)); // r.copysign(along), r ≥ 0
    let a = _mm256_blendv_ps(angular, radial, x_wedge);
    let b = _mm256_blendv_ps(radial, angular, x_wedge);
    let (half, one) = (_mm256_set1_ps(0.5), _mm256_set1_ps(1.0));
    let resf = _mm256_set1_ps(res as f32);
    let (pa, pb) = (
        mul(mul(half, add(a, one)), resf),
        mul(mul(half, add(b, one)), resf),
    );
    // certified_cell, per axis: c = (v as u32).min(res − 1), v more than the margin from
    // every interior cell boundary.
    let m = _mm256_set1_ps(certificate_margin(res));
    let last = _mm256_set1_epi32(res as i32 - 1);
    let axis = |v: __m256| {
        let number = _mm256_cmp_ps::<_CMP_ORD_Q>(v, v);
        // The saturating cast: negative → 0, beyond i32 → i32::MIN → (unsigned) the last cell.
        let c = _mm256_min_epu32(_mm256_cvttps_epi32(_mm256_max_ps(v, zero)), last);
        let cf = _mm256_cvtepi32_ps(c);
        let below = _mm256_or_ps(
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(c, _mm256_setzero_si256())),
            _mm256_cmp_ps::<_CMP_GT_OQ>(_mm256_sub_ps(v, cf), m),
        );
        let above = _mm256_or_ps(
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(c, last)),
            _mm256_cmp_ps::<_CMP_GT_OQ>(_mm256_sub_ps(add(cf, one), v), m),
        );
        (c, _mm256_and_ps(number, _mm256_and_ps(below, above)))
    };
    let ((col, ok_a), (row, ok_b)) = (axis(pa), axis(pb));
    let ok = _mm256_and_ps(valid, _mm256_and_ps(ok_a, ok_b));
    let texel = _mm256_add_epi32(_mm256_mullo_epi32(row, _mm256_set1_epi32(res as i32)), col);
    _mm256_or_si256(
        texel,
        _mm256_castps_si256(_mm256_andnot_ps(
            ok,
            _mm256_castsi256_ps(_mm256_set1_epi32(-1)),
        )),
    )
}
