//! What every field kernel shares (Gaitatzes et al., WSCG 2008 Algorithm 2 and WSCG 2010 on the
//! GPU): the options ([`FieldGpuOptions`]), the parameter header ([`KernelParamsGpu`], twin of
//! WGSL `Params` in shaders/field_kernel.wgsl), and the skeleton ([`FieldKernel`]): the fields
//! in a [`FieldBinding`] (group 1), the kernel's own group 0 (params, receivers and output
//! words at bindings 0-2, then the kernel's own read-only inputs from [`FIRST_OWN_BINDING`]),
//! the shader source with the lookup's WGSL and the shared header, the rays-per-invocation
//! budget, and one batched dispatch. Each quantity (`field_ao.rs`, `field_shadow.rs`,
//! `field_reflect.rs`) supplies only its inputs, its ray loop in WGSL and how its output words
//! become values (src/gpu/loop_budget.rs). The group-0 part alone ([`KernelGroup`], the WGSL
//! of [`HEADER_WGSL`]) also serves the per-object peers' kernels, which bind no field.

use super::context::{entry, storage_layout_entry, uniform_layout_entry, GpuContext};
use super::field_binding::{FieldBinding, FieldBindingOptions, FieldLayout};
use super::loop_budget::{Dispatched, COMPLETION_TRIPS};
use super::rays::ReceiverGpu;
use super::GpuError;
use crate::field::lookup::{IntraBias, LookupOptions};
use crate::field::scene::FieldInstance;
use crate::field::Selection;
use std::sync::atomic::AtomicU32;

/// Options of the field kernels ([`super::FieldAoKernel`], [`super::FieldShadowKernel`],
/// [`super::FieldReflectKernel`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldGpuOptions {
    pub lookup: LookupOptions,
    pub layout: FieldLayout,
    /// Largest window in bytes (storage layout); `None`: the adapter's binding limit. Smaller
    /// windows only serve to test the windowing.
    pub window_bytes: Option<u64>,
    /// Most rays one invocation traces (a point's rays are spread over several invocations);
    /// divided by the instance count to start with, then halved while the driver cuts
    /// invocations short (src/gpu/loop_budget.rs).
    pub rays_per_invocation: u32,
    /// Largest texture depth (texture layout); `None`: the adapter's
    /// `max_texture_dimension_3d`. Smaller depths only serve to test the tiling.
    pub max_texture_depth: Option<u32>,
    /// AO kernel: cull each round of rays against the world spheres and answer only the rays
    /// that meet one, shared over the workgroup (WGSL `ao_main`, the default); `false`: every
    /// invocation answers its own rays (`ao_main_direct`, kept for comparison; the answers are
    /// the same). See docs/gpu.md, "Field kernel speed on lavapipe".
    pub queue_rays: bool,
    /// Read each field's owner table (the CPU's `SpherePoints::nearest` table) and texel table
    /// on the device before the ring search and the concentric map, which remain for the cells
    /// the tables leave open (the default); `false`: the ring search and the map alone. The
    /// same map and texel but for f32 near-ties (docs/gpu.md, "Field kernel speed on
    /// lavapipe").
    pub lookup_tables: bool,
}

impl FieldGpuOptions {
    /// The field binding of a kernel with these options and `kernel_storage_buffers` storage
    /// buffers of its own (every field kernel binds its fields this way).
    pub(super) fn binding_options(&self, kernel_storage_buffers: u32) -> FieldBindingOptions {
        FieldBindingOptions {
            layout: self.layout,
            window_bytes: self.window_bytes,
            max_texture_depth: self.max_texture_depth,
            kernel_storage_buffers,
            lookup_tables: self.lookup_tables,
        }
    }

    /// The rays one invocation starts with over `instances` instances: `rays_per_invocation`
    /// shared among them, at least 1.
    pub(super) fn start_rays_per_invocation(&self, instances: usize) -> AtomicU32 {
        AtomicU32::new((self.rays_per_invocation / instances.max(1) as u32).max(1))
    }
}

impl Default for FieldGpuOptions {
    fn default() -> Self {
        FieldGpuOptions {
            lookup: LookupOptions::default(),
            layout: FieldLayout::StorageBuffers,
            window_bytes: None,
            rays_per_invocation: super::loop_budget::DEFAULT_RAYS_PER_INVOCATION,
            max_texture_depth: None,
            queue_rays: true,
            lookup_tables: true,
        }
    }
}

