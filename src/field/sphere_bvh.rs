//! A BVH over the instances' bounding spheres, so that a ray in a scene of many casters tests
//! the spheres near it instead of every sphere ([`SphereBvhScene`]).
//!
//! The 2008 paper's Algorithm 2 loops over every occluder's bounding sphere per ray, and so does
//! [`FieldScene`]; with a crowd of hundreds of moving casters that loop, not the lookups,
//! dominates a frame. Deviation from the paper: a binary tree of boxes over the instances'
//! spheres, rebuilt whenever the instances move ([`SphereBvhScene::new`], O(N log N) in their
//! number with a median split per level, no triangle touched), is traversed first; the
//! instances at its leaves then run the same tests and lookups as in [`FieldScene`].
//!
//! The nodes are boxes, not spheres: over a flat crowd a node's bounding sphere reaches far above
//! and below its casters and holds the receiver points themselves, so every ray from them passes
//! it; a box's slab test keeps far fewer (docs/performance.md, "The field in a moving crowd").
//! A batch of rays from one origin (AO and shadow rays) descends the tree 64 rays at a time, the
//! rays a node keeps held as a bit mask, so nothing is copied per node; the rays a leaf keeps are
//! gathered once per instance for its batched lookup, and a ray is dropped from every later node
//! as soon as one instance occludes it.
//!
//! Answers are bit-identical to [`FieldScene`]'s on every ray: a node's test is conservative
//! (its box holds each instance's [`FieldInstance::may_meet`] ball, padded beyond the f32
//! rounding of the slab test and of the instances' own tests), so every instance the plain scene
//! would consider (its `may_meet` and its world sphere's segment test both pass) is still
//! considered, and whether a ray is occluded, or its nearest hit, does not depend on the order
//! the instances are tried in. Tested against [`FieldScene`] on crowds in `tests/sphere_bvh.rs`.

use super::lanes::Isa;
use super::scene::{FieldInstance, FieldScene, MAY_MEET_SLACK};
use crate::visibility::{SurfaceHit, Visibility};
use glam::Vec3;

/// Instances per leaf.
const LEAF: usize = 1;

/// Rays a batched traversal carries in one bit mask.
const WINDOW: usize = 64;

/// One node: a box holding its instances' may-meet balls (with their rounding margins and the
/// node's own pad); a leaf holds `count` instances from `first` in [`SphereBvh::order`], an inner
/// node its two children (`first`, `first + 1`).
#[derive(Clone, Copy, Debug, Default)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    first: u32,
    count: u32,
}

/// A node's box seen from one origin: its corners less the origin, widened by the origin's share
/// of the rounding margin (as [`FieldInstance::may_meet_from`] widens an instance's ball).
#[derive(Clone, Copy, Debug)]
struct BoxFrom {
    lo: Vec3,
    hi: Vec3,
}

impl Node {
    #[inline]
    fn from(&self, origin: Vec3) -> BoxFrom {
        let pad = Vec3::splat(MAY_MEET_SLACK * origin.abs().max_element());
        BoxFrom {
            lo: self.lo - origin - pad,
            hi: self.hi - origin + pad,
        }
    }
}

impl BoxFrom {
    /// `false` only when the ray along a direction whose reciprocal is `inv` certainly misses
    /// the box between `tmin` and `tmax` (a direction component of 0 gives an infinite
    /// reciprocal; the slab's `0 · ∞` NaN, which only a ray lying in a face's plane can give,
    /// may drop the box, which the pad keeps clear of every ball). The minima and maxima are
    /// the x86 `minps` / `maxps` ones ([`vmin`], [`vmax`]), so the eight-lane test
    /// ([`Self::test_lanes`]) decides every ray alike.
    #[inline]
    fn test(&self, inv: Vec3, tmin: f32, tmax: f32) -> bool {
        let (t0, t1) = (self.lo * inv, self.hi * inv);
        let near = vmax(vmax(vmin(t0.x, t1.x), vmin(t0.y, t1.y)), vmin(t0.z, t1.z));
        let far = vmin(vmin(vmax(t0.x, t1.x), vmax(t0.y, t1.y)), vmax(t0.z, t1.z));
        near <= far && far >= tmin && near <= tmax
    }

