//! The GPU ray-cast reference: an obvhs CWBVH traversed in WGSL (Ylitie, Karras, Laine, HPG
//! 2017) with the watertight triangle test (Woop, Benthin, Wald, JCGT 2013), so that GPU field
//! lookup is compared with GPU ray casting on the same device: any-hit and closest-hit queries,
//! vertex AO ([`GpuTracer::ao`]), soft shadows from spherical lights ([`GpuTracer::shadows`])
//! and glossy reflections ([`GpuTracer::reflections`]; Gaitatzes, Andreadis, Papaioannou,
//! Chrysanthou, WSCG 2010, §4.2), on the CPU path's rays.

use super::context::{entry, GpuContext};
use super::loop_budget::{
    free_fractions, weighted_fractions, weighted_means, Dispatched, COMPLETION_TRIPS,
};
use super::rays::{base_directions, receivers};
use super::reflect_rays::{lobe_directions, rays_per_point, shading};
use super::shadow_rays::{check_binding, cone_samples, light_records, lights};
use super::{GpuError, GpuTiming};
use crate::render::ao::AoOptions;
use crate::render::reflect::ReflectOptions;
use crate::render::shadow::ShadowOptions;
use crate::sampling::rays::RaySet;
use crate::trace::RayQuery;
use glam::Vec3;
use obvhs::{aabb::Aabb, cwbvh::builder::build_cwbvh, cwbvh::node::CwBvhNode, BvhBuildParams};
use std::sync::atomic::AtomicU32;
use std::time::{Duration, Instant};

/// The node struct uploaded as is: WGSL reads it as five `vec4<u32>`.
const _: () = assert!(std::mem::size_of::<CwBvhNode>() == 80);

/// Twin of WGSL `Ray` (shaders/bvh.wgsl): one query ray.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct RayGpu {
    /// Origin.
    origin: [f32; 3],
    /// Smallest hit distance.
    tmin: f32,
    /// Direction.
    direction: [f32; 3],
    /// Largest hit distance.
    tmax: f32,
}
const _: () = assert!(std::mem::size_of::<RayGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(RayGpu, direction) == 16);

/// Twin of WGSL `Params` (shaders/bvh.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct TraceParamsGpu {
    /// Rays (or receiver points for AO) in this dispatch.
    ray_count: u32,
    /// AO: rays per point (the base directions); reflections: reflection rays per point.
    rays_per_point: u32,
    /// Invocations per row of the dispatch grid.
    row_stride: u32,
    /// CWBVH nodes (0: an empty scene).
    node_count: u32,
    /// AO, shadows, reflections: ray origin offset along the normal.
    origin_offset: f32,
    /// AO: largest hit distance.
    tmax: f32,
    /// Shadows: lights.
    light_count: u32,
    /// Shadows: samples per light (k²).
    cells: u32,
    /// AO, shadows, reflections: rays one invocation traces.
    rays_per_invocation: u32,
    /// AO, shadows, reflections: invocations per point.
    invocations_per_point: u32,
    /// AO, shadows, reflections: trips of the completion loop ([`COMPLETION_TRIPS`]).
    completion_trips: u32,
    _pad2: u32,
}
const _: () = assert!(std::mem::size_of::<TraceParamsGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(TraceParamsGpu, origin_offset) == 16);
const _: () = assert!(std::mem::offset_of!(TraceParamsGpu, light_count) == 24);
const _: () = assert!(std::mem::offset_of!(TraceParamsGpu, rays_per_invocation) == 32);

