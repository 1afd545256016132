//! The integrand layer of every GPU kernel (Gaitatzes, Andreadis, Papaioannou, Chrysanthou,
//! WSCG 2010: the 2010 kinds' per-point loops on the GPU): a render kind's per-point loop,
//! written once in WGSL against a visibility's queries (src/gpu/visibility.rs), on one bind
//! group 0 ([`KernelGroup`], src/gpu/kernel_group.rs: the header [`IntegrandParamsGpu`], the
//! receivers, the output words, then the integrand's own inputs). AO
//! (shaders/ao.wgsl: free rays), soft shadows (shaders/shadows.wgsl: weighted unblocked rays)
//! and glossy reflections (shaders/reflections.wgsl: shaded closest hits) run on any
//! [`GpuVisibility`] through [`ao`], [`shadows`] and [`reflections`], on the CPU path's rays,
//! a point's rays spread over several invocations (src/gpu/loop_budget.rs). The direct
//! estimators that cast no ray (SDF cones, AO fields) share the group and its header.

pub(crate) use super::kernel_group::{Integrand, IntegrandParamsGpu, KernelGroup, HEADER_WGSL};
use super::loop_budget::{free_fractions, weighted_means, Dispatched};
use super::rays::{base_directions, receivers, ReceiverGpu};
use super::reflect_rays::{lobe_directions, rays_per_point, shading};
use super::shadow_rays::{check_binding, cone_samples, light_records};
use super::visibility::GpuVisibility;
use super::{GpuError, GpuTiming};
use crate::render::ao::AoOptions;
use crate::render::reflect::ReflectOptions;
use crate::render::shadow::ShadowOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;
use std::time::Instant;

/// The receivers' record and binding.
pub(crate) const RECEIVER_WGSL: &str = include_str!("../../shaders/receiver.wgsl");

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

/// The dispatch of `integrand` on `vis` (with `group` as its group 1; `None`: the
/// visibility's own, [`GpuVisibility::bind_group`]) over `recv` with `own` inputs,
/// `words_per_thread` words per invocation (`None`: one a ray, the rays per invocation), as
/// the split functions of src/gpu/loop_budget.rs call it with (rays per invocation,
/// invocations per point).
pub(crate) fn dispatcher<'a>(
    vis: &'a dyn GpuVisibility,
    integrand: &Integrand,
    group: Option<wgpu::BindGroup>,
    params: IntegrandParamsGpu,
    recv: &'a [ReceiverGpu],
    own: &'a [&'a wgpu::Buffer],
    words_per_thread: Option<u32>,
) -> Result<impl FnMut(u32, u32) -> Result<Dispatched, GpuError> + 'a, GpuError> {
    let kernel = vis.kernels().compiled(vis, integrand)?;
    let group = group.unwrap_or_else(|| vis.bind_group());
    Ok(move |per_invocation: u32, per_point: u32| {
        let params = IntegrandParamsGpu {
            rays_per_invocation: per_invocation,
            invocations_per_point: per_point,
            ..params
        };
        let shape = (per_point, words_per_thread.unwrap_or(per_invocation));
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
    let each = dispatcher(vis, integrand, None, params, &recv, &own, Some(1))?;
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
    let light_records = light_records(&opts.lights);
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
    let params = IntegrandParamsGpu::new(rays_n, opts.offset);
    let own = [&samples_buf, &lights_buf];
    let each = dispatcher(vis, &SHADOWS, None, params, &recv, &own, Some(2))?;
    let budget = vis.kernels().budget(SHADOWS.slot);
    let (values, kernel, upload) = weighted_means(budget, rays_n, recv.len(), 1.0, each)?;
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
    let each = dispatcher(vis, &REFLECTIONS, None, params, &recv, &own, Some(2))?;
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