    /// [`Self::test`] of the window's rays whose bits are set in `rays` (at most [`WINDOW`]),
    /// eight at a time on `isa`: the bits of the rays that pass.
    #[inline]
    fn test_lanes(&self, isa: Isa, w: &Window, tmin: f32, rays: u64) -> u64 {
        #[cfg(target_arch = "x86_64")]
        if isa.runs_avx2() {
            // SAFETY: the CPU has AVX2 (`Isa::runs_avx2`).
            return unsafe { avx2::test_lanes(self, w, tmin, rays) };
        }
        let _ = isa;
        let mut bits = rays;
        let mut kept = 0u64;
        while bits != 0 {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let inv = Vec3::new(w.inv_x[k], w.inv_y[k], w.inv_z[k]);
            kept |= (self.test(inv, tmin, w.far[k]) as u64) << k;
        }
        kept
    }
}

/// x86's `minps`: `a` where `a < b`, else `b` (so `b` where either is NaN).
#[inline]
fn vmin(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// x86's `maxps`: `a` where `a > b`, else `b`.
#[inline]
fn vmax(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// A window of at most [`WINDOW`] rays from one origin, as the node tests read them: each
/// direction's reciprocal and the ray's far end, structure of arrays.
struct Window {
    inv_x: [f32; WINDOW],
    inv_y: [f32; WINDOW],
    inv_z: [f32; WINDOW],
    far: [f32; WINDOW],
}

impl Window {
    /// A window whose ray `k` goes along `dirs[k]` to `far(k)`.
    #[inline]
    fn new(dirs: impl IntoIterator<Item = Vec3>, far: impl Fn(usize) -> f32) -> Window {
        let mut w = Window {
            inv_x: [0.0; WINDOW],
            inv_y: [0.0; WINDOW],
            inv_z: [0.0; WINDOW],
            far: [0.0; WINDOW],
        };
        for (k, d) in dirs.into_iter().enumerate() {
            let inv = d.recip();
            (w.inv_x[k], w.inv_y[k], w.inv_z[k]) = (inv.x, inv.y, inv.z);
            w.far[k] = far(k);
        }
        w
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{BoxFrom, Window};
    use std::arch::x86_64::*;

    /// [`BoxFrom::test_lanes`] with AVX2: each group of eight rays with a bit set in `rays`
    /// takes the slab test in 8 × f32, the scalar [`BoxFrom::test`]'s operations in its order.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn test_lanes(b: &BoxFrom, w: &Window, tmin: f32, rays: u64) -> u64 {
        let (lx, ly, lz) = (
            _mm256_set1_ps(b.lo.x),
            _mm256_set1_ps(b.lo.y),
            _mm256_set1_ps(b.lo.z),
        );
        let (hx, hy, hz) = (
            _mm256_set1_ps(b.hi.x),
            _mm256_set1_ps(b.hi.y),
            _mm256_set1_ps(b.hi.z),
        );
        let tmin_v = _mm256_set1_ps(tmin);
        let mut kept = 0u64;
        for g in 0..super::WINDOW / 8 {
            let lanes = (rays >> (8 * g)) & 0xff;
            if lanes == 0 {
                continue;
            }
            let at = 8 * g;
            let ix = _mm256_loadu_ps(w.inv_x.as_ptr().add(at));
            let iy = _mm256_loadu_ps(w.inv_y.as_ptr().add(at));
            let iz = _mm256_loadu_ps(w.inv_z.as_ptr().add(at));
            let far_v = _mm256_loadu_ps(w.far.as_ptr().add(at));
            let (t0x, t1x) = (_mm256_mul_ps(lx, ix), _mm256_mul_ps(hx, ix));
            let (t0y, t1y) = (_mm256_mul_ps(ly, iy), _mm256_mul_ps(hy, iy));
            let (t0z, t1z) = (_mm256_mul_ps(lz, iz), _mm256_mul_ps(hz, iz));
            let near = _mm256_max_ps(
                _mm256_max_ps(_mm256_min_ps(t0x, t1x), _mm256_min_ps(t0y, t1y)),
                _mm256_min_ps(t0z, t1z),
            );
            let far = _mm256_min_ps(
                _mm256_min_ps(_mm256_max_ps(t0x, t1x), _mm256_max_ps(t0y, t1y)),
                _mm256_max_ps(t0z, t1z),
            );
            let pass = _mm256_and_ps(
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_LE_OQ>(near, far),
                    _mm256_cmp_ps::<_CMP_GE_OQ>(far, tmin_v),
                ),
                _mm256_cmp_ps::<_CMP_LE_OQ>(near, far_v),
            );
            kept |= ((_mm256_movemask_ps(pass) as u64) & lanes) << at;
        }
        kept
    }
}

/// One node of [`SphereBvh::flat_nodes`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatNode {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Whether it is a leaf.
    pub leaf: bool,
    /// A leaf's instance, or an inner node's first child.
    pub index: u32,
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
            tree.nodes.push(Node::default());
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
        // The pad: far above the f32 rounding of the box's corners, of the slab test and of the
        // instances' own tests, which all stay within a few ulps of the coordinates' magnitude.
        let pad = Vec3::splat(MAY_MEET_SLACK * lo.abs().max(hi.abs()).max_element());
        let (lo, hi) = (lo - pad, hi + pad);
        if end - start <= LEAF {
            self.nodes[node] = Node {
                lo,
                hi,
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
        self.nodes.extend([Node::default(); 2]);
        self.nodes[node] = Node {
            lo,
            hi,
            first: first as u32,
            count: 0,
        };
        self.build(first, start, mid, spheres);
        self.build(first + 1, mid, end, spheres);
    }

    /// The tree as the GPU walks it (src/gpu/field_binding.rs, shaders/field_top_level.wgsl):
    /// its nodes in order, the root first, each with its box (the may-meet balls and the pad, as
    /// the CPU's test reads it) and, for a leaf, its instance, for an inner node its first child
    /// (the second follows it). A leaf holds one instance (`LEAF`).
    pub fn flat_nodes(&self) -> Vec<FlatNode> {
        const _: () = assert!(LEAF == 1);
        (self.nodes.iter())
            .map(|n| FlatNode {
                lo: n.lo,
                hi: n.hi,
                leaf: n.count > 0,
                index: if n.count > 0 {
                    self.order[n.first as usize]
                } else {
                    n.first
                },
            })
            .collect()
    }

    /// Bytes of the tree.
    pub fn bytes(&self) -> u64 {
        (self.nodes.len() * std::mem::size_of::<Node>() + self.order.len() * 4) as u64
    }

    /// The instances a ray from `origin` along unit `dir` is tested against (those at the
    /// leaves it reaches), in tree order: a superset of the instances whose world sphere the
    /// ray meets from `tmin` on.
    pub fn candidates(&self, origin: Vec3, dir: Vec3, tmin: f32) -> Vec<usize> {
        let mut out = Vec::new();
        self.for_each_leaf_instance(origin, dir, tmin, f32::INFINITY, |i| out.push(i));
        out
    }

    /// Calls `f` with every instance at a leaf whose every node the segment may meet, in tree
    /// order.
    fn for_each_leaf_instance(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        mut f: impl FnMut(usize),
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = dir.recip();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            if !n.from(origin).test(inv, tmin, tmax) {
                continue;
            }
            if n.count == 0 {
                stack[top] = n.first + 1;
                stack[top + 1] = n.first;
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
    /// tree together, 64 at a time, each node keeping the rays that may meet it as a bit mask,
    /// and each leaf's instances run their batched lookup on those rays only.
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
        crate::visibility::check_batch_to(dirs.len(), tmaxs.len(), out.len());
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
        for (w, (dirs, out)) in dirs.chunks(WINDOW).zip(out.chunks_mut(WINDOW)).enumerate() {
            let start = w * WINDOW;
            self.occluded_window(isa, origin, dirs, tmin, |k| tmax(start + k), out);
        }
    }

    /// At most [`WINDOW`] rays of a batch through the tree (see the module documentation).
    fn occluded_window(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: impl Fn(usize) -> f32 + Copy,
        out: &mut [bool],
    ) {
        let n = dirs.len();
        debug_assert!(n <= WINDOW);
        let w = Window::new(dirs.iter().copied(), tmax);
        // Rays not yet occluded.
        let mut alive: u64 = if n == WINDOW { !0 } else { (1u64 << n) - 1 };
        let nodes = &self.bvh.nodes;
        let mut stack = [(0u32, 0u64); 64];
        stack[0] = (0, alive);
        let mut top = 1;
        let mut sub_dirs = [Vec3::ZERO; WINDOW];
        let mut sub_index = [0u8; WINDOW];
        let mut hit = [false; WINDOW];
        while top > 0 {
            top -= 1;
            let (node, entered) = stack[top];
            let rays = entered & alive;
            if rays == 0 {
                continue;
            }
            let nd = nodes[node as usize];
            let kept = nd.from(origin).test_lanes(isa, &w, tmin, rays);
            if kept == 0 {
                continue;
            }
            if nd.count == 0 {
                stack[top] = (nd.first + 1, kept);
                stack[top + 1] = (nd.first, kept);
                top += 2;
                continue;
            }
            for &j in &self.bvh.order[nd.first as usize..(nd.first + nd.count) as usize] {
                let inst = &self.scene.instances[j as usize];
                let mut m = kept & alive;
                let mut count = 0;
                while m != 0 {
                    let k = m.trailing_zeros() as usize;
                    m &= m - 1;
                    sub_dirs[count] = dirs[k];
                    sub_index[count] = k as u8;
                    count += 1;
                }
                if count == 0 {
                    break;
                }
                let answers = &mut hit[..count];
                answers.fill(false);
                let sub = &sub_index[..count];
                let tmax_k = |c: usize| w.far[sub[c] as usize];
                let also = |c: usize, dir: Vec3| {
                    inst.meets_segment(origin, dir, tmin, tmax_k(c)).is_some()
                };
                inst.occluded_many(
                    isa,
                    origin,
                    &sub_dirs[..count],
                    tmin,
                    tmax_k,
                    &self.scene.options,
                    also,
                    answers,
                );
                for (c, &h) in answers.iter().enumerate() {
                    if h {
                        let k = sub[c] as usize;
                        out[k] = true;
                        alive &= !(1u64 << k);
                    }
                }
            }
        }
    }
}

impl Visibility for SphereBvhScene {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let leaves =
            |f: &mut dyn FnMut(usize)| self.bvh.for_each_leaf_instance(origin, dir, tmin, tmax, f);
        self.scene.occluded_among(&leaves, origin, dir, tmin, tmax)
    }

    fn occluded_many(&self, origin: Vec3, dirs: &[Vec3], tmin: f32, tmax: f32, out: &mut [bool]) {
        crate::visibility::check_batch("occluded_many", dirs.len(), out.len());
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
            |f: &mut dyn FnMut(usize)| self.bvh.for_each_leaf_instance(origin, dir, tmin, tmax, f);
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
            |f: &mut dyn FnMut(usize)| self.bvh.for_each_leaf_instance(origin, dir, tmin, tmax, f);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rays::seeded_sphere_direction;

    /// The eight-lane node test decides every ray as the one-ray test does, on every
    /// instruction set, rays along the axes and in the boxes' face planes included.
    #[test]
    fn the_lane_test_decides_as_the_ray_test() {
        let mut passed = 0;
        for b in 0..200u64 {
            let c = seeded_sphere_direction(b, 1) * 3.0;
            let h = seeded_sphere_direction(b, 2).abs() + Vec3::splat(0.5);
            let bx = BoxFrom {
                lo: c - h,
                hi: c + h,
            };
            let dirs = (0..WINDOW).map(|k| {
                let d = seeded_sphere_direction(b * 64 + k as u64, 3);
                // Axis-aligned and in-plane rays: zero components, infinite reciprocals.
                match k % 8 {
                    0 => Vec3::new(0.0, d.y, d.z).normalize(),
                    1 => Vec3::new(-0.0, 0.0, 1.0),
                    2 => Vec3::X,
                    _ => d,
                }
            });
            let w = Window::new(dirs, |k| {
                if k.is_multiple_of(5) {
                    f32::INFINITY
                } else {
                    0.5 * k as f32
                }
            });
            // A box face through the origin: 0 · ∞ in the slab.
            let bx = if b % 7 == 0 {
                BoxFrom {
                    lo: Vec3::new(0.0, bx.lo.y, bx.lo.z),
                    ..bx
                }
            } else {
                bx
            };
            let rays = seeded_sphere_direction(b, 4).x.to_bits() as u64 * 0x9e37_79b9_7f4a_7c15;
            let expect: u64 = (0..WINDOW)
                .filter(|&k| rays >> k & 1 == 1)
                .filter(|&k| {
                    let inv = Vec3::new(w.inv_x[k], w.inv_y[k], w.inv_z[k]);
                    bx.test(inv, 1e-4, w.far[k])
                })
                .map(|k| 1u64 << k)
                .sum();
            passed += expect.count_ones();
            for isa in Isa::all_available() {
                assert_eq!(
                    bx.test_lanes(isa, &w, 1e-4, rays),
                    expect,
                    "box {b} {isa:?}"
                );
            }
        }
        // Both answers occur.
        assert!(passed > 100 && passed < 200 * 32 / 2, "{passed} rays kept");
    }
}
