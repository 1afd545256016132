//! Two-level ray casting for rigid instances: one [`Tracer`] per mesh in model space, built
//! once, and a top level over the instances' world bounds rebuilt every frame
//! ([`TwoLevel::update`]); a ray meets the top level, then each instance it may hit in that
//! instance's model space (the similarity's inverse: rotation, translation, and distances
//! divided by the scale). This is how engines cast rays in scenes of moving rigid objects (a
//! TLAS over BLASes): what motion costs is the top level's rebuild, not the triangles'.
//!
//! Its answers equal the world-space tracer's up to the rounding of moving the ray instead of
//! the triangles (f32): the same hits and misses away from edges and grazing rays, distances
//! within a few ulps of the world's (tested on moving scenes in `tests/two_level.rs`).

use super::box_tree::{BoxNode, BoxTree};
use super::Tracer;
use crate::geometry::Similarity;
use crate::visibility::{SurfaceHit, Visibility};
use glam::Vec3;
use std::sync::Arc;

/// Instances of meshes, each with its own model-space BVH, under a top level over their world
/// boxes.
pub struct TwoLevel {
    /// One tracer per mesh, model space.
    meshes: Vec<Arc<Tracer>>,
    /// Per mesh, its model-space bounding sphere (centre, radius): the instance's world box.
    bounds: Vec<(Vec3, f32)>,
    /// Per instance: its mesh and transform.
    instances: Vec<(usize, Similarity)>,
    /// The top level over the instances' world boxes.
    top: BoxTree,
}

/// Instances per top-level leaf.
const LEAF: usize = 2;

impl TwoLevel {
    /// Builds each mesh's tracer (model-space triangles); no instance yet.
    pub fn new(meshes: &[Vec<[Vec3; 3]>]) -> TwoLevel {
        let bounds = meshes
            .iter()
            .map(|tris| {
                let (lo, hi) = tris.iter().flatten().fold(
                    (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                    |(lo, hi), &v| (lo.min(v), hi.max(v)),
                );
                let c = 0.5 * (lo + hi);
                let r = tris
                    .iter()
                    .flatten()
                    .map(|v| v.distance(c))
                    .fold(0.0f32, f32::max);
                (c, r)
            })
            .collect();
        TwoLevel {
            meshes: meshes.iter().map(|t| Arc::new(Tracer::new(t))).collect(),
            bounds,
            instances: Vec::new(),
            top: BoxTree::default(),
        }
    }

    /// Places the instances (mesh index, transform) for this frame and rebuilds the top level
    /// over their world boxes ([`BoxTree`]).
    ///
    /// # Panics
    /// If an instance names a mesh that does not exist.
    pub fn update(&mut self, instances: &[(usize, Similarity)]) {
        self.instances = instances.to_vec();
        let boxes: Vec<(Vec3, Vec3)> = self
            .instances
            .iter()
            .map(|&(m, t)| {
                let (c, r) = self.bounds[m];
                let wc = t.to_world_point(c);
                // One ulp-scale pad so the box holds the triangles' rounded world positions.
                let wr = t.scale * r * (1.0 + 1e-5) + 1e-6 * wc.abs().max_element();
                (wc - Vec3::splat(wr), wc + Vec3::splat(wr))
            })
            .collect();
        self.top = BoxTree::new(&boxes, LEAF);
    }

    /// Bytes of the top level and of every mesh's tracer.
    pub fn bytes(&self) -> u64 {
        self.top.bytes() + self.meshes.iter().map(|t| t.bytes()).sum::<u64>()
    }

    /// Calls `f(instance)` for each instance whose top-level box the segment meets, in no
    /// particular order, until `f` returns false (`tmax` may shrink through `f`'s result:
    /// `f` returns the segment's new end).
    fn walk(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        mut tmax: f32,
        mut f: impl FnMut(usize, f32) -> Option<f32>,
    ) {
        if self.top.nodes.is_empty() {
            return;
        }
        let inv = d.recip();
        let meets = |n: &BoxNode, tmax: f32| {
            let t0 = (n.lo - o) * inv;
            let t1 = (n.hi - o) * inv;
            let near = t0.min(t1).max_element().max(tmin);
            let far = t0.max(t1).min_element().min(tmax);
            // NaN (a zero direction component on a slab's plane) keeps the node.
            near.partial_cmp(&far) != Some(std::cmp::Ordering::Greater)
        };
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = self.top.nodes[stack[top] as usize];
            if !meets(&n, tmax) {
                continue;
            }
            let Some(items) = n.items() else {
                [stack[top], stack[top + 1]] = n.children();
                top += 2;
                continue;
            };
            for &i in &self.top.order[items] {
                match f(i as usize, tmax) {
                    Some(t) => tmax = t,
                    None => return,
                }
            }
        }
    }

    /// The ray in instance `i`'s model space: origin, unit direction, and the factor from world
    /// to model distances.
    #[inline]
    fn local(&self, i: usize, o: Vec3, d: Vec3) -> (Vec3, Vec3, f32) {
        let t = &self.instances[i].1;
        (t.to_local_point(o), t.to_local_dir(d), 1.0 / t.scale)
    }
}

impl Visibility for TwoLevel {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let mut hit = false;
        self.walk(origin, dir, tmin, tmax, |i, tmax| {
            let (o, d, k) = self.local(i, origin, dir);
            if self.meshes[self.instances[i].0].any_hit(o, d, tmin * k, tmax * k) {
                hit = true;
                None
            } else {
                Some(tmax)
            }
        });
        hit
    }

    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        self.surface_hit(origin, dir, tmin, tmax).map(|h| h.t)
    }

    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        let mut best: Option<SurfaceHit> = None;
        self.walk(origin, dir, tmin, tmax, |i, tmax| {
            let (o, d, k) = self.local(i, origin, dir);
            let (m, t) = self.instances[i];
            if let Some(h) = self.meshes[m].closest_hit(o, d, tmin * k, tmax * k) {
                let world_t = (h.t / k).min(tmax);
                best = Some(SurfaceHit {
                    t: world_t,
                    normal: t.to_world_dir(h.normal),
                });
                return Some(world_t);
            }
            Some(tmax)
        });
        best
    }
}
