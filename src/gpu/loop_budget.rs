//! Splitting a point's rays over several invocations, so that no invocation loops longer than
//! the driver lets it.
//!
//! llvmpipe (Mesa's lavapipe) gives each shader invocation one budget of 65,535 loop
//! iterations shared by all of its loops (gallivm's `LP_MAX_TGSI_LOOP_ITERATIONS`); once it is
//! spent every loop stops after its current iteration and the kernel returns a wrong answer
//! without an error. Masked SIMD execution charges every loop on a ray's path at least once,
//! so a field lookup costs about 31 iterations per ray even when the ray misses every field:
//! one invocation looping over 4096 rays ran out after 2115 of them.
//!
//! The AO and shadow kernels therefore trace at most `rays_per_invocation` rays per invocation
//! (a point's rays spread over `ceil(rays / rays_per_invocation)` invocations whose free-ray
//! counts, or lit and total weights, the host adds up), and each invocation ends with a loop
//! whose trip count only the host knows (shaders/loop_budget.wgsl): when that loop is cut short
//! the budget was spent, the invocation writes [`CUT_SHORT`], and [`complete_runs`] (under
//! [`free_fractions`] and [`weighted_means`]) halves the rays per invocation and runs
//! again. Drivers without such a budget never cut anything short.

use super::GpuError;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

/// What an invocation writes instead of its free-ray count when its loops were cut short
/// (WGSL `CUT_SHORT`).
pub(crate) const CUT_SHORT: u32 = u32::MAX;

/// Trip count of the completion loop (WGSL `loops_completed(trips)`).
pub(crate) const COMPLETION_TRIPS: u32 = 2;

/// Rays per invocation a kernel starts with when the options do not say
/// ([`crate::gpu::FieldGpuOptions::rays_per_invocation`]): about 8,000 of lavapipe's 65,535
/// loop iterations for one field instance, and enough invocations per point to fill a GPU.
pub const DEFAULT_RAYS_PER_INVOCATION: u32 = 256;

/// One dispatch of an AO kernel: its output words, kernel time, upload time.
pub(crate) type Dispatched = (Vec<u32>, Option<Duration>, Duration);

/// Kernel time summed over dispatches, where the adapter measured any.
pub(crate) fn add_kernel(total: Option<Duration>, k: Option<Duration>) -> Option<Duration> {
    match (total, k) {
        (Some(a), Some(b)) => Some(a + b),
        (a, b) => a.or(b),
    }
}

/// What [`complete_runs`] returns: the words, the invocations per point, the rays per
/// invocation, the kernel time and the upload time.
pub(crate) type Completed = (Vec<u32>, u32, u32, Option<Duration>, Duration);

/// Runs `dispatch(rays_per_invocation, invocations_per_point)`, which returns
/// `words_per_invocation` words per invocation, point-major, the first of them [`CUT_SHORT`]
/// where the invocation was cut short, until no invocation is: starts from `split`'s rays per
/// invocation, halves them while any invocation is cut short, and keeps the last value in
/// `split` for the next call. Returns the words, the invocations per point, the rays per
/// invocation, and the kernel and upload times added up over the dispatches. `rays` must be
/// positive.
///
/// Errors: [`GpuError::Unsupported`] when even one ray per invocation is cut short.
pub(crate) fn complete_runs(
    split: &AtomicU32,
    rays: u32,
    words_per_invocation: usize,
    mut dispatch: impl FnMut(u32, u32) -> Result<Dispatched, GpuError>,
) -> Result<Completed, GpuError> {
    debug_assert!(rays > 0 && words_per_invocation > 0);
    let (mut kernel, mut upload) = (None, Duration::ZERO);
    loop {
        let per_invocation = split.load(Ordering::Relaxed).clamp(1, rays);
        let per_point = rays.div_ceil(per_invocation);
        let (words, k, u) = dispatch(per_invocation, per_point)?;
        kernel = add_kernel(kernel, k);
        upload += u;
        if !words
            .chunks_exact(words_per_invocation)
            .any(|w| w[0] == CUT_SHORT)
        {
            return Ok((words, per_point, per_invocation, kernel, upload));
        }
        if per_invocation == 1 {
            return Err(GpuError::Unsupported(
                "one ray overruns the driver's loop budget per invocation \
                 (lavapipe: 65,535 iterations)"
                    .into(),
            ));
        }
        split.store(per_invocation / 2, Ordering::Relaxed);
    }
}

/// AO (the fraction of free rays) of `points` points with `rays` rays each, from
/// `dispatch(rays_per_invocation, invocations_per_point)`, which returns one free-ray count
/// (or [`CUT_SHORT`]) per invocation, point-major ([`complete_runs`]).
///
/// Errors: [`GpuError::Unsupported`] when even one ray per invocation is cut short.
pub(crate) fn free_fractions(
    split: &AtomicU32,
    rays: u32,
    points: usize,
    dispatch: impl FnMut(u32, u32) -> Result<Dispatched, GpuError>,
) -> Result<(Vec<f32>, Option<Duration>, Duration), GpuError> {
    if rays == 0 {
        return Ok((vec![1.0; points], None, Duration::ZERO));
    }
    let (words, per_point, _, kernel, upload) = complete_runs(split, rays, 1, dispatch)?;
    debug_assert_eq!(words.len(), points * per_point as usize);
    let ao = words
        .chunks_exact(per_point as usize)
        .map(|w| w.iter().sum::<u32>() as f32 / rays as f32)
        .collect();
    Ok((ao, kernel, upload))
}

