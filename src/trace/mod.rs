//! The ray-cast reference: an obvhs CWBVH over world-space triangles with watertight
//! ray–triangle tests (Woop, Benthin, Wald, "Watertight Ray/Triangle Intersection", JCGT 2013).

pub mod box_tree;
pub mod bvh_build;
#[cfg(feature = "embree")]
pub mod embree;
#[cfg(feature = "embree")]
pub mod embree_instances;
#[cfg(feature = "embree")]
mod embree_sys;
mod tracer;
pub mod two_level;
pub mod watertight;

#[cfg(test)]
pub(crate) mod test_scenes;

pub use tracer::{Hit, RayQuery, Tracer};

use glam::Vec3;

/// A closest-hit ray caster over world triangles: what a field bake traces with
/// ([`crate::field::bake::bake_with`]). [`Tracer`] is the reference; with the `embree` feature,
/// `embree::EmbreeTracer` is the second.
pub trait ClosestHit: Sync {
    /// The closest hit with `tmin <= t <= tmax`, its triangle's index and unit normal.
    fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit>;
}

impl ClosestHit for Tracer {
    #[inline]
    fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        Tracer::closest_hit(self, origin, dir, tmin, tmax)
    }
}

#[cfg(feature = "embree")]
impl ClosestHit for embree::EmbreeTracer {
    #[inline]
    fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        embree::EmbreeTracer::closest_hit(self, origin, dir, tmin, tmax)
    }
}
