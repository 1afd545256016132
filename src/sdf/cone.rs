//! Cone tracing through distance volumes, the engines' direct estimators of ambient occlusion
//! and of a spherical light's soft shadow (D. Wright, "Dynamic Occlusion with Signed Distance
//! Fields", SIGGRAPH 2015 course *Advances in Real-Time Rendering*; Unreal Engine 4's
//! `DistanceFieldScreenGridLighting.usf`, object cone traces, and `DistanceFieldShadowing.usf`;
//! I. Quilez, "Soft shadows in raymarched SDFs", 2010, whose `k` is 1 / tan θ here).
//!
//! **The closest-approach visibility.** A cone with apex o, unit axis a and half-angle θ is
//! marched along its axis; at each step t the volume reads d(t), the distance to the nearest
//! surface from o + t·a, and the cone's visibility is
//!
//!   V = min over steps of saturate( d(t) / (t · tan θ) ),
//!
//! the engines' "1d intersection": the share of the cone's radius t·tan θ at t that is clear.
//! A step reading below the hit threshold (as sphere tracing's, a share of a voxel) gives 0.
//! Over instances the cone's visibility is the least over them (UE's `InterlockedMin` over
//! objects; the same as one trace through the union's distance, the least of the reads).
//!
//! **Step rule.** t starts at `start_voxels` of the volume's voxels (the self-shadow offset:
//! UE's object traces start at their first step offset, its shadows past a ray-start offset) and
//! advances by max(d, step · t · tan θ, threshold): sphere tracing, with a least step a share
//! [`ConeTrace::step`] of the cone's radius (UE: `max(DistanceToOccluder, MinStepSize)`). The
//! least step binds only where d < step · t · tan θ, where the visibility already read is below
//! `step`. The trace ends past the cone's far end (the AO radius, the light's near side), after
//! [`ConeTrace::max_steps`], or where no later step can lower V (below).
//!
//! **The bound that ends a trace.** Let a volume's reads be at least |p − c| − R outside a
//! sphere (c, R) ([`ConeField::bounds`]). For a cone apex at distance D > R from c, at angle γ
//! between the axis and c − o, and sin α = R / D, the lower bound g(t) = (|o + t·a − c| − R) / t
//! is, in s = 1/t, a norm of an affine function minus a linear one, so convex; it is least at
//!
//!   t* = D cos α / cos(γ − α),   g(t*) = sin(γ − α)
//!
//! (set the derivative to zero: (u − cos γ) / √(1 − 2u cos γ + u²) = sin α with u = D/t).
//! So a volume whose sin(γ − α) / tan θ is not below the visibility already found cannot lower
//! it and is not marched (nor when the sphere lies wholly behind the apex, cos(γ − α) ≤ 0, with
//! tan θ ≤ 1); and past t* the bound only grows, so a trace ends once (|p − c| − R) / (t tan θ)
//! reaches V. The ends change nothing of V (up to the step count): every step they skip reads
//! no less. For an exact sphere occluder the same algebra is the estimator's continuous limit:
//! V = saturate(sin(γ − α) / tan θ), the angular gap between the axis and the sphere's outline
//! over tan θ (tests/sdf_cone.rs measures the stepped, baked estimate against it).
//!
//! **AO.** N cones about the normal ([`ConeSet::hemisphere`]): axes at the centres of N
//! equal-area cells of the hemisphere (a spherical Fibonacci lattice: z_i = 1 − (i + ½)/N,
//! φ_i = i · π(3 − √5)), each of half-angle θ with cos θ = 1 − 1/N, so that the N cones' solid
//! angles, 2π(1 − cos θ) each, sum to the hemisphere's (UE: `GAOConeHalfAngle =
//! acos(1 − 1/NumConeSampleDirections)`, 9 cones). The AO is the cosine-weighted mean
//! Σ cos β_i V_i / Σ cos β_i (β_i: axis to normal), an estimate of (1/π)∫V (n·ω) dω with the
//! cells' equal solid angles (Σ cos β_i = N/2 exactly), 1 exactly where nothing occludes.
//!
//! **Soft shadows.** One cone per spherical light, from the point towards the light's centre,
//! its half-angle the light's angular radius (sin θ = r / |c − o|), marched to the light's near
//! side; a point light (r = 0) is the limit tan θ = 0: a hard shadow, 0 on a hit, else 1. The
//! lights are weighed by their unshadowed irradiance: the light fraction is
//! Σ E_L V_L / Σ E_L with E_L = intensity · ∫_cap (n·ω)⁺ dω ([`cap_irradiance`]), intensity ·
//! (n·a)⁺ / d² for a point light, the weights `render::shadow` samples (its light fraction's
//! expectation with V = 1 per light); 1 where no light reaches the point.
//!
//! Deviations from the engines: UE combines its 9 cones into a bent normal whose length is the
//! occlusion (|Σ V_i a_i| / |Σ a_i|, equal to our Σ cos β_i V_i / Σ cos β_i where the bent
//! normal stays along n) and rotates its fixed `SpacedVectors9` set per frame; we take the
//! cosine-weighted mean over a fixed Fibonacci set. We leave out UE's heuristics: the distance
//! fade near the AO radius, the small-object and self-shadow visibility floors, the "force to
//! shadowed at the last step"; our steps have no fixed schedule (UE's step offsets grow
//! quadratically) and the trace ends by the bound above rather than at a fixed step count.

