//! A BVH over the instances' bounding spheres, so that a ray in a scene of many casters tests
//! the spheres near it instead of every sphere ([`SphereBvhScene`]).
//!
//! The 2008 paper's Algorithm 2 loops over every occluder's bounding sphere per ray, and so does
//! [`FieldScene`]; with a crowd of hundreds of moving casters that loop, not the lookups,
//! dominates a frame. Deviation from the paper: a binary tree of bounding spheres over the
//! instances, rebuilt whenever the instances move ([`SphereBvhScene::new`], linear in their
//! number after a sort per level, no triangle touched), is traversed first; the instances at its
//! leaves then run the same tests and lookups as in [`FieldScene`].
//!
//! Answers are bit-identical to [`FieldScene`]'s on every ray: a node's test is conservative
//! (its reach covers each instance's [`FieldInstance::may_meet`] reach plus the distance
//! between the centres, padded beyond the f32 rounding of either test), so every instance the
//! plain scene would consider is still considered, and whether a ray is occluded, or its
//! nearest hit, does not depend on the order the instances are tried in. Tested against
//! [`FieldScene`] on crowds in `tests/sphere_bvh.rs`.

use super::lanes::{Isa, MayMeetFrom};
use super::scene::{FieldInstance, FieldScene, MAY_MEET_SLACK};
use crate::visibility::{SurfaceHit, Visibility};
use glam::Vec3;

/// Instances per leaf.
const LEAF: usize = 2;

/// One node: a sphere holding its instances' spheres (with their rounding margins); a leaf holds
/// `count` instances from `first` in [`SphereBvh::order`], an inner node its two children
/// (`first`, `first + 1`).
#[derive(Clone, Copy, Debug)]
struct Node {
    center: Vec3,
    /// The node's radius, each instance's may-meet margin and the node test's own rounding pad
    /// included; the origin's share of the margin is added per query.
    reach: f32,
    first: u32,
    count: u32,
}

impl Node {
    #[inline]
    fn from(&self, origin: Vec3) -> MayMeetFrom {
        MayMeetFrom {
            f: self.center - origin,
            reach: self.reach + MAY_MEET_SLACK * origin.abs().max_element(),
        }
    }
}

/// The tree over a scene's instances (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct SphereBvh {
    nodes: Vec<Node>,
    /// Instance indices in leaf order.
    order: Vec<u32>,
}

impl SphereBvh {
    /// Builds the tree over `instances`' world spheres (median splits of the centres on the
    /// longest axis of their bounds).
    pub fn new(instances: &[FieldInstance]) -> SphereBvh {
        // Each instance's reach from the world origin: its radius and the part of its margin
        // that does not depend on the ray's origin.
        let spheres: Vec<(Vec3, f32)> = instances
            .iter()
            .map(|inst| (inst.world_center, inst.may_meet_from(Vec3::ZERO).reach))
            .collect();
        let mut tree = SphereBvh {
            nodes: Vec::with_capacity(2 * spheres.len()),
            order: (0..spheres.len() as u32).collect(),
        };
        if !spheres.is_empty() {
            tree.nodes.push(Node {
                center: Vec3::ZERO,
                reach: 0.0,
                first: 0,
                count: 0,
            });
            tree.build(0, 0, spheres.len(), &spheres);
        }
        tree
    }

