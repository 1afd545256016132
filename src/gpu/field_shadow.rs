//! Soft shadows from spherical lights by field lookup on the GPU (Gaitatzes, Andreadis,
//! Papaioannou, Chrysanthou, WSCG 2010, §4.2: every shadow ray a lookup in the visibility
//! fields), with the CPU path's shadow rays ([`crate::render::shadow::shadow_at_points`]).
//!
//! One invocation takes a receiver point and a run of its shadow rays (all lights' k² rays,
//! light-major), builds each ray from the host's disk samples and the point's rotation as the
//! CPU does (src/gpu/shadow_rays.rs, shaders/shadow_rays.wgsl), answers it with the same WGSL
//! lookup as [`super::FieldAoKernel`] (inter- and intra-object, nearest or interpolated) over
//! the segment from the offset origin to the ray's own far end, the near side of its light, as
//! `FieldScene::occluded_many_to` does, and writes the weight of its unblocked rays and of all
//! its rays; the host adds up a point's runs and divides (src/gpu/loop_budget.rs).
//!
//! Deviations from the CPU path: those of [`super::FieldAoKernel`] (f32 sphere tests and entry
//! point, instances in index order, Fibonacci point sets and jittered ray sets refused), and the
//! weights computed and summed in f32 (src/gpu/shadow_rays.rs). Deviation from the paper: it
//! samples "stratified points on each spherical light" without saying how; we sample the cone
//! each light subtends, as the CPU path does.

use super::context::{entry, storage_layout_entry, uniform_layout_entry, GpuContext};
use super::field_ao::{intra_terms, selection_code, FieldGpuOptions};
use super::field_binding::FieldBinding;
use super::loop_budget::{weighted_fractions, Dispatched, COMPLETION_TRIPS};
use super::rays::{receivers, ReceiverGpu};
use super::shadow_rays::{check_binding, cone_samples, lights, ConeSampleGpu, LightGpu};
use super::{GpuError, GpuTiming};
use crate::field::lookup::LookupOptions;
use crate::field::scene::FieldInstance;
use crate::render::shadow::ShadowOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;
use std::sync::atomic::AtomicU32;
use std::time::{Duration, Instant};

/// Twin of WGSL `Params` (shaders/field_shadow.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadowParamsGpu {
    /// Receiver points in this dispatch.
    point_count: u32,
    /// Samples per light (k²).
    cells: u32,
    /// Lights.
    light_count: u32,
    /// Invocations per row of the dispatch grid.
    row_stride: u32,
    /// Field instances.
    instance_count: u32,
    /// Selection (0 nearest, 1 interpolated).
    selection: u32,
    /// Rays one invocation traces.
    rays_per_invocation: u32,
    /// Invocations per point.
    invocations_per_point: u32,
    /// Trips of the completion loop ([`COMPLETION_TRIPS`]).
    completion_trips: u32,
    /// Ray origin offset along the normal.
    origin_offset: f32,
    /// Intra-object bias: a fraction of 2R, or the scale of the field's own tolerance.
    intra_bias: f32,
    /// 1 when `intra_bias` scales the field's own tolerance, else 0.
    intra_auto: u32,
}
const _: () = assert!(std::mem::size_of::<ShadowParamsGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(ShadowParamsGpu, instance_count) == 16);
const _: () = assert!(std::mem::offset_of!(ShadowParamsGpu, completion_trips) == 32);

/// The kernel's own bindings (group 0; the fields are group 1): params, receivers, output,
/// cone samples, lights.
const PARAMS_BINDING: u32 = 0;
const RECEIVERS_BINDING: u32 = 1;
const OUT_BINDING: u32 = 2;
const SAMPLES_BINDING: u32 = 3;
const LIGHTS_BINDING: u32 = 4;
/// Storage buffers among them (receivers, output, samples, lights).
const KERNEL_STORAGE_BUFFERS: u32 = 4;

/// Field-lookup soft shadows over a set of field instances, uploaded once (Gaitatzes et al.,
/// WSCG 2010, §4.2): its own bindings in group 0, the fields in a `FieldBinding`
/// (src/gpu/field_binding.rs), as [`super::FieldAoKernel`].
pub struct FieldShadowKernel<'a> {
    ctx: &'a GpuContext,
    pipeline: wgpu::ComputePipeline,
    group_layout: wgpu::BindGroupLayout,
    field: FieldBinding,
    /// Rays per invocation, as last found to fit (`loop_budget::complete_runs`).
    rays_per_invocation: AtomicU32,
    setup: Duration,
    /// Selection and intra-object bias of the lookups (may be changed between calls).
    pub lookup: LookupOptions,
}

