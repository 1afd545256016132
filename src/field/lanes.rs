//! The batched lookup's first steps, eight rays at a time: the bounding-sphere cull of many rays
//! from one origin ([`cull`]) and their exact sphere crossings ([`crossings`]).
//!
//! Every field lookup starts by deciding whether its ray meets the caster's bounding sphere and
//! where (2008 Algorithm 2); for AO rays three quarters of the rays stop there. Where the CPU
//! has AVX2 ([`Isa::detect`]) these run [`LANES`] rays per step with intrinsics
//! (`lanes_avx2.rs`: the directions transposed in registers, the cull in 8 × f32, the crossing
//! in 2 × 4 × f64), elsewhere one ray at a time. Each lane performs the scalar code's IEEE
//! operations in the scalar code's order (no fused multiply-add, no reassociation), so every
//! answer is bit-identical to the per-ray [`MayMeetFrom::test`] and
//! [`SphereOrigin::crossing`] (tests below and in `tests/field_batch.rs`).

use super::lookup::{SphereCrossing, SphereOrigin};
use glam::Vec3;

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
    match isa {
        Isa::Portable => cull_scalar(meet, dirs, tmin, skip, idx),
        // SAFETY: the CPU has AVX2 (checked here, a cached flag: `Isa::Avx2` is a request).
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if Isa::detect() == Isa::Avx2 => unsafe {
            avx2::cull(meet, dirs, tmin, skip, idx)
        },
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => cull_scalar(meet, dirs, tmin, skip, idx),
    }
}

/// Rays culled and crossed per window of [`for_each_crossing`].
const WINDOW: usize = 64;

/// The batched lookup's first steps over every ray from one origin, window by window: the rays
/// not yet marked in `out` that pass `meet` ([`cull`]) and `pick(i, dirs[i])` (which gives the
/// direction to cross, e.g. in a field's model space, or `None` to leave the ray), crossed
/// with `from`'s sphere ([`crossings`]); `visit(out, i, dir, crossing)` is called, in increasing
/// `i`, for each that meets it. A window's cull reads `out` before its rays are visited, so
/// `visit` may mark rays (its own or earlier ones) as it goes.
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
    mut pick: impl FnMut(usize, Vec3) -> Option<Vec3>,
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
            if let Some(d) = pick(i, dirs[i]) {
                (idx[kept], picked[kept]) = (idx[k], d);
                kept += 1;
            }
        }
        crossings(isa, from, &picked[..kept], &mut hits[..kept]);
        for k in 0..kept {
            if let Some(c) = hits[k] {
                visit(out, start + idx[k] as usize, picked[k], c);
            }
        }
    }
}

/// [`cull`] one ray at a time.
fn cull_scalar(
    meet: &MayMeetFrom,
    dirs: &[Vec3],
    tmin: f32,
    skip: &[bool],
    idx: &mut [u32],
) -> usize {
    let mut n = 0;
    for (i, (&d, &s)) in dirs.iter().zip(skip).enumerate() {
        idx[n] = i as u32;
        n += (!s && meet.test(d, tmin)) as usize;
    }
    n
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
    match isa {
        Isa::Portable => crossings_scalar(from, dirs, out),
        // SAFETY: as in `cull`.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if Isa::detect() == Isa::Avx2 => unsafe { avx2::crossings(from, dirs, out) },
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => crossings_scalar(from, dirs, out),
    }
}

/// [`crossings`] one ray at a time.
fn crossings_scalar(from: &SphereOrigin, dirs: &[Vec3], out: &mut [Option<SphereCrossing>]) {
    for (o, &d) in out.iter_mut().zip(dirs) {
        *o = from.crossing(d);
    }
}

