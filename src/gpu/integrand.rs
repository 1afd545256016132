//! The integrand layer of every GPU kernel (Gaitatzes, Andreadis, Papaioannou, Chrysanthou,
//! WSCG 2010: the 2010 kinds' per-point loops on the GPU): a render kind's per-point loop,
//! written once in WGSL against a visibility's queries (src/gpu/visibility.rs), on one bind
//! group 0 ([`KernelGroup`]: the header [`IntegrandParamsGpu`], the receivers, the output
//! words, then the integrand's own inputs from [`FIRST_OWN_BINDING`]). AO
//! (shaders/ao.wgsl: free rays), soft shadows (shaders/shadows.wgsl: weighted unblocked rays)
//! and glossy reflections (shaders/reflections.wgsl: shaded closest hits) run on any
//! [`GpuVisibility`] through [`ao`], [`shadows`] and [`reflections`], on the CPU path's rays,
//! a point's rays spread over several invocations (src/gpu/loop_budget.rs). The direct
//! estimators that cast no ray (SDF cones, AO fields) share the group and its header.

use super::context::{entry, storage_layout_entry, uniform_layout_entry, GpuContext};
use super::loop_budget::{
    free_fractions, weighted_fractions, weighted_means, Dispatched, COMPLETION_TRIPS,
};
use super::rays::{base_directions, receivers, ReceiverGpu};
use super::reflect_rays::{lobe_directions, rays_per_point, shading};
use super::shadow_rays::{check_binding, cone_samples, light_records, lights};
use super::visibility::GpuVisibility;
use super::{GpuError, GpuTiming};
use crate::render::ao::AoOptions;
use crate::render::reflect::ReflectOptions;
use crate::render::shadow::ShadowOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;
use std::time::Instant;

/// Twin of WGSL `Params` (shaders/integrand.wgsl): one dispatch of an integrand.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct IntegrandParamsGpu {
    /// Receiver points (ray queries: rays) in this dispatch.
    pub point_count: u32,
    /// Rays per point (shadows: per light).
    pub rays_per_point: u32,
    /// Invocations per row of the dispatch grid.
    pub row_stride: u32,
    /// Rays one invocation traces.
    pub rays_per_invocation: u32,
    /// Invocations per point.
    pub invocations_per_point: u32,
    /// Trips of the completion loop ([`COMPLETION_TRIPS`]).
    pub completion_trips: u32,
    /// Ray origin offset along the normal.
    pub origin_offset: f32,
    /// AO and cones: the largest hit distance.
    pub tmax: f32,
    /// Shadows: the lights.
    pub light_count: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<IntegrandParamsGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(IntegrandParamsGpu, invocations_per_point) == 16);
const _: () = assert!(std::mem::offset_of!(IntegrandParamsGpu, light_count) == 32);

impl IntegrandParamsGpu {
    /// The header of a call with `rays_per_point` rays per point from origins moved by
    /// `origin_offset`; the dispatch fills in the rest.
    pub fn new(rays_per_point: u32, origin_offset: f32) -> Self {
        IntegrandParamsGpu {
            rays_per_point,
            origin_offset,
            completion_trips: COMPLETION_TRIPS,
            ..Default::default()
        }
    }
}

/// Group 0's shared bindings: the header, the receivers (or a ray query's rays), the words.
const PARAMS_BINDING: u32 = 0;
const RECEIVERS_BINDING: u32 = 1;
const OUT_BINDING: u32 = 2;
/// The first binding of an integrand's own inputs.
pub(crate) const FIRST_OWN_BINDING: u32 = 3;

/// What every kernel's WGSL starts with: the frame, the loop budget, the header.
pub(crate) const HEADER_WGSL: [&str; 3] = [
    include_str!("../../shaders/frame.wgsl"),
    include_str!("../../shaders/loop_budget.wgsl"),
    include_str!("../../shaders/integrand.wgsl"),
];
/// The receivers' record and binding.
pub(crate) const RECEIVER_WGSL: &str = include_str!("../../shaders/receiver.wgsl");

