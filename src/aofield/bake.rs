//! The bake (Kontkanen & Laine 2005, preprocessing): per texel of the cube map, the occluder's solid
//! angle Ω and average occluded direction Υ sampled at `radial_samples` distances along the
//! texel's direction, then the two radial models fitted to them ([`super::fit`]).
//!
//! **Where.** Along texel direction ω, from the hull's distance s₀ = r₀/R ([`super::hull`]) to
//! `reach` bounding radii R, at `sᵢ = s₀ + d·(D/d)^{i/(N−1)}`, i = 0…N−1, `d` = [`NEAR`] and
//! `D = reach − s₀`: logarithmically spaced distances from the hull, dense near it where contact
//! shadows change fastest. The paper samples "logarithmically in r" outside the hull and not too
//! far; deviation from the paper: the exact rule is ours.
//!
//! **How.** The paper rasterises the occluder into a cube around each sample point; ours casts
//! rays with our tracer ([`crate::trace::Tracer`], in model space): `k × k` strata of the unit
//! square, each stratum's centre mapped by the concentric map to the disk and then, area
//! preserving, onto the cone that the bounding sphere subtends from the point (`cos θ = 1 −
//! ρ²(1 − cos β)`, `sin β = R/dist`), so every ray has the same solid angle `Ω_cone/k²`; a point
//! inside the bounding sphere uses the whole sphere (`square_to_uniform_sphere`, `4π/k²` each).
//! Ω is the solid angle of the rays that hit, Υ the normalised sum of their directions.
//! Deviation from the paper: no low-pass filter of the cube map before fitting (the paper
//! renders it at a higher resolution and filters it down); each texel is fitted from its centre
//! direction alone.

use super::cube::Cube;
use super::fit::{fit_centre, fit_solid_angle, model_direction};
use super::hull::SupportPlanes;
use super::storage::Texel;
use super::{AoFieldError, BakeParams};
use crate::geometry::{minimal_bounding_sphere, Sphere};
use crate::sampling::warp::{square_to_concentric_disk, square_to_uniform_sphere};
use crate::sampling::Frame;
use crate::trace::Tracer;
use crate::visibility::Visibility;
use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// The first sample's distance from the hull, in bounding radii.
pub const NEAR: f64 = 0.01;

/// A fitted field before it is stored at a precision: the f32 channels of every texel.
#[derive(Clone, Debug, PartialEq)]
pub struct Fitted {
    pub params: BakeParams,
    /// The occluder's minimal bounding sphere (model space): its centre is the field's centre,
    /// its radius the unit of `s`.
    pub bounds: Sphere,
    pub texels: Vec<Texel>,
}

/// What a bake measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeStats {
    /// Rays cast.
    pub rays: u64,
    /// The largest |Ωᵢ − Ω̃(sᵢ)| over every texel's samples (steradians).
    pub max_omega_residual: f64,
    /// The RMS of Ωᵢ − Ω̃(sᵢ) over every sample (steradians).
    pub rms_omega_residual: f64,
    /// The largest angle between a sample's Υᵢ and the model's Υ̃(sᵢ) (radians).
    pub max_direction_residual: f64,
    /// The least and greatest hull distance s₀ over the texels (bounding radii).
    pub hull_range: (f64, f64),
}

/// The sample distances (bounding radii) along a texel whose hull distance is `s0`.
pub fn sample_radii(s0: f64, params: &BakeParams) -> Vec<f64> {
    let n = params.radial_samples;
    let span = (f64::from(params.reach) - s0).max(2.0 * NEAR);
    (0..n)
        .map(|i| s0 + NEAR * (span / NEAR).powf(i as f64 / (n - 1) as f64))
        .collect()
}

/// One sample: Ω and the (unnormalised) sum of the hit directions' solid angles times
/// direction, at `point` (model space), through `k²` rays.
pub fn sample_at(tracer: &Tracer, bounds: &Sphere, point: Vec3, k: u32) -> (f64, DVec3) {
    let to_centre = bounds.center - point;
    let dist = to_centre.length();
    let n = (k * k) as usize;
    let mut dirs = Vec::with_capacity(n);
    let weight;
    if f64::from(dist) > f64::from(bounds.radius) * (1.0 + 1e-6) {
        let axis = to_centre / dist;
        let sin_b = f64::from(bounds.radius) / f64::from(dist);
        let one_minus_cos_b = sin_b * sin_b / (1.0 + (1.0 - sin_b * sin_b).sqrt());
        weight = 2.0 * PI * one_minus_cos_b / n as f64;
        let frame = Frame::from_normal(axis);
        for j in 0..k {
            for i in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let p = square_to_concentric_disk(u);
                let rho2 = f64::from(p.length_squared());
                let cos_t = 1.0 - rho2 * one_minus_cos_b;
                let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                let rho = rho2.sqrt();
                let local = if rho > 0.0 {
                    Vec3::new(
                        (f64::from(p.x) / rho * sin_t) as f32,
                        (f64::from(p.y) / rho * sin_t) as f32,
                        cos_t as f32,
                    )
                } else {
                    Vec3::Z
                };
                dirs.push(frame.to_world(local).normalize());
            }
        }
    } else {
        weight = 4.0 * PI / n as f64;
        for j in 0..k {
            for i in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                dirs.push(square_to_uniform_sphere(u));
            }
        }
    }
    let mut hit = vec![false; n];
    tracer.occluded_many(point, &dirs, 0.0, f32::INFINITY, &mut hit);
    let mut omega = 0.0;
    let mut sum = DVec3::ZERO;
    for (d, &h) in dirs.iter().zip(&hit) {
        if h {
            omega += weight;
            sum += weight * d.as_dvec3();
        }
    }
    (omega, sum)
}