use super::{DistanceVolume, SdfScene};
use crate::sampling::Frame;
use glam::Vec3;

/// A field cone tracing reads.
pub trait ConeField {
    /// The read distance at `p` (negative inside).
    fn distance(&self, p: Vec3) -> f32;
    /// A sphere (centre, radius) outside which every read is at least the distance to it.
    fn bounds(&self) -> (Vec3, f32);
}

impl ConeField for DistanceVolume {
    #[inline]
    fn distance(&self, p: Vec3) -> f32 {
        self.sample(p)
    }

    fn bounds(&self) -> (Vec3, f32) {
        self.bounding_sphere()
    }
}

/// How cones are marched (beside [`super::SdfTrace`]'s hit threshold and start offset).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeTrace {
    /// The least step, as a share of the cone's radius t · tan θ.
    pub step: f32,
    /// Steps per cone and volume; where they run out, the visibility read so far stands.
    pub max_steps: u32,
}

impl Default for ConeTrace {
    /// A quarter of the cone's radius, 256 steps.
    fn default() -> Self {
        ConeTrace {
            step: 0.25,
            max_steps: 256,
        }
    }
}

/// The closest-approach visibility of one cone through `field`, in the field's space: apex
/// `o`, unit `axis`, tan of the half-angle `tan` (0: a ray), marched over [t0, t1] with the hit
/// threshold `eps`, no more than `upper` (the visibility other volumes already gave).
#[allow(clippy::too_many_arguments)]
pub fn cone_visibility<F: ConeField + ?Sized>(
    field: &F,
    o: Vec3,
    axis: Vec3,
    tan: f32,
    (t0, t1): (f32, f32),
    eps: f32,
    upper: f32,
    opts: &ConeTrace,
) -> f32 {
    let (c, r) = field.bounds();
    let oc = c - o;
    let dd = oc.length();
    let mut t_star = 0.0f32;
    if dd > r {
        let (sin_a, cos_g) = (r / dd, axis.dot(oc) / dd);
        let cos_a = (1.0 - sin_a * sin_a).max(0.0).sqrt();
        let sin_g = (1.0 - cos_g * cos_g).max(0.0).sqrt();
        let sin_ga = sin_g * cos_a - cos_g * sin_a;
        let cos_ga = cos_g * cos_a + sin_g * sin_a;
        // The ray's least distance to the sphere: no hit below the threshold where it is not
        // below it.
        let gap = if cos_g > 0.0 { dd * sin_g } else { dd } - r;
        if gap >= eps && ((cos_ga <= 0.0 && tan <= 1.0) || (cos_ga > 0.0 && sin_ga >= tan * upper))
        {
            return upper;
        }
        t_star = if cos_ga > 0.0 {
            dd * cos_a / cos_ga
        } else {
            f32::INFINITY
        };
    }
    let mut v = upper;
    let mut t = t0;
    for _ in 0..opts.max_steps {
        if t > t1 {
            break;
        }
        let p = o + t * axis;
        let d = field.distance(p);
        if d < eps {
            return 0.0;
        }
        let radius = t * tan;
        if d < v * radius {
            v = d / radius;
        }
        if t >= t_star {
            let lower = (p - c).length() - r;
            if lower >= eps && lower >= v * radius {
                break;
            }
        }
        t += d.max(opts.step * radius).max(eps);
    }
    v
}

/// The cones of AO about a normal: axes in the normal's frame (z up) and the tangent of their
/// common half-angle.
#[derive(Clone, Debug, PartialEq)]
pub struct ConeSet {
    pub axes: Vec<Vec3>,
    pub tan_half: f32,
}

impl ConeSet {
    /// The most cones of a set.
    pub const MAX: usize = 256;

    /// `n` cones (2..=[`Self::MAX`]) over the hemisphere (see the module docs): Fibonacci
    /// axes at the centres of equal-area cells, cos θ = 1 − 1/n.
    ///
    /// # Panics
    /// If `n` is outside 2..=[`Self::MAX`] (callers validate it).
    pub fn hemisphere(n: usize) -> ConeSet {
        assert!(
            (2..=Self::MAX).contains(&n),
            "cone count {n} outside 2..={}",
            Self::MAX
        );
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let axes = (0..n)
            .map(|i| {
                let z = 1.0 - (i as f64 + 0.5) / n as f64;
                let s = (1.0 - z * z).sqrt();
                let phi = golden * i as f64;
                Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32)
            })
            .collect();
        // cos θ = (n − 1)/n, sin θ = √(2n − 1)/n.
        let tan_half = ((2 * n - 1) as f64).sqrt() / (n - 1) as f64;
        ConeSet {
            axes,
            tan_half: tan_half as f32,
        }
    }
}

