//! The GPU ray-cast reference: an obvhs CWBVH traversed in WGSL (Ylitie, Karras, Laine, HPG
//! 2017) with the watertight triangle test (Woop, Benthin, Wald, JCGT 2013), so that GPU field
//! lookup is compared with GPU ray casting on the same device: any-hit and closest-hit queries,
//! and, as a [`GpuVisibility`], every kind's integrand: vertex AO ([`super::ao`]), soft shadows
//! from spherical lights ([`super::shadows`]) and glossy reflections ([`super::reflections`];
//! Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010, §4.2), on the CPU path's rays.

use super::context::GpuContext;
use super::integrand::{self, timing, Integrand, IntegrandParamsGpu};
use super::shadow_rays::check_binding;
use super::visibility::{GpuVisibility, Kernels, VisibilityGroup};
use super::{GpuError, GpuTiming};
use crate::trace::RayQuery;
use glam::Vec3;
use obvhs::{aabb::Aabb, cwbvh::node::CwBvhNode};
use std::time::{Duration, Instant};

/// The node struct uploaded as is: WGSL reads it as five `vec4<u32>`.
const _: () = assert!(std::mem::size_of::<CwBvhNode>() == 80);

/// Twin of WGSL `Ray` (shaders/ray_queries.wgsl): one query ray.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct RayGpu {
    /// Origin.
    pub origin: [f32; 3],
    /// Smallest hit distance.
    pub tmin: f32,
    /// Direction.
    pub direction: [f32; 3],
    /// Largest hit distance.
    pub tmax: f32,
}
const _: () = assert!(std::mem::size_of::<RayGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(RayGpu, direction) == 16);

/// Twin of WGSL `CasterHeader` (shaders/caster_header.wgsl): the header of every ray-casting
/// visibility (this CWBVH, [`super::GpuTwoLevel`], [`super::RayQueryScene`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct CasterHeaderGpu {
    /// Nodes of the BVH walked first: the world CWBVH's, the top level's (0: nothing to hit).
    pub node_count: u32,
    /// Instances placed (the two levels, ray queries).
    pub instance_count: u32,
    pub _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<CasterHeaderGpu>() == 16);

/// The header's WGSL, before a ray-casting visibility's own.
pub(super) const CASTER_HEADER_WGSL: &str = include_str!("../../shaders/caster_header.wgsl");

/// The any- and closest-hit entries of a ray-casting visibility ([`query_rays`], the rays in
/// place of receivers).
pub(super) struct RayQueries {
    pub any: Integrand,
    pub closest: Integrand,
}

impl RayQueries {
    /// Compiles, on `vis`, these queries and every kind's integrand (AO, shadows,
    /// reflections), so that a visibility's setup time holds its pipelines.
    pub(super) fn precompile(
        &self,
        vis: &dyn GpuVisibility,
        kernels: &Kernels,
    ) -> Result<(), GpuError> {
        for i in [
            &self.any,
            &self.closest,
            &integrand::AO,
            &integrand::SHADOWS,
            &integrand::REFLECTIONS,
        ] {
            kernels.compiled(vis, i)?;
        }
        Ok(())
    }
}

/// A ray-casting visibility's [`RayQueries`]: `sources` are the queries they all share
/// ([`RAY_QUERIES_WGSL`]), then the visibility's own WGSL (its `write_closest`).
pub(super) const fn ray_queries(sources: &'static [&'static str]) -> RayQueries {
    let any = Integrand {
        sources,
        entry: "any_main",
        own: 0,
        slot: 0,
    };
    RayQueries {
        closest: Integrand {
            entry: "closest_main",
            ..any
        },
        any,
    }
}

/// The queries every ray-casting visibility shares (shaders/ray_queries.wgsl).
pub(super) const RAY_QUERIES_WGSL: &str = include_str!("../../shaders/ray_queries.wgsl");

/// The CWBVH's own ray queries (its closest-hit words: shaders/bvh_queries.wgsl).
const QUERIES: RayQueries = ray_queries(&[
    RAY_QUERIES_WGSL,
    include_str!("../../shaders/bvh_queries.wgsl"),
]);

/// Box padding relative to the scene extent, as the CPU tracer pads (`2^-18`), so that the
/// quantised node test stays conservative for the watertight triangle test.
const BOX_PAD_RELATIVE: f32 = 1.0 / (1u32 << 18) as f32;

