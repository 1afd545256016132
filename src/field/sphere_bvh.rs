//! A BVH over the instances' bounding spheres, so that a ray in a scene of many casters tests
//! the spheres near it instead of every sphere ([`SphereBvhScene`]).
//!
//! The 2008 paper's Algorithm 2 loops over every occluder's bounding sphere per ray, and so does
//! [`FieldScene`]; with a crowd of hundreds of moving casters that loop, not the lookups,
//! dominates a frame. Deviation from the paper: a binary tree of bounding spheres over the
//! instances, rebuilt whenever the instances move ([`SphereBvhScene::new`], O(N log N) in their
//! number with a median split per level, no triangle touched), is traversed first; the
//! instances at its leaves then run the same tests and lookups as in [`FieldScene`].
//!
//! Answers are bit-identical to [`FieldScene`]'s on every ray: a node's test is conservative
//! (its reach covers each instance's [`FieldInstance::may_meet`] reach plus the distance
//! between the centres, padded beyond the f32 rounding of either test), so every instance the
//! plain scene would consider is still considered, and whether a ray is occluded, or its
//! nearest hit, does not depend on the order the instances are tried in. Tested against
//! [`FieldScene`] on crowds in `tests/sphere_bvh.rs`.

use super::lanes::{self, Isa, MayMeetFrom};
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
    scene: FieldScene,
    bvh: SphereBvh,
}

impl SphereBvhScene {
    /// The tree over `scene`'s instances (rebuild it, through a new value, when they move).
    pub fn new(scene: FieldScene) -> SphereBvhScene {
        SphereBvhScene {
            bvh: SphereBvh::new(&scene.instances),
            scene,
        }
    }

    /// The scene the tree is over.
    pub fn scene(&self) -> &FieldScene {
        &self.scene
    }

    /// The tree.
    pub fn bvh(&self) -> &SphereBvh {
        &self.bvh
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
        SCRATCH.with(|levels| {
            let mut levels = levels.borrow_mut();
            let (root, rest) = levels.split_first_mut().expect("levels");
            let all = root.filter(isa, &self.bvh.nodes[0].from(origin), dirs, None, tmin, out);
            if all > 0 {
                self.descend(
                    isa, origin, tmin, &tmax, 0, &root.dirs, &root.map, rest, out,
                );
            }
        });
    }

    /// The rays `dirs` (ray `map[k]` of the batch) have passed `node`'s test: the leaf's
    /// instances run their batched lookup on those not yet occluded, an inner node hands each
    /// child the rays that pass its test ([`lanes::cull`], eight rays at a time).
    #[allow(clippy::too_many_arguments)]
    fn descend(
        &self,
        isa: Isa,
        origin: Vec3,
        tmin: f32,
        tmax: &impl Fn(usize) -> f32,
        node: u32,
        dirs: &[Vec3],
        map: &[u32],
        levels: &mut [Level],
        out: &mut [bool],
    ) {
        let nodes = &self.bvh.nodes;
        let n = nodes[node as usize];
        let (this, rest) = levels
            .split_first_mut()
            .expect("a tree deeper than its scratch levels");
        if n.count == 0 {
            for child in [n.first, n.first + 1] {
                let meet = nodes[child as usize].from(origin);
                if this.filter(isa, &meet, dirs, Some(map), tmin, out) > 0 {
                    self.descend(
                        isa, origin, tmin, tmax, child, &this.dirs, &this.map, rest, out,
                    );
                }
            }
            return;
        }
        for &j in &self.bvh.order[n.first as usize..(n.first + n.count) as usize] {
            let inst = &self.scene.instances[j as usize];
            this.dirs.clear();
            this.map.clear();
            for (k, &i) in map.iter().enumerate() {
                if !out[i as usize] {
                    this.dirs.push(dirs[k]);
                    this.map.push(i);
                }
            }
            if this.dirs.is_empty() {
                return;
            }
            this.hit.clear();
            this.hit.resize(this.dirs.len(), false);
            let sub = &this.map;
            let tmax_k = |k: usize| tmax(sub[k] as usize);
            let also =
                |k: usize, dir: Vec3| inst.meets_segment(origin, dir, tmin, tmax_k(k)).is_some();
            inst.occluded_many(
                isa,
                origin,
                &this.dirs,
                tmin,
                tmax_k,
                &self.scene.options,
                also,
                &mut this.hit,
            );
            for (k, &hit) in this.hit.iter().enumerate() {
                out[sub[k] as usize] |= hit;
            }
        }
    }
}

/// One tree level's rays: their directions and their indices in the batch.
#[derive(Default)]
struct Level {
    dirs: Vec<Vec3>,
    map: Vec<u32>,
    /// Per ray: already occluded (the cull's skip flags), then a leaf's lookup answers.
    hit: Vec<bool>,
    idx: Vec<u32>,
}

impl Level {
    /// Keeps in `self` the rays of `dirs` (batch indices `map`, or `0..` when `None`) that are
    /// not yet occluded in `out` and pass `meet`; returns their count.
    fn filter(
        &mut self,
        isa: Isa,
        meet: &MayMeetFrom,
        dirs: &[Vec3],
        map: Option<&[u32]>,
        tmin: f32,
        out: &[bool],
    ) -> usize {
        let at = |k: usize| map.map_or(k as u32, |m| m[k]);
        self.hit.clear();
        self.hit
            .extend((0..dirs.len()).map(|k| out[at(k) as usize]));
        self.idx.resize(dirs.len().max(self.idx.len()), 0);
        let kept = lanes::cull(isa, meet, dirs, tmin, &self.hit, &mut self.idx);
        self.dirs.clear();
        self.map.clear();
        for &k in &self.idx[..kept] {
            self.dirs.push(dirs[k as usize]);
            self.map.push(at(k as usize));
        }
        kept
    }
}

thread_local! {
    /// The batched traversal's buffers, one level per tree depth (a median-split tree over
    /// fewer than 2⁶³ instances is shallower), kept between calls.
    static SCRATCH: std::cell::RefCell<Vec<Level>> =
        std::cell::RefCell::new((0..66).map(|_| Level::default()).collect());
}

impl Visibility for SphereBvhScene {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let leaves =
            |f: &mut dyn FnMut(usize)| self.bvh.for_each_leaf_instance(origin, dir, tmin, f);
        self.scene.occluded_among(&leaves, origin, dir, tmin, tmax)
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
        let leaves =
            |f: &mut dyn FnMut(usize)| self.bvh.for_each_leaf_instance(origin, dir, tmin, f);
        let opts = &self.scene.options;
        self.scene.nearest_among(
            &leaves,
            origin,
            dir,
            tmin,
            tmax,
            |&t| t,
            |inst, limit| inst.hit_distance(origin, dir, tmin, limit, opts),
        )
    }

    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        let leaves =
            |f: &mut dyn FnMut(usize)| self.bvh.for_each_leaf_instance(origin, dir, tmin, f);
        let opts = &self.scene.options;
        self.scene.nearest_among(
            &leaves,
            origin,
            dir,
            tmin,
            tmax,
            |h: &SurfaceHit| h.t,
            |inst, limit| inst.surface_hit(origin, dir, tmin, limit, opts),
        )
    }
}
