//! Closest-hit and early-out any-hit queries over a CWBVH.

use glam::Vec3;

/// A closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter (the direction is unit, so a distance).
    pub t: f32,
    /// Index into the triangles the tracer was built from.
    pub triangle: u32,
    /// Barycentrics of the hit: p = (1-u-v)·v0 + u·v1 + v·v2.
    pub u: f32,
    pub v: f32,
    /// Unit geometric normal (v1-v0)×(v2-v0).
    pub normal: Vec3,
}

/// The reference tracer over a fixed set of world-space triangles.
pub struct Tracer {
    _private: (),
}

impl Tracer {
    /// Builds the BVH over `triangles`.
    pub fn new(triangles: &[[Vec3; 3]]) -> Tracer {
        let _ = triangles;
        todo!("trace helper")
    }

    /// Closest hit with t in [tmin, tmax]; `dir` unit.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        let _ = (origin, dir, tmin, tmax);
        todo!("trace helper")
    }

    /// Whether any triangle is hit with t in [tmin, tmax]; stops at the first hit found.
    pub fn any_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let _ = (origin, dir, tmin, tmax);
        todo!("trace helper")
    }
}