/// Per texel: its channels and its residuals (Ω, direction) and rays.
struct TexelFit {
    texel: Texel,
    max_omega: f64,
    sum_sq_omega: f64,
    max_angle: f64,
}

/// Bakes the AO field of the triangles `triangles` (model space).
pub fn bake(
    triangles: &[[Vec3; 3]],
    params: &BakeParams,
) -> Result<(Fitted, BakeStats), AoFieldError> {
    params.check()?;
    if triangles.is_empty() {
        return Err(AoFieldError::Invalid("an occluder needs triangles".into()));
    }
    let points: Vec<Vec3> = triangles.iter().flatten().copied().collect();
    let bounds = minimal_bounding_sphere(&points);
    if !(bounds.radius > 0.0 && bounds.radius.is_finite()) {
        return Err(AoFieldError::Invalid(format!(
            "the occluder's bounding radius is {}",
            bounds.radius
        )));
    }
    let centre = bounds.center.as_dvec3();
    let radius = f64::from(bounds.radius);
    // Each vertex once (a mesh repeats each about six times over its triangles).
    let mut unique: Vec<[u32; 3]> = points
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect();
    unique.sort_unstable();
    unique.dedup();
    let dpoints: Vec<DVec3> = unique
        .iter()
        .map(|b| Vec3::from_array(b.map(f32::from_bits)).as_dvec3())
        .collect();
    let planes = SupportPlanes::new(&dpoints, centre);
    let tracer = Tracer::new(triangles);
    let cube = Cube { res: params.res };
    let k = params.rays_per_side();
    let fits: Vec<TexelFit> = (0..cube.len())
        .into_par_iter()
        .map(|t| {
            let w = cube.texel_direction(t).as_dvec3().normalize();
            let s0 = planes.distance(w, radius) / radius;
            let radii = sample_radii(s0, params);
            let mut omega = Vec::with_capacity(radii.len());
            let mut dir_s = Vec::with_capacity(radii.len());
            let mut dirs = Vec::with_capacity(radii.len());
            for &s in &radii {
                let p = (centre + s * radius * w).as_vec3();
                let (o, sum) = sample_at(&tracer, &bounds, p, k);
                omega.push(o);
                if let Some(d) = sum.try_normalize() {
                    dir_s.push(s);
                    dirs.push(d);
                }
            }
            let q = fit_solid_angle(&radii, &omega, s0);
            let c = fit_centre(&dir_s, &dirs, w);
            let (mut max_omega, mut sum_sq_omega) = (0.0f64, 0.0);
            for (&s, &o) in radii.iter().zip(&omega) {
                let e = (o - q.omega(s)).abs();
                max_omega = max_omega.max(e);
                sum_sq_omega += e * e;
            }
            let max_angle = dir_s
                .iter()
                .zip(&dirs)
                .map(|(&s, d)| d.dot(model_direction(c, s, w)).clamp(-1.0, 1.0).acos())
                .fold(0.0, f64::max);
            TexelFit {
                texel: [
                    q.a as f32, q.b as f32, q.c as f32, s0 as f32, c.x as f32, c.y as f32,
                    c.z as f32,
                ],
                max_omega,
                sum_sq_omega,
                max_angle,
            }
        })
        .collect();
    let samples = (fits.len() * params.radial_samples) as f64;
    let stats = BakeStats {
        rays: (fits.len() * params.radial_samples) as u64 * u64::from(k * k),
        max_omega_residual: fits.iter().map(|f| f.max_omega).fold(0.0, f64::max),
        rms_omega_residual: (fits.iter().map(|f| f.sum_sq_omega).sum::<f64>() / samples).sqrt(),
        max_direction_residual: fits.iter().map(|f| f.max_angle).fold(0.0, f64::max),
        hull_range: fits.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), f| {
            let s0 = f64::from(f.texel[3]);
            (lo.min(s0), hi.max(s0))
        }),
    };
    Ok((
        Fitted {
            params: *params,
            bounds,
            texels: fits.into_iter().map(|f| f.texel).collect(),
        },
        stats,
    ))
}