/// A closest hit found on the GPU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuHit {
    pub t: f32,
    /// Index into the triangles the tracer was built from.
    pub triangle: u32,
}

/// CWBVH ray casting on the GPU over a fixed set of world-space triangles (both windings hit,
/// `tmin <= t <= tmax` inclusive, as [`crate::trace::Tracer`]).
pub struct GpuTracer<'a> {
    ctx: &'a GpuContext,
    /// The header (node count), nodes and triangles, as group 1.
    group: VisibilityGroup,
    node_count: u32,
    kernels: Kernels,
    setup: Duration,
}

impl<'a> GpuTracer<'a> {
    /// Builds the CWBVH (obvhs, `medium_build`, boxes padded) on the host and uploads it.
    pub fn new(ctx: &'a GpuContext, triangles: &[[Vec3; 3]]) -> Result<Self, GpuError> {
        let start = Instant::now();
        // The triangles and the nodes are one storage binding each: refused by name past the
        // adapter's limit (three vec4 a triangle: 2.8 M triangles fill lavapipe's 128 MiB),
        // the triangles before the build, the nodes before the upload.
        let (nodes, tri_data) = packed_cwbvh(ctx, triangles)?;
        let tracer = GpuTracer {
            ctx,
            group: VisibilityGroup::new(
                ctx,
                "cwbvh",
                &[
                    bytemuck::cast_slice(&nodes),
                    bytemuck::cast_slice(&tri_data),
                ],
            ),
            node_count: nodes.len() as u32,
            kernels: Kernels::new(super::loop_budget::DEFAULT_RAYS_PER_INVOCATION),
            setup: Duration::ZERO,
        };
        QUERIES.precompile(&tracer, &tracer.kernels)?;
        Ok(GpuTracer {
            setup: start.elapsed(),
            ..tracer
        })
    }

    /// Host time of the BVH build, upload and shader compilation.
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Whether each ray hits any triangle with `tmin <= t <= tmax`.
    pub fn any_hits(&self, rays: &[RayQuery]) -> Result<(Vec<bool>, GpuTiming), GpuError> {
        any_hits(self, &self.kernels, &QUERIES.any, rays)
    }

    /// The closest hit of each ray with `tmin <= t <= tmax`.
    pub fn closest_hits(
        &self,
        rays: &[RayQuery],
    ) -> Result<(Vec<Option<GpuHit>>, GpuTiming), GpuError> {
        closest_hits(self, &self.kernels, &QUERIES.closest, rays, 2, |w| {
            (w[1] != u32::MAX).then(|| GpuHit {
                t: f32::from_bits(w[0]),
                triangle: w[1],
            })
        })
    }
}

impl GpuVisibility for GpuTracer<'_> {
    fn context(&self) -> &GpuContext {
        self.ctx
    }

    fn wgsl(&self, _: u32) -> String {
        [
            include_str!("../../shaders/cwbvh.wgsl"),
            CASTER_HEADER_WGSL,
            include_str!("../../shaders/bvh.wgsl"),
        ]
        .concat()
    }

    fn layout(&self) -> &wgpu::BindGroupLayout {
        self.group.layout()
    }

    fn bind_group(&self) -> wgpu::BindGroup {
        let header = CasterHeaderGpu {
            node_count: self.node_count,
            ..Default::default()
        };
        self.group.bind(self.ctx, bytemuck::bytes_of(&header))
    }

    fn kernels(&self) -> &Kernels {
        &self.kernels
    }
}

