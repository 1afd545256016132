//! Field lookup: 2008 Algorithm 2 (inter-object) and the 2010 intra-object test (Figure 2).
//!
//! All queries here are in the field's model space with a unit direction.
//!
//! - **Outside** the bounding sphere (inter-object): the ray enters the sphere at q (t_entry); the
//!   map of the positional sample nearest to q is read in the texel of the ray's direction in that
//!   map's inward frame; the approximate hit lies at t_entry + 2R·D.
//! - **Inside** the sphere (intra-object, and receivers inside a caster's sphere): the ray leaves
//!   the sphere at p1 (t_exit = d1); the map at p1 is read in direction p1→p0 (−d), giving d2 = 2R·D,
//!   the distance from p1 back to the surface nearest p1. The origin is occluded when d1 > d2, i.e.
//!   a surface lies between the origin and p1, at distance d1 − d2 from the origin.
//!   Deviation from the paper: the test is d1 − d2 > tmin + bias, with `bias` (default 1% of 2R)
//!   absorbing the discretisation error of the self-hit for origins on the object; the paper gives
//!   no tolerance. For origins inside the sphere the hit found is the one nearest p1, not the
//!   nearest to the origin, which matters only for distance-limited queries.

use super::{Selection, VisibilityField};
use crate::sampling::{HemisphereLayout, LayoutKind};
use glam::{DVec3, Vec2, Vec3};

/// Near and far roots of a unit-direction ray against a sphere, or `None` if it misses.
///
/// Follows Haines et al., "Precision Improvements for Ray/Sphere Intersection" (Ray Tracing
/// Gems, ch. 7): the discriminant from the perpendicular offset and the roots from the stable
/// quadratic form, computed in f64 so that origins far from the sphere (1e6 R) keep the entry
/// point accurate to far below 1e-5 R.
#[inline]
pub fn ray_sphere(origin: Vec3, dir: Vec3, center: Vec3, radius: f32) -> Option<(f32, f32)> {
    let f = origin.as_dvec3() - center.as_dvec3();
    let d = dir.as_dvec3();
    let r = radius as f64;
    let b = -f.dot(d);
    let l = f + b * d; // component of f perpendicular to d
    let ll = l.length();
    let disc = (r - ll) * (r + ll);
    if disc < 0.0 {
        return None;
    }
    let c = f.length_squared() - r * r;
    let s = disc.sqrt();
    let q = if b >= 0.0 { b + s } else { b - s };
    let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q) };
    let (t0, t1) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
    Some((t0 as f32, t1 as f32))
}

/// Entry point of a ray on a sphere, relative to the centre, in f64: l − sqrt(disc)·d, exact up
/// to rounding of the inputs (no cancellation against a far origin).
pub fn entry_point_relative(origin: Vec3, dir: Vec3, center: Vec3, radius: f32) -> Option<DVec3> {
    let f = origin.as_dvec3() - center.as_dvec3();
    let d = dir.as_dvec3();
    let r = radius as f64;
    let l = f - f.dot(d) * d;
    let ll = l.length();
    let disc = (r - ll) * (r + ll);
    (disc >= 0.0).then(|| l - disc.sqrt() * d)
}

/// Options of a lookup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookupOptions {
    pub selection: Selection,
    /// Tolerance of the intra-object test, as a fraction of 2R.
    pub intra_bias: f32,
}

impl Default for LookupOptions {
    fn default() -> Self {
        LookupOptions {
            selection: Selection::Nearest,
            intra_bias: 0.01,
        }
    }
}

impl VisibilityField {
    /// Normalised distance D stored for a ray crossing the sphere at unit position `u` (relative
    /// to the centre) with model-space direction `dir` pointing into the sphere.
    #[inline]
    pub fn sample(&self, u: Vec3, dir: Vec3, selection: Selection) -> f32 {
        match selection {
            Selection::Nearest => {
                let m = self.points.nearest(u);
                let local = self.frames[m].to_local(dir);
                self.storage.get(m, self.layout.to_texel(local) as usize)
            }
            Selection::Interpolated => self.sample_interpolated(u, dir),
        }
    }

