//! Glossy reflections by field lookup on the GPU (Gaitatzes, Andreadis, Papaioannou,
//! Chrysanthou, WSCG 2010, §4.2 and Figure 9: every reflection ray answered by the visibility
//! fields with an approximate hit point, and by the normal fields with the normal there), with
//! the CPU path's reflection rays ([`crate::render::reflect::reflect_at_points`]).
//!
//! One invocation takes a receiver point and a run of its reflection rays (the mirror ray, or
//! the k² rays of a Phong lobe), builds each from the host's lobe directions and the point's
//! rotation as the CPU does (src/gpu/reflect_rays.rs, shaders/reflect_rays.wgsl), answers it
//! with the lookup WGSL of [`super::FieldAoKernel`] (inter- and intra-object, nearest or
//! interpolated) over every instance the ray meets, keeping the nearest hit as
//! `FieldScene::surface_hit` does, reads the normal of the map and texel the nearest selection
//! reads from the instance's normal field (bound as one extra storage buffer, a texel a word,
//! unpacked as `unpack_normal`), turns it to the world, shades the hit as `shade`, and writes
//! the sum of its kept rays' radiance and their count; the host adds up a point's runs and
//! divides (src/gpu/loop_budget.rs).
//!
//! Deviations from the CPU path: those of [`super::FieldAoKernel`] (f32 sphere tests and entry
//! point, Fibonacci point sets and jittered ray sets refused), instances tried in index order
//! (the host sorts them by entry; the nearest hit is the same, ties resolved alike), and the
//! radiance summed in f32 within an invocation (src/gpu/reflect_rays.rs). Deviation from the
//! paper: it does not give its lobe, shading or lights; ours are the CPU path's
//! (`render::reflect`).

use super::context::{entry, storage_layout_entry, uniform_layout_entry, GpuContext};
use super::field_ao::{intra_terms, selection_code, FieldGpuOptions};
use super::field_binding::FieldBinding;
use super::loop_budget::{weighted_means, Dispatched, COMPLETION_TRIPS};
use super::rays::{receivers, ReceiverGpu};
use super::reflect_rays::{lobe_directions, normal_words, rays_per_point, shading};
use super::shadow_rays::{check_binding, light_records, LightGpu};
use super::{GpuError, GpuTiming};
use crate::field::lookup::LookupOptions;
use crate::field::scene::FieldInstance;
use crate::render::reflect::ReflectOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;
use std::sync::atomic::AtomicU32;
use std::time::{Duration, Instant};

/// Twin of WGSL `Params` (shaders/field_reflect.wgsl): one dispatch of the reflection lookup
/// (Gaitatzes et al., WSCG 2010, §4.2).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct ReflectParamsGpu {
    /// Receiver points in this dispatch.
    point_count: u32,
    /// Reflection rays per point (1 for the mirror, k² for a Phong lobe).
    rays_per_point: u32,
    /// Field instances.
    instance_count: u32,
    /// Invocations per row of the dispatch grid.
    row_stride: u32,
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
    _pad0: u32,
}
const _: () = assert!(std::mem::size_of::<ReflectParamsGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(ReflectParamsGpu, selection) == 16);
const _: () = assert!(std::mem::offset_of!(ReflectParamsGpu, origin_offset) == 32);

/// The kernel's own bindings (group 0; the fields are group 1): params, receivers, output,
/// lobe directions, lights, shading, normal fields.
const PARAMS_BINDING: u32 = 0;
const RECEIVERS_BINDING: u32 = 1;
const OUT_BINDING: u32 = 2;
const LOBE_BINDING: u32 = 3;
const LIGHTS_BINDING: u32 = 4;
const SHADING_BINDING: u32 = 5;
const NORMALS_BINDING: u32 = 6;
/// Storage buffers among them (all but the params).
const KERNEL_STORAGE_BUFFERS: u32 = 6;

/// Field-lookup glossy reflections over a set of field instances and their normal fields,
/// uploaded once (Gaitatzes et al., WSCG 2010, §4.2): its own bindings in group 0 (the normal
/// fields among them), the fields in a `FieldBinding` (src/gpu/field_binding.rs), as
/// [`super::FieldShadowKernel`].
pub struct FieldReflectKernel<'a> {
    ctx: &'a GpuContext,
    pipeline: wgpu::ComputePipeline,
    group_layout: wgpu::BindGroupLayout,
    field: FieldBinding,
    normals: wgpu::Buffer,
    normal_bytes: u64,
    /// Rays per invocation, as last found to fit (`loop_budget::complete_runs`).
    rays_per_invocation: AtomicU32,
    setup: Duration,
    /// Selection and intra-object bias of the lookups (may be changed between calls).
    pub lookup: LookupOptions,
}

