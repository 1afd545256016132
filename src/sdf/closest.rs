//! Closest points on a triangle set: a median-split BVH of boxes over the triangles
//! (`trace::box_tree`), searched nearest box first with pruning by the box distance, and the
//! exact closest point on one triangle (C. Ericson, *Real-Time Collision Detection*, 2005,
//! §5.1.5, by Voronoi regions: `geometry::closest_point_on_triangle`). The distance bake of
//! [`super::DistanceVolume`] asks it once per grid point.

use crate::geometry::closest_point_on_triangle;
use crate::trace::box_tree::{BoxNode, BoxTree};
use glam::Vec3;

/// Triangles per leaf.
const LEAF: usize = 4;

/// The triangles under a BVH answering nearest-point queries.
pub struct ClosestPoints {
    /// The triangles in leaf order.
    triangles: Vec<[Vec3; 3]>,
    tree: BoxTree,
}

impl ClosestPoints {
    /// Builds the tree over the triangles' boxes ([`BoxTree`]). An empty set answers every
    /// query with `None`.
    pub fn new(triangles: &[[Vec3; 3]]) -> ClosestPoints {
        let boxes: Vec<(Vec3, Vec3)> = triangles
            .iter()
            .map(|t| (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2])))
            .collect();
        let tree = BoxTree::new(&boxes, LEAF);
        ClosestPoints {
            triangles: tree.order.iter().map(|&i| triangles[i as usize]).collect(),
            tree,
        }
    }

    /// The nearest point of any triangle to `p` and its squared distance.
    pub fn nearest(&self, p: Vec3) -> Option<(Vec3, f32)> {
        let nodes = &self.tree.nodes;
        if nodes.is_empty() {
            return None;
        }
        let box_d2 = |n: &BoxNode| {
            let d = (n.lo - p).max(p - n.hi).max(Vec3::ZERO);
            d.length_squared()
        };
        let mut best = (Vec3::ZERO, f32::INFINITY);
        let mut stack = [(0u32, 0.0f32); 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (i, d2) = stack[top];
            if d2 >= best.1 {
                continue;
            }
            let n = nodes[i as usize];
            if let Some(items) = n.items() {
                for t in &self.triangles[items] {
                    let q = closest_point_on_triangle(p, t);
                    let d2 = q.distance_squared(p);
                    if d2 < best.1 {
                        best = (q, d2);
                    }
                }
                continue;
            }
            // The nearer child last, so that it is searched first.
            let [a, b] = n.children();
            let (da, db) = (box_d2(&nodes[a as usize]), box_d2(&nodes[b as usize]));
            let (near, far) = if da <= db {
                ((a, da), (b, db))
            } else {
                ((b, db), (a, da))
            };
            stack[top] = far;
            stack[top + 1] = near;
            top += 2;
        }
        Some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tree_finds_what_a_scan_finds() {
        let mesh = crate::geometry::procedural::uv_sphere(1.0, 12, 24).unwrap();
        let tris: Vec<[Vec3; 3]> = (0..mesh.triangle_count())
            .map(|i| mesh.triangle(i))
            .collect();
        let cp = ClosestPoints::new(&tris);
        for k in 0..500u64 {
            let p = crate::sampling::rays::seeded_sphere_direction(k, 3)
                * (0.1 + (k % 30) as f32 * 0.1);
            let scan = tris
                .iter()
                .map(|t| closest_point_on_triangle(p, t).distance_squared(p))
                .fold(f32::INFINITY, f32::min);
            let (_, d2) = cp.nearest(p).unwrap();
            assert_eq!(d2, scan, "{p}");
        }
        assert!(ClosestPoints::new(&[]).nearest(Vec3::ZERO).is_none());
    }
}