/// Light fractions (`render::shadow::light_fraction`, `empty` 1) of `points` points with
/// `rays` shadow rays each, from `dispatch(rays_per_invocation, invocations_per_point)`, which
/// returns two words per invocation, point-major: the f32 bits of the weight of the
/// invocation's unblocked rays and of all its rays (or [`CUT_SHORT`] first, [`complete_runs`]).
/// A point's partial sums are added in f64 and divided as on the host; a point without weight
/// is `empty`. With `empty` 0, the means of reflected radiance
/// (`render::reflect::reflect_at_points`), whose invocations write the sum of their kept rays'
/// radiance and the number of those rays, and whose points without a kept ray are 0.
///
/// Errors: [`GpuError::Unsupported`] when even one ray per invocation is cut short.
pub(crate) fn weighted_means(
    split: &AtomicU32,
    rays: u32,
    points: usize,
    empty: f32,
    dispatch: impl FnMut(u32, u32) -> Result<Dispatched, GpuError>,
) -> Result<(Vec<f32>, Option<Duration>, Duration), GpuError> {
    if rays == 0 {
        return Ok((vec![empty; points], None, Duration::ZERO));
    }
    let (words, per_point, _, kernel, upload) = complete_runs(split, rays, 2, dispatch)?;
    debug_assert_eq!(words.len(), points * 2 * per_point as usize);
    let fractions = words
        .chunks_exact(2 * per_point as usize)
        .map(|w| {
            let (mut lit, mut total) = (0.0f64, 0.0f64);
            for run in w.chunks_exact(2) {
                lit += f32::from_bits(run[0]) as f64;
                total += f32::from_bits(run[1]) as f64;
            }
            if total > 0.0 {
                (lit / total) as f32
            } else {
                empty
            }
        })
        .collect();
    Ok((fractions, kernel, upload))
}

