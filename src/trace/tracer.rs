//! Closest-hit and early-out any-hit queries over a CWBVH (Ylitie, Karras, Laine, "Efficient
//! Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", HPG 2017, as built and
//! traversed by obvhs) with watertight triangle tests.

use super::watertight::{PackedTriangle, WatertightRay};
use crate::visibility::{SurfaceHit, Visibility};
use glam::{Vec3, Vec3A};
use obvhs::{
    aabb::Aabb,
    cwbvh::CwBvh,
    ray::{Ray, RayHit},
};
use rayon::prelude::*;

/// A closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter, in units of the direction's length (a distance for unit directions).
    pub t: f32,
    /// Index into the triangles the tracer was built from.
    pub triangle: u32,
    /// Barycentrics of the hit: p = (1-u-v)·v0 + u·v1 + v·v2.
    pub u: f32,
    pub v: f32,
    /// Unit geometric normal (v1-v0)×(v2-v0), whichever side the ray came from.
    pub normal: Vec3,
}

/// One ray of a batched query: `origin + t·dir` with `tmin <= t <= tmax`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayQuery {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmin: f32,
    pub tmax: f32,
}

/// Internal working scale: the scene is scaled by a power of two (exact in floating point) so
/// that its largest extent lies in `[2^19, 2^20)`.
const WORKING_EXTENT_LOG2: i32 = 20;

/// Box padding, relative to the (scaled) scene extent: `2^-18 ≈ 3.8e-6`.
const BOX_PAD_RELATIVE: f32 = 1.0 / (1u32 << 18) as f32;

/// The reference tracer over a fixed set of world-space triangles.
///
/// Queries: a hit counts when `tmin <= t <= tmax` (both inclusive); `tmin` must be `>= 0`;
/// `origin` must be finite; `dir` must be finite and non-zero and need not be unit (then `t` is
/// in units of its length). These are checked by `debug_assert!` only (as in obvhs's
/// `Ray::new`); `tmin > tmax` or a NaN bound gives a miss.
/// Triangles hit from either side (no backface culling). Closest-hit ties (two triangles at
/// exactly the same `t`) return one of them.
///
/// Robustness: a watertight triangle test is only watertight behind a conservative box test
/// (Woop et al. 2013: "we must dynamically enlarge bounds during BVH traversal to conservatively
/// bound the triangles intersected"). obvhs's node test is a plain slab test on 8-bit quantised
/// child boxes, which are rounded outwards, but it is not conservative by itself: the slab
/// distances are rounded, a direction component with `|d| <= f32::EPSILON` is replaced by
/// `±f32::EPSILON` (`safe_inverse`), boxes are flat for axis-aligned triangles, and the box
/// interval starts at a fixed absolute `t = 1e-4` instead of `tmin`. A ray through a shared
/// edge or vertex that lies on a child box face can then lose the box holding the one triangle
/// the watertight test reports (the tests find such a ray on an axis-aligned grid). Deviation
/// from the paper: instead of enlarging the bounds during traversal, two changes around plain
/// obvhs make it conservative:
/// - every triangle box is padded by `2^-18` of the scene extent before the build, which
///   exceeds the slab rounding error (a few ulps of the origin-to-box distance) for origins
///   within about 10 scene extents of the scene and rays shorter than about 30 extents, and
///   exceeds the `safe_inverse` drift over such lengths;
/// - the scene (and each ray origin and t range) is scaled internally by a power of two, which
///   is exact and leaves every watertight result bit-identical, so that the scene extent is
///   about `2^20`: obvhs's absolute `1e-4` box start becomes `≈ 1e-10` of the scene extent,
///   far below the offsets renderers use (see [`crate::render::ao::scene_epsilon`]).
///
/// With both, the BVH returns exactly what a brute-force loop of the watertight test over all
/// triangles returns (tested on rays exactly through grid vertices and edges).
pub struct Tracer {
    bvh: CwBvh,
    /// Triangles in BVH order (`bvh.primitive_indices`), scaled by `scale`.
    triangles: Vec<PackedTriangle>,
    /// Original index of each BVH-ordered triangle.
    original_index: Vec<u32>,
    /// Power of two applied to positions internally, and its inverse.
    scale: f32,
    inv_scale: f32,
}

/// `2^k` for `k` in the normal exponent range.
fn pow2(k: i32) -> f32 {
    f32::from_bits(((k.clamp(-126, 127) + 127) as u32) << 23)
}