    fn build(&mut self, node: usize, start: usize, end: usize, spheres: &[(Vec3, f32)]) {
        let members = &self.order[start..end];
        let (lo, hi) = members.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &i| {
                let (c, r) = spheres[i as usize];
                (lo.min(c - Vec3::splat(r)), hi.max(c + Vec3::splat(r)))
            },
        );
        let center = 0.5 * (lo + hi);
        let radius = members
            .iter()
            .map(|&i| {
                let (c, r) = spheres[i as usize];
                c.distance(center) + r
            })
            .fold(0.0f32, f32::max);
        // The pad: far above the f32 rounding of this test and of the instances' own, which
        // both stay within a few ulps of |centre| + |origin| + radius.
        let reach = radius + MAY_MEET_SLACK * (center.abs().max_element() + radius);
        if end - start <= LEAF {
            self.nodes[node] = Node {
                center,
                reach,
                first: start as u32,
                count: (end - start) as u32,
            };
            return;
        }
        let (clo, chi) = self.order[start..end].iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &i| (lo.min(spheres[i as usize].0), hi.max(spheres[i as usize].0)),
        );
        let axis = (chi - clo).max_position();
        let mid = (start + end) / 2;
        self.order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            spheres[a as usize].0[axis].total_cmp(&spheres[b as usize].0[axis])
        });
        let first = self.nodes.len();
        for _ in 0..2 {
            self.nodes.push(Node {
                center: Vec3::ZERO,
                reach: 0.0,
                first: 0,
                count: 0,
            });
        }
        self.nodes[node] = Node {
            center,
            reach,
            first: first as u32,
            count: 0,
        };
        self.build(first, start, mid, spheres);
        self.build(first + 1, mid, end, spheres);
    }

    /// Bytes of the tree.
    pub fn bytes(&self) -> u64 {
        (self.nodes.len() * std::mem::size_of::<Node>() + self.order.len() * 4) as u64
    }

    /// The instances a ray from `origin` along unit `dir` is tested against (those at the
    /// leaves it reaches), in tree order: a superset of the instances whose
    /// [`FieldInstance::may_meet`] passes.
    pub fn candidates(&self, origin: Vec3, dir: Vec3, tmin: f32) -> Vec<usize> {
        let mut out = Vec::new();
        self.for_each_leaf_instance(origin, dir, tmin, |i| out.push(i));
        out
    }

    /// Calls `f` with every instance at a leaf whose every node the ray may meet, in tree order.
    fn for_each_leaf_instance(&self, origin: Vec3, dir: Vec3, tmin: f32, mut f: impl FnMut(usize)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            if !n.from(origin).test(dir, tmin) {
                continue;
            }
            if n.count == 0 {
                stack[top] = n.first;
                stack[top + 1] = n.first + 1;
                top += 2;
            } else {
                for &i in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    f(i as usize);
                }
            }
        }
    }
}

/// A [`FieldScene`] whose instances are found through a [`SphereBvh`]: the same answers, bit
/// for bit, with a ray's cost growing with the spheres near it rather than with all of them.
#[derive(Clone, Debug, Default)]
pub struct SphereBvhScene {
    pub scene: FieldScene,
    pub bvh: SphereBvh,
}

impl SphereBvhScene {
    /// The tree over `scene`'s instances (rebuild it, through a new value, when they move).
    pub fn new(scene: FieldScene) -> SphereBvhScene {
        SphereBvhScene {
            bvh: SphereBvh::new(&scene.instances),
            scene,
        }
    }