/// Twin of WGSL `Params` (shaders/field_kernel.wgsl): one dispatch of a field kernel.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct KernelParamsGpu {
    /// Receiver points in this dispatch.
    pub point_count: u32,
    /// Rays per point (shadows: per light).
    pub rays_per_point: u32,
    /// Field instances.
    pub instance_count: u32,
    /// Invocations per row of the dispatch grid.
    pub row_stride: u32,
    /// Selection ([`selection_code`]: 0 nearest, 1 interpolated).
    pub selection: u32,
    /// Rays one invocation traces.
    pub rays_per_invocation: u32,
    /// Invocations per point.
    pub invocations_per_point: u32,
    /// Trips of the completion loop ([`COMPLETION_TRIPS`]).
    pub completion_trips: u32,
    /// Ray origin offset along the normal.
    pub origin_offset: f32,
    /// Intra-object bias: a fraction of 2R, or the scale of the field's own tolerance.
    pub intra_bias: f32,
    /// 1 when `intra_bias` scales the field's own tolerance ([`IntraBias::Auto`]), else 0.
    pub intra_auto: u32,
    /// AO: the largest hit distance.
    pub tmax: f32,
    /// Shadows: the lights.
    pub light_count: u32,
    /// SDF kernels: steps per ray, cone and volume (`SdfTrace::max_steps`).
    pub max_steps: u32,
    /// SDF cone kernels: a cone's least step, a share of its radius (`ConeTrace::step`).
    pub cone_step: f32,
    /// SDF cone AO: tan of the cones' common half-angle (`ConeSet::tan_half`).
    pub cone_tan: f32,
}
const _: () = assert!(std::mem::size_of::<KernelParamsGpu>() == 64);
const _: () = assert!(std::mem::offset_of!(KernelParamsGpu, selection) == 16);
const _: () = assert!(std::mem::offset_of!(KernelParamsGpu, origin_offset) == 32);
const _: () = assert!(std::mem::offset_of!(KernelParamsGpu, light_count) == 48);
const _: () = assert!(std::mem::offset_of!(KernelParamsGpu, cone_tan) == 60);

/// The shared bindings of a field kernel's own group (0); the fields are group
/// [`super::field_binding::FIELD_GROUP`].
const PARAMS_BINDING: u32 = 0;
const RECEIVERS_BINDING: u32 = 1;
const OUT_BINDING: u32 = 2;
/// The first binding of a kernel's own inputs.
pub(super) const FIRST_OWN_BINDING: u32 = 3;

/// A kernel's own bind group (0): the shared header's bindings (params, receivers, output
/// words) and the kernel's own read-only storage inputs from [`FIRST_OWN_BINDING`] on. The
/// field kernels add the fields as group 1 ([`FieldKernel`]); the per-object peers' kernels
/// (src/gpu/sdf_kernel.rs, src/gpu/aofield_kernel.rs) bind everything here.
pub(super) struct KernelGroup {
    pub layout: wgpu::BindGroupLayout,
    label: &'static str,
}

