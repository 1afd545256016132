//! Glossy reflections through visibility fields and normal fields (Gaitatzes, Andreadis,
//! Papaioannou, Chrysanthou, WSCG 2010, §4.2 and Figure 9): the reflected radiance at a
//! reflective receiver point, its reflection rays answered by any [`Visibility`] through
//! [`Visibility::surface_hit`] (ray casting: the true closest triangle and its normal; a field:
//! the stored distance, hence the hit point, and the normal field's normal).
//!
//! At a point p with unit normal n (facing the eye) seen from the eye e, the mirror direction
//! is r = v − 2(v·n)n with v = (p − e)/|p − e|. The receiver's lobe ([`Gloss`]):
//!
//! - `Mirror`: the single ray along r;
//! - `Phong { exponent }`: k² directions about r with density ∝ cos^exponent of their angle
//!   to r (cos α = u^(1/(exponent+1)), φ = 2πu', [`square_to_phong`], exact in the tails of
//!   the exponents' range), from the point's stratified square samples
//!   ([`RaySet::fill_square`]), turned about r by the point's seeded rotation. Directions with
//!   n·ω ≤ 0 (below the surface) are dropped.
//!
//! Each ray from p + offset·n returns the radiance of what it meets: `sky` on a miss, else the
//! hit shaded as a diffuse surface of albedo `albedo` under the lights (each light a point at its
//! centre, of relative weight intensity / Σ intensity, unshadowed):
//!
//!   L(q, m) = albedo · Σ_l w_l · max(0, m·(c_l − q)/|c_l − q|),
//!
//! m the hit's normal faced against the ray. The value at p is the mean of L over the kept rays
//! (0 when none is kept), in \[0, 1\] (albedo and sky are at most 1), the same on every backend
//! for the same rays.
//!
//! Deviation from the paper: it does not give its lobe, its shading or its lights. Ours is a
//! Phong lobe sampled by importance (every ray weighs the same), an unshadowed diffuse hit lit
//! by the lights' centres and a constant sky; "brushed metal" here is this lobe, converged.

use super::estimator::{Estimates, Estimator, Points};
use super::per_point;
use super::ray_lanes::{self, Isa};
use super::shadow::SphereLight;
use crate::sampling::rays::RaySet;
use crate::sampling::Frame;
use crate::visibility::{SurfaceHit, Visibility};
use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// The reflective receiver's lobe.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Gloss {
    /// A perfect mirror: one ray along the mirror direction.
    Mirror,
    /// A Phong lobe about the mirror direction, density ∝ cos^exponent (exponent > 0; larger is
    /// sharper: half the lobe's rays lie within about acos(0.5^(1/(exponent+1))) of r).
    Phong { exponent: f32 },
}

/// Options of [`reflect_at_points`].
#[derive(Clone, Debug, PartialEq)]
pub struct ReflectOptions {
    /// How far the ray origin is moved along the normal (model units).
    pub offset: f32,
    /// The eye the points are seen from (world).
    pub eye: Vec3,
    pub gloss: Gloss,
    /// The lights shading the hits (their centres, weighted by intensity).
    pub lights: Vec<SphereLight>,
    /// Diffuse albedo of the reflected surfaces, in \[0, 1\].
    pub albedo: f32,
    /// Radiance of a ray that meets nothing, in \[0, 1\].
    pub sky: f32,
}

impl ReflectOptions {
    /// The same options with a mirror lobe.
    pub fn mirror(&self) -> ReflectOptions {
        ReflectOptions {
            gloss: Gloss::Mirror,
            ..self.clone()
        }
    }
}

/// A square sample mapped to the Phong lobe of `exponent` about +z: cos α = u^(1/(exponent+1)),
/// φ = 2πu'. Across the exponents' range (1e-3 … 1e7 and beyond) the angle comes from
/// t = 1 − cos α = −expm1(ln u / (exponent + 1)) in f64 and sin α = √(t(2 − t)), never from a
/// cos α rounded to f32 (which is 1 for most u once the exponent passes about 1e6, collapsing
/// the lobe onto its axis); the f32 direction is (sin α cos φ, sin α sin φ, 1 − t).
#[inline]
pub fn square_to_phong(u: Vec2, exponent: f32) -> Vec3 {
    let t = -((u.x as f64).ln() / (exponent as f64 + 1.0)).exp_m1();
    let sin = (t * (2.0 - t)).max(0.0).sqrt() as f32;
    let phi = std::f32::consts::TAU * u.y;
    Vec3::new(sin * phi.cos(), sin * phi.sin(), (1.0 - t) as f32)
}

