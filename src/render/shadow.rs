//! Soft shadows from spherical lights (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG
//! 2010, §4.2 and Figures 7–8): the fraction of the direct light of spherical area lights that
//! reaches a point, its shadow rays answered by any [`Visibility`] (ray casting, or the
//! visibility field's lookup, which the paper uses for every secondary ray).
//!
//! At a point p with unit normal n, light L (centre c, radius r, radiance `intensity`) subtends
//! the cone of half-angle θ_max, sin θ_max = r / |c − p|. Its `k²` shadow directions are the
//! point's stratified square samples ([`RaySet::fill_square`], cell centres or jittered) mapped
//! to the cone uniformly in solid angle (concentric disk, then cos θ = 1 − ρ²(1 − cos θ_max)),
//! turned about the cone's axis by the point's seeded rotation. Each direction ω with n·ω > 0
//! carries the weight `intensity · (n·ω) · Ω / k²` (Ω = 2π(1 − cos θ_max), the cone's solid
//! angle) and is a shadow ray from p + offset·n to the near side of the light: it is blocked
//! only by a hit before the light. The value at p is
//!
//!   S(p) = Σ weight · V / Σ weight  ∈ \[0, 1\],
//!
//! the light fraction (1: unshadowed; the visibility-only image), the same on every backend for
//! the same rays. A point facing away from every light (no weight) has S = 1: no light, no
//! shadow. A point inside a light sphere skips that light.
//!
//! Deviation from the paper: it samples "stratified points on each spherical light" without
//! saying how; we sample the cone the light subtends, uniformly in solid angle and stratified
//! (k² per light, so 16 or 25 where the paper has 20).

use super::estimator::{Estimator, Points};
use super::per_point;
use super::truth::{converged, Truth, TruthOptions};
use crate::sampling::rays::RaySet;
use crate::sampling::warp::square_to_concentric_disk;
use crate::sampling::Frame;
use crate::visibility::Visibility;
use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// A spherical area light of uniform radiance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereLight {
    /// Centre (world).
    pub center: Vec3,
    /// Radius (positive).
    pub radius: f32,
    /// Radiance (positive; only ratios between lights matter to the light fraction).
    pub intensity: f32,
}

/// Options of [`shadow_at_points`].
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowOptions {
    /// How far the ray origin is moved along the normal (model units).
    pub offset: f32,
    /// The lights (at least one).
    pub lights: Vec<SphereLight>,
}

/// A square sample mapped to the cone of half-angle θ_max about +z (`cos_max` = cos θ_max),
/// uniformly in solid angle: concentric disk (ρ, φ), then cos θ = 1 − ρ²(1 − cos θ_max).
#[inline]
pub fn square_to_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let d = square_to_concentric_disk(u);
    let r2 = d.length_squared();
    if r2 == 0.0 {
        return Vec3::Z;
    }
    let cos = 1.0 - r2 * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let r = r2.sqrt();
    Vec3::new(d.x / r * sin, d.y / r * sin, cos)
}

/// Reused buffers of [`light_fraction`].
#[derive(Default)]
pub struct ShadowScratch {
    squares: Vec<Vec2>,
    dirs: Vec<Vec3>,
    tmaxs: Vec<f32>,
    weights: Vec<f64>,
    blocked: Vec<bool>,
}

/// The shadow rays of one point into `sc` (directions, far ends, weights), every light's, in
/// light order; returns the ray origin.
fn shadow_rays(
    point_index: u32,
    point: Vec3,
    normal: Vec3,
    rays: &RaySet,
    opts: &ShadowOptions,
    sc: &mut ShadowScratch,
) -> Vec3 {
    let origin = point + opts.offset * normal;
    let (s, c) = rays.rotation(point_index);
    rays.fill_square(point_index, &mut sc.squares);
    let n = sc.squares.len().max(1) as f64;
    sc.dirs.clear();
    sc.tmaxs.clear();
    sc.weights.clear();
    for light in &opts.lights {
        let to = light.center - origin;
        let d2 = to.length_squared();
        let r2 = light.radius * light.radius;
        if d2 <= r2 {
            continue;
        }
        let axis = to / d2.sqrt();
        let cos_max = (1.0 - r2 / d2).max(0.0).sqrt();
        let solid_angle = std::f64::consts::TAU * (1.0 - cos_max as f64);
        let frame = Frame::from_normal(axis);
        for &u in sc.squares.iter() {
            let l = square_to_cone(u, cos_max);
            let l = Vec3::new(c * l.x - s * l.y, s * l.x + c * l.y, l.z);
            let dir = frame.to_world(l).normalize();
            let cos_n = normal.dot(dir);
            if cos_n <= 0.0 {
                continue;
            }
            // The near side of the light along dir (the ray is inside the cone: it meets it).
            let b = dir.dot(to);
            sc.dirs.push(dir);
            sc.tmaxs.push(b - (b * b - (d2 - r2)).max(0.0).sqrt());
            sc.weights
                .push(light.intensity as f64 * cos_n as f64 * solid_angle / n);
        }
    }
    origin
}