/// One integrand: its WGSL after the header (in order), its entry point, its own read-only
/// storage inputs and the slot of its rays-per-invocation budget in a visibility's
/// [`super::visibility::Kernels`].
pub struct Integrand {
    pub sources: &'static [&'static str],
    pub entry: &'static str,
    pub own: u32,
    pub slot: usize,
}

/// AO: free rays (shaders/ao.wgsl; the base directions at binding 3).
pub(crate) const AO: Integrand = Integrand {
    sources: &[RECEIVER_WGSL, include_str!("../../shaders/ao.wgsl")],
    entry: "ao_main",
    own: 1,
    slot: 0,
};
/// Soft shadows: weighted unblocked rays (shaders/shadows.wgsl; cone samples, lights).
pub(crate) const SHADOWS: Integrand = Integrand {
    sources: &[
        RECEIVER_WGSL,
        include_str!("../../shaders/shadow_rays.wgsl"),
        include_str!("../../shaders/shadows.wgsl"),
    ],
    entry: "shadow_main",
    own: 2,
    slot: 1,
};
/// Glossy reflections: shaded closest hits (shaders/reflections.wgsl; lobe, lights, shading).
pub(crate) const REFLECTIONS: Integrand = Integrand {
    sources: &[
        RECEIVER_WGSL,
        include_str!("../../shaders/shadow_rays.wgsl"),
        include_str!("../../shaders/reflect_rays.wgsl"),
        include_str!("../../shaders/reflections.wgsl"),
    ],
    entry: "reflect_main",
    own: 3,
    slot: 2,
};

/// A kernel's group 0: the header's bindings (params, receivers, output words) and `own`
/// read-only storage inputs from [`FIRST_OWN_BINDING`] on.
pub(crate) struct KernelGroup {
    pub layout: wgpu::BindGroupLayout,
    label: &'static str,
}

impl KernelGroup {
    /// The layout of the shared bindings and `own` read-only storage inputs.
    pub fn new(ctx: &GpuContext, label: &'static str, own: u32) -> KernelGroup {
        let mut entries = vec![
            uniform_layout_entry(PARAMS_BINDING),
            storage_layout_entry(RECEIVERS_BINDING, true),
            storage_layout_entry(OUT_BINDING, false),
        ];
        entries.extend((0..own).map(|i| storage_layout_entry(FIRST_OWN_BINDING + i, true)));
        let layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &entries,
            });
        KernelGroup { layout, label }
    }

    /// Compiles `entry_point` of `source` with this group as 0 and `groups` as 1, 2, ….
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        source: &str,
        entry_point: &str,
        groups: &[&wgpu::BindGroupLayout],
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let mut layouts = vec![Some(&self.layout)];
        layouts.extend(groups.iter().map(|g| Some(*g)));
        let layout = ctx
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(self.label),
                bind_group_layouts: &layouts,
                immediate_size: 0,
            });
        ctx.compute_pipeline_with_layout(self.label, source, entry_point, Some(&layout))
    }

    /// Uploads the records (receivers, or a ray query's rays) batch by batch, dispatches
    /// `threads_per_item` threads per record, each writing `words_per_thread` words, with `own`
    /// bound from [`FIRST_OWN_BINDING`] on and `fixed_groups` as groups 1, 2, …, and reads the
    /// words back, record-major ([`GpuContext::run_batched`]).
    #[allow(clippy::too_many_arguments)]
    pub fn run<T: bytemuck::Pod>(
        &self,
        ctx: &GpuContext,
        pipeline: &wgpu::ComputePipeline,
        fixed_groups: &[&wgpu::BindGroup],
        mut params: IntegrandParamsGpu,
        records: &[T],
        own: &[&wgpu::Buffer],
        shape: (u32, u32),
    ) -> Result<Dispatched, GpuError> {
        ctx.run_batched(
            pipeline,
            fixed_groups,
            records,
            "receiver",
            shape,
            |part, stride, out| {
                params.point_count = part.len() as u32;
                params.row_stride = stride;
                let uniform = ctx.uniform_buffer("kernel params", bytemuck::bytes_of(&params));
                let recv_buf = ctx.storage_buffer("receivers", bytemuck::cast_slice(part));
                let mut entries = vec![
                    entry(PARAMS_BINDING, uniform.as_entire_binding()),
                    entry(RECEIVERS_BINDING, recv_buf.as_entire_binding()),
                    entry(OUT_BINDING, out.as_entire_binding()),
                ];
                entries.extend(
                    own.iter()
                        .zip(FIRST_OWN_BINDING..)
                        .map(|(b, i)| entry(i, b.as_entire_binding())),
                );
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(self.label),
                    layout: &self.layout,
                    entries: &entries,
                })
            },
        )
    }
}