/// ∫ over a cap of angular radius σ (sin² σ = `sin2_sigma`) of (n·ω)⁺ dω, its axis at angle θ
/// from n (cos θ = `cos_theta`): π sin² σ cos θ where the cap lies wholly above the horizon,
/// else the horizon-clipped form (J. Snyder, "Area light sources for real-time graphics",
/// Microsoft Research MSR-TR-96-11, 1996; as written in S. Lagarde, C. de Rousiers, "Moving
/// Frostbite to Physically Based Rendering", SIGGRAPH 2014 course, §4.7.2,
/// `illuminanceSphereOrDisk`); 0 for a cap wholly below.
pub fn cap_irradiance(cos_theta: f64, sin2_sigma: f64) -> f64 {
    use std::f64::consts::PI;
    let cos_theta = cos_theta.clamp(-1.0, 1.0);
    if cos_theta * cos_theta > sin2_sigma {
        return PI * sin2_sigma * cos_theta.max(0.0);
    }
    let sin_theta = (1.0 - cos_theta * cos_theta).sqrt();
    let x = (1.0 / sin2_sigma - 1.0).max(0.0).sqrt();
    let y = (-x * cos_theta / sin_theta).clamp(-1.0, 1.0);
    let sin_theta_sqrt_y = sin_theta * (1.0 - y * y).sqrt();
    let e =
        (cos_theta * y.acos() - x * sin_theta_sqrt_y) * sin2_sigma + (sin_theta_sqrt_y / x).atan();
    e.max(0.0)
}

/// A spherical light as cone tracing reads it (the harness maps the kinds' lights to these).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeLight {
    pub center: Vec3,
    /// Radius; 0: a point light.
    pub radius: f32,
    /// Radiance (a point light's radiant intensity): only ratios between lights matter.
    pub intensity: f32,
}

impl SdfScene {
    /// The visibility of the world cone from `o` along unit `axis`, tan of its half-angle
    /// `tan`, to `tmax`: the least over the instances, each marched in its model space (the
    /// ratio d / (t tan θ) does not change under a similarity).
    pub fn cone_visibility(
        &self,
        o: Vec3,
        axis: Vec3,
        tan: f32,
        tmax: f32,
        opts: &ConeTrace,
    ) -> f32 {
        let mut v = 1.0f32;
        for inst in &self.instances {
            let tr = &inst.transform;
            let vol = &*inst.volume;
            let range = (
                self.trace.start_voxels * vol.voxel,
                tr.to_local_distance(tmax),
            );
            let eps = self.trace.hit_voxels * vol.voxel;
            let (lo, la) = (tr.to_local_point(o), tr.to_local_dir(axis));
            v = cone_visibility(vol, lo, la, tan, range, eps, v, opts);
            if v <= 0.0 {
                return 0.0;
            }
        }
        v
    }

    /// Cone-traced ambient occlusion at `origin` (already off the surface) with unit normal
    /// `n`: the cosine-weighted mean of the cones' visibilities, each to `tmax` (the AO radius;
    /// infinite: unbounded).
    pub fn cone_ao(
        &self,
        origin: Vec3,
        n: Vec3,
        cones: &ConeSet,
        tmax: f32,
        opts: &ConeTrace,
    ) -> f32 {
        let frame = Frame::from_normal(n);
        cone_ao_mean(
            cones,
            cones.axes.iter().map(|&a| {
                let axis = frame.to_world(a).normalize();
                self.cone_visibility(origin, axis, cones.tan_half, tmax, opts)
            }),
        )
    }

    /// The cone-traced light fraction of `lights` at `origin` (already off the surface) with
    /// unit normal `n` (see the module docs); 1 where no light reaches the point.
    pub fn cone_light_fraction(
        &self,
        origin: Vec3,
        n: Vec3,
        lights: &[ConeLight],
        opts: &ConeTrace,
    ) -> f32 {
        light_fraction(lights.iter().map(|l| {
            LightCone::new(origin, n, l).map(|c| {
                let v = self.cone_visibility(origin, c.axis, c.tan, c.far, opts);
                (c.weight, v)
            })
        }))
    }
}

/// One spherical light's cone at a point (see the module docs, soft shadows).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightCone {
    /// Unit axis, from the point towards the light's centre.
    pub axis: Vec3,
    /// tan of the half-angle (0: a point light).
    pub tan: f32,
    /// Where the cone ends: the light's near side (its centre for a point light).
    pub far: f32,
    /// The light's unshadowed irradiance at the point, E_L (positive).
    pub weight: f64,
}