impl Tracer {
    /// Builds the BVH over `triangles` (obvhs PLOC + reinsertion, `medium_build` preset,
    /// collapsed to a CWBVH; a median-split tree where PLOC would take quadratic time, see
    /// [`super::bvh_build`]). An empty list gives a tracer that always misses.
    ///
    /// # Panics
    /// If a vertex is not finite.
    pub fn new(triangles: &[[Vec3; 3]]) -> Tracer {
        assert!(
            triangles.iter().flatten().all(|v| v.is_finite()),
            "Tracer::new: triangle vertices must be finite"
        );
        let (lo, hi) = triangles.iter().flatten().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        let extent = (hi - lo).max_element();
        let max_abs = lo.abs().max(hi.abs()).max_element();
        let scale = if extent > 0.0 && extent.is_finite() {
            // Largest extent into [2^19, 2^20), keeping coordinates below 2^100.
            let k = (WORKING_EXTENT_LOG2 - 1 - extent.log2().floor() as i32)
                .min(100 - max_abs.log2().ceil() as i32);
            pow2(k)
        } else {
            1.0
        };
        let scaled: Vec<[Vec3A; 3]> = triangles
            .iter()
            .map(|t| t.map(|v| Vec3A::from(v) * scale))
            .collect();
        let pad = Vec3A::splat(BOX_PAD_RELATIVE * extent * scale);
        let boxes: Vec<Aabb> = scaled
            .iter()
            .map(|t| {
                let lo = t[0].min(t[1]).min(t[2]);
                let hi = t[0].max(t[1]).max(t[2]);
                Aabb::new(lo - pad, hi + pad)
            })
            .collect();
        let bvh = super::bvh_build::build(&boxes);
        // Without spatial splits the primitive indices are a permutation of 0..n.
        let original_index = bvh.primitive_indices.clone();
        debug_assert_eq!(original_index.len(), triangles.len());
        let triangles = original_index
            .iter()
            .map(|&i| {
                let [v0, v1, v2] = scaled[i as usize];
                PackedTriangle::new(v0, v1, v2)
            })
            .collect();
        Tracer {
            bvh,
            triangles,
            original_index,
            scale,
            inv_scale: 1.0 / scale,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Bytes of what a query reads: the CWBVH's nodes and primitive indices, the packed
    /// triangles and their original indices (the vectors' lengths, not their capacities).
    pub fn bytes(&self) -> u64 {
        use std::mem::size_of_val;
        (size_of_val(self.bvh.nodes.as_slice())
            + size_of_val(self.bvh.primitive_indices.as_slice())
            + size_of_val(self.triangles.as_slice())
            + size_of_val(self.original_index.as_slice())) as u64
    }

    /// The obvhs ray (scaled) and the watertight ray, or `None` when nothing can be hit.
    #[inline]
    fn prepare(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> Option<(Ray, WatertightRay, f32, f32)> {
        debug_assert!(
            tmin.is_nan() || tmin >= 0.0,
            "tmin must be >= 0, got {tmin}"
        );
        if self.triangles.is_empty() || tmin.is_nan() || tmax.is_nan() || tmin > tmax {
            return None;
        }
        let o = Vec3A::from(origin) * self.scale;
        // −0 folded into +0: obvhs takes a ray's octant from `d < 0` (+ for −0) but its inverse
        // from the sign (−1/ε for −0), and a ray with a −0 component missed everything.
        let d = Vec3A::from(dir) + Vec3A::ZERO;
        let (tmin_s, tmax_s) = (tmin * self.scale, tmax * self.scale);
        // obvhs accepts hits with t < ray.tmax; one ulp more makes tmax inclusive (the
        // watertight test itself enforces [tmin, tmax]).
        let ray = Ray::new(o, d, tmin_s, tmax_s.next_up());
        Some((ray, WatertightRay::new(o, d), tmin_s, tmax_s))
    }

    /// Closest hit with `tmin <= t <= tmax`.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        let (ray, wray, tmin_s, tmax_s) = self.prepare(origin, dir, tmin, tmax)?;
        let mut best = None;
        let mut ray_hit = RayHit::none();
        self.bvh.ray_traverse(ray, &mut ray_hit, |r, id| {
            match wray.intersect_packed(&self.triangles[id], tmin_s, tmax_s) {
                // obvhs keeps the hit only if t < its current tmax: mirror that here.
                Some(h) if h.t < r.tmax => {
                    best = Some((id, h));
                    h.t
                }
                _ => f32::INFINITY,
            }
        });
        best.map(|(id, h)| {
            let [v0, v1, v2] = self.triangles[id].vertices();
            Hit {
                t: h.t * self.inv_scale,
                triangle: self.original_index[id],
                u: h.u,
                v: h.v,
                normal: Vec3::from((v1 - v0).cross(v2 - v0).normalize()),
            }
        })
    }

    /// Whether any triangle is hit with `tmin <= t <= tmax`; stops at the first hit found.
    pub fn any_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let Some((ray, wray, tmin_s, tmax_s)) = self.prepare(origin, dir, tmin, tmax) else {
            return false;
        };
        !self.bvh.ray_traverse_miss(ray, |_, id| {
            match wray.intersect_packed(&self.triangles[id], tmin_s, tmax_s) {
                Some(_) => f32::NEG_INFINITY, // below any tmax: ends the traversal
                None => f32::INFINITY,
            }
        })
    }

    /// [`Tracer::closest_hit`] for each ray, in parallel (rayon); output in input order.
    pub fn closest_hits(&self, rays: &[RayQuery]) -> Vec<Option<Hit>> {
        rays.par_iter()
            .with_min_len(64)
            .map(|r| self.closest_hit(r.origin, r.dir, r.tmin, r.tmax))
            .collect()
    }

    /// [`Tracer::any_hit`] for each ray, in parallel (rayon); output in input order.
    pub fn any_hits(&self, rays: &[RayQuery]) -> Vec<bool> {
        rays.par_iter()
            .with_min_len(64)
            .map(|r| self.any_hit(r.origin, r.dir, r.tmin, r.tmax))
            .collect()
    }
}

/// The ray-cast backend: exact watertight ray casting against the scene's triangles.
impl Visibility for Tracer {
    #[inline]
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.any_hit(origin, dir, tmin, tmax)
    }

    #[inline]
    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        self.closest_hit(origin, dir, tmin, tmax).map(|h| h.t)
    }

    #[inline]
    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        self.closest_hit(origin, dir, tmin, tmax)
            .map(|h| SurfaceHit {
                t: h.t,
                normal: h.normal,
            })
    }
}

#[cfg(test)]
#[path = "tracer_tests.rs"]
mod tests;