/// The shared header's WGSL, in order: the receivers, the loop budget, `Params` and the
/// bindings of group 0.
pub(super) const HEADER_WGSL: [&str; 3] = [
    include_str!("../../shaders/receiver.wgsl"),
    include_str!("../../shaders/loop_budget.wgsl"),
    include_str!("../../shaders/field_kernel.wgsl"),
];

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

    /// Compiles `entry_point` of `source` for a kernel whose only group is this one.
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        name: &str,
        source: &str,
        entry_point: &str,
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let layout = ctx
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(self.label),
                bind_group_layouts: &[Some(&self.layout)],
                immediate_size: 0,
            });
        ctx.compute_pipeline_with_layout(name, source, entry_point, Some(&layout))
    }

    /// Uploads the receivers batch by batch, dispatches `threads_per_item` threads per
    /// receiver, each writing `words_per_thread` words, with `own` bound from
    /// [`FIRST_OWN_BINDING`] on and `fixed_groups` as groups 1, 2, …, and reads the words back,
    /// receiver-major ([`GpuContext::run_batched`]).
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        ctx: &GpuContext,
        pipeline: &wgpu::ComputePipeline,
        fixed_groups: &[&wgpu::BindGroup],
        mut params: KernelParamsGpu,
        recv: &[ReceiverGpu],
        own: &[&wgpu::Buffer],
        shape: (u32, u32),
    ) -> Result<Dispatched, GpuError> {
        ctx.run_batched(
            pipeline,
            fixed_groups,
            recv,
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

/// The skeleton of a field kernel: its fields bound, its group layout, its rays-per-invocation
/// budget and its lookup options; the quantity's kernel holds one and its pipelines.
pub(super) struct FieldKernel<'a> {
    pub ctx: &'a GpuContext,
    /// The kernel's own group (0).
    group: KernelGroup,
    pub field: FieldBinding,
    /// Rays per invocation, as last found to fit (src/gpu/loop_budget.rs).
    pub rays_per_invocation: AtomicU32,
}

impl<'a> FieldKernel<'a> {
    /// Packs and uploads `instances` (their distinct fields once each) with room for `own`
    /// read-only storage inputs of the kernel (bound from [`FIRST_OWN_BINDING`] on).
    pub fn new(
        ctx: &'a GpuContext,
        instances: &[FieldInstance],
        opts: &FieldGpuOptions,
        label: &'static str,
        own: u32,
    ) -> Result<Self, GpuError> {
        // The receivers and the output are storage buffers too.
        let field = FieldBinding::new(ctx, instances, &opts.binding_options(own + 2))?;
        Ok(FieldKernel {
            ctx,
            group: KernelGroup::new(ctx, label, own),
            field,
            rays_per_invocation: opts.start_rays_per_invocation(instances.len()),
        })
    }

    /// The kernel's WGSL: the lookup's, the shared header ([`HEADER_WGSL`]), then `kernel`
    /// (the quantity's helpers and its entry points).
    pub fn source(&self, kernel: &[&str]) -> String {
        let mut parts = HEADER_WGSL.to_vec();
        parts.extend_from_slice(kernel);
        self.field.shader_source(&parts)
    }

    /// The pipeline layout: the kernel's group 0 and the fields' group 1.
    pub fn pipeline_layout(&self) -> wgpu::PipelineLayout {
        self.field.pipeline_layout(self.ctx, &self.group.layout)
    }

    /// Compiles `entry_point` of `source` with [`Self::pipeline_layout`].
    pub fn pipeline(
        &self,
        name: &str,
        source: &str,
        entry_point: &str,
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        self.ctx.compute_pipeline_with_layout(
            name,
            source,
            entry_point,
            Some(&self.pipeline_layout()),
        )
    }

    /// Moves the bound instances to `instances`' transforms ([`FieldBinding::place`]).
    pub fn place(&self, instances: &[FieldInstance]) -> Result<(), GpuError> {
        self.field.place(self.ctx, instances)
    }

    /// Rays per invocation the next call starts with.
    pub fn rays_per_invocation(&self) -> u32 {
        self.rays_per_invocation
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The header of a call with `rays_per_point` rays per point from origins moved by
    /// `origin_offset`, read with `lookup`: the instance count, the selection and intra-object
    /// bias, the completion trips; the rest zero for the quantity and the dispatch to fill.
    pub fn params(
        &self,
        lookup: &LookupOptions,
        rays_per_point: u32,
        origin_offset: f32,
    ) -> KernelParamsGpu {
        let (intra_bias, intra_auto) = intra_terms(lookup.intra_bias);
        KernelParamsGpu {
            rays_per_point,
            instance_count: self.field.instance_count(),
            selection: selection_code(lookup.selection),
            completion_trips: COMPLETION_TRIPS,
            origin_offset,
            intra_bias,
            intra_auto,
            ..Default::default()
        }
    }

    /// Runs `pipeline` over the receivers ([`KernelGroup::run`]) with the fields as group 1.
    pub fn run(
        &self,
        pipeline: &wgpu::ComputePipeline,
        params: KernelParamsGpu,
        recv: &[ReceiverGpu],
        own: &[&wgpu::Buffer],
        shape: (u32, u32),
    ) -> Result<Dispatched, GpuError> {
        let field_group = [self.field.bind_group()];
        self.group
            .run(self.ctx, pipeline, &field_group, params, recv, own, shape)
    }
}

/// WGSL `intra_bias` and `intra_auto` of a lookup's intra-object bias.
fn intra_terms(b: IntraBias) -> (f32, u32) {
    match b {
        IntraBias::Auto { scale } => (scale, 1),
        IntraBias::Fixed(f) => (f, 0),
    }
}

/// WGSL `selection` of a selection.
pub(super) fn selection_code(s: Selection) -> u32 {
    match s {
        Selection::Nearest => 0,
        Selection::Interpolated => 1,
    }
}
