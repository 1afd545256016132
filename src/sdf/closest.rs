//! Closest points on a triangle set: a median-split BVH of boxes over the triangles, searched
//! nearest box first with pruning by the box distance, and the exact closest point on one
//! triangle (C. Ericson, *Real-Time Collision Detection*, 2005, §5.1.5, `ClosestPtPointTriangle`,
//! by Voronoi regions, `geometry::closest_point_on_triangle`). The distance bake of [`super::DistanceVolume`] asks it once per grid
//! point.

use crate::geometry::closest_point_on_triangle;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// A leaf's first triangle in `order`, or an inner node's first child (the second follows).
    first: u32,
    /// Triangles of a leaf; 0 for an inner node.
    count: u32,
}

/// Triangles per leaf.
const LEAF: usize = 4;

/// The triangles under a BVH answering nearest-point queries.
pub struct ClosestPoints {
    triangles: Vec<[Vec3; 3]>,
    nodes: Vec<Node>,
}

impl ClosestPoints {
    /// Builds the tree (median splits of the centroids on the longest axis). An empty set
    /// answers every query with `None`.
    pub fn new(triangles: &[[Vec3; 3]]) -> ClosestPoints {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let centroid = |i: u32| {
            let [a, b, c] = triangles[i as usize];
            (a + b + c) / 3.0
        };
        let mut nodes = Vec::with_capacity(2 * triangles.len() / LEAF + 1);
        if !triangles.is_empty() {
            nodes.push(Node {
                lo: Vec3::ZERO,
                hi: Vec3::ZERO,
                first: 0,
                count: 0,
            });
            // (node, start, end) still to build.
            let mut todo = vec![(0usize, 0usize, triangles.len())];
            while let Some((node, start, end)) = todo.pop() {
                let (lo, hi) = order[start..end].iter().fold(
                    (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                    |(lo, hi), &i| {
                        let t = triangles[i as usize];
                        (
                            lo.min(t[0].min(t[1]).min(t[2])),
                            hi.max(t[0].max(t[1]).max(t[2])),
                        )
                    },
                );
                if end - start <= LEAF {
                    nodes[node] = Node {
                        lo,
                        hi,
                        first: start as u32,
                        count: (end - start) as u32,
                    };
                    continue;
                }
                let (clo, chi) = order[start..end].iter().fold(
                    (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                    |(lo, hi), &i| (lo.min(centroid(i)), hi.max(centroid(i))),
                );
                let axis = (chi - clo).max_position();
                let mid = (start + end) / 2;
                order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
                    centroid(a)[axis].total_cmp(&centroid(b)[axis])
                });
                let first = nodes.len();
                nodes.push(nodes[node]);
                nodes.push(nodes[node]);
                nodes[node] = Node {
                    lo,
                    hi,
                    first: first as u32,
                    count: 0,
                };
                todo.push((first, start, mid));
                todo.push((first + 1, mid, end));
            }
        }
        ClosestPoints {
            triangles: order.iter().map(|&i| triangles[i as usize]).collect(),
            nodes,
        }
    }

    /// The nearest point of any triangle to `p` and its squared distance.
    pub fn nearest(&self, p: Vec3) -> Option<(Vec3, f32)> {
        if self.nodes.is_empty() {
            return None;
        }
        let box_d2 = |n: &Node| {
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
            let n = self.nodes[i as usize];
            if n.count > 0 {
                for t in &self.triangles[n.first as usize..(n.first + n.count) as usize] {
                    let q = closest_point_on_triangle(p, t);
                    let d2 = q.distance_squared(p);
                    if d2 < best.1 {
                        best = (q, d2);
                    }
                }
                continue;
            }
            // The nearer child last, so that it is searched first.
            let (a, b) = (n.first, n.first + 1);
            let (da, db) = (
                box_d2(&self.nodes[a as usize]),
                box_d2(&self.nodes[b as usize]),
            );
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