/// The radiance a reflection ray brings back from `hit` (see the module docs).
#[inline]
pub fn shade(origin: Vec3, dir: Vec3, hit: Option<SurfaceHit>, opts: &ReflectOptions) -> f32 {
    let Some(h) = hit else {
        return opts.sky;
    };
    let q = origin + h.t * dir;
    let m = if h.normal.dot(dir) > 0.0 {
        -h.normal
    } else {
        h.normal
    };
    let total: f32 = opts.lights.iter().map(|l| l.intensity).sum();
    let lit: f32 = opts
        .lights
        .iter()
        .map(|l| l.intensity * m.dot((l.center - q).normalize_or_zero()).max(0.0))
        .sum();
    if total > 0.0 {
        opts.albedo * (lit / total).min(1.0)
    } else {
        0.0
    }
}

/// The reflection directions of one point into `dirs` (see the module docs); returns the ray
/// origin. `squares` is a buffer for the point's square samples.
pub fn reflection_rays(
    point_index: u32,
    point: Vec3,
    normal: Vec3,
    rays: &RaySet,
    opts: &ReflectOptions,
    squares: &mut Vec<Vec2>,
    dirs: &mut Vec<Vec3>,
) -> Vec3 {
    let mut lobe = Vec::new();
    if let Gloss::Phong { exponent } = opts.gloss {
        phong_lobe(rays, point_index, exponent, squares, &mut lobe);
    }
    lobe_rays_on(
        Isa::detect(),
        point_index,
        point,
        normal,
        rays,
        opts,
        &lobe,
        dirs,
    )
}

/// The Phong lobe's directions of point `point_index`'s squares (in the lobe's frame) into
/// `lobe`, its squares into `squares`.
fn phong_lobe(
    rays: &RaySet,
    point_index: u32,
    exponent: f32,
    squares: &mut Vec<Vec2>,
    lobe: &mut Vec<Vec3>,
) {
    rays.fill_square(point_index, squares);
    lobe.clear();
    lobe.extend(squares.iter().map(|&u| square_to_phong(u, exponent)));
}

/// Reused buffers of [`reflect_at_points`], and the Phong lobe's directions of the last ray
/// set and exponent they served (the same for every point of a set without jitter).
#[derive(Default)]
pub struct ReflectScratch {
    squares: Vec<Vec2>,
    /// [`square_to_phong`] of each square, in the lobe's frame.
    lobe: Vec<Vec3>,
    /// The set and the exponent's bits whose (unjittered) lobe `lobe` holds.
    lobe_of: Option<(RaySet, u32)>,
    dirs: Vec<Vec3>,
    hits: Vec<Option<SurfaceHit>>,
}

/// [`reflection_rays`] into `sc.dirs`, the lobe's directions made once per ray set and
/// exponent (per point when jittered): the same rays bit for bit.
pub(super) fn reflection_rays_in(
    isa: Isa,
    point_index: u32,
    point: Vec3,
    normal: Vec3,
    rays: &RaySet,
    opts: &ReflectOptions,
    sc: &mut ReflectScratch,
) -> Vec3 {
    if let Gloss::Phong { exponent } = opts.gloss {
        let key = (*rays, exponent.to_bits());
        if rays.jitter || sc.lobe_of != Some(key) {
            phong_lobe(rays, point_index, exponent, &mut sc.squares, &mut sc.lobe);
            sc.lobe_of = (!rays.jitter).then_some(key);
        }
    }
    lobe_rays_on(
        isa,
        point_index,
        point,
        normal,
        rays,
        opts,
        &sc.lobe,
        &mut sc.dirs,
    )
}

impl ReflectScratch {
    #[cfg(test)]
    /// The directions the last point left here.
    pub(super) fn dirs(&self) -> &[Vec3] {
        &self.dirs
    }
}

