//! The ray caster's CWBVH build: obvhs's PLOC (Meister, Bittner, "Parallel Locally-Ordered
//! Clustering for Bounding Volume Hierarchy Construction", IEEE TVCG 2018) followed by its
//! reinsertion optimiser, or, where PLOC would take quadratic time, a median-split tree
//! ([`super::box_tree::BoxTree`]) converted by obvhs.
//!
//! PLOC sorts the boxes by the Morton codes of their centres and, level by level, merges each
//! pair of neighbours that choose each other as the cheapest merge (the smallest union surface
//! area). Where neighbouring costs tie or rise along the order, only a few pairs agree per level
//! and a build of n boxes takes up to n levels of n work: N copies of one triangle (every cost
//! ties), N distinct triangles in one box, a row of equally spaced equal triangles (ties), N
//! triangles scaled about one centroid (costs rise along the order), a disk fan or a triangle
//! turned in small steps about one corner (boxes that all hold one point). 5,000 of the first
//! four took 1.3–2.9 s to build, 20,000 copies 18 s, a 20,000-slice fan 1.2–2.2 s, 20,000 turns
//! of 10⁻⁵ rad 19–29 s (2 shared cores). `ploc_stalls` predicts this in linear time by running
//! PLOC's clustering rule without building anything; such inputs get the median-split tree,
//! O(n log n) on any input, and every other input the PLOC build exactly as before. The check
//! adds about a sixth to a PLOC build (1 M random triangles: 0.45 s beside 2.7 s).

use super::box_tree::BoxTree;
use glam::{DVec3, Vec3};
use obvhs::{
    aabb::Aabb,
    bvh2::{node::Bvh2Node, Bvh2, DEFAULT_MAX_STACK_DEPTH},
    cwbvh::{builder::build_cwbvh, bvh2_to_cwbvh::bvh2_to_cwbvh, CwBvh},
    ploc::morton::morton_encode_u64_unorm,
    BvhBuildParams,
};
use rayon::prelude::*;
use std::time::Duration;

/// Below this many boxes a quadratic PLOC costs nothing worth avoiding.
const MIN_STALL_COUNT: usize = 256;

/// PLOC stalls where its levels hold more than this many times the boxes in all (a healthy
/// build's levels hold 2–3 times as many: each merges a third to two thirds of its nodes).
const STALL_WORK: usize = 32;

/// The CWBVH over `boxes` (a primitive per box, in order): PLOC with obvhs's `medium_build`
/// preset where `ploc_stalls` says it is near-linear, else the median-split tree. Leaves hold
/// at most 3 primitives either way.
pub fn build(boxes: &[Aabb]) -> CwBvh {
    if boxes.is_empty() {
        return CwBvh::default();
    }
    let params = BvhBuildParams::medium_build();
    if !ploc_stalls(boxes) {
        return build_cwbvh(boxes, params, &mut Duration::default());
    }
    let tree = BoxTree::new(
        &boxes
            .iter()
            .map(|b| (Vec3::from(b.min), Vec3::from(b.max)))
            .collect::<Vec<_>>(),
        1,
    );
    let bvh2 = Bvh2 {
        nodes: tree
            .nodes
            .iter()
            .map(|n| {
                let aabb = Aabb::new(n.lo.into(), n.hi.into());
                Bvh2Node::new(aabb, n.count, n.first)
            })
            .collect(),
        primitive_indices: tree.order,
        // Median splits: depth ⌈log₂ n⌉ + 1, far below the default stack.
        max_depth: DEFAULT_MAX_STACK_DEPTH,
        ..Bvh2::default()
    };
    bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false)
}

