//! The estimator seam: what a render kind computes at its evaluation points, written once
//! against [`Visibility`] so that ray casting and field lookup answer the same question on the
//! same rays (in the spirit of pbrt-v4's `Integrator`: the integrand is the kind's, the
//! visibility is the backend's).
//!
//! A render kind supplies
//! - its evaluation points ([`super::points::EvalPoints`]: the receivers' vertices, or the receiver pixels of a
//!   G-buffer, [`super::points`]);
//! - an [`Estimator`]: per point, a value in \[0, 1\] from `k²` seeded rays
//!   ([`Estimator::estimate`]), and the same quantity converged ([`Estimator::converged`],
//!   the reference every `_vs_truth` error is measured against);
//! - the cache key of everything beside the points and rays that determines its values
//!   ([`Estimator::key`]).
//!
//! [`AoEstimator`] is the first estimator: the AO integral of [`super::ao`] (the 2008 paper's
//! vertex AO and the 2010 paper's per-pixel AO evaluate it at different points).

use super::ao::{ao_at_points, AoOptions};
use super::truth::{converged_ao, Truth, TruthOptions};
use crate::visibility::Visibility;
use crate::sampling::rays::RaySet;
use glam::Vec3;

/// Evaluation points: world positions and unit normals, point `i` using the rays of point
/// index `i`.
#[derive(Clone, Copy, Debug)]
pub struct Points<'a> {
    pub points: &'a [Vec3],
    pub normals: &'a [Vec3],
}

impl Points<'_> {
    /// The number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// A per-point quantity estimated through any [`Visibility`].
pub trait Estimator: Sync {
    /// Short name for tables and messages ("ao").
    fn name(&self) -> &'static str;

    /// The estimate at every point from the `k²` rays of `rays` (point `i` uses the directions
    /// of point index `i`). Deterministic: the same inputs give the same bits on any thread
    /// count.
    fn estimate(&self, vis: &dyn Visibility, at: Points, rays: &RaySet) -> Vec<f32>;

    /// The converged estimate (see [`super::truth`]).
    fn converged(&self, vis: &dyn Visibility, at: Points, t: &TruthOptions) -> Truth;

    /// Everything beside the points, the casters and the rays that determines the values, as
    /// JSON object entries (part of the converged reference's cache key).
    fn key(&self) -> serde_json::Map<String, serde_json::Value>;

    /// The AO options when this estimator is the AO integral of [`super::ao`]: the GPU's AO
    /// kernels then compute it. `None` for other quantities.
    fn ao_options(&self) -> Option<&AoOptions> {
        None
    }

    /// The shadow options when this estimator is the light fraction of spherical lights of
    /// [`super::shadow`]: the GPU's shadow kernels then compute it. `None` for other quantities.
    fn shadow_options(&self) -> Option<&super::shadow::ShadowOptions> {
        None
    }

    /// The reflection options when this estimator is the reflected radiance of
    /// [`super::reflect`]: the GPU's reflection kernels then compute it. `None` for other
    /// quantities.
    fn reflect_options(&self) -> Option<&super::reflect::ReflectOptions> {
        None
    }
}

/// Ambient occlusion at each point (Gaitatzes, Chrysanthou, Papaioannou, WSCG 2008; per pixel:
/// Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010): [`ao_at_points`] and, converged,
/// [`converged_ao`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AoEstimator {
    pub opts: AoOptions,
}

impl Estimator for AoEstimator {
    fn name(&self) -> &'static str {
        "ao"
    }

    fn estimate(&self, vis: &dyn Visibility, at: Points, rays: &RaySet) -> Vec<f32> {
        ao_at_points(vis, at.points, at.normals, rays, &self.opts)
    }

    fn converged(&self, vis: &dyn Visibility, at: Points, t: &TruthOptions) -> Truth {
        converged_ao(vis, at.points, at.normals, &self.opts, t)
    }

    fn key(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = serde_json::Map::new();
        m.insert("offset".into(), serde_json::json!(self.opts.offset));
        m.insert(
            "max_distance".into(),
            serde_json::json!(self.opts.max_distance),
        );
        m.insert("falloff".into(), serde_json::json!(self.opts.falloff));
        m
    }

    fn ao_options(&self) -> Option<&AoOptions> {
        Some(&self.opts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::test_scenes::square;
    use crate::trace::Tracer;

    #[test]
    fn the_ao_estimator_is_ao_at_points_bit_for_bit_through_dyn_visibility() {
        // A ceiling over a row of points: the estimate through `&dyn Visibility` is the
        // generic path's, bit for bit, so moving a kind onto the seam changes no result.
        let tracer = Tracer::new(&square(1.0, 0.4));
        let points: Vec<Vec3> = (0..50)
            .map(|i| Vec3::new(0.05 * i as f32 - 1.2, 0.03 * i as f32 - 0.7, 0.0))
            .collect();
        let normals = vec![Vec3::Z; points.len()];
        let opts = AoOptions {
            max_distance: Some(2.0),
            offset: 1e-4,
            falloff: crate::render::ao::Falloff::Step,
        };
        let rays = RaySet::new(8, 3);
        let est = AoEstimator { opts };
        let at = Points {
            points: &points,
            normals: &normals,
        };
        let a = est.estimate(&tracer, at, &rays);
        let b = ao_at_points(&tracer, &points, &normals, &rays, &opts);
        assert_eq!(a, b);
        // Some points see the ceiling's edge: the test is not all ones.
        assert!(a.iter().any(|&v| v < 1.0) && a.iter().any(|&v| v > 0.0));
        assert_eq!(est.ao_options(), Some(&opts));
        assert!(est.shadow_options().is_none());
        assert!(est.reflect_options().is_none());
        assert_eq!(
            serde_json::Value::Object(est.key()),
            serde_json::json!({"offset": 1e-4f32, "max_distance": 2.0, "falloff": "step"})
        );
    }
}
