//! Two-level ray casting on the GPU for rigid instances, the twin of the CPU's
//! [`crate::trace::two_level::TwoLevel`] and the way engines cast rays in scenes of moving
//! rigid objects (a top level over bottom levels): each mesh's CWBVH (Ylitie, Karras, Laine,
//! HPG 2017, the traversal and watertight triangle test of [`super::GpuTracer`],
//! shaders/cwbvh.wgsl) built on the host and uploaded once, shared by all its instances; a top
//! level over the instances' world boxes ([`crate::trace::box_tree::BoxTree`], as the CPU's)
//! rebuilt on the host every frame with each instance's world → model transform and uploaded
//! ([`GpuTwoLevel::update`], which waits for the upload, so a frame's update carries it); in
//! WGSL each ray meets the top level, then each instance whose box it may meet in that
//! instance's model space (shaders/two_level.wgsl): any hit for `occluded`, the closest hit
//! with its triangle's normal turned to the world for `surface_hit`. A [`GpuVisibility`], so
//! every integrand (AO, soft shadows, glossy reflections) runs on it.
//!
//! What motion costs it is the top level (N boxes, N transforms), not the triangles: a crowd of
//! 64 or 256 instances of a few meshes holds each mesh's triangles once, where the world BVH
//! ([`super::GpuTracer`]) copies every instance's triangles into one storage binding and is
//! refused past it ([`GpuError::TooLarge`]). Its own limit is the same binding for the distinct
//! meshes' triangles and nodes together, refused by name.
//!
//! Its answers are the CPU two-level caster's up to f32 rounding on the device (the ray moved
//! into each instance's space with the same operations; the node and triangle tests those of
//! [`super::GpuTracer`]): the same hits and misses away from edges and grazing rays, distances
//! within a few ulps (tests/gpu_two_level.rs).

use super::context::GpuContext;
use super::integrand;
use super::shadow_rays::check_binding;
use super::tracer::{
    any_hits, bounding_box, closest_hits, packed_cwbvh, ray_queries, CasterHeaderGpu, RayQueries,
    CASTER_HEADER_WGSL, RAY_QUERIES_WGSL,
};
use super::visibility::{GpuVisibility, Kernels, VisibilityGroup, READ_ONLY_STORAGE};
use super::{GpuError, GpuTiming};
use crate::geometry::Similarity;
use crate::trace::box_tree::BoxTree;
use crate::trace::RayQuery;
use glam::Vec3;
use obvhs::cwbvh::node::CwBvhNode;
use std::time::{Duration, Instant};

/// Twin of WGSL `TopNode` (shaders/two_level.wgsl): one node of the top level, the CPU's
/// [`crate::trace::box_tree::BoxNode`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct TopNodeGpu {
    lo: [f32; 3],
    /// A leaf's first entry in the order, an inner node's first child.
    first: u32,
    hi: [f32; 3],
    /// Instances of a leaf; 0 for an inner node.
    count: u32,
}
const _: () = assert!(std::mem::size_of::<TopNodeGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(TopNodeGpu, hi) == 16);

/// Twin of WGSL `Placement` (shaders/two_level.wgsl): one instance this frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct PlacementGpu {
    /// World → model rotation as a unit quaternion (x, y, z, w).
    rotation: [f32; 4],
    /// World translation: world = translation + scale R model.
    translation: [f32; 3],
    /// Uniform scale.
    scale: f32,
    /// Its mesh's root node.
    root: u32,
    /// Its mesh's node count (0: an empty mesh).
    node_count: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<PlacementGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(PlacementGpu, translation) == 16);
const _: () = assert!(std::mem::offset_of!(PlacementGpu, root) == 32);

/// Its own ray queries (its closest-hit words: shaders/two_level_queries.wgsl).
const QUERIES: RayQueries = ray_queries(&[
    RAY_QUERIES_WGSL,
    include_str!("../../shaders/two_level_queries.wgsl"),
]);

/// Instances per top-level leaf (as the CPU's).
const LEAF: usize = 2;

/// A closest hit of the two-level GPU caster.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoLevelHit {
    /// World distance.
    pub t: f32,
    /// The instance hit (index into the last [`GpuTwoLevel::update`]'s list).
    pub instance: u32,
    /// The triangle's unit geometric normal, world space.
    pub normal: Vec3,
}

/// One mesh's bottom level in the shared buffers.
#[derive(Clone, Copy, Debug)]
struct MeshLevel {
    root: u32,
    node_count: u32,
    /// Model-space bounding sphere (the centre of its box, the farthest vertex), as the CPU's.
    center: Vec3,
    radius: f32,
}

/// The top level on the device, with room for `capacity` instances.
struct TopLevel {
    nodes: wgpu::Buffer,
    order: wgpu::Buffer,
    placements: wgpu::Buffer,
    capacity: usize,
}

