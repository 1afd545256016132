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

use super::context::GpuContext;
use super::field_kernel::{FieldGpuOptions, FieldKernel, KernelParamsGpu};
use super::loop_budget::weighted_fractions;
use super::rays::receivers;
use super::shadow_rays::{check_binding, cone_samples, lights, ConeSampleGpu, LightGpu};
use super::{GpuError, GpuTiming};
use crate::field::lookup::LookupOptions;
use crate::field::scene::FieldInstance;
use crate::render::shadow::ShadowOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;
use std::time::{Duration, Instant};

/// The kernel's own inputs (after the shared header's bindings): cone samples, lights.
const OWN_INPUTS: u32 = 2;

/// Field-lookup soft shadows over a set of field instances, uploaded once (Gaitatzes et al.,
/// WSCG 2010, §4.2): its own bindings in group 0, the fields in a `FieldBinding`
/// (src/gpu/field_binding.rs), as [`super::FieldAoKernel`].
pub struct FieldShadowKernel<'a> {
    core: FieldKernel<'a>,
    pipeline: wgpu::ComputePipeline,
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
        let core = FieldKernel::new(ctx, instances, opts, "field shadow", OWN_INPUTS)?;
        let source = core.source(&[
            include_str!("../../shaders/shadow_rays.wgsl"),
            include_str!("../../shaders/field_shadow.wgsl"),
        ]);
        let pipeline = core.pipeline("field_shadow", &source, "shadow_main")?;
        Ok(FieldShadowKernel {
            core,
            pipeline,
            setup: start.elapsed(),
            lookup: opts.lookup,
        })
    }

    /// Moves the instances to `instances`' transforms, the fields staying on the device (the
    /// same fields, instance by instance, as at `new`): a moving rigid object's per-frame cost.
    pub fn place(&self, instances: &[FieldInstance]) -> Result<(), GpuError> {
        self.core.place(instances)
    }

    /// Host time of packing, uploading and compiling in [`Self::new`].
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Rays per invocation the next call starts with (see
    /// [`super::FieldAoKernel::rays_per_invocation`]).
    pub fn rays_per_invocation(&self) -> u32 {
        self.core.rays_per_invocation()
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
        let ctx = self.core.ctx;
        check_binding::<ConeSampleGpu>(ctx, "cone samples", samples.len())?;
        check_binding::<LightGpu>(ctx, "lights", light_records.len())?;
        let samples_buf = ctx.storage_buffer("cone samples", bytemuck::cast_slice(&samples));
        let lights_buf = ctx.storage_buffer("lights", bytemuck::cast_slice(&light_records));
        let cells = samples.len() as u32;
        let rays_n = cells
            .checked_mul(light_records.len() as u32)
            .ok_or_else(|| GpuError::Invalid("shadow rays per point overflow u32".into()))?;
        let mut params = KernelParamsGpu {
            light_count: light_records.len() as u32,
            ..self.core.params(&self.lookup, cells, opts.offset)
        };
        let (values, kernel, upload) = weighted_fractions(
            &self.core.rays_per_invocation,
            rays_n,
            recv.len(),
            |per_invocation, per_point| {
                params.rays_per_invocation = per_invocation;
                params.invocations_per_point = per_point;
                let own = [&samples_buf, &lights_buf];
                self.core
                    .run(&self.pipeline, params, &recv, &own, (per_point, 2))
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
}