    /// Beyond the paper: blends the three maps around `u` with barycentric weights and each map's
    /// four texels around the direction bilinearly. Hits and misses are blended as an occupancy:
    /// the ray hits when the weighted share of hitting samples is at least one half, at the
    /// weighted mean distance of the hitting samples (averaging a miss's 1 into a hit distance
    /// would invent surfaces).
    pub fn sample_interpolated(&self, u: Vec3, dir: Vec3) -> f32 {
        let (maps, weights) = self.points.surrounding(u);
        let (mut occ, mut dist) = (0.0f32, 0.0f32);
        for (&m, &w) in maps.iter().zip(&weights) {
            if w <= 0.0 {
                continue;
            }
            let local = self.frames[m].to_local(dir);
            let (texels, n) = bilinear_texels(&self.layout, local);
            for &(t, tw) in &texels[..n] {
                let d = self.storage.get(m, t as usize);
                if d < 1.0 {
                    occ += w * tw;
                    dist += w * tw * d;
                }
            }
        }
        if occ >= 0.5 {
            dist / occ
        } else {
            1.0
        }
    }

    /// Distance from `origin` to the approximate surface along unit `dir`, if it lies within
    /// [tmin, tmax] (model space).
    pub fn hit_distance(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        opts: &LookupOptions,
    ) -> Option<f32> {
        let c = self.bounds.center;
        let r = self.bounds.radius;
        let (t0, t1) = ray_sphere(origin, dir, c, r)?;
        let diameter = 2.0 * r;
        if t1 < tmin {
            return None; // sphere behind the ray
        }
        if t0 >= 0.0 {
            // Outside (or on) the sphere: inter-object lookup.
            if t0 > tmax {
                return None;
            }
            let u = entry_point_relative(origin, dir, c, r)?;
            let u = (u / r as f64).as_vec3();
            let d = self.sample(u, dir, opts.selection);
            if d >= 1.0 {
                return None;
            }
            let t = t0 + diameter * d;
            (t >= tmin && t <= tmax).then_some(t)
        } else {
            // Inside: intra-object test from the exit point back towards the origin.
            let p1 = (origin - c) + t1 * dir;
            let u = p1.normalize_or_zero();
            let d = self.sample(u, -dir, opts.selection);
            if d >= 1.0 {
                return None;
            }
            let t = t1 - diameter * d;
            (t > tmin + opts.intra_bias * diameter && t <= tmax).then_some(t)
        }
    }
}

/// The (up to) four texels around a local direction and their bilinear weights (summing to 1).
/// Polar maps wrap in φ (columns); other edges clamp; unused texels (rejection rim) are skipped
/// and the remaining weights renormalised.
fn bilinear_texels(layout: &HemisphereLayout, local: Vec3) -> ([(u32, f32); 4], usize) {
    let res = layout.res as i64;
    let p = layout.to_texel_continuous(local) - Vec2::splat(0.5);
    let (c0, r0) = (p.x.floor() as i64, p.y.floor() as i64);
    let (fx, fy) = (p.x - c0 as f32, p.y - r0 as f32);
    let wrap = layout.kind == LayoutKind::Polar;
    let col = |c: i64| {
        if wrap {
            c.rem_euclid(res)
        } else {
            c.clamp(0, res - 1)
        }
    };
    let row = |r: i64| r.clamp(0, res - 1);
    let mut out = [(0u32, 0.0f32); 4];
    let mut n = 0;
    let mut total = 0.0;
    for (dc, dr, w) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        let t = (row(r0 + dr) * res + col(c0 + dc)) as u32;
        if w > 0.0 && layout.is_used(t) {
            out[n] = (t, w);
            n += 1;
            total += w;
        }
    }
    if n == 0 {
        return (
            [(layout.to_texel(local), 1.0), (0, 0.0), (0, 0.0), (0, 0.0)],
            1,
        );
    }
    for o in &mut out[..n] {
        o.1 /= total;
    }
    (out, n)
}
