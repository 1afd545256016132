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

use super::Tracer;
use crate::geometry::Similarity;
use crate::visibility::{SurfaceHit, Visibility};
use glam::Vec3;
use std::sync::Arc;

/// One node of the top level: a box over its instances; a leaf holds `count` instances from
/// `first` in [`TwoLevel::order`], an inner node its two children (`first`, `first + 1`).
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    first: u32,
    /// Instances of a leaf; 0 for an inner node.
    count: u32,
}

/// Instances of meshes, each with its own model-space BVH, under a top level over their world
/// boxes.
pub struct TwoLevel {
    /// One tracer per mesh, model space.
    meshes: Vec<Arc<Tracer>>,
    /// Per mesh, its model-space bounding sphere (centre, radius): the instance's world box.
    bounds: Vec<(Vec3, f32)>,
    /// Per instance: its mesh and transform.
    instances: Vec<(usize, Similarity)>,
    /// Instance indices in top-level order.
    order: Vec<u32>,
    nodes: Vec<Node>,
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
            order: Vec::new(),
            nodes: Vec::new(),
        }
    }

    /// Places the instances (mesh index, transform) for this frame and rebuilds the top level
    /// over their world boxes (median splits on the longest axis).
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
        self.order = (0..boxes.len() as u32).collect();
        self.nodes.clear();
        if boxes.is_empty() {
            return;
        }
        self.nodes.push(Node {
            lo: Vec3::ZERO,
            hi: Vec3::ZERO,
            first: 0,
            count: 0,
        });
        let n = boxes.len();
        self.build(0, 0, n, &boxes);
    }

    fn build(&mut self, node: usize, start: usize, end: usize, boxes: &[(Vec3, Vec3)]) {
        let (lo, hi) = self.order[start..end].iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &i| (lo.min(boxes[i as usize].0), hi.max(boxes[i as usize].1)),
        );
        if end - start <= LEAF {
            self.nodes[node] = Node {
                lo,
                hi,
                first: start as u32,
                count: (end - start) as u32,
            };
            return;
        }
        let ext = hi - lo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = (start + end) / 2;
        let centre = |i: u32| {
            let (a, b) = boxes[i as usize];
            (a + b)[axis]
        };
        self.order[start..end]
            .select_nth_unstable_by(mid - start, |&a, &b| centre(a).total_cmp(&centre(b)));
        let left = self.nodes.len();
        let empty = Node {
            lo: Vec3::ZERO,
            hi: Vec3::ZERO,
            first: 0,
            count: 0,
        };
        self.nodes.push(empty);
        self.nodes.push(empty);
        self.nodes[node] = Node {
            lo,
            hi,
            first: left as u32,
            count: 0,
        };
        self.build(left, start, mid, boxes);
        self.build(left + 1, mid, end, boxes);
    }

    /// Bytes of the top level and of every mesh's tracer.
    pub fn bytes(&self) -> u64 {
        let top = std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.order.as_slice());
        top as u64 + self.meshes.iter().map(|t| t.bytes()).sum::<u64>()
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
        if self.nodes.is_empty() {
            return;
        }
        let inv = d.recip();
        let meets = |n: &Node, tmax: f32| {
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
            let n = self.nodes[stack[top] as usize];
            if !meets(&n, tmax) {
                continue;
            }
            if n.count == 0 {
                stack[top] = n.first;
                stack[top + 1] = n.first + 1;
                top += 2;
                continue;
            }
            for &i in &self.order[n.first as usize..(n.first + n.count) as usize] {
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
