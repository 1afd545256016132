//! Soft shadows from spherical lights (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG
//! 2010, §4.2 and Figures 7–8): the fraction of the direct light of spherical area lights that
//! reaches a point, its shadow rays answered by any [`Visibility`] (ray casting, or the
//! visibility field's lookup, which the paper uses for every secondary ray).
//!
//! At a point p with unit normal n, light L (centre c, radius r, radiance `intensity`) subtends
//! the cone of half-angle θ_max, sin θ_max = r / |c − p| ([`LightCone`]). Its `k²` shadow
//! directions are the point's stratified square samples ([`RaySet::fill_square`], cell centres
//! or jittered) mapped to the cone uniformly in solid angle ([`square_to_cone`]: concentric
//! disk, then 1 − cos θ = ρ²(1 − cos θ_max)), turned about the cone's axis by the point's seeded
//! rotation. Each direction ω with n·ω > 0 carries the weight `intensity · (n·ω) · Ω / k²`
//! (Ω = 2π(1 − cos θ_max), the cone's solid angle) and is a shadow ray from p + offset·n to the
//! near side of the light: it is blocked only by a hit before the light. The value at p is
//!
//!   S(p) = Σ weight · V / Σ weight  ∈ \[0, 1\],
//!
//! the light fraction (1: unshadowed; the visibility-only image), the same on every backend for
//! the same rays. A point facing away from every light (no weight) has S = 1: no light, no
//! shadow. A point inside a light sphere skips that light.
//!
//! Small lights. Nothing on the way from r to the rays rounds through cos θ_max: 1 − cos θ_max
//! is (r²/d²) / (1 + cos θ_max) (Ω from it in f64), the directions take 1 − cos θ and sin θ
//! from it ([`square_to_cone`]), and the far end is the near root in its cancellation-free form
//! ([`LightCone::far_end`]). So a light of any angular size, down to the f32 limit of its
//! directions, casts the shadow its limit does, and a sun (r = 7e8 at 1.5e11) the shadow of the
//! same angular size nearby.
//!
//! Point lights. A light of radius 0 is a point light: one shadow ray per point, along the axis
//! to the centre (the exact hard shadow), weighing `intensity · (n·ω) / d²`: for a point light
//! `intensity` is the radiant intensity, the limit of a sphere light of radius r and radiance
//! intensity / (πr²). (It matters only where lights of both kinds are mixed: the light fraction
//! of one light does not depend on its weight.)
//!
//! Deviation from the paper: it samples "stratified points on each spherical light" without
//! saying how; we sample the cone the light subtends, uniformly in solid angle and stratified
//! (k² per light, so 16 or 25 where the paper has 20). Point lights are ours.

use super::estimator::{Estimates, Estimator, Points};
use super::per_point;
use super::ray_lanes::{self, DiskSamples, Isa, ShadowRays};
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
    /// Radius (positive, or 0 for a point light).
    pub radius: f32,
    /// Radiance (positive; only ratios between lights matter to the light fraction); for a
    /// point light its radiant intensity (see the module docs).
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

/// A square sample mapped to the cone of half-angle θ_max about +z, uniformly in solid angle,
/// given `one_minus_cos` = 1 − cos θ_max (see [`one_minus_cos_max`]): concentric disk (ρ, φ),
/// then t = 1 − cos θ = ρ²(1 − cos θ_max), cos θ = 1 − t and sin θ = √(t(2 − t)). Neither
/// passes through a rounded cos θ_max or subtracts two numbers near 1, so the directions keep
/// their spread down to the point-light limit (`one_minus_cos` = 0 gives +z).
#[inline]
pub fn square_to_cone(u: Vec2, one_minus_cos: f32) -> Vec3 {
    let d = square_to_concentric_disk(u);
    let r2 = d.length_squared();
    if r2 == 0.0 {
        return Vec3::Z;
    }
    let t = r2 * one_minus_cos;
    let sin = (t * (2.0 - t)).max(0.0).sqrt();
    let r = r2.sqrt();
    Vec3::new(d.x / r * sin, d.y / r * sin, 1.0 - t)
}