impl LightCone {
    /// The cone of `l` at `origin` with unit normal `n`, or none where the light does not
    /// count: the point inside it or at its centre, or no irradiance (below the horizon).
    pub fn new(origin: Vec3, n: Vec3, l: &ConeLight) -> Option<LightCone> {
        let to = l.center - origin;
        let (d2, r2) = (to.length_squared(), l.radius * l.radius);
        if d2 <= r2 || d2 == 0.0 {
            return None;
        }
        let d = d2.sqrt();
        let axis = to / d;
        let cos = n.dot(axis) as f64;
        let (weight, tan, far) = if l.radius == 0.0 {
            (l.intensity as f64 * cos.max(0.0) / d2 as f64, 0.0, d)
        } else {
            let q = (l.radius as f64).powi(2) / d2 as f64;
            let w = l.intensity as f64 * cap_irradiance(cos, q);
            (w, l.radius / (d2 - r2).sqrt(), d - l.radius)
        };
        if weight <= 0.0 {
            return None;
        }
        Some(LightCone {
            axis,
            tan,
            far,
            weight,
        })
    }
}

/// Σ E_L V_L / Σ E_L over the lights' (weight, visibility), in f64, in order (none: a light
/// that does not count); 1 where no light counts.
pub fn light_fraction(lights: impl Iterator<Item = Option<(f64, f32)>>) -> f32 {
    let (mut lit, mut total) = (0.0f64, 0.0f64);
    for (w, v) in lights.flatten() {
        total += w;
        lit += w * v as f64;
    }
    if total > 0.0 {
        (lit / total) as f32
    } else {
        1.0
    }
}

/// The cosine-weighted mean Σ cos β_i V_i / Σ cos β_i of the cones' visibilities (in the
/// order of `cones`' axes), in f32 as [`SdfScene::cone_ao`] sums them.
pub fn cone_ao_mean(cones: &ConeSet, visibility: impl Iterator<Item = f32>) -> f32 {
    let (mut sum, mut weight) = (0.0f32, 0.0f32);
    for (a, v) in cones.axes.iter().zip(visibility) {
        sum += a.z * v;
        weight += a.z;
    }
    sum / weight
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cones_tile_the_hemisphere() {
        for n in [2usize, 5, 9, 16, 64] {
            let s = ConeSet::hemisphere(n);
            assert_eq!(s.axes.len(), n);
            // Σ cos β = N/2 (the cells' centres in z), N solid angles 2π(1 − cos θ) = 2π.
            let sum: f64 = s.axes.iter().map(|a| a.z as f64).sum();
            assert!((sum - n as f64 / 2.0).abs() < 1e-5 * n as f64, "{n}: {sum}");
            let cos = 1.0 / (1.0 + (s.tan_half as f64).powi(2)).sqrt();
            assert!((n as f64 * (1.0 - cos) - 1.0).abs() < 1e-6, "{n}");
            assert!(s
                .axes
                .iter()
                .all(|a| (a.length() - 1.0).abs() < 1e-6 && a.z > 0.0));
        }
    }

    /// ∫ over the cap of (n·ω)⁺ by a midpoint rule in the cap's own polar coordinates.
    fn cap_quadrature(theta: f64, sigma: f64) -> f64 {
        let (na, nb) = (2000, 2000);
        let mut e = 0.0;
        for i in 0..na {
            let a = sigma * (i as f64 + 0.5) / na as f64;
            for j in 0..nb {
                let b = std::f64::consts::TAU * (j as f64 + 0.5) / nb as f64;
                // ω in the cap's frame, then its cosine with n (n tilted by θ about y).
                let (x, z) = (a.sin() * b.cos(), a.cos());
                let cos_n = z * theta.cos() + x * theta.sin();
                e += cos_n.max(0.0) * a.sin();
            }
        }
        e * (sigma / na as f64) * (std::f64::consts::TAU / nb as f64)
    }

    #[test]
    fn cap_irradiance_is_the_clipped_integral() {
        for &sigma in &[0.05f64, 0.3, 0.8, 1.3] {
            for &theta in &[0.0f64, 0.4, 1.2, 1.5, 1.7, 2.2, 3.0] {
                let want = cap_quadrature(theta, sigma);
                let got = cap_irradiance(theta.cos(), sigma.sin().powi(2));
                // The midpoint rule's error at 2000² cells, relative to the cap's π sin² σ.
                let tol = 1e-5 * std::f64::consts::PI * sigma.sin().powi(2);
                assert!(
                    (got - want).abs() < tol,
                    "σ {sigma} θ {theta}: {got} against {want}"
                );
            }
        }
    }
}
