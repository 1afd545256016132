//! The converged AO reference ("truth"): the AO integral of [`super::ao`] estimated with enough
//! rays that the estimate's own noise is below a stated standard error.
//!
//! The papers (Gaitatzes et al. 2008, 2010) measure a field against a ray cast on the same 256
//! rays. That isolates the field's error, but a 256-ray AO is itself noisy; error against time is
//! only honest against a converged answer. This module computes one:
//!
//! - `B` independent batches per point, each a jittered k² stratified cosine set
//!   ([`RaySet`] with `jitter`) under its own seed (its own per-point rotation and jitter). A
//!   jittered stratified estimate is unbiased (a centred one is not: it is a midpoint rule), and
//!   batches with distinct seeds are independent, so the batch means' spread is an honest
//!   estimate of the error of their mean: `stderr = sd(batch means) / √B` per point.
//! - k doubles (rays per point ×4) until the RMS over points of the per-point standard error is
//!   at most the target (0.25 on the 0–255 scale by default), or the next step would pass the
//!   cap on rays per point. The RMS over points is the criterion because it is what adds, in
//!   quadrature, to an RMS error measured against the truth; the largest per-point standard
//!   error is recorded beside it.
//!
//! The visibility is the same as the render's ([`AoOptions`]: the same origin offset, the same AO
//! radius), so the truth differs from a render only in its rays.
//!
//! Any estimator converges the same way ([`converged`]); one with several values per point
//! ([`super::estimator::Estimator::channels`]: an RGB, a direction) has a mean and a standard
//! error per point and channel ([`converged_channels`]), and the criterion is the RMS of the
//! standard error over every point and channel.

use super::ao::{ao_at_points, AoOptions};
use crate::sampling::rays::{mix64, RaySet};
use crate::visibility::Visibility;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// When to stop adding rays.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TruthOptions {
    /// Target RMS over points of the per-point standard error, on the 0–255 scale.
    pub target_stderr_255: f64,
    /// Largest rays per point (all batches together).
    pub max_rays: u32,
    /// Independent batches per point (at least 2: their spread is the error estimate).
    pub batches: u32,
    /// Cells per side of the first round's sets.
    pub start_k: u32,
    /// Seed of the batches (each batch and round derives its own).
    pub seed: u64,
}

impl Default for TruthOptions {
    /// Target 0.25 (0–255), at most 16,384 rays per point, 4 batches from 8² rays each.
    fn default() -> Self {
        TruthOptions {
            target_stderr_255: 0.25,
            max_rays: 16_384,
            batches: 4,
            start_k: 8,
            seed: 0x7275_7468,
        }
    }
}

/// A converged reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Truth {
    /// The values per point (AO, or the estimator's quantity), the means of the batches:
    /// `channels` per point, point-major (point i's channel c at `i * channels + c`).
    pub values: Vec<f32>,
    /// Standard error of each of `values` (0–1 scale).
    pub stderr: Vec<f32>,
    /// Values per point (1: a scalar quantity).
    pub channels: usize,
    /// Rays per point of the final round (batches × k²).
    pub rays_per_point: u32,
    /// Cells per side of the final round's sets.
    pub k: u32,
    /// Batches per point.
    pub batches: u32,
    /// Per round: (rays per point, RMS standard error on 0–255).
    pub rounds: Vec<(u32, f64)>,
}

impl Truth {
    /// Scalar values that are exact as they stand (an estimator that samples nothing, such as
    /// a direct estimator of a method: its estimate is its own converged value), with no
    /// standard error.
    pub fn exact(values: Vec<f32>) -> Truth {
        Truth {
            stderr: vec![0.0; values.len()],
            values,
            channels: 1,
            rays_per_point: 0,
            k: 0,
            batches: 1,
            rounds: Vec::new(),
        }
    }

    /// The number of points.
    pub fn points(&self) -> usize {
        self.values.len() / self.channels.max(1)
    }

    /// RMS over points (and channels) of the standard error, on the 0–255 scale.
    pub fn rms_stderr_255(&self) -> f64 {
        rms_stderr_255(&self.stderr)
    }

    /// Largest standard error of a point (or channel), on the 0–255 scale.
    pub fn max_stderr_255(&self) -> f64 {
        self.stderr.iter().fold(0.0f64, |m, &s| m.max(s as f64)) * 255.0
    }

    /// Whether the target was met (false: stopped at the cap).
    pub fn converged(&self, opts: &TruthOptions) -> bool {
        self.rms_stderr_255() <= opts.target_stderr_255
    }
}

fn rms_stderr_255(stderr: &[f32]) -> f64 {
    let s: f64 = stderr.iter().map(|&e| (e as f64).powi(2)).sum();
    255.0 * (s / stderr.len().max(1) as f64).sqrt()
}

/// The seed of batch `b` of the round with `k` cells per side.
fn batch_seed(seed: u64, k: u32, b: u32) -> u64 {
    mix64(seed ^ mix64(((k as u64) << 32) | b as u64))
}