impl TopLevel {
    fn with_capacity(ctx: &GpuContext, capacity: usize) -> TopLevel {
        let capacity = capacity.max(1);
        let zeros = |bytes: usize| vec![0u8; bytes];
        TopLevel {
            nodes: ctx.storage_buffer(
                "top-level nodes",
                &zeros(2 * capacity * std::mem::size_of::<TopNodeGpu>()),
            ),
            order: ctx.storage_buffer("top-level order", &zeros(capacity * 4)),
            placements: ctx.storage_buffer(
                "placements",
                &zeros(capacity * std::mem::size_of::<PlacementGpu>()),
            ),
            capacity,
        }
    }
}

/// Two-level ray casting on the GPU (see the module documentation).
pub struct GpuTwoLevel<'a> {
    ctx: &'a GpuContext,
    /// The header, every mesh's nodes and triangles (uploaded once), then the top level's
    /// buffers, bound at each call.
    group: VisibilityGroup,
    meshes: Vec<MeshLevel>,
    mesh_bytes: u64,
    top: TopLevel,
    top_node_count: u32,
    instance_count: u32,
    kernels: Kernels,
    setup: Duration,
}

impl<'a> GpuTwoLevel<'a> {
    /// Builds each mesh's CWBVH over its model-space `meshes[m]` triangles on the host (the
    /// CPU tracer's build, as [`super::GpuTracer`]), uploads them once and compiles the
    /// integrands; no instance yet ([`Self::update`] places them).
    ///
    /// Errors: [`GpuError::Invalid`] for a vertex that is not finite, [`GpuError::TooLarge`]
    /// where the meshes' triangles or nodes together pass one storage binding.
    pub fn new(ctx: &'a GpuContext, meshes: &[Vec<[Vec3; 3]>]) -> Result<Self, GpuError> {
        let start = Instant::now();
        let total: usize = meshes.iter().map(Vec::len).sum();
        check_binding::<[f32; 4]>(
            ctx,
            "triangle vertices of the distinct meshes (each uploaded once)",
            total * 3,
        )?;
        let mut all_nodes: Vec<CwBvhNode> = Vec::new();
        let mut all_tris: Vec<[f32; 4]> = Vec::with_capacity(total * 3);
        let mut levels = Vec::with_capacity(meshes.len());
        for tris in meshes {
            let (mut nodes, data) = packed_cwbvh(ctx, tris)?;
            let (node_base, tri_base) = (all_nodes.len() as u32, (all_tris.len() / 3) as u32);
            for n in &mut nodes {
                n.child_base_idx += node_base;
                n.primitive_base_idx += tri_base;
            }
            let (center, radius) = bounds(tris);
            levels.push(MeshLevel {
                root: node_base,
                node_count: nodes.len() as u32,
                center,
                radius,
            });
            all_nodes.extend(nodes);
            all_tris.extend(data);
        }
        check_binding::<CwBvhNode>(
            ctx,
            "CWBVH nodes of the distinct meshes (each uploaded once)",
            all_nodes.len(),
        )?;
        let mesh_bytes =
            (all_nodes.len() * std::mem::size_of::<CwBvhNode>() + all_tris.len() * 16) as u64;
        let tl = GpuTwoLevel {
            ctx,
            group: VisibilityGroup::with_bindings(
                ctx,
                "two-level",
                &[
                    bytemuck::cast_slice(&all_nodes),
                    bytemuck::cast_slice(&all_tris),
                ],
                &[READ_ONLY_STORAGE; 3],
            ),
            meshes: levels,
            mesh_bytes,
            top: TopLevel::with_capacity(ctx, 1),
            top_node_count: 0,
            instance_count: 0,
            kernels: Kernels::new(super::loop_budget::DEFAULT_RAYS_PER_INVOCATION),
            setup: Duration::ZERO,
        };
        for i in [&integrand::AO, &integrand::SHADOWS, &integrand::REFLECTIONS] {
            tl.kernels.compiled(&tl, i)?;
        }
        Ok(GpuTwoLevel {
            setup: start.elapsed(),
            ..tl
        })
    }