    /// One query's candidates, through the tree (or the plain scene's loop for one instance).
    fn candidates(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
    ) -> impl FnOnce(&mut dyn FnMut(usize)) + '_ {
        move |f| self.bvh.for_each_leaf_instance(origin, dir, tmin, f)
    }

    /// [`FieldScene::occluded_many_to_on`] through the tree: the rays of a batch descend the
    /// tree together, each node keeping the rays that may meet it, and each leaf's instances
    /// run their batched lookup on those rays only.
    ///
    /// # Panics
    /// If `dirs`, `tmaxs` and `out` differ in length.
    pub fn occluded_many_to_on(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmaxs: &[f32],
        out: &mut [bool],
    ) {
        assert!(
            dirs.len() == out.len() && dirs.len() == tmaxs.len(),
            "occluded_many_to: dirs, tmaxs and out differ in length"
        );
        self.occluded_from(isa, origin, dirs, tmin, |i| tmaxs[i], out);
    }

    fn occluded_from(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: impl Fn(usize) -> f32 + Copy,
        out: &mut [bool],
    ) {
        if self.scene.instances.len() <= 1 {
            self.scene.occluded_from(isa, origin, dirs, tmin, tmax, out);
            return;
        }
        out.fill(false);
        let nodes = &self.bvh.nodes;
        // Each pending node's rays: a range of `lists`; the node popped last holds the last
        // range, so popping truncates `lists` to it and its children's ranges follow.
        let mut lists: Vec<u32> = Vec::with_capacity(4 * dirs.len());
        let mut stack: Vec<(u32, usize, usize)> = Vec::with_capacity(64);
        let root = nodes[0].from(origin);
        lists.extend((0..dirs.len() as u32).filter(|&i| root.test(dirs[i as usize], tmin)));
        stack.push((0, 0, lists.len()));
        let (mut sub_dirs, mut sub_map, mut sub_out) = (Vec::new(), Vec::new(), Vec::new());
        while let Some((node, start, end)) = stack.pop() {
            lists.truncate(end);
            let n = nodes[node as usize];
            if n.count == 0 {
                for child in [n.first, n.first + 1] {
                    let meet = nodes[child as usize].from(origin);
                    let s = lists.len();
                    for k in start..end {
                        let i = lists[k] as usize;
                        if !out[i] && meet.test(dirs[i], tmin) {
                            lists.push(i as u32);
                        }
                    }
                    if lists.len() > s {
                        stack.push((child, s, lists.len()));
                    }
                }
                continue;
            }
            for &j in &self.bvh.order[n.first as usize..(n.first + n.count) as usize] {
                let inst = &self.scene.instances[j as usize];
                sub_dirs.clear();
                sub_map.clear();
                for &i in &lists[start..end] {
                    if !out[i as usize] {
                        sub_dirs.push(dirs[i as usize]);
                        sub_map.push(i);
                    }
                }
                if sub_dirs.is_empty() {
                    break;
                }
                sub_out.clear();
                sub_out.resize(sub_dirs.len(), false);
                let tmax_k = |k: usize| tmax(sub_map[k] as usize);
                let also = |k: usize, dir: Vec3| {
                    inst.meets_segment(origin, dir, tmin, tmax_k(k)).is_some()
                };
                inst.occluded_many(
                    isa,
                    origin,
                    &sub_dirs,
                    tmin,
                    tmax_k,
                    &self.scene.options,
                    also,
                    &mut sub_out,
                );
                for (k, &hit) in sub_out.iter().enumerate() {
                    out[sub_map[k] as usize] |= hit;
                }
            }
        }
    }
}

impl Visibility for SphereBvhScene {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        if self.scene.instances.len() <= 1 {
            return self.scene.occluded(origin, dir, tmin, tmax);
        }
        self.scene
            .occluded_among(self.candidates(origin, dir, tmin), origin, dir, tmin, tmax)
    }

    fn occluded_many(&self, origin: Vec3, dirs: &[Vec3], tmin: f32, tmax: f32, out: &mut [bool]) {
        assert_eq!(
            dirs.len(),
            out.len(),
            "occluded_many: dirs and out differ in length"
        );
        self.occluded_from(Isa::detect(), origin, dirs, tmin, |_| tmax, out);
    }

    fn occluded_many_to(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmaxs: &[f32],
        out: &mut [bool],
    ) {
        self.occluded_many_to_on(Isa::detect(), origin, dirs, tmin, tmaxs, out);
    }

    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        if self.scene.instances.len() <= 1 {
            return self.scene.hit_distance(origin, dir, tmin, tmax);
        }
        let opts = &self.scene.options;
        self.scene.nearest_among(
            self.candidates(origin, dir, tmin),
            origin,
            dir,
            tmin,
            tmax,
            |&t| t,
            |inst, limit| inst.hit_distance(origin, dir, tmin, limit, opts),
        )
    }

    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        if self.scene.instances.len() <= 1 {
            return self.scene.surface_hit(origin, dir, tmin, tmax);
        }
        let opts = &self.scene.options;
        self.scene.nearest_among(
            self.candidates(origin, dir, tmin),
            origin,
            dir,
            tmin,
            tmax,
            |h: &SurfaceHit| h.t,
            |inst, limit| inst.surface_hit(origin, dir, tmin, limit, opts),
        )
    }
}
