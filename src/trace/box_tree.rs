//! A binary tree of boxes over items, built by median splits: the top level of the two-level
//! tracer ([`super::two_level`], over the instances' world boxes) and the SDF bake's
//! closest-point search (`sdf::closest`, over the triangles). Each node's box holds its items'
//! boxes; a node of more than `leaf` items is split at the median of its items' box centres
//! along the longest axis of its own box (ties: x before y before z), the left half first.

use glam::Vec3;
use std::ops::Range;

/// One node: a box over its items; a leaf holds `count` items from `first` in
/// [`BoxTree::order`], an inner node its two children (`first`, `first + 1`).
#[derive(Clone, Copy, Debug)]
pub struct BoxNode {
    pub lo: Vec3,
    pub hi: Vec3,
    pub first: u32,
    /// Items of a leaf; 0 for an inner node.
    pub count: u32,
}

impl BoxNode {
    /// A leaf's range of [`BoxTree::order`]; none for an inner node.
    #[inline]
    pub fn items(&self) -> Option<Range<usize>> {
        (self.count > 0).then(|| self.first as usize..(self.first + self.count) as usize)
    }

    /// An inner node's children.
    #[inline]
    pub fn children(&self) -> [u32; 2] {
        [self.first, self.first + 1]
    }
}

/// The tree: its nodes (the root first) and the items in leaf order.
#[derive(Clone, Debug, Default)]
pub struct BoxTree {
    pub nodes: Vec<BoxNode>,
    pub order: Vec<u32>,
}

impl BoxTree {
    /// The tree over `boxes` (lo, hi per item), at most `leaf` items per leaf. No items, no
    /// nodes.
    ///
    /// # Panics
    /// If `leaf` is 0.
    pub fn new(boxes: &[(Vec3, Vec3)], leaf: usize) -> BoxTree {
        assert!(leaf > 0, "BoxTree::new: a leaf holds at least one item");
        let mut tree = BoxTree {
            nodes: Vec::with_capacity(2 * boxes.len().div_ceil(leaf)),
            order: (0..boxes.len() as u32).collect(),
        };
        if boxes.is_empty() {
            return tree;
        }
        let empty = BoxNode {
            lo: Vec3::ZERO,
            hi: Vec3::ZERO,
            first: 0,
            count: 0,
        };
        tree.nodes.push(empty);
        // (node, start, end) still to build, the left child popped first (pre-order).
        let mut todo = vec![(0usize, 0usize, boxes.len())];
        while let Some((node, start, end)) = todo.pop() {
            let (lo, hi) = tree.order[start..end].iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), &i| (lo.min(boxes[i as usize].0), hi.max(boxes[i as usize].1)),
            );
            if end - start <= leaf {
                tree.nodes[node] = BoxNode {
                    lo,
                    hi,
                    first: start as u32,
                    count: (end - start) as u32,
                };
                continue;
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
            tree.order[start..end]
                .select_nth_unstable_by(mid - start, |&a, &b| centre(a).total_cmp(&centre(b)));
            let left = tree.nodes.len();
            tree.nodes.push(empty);
            tree.nodes.push(empty);
            tree.nodes[node] = BoxNode {
                lo,
                hi,
                first: left as u32,
                count: 0,
            };
            todo.push((left + 1, mid, end));
            todo.push((left, start, mid));
        }
        tree
    }

    /// Bytes of the nodes and the order.
    pub fn bytes(&self) -> u64 {
        (std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.order.as_slice())) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_item_sits_in_one_leaf_inside_every_box_above_it() {
        let boxes: Vec<(Vec3, Vec3)> = (0..37)
            .map(|i| {
                let c = Vec3::new((i * 7 % 11) as f32, (i * 3 % 5) as f32, (i % 4) as f32);
                (c, c + Vec3::splat(0.5 + (i % 3) as f32))
            })
            .collect();
        let tree = BoxTree::new(&boxes, 2);
        let mut seen = vec![0; boxes.len()];
        // Walk down, checking that each node's box holds its items' boxes.
        let mut stack = vec![(0u32, Vec::<u32>::new())];
        while let Some((n, path)) = stack.pop() {
            let node = tree.nodes[n as usize];
            let mut path = path.clone();
            path.push(n);
            match node.items() {
                Some(r) => {
                    assert!(r.len() <= 2);
                    for &i in &tree.order[r] {
                        seen[i as usize] += 1;
                        for &a in &path {
                            let b = tree.nodes[a as usize];
                            let (lo, hi) = boxes[i as usize];
                            assert!(lo.cmpge(b.lo).all() && hi.cmple(b.hi).all());
                        }
                    }
                }
                None => stack.extend(node.children().map(|c| (c, path.clone()))),
            }
        }
        assert!(seen.iter().all(|&s| s == 1), "{seen:?}");
        assert!(BoxTree::new(&[], 4).nodes.is_empty());
    }
}
