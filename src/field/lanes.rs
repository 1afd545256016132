//! The batched lookup's steps, eight rays at a time: the bounding-sphere cull of many rays from
//! one origin ([`cull`]), their exact sphere crossings ([`crossings`]), and for the rays that
//! enter the sphere the map and texel they read ([`nearest_reads`]).
//!
//! Every field lookup starts by deciding whether its ray meets the caster's bounding sphere and
//! where (2008 Algorithm 2); for AO rays three quarters of the rays stop there. Where the CPU
//! has AVX2 ([`Isa::detect`]) these run [`LANES`] rays per step with intrinsics
//! (`lanes_avx2.rs`: the directions transposed in registers, the cull in 8 × f32, the crossing
//! in 2 × 4 × f64), elsewhere one ray at a time. Each lane performs the scalar code's IEEE
//! operations in the scalar code's order (no fused multiply-add, no reassociation), so every
//! answer is bit-identical to the per-ray [`MayMeetFrom::test`] and
//! [`SphereOrigin::crossing`] (tests below and in `tests/field_batch.rs`).

use super::lookup::{Crossed, NearestRead, SphereCrossing, SphereOrigin};
use super::VisibilityField;
use glam::{Quat, Vec3};

/// Rays per step.
pub const LANES: usize = 8;

pub use crate::simd::Isa;

/// [`crate::field::scene::FieldInstance::may_meet`] for rays from one origin: the terms that
/// depend only on the origin.
#[derive(Clone, Copy, Debug)]
pub struct MayMeetFrom {
    /// Sphere centre − origin.
    pub f: Vec3,
    /// The sphere's radius plus the rounding margin.
    pub reach: f32,
}

impl MayMeetFrom {
    /// `false` only when a unit `dir` certainly misses the sphere, or the sphere lies wholly
    /// before `tmin`.
    #[inline]
    pub fn test(&self, dir: Vec3, tmin: f32) -> bool {
        let (f, reach) = (self.f, self.reach);
        let b = f.dot(dir);
        let l = f - b * dir;
        // Line misses: |l| > R. Sphere behind: every point of it has t ≤ b + R < tmin.
        l.length_squared() <= reach * reach && b + reach >= tmin
    }
}

/// Writes to the front of `idx` the index `i` of every ray with `!skip[i]` and
/// `meet.test(dirs[i], tmin)`, in increasing order, and returns their count: the rays a lookup
/// must cross with the sphere.
///
/// # Panics
/// If `dirs` and `skip` differ in length or `idx` is shorter than them.
#[inline]
pub fn cull(
    isa: Isa,
    meet: &MayMeetFrom,
    dirs: &[Vec3],
    tmin: f32,
    skip: &[bool],
    idx: &mut [u32],
) -> usize {
    assert!(
        dirs.len() == skip.len() && idx.len() >= dirs.len(),
        "cull: {} dirs, {} skip flags, room for {} indices",
        dirs.len(),
        skip.len(),
        idx.len()
    );
    if isa.runs_avx2() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 (`Isa::runs_avx2`).
        return unsafe { avx2::cull(meet, dirs, tmin, skip, idx) };
    }
    let mut n = 0;
    for (i, (&d, &s)) in dirs.iter().zip(skip).enumerate() {
        idx[n] = i as u32;
        n += (!s && meet.test(d, tmin)) as usize;
    }
    n
}

/// Rays culled and crossed per window of [`for_each_crossing`].
const WINDOW: usize = 64;

