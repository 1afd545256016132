//! The estimator seam: what a render kind computes at its evaluation points, written once
//! against [`Visibility`] so that ray casting and field lookup answer the same question on the
//! same rays (in the spirit of pbrt-v4's `Integrator`: the integrand is the kind's, the
//! visibility is the backend's).
//!
//! A render kind supplies
//! - its evaluation points ([`super::points::EvalPoints`]: the receivers' vertices, or the receiver pixels of a
//!   G-buffer, [`super::points`]);
//! - an [`Estimator`]: per point, a value in \[0, 1\] from `k²` seeded rays
//!   ([`Estimator::estimate`]), or several (its [`Estimator::channels`]: an RGB, a direction
//!   mapped into \[0, 1\]³), and the same quantity converged ([`Estimator::converged`],
//!   the reference every `_vs_truth` error is measured against);
//! - the cache key of everything beside the points and rays that determines its values
//!   ([`Estimator::key`]).
//!
//! [`AoEstimator`] is the first estimator: the AO integral of [`super::ao`] (the 2008 paper's
//! vertex AO and the 2010 paper's per-pixel AO evaluate it at different points).

use super::ao::{ao_at_points, AoOptions};
use super::reflect::ReflectOptions;
use super::shadow::ShadowOptions;
use super::truth::{converged_ao, converged_channels, Truth, TruthOptions};
use crate::sampling::rays::RaySet;
use crate::visibility::Visibility;
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

/// What a render kind estimates, as a tag: what tables and plots call its values, and what
/// `run.json` records (`"quantity"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Ambient occlusion.
    Ao,
    /// The light fraction of spherical lights.
    Shadow,
    /// Reflected radiance.
    Reflection,
    /// Anything else (a kind of a user's own).
    #[default]
    Other,
}

impl Quantity {
    /// How a plot's axis names it: "AO", "shadow", "reflection", or "estimate".
    pub fn label(self) -> &'static str {
        match self {
            Quantity::Ao => "AO",
            Quantity::Shadow => "shadow",
            Quantity::Reflection => "reflection",
            Quantity::Other => "estimate",
        }
    }
}

/// What an estimator computes, typed, with the options that decide its values: how a method
/// that answers a quantity by its own means (cone tracing a distance field) reads the kind's
/// options, instead of parsing [`Estimator::key`].
#[derive(Clone, Copy, Debug)]
pub enum Estimates<'a> {
    /// Ambient occlusion ([`AoEstimator`]).
    Ao(&'a AoOptions),
    /// The light fraction of spherical lights ([`super::shadow::ShadowEstimator`]).
    Shadow(&'a ShadowOptions),
    /// Glossy reflections ([`super::reflect::ReflectionEstimator`]).
    Reflection(&'a ReflectOptions),
    /// Anything else.
    Other,
}

impl Estimates<'_> {
    /// Its tag.
    pub fn quantity(&self) -> Quantity {
        match self {
            Estimates::Ao(_) => Quantity::Ao,
            Estimates::Shadow(_) => Quantity::Shadow,
            Estimates::Reflection(_) => Quantity::Reflection,
            Estimates::Other => Quantity::Other,
        }
    }
}

/// A per-point quantity estimated through any [`Visibility`].
pub trait Estimator: Sync {
    /// Short name for tables and messages ("ao").
    fn name(&self) -> &'static str;

    /// Values per point, each in \[0, 1\]: 1 for a scalar quantity (AO, a light fraction, a
    /// reflected radiance), more for one with channels. [`Self::estimate`] and
    /// [`Self::converged`] give this many values per point, point-major: point `i`'s channel
    /// `c` at `i * channels + c`.
    fn channels(&self) -> usize {
        1
    }

    /// The estimate at every point from the `k²` rays of `rays` (point `i` uses the directions
    /// of point index `i`), [`Self::channels`] values per point. Deterministic: the same
    /// inputs give the same bits on any thread count.
    fn estimate(&self, vis: &dyn Visibility, at: Points, rays: &RaySet) -> Vec<f32>;

    /// The converged estimate (see [`super::truth`]): by default [`Self::estimate`] over
    /// jittered batches, [`Self::channels`] values per point ([`converged_channels`]).
    fn converged(&self, vis: &dyn Visibility, at: Points, t: &TruthOptions) -> Truth {
        converged_channels(at.len(), self.channels(), t, |rays| {
            self.estimate(vis, at, rays)
        })
    }

    /// Everything beside the points, the casters and the rays that determines the values, as
    /// JSON object entries (part of the converged reference's cache key).
    fn key(&self) -> serde_json::Map<String, serde_json::Value>;

    /// What it computes, with its options ([`Estimates`]); none of the three built-in
    /// quantities by default.
    fn estimates(&self) -> Estimates<'_> {
        Estimates::Other
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

    fn estimates(&self) -> Estimates<'_> {
        Estimates::Ao(&self.opts)
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
}