/// The reflection rays of one point from its lobe directions `lobe` (the point's
/// [`square_to_phong`] of each square; unread for a mirror), eight at a time
/// ([`ray_lanes::lobe_rays`]); returns the ray origin.
#[allow(clippy::too_many_arguments)]
fn lobe_rays_on(
    isa: Isa,
    point_index: u32,
    point: Vec3,
    normal: Vec3,
    rays: &RaySet,
    opts: &ReflectOptions,
    lobe: &[Vec3],
    dirs: &mut Vec<Vec3>,
) -> Vec3 {
    let origin = point + opts.offset * normal;
    let v = (point - opts.eye).normalize_or_zero();
    let r = (v - 2.0 * v.dot(normal) * normal).normalize_or_zero();
    dirs.clear();
    match opts.gloss {
        Gloss::Mirror => {
            if normal.dot(r) > 0.0 {
                dirs.push(r);
            }
        }
        Gloss::Phong { .. } => {
            let rotation = rays.rotation(point_index);
            let frame = Frame::from_normal(r);
            ray_lanes::lobe_rays(isa, lobe, rotation, &frame, normal, dirs);
        }
    }
    origin
}

/// The reflected radiance at every point (rayon over points; the same bits on any thread
/// count). Each point's rays go to [`Visibility::surface_hit_many`] together.
///
/// # Panics
/// If `points` and `normals` differ in length, or a field backend lacks its normal fields.
pub fn reflect_at_points<V: Visibility + ?Sized>(
    vis: &V,
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &ReflectOptions,
) -> Vec<f32> {
    per_point(
        "reflect_at_points",
        points,
        normals,
        |sc: &mut ReflectScratch, i, p, n| reflected(vis, i, p, n, rays, opts, sc),
    )
}

/// The reflected radiance at one point (see the module docs), its rays through
/// [`Visibility::surface_hit_many`].
#[inline]
pub fn reflected<V: Visibility + ?Sized>(
    vis: &V,
    point_index: u32,
    point: Vec3,
    normal: Vec3,
    rays: &RaySet,
    opts: &ReflectOptions,
    sc: &mut ReflectScratch,
) -> f32 {
    let o = reflection_rays_in(Isa::detect(), point_index, point, normal, rays, opts, sc);
    if sc.dirs.is_empty() {
        return 0.0;
    }
    sc.hits.clear();
    sc.hits.resize(sc.dirs.len(), None);
    vis.surface_hit_many(o, &sc.dirs, 0.0, f32::INFINITY, &mut sc.hits);
    let sum: f64 = sc
        .dirs
        .iter()
        .zip(&sc.hits)
        .map(|(&d, &h)| shade(o, d, h, opts) as f64)
        .sum();
    (sum / sc.dirs.len() as f64) as f32
}

/// The reflected radiance of a glossy receiver at each point (Gaitatzes et al. 2010, §4.2):
/// [`reflect_at_points`] and, converged, the same with jittered batches.
#[derive(Clone, Debug, PartialEq)]
pub struct ReflectionEstimator {
    pub opts: ReflectOptions,
}

impl Estimator for ReflectionEstimator {
    fn name(&self) -> &'static str {
        "reflection"
    }

    fn estimate(&self, vis: &dyn Visibility, at: Points, rays: &RaySet) -> Vec<f32> {
        reflect_at_points(vis, at.points, at.normals, rays, &self.opts)
    }

    fn estimates(&self) -> Estimates<'_> {
        Estimates::Reflection(&self.opts)
    }

    fn key(&self) -> serde_json::Map<String, serde_json::Value> {
        let o = &self.opts;
        let mut m = serde_json::Map::new();
        m.insert("quantity".into(), serde_json::json!("reflection"));
        m.insert("offset".into(), serde_json::json!(o.offset));
        m.insert("eye".into(), serde_json::json!(o.eye));
        m.insert("gloss".into(), serde_json::json!(o.gloss));
        m.insert("lights".into(), serde_json::json!(o.lights));
        m.insert("albedo".into(), serde_json::json!(o.albedo));
        m.insert("sky".into(), serde_json::json!(o.sky));
        m
    }
}

#[cfg(test)]
#[path = "reflect_tests.rs"]
mod tests;