impl<'a> FieldReflectKernel<'a> {
    /// Packs and uploads `instances` (their distinct fields and normal fields once each) and
    /// compiles the kernel; `opts` as for [`super::FieldAoKernel::new`].
    ///
    /// Errors: [`GpuError::Invalid`] when an instance has no normal field
    /// ([`FieldInstance::with_normals`]), [`GpuError::TooLarge`] when the normal fields pass
    /// one storage binding, and those of [`super::FieldAoKernel::new`].
    pub fn new(
        ctx: &'a GpuContext,
        instances: &[FieldInstance],
        opts: &FieldGpuOptions,
    ) -> Result<Self, GpuError> {
        let start = Instant::now();
        let words = normal_words(instances)?;
        check_binding::<u32>(ctx, "normal field words", words.len())?;
        let field = FieldBinding::new(
            ctx,
            instances,
            &opts.binding_options(KERNEL_STORAGE_BUFFERS),
        )?;
        let group_layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("field reflect"),
                entries: &[
                    uniform_layout_entry(PARAMS_BINDING),
                    storage_layout_entry(RECEIVERS_BINDING, true),
                    storage_layout_entry(OUT_BINDING, false),
                    storage_layout_entry(LOBE_BINDING, true),
                    storage_layout_entry(LIGHTS_BINDING, true),
                    storage_layout_entry(SHADING_BINDING, true),
                    storage_layout_entry(NORMALS_BINDING, true),
                ],
            });
        let source = field.shader_source(&[
            include_str!("../../shaders/receiver.wgsl"),
            include_str!("../../shaders/loop_budget.wgsl"),
            include_str!("../../shaders/shadow_rays.wgsl"),
            include_str!("../../shaders/reflect_rays.wgsl"),
            include_str!("../../shaders/field_reflect.wgsl"),
        ]);
        let layout = field.pipeline_layout(ctx, &group_layout);
        let pipeline = ctx.compute_pipeline_with_layout(
            "field_reflect",
            &source,
            "reflect_main",
            Some(&layout),
        )?;
        let normals = ctx.storage_buffer("normal fields", bytemuck::cast_slice(&words));
        Ok(FieldReflectKernel {
            ctx,
            pipeline,
            group_layout,
            rays_per_invocation: opts.start_rays_per_invocation(instances.len()),
            field,
            normals,
            normal_bytes: words.len() as u64 * 4,
            setup: start.elapsed(),
            lookup: opts.lookup,
        })
    }

    /// Host time of packing, uploading and compiling in [`Self::new`].
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Bytes of the normal fields on the device (4 a texel: both precisions are held in a
    /// 32-bit word).
    pub fn normal_bytes(&self) -> u64 {
        self.normal_bytes
    }

    /// Rays per invocation the next call starts with (see
    /// [`super::FieldAoKernel::rays_per_invocation`]).
    pub fn rays_per_invocation(&self) -> u32 {
        self.rays_per_invocation
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The reflected radiance at every point (point `i` uses the square samples and rotation
    /// of point index `i` of `rays`), as [`crate::render::reflect::reflect_at_points`]
    /// computes it over a [`crate::field::scene::FieldScene`] of the same instances and lookup
    /// options.
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
        let recv = receivers(points, normals, rays)?;
        let ctx = self.ctx;
        check_binding::<[f32; 4]>(ctx, "lobe directions", lobe.len())?;
        check_binding::<LightGpu>(ctx, "lights", light_records.len())?;
        let lobe_buf = ctx.storage_buffer("lobe directions", bytemuck::cast_slice(&lobe));
        let lights_buf = ctx.storage_buffer("lights", bytemuck::cast_slice(&light_records));
        let shading_buf = ctx.storage_buffer("shading", bytemuck::bytes_of(&shading(opts)));
        let (intra_bias, intra_auto) = intra_terms(self.lookup.intra_bias);
        let rays_n = rays_per_point(rays, opts.gloss);
        let mut params = ReflectParamsGpu {
            rays_per_point: rays_n,
            instance_count: self.field.instance_count(),
            selection: selection_code(self.lookup.selection),
            completion_trips: COMPLETION_TRIPS,
            origin_offset: opts.offset,
            intra_bias,
            intra_auto,
            ..Default::default()
        };
        let (values, kernel, upload) = weighted_means(
            &self.rays_per_invocation,
            rays_n,
            recv.len(),
            0.0,
            |per_invocation, per_point| {
                params.rays_per_invocation = per_invocation;
                params.invocations_per_point = per_point;
                self.run(
                    params,
                    &recv,
                    [&lobe_buf, &lights_buf, &shading_buf],
                    per_point,
                )
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
        mut params: ReflectParamsGpu,
        recv: &[ReceiverGpu],
        [lobe, lights, shading]: [&wgpu::Buffer; 3],
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
                let uniform = ctx.uniform_buffer("reflect params", bytemuck::bytes_of(&params));
                let recv_buf = ctx.storage_buffer("receivers", bytemuck::cast_slice(part));
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("field reflect"),
                    layout: &self.group_layout,
                    entries: &[
                        entry(PARAMS_BINDING, uniform.as_entire_binding()),
                        entry(RECEIVERS_BINDING, recv_buf.as_entire_binding()),
                        entry(OUT_BINDING, out.as_entire_binding()),
                        entry(LOBE_BINDING, lobe.as_entire_binding()),
                        entry(LIGHTS_BINDING, lights.as_entire_binding()),
                        entry(SHADING_BINDING, shading.as_entire_binding()),
                        entry(NORMALS_BINDING, self.normals.as_entire_binding()),
                    ],
                })
            },
        )
    }
}
