//! [`super::cone_rays`] and [`super::lobe_rays`] with AVX2 intrinsics, eight rays per step in
//! 8 × f32: each lane performs the one-ray code's IEEE operations in its order
//! (multiplications and additions kept apart, no fused multiply-add; `max(x, 0)` as
//! `_mm256_max_ps(x, 0)`, which like `f32::max` gives 0 for a NaN `x`), so the rays are its
//! bits. Callers guarantee the CPU has AVX2.

use super::{DiskSamples, ShadowRays, LANES};
use crate::render::shadow::LightCone;
use crate::sampling::Frame;
use crate::simd::x86::{load3x8, store3x8};
use glam::Vec3;
use std::arch::x86_64::*;

/// For each 8-bit lane mask, the indices of its set lanes in increasing order, then zeros:
/// `_mm256_permutevar8x32_ps` by row `m` moves the lanes of `m` to the front.
static COMPRESS: [[u32; LANES]; 256] = {
    let mut t = [[0u32; LANES]; 256];
    let mut m = 0;
    while m < 256 {
        let (mut lane, mut n) = (0, 0);
        while lane < LANES {
            if m >> lane & 1 == 1 {
                t[m][n] = lane as u32;
                n += 1;
            }
            lane += 1;
        }
        m += 1;
    }
    t
};

/// A vector's three components, each in all eight lanes.
#[inline]
#[target_feature(enable = "avx2")]
fn splat3(v: Vec3) -> [__m256; 3] {
    [
        _mm256_set1_ps(v.x),
        _mm256_set1_ps(v.y),
        _mm256_set1_ps(v.z),
    ]
}

/// a·x + b·y + c·z per lane, as `Vec3::dot` and `Frame::to_world` sum it: (ax + by) + cz.
#[inline]
#[target_feature(enable = "avx2")]
fn sum3(a: __m256, x: __m256, b: __m256, y: __m256, c: __m256, z: __m256) -> __m256 {
    let mul = _mm256_mul_ps;
    _mm256_add_ps(_mm256_add_ps(mul(a, x), mul(b, y)), mul(c, z))
}

/// The lobe-frame vectors (x, y, z) turned by (sin `s`, cos `c`) about +z, taken to the world
/// by `frame` and renormalised (`Vec3::normalize`: v · (1 / |v|)).
#[inline]
#[target_feature(enable = "avx2")]
fn turn_to_world_normalize(
    (x, y, z): (__m256, __m256, __m256),
    (s, c): (__m256, __m256),
    f: &[[__m256; 3]; 3],
) -> (__m256, __m256, __m256) {
    let (mul, add, sub) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps);
    // Vec3::new(c x − s y, s x + c y, z), then x·F.x + y·F.y + z·F.z.
    let (lx, ly) = (sub(mul(c, x), mul(s, y)), add(mul(s, x), mul(c, y)));
    let wx = sum3(f[0][0], lx, f[1][0], ly, f[2][0], z);
    let wy = sum3(f[0][1], lx, f[1][1], ly, f[2][1], z);
    let wz = sum3(f[0][2], lx, f[1][2], ly, f[2][2], z);
    let len = _mm256_sqrt_ps(sum3(wx, wx, wy, wy, wz, wz));
    let inv = _mm256_div_ps(_mm256_set1_ps(1.0), len);
    (mul(wx, inv), mul(wy, inv), mul(wz, inv))
}

/// A frame's three axes, each splatted.
#[inline]
#[target_feature(enable = "avx2")]
fn splat_frame(f: &Frame) -> [[__m256; 3]; 3] {
    [splat3(f.x), splat3(f.y), splat3(f.z)]
}

/// What every ray of one light's cone at one point shares, splatted.
struct ConeLanes {
    omc: __m256,
    rot: (__m256, __m256),
    frame: [[__m256; 3]; 3],
    normal: [__m256; 3],
    to: [__m256; 3],
    r2: __m256,
    /// d² − r².
    near: __m256,
    weight_scale: __m256d,
}