/// The light fraction at one point (see the module docs). The shadow rays of all lights go to
/// [`Visibility::occluded_many_to`] together (one origin, each ray ending at its light).
pub fn light_fraction<V: Visibility + ?Sized>(
    vis: &V,
    point_index: u32,
    point: Vec3,
    normal: Vec3,
    rays: &RaySet,
    opts: &ShadowOptions,
    scratch: &mut ShadowScratch,
) -> f32 {
    let sc = scratch;
    let origin = shadow_rays(point_index, point, normal, rays, opts, sc);
    if sc.dirs.is_empty() {
        return 1.0;
    }
    sc.blocked.clear();
    sc.blocked.resize(sc.dirs.len(), false);
    vis.occluded_many_to(origin, &sc.dirs, 0.0, &sc.tmaxs, &mut sc.blocked);
    let (mut lit, mut total) = (0.0f64, 0.0f64);
    for (&w, &b) in sc.weights.iter().zip(&sc.blocked) {
        total += w;
        if !b {
            lit += w;
        }
    }
    if total > 0.0 {
        (lit / total) as f32
    } else {
        1.0
    }
}

/// [`light_fraction`] at every point (rayon over points; the same bits on any thread count).
///
/// # Panics
/// If `points` and `normals` differ in length.
pub fn shadow_at_points<V: Visibility + ?Sized>(
    vis: &V,
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &ShadowOptions,
) -> Vec<f32> {
    per_point(
        "shadow_at_points",
        points,
        normals,
        |sc: &mut ShadowScratch, i, p, n| light_fraction(vis, i, p, n, rays, opts, sc),
    )
}

/// The unshadowed direct light at every point, normalised to the brightest (in \[0, 1\]): the
/// light fraction's denominator Σ weight over the shadow directions of `rays` (n·ω-weighted
/// light reaching the point with nothing in the way), divided by its largest value over the
/// points. Times the light fraction it is the shadowed image of a white diffuse receiver.
///
/// # Panics
/// If `points` and `normals` differ in length.
pub fn direct_light(
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &ShadowOptions,
) -> Vec<f32> {
    let raw: Vec<f64> = per_point(
        "direct_light",
        points,
        normals,
        |sc: &mut ShadowScratch, i, p, n| {
            shadow_rays(i, p, n, rays, opts, sc);
            sc.weights.iter().sum()
        },
    );
    let top = raw.iter().copied().fold(0.0f64, f64::max);
    raw.iter()
        .map(|&e| if top > 0.0 { (e / top) as f32 } else { 0.0 })
        .collect()
}

/// The light fraction of spherical lights at each point (Gaitatzes et al. 2010, §4.2):
/// [`shadow_at_points`] and, converged, the same with jittered batches.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowEstimator {
    pub opts: ShadowOptions,
}

impl Estimator for ShadowEstimator {
    fn name(&self) -> &'static str {
        "shadow"
    }

    fn estimate(&self, vis: &dyn Visibility, at: Points, rays: &RaySet) -> Vec<f32> {
        shadow_at_points(vis, at.points, at.normals, rays, &self.opts)
    }

    fn converged(&self, vis: &dyn Visibility, at: Points, t: &TruthOptions) -> Truth {
        converged(at.len(), t, |rays| {
            shadow_at_points(vis, at.points, at.normals, rays, &self.opts)
        })
    }

    fn key(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = serde_json::Map::new();
        m.insert("quantity".into(), serde_json::json!("shadow"));
        m.insert("offset".into(), serde_json::json!(self.opts.offset));
        m.insert("lights".into(), serde_json::json!(self.opts.lights));
        m
    }
}

#[cfg(test)]
#[path = "shadow_tests.rs"]
mod tests;