/// 1 − cos θ_max of a cone with sin² θ_max = `q` (r²/d² of a sphere light), without
/// cancellation: q / (1 + √(1 − q)). Written so that it holds for f32 and f64 alike (the f32
/// twin is [`one_minus_cos_max_f32`]); exact 0 at q = 0, 1 at q = 1.
#[inline]
pub fn one_minus_cos_max(q: f64) -> f64 {
    q / (1.0 + (1.0 - q).max(0.0).sqrt())
}

/// [`one_minus_cos_max`] in f32, the expression the directions (and the GPU) use.
#[inline]
pub fn one_minus_cos_max_f32(q: f32) -> f32 {
    q / (1.0 + (1.0 - q).max(0.0).sqrt())
}

/// The cone one light subtends at one ray origin: what every shadow ray to it shares.
#[derive(Clone, Copy, Debug)]
pub struct LightCone {
    /// Light centre − origin.
    pub to: Vec3,
    /// |to|².
    pub d2: f32,
    /// r².
    pub r2: f32,
    /// The unit axis to / |to|.
    pub axis: Vec3,
    /// 1 − cos θ_max in f32 (0 for a point light, or one too small for f32), for the directions.
    pub one_minus_cos: f32,
    /// The weight of one ray before n·ω: intensity · Ω / k² (Ω = 2π(1 − cos θ_max) in f64)
    /// for a sphere light, intensity / d² for a point light (radius 0, one ray).
    pub weight_scale: f64,
    /// Radius 0: one ray, along the axis, to the centre.
    pub point: bool,
    /// The frame about the axis the cone's directions are taken to the world by.
    pub frame: Frame,
}

impl LightCone {
    /// The cone of `light` at `origin` for `cells` = k² samples; `None` when the origin is inside
    /// the light (or at a point light's centre), which then gives no light.
    pub fn new(light: &SphereLight, origin: Vec3, cells: usize) -> Option<LightCone> {
        let to = light.center - origin;
        let d2 = to.length_squared();
        let r2 = light.radius * light.radius;
        if d2 <= r2 || d2 == 0.0 {
            return None;
        }
        let axis = to / d2.sqrt();
        let point = light.radius == 0.0;
        let intensity = light.intensity as f64;
        let weight_scale = if point {
            intensity / d2 as f64
        } else {
            // In f64: r²/d² and Ω stay positive for every radius f32 holds.
            let q = (light.radius as f64).powi(2) / d2 as f64;
            intensity * std::f64::consts::TAU * one_minus_cos_max(q) / cells.max(1) as f64
        };
        Some(LightCone {
            to,
            d2,
            r2,
            axis,
            one_minus_cos: one_minus_cos_max_f32(r2 / d2),
            weight_scale,
            point,
            frame: Frame::from_normal(axis),
        })
    }

    /// The direction of square sample `u`, turned by the point's rotation (sin `s`, cos `c`)
    /// about the axis; a point light's is the axis itself.
    #[inline]
    pub fn direction(&self, u: Vec2, s: f32, c: f32) -> Vec3 {
        if self.point {
            return self.axis;
        }
        let l = square_to_cone(u, self.one_minus_cos);
        ray_lanes::lobe_direction(l, (s, c), &self.frame)
    }

    /// The near side of the light along `dir` (a direction of this cone), without
    /// cancellation: the near root of t² − 2bt + (d² − r²), b = dir·to, written as
    /// (d² − r²) / (b + √(r² − h²)) with h² = |to − b·dir|² the squared distance of the centre
    /// from the ray (formed directly, not as d² − b²); d for a point light.
    #[inline]
    pub fn far_end(&self, dir: Vec3) -> f32 {
        if self.point {
            return self.d2.sqrt();
        }
        let b = dir.dot(self.to);
        let h = self.to - b * dir;
        (self.d2 - self.r2) / (b + (self.r2 - h.length_squared()).max(0.0).sqrt())
    }
}