/// The CWBVH of `triangles` as [`GpuTracer`] uploads it (obvhs, the CPU tracer's build, boxes
/// padded by [`BOX_PAD_RELATIVE`] of the triangles' extent): its nodes, and its triangles in BVH
/// order, three `vec4` each (v0 with the original index's bits in w, v1, v2). Refused with
/// [`GpuError::TooLarge`] where either passes one storage binding (the triangles before the
/// build, the nodes after it), and with [`GpuError::Invalid`] for a vertex that is not finite.
pub(super) fn packed_cwbvh(
    ctx: &GpuContext,
    triangles: &[[Vec3; 3]],
) -> Result<(Vec<CwBvhNode>, Vec<[f32; 4]>), GpuError> {
    if triangles.iter().flatten().any(|v| !v.is_finite()) {
        return Err(GpuError::Invalid("triangle vertices must be finite".into()));
    }
    check_binding::<[f32; 4]>(ctx, "triangle vertices", triangles.len() * 3)?;
    let (lo, hi) = bounding_box(triangles);
    let extent = (hi - lo).max_element().max(0.0);
    let pad = glam::Vec3A::splat(BOX_PAD_RELATIVE * extent);
    let boxes: Vec<Aabb> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(glam::Vec3A::from);
            Aabb::new(a.min(b).min(c) - pad, a.max(b).max(c) + pad)
        })
        .collect();
    // The CPU tracer's build: obvhs's PLOC, or the median-split tree where PLOC would take
    // quadratic time (fans, nested or turned copies of a triangle).
    let bvh = crate::trace::bvh_build::build(&boxes);
    check_binding::<CwBvhNode>(ctx, "CWBVH nodes", bvh.nodes.len())?;
    let tri_data = triangle_records(triangles, &bvh.primitive_indices);
    Ok((bvh.nodes, tri_data))
}

/// The box of every vertex of `triangles` (lo, hi).
pub(super) fn bounding_box(triangles: &[[Vec3; 3]]) -> (Vec3, Vec3) {
    triangles.iter().flatten().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    )
}

/// `triangles` in the order `order`, three `vec4` each: v0 with the original index's bits in
/// w, v1, v2.
pub(super) fn triangle_records(triangles: &[[Vec3; 3]], order: &[u32]) -> Vec<[f32; 4]> {
    (order.iter())
        .flat_map(|&i| {
            let [a, b, c] = triangles[i as usize];
            [
                [a.x, a.y, a.z, f32::from_bits(i)],
                b.extend(0.0).to_array(),
                c.extend(0.0).to_array(),
            ]
        })
        .collect()
}

/// One query ray per invocation of `integrand` (a ray-casting visibility's own any- or
/// closest-hit entry) on `vis`, `words` words each, in batches that fit one binding: the query
/// of every ray-casting visibility (the CWBVH, the two levels, ray queries).
pub(super) fn query_rays(
    vis: &dyn GpuVisibility,
    kernels: &Kernels,
    integrand: &Integrand,
    rays: &[RayQuery],
    words: u32,
) -> Result<super::loop_budget::Dispatched, GpuError> {
    let k = kernels.compiled(vis, integrand)?;
    let group = vis.bind_group();
    (k.group).run(
        vis.context(),
        &k.pipeline,
        &[&group],
        IntegrandParamsGpu::default(),
        &ray_records(rays),
        &[],
        (1, words),
    )
}

/// Whether each ray hits, by `any` (an entry of [`query_rays`] writing one word a ray, not 0
/// for a hit).
pub(super) fn any_hits(
    vis: &dyn GpuVisibility,
    kernels: &Kernels,
    any: &Integrand,
    rays: &[RayQuery],
) -> Result<(Vec<bool>, GpuTiming), GpuError> {
    let start = Instant::now();
    let (words, kernel, upload) = query_rays(vis, kernels, any, rays, 1)?;
    let hits = words.into_iter().map(|w| w != 0).collect();
    Ok((hits, timing(kernel, upload, start)))
}

/// The closest hit of each ray by `closest` (an entry of [`query_rays`] writing `words` words a
/// ray), each ray's words read by `hit` (none: a miss).
pub(super) fn closest_hits<H>(
    vis: &dyn GpuVisibility,
    kernels: &Kernels,
    closest: &Integrand,
    rays: &[RayQuery],
    words: u32,
    hit: impl Fn(&[u32]) -> Option<H>,
) -> Result<(Vec<Option<H>>, GpuTiming), GpuError> {
    let start = Instant::now();
    let (w, kernel, upload) = query_rays(vis, kernels, closest, rays, words)?;
    let hits = w.chunks_exact(words as usize).map(hit).collect();
    Ok((hits, timing(kernel, upload, start)))
}

/// The query rays as the WGSL reads them.
fn ray_records(rays: &[RayQuery]) -> Vec<RayGpu> {
    rays.iter()
        .map(|r| RayGpu {
            origin: r.origin.to_array(),
            tmin: r.tmin,
            direction: r.dir.to_array(),
            tmax: r.tmax.min(f32::MAX),
        })
        .collect()
}