/// Binding of the query rays (any / closest hit) in shaders/bvh.wgsl.
const RAYS_BINDING: u32 = 3;
/// Binding of the AO base directions in shaders/bvh.wgsl.
const DIRS_BINDING: u32 = 5;
/// Binding of the AO and shadow receivers in shaders/bvh.wgsl.
const RECEIVERS_BINDING: u32 = 6;
/// Bindings of the shadow kernel's cone samples and lights in shaders/bvh_shadow.wgsl.
const SAMPLES_BINDING: u32 = 7;
/// Binding of the lights (shadows and reflections) in shaders/bvh_shadow.wgsl.
const LIGHTS_BINDING: u32 = 8;
/// Bindings of the reflection kernel's lobe directions and shading in shaders/bvh_reflect.wgsl.
const LOBE_BINDING: u32 = 9;
const SHADING_BINDING: u32 = 10;

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
    nodes: wgpu::Buffer,
    tris: wgpu::Buffer,
    node_count: u32,
    any: wgpu::ComputePipeline,
    closest: wgpu::ComputePipeline,
    ao: wgpu::ComputePipeline,
    shadow: wgpu::ComputePipeline,
    reflect: wgpu::ComputePipeline,
    /// Rays per AO invocation, as last found to fit (`loop_budget::free_fractions`).
    rays_per_invocation: AtomicU32,
    /// Rays per shadow invocation, as last found to fit (`loop_budget::weighted_fractions`).
    shadow_rays_per_invocation: AtomicU32,
    /// Rays per reflection invocation, as last found to fit (`loop_budget::weighted_means`).
    reflect_rays_per_invocation: AtomicU32,
    setup: Duration,
}