/// One word per ray of `points` points with `rays` rays each (the cone kernels: a cone's
/// visibility as f32 bits), point-major, from `dispatch(rays_per_invocation,
/// invocations_per_point)`, which returns `rays_per_invocation` words per invocation,
/// point-major: invocation c of a point writes the words of its rays c·rays_per_invocation …,
/// leaving those past the point's last ray, and writes [`CUT_SHORT`] in each of its words when
/// it was cut short ([`complete_runs`], which then halves the rays per invocation).
///
/// Errors: [`GpuError::Unsupported`] when even one ray per invocation is cut short.
pub(crate) fn ray_words(
    split: &AtomicU32,
    rays: u32,
    points: usize,
    dispatch: impl FnMut(u32, u32) -> Result<Dispatched, GpuError>,
) -> Result<(Vec<u32>, Option<Duration>, Duration), GpuError> {
    if rays == 0 {
        return Ok((Vec::new(), None, Duration::ZERO));
    }
    let (words, per_point, per_invocation, kernel, upload) =
        complete_runs(split, rays, 1, dispatch)?;
    let stride = (per_point * per_invocation) as usize;
    debug_assert_eq!(words.len(), points * stride);
    let out = words
        .chunks_exact(stride)
        .flat_map(|w| &w[..rays as usize])
        .copied()
        .collect();
    Ok((out, kernel, upload))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stand-in for lavapipe: every invocation may spend `budget` iterations at `cost` per
    /// ray; point p has its first `p % rays` rays blocked.
    fn fake(
        budget: u32,
        cost: u32,
        rays: u32,
        points: usize,
        calls: &mut Vec<u32>,
    ) -> impl FnMut(u32, u32) -> Result<Dispatched, GpuError> + '_ {
        move |per_invocation, per_point| {
            calls.push(per_invocation);
            let mut words = Vec::new();
            for p in 0..points as u32 {
                let blocked = p % rays;
                for c in 0..per_point {
                    let (lo, hi) = (c * per_invocation, ((c + 1) * per_invocation).min(rays));
                    if (hi - lo) * cost > budget {
                        words.push(CUT_SHORT);
                    } else {
                        words.push((lo..hi).filter(|&r| r >= blocked).count() as u32);
                    }
                }
            }
            Ok((words, Some(Duration::from_millis(1)), Duration::ZERO))
        }
    }

    #[test]
    fn cut_short_invocations_are_split_until_they_fit() {
        // 4096 rays at 31 iterations each: 2114 rays fit lavapipe's budget, so 256 fit at once
        // for one instance; at 200 per ray only 327 fit, so 256 does, and at 300 per ray
        // 218 fit: 256 → 128.
        for (cost, want) in [
            (31u32, vec![256u32]),
            (200, vec![256]),
            (300, vec![256, 128]),
        ] {
            let split = AtomicU32::new(256);
            let mut calls = Vec::new();
            let (ao, kernel, _) =
                free_fractions(&split, 4096, 5, fake(65_535, cost, 4096, 5, &mut calls)).unwrap();
            assert_eq!(calls, want, "cost {cost}");
            assert_eq!(split.load(Ordering::Relaxed), *want.last().unwrap());
            // Point p: 4096 − p rays free, summed over the invocations.
            for (p, a) in ao.iter().enumerate() {
                assert_eq!(*a, (4096 - p as u32) as f32 / 4096.0, "point {p}");
            }
            assert_eq!(kernel, Some(Duration::from_millis(want.len() as u64)));
        }
        // Starting from every ray in one invocation: halved down to what fits (2048 × 31 =
        // 63,488 iterations).
        let split = AtomicU32::new(u32::MAX);
        let mut calls = Vec::new();
        free_fractions(&split, 4096, 2, fake(65_535, 31, 4096, 2, &mut calls)).unwrap();
        assert_eq!(calls, vec![4096, 2048]);
    }

    #[test]
    fn no_rays_is_unoccluded_and_an_unaffordable_ray_is_an_error() {
        let split = AtomicU32::new(256);
        let (ao, _, _) = free_fractions(&split, 0, 3, |_, _| unreachable!()).unwrap();
        assert_eq!(ao, vec![1.0; 3]);
        let mut calls = Vec::new();
        let r = free_fractions(&split, 16, 2, fake(10, 11, 16, 2, &mut calls));
        assert!(matches!(r, Err(GpuError::Unsupported(_))));
        assert_eq!(calls, vec![16, 8, 4, 2, 1]);
    }

    #[test]
    fn weighted_runs_are_summed_in_f64_and_cut_short_runs_split() {
        // 6 rays a point; ray r weighs r + 1, and point p has its rays below p blocked. The
        // budget allows 2 rays an invocation: 4 → 2.
        let rays = 6u32;
        let points = 4usize;
        let split = AtomicU32::new(4);
        let mut calls = Vec::new();
        let dispatch = |per_invocation: u32, per_point: u32| {
            calls.push(per_invocation);
            let mut words = Vec::new();
            for p in 0..points as u32 {
                for c in 0..per_point {
                    let (lo, hi) = (c * per_invocation, ((c + 1) * per_invocation).min(rays));
                    if hi - lo > 2 {
                        words.extend([CUT_SHORT, 0]);
                        continue;
                    }
                    let w = |r: u32| (r + 1) as f32;
                    let lit: f32 = (lo..hi).filter(|&r| r >= p).map(w).sum();
                    let total: f32 = (lo..hi).map(w).sum();
                    words.extend([lit.to_bits(), total.to_bits()]);
                }
            }
            Ok((words, None, Duration::ZERO))
        };
        let (v, _, _) = weighted_means(&split, rays, points, 1.0, dispatch).unwrap();
        assert_eq!(calls, vec![4, 2]);
        assert_eq!(split.load(Ordering::Relaxed), 2);
        for (p, &f) in v.iter().enumerate() {
            let lit: u32 = (p as u32..rays).map(|r| r + 1).sum();
            assert_eq!(f, (lit as f64 / 21.0) as f32, "point {p}");
        }
        // No rays, or no weight: lit.
        let (v, _, _) = weighted_means(&split, 0, 2, 1.0, |_, _| unreachable!()).unwrap();
        assert_eq!(v, vec![1.0; 2]);
        let (v, _, _) = weighted_means(&split, 2, 1, 1.0, |_, _| {
            Ok((vec![0, 0], None, Duration::ZERO))
        })
        .unwrap();
        assert_eq!(v, vec![1.0]);
    }

    #[test]
    fn ray_words_keep_each_rays_word_in_order_across_splits() {
        // 7 rays a point, word of ray r of point p = 100 p + r; an invocation of more than 3
        // rays is cut short (every word CUT_SHORT): 4 → 2, then 4 invocations a point, the
        // last with one ray and a word left unwritten (0).
        let (rays, points) = (7u32, 3usize);
        let split = AtomicU32::new(4);
        let mut calls = Vec::new();
        let dispatch = |per_invocation: u32, per_point: u32| {
            calls.push(per_invocation);
            let mut words = Vec::new();
            for p in 0..points as u32 {
                for c in 0..per_point {
                    let lo = c * per_invocation;
                    let hi = (lo + per_invocation).min(rays);
                    for k in 0..per_invocation {
                        words.push(if per_invocation > 3 {
                            CUT_SHORT
                        } else if lo + k < hi {
                            100 * p + lo + k
                        } else {
                            0
                        });
                    }
                }
            }
            Ok((words, None, Duration::ZERO))
        };
        let (w, _, _) = ray_words(&split, rays, points, dispatch).unwrap();
        assert_eq!(calls, vec![4, 2]);
        let want: Vec<u32> = (0..points as u32)
            .flat_map(|p| (0..rays).map(move |r| 100 * p + r))
            .collect();
        assert_eq!(w, want);
        let (w, _, _) = ray_words(&split, 0, 2, |_, _| unreachable!()).unwrap();
        assert!(w.is_empty());
    }
}