/// One round: `batches` independent jittered k² sets per point, each estimated by `estimate`
/// (`n` values: points × channels); (mean, stderr) per value.
fn round(
    n: usize,
    t: &TruthOptions,
    k: u32,
    estimate: &impl Fn(&RaySet) -> Vec<f32>,
) -> (Vec<f32>, Vec<f32>) {
    let b = t.batches as usize;
    let runs: Vec<Vec<f32>> = (0..t.batches)
        .map(|i| {
            let rays = RaySet {
                k,
                seed: batch_seed(t.seed, k, i),
                jitter: true,
            };
            let r = estimate(&rays);
            assert_eq!(
                r.len(),
                n,
                "converged: the estimate has one value per point and channel"
            );
            r
        })
        .collect();
    (0..n)
        .map(|p| {
            let mean = runs.iter().map(|r| r[p] as f64).sum::<f64>() / b as f64;
            let var = runs
                .iter()
                .map(|r| (r[p] as f64 - mean).powi(2))
                .sum::<f64>()
                / (b - 1) as f64;
            (mean as f32, (var / b as f64).sqrt() as f32)
        })
        .unzip()
}

/// The converged AO at every point (see the module docs).
///
/// # Panics
/// If `t.batches < 2`, `t.start_k == 0`, or `points` and `normals` differ in length.
pub fn converged_ao<V: Visibility + ?Sized>(
    vis: &V,
    points: &[Vec3],
    normals: &[Vec3],
    opts: &AoOptions,
    t: &TruthOptions,
) -> Truth {
    assert_eq!(
        points.len(),
        normals.len(),
        "converged_ao: one normal per point"
    );
    converged(points.len(), t, |rays| {
        ao_at_points(vis, points, normals, rays, opts)
    })
}

/// Any per-point estimate in \[0, 1\] converged as the AO is (see the module docs):
/// `estimate` evaluates every one of the `n` points with the given jittered ray set (its `k²`
/// stratified cells are the estimator's to map: cosine directions for AO, points on a light for
/// shadows) and must be unbiased for jittered sets.
///
/// # Panics
/// If `t.batches < 2`, `t.start_k == 0`, or `estimate` returns other than `n` values.
pub fn converged(n: usize, t: &TruthOptions, estimate: impl Fn(&RaySet) -> Vec<f32>) -> Truth {
    converged_channels(n, 1, t, estimate)
}