/// Whether PLOC would take quadratic time on `boxes`: obvhs's clustering is run on the boxes
/// in Morton order, level by level (each node picks the neighbour within the search distance,
/// 1 for the first 3 levels and 14 after as in `medium_build`, whose union with it has the
/// smallest surface area, a tie going to the later one; a pair merges when both pick each
/// other, into the later one's place), counting the nodes of every level, until one node is
/// left or the count passes [`STALL_WORK`] times the boxes. The run is linear in the boxes
/// after the sort (at most `STALL_WORK · n` node visits of at most 29 unions each).
pub(super) fn ploc_stalls(boxes: &[Aabb]) -> bool {
    if boxes.len() < MIN_STALL_COUNT {
        return false;
    }
    let total = boxes.iter().fold(Aabb::empty(), |t, b| t.union(b));
    // obvhs's Morton frame: the total box mapped onto the unit cube.
    let scale = 1.0
        / total
            .diagonal()
            .as_dvec3()
            .max(DVec3::splat(f64::MIN_POSITIVE));
    let offset = -total.min.as_dvec3() * scale;
    let mut codes: Vec<(u64, u32)> = boxes
        .par_iter()
        .enumerate()
        .map(|(i, b)| {
            let c = b.center().as_dvec3() * scale + offset;
            (
                morton_encode_u64_unorm(c.clamp(DVec3::ZERO, DVec3::ONE)),
                i as u32,
            )
        })
        .collect();
    codes.par_sort_unstable();
    let sorted: Vec<Aabb> = codes.par_iter().map(|&(_, i)| boxes[i as usize]).collect();
    // Distance 1 throughout first, a cheap filter that ordinary meshes pass (on every input
    // tried, a wider search found at least as many pairs); the search as obvhs runs it only to
    // confirm a stall.
    clusters_slowly(sorted.clone(), |_| 1)
        && clusters_slowly(sorted, |level| if level < 3 { 1 } else { 14 })
}

/// Whether clustering `nodes` (in Morton order), searching `distance(level)` neighbours on each
/// side at each level, passes [`STALL_WORK`] times the nodes in all its levels.
fn clusters_slowly(mut nodes: Vec<Aabb>, distance: impl Fn(usize) -> usize) -> bool {
    let limit = STALL_WORK * nodes.len();
    let mut next = Vec::with_capacity(nodes.len());
    let mut best = Vec::with_capacity(nodes.len());
    let (mut level, mut work) = (0, 0);
    while nodes.len() > 1 {
        work += nodes.len();
        if work > limit {
            return true;
        }
        let n = nodes.len();
        let cost = |i: usize, j: usize| nodes[i].union(&nodes[j]).half_area();
        let d = distance(level);
        best.clear();
        best.par_extend((0..n).into_par_iter().with_min_len(4096).map(|i| {
            let (mut b, mut b_cost) = (i, f32::INFINITY);
            for j in (i.saturating_sub(d)..(i + d + 1).min(n)).filter(|&j| j != i) {
                let c = cost(i, j);
                if c <= b_cost {
                    (b, b_cost) = (j, c);
                }
            }
            b
        }));
        next.clear();
        for (i, &b) in best.iter().enumerate() {
            if best[b] != i {
                next.push(nodes[i]);
            } else if b < i {
                next.push(nodes[i].union(&nodes[b]));
            }
        }
        std::mem::swap(&mut nodes, &mut next);
        level += 1;
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::test_scenes::{grid, icosphere, ploc_worst_cases, random_soup};
    use glam::Vec3A;

    fn boxes(tris: &[[Vec3; 3]]) -> Vec<Aabb> {
        tris.iter()
            .map(|t| {
                let t = t.map(Vec3A::from);
                Aabb::new(t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
            })
            .collect()
    }

    #[test]
    fn ordinary_meshes_keep_ploc_and_degenerate_ones_do_not() {
        for (name, tris) in [
            ("soup", random_soup(5000, 0.1, 3)),
            ("sphere", icosphere(5, 1.0, Vec3::ZERO)),
            ("grid", grid(64, 1.0)),
        ] {
            assert!(!ploc_stalls(&boxes(&tris)), "{name}");
        }
        for (name, tris) in ploc_worst_cases(5000) {
            assert!(ploc_stalls(&boxes(&tris)), "{name}");
        }
        // Too few to matter.
        assert!(!ploc_stalls(&boxes(&ploc_worst_cases(200)[0].1)));
    }
}