/// The dispatch of `integrand` on `vis` over `recv` with `own` inputs, `words_per_thread`
/// words per invocation, as the split functions of src/gpu/loop_budget.rs call it with
/// (rays per invocation, invocations per point).
fn dispatcher<'a>(
    vis: &'a dyn GpuVisibility,
    integrand: &Integrand,
    params: IntegrandParamsGpu,
    recv: &'a [ReceiverGpu],
    own: &'a [&'a wgpu::Buffer],
    words_per_thread: u32,
) -> Result<impl FnMut(u32, u32) -> Result<Dispatched, GpuError> + 'a, GpuError> {
    let kernel = vis.kernels().compiled(vis, integrand)?;
    let group = vis.bind_group();
    Ok(move |per_invocation: u32, per_point: u32| {
        let params = IntegrandParamsGpu {
            rays_per_invocation: per_invocation,
            invocations_per_point: per_point,
            ..params
        };
        let shape = (per_point, words_per_thread);
        let groups = [&group];
        (kernel.group).run(
            vis.context(),
            &kernel.pipeline,
            &groups,
            params,
            recv,
            own,
            shape,
        )
    })
}

/// Vertex AO on `vis` with the same rays as [`crate::render::ao::ao_at_points`] (point `i`
/// uses the directions of point index `i` of `rays`): the AO integrand (shaders/ao.wgsl).
pub fn ao(
    vis: &dyn GpuVisibility,
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &AoOptions,
) -> Result<(Vec<f32>, GpuTiming), GpuError> {
    ao_with(vis, &AO, points, normals, rays, opts)
}

/// [`ao`] through `integrand` (the AO integrand or a visibility's batched form of it).
pub(crate) fn ao_with(
    vis: &dyn GpuVisibility,
    integrand: &Integrand,
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &AoOptions,
) -> Result<(Vec<f32>, GpuTiming), GpuError> {
    let start = Instant::now();
    let base = base_directions(rays)?;
    let recv = receivers(points, normals, rays)?;
    let ctx = vis.context();
    check_binding::<[f32; 4]>(ctx, "ray directions", base.len())?;
    let dirs = ctx.storage_buffer("ray directions", bytemuck::cast_slice(&base));
    let rays_n = base.len() as u32;
    let params = IntegrandParamsGpu {
        tmax: opts.max_distance.unwrap_or(f32::MAX).min(f32::MAX),
        ..IntegrandParamsGpu::new(rays_n, opts.offset)
    };
    let own = [&dirs];
    let each = dispatcher(vis, integrand, params, &recv, &own, 1)?;
    let budget = vis.kernels().budget(integrand.slot);
    let (ao, kernel, upload) = free_fractions(budget, rays_n, recv.len(), each)?;
    Ok((ao, timing(kernel, upload, start)))
}