/// Reused buffers of [`light_fraction`], and the disk samples of the last ray set they served
/// (the same for every point of a set without jitter).
#[derive(Default)]
pub struct ShadowScratch {
    squares: Vec<Vec2>,
    disk: DiskSamples,
    /// The set whose (unjittered) samples `disk` holds.
    disk_of: Option<RaySet>,
    rays: ShadowRays,
    blocked: Vec<bool>,
}

impl ShadowScratch {
    #[cfg(test)]
    /// The shadow rays the last point left here.
    pub(super) fn rays(&self) -> &ShadowRays {
        &self.rays
    }
}

/// The shadow rays of one point into `sc.rays` (directions, far ends, weights), every light's,
/// in light order; returns the ray origin. The disk points of the stratified squares are made
/// once per ray set (per point when jittered) and each light's rays eight at a time on the
/// instruction set `isa` ([`ray_lanes::cone_rays`]; tests compare them): the rays of
/// [`LightCone::direction`] and [`LightCone::far_end`] of each square, bit for bit.
pub(super) fn shadow_rays(
    isa: Isa,
    point_index: u32,
    point: Vec3,
    normal: Vec3,
    rays: &RaySet,
    opts: &ShadowOptions,
    sc: &mut ShadowScratch,
) -> Vec3 {
    let origin = point + opts.offset * normal;
    let (s, c) = rays.rotation(point_index);
    if rays.jitter || sc.disk_of != Some(*rays) {
        rays.fill_square(point_index, &mut sc.squares);
        sc.disk.fill(&sc.squares);
        sc.disk_of = (!rays.jitter).then_some(*rays);
    }
    sc.rays.clear();
    let cells = sc.disk.len();
    for light in &opts.lights {
        let Some(cone) = LightCone::new(light, origin, cells) else {
            continue;
        };
        if !cone.point {
            ray_lanes::cone_rays(isa, &sc.disk, &cone, (s, c), normal, &mut sc.rays);
        } else if cells > 0 {
            // One ray, along the axis.
            let dir = cone.axis;
            let cos_n = normal.dot(dir);
            if cos_n > 0.0 || cos_n.is_nan() {
                sc.rays.dirs.push(dir);
                sc.rays.tmaxs.push(cone.far_end(dir));
                sc.rays.weights.push(cone.weight_scale * cos_n as f64);
            }
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
    let origin = shadow_rays(Isa::detect(), point_index, point, normal, rays, opts, sc);
    let r = &sc.rays;
    if r.dirs.is_empty() {
        return 1.0;
    }
    sc.blocked.clear();
    sc.blocked.resize(r.dirs.len(), false);
    vis.occluded_many_to(origin, &r.dirs, 0.0, &r.tmaxs, &mut sc.blocked);
    let (mut lit, mut total) = (0.0f64, 0.0f64);
    for (&w, &b) in r.weights.iter().zip(&sc.blocked) {
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

/// The unshadowed direct light at every point: the light fraction's denominator Σ weight over
/// the shadow directions of `rays` (n·ω-weighted light reaching the point with nothing in the
/// way; for a point on a sphere light's axis, facing it, π · intensity · sin²θ_max up to the
/// stratification, intensity / d² for a point light).
///
/// # Panics
/// If `points` and `normals` differ in length.
pub fn unshadowed_light(
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &ShadowOptions,
) -> Vec<f64> {
    per_point(
        "unshadowed_light",
        points,
        normals,
        |sc: &mut ShadowScratch, i, p, n| {
            shadow_rays(Isa::detect(), i, p, n, rays, opts, sc);
            sc.rays.weights.iter().sum()
        },
    )
}

/// [`unshadowed_light`] normalised to the brightest point (in \[0, 1\]). Times the light
/// fraction it is the shadowed image of a white diffuse receiver.
///
/// # Panics
/// If `points` and `normals` differ in length.
pub fn direct_light(
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &ShadowOptions,
) -> Vec<f32> {
    let raw = unshadowed_light(points, normals, rays, opts);
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

    fn estimates(&self) -> Estimates<'_> {
        Estimates::Shadow(&self.opts)
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
