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

impl FieldScene {
    /// Calls `f` on the instances whose world spheres the segment meets, in order of entry
    /// distance, until it returns `false`. No allocation for up to 16 instances.
    fn for_each_candidate(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        mut f: impl FnMut(f32, &FieldInstance) -> bool,
    ) {
        if let [only] = self.instances.as_slice() {
            // One instance: its own lookup does the sphere test.
            f(tmin, only);
            return;
        }
        let mut stack = [(0.0f32, 0usize); 16];
        let mut heap = Vec::new();
        let mut n = 0;
        for (i, inst) in self.instances.iter().enumerate() {
            if let Some((t0, t1)) = ray_sphere(origin, dir, inst.world_center, inst.world_radius) {
                if t1 >= tmin && t0 <= tmax {
                    if n < stack.len() {
                        stack[n] = (t0.max(tmin), i);
                    } else {
                        if heap.is_empty() {
                            heap.extend_from_slice(&stack);
                        }
                        heap.push((t0.max(tmin), i));
                    }
                    n += 1;
                }
            }
        }
        let order = if heap.is_empty() {
            &mut stack[..n]
        } else {
            &mut heap[..]
        };
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(t, i) in order.iter() {
            if !f(t, &self.instances[i]) {
                return;
            }
        }
    }
}

impl Visibility for FieldScene {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let mut hit = false;
        self.for_each_candidate(origin, dir, tmin, tmax, |_, inst| {
            hit = inst
                .hit_distance(origin, dir, tmin, tmax, &self.options)
                .is_some();
            !hit
        });
        hit
    }

    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        // Spheres may overlap, so a later entry can still hold a nearer surface: keep the
        // nearest hit, stopping once no remaining sphere starts before it.
        let mut best: Option<f32> = None;
        self.for_each_candidate(origin, dir, tmin, tmax, |t_entry, inst| {
            if best.is_some_and(|b| t_entry > b) {
                return false;
            }
            let limit = best.unwrap_or(tmax);
            if let Some(t) = inst.hit_distance(origin, dir, tmin, limit, &self.options) {
                best = Some(best.map_or(t, |b| b.min(t)));
            }
            true
        });
        best
    }
}