/// [`super::cone_rays`], eight samples per step (the last few padded); returns how many were
/// done (all).
///
/// # Safety
/// The CPU must have AVX2; the disk's three arrays as long as each other.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn cone_rays(
    disk: &DiskSamples,
    cone: &LightCone,
    (s, c): (f32, f32),
    normal: Vec3,
    out: &mut ShadowRays,
) -> usize {
    let k = ConeLanes {
        omc: _mm256_set1_ps(cone.one_minus_cos),
        rot: (_mm256_set1_ps(s), _mm256_set1_ps(c)),
        frame: splat_frame(&cone.frame),
        normal: splat3(normal),
        to: splat3(cone.to),
        r2: _mm256_set1_ps(cone.r2),
        near: _mm256_set1_ps(cone.d2 - cone.r2),
        weight_scale: _mm256_set1_pd(cone.weight_scale),
    };
    let n = disk.len();
    // Room for a whole group past the kept rays (see `cone_group`).
    out.dirs.reserve(n + LANES);
    out.tmaxs.reserve(n + LANES);
    out.weights.reserve(n + LANES);
    let whole = n / LANES * LANES;
    for i in (0..whole).step_by(LANES) {
        let load = |v: &[f32]| _mm256_loadu_ps(v.as_ptr().add(i));
        cone_group(
            &k,
            load(&disk.r2),
            load(&disk.cos),
            load(&disk.sin),
            0xff,
            out,
        );
    }
    // The last few samples as one group, padded with the disk's centre.
    let rest = n - whole;
    if rest > 0 {
        let load = |v: &[f32]| {
            let mut pad = [0.0f32; LANES];
            pad[..rest].copy_from_slice(&v[whole..]);
            _mm256_loadu_ps(pad.as_ptr())
        };
        let live = (1 << rest) - 1;
        cone_group(
            &k,
            load(&disk.r2),
            load(&disk.cos),
            load(&disk.sin),
            live,
            out,
        );
    }
    n
}

/// The rays of eight disk samples (ρ², x/ρ, y/ρ), of which the lanes of `live` are real,
/// appended to `out`.
///
/// # Safety
/// `out`'s arrays must have room for eight more past their lengths.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn cone_group(
    k: &ConeLanes,
    r2s: __m256,
    cos: __m256,
    sin: __m256,
    live: u32,
    out: &mut ShadowRays,
) {
    let (mul, add, sub, max) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps, _mm256_max_ps);
    let zero = _mm256_setzero_ps();
    let (one, two) = (_mm256_set1_ps(1.0), _mm256_set1_ps(2.0));
    // square_to_cone: t = ρ² (1 − cos θ_max), sin θ = √max(t(2 − t), 0),
    // (x/ρ · sin θ, y/ρ · sin θ, 1 − t).
    let t = mul(r2s, k.omc);
    let st = _mm256_sqrt_ps(max(mul(t, sub(two, t)), zero));
    let l = (mul(cos, st), mul(sin, st), sub(one, t));
    let (dx, dy, dz) = turn_to_world_normalize(l, k.rot, &k.frame);
    // The cosine with the normal; kept unless ≤ 0 (a NaN is kept, as one ray at a time).
    let [nx, ny, nz] = k.normal;
    let cos_n = sum3(nx, dx, ny, dy, nz, dz);
    let keep = live & _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_NLE_UQ>(cos_n, zero)) as u32;
    if keep == 0 {
        return;
    }
    // LightCone::far_end: b = d·to, h = to − b d, (d² − r²) / (b + √max(r² − |h|², 0)).
    let [tx, ty, tz] = k.to;
    let b = sum3(dx, tx, dy, ty, dz, tz);
    let (hx, hy, hz) = (
        sub(tx, mul(b, dx)),
        sub(ty, mul(b, dy)),
        sub(tz, mul(b, dz)),
    );
    let h2 = sum3(hx, hx, hy, hy, hz, hz);
    let tmax = _mm256_div_ps(k.near, add(b, _mm256_sqrt_ps(max(sub(k.r2, h2), zero))));
    // The kept lanes moved to the front and written past the arrays' ends (room for eight);
    // the lengths grow by the kept count.
    let pick = _mm256_loadu_si256(COMPRESS[keep as usize].as_ptr().cast());
    let pack = |v| _mm256_permutevar8x32_ps(v, pick);
    let kept = keep.count_ones() as usize;
    let len = out.dirs.len();
    let cos_kept = pack(cos_n);
    store3x8(
        out.dirs.as_mut_ptr().add(len).cast(),
        pack(dx),
        pack(dy),
        pack(dz),
    );
    _mm256_storeu_ps(out.tmaxs.as_mut_ptr().add(len), pack(tmax));
    // weight_scale · (cos as f64), four at a time.
    let wp = out.weights.as_mut_ptr().add(len);
    let lo = _mm256_cvtps_pd(_mm256_castps256_ps128(cos_kept));
    let hi = _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(cos_kept));
    _mm256_storeu_pd(wp, _mm256_mul_pd(k.weight_scale, lo));
    _mm256_storeu_pd(wp.add(4), _mm256_mul_pd(k.weight_scale, hi));
    out.dirs.set_len(len + kept);
    out.tmaxs.set_len(len + kept);
    out.weights.set_len(len + kept);
}