impl<'a> FieldShadowKernel<'a> {
    /// Packs and uploads `instances` (their distinct fields once each) and compiles the kernel;
    /// `opts` as for [`super::FieldAoKernel::new`].
    pub fn new(
        ctx: &'a GpuContext,
        instances: &[FieldInstance],
        opts: &FieldGpuOptions,
    ) -> Result<Self, GpuError> {
        let start = Instant::now();
        let field = FieldBinding::new(
            ctx,
            instances,
            &opts.binding_options(KERNEL_STORAGE_BUFFERS),
        )?;
        let group_layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("field shadow"),
                entries: &[
                    uniform_layout_entry(PARAMS_BINDING),
                    storage_layout_entry(RECEIVERS_BINDING, true),
                    storage_layout_entry(OUT_BINDING, false),
                    storage_layout_entry(SAMPLES_BINDING, true),
                    storage_layout_entry(LIGHTS_BINDING, true),
                ],
            });
        let source = field.shader_source(&[
            include_str!("../../shaders/receiver.wgsl"),
            include_str!("../../shaders/loop_budget.wgsl"),
            include_str!("../../shaders/shadow_rays.wgsl"),
            include_str!("../../shaders/field_shadow.wgsl"),
        ]);
        let layout = field.pipeline_layout(ctx, &group_layout);
        let pipeline = ctx.compute_pipeline_with_layout(
            "field_shadow",
            &source,
            "shadow_main",
            Some(&layout),
        )?;
        Ok(FieldShadowKernel {
            ctx,
            pipeline,
            group_layout,
            rays_per_invocation: opts.start_rays_per_invocation(instances.len()),
            field,
            setup: start.elapsed(),
            lookup: opts.lookup,
        })
    }

    /// Host time of packing, uploading and compiling in [`Self::new`].
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Rays per invocation the next call starts with (see
    /// [`super::FieldAoKernel::rays_per_invocation`]).
    pub fn rays_per_invocation(&self) -> u32 {
        self.rays_per_invocation
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The light fraction at every point (point `i` uses the square samples and rotation of
    /// point index `i` of `rays`), as [`crate::render::shadow::shadow_at_points`] computes it
    /// over a [`crate::field::scene::FieldScene`] of the same instances and lookup options.
    pub fn light_fractions(
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
        let ctx = self.ctx;
        check_binding::<ConeSampleGpu>(ctx, "cone samples", samples.len())?;
        check_binding::<LightGpu>(ctx, "lights", light_records.len())?;
        let samples_buf = ctx.storage_buffer("cone samples", bytemuck::cast_slice(&samples));
        let lights_buf = ctx.storage_buffer("lights", bytemuck::cast_slice(&light_records));
        let (intra_bias, intra_auto) = intra_terms(self.lookup.intra_bias);
        let cells = samples.len() as u32;
        let rays_n = cells
            .checked_mul(light_records.len() as u32)
            .ok_or_else(|| GpuError::Invalid("shadow rays per point overflow u32".into()))?;
        let mut params = ShadowParamsGpu {
            cells,
            light_count: light_records.len() as u32,
            instance_count: self.field.instance_count(),
            selection: selection_code(self.lookup.selection),
            completion_trips: COMPLETION_TRIPS,
            origin_offset: opts.offset,
            intra_bias,
            intra_auto,
            ..Default::default()
        };
        let (values, kernel, upload) = weighted_fractions(
            &self.rays_per_invocation,
            rays_n,
            recv.len(),
            |per_invocation, per_point| {
                params.rays_per_invocation = per_invocation;
                params.invocations_per_point = per_point;
                self.run(params, &recv, (&samples_buf, &lights_buf), per_point)
            },
        )?;
        Ok((
            values,
            GpuTiming {
                kernel,
                upload,
                wall: start.elapsed(),
            },
        ))
    }

    /// Dispatches `per_point` invocations per receiver, two output words each, in batches
    /// ([`GpuContext::run_batched`]), with the fields bound as their own group.
    fn run(
        &self,
        mut params: ShadowParamsGpu,
        recv: &[ReceiverGpu],
        (samples, lights): (&wgpu::Buffer, &wgpu::Buffer),
        per_point: u32,
    ) -> Result<Dispatched, GpuError> {
        let ctx = self.ctx;
        let field_group = [self.field.bind_group()];
        ctx.run_batched(
            &self.pipeline,
            &field_group,
            recv,
            "receiver",
            (per_point, 2),
            |part, stride, out| {
                params.point_count = part.len() as u32;
                params.row_stride = stride;
                let uniform = ctx.uniform_buffer("shadow params", bytemuck::bytes_of(&params));
                let recv_buf = ctx.storage_buffer("receivers", bytemuck::cast_slice(part));
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("field shadow"),
                    layout: &self.group_layout,
                    entries: &[
                        entry(PARAMS_BINDING, uniform.as_entire_binding()),
                        entry(RECEIVERS_BINDING, recv_buf.as_entire_binding()),
                        entry(OUT_BINDING, out.as_entire_binding()),
                        entry(SAMPLES_BINDING, samples.as_entire_binding()),
                        entry(LIGHTS_BINDING, lights.as_entire_binding()),
                    ],
                })
            },
        )
    }
}
