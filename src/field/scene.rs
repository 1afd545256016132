//! Several instanced fields answering one [`Visibility`] query (2008 Algorithm 2 over all
//! occluders; 2010 §3.2).

use super::lookup::{ray_sphere, LookupOptions};
use super::VisibilityField;
use crate::geometry::Similarity;
use crate::render::Visibility;
use glam::Vec3;
use std::sync::Arc;

/// A field placed in the world by a rigid transform (the same field serves every instance).
#[derive(Clone, Debug)]
pub struct FieldInstance {
    pub field: Arc<VisibilityField>,
    pub transform: Similarity,
    /// World-space bounding sphere (centre transformed, radius scaled).
    pub world_center: Vec3,
    pub world_radius: f32,
}

impl FieldInstance {
    pub fn new(field: Arc<VisibilityField>, transform: Similarity) -> Self {
        let world = transform.to_world_sphere(&field.bounds);
        FieldInstance {
            field,
            transform,
            world_center: world.center,
            world_radius: world.radius,
        }
    }

    /// World-space hit distance through this instance's field.
    pub fn hit_distance(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        opts: &LookupOptions,
    ) -> Option<f32> {
        let tr = &self.transform;
        let o = tr.to_local_point(origin);
        let d = tr.to_local_dir(dir).normalize();
        self.field
            .hit_distance(
                o,
                d,
                tr.to_local_distance(tmin),
                tr.to_local_distance(tmax),
                opts,
            )
            .map(|t| t * tr.scale)
    }
}

/// Every caster's field; a ray tests the instances whose spheres it meets, nearest entry first,
/// and stops at the first occlusion.
#[derive(Clone, Debug, Default)]
pub struct FieldScene {
    pub instances: Vec<FieldInstance>,
    pub options: LookupOptions,
}

impl Visibility for FieldScene {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let mut order: Vec<(f32, usize)> = Vec::with_capacity(self.instances.len());
        for (i, inst) in self.instances.iter().enumerate() {
            if let Some((t0, t1)) = ray_sphere(origin, dir, inst.world_center, inst.world_radius) {
                if t1 >= tmin && t0 <= tmax {
                    order.push((t0.max(tmin), i));
                }
            }
        }
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        order.iter().any(|&(_, i)| {
            self.instances[i]
                .hit_distance(origin, dir, tmin, tmax, &self.options)
                .is_some()
        })
    }
}