impl<'a> GpuTracer<'a> {
    /// Builds the CWBVH (obvhs, `medium_build`, boxes padded) on the host and uploads it.
    pub fn new(ctx: &'a GpuContext, triangles: &[[Vec3; 3]]) -> Result<Self, GpuError> {
        let start = Instant::now();
        if triangles.iter().flatten().any(|v| !v.is_finite()) {
            return Err(GpuError::Invalid("triangle vertices must be finite".into()));
        }
        // The triangles and the nodes are one storage binding each: refused by name past the
        // adapter's limit (three vec4 a triangle: 2.8 M triangles fill lavapipe's 128 MiB),
        // the triangles before the build, the nodes before the upload.
        check_binding::<[f32; 4]>(ctx, "triangle vertices", triangles.len() * 3)?;
        let (lo, hi) = triangles.iter().flatten().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        let extent = (hi - lo).max_element().max(0.0);
        let pad = glam::Vec3A::splat(BOX_PAD_RELATIVE * extent);
        let boxes: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(glam::Vec3A::from);
                Aabb::new(a.min(b).min(c) - pad, a.max(b).max(c) + pad)
            })
            .collect();
        let bvh = if boxes.is_empty() {
            obvhs::cwbvh::CwBvh::default()
        } else {
            build_cwbvh(
                &boxes,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            )
        };
        check_binding::<CwBvhNode>(ctx, "CWBVH nodes", bvh.nodes.len())?;
        let mut tri_data: Vec<[f32; 4]> = Vec::with_capacity(bvh.primitive_indices.len() * 3);
        for &i in &bvh.primitive_indices {
            let [a, b, c] = triangles[i as usize];
            tri_data.push([a.x, a.y, a.z, f32::from_bits(i)]);
            tri_data.push(b.extend(0.0).to_array());
            tri_data.push(c.extend(0.0).to_array());
        }
        let source = [
            include_str!("../../shaders/frame.wgsl"),
            include_str!("../../shaders/receiver.wgsl"),
            include_str!("../../shaders/loop_budget.wgsl"),
            include_str!("../../shaders/bvh.wgsl"),
            include_str!("../../shaders/shadow_rays.wgsl"),
            include_str!("../../shaders/bvh_shadow.wgsl"),
            include_str!("../../shaders/reflect_rays.wgsl"),
            include_str!("../../shaders/bvh_reflect.wgsl"),
        ]
        .concat();
        Ok(GpuTracer {
            ctx,
            nodes: ctx.storage_buffer("cwbvh nodes", bytemuck::cast_slice(&bvh.nodes)),
            tris: ctx.storage_buffer("triangles", bytemuck::cast_slice(&tri_data)),
            node_count: bvh.nodes.len() as u32,
            any: ctx.compute_pipeline("bvh_any", &source, "any_main")?,
            closest: ctx.compute_pipeline("bvh_closest", &source, "closest_main")?,
            ao: ctx.compute_pipeline("bvh_ao", &source, "ao_main")?,
            shadow: ctx.compute_pipeline("bvh_shadow", &source, "shadow_main")?,
            reflect: ctx.compute_pipeline("bvh_reflect", &source, "reflect_main")?,
            rays_per_invocation: AtomicU32::new(super::loop_budget::DEFAULT_RAYS_PER_INVOCATION),
            shadow_rays_per_invocation: AtomicU32::new(
                super::loop_budget::DEFAULT_RAYS_PER_INVOCATION,
            ),
            reflect_rays_per_invocation: AtomicU32::new(
                super::loop_budget::DEFAULT_RAYS_PER_INVOCATION,
            ),
            setup: start.elapsed(),
        })
    }

    /// Host time of the BVH build, upload and shader compilation.
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Whether each ray hits any triangle with `tmin <= t <= tmax`.
    pub fn any_hits(&self, rays: &[RayQuery]) -> Result<(Vec<bool>, GpuTiming), GpuError> {
        let start = Instant::now();
        let (words, kernel, upload) = self.dispatch(
            &self.any,
            (&ray_records(rays), RAYS_BINDING),
            (1, 1),
            &[],
            Default::default(),
        )?;
        let hits = words.into_iter().map(|w| w != 0).collect();
        Ok((hits, timing(kernel, upload, start)))
    }

    /// The closest hit of each ray with `tmin <= t <= tmax`.
    pub fn closest_hits(
        &self,
        rays: &[RayQuery],
    ) -> Result<(Vec<Option<GpuHit>>, GpuTiming), GpuError> {
        let start = Instant::now();
        let (words, kernel, upload) = self.dispatch(
            &self.closest,
            (&ray_records(rays), RAYS_BINDING),
            (1, 2),
            &[],
            Default::default(),
        )?;
        let hits = words
            .chunks_exact(2)
            .map(|w| {
                (w[1] != u32::MAX).then(|| GpuHit {
                    t: f32::from_bits(w[0]),
                    triangle: w[1],
                })
            })
            .collect();
        Ok((hits, timing(kernel, upload, start)))
    }

    /// Vertex AO by ray casting with the same rays as [`crate::render::ao::ao_at_points`].
    /// A point's rays are spread over several invocations, as in
    /// [`super::FieldAoKernel::ao`].
    pub fn ao(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        let start = Instant::now();
        let base = base_directions(rays)?;
        let recv = receivers(points, normals, rays)?;
        let tmax = opts.max_distance.unwrap_or(f32::MAX).min(f32::MAX);
        let rays_n = base.len() as u32;
        let (ao, kernel, upload) = free_fractions(
            &self.rays_per_invocation,
            rays_n,
            recv.len(),
            |per_invocation, per_point| {
                let params = TraceParamsGpu {
                    rays_per_point: rays_n,
                    origin_offset: opts.offset,
                    tmax,
                    rays_per_invocation: per_invocation,
                    invocations_per_point: per_point,
                    completion_trips: COMPLETION_TRIPS,
                    ..Default::default()
                };
                let records = (&recv[..], RECEIVERS_BINDING);
                let dirs = [(DIRS_BINDING, bytemuck::cast_slice(&base))];
                self.dispatch(&self.ao, records, (per_point, 1), &dirs, params)
            },
        )?;
        Ok((ao, timing(kernel, upload, start)))
    }

    /// Soft shadows by ray casting: the light fraction at every point with the same shadow
    /// rays as [`crate::render::shadow::shadow_at_points`] (each an any-hit query from the
    /// offset origin to the near side of its light), weighted as there (src/gpu/shadow_rays.rs
    /// for the f32 weights). A point's rays are spread over several invocations, as in
    /// [`Self::ao`].
    pub fn shadows(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        rays: &RaySet,
        opts: &ShadowOptions,
    ) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        let start = Instant::now();
        let samples = cone_samples(rays)?;
        let light_records = lights(opts);
        let recv = receivers(points, normals, rays)?;
        let cells = samples.len() as u32;
        let rays_n = cells
            .checked_mul(light_records.len() as u32)
            .ok_or_else(|| GpuError::Invalid("shadow rays per point overflow u32".into()))?;
        let (values, kernel, upload) = weighted_fractions(
            &self.shadow_rays_per_invocation,
            rays_n,
            recv.len(),
            |per_invocation, per_point| {
                let params = TraceParamsGpu {
                    origin_offset: opts.offset,
                    light_count: light_records.len() as u32,
                    cells,
                    rays_per_invocation: per_invocation,
                    invocations_per_point: per_point,
                    completion_trips: COMPLETION_TRIPS,
                    ..Default::default()
                };
                let records = (&recv[..], RECEIVERS_BINDING);
                let extra = [
                    (SAMPLES_BINDING, bytemuck::cast_slice(&samples)),
                    (LIGHTS_BINDING, bytemuck::cast_slice(&light_records)),
                ];
                self.dispatch(&self.shadow, records, (per_point, 2), &extra, params)
            },
        )?;
        Ok((values, timing(kernel, upload, start)))
    }

    /// Glossy reflections by ray casting: the reflected radiance at every point with the same
    /// reflection rays as [`crate::render::reflect::reflect_at_points`] (each a closest-hit
    /// query from the offset origin, the hit shaded with the triangle's unit geometric normal
    /// as the CPU tracer's `Hit::normal`), averaged as there (src/gpu/reflect_rays.rs for the
    /// f32 sums). A point's rays are spread over several invocations, as in [`Self::ao`].
    pub fn reflections(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        rays: &RaySet,
        opts: &ReflectOptions,
    ) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        let start = Instant::now();
        let lobe = lobe_directions(rays, opts.gloss)?;
        let light_records = light_records(&opts.lights);
        let shading = shading(opts);
        let recv = receivers(points, normals, rays)?;
        let rays_n = rays_per_point(rays, opts.gloss);
        let (values, kernel, upload) = weighted_means(
            &self.reflect_rays_per_invocation,
            rays_n,
            recv.len(),
            0.0,
            |per_invocation, per_point| {
                let params = TraceParamsGpu {
                    rays_per_point: rays_n,
                    origin_offset: opts.offset,
                    rays_per_invocation: per_invocation,
                    invocations_per_point: per_point,
                    completion_trips: COMPLETION_TRIPS,
                    ..Default::default()
                };
                let records = (&recv[..], RECEIVERS_BINDING);
                let extra = [
                    (LOBE_BINDING, bytemuck::cast_slice(&lobe)),
                    (LIGHTS_BINDING, bytemuck::cast_slice(&light_records)),
                    (SHADING_BINDING, bytemuck::bytes_of(&shading)),
                ];
                self.dispatch(&self.reflect, records, (per_point, 2), &extra, params)
            },
        )?;
        Ok((values, timing(kernel, upload, start)))
    }

    /// Dispatches `threads_per_item` threads per record (`records`: the records and their
    /// binding), each writing `words_per_thread` words, and reads the words back, record-major;
    /// records go in batches small enough for their buffer and the output to fit one binding
    /// each. `shared` are the buffers every batch binds (binding, bytes). `params` gives
    /// everything but the batch's record count and the dispatch row (set here).
    fn dispatch<T: bytemuck::Pod>(
        &self,
        pipeline: &wgpu::ComputePipeline,
        (records, records_binding): (&[T], u32),
        shape: (u32, u32),
        shared: &[(u32, &[u8])],
        mut params: TraceParamsGpu,
    ) -> Result<Dispatched, GpuError> {
        let ctx = self.ctx;
        let max_binding = ctx.max_binding();
        for &(binding, bytes) in shared {
            let need = bytes.len() as u64;
            if need > max_binding {
                return Err(GpuError::TooLarge {
                    what: format!("the buffer of binding {binding} (ray directions or samples)"),
                    need,
                    limit: max_binding,
                    limit_name: "max_storage_buffer_binding_size",
                });
            }
        }
        let shared_bufs: Vec<(u32, wgpu::Buffer)> = shared
            .iter()
            .map(|&(binding, bytes)| (binding, ctx.storage_buffer("shared", bytes)))
            .collect();
        ctx.run_batched(pipeline, &[], records, "ray", shape, |part, stride, out| {
            params.ray_count = part.len() as u32;
            params.row_stride = stride;
            params.node_count = self.node_count;
            let uniform = ctx.uniform_buffer("trace params", bytemuck::bytes_of(&params));
            let records = ctx.storage_buffer("records", bytemuck::cast_slice(part));
            let mut entries = vec![
                entry(0, uniform.as_entire_binding()),
                entry(1, self.nodes.as_entire_binding()),
                entry(2, self.tris.as_entire_binding()),
                entry(records_binding, records.as_entire_binding()),
                entry(4, out.as_entire_binding()),
            ];
            for (binding, b) in &shared_bufs {
                entries.push(entry(*binding, b.as_entire_binding()));
            }
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("trace"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            })
        })
    }
}

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

fn timing(kernel: Option<Duration>, upload: Duration, start: Instant) -> GpuTiming {
    GpuTiming {
        kernel,
        upload,
        wall: start.elapsed(),
    }
}