/// The batched lookup's first steps over every ray from one origin, window by window: the rays
/// not yet marked in `out` that pass `meet` ([`cull`]) and `keep(i, dirs[i])`, turned by
/// `rotate` (into a field's model space: `(q * d).normalize()`, [`rotate_normalize`]) when
/// given, crossed with `from`'s sphere ([`crossings`]); `visit(out, i, dir, crossing)` is
/// called, in increasing `i`, for each that meets it, with the direction crossed. A window's
/// cull reads `out` before its rays are visited, so `visit` may mark rays (its own or earlier
/// ones) as it goes.
///
/// # Panics
/// If `dirs` and `out` differ in length.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn for_each_crossing(
    isa: Isa,
    meet: &MayMeetFrom,
    from: &SphereOrigin,
    dirs: &[Vec3],
    tmin: f32,
    out: &mut [bool],
    rotate: Option<Quat>,
    mut keep: impl FnMut(usize, Vec3) -> bool,
    mut visit: impl FnMut(&mut [bool], usize, Vec3, SphereCrossing),
) {
    assert_eq!(
        dirs.len(),
        out.len(),
        "for_each_crossing: dirs and out differ in length"
    );
    let mut idx = [0u32; WINDOW];
    let mut picked = [Vec3::ZERO; WINDOW];
    let mut hits: [Option<SphereCrossing>; WINDOW] = [None; WINDOW];
    for start in (0..dirs.len()).step_by(WINDOW) {
        let end = (start + WINDOW).min(dirs.len());
        let culled = cull(
            isa,
            meet,
            &dirs[start..end],
            tmin,
            &out[start..end],
            &mut idx,
        );
        let mut kept = 0;
        for k in 0..culled {
            let i = start + idx[k] as usize;
            if keep(i, dirs[i]) {
                (idx[kept], picked[kept]) = (idx[k], dirs[i]);
                kept += 1;
            }
        }
        if let Some(q) = rotate {
            rotate_normalize(isa, q, &mut picked[..kept]);
        }
        crossings(isa, from, &picked[..kept], &mut hits[..kept]);
        for k in 0..kept {
            if let Some(c) = hits[k] {
                visit(out, start + idx[k] as usize, picked[k], c);
            }
        }
    }
}

/// `d ← (q * d).normalize()` for every `d` (a rotation into a field's model space, renormalised),
/// bit for bit: with AVX2 eight directions per instruction in the order of glam's SSE2
/// `Quat::mul_vec3a` and `Vec3::normalize`.
#[inline]
pub fn rotate_normalize(isa: Isa, q: Quat, dirs: &mut [Vec3]) {
    if isa.runs_avx2() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 (`Isa::runs_avx2`).
        return unsafe { avx2::rotate_normalize(q, dirs) };
    }
    for d in dirs {
        *d = (q * *d).normalize();
    }
}

/// `out[k] = from.crossing(dirs[k])` for every `k`, bit for bit.
///
/// # Panics
/// If `dirs` and `out` differ in length.
#[inline]
pub fn crossings(isa: Isa, from: &SphereOrigin, dirs: &[Vec3], out: &mut [Option<SphereCrossing>]) {
    assert_eq!(
        dirs.len(),
        out.len(),
        "crossings: dirs and out differ in length"
    );
    if isa.runs_avx2() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 (`Isa::runs_avx2`); `out` as long as `dirs` (asserted).
        return unsafe { avx2::crossings(from, dirs, out) };
    }
    for (o, &d) in out.iter_mut().zip(dirs) {
        *o = from.crossing(d);
    }
}

/// `out[k] = NearestRead::of(field, at[k].u, at[k].dir)` for every `k`, with each read's
/// storage prefetched ([`crate::field::lookup::Reads::of_block`]): the owner-table cell of
/// every crossing, then its map, then the map's frame turning the direction into the map's
/// frame, then the texel, in stages of sixteen crossings. With AVX2 the owner cells, the
/// rotation and, for concentric maps, the texel itself (the layout's libm-free path, in place of
/// the texel table) run eight crossings per instruction, with the same IEEE operations in the
/// same order as [`crate::sampling::SpherePoints::nearest`],
/// [`crate::sampling::Frame::to_local`] and [`crate::sampling::HemisphereLayout::to_texel`];
/// the owner-table reads and the fallbacks (the candidate search, the texel table and the exact
/// texel where the fast path defers) run one crossing at a time.
///
/// # Panics
/// If `at` and `out` differ in length.
#[inline]
pub fn nearest_reads(isa: Isa, field: &VisibilityField, at: &[Crossed], out: &mut [NearestRead]) {
    assert_eq!(
        at.len(),
        out.len(),
        "nearest_reads: at and out differ in length"
    );
    if isa.runs_avx2() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 (`Isa::runs_avx2`); `out` as long as `at` (asserted).
        return unsafe { avx2::nearest_reads(field, at, out) };
    }
    NearestRead::staged(field, at, out)
}

#[cfg(target_arch = "x86_64")]
#[path = "lanes_avx2.rs"]
mod avx2;

#[cfg(test)]
#[path = "lanes_tests.rs"]
mod tests;