/// Soft shadows on `vis`: the light fraction at every point with the same shadow rays as
/// [`crate::render::shadow::shadow_at_points`] (each an occlusion query from the offset origin
/// to the near side of its light), weighted as there (src/gpu/shadow_rays.rs for the f32
/// weights): the shadow integrand (shaders/shadows.wgsl).
pub fn shadows(
    vis: &dyn GpuVisibility,
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &ShadowOptions,
) -> Result<(Vec<f32>, GpuTiming), GpuError> {
    let start = Instant::now();
    let samples = cone_samples(rays)?;
    let light_records = lights(opts);
    let recv = receivers(points, normals, rays)?;
    let ctx = vis.context();
    check_binding::<super::shadow_rays::ConeSampleGpu>(ctx, "cone samples", samples.len())?;
    check_binding::<super::shadow_rays::LightGpu>(ctx, "lights", light_records.len())?;
    let samples_buf = ctx.storage_buffer("cone samples", bytemuck::cast_slice(&samples));
    let lights_buf = ctx.storage_buffer("lights", bytemuck::cast_slice(&light_records));
    let cells = samples.len() as u32;
    let rays_n = cells
        .checked_mul(light_records.len() as u32)
        .ok_or_else(|| GpuError::Invalid("shadow rays per point overflow u32".into()))?;
    let params = IntegrandParamsGpu {
        light_count: light_records.len() as u32,
        ..IntegrandParamsGpu::new(cells, opts.offset)
    };
    let own = [&samples_buf, &lights_buf];
    let each = dispatcher(vis, &SHADOWS, params, &recv, &own, 2)?;
    let budget = vis.kernels().budget(SHADOWS.slot);
    let (values, kernel, upload) = weighted_fractions(budget, rays_n, recv.len(), each)?;
    Ok((values, timing(kernel, upload, start)))
}

/// Glossy reflections on `vis`: the reflected radiance at every point with the same
/// reflection rays as [`crate::render::reflect::reflect_at_points`] (each a closest-hit query
/// from the offset origin, the hit shaded with the visibility's normal), averaged as there
/// (src/gpu/reflect_rays.rs for the f32 sums): the reflection integrand
/// (shaders/reflections.wgsl).
pub fn reflections(
    vis: &dyn GpuVisibility,
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &ReflectOptions,
) -> Result<(Vec<f32>, GpuTiming), GpuError> {
    let start = Instant::now();
    let lobe = lobe_directions(rays, opts.gloss)?;
    let light_records = light_records(&opts.lights);
    let recv = receivers(points, normals, rays)?;
    let ctx = vis.context();
    check_binding::<[f32; 4]>(ctx, "lobe directions", lobe.len())?;
    check_binding::<super::shadow_rays::LightGpu>(ctx, "lights", light_records.len())?;
    let lobe_buf = ctx.storage_buffer("lobe directions", bytemuck::cast_slice(&lobe));
    let lights_buf = ctx.storage_buffer("lights", bytemuck::cast_slice(&light_records));
    let shading_buf = ctx.storage_buffer("shading", bytemuck::bytes_of(&shading(opts)));
    let rays_n = rays_per_point(rays, opts.gloss);
    let params = IntegrandParamsGpu::new(rays_n, opts.offset);
    let own = [&lobe_buf, &lights_buf, &shading_buf];
    let each = dispatcher(vis, &REFLECTIONS, params, &recv, &own, 2)?;
    let budget = vis.kernels().budget(REFLECTIONS.slot);
    let (values, kernel, upload) = weighted_means(budget, rays_n, recv.len(), 0.0, each)?;
    Ok((values, timing(kernel, upload, start)))
}

/// A call's timing from its kernel and upload times and its start.
pub(crate) fn timing(
    kernel: Option<std::time::Duration>,
    upload: std::time::Duration,
    start: Instant,
) -> GpuTiming {
    GpuTiming {
        kernel,
        upload,
        wall: start.elapsed(),
    }
}