    /// Places the instances (mesh index, transform) for this frame: the top level over their
    /// world boxes rebuilt on the host ([`BoxTree`], each box the mesh's model sphere moved and
    /// padded as the CPU's) and uploaded with their transforms, waiting until the device holds
    /// them (so the upload is this call's cost, not the next query's).
    ///
    /// Errors: [`GpuError::Invalid`] for a mesh index out of range or a transform that is not
    /// finite with a positive scale; [`GpuError::Poll`] if waiting for the upload fails.
    pub fn update(&mut self, instances: &[(usize, Similarity)]) -> Result<(), GpuError> {
        for (i, &(m, t)) in instances.iter().enumerate() {
            if m >= self.meshes.len() {
                return Err(GpuError::Invalid(format!(
                    "instance {i} names mesh {m} of {}",
                    self.meshes.len()
                )));
            }
            let finite = t.rotation.is_finite() && t.translation.is_finite();
            if !(finite && t.scale.is_finite() && t.scale > 0.0) {
                return Err(GpuError::Invalid(format!(
                    "instance {i}: transform not finite with a positive scale ({t:?})"
                )));
            }
        }
        let boxes: Vec<(Vec3, Vec3)> = instances
            .iter()
            .map(|&(m, t)| {
                let mesh = &self.meshes[m];
                let wc = t.to_world_point(mesh.center);
                // One ulp-scale pad so the box holds the triangles' rounded world positions
                // (`TwoLevel::update`'s).
                let wr = t.scale * mesh.radius * (1.0 + 1e-5) + 1e-6 * wc.abs().max_element();
                (wc - Vec3::splat(wr), wc + Vec3::splat(wr))
            })
            .collect();
        let tree = BoxTree::new(&boxes, LEAF);
        let nodes: Vec<TopNodeGpu> = (tree.nodes.iter())
            .map(|n| TopNodeGpu {
                lo: n.lo.to_array(),
                first: n.first,
                hi: n.hi.to_array(),
                count: n.count,
            })
            .collect();
        let placements: Vec<PlacementGpu> = instances
            .iter()
            .map(|&(m, t)| {
                let mesh = &self.meshes[m];
                PlacementGpu {
                    rotation: t.rotation.inverse().to_array(),
                    translation: t.translation.to_array(),
                    scale: t.scale,
                    root: mesh.root,
                    node_count: mesh.node_count,
                    _pad: [0; 2],
                }
            })
            .collect();
        if instances.len() > self.top.capacity || nodes.len() > 2 * self.top.capacity {
            self.top = TopLevel::with_capacity(self.ctx, instances.len());
        }
        let q = &self.ctx.queue;
        q.write_buffer(&self.top.nodes, 0, bytemuck::cast_slice(&nodes));
        q.write_buffer(&self.top.order, 0, bytemuck::cast_slice(&tree.order));
        q.write_buffer(&self.top.placements, 0, bytemuck::cast_slice(&placements));
        q.submit([]);
        self.ctx.wait("waiting for the top level's upload")?;
        self.top_node_count = nodes.len() as u32;
        self.instance_count = instances.len() as u32;
        Ok(())
    }

    /// Host time of the meshes' BVH builds, their upload and the integrands' compilation.
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Bytes on the device: every mesh's nodes and triangles (once each) and the top level.
    pub fn bytes(&self) -> u64 {
        let top = self.top_node_count as u64 * std::mem::size_of::<TopNodeGpu>() as u64
            + self.instance_count as u64 * (4 + std::mem::size_of::<PlacementGpu>() as u64);
        self.mesh_bytes + top
    }

    /// Whether each ray hits any instance's triangle with `tmin <= t <= tmax`.
    pub fn any_hits(&self, rays: &[RayQuery]) -> Result<(Vec<bool>, GpuTiming), GpuError> {
        any_hits(self, &self.kernels, &QUERIES.any, rays)
    }

    /// The closest hit of each ray with `tmin <= t <= tmax`: its distance, instance and world
    /// normal.
    pub fn closest_hits(
        &self,
        rays: &[RayQuery],
    ) -> Result<(Vec<Option<TwoLevelHit>>, GpuTiming), GpuError> {
        let f = f32::from_bits;
        closest_hits(self, &self.kernels, &QUERIES.closest, rays, 5, |w| {
            (w[1] != u32::MAX).then(|| TwoLevelHit {
                t: f(w[0]),
                instance: w[1],
                normal: Vec3::new(f(w[2]), f(w[3]), f(w[4])),
            })
        })
    }
}

/// A mesh's model-space bounding sphere as [`crate::trace::two_level::TwoLevel`] takes it: the
/// centre of its box and the farthest vertex from it.
fn bounds(tris: &[[Vec3; 3]]) -> (Vec3, f32) {
    let (lo, hi) = bounding_box(tris);
    let c = 0.5 * (lo + hi);
    let r = (tris.iter().flatten())
        .map(|v| v.distance(c))
        .fold(0.0f32, f32::max);
    (c, r)
}

impl GpuVisibility for GpuTwoLevel<'_> {
    fn context(&self) -> &GpuContext {
        self.ctx
    }

    fn wgsl(&self, _: u32) -> String {
        [
            include_str!("../../shaders/cwbvh.wgsl"),
            CASTER_HEADER_WGSL,
            include_str!("../../shaders/two_level.wgsl"),
        ]
        .concat()
    }

    fn layout(&self) -> &wgpu::BindGroupLayout {
        self.group.layout()
    }

    fn bind_group(&self) -> wgpu::BindGroup {
        let header = CasterHeaderGpu {
            node_count: self.top_node_count,
            instance_count: self.instance_count,
            _pad: [0; 2],
        };
        let top = &self.top;
        self.group.bind_with(
            self.ctx,
            bytemuck::bytes_of(&header),
            &[
                top.nodes.as_entire_binding(),
                top.order.as_entire_binding(),
                top.placements.as_entire_binding(),
            ],
        )
    }

    fn kernels(&self) -> &Kernels {
        &self.kernels
    }
}