#[cfg(target_arch = "x86_64")]
#[path = "lanes_avx2.rs"]
mod avx2;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rays::seeded_sphere_direction;

    fn isas() -> Vec<Isa> {
        Isa::all_available()
    }

    /// Directions from the origin that graze, enter and miss a sphere, with lengths off unit
    /// by f32 rounding and far from it (both normalisation branches), and a non-direction.
    fn directions(origin: Vec3, center: Vec3, radius: f32) -> Vec<Vec3> {
        let to = (center - origin).normalize();
        let mut v: Vec<Vec3> = (0..997).map(|i| seeded_sphere_direction(i, 5)).collect();
        for i in 0..400 {
            // Around the sphere's outline as seen from the origin.
            let side = seeded_sphere_direction(i, 9).cross(to).normalize();
            let tangent = radius / (center - origin).length();
            let k = tangent * (1.0 + (i as f32 - 200.0) * 1e-6);
            v.push((to + k * side).normalize());
        }
        v.extend([to, -to, to * 1.5, to * 1e-3, Vec3::ZERO, Vec3::NAN]);
        v
    }

    #[test]
    fn the_culls_are_the_per_ray_test() {
        for (origin, center, radius) in [
            (Vec3::new(0.3, -0.2, 0.1), Vec3::new(0.0, 0.0, 2.0), 0.7),
            (
                Vec3::new(1e3, 2e3, -5e2),
                Vec3::new(1e3 + 3.0, 2e3, -5e2),
                1.0,
            ),
            (Vec3::new(0.1, 0.1, 0.1), Vec3::ZERO, 1.0), // inside
        ] {
            let dirs = directions(origin, center, radius);
            let meet = MayMeetFrom {
                f: center - origin,
                reach: radius * (1.0 + 1e-5),
            };
            let skip: Vec<bool> = (0..dirs.len()).map(|i| i % 7 == 3).collect();
            for tmin in [0.0, 1.0, 1e9] {
                let want: Vec<u32> = (0..dirs.len() as u32)
                    .filter(|&i| !skip[i as usize] && meet.test(dirs[i as usize], tmin))
                    .collect();
                assert!(!want.is_empty() || tmin > 1.0);
                assert!(want.len() < dirs.len() - dirs.len() / 7);
                for isa in isas() {
                    for n in [0, 1, 7, 8, 9, 64, dirs.len()] {
                        let mut got = vec![u32::MAX; n];
                        let kept = cull(isa, &meet, &dirs[..n], tmin, &skip[..n], &mut got);
                        got.truncate(kept);
                        let w: Vec<u32> =
                            want.iter().copied().filter(|&i| (i as usize) < n).collect();
                        assert_eq!(got, w, "{isa:?}, {n} rays, tmin {tmin}");
                    }
                }
            }
        }
    }

    #[test]
    fn the_crossings_are_the_per_ray_crossing_bit_for_bit() {
        for (origin, center, radius) in [
            (Vec3::new(0.3, -0.2, 0.1), Vec3::new(0.0, 0.0, 2.0), 0.7),
            (Vec3::new(1e6, -3e5, 2e6), Vec3::new(1.0, 2.0, 3.0), 0.5),
            (Vec3::new(0.1, 0.1, 0.1), Vec3::ZERO, 1.0),
        ] {
            let from = SphereOrigin::new(origin, center, radius);
            let dirs = directions(origin, center, radius);
            let want: Vec<_> = dirs.iter().map(|&d| from.crossing(d)).collect();
            let hits = want.iter().filter(|c| c.is_some()).count();
            assert!(hits > 150 && hits < dirs.len(), "{hits} of {}", dirs.len());
            for isa in isas() {
                for n in [0, 3, 8, 13, dirs.len()] {
                    let mut got = vec![None; n];
                    crossings(isa, &from, &dirs[..n], &mut got);
                    // Bit for bit, NaN-free fields compared by their bits.
                    let bits = |c: &Option<SphereCrossing>| {
                        c.map(|c| {
                            [
                                c.t0.to_bits() as u64,
                                c.t1.to_bits() as u64,
                                c.entry.x.to_bits(),
                                c.entry.y.to_bits(),
                                c.entry.z.to_bits(),
                            ]
                        })
                    };
                    for k in 0..n {
                        assert_eq!(
                            bits(&got[k]),
                            bits(&want[k]),
                            "{isa:?}, ray {k}: {:?}",
                            dirs[k]
                        );
                    }
                }
            }
        }
    }
}