/// [`super::lobe_rays`], eight lobe directions per step (the last few padded); returns how many
/// were done (all).
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn lobe_rays(
    base: &[Vec3],
    (s, c): (f32, f32),
    frame: &Frame,
    normal: Vec3,
    dirs: &mut Vec<Vec3>,
) -> usize {
    let rot = (_mm256_set1_ps(s), _mm256_set1_ps(c));
    let frame = splat_frame(frame);
    let normal = splat3(normal);
    let n = base.len();
    // Room for a whole group past the kept rays (see `lobe_group`).
    dirs.reserve(n + LANES);
    let whole = n / LANES * LANES;
    for i in (0..whole).step_by(LANES) {
        lobe_group(base.as_ptr().add(i), rot, &frame, normal, 0xff, dirs);
    }
    // The last few as one group, padded with +z.
    let rest = n - whole;
    if rest > 0 {
        let mut pad = [Vec3::Z; LANES];
        pad[..rest].copy_from_slice(&base[whole..]);
        lobe_group(pad.as_ptr(), rot, &frame, normal, (1 << rest) - 1, dirs);
    }
    n
}

/// The rays of the eight lobe directions at `p`, of which the lanes of `live` are real,
/// appended to `dirs`.
///
/// # Safety
/// `p` must point to eight `Vec3`s; `dirs` must have room for eight more past its length.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn lobe_group(
    p: *const Vec3,
    rot: (__m256, __m256),
    frame: &[[__m256; 3]; 3],
    [nx, ny, nz]: [__m256; 3],
    live: usize,
    dirs: &mut Vec<Vec3>,
) {
    let (dx, dy, dz) = turn_to_world_normalize(load3x8(p.cast()), rot, frame);
    // Kept where the cosine with the normal is > 0 (a NaN is dropped, as one at a time).
    let cos_n = sum3(nx, dx, ny, dy, nz, dz);
    let keep =
        live & _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(cos_n, _mm256_setzero_ps())) as usize;
    // The kept lanes to the front, written past the end.
    let pick = _mm256_loadu_si256(COMPRESS[keep].as_ptr().cast());
    let pack = |v| _mm256_permutevar8x32_ps(v, pick);
    let len = dirs.len();
    store3x8(
        dirs.as_mut_ptr().add(len).cast(),
        pack(dx),
        pack(dy),
        pack(dz),
    );
    dirs.set_len(len + keep.count_ones() as usize);
}