/// [`converged`] for an estimate of `channels` values per point (point-major, each in
/// \[0, 1\]): a mean and a standard error per point and channel, the stopping rule on their
/// RMS over all of them. One channel is [`converged`], bit for bit.
///
/// # Panics
/// If `t.batches < 2`, `t.start_k == 0`, `channels == 0`, or `estimate` returns other than
/// `n × channels` values.
pub fn converged_channels(
    n: usize,
    channels: usize,
    t: &TruthOptions,
    estimate: impl Fn(&RaySet) -> Vec<f32>,
) -> Truth {
    assert!(channels > 0, "converged: needs at least one channel");
    let n_values = n * channels;
    assert!(t.batches >= 2, "converged: needs at least 2 batches");
    assert!(t.start_k > 0, "converged: start_k must be positive");
    let rays = |k: u32| t.batches as u64 * k as u64 * k as u64;
    let mut k = t.start_k;
    let mut rounds = Vec::new();
    loop {
        let (values, stderr) = round(n_values, t, k, &estimate);
        let rms = rms_stderr_255(&stderr);
        rounds.push((rays(k) as u32, rms));
        if rms <= t.target_stderr_255 || rays(2 * k) > t.max_rays as u64 {
            return Truth {
                values,
                stderr,
                channels,
                rays_per_point: rays(k) as u32,
                k,
                batches: t.batches,
                rounds,
            };
        }
        k *= 2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::ao::Falloff;
    use crate::trace::test_scenes::square;
    use crate::trace::Tracer;

    /// Binary visibility within an AO radius of 1, origins offset by 1e-5.
    fn step_within_one() -> AoOptions {
        AoOptions {
            max_distance: Some(1.0),
            offset: 1e-5,
            falloff: Falloff::Step,
        }
    }

    #[test]
    fn ceiling_within_the_ao_radius_has_closed_form_ao_and_honest_error_bars() {
        // A point facing +z under a plane at height h, AO radius d: a ray at polar angle θ hits
        // at t = h / cos θ, within d iff cos θ ≥ h/d. Under the cosine density
        // P(cos θ ≥ c) = 1 − c², so AO = (h/d)². h = 0.5, d = 1: AO = 0.25.
        let tracer = Tracer::new(&square(50.0, 0.5));
        let n = 400;
        let points: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(0.01 * i as f32, -0.005 * i as f32, 0.0))
            .collect();
        let normals = vec![Vec3::Z; n];
        let opts = step_within_one();
        let t = TruthOptions {
            target_stderr_255: 0.25,
            max_rays: 4096,
            ..TruthOptions::default()
        };
        let truth = converged_ao(&tracer, &points, &normals, &opts, &t);
        // The offset lowers the plane by 1e-5: AO = ((0.5 − 1e-5)/1)², a 2e-5 change.
        let exact = 0.25f64;
        // The error bars are honest: the RMS error over the points matches the RMS standard
        // error (400 points with the same variance: either RMS is within ~7%, so a standard
        // error wrong by a factor 1.6 either way fails).
        let rms_err = 255.0
            * (truth
                .values
                .iter()
                .map(|&a| (a as f64 - exact).powi(2))
                .sum::<f64>()
                / n as f64)
                .sqrt();
        let ratio = rms_err / truth.rms_stderr_255();
        assert!(
            (0.6..1.6).contains(&ratio),
            "RMS error {rms_err} against RMS stderr {}: {:?}",
            truth.rms_stderr_255(),
            truth.rounds
        );
        // Rays doubled per side (×4 per round) from 4 × 8², stopping at the target or the cap.
        for (i, &(r, _)) in truth.rounds.iter().enumerate() {
            assert_eq!(r, 256 << (2 * i));
        }
        assert!(truth.converged(&t) || truth.rays_per_point * 4 > t.max_rays);
        assert!(truth.max_stderr_255() >= truth.rms_stderr_255());
    }

    #[test]
    fn unoccluded_points_are_exact_with_zero_error() {
        // Nothing above: every batch gives 1, so AO 1 and standard error 0 after one round.
        let tracer = Tracer::new(&square(10.0, 0.0));
        let points = vec![Vec3::new(0.3, 0.2, 0.0); 5];
        let truth = converged_ao(
            &tracer,
            &points,
            &[Vec3::Z; 5],
            &AoOptions::for_scene_radius(10.0),
            &TruthOptions::default(),
        );
        assert!(truth.values.iter().all(|&a| a == 1.0));
        assert_eq!(truth.rms_stderr_255(), 0.0);
        assert_eq!((truth.rounds.len(), truth.rays_per_point), (1, 256));
    }

    #[test]
    fn the_cap_stops_the_rounds() {
        // A target of 0 is never met: the rounds stop where the next would pass the cap.
        let tracer = Tracer::new(&square(50.0, 0.5));
        let points: Vec<Vec3> = (0..20)
            .map(|i| Vec3::new(0.1 * i as f32, 0.0, 0.0))
            .collect();
        let opts = step_within_one();
        let t = TruthOptions {
            target_stderr_255: 0.0,
            max_rays: 5000,
            ..TruthOptions::default()
        };
        let truth = converged_ao(&tracer, &points, &vec![Vec3::Z; 20], &opts, &t);
        assert_eq!(truth.rays_per_point, 4096);
        assert_eq!(truth.rounds.len(), 3);
        assert!(!truth.converged(&t));
    }

    #[test]
    fn channels_converge_point_major_and_one_channel_is_the_scalar_path() {
        // Three channels per point from the AO under a ceiling: v, 1 − v and 0.5. With a target
        // of 0 both runs stop at the cap after the same rounds, so channel 0 is the scalar
        // truth bit for bit, channel 1 its complement with the same standard errors, channel 2
        // exact with none.
        let tracer = Tracer::new(&square(50.0, 0.5));
        let n = 30;
        let points: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(0.05 * i as f32, 0.0, 0.0))
            .collect();
        let normals = vec![Vec3::Z; n];
        let opts = step_within_one();
        let t = TruthOptions {
            target_stderr_255: 0.0,
            max_rays: 1100,
            ..TruthOptions::default()
        };
        let ao = |rays: &RaySet| ao_at_points(&tracer, &points, &normals, rays, &opts);
        let scalar = converged(n, &t, ao);
        let three = converged_channels(n, 3, &t, |rays| {
            ao(rays)
                .into_iter()
                .flat_map(|v| [v, 1.0 - v, 0.5])
                .collect()
        });
        assert_eq!((three.channels, three.points()), (3, n));
        assert_eq!(three.rays_per_point, scalar.rays_per_point);
        for i in 0..n {
            let (v, e) = (
                &three.values[3 * i..3 * i + 3],
                &three.stderr[3 * i..3 * i + 3],
            );
            assert_eq!((v[0], e[0]), (scalar.values[i], scalar.stderr[i]));
            assert!((v[1] - (1.0 - scalar.values[i])).abs() < 1e-6, "{v:?}");
            assert!((e[1] - e[0]).abs() <= 1e-6 * e[0].max(1e-3), "{e:?}");
            assert_eq!((v[2], e[2]), (0.5, 0.0));
        }
        // The criterion is over every value: two channels of the scalar's errors and one of
        // none give √(2/3) of its RMS.
        let want = scalar.rms_stderr_255() * (2.0f64 / 3.0).sqrt();
        let got = three.rounds.last().unwrap().1;
        assert!((got - want).abs() < 1e-4 * want, "{got} vs {want}");
        // One channel through `converged_channels` is `converged`.
        assert_eq!(converged_channels(n, 1, &t, ao), scalar);
    }
}
