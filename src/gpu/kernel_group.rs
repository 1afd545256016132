//! Group 0 of every GPU kernel, below both layers of the skeleton (src/gpu/integrand.rs asks
//! a visibility, src/gpu/visibility.rs compiles an integrand against one): the header
//! [`IntegrandParamsGpu`] (twin of WGSL `Params`, shaders/integrand.wgsl), the shared bindings
//! (params, receivers, output words, then an integrand's own inputs from
//! [`FIRST_OWN_BINDING`]), the WGSL every kernel starts with ([`HEADER_WGSL`]), what an
//! integrand is ([`Integrand`]) and [`KernelGroup`], the group's layout, pipeline and batched
//! dispatch.

use super::context::{entry, storage_layout_entry, uniform_layout_entry, GpuContext};
use super::loop_budget::{Dispatched, COMPLETION_TRIPS};
use super::GpuError;

/// Twin of WGSL `Params` (shaders/integrand.wgsl): one dispatch of an integrand.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct IntegrandParamsGpu {
    /// Receiver points (ray queries: rays) in this dispatch.
    pub point_count: u32,
    /// Rays per point (shadows: the cone samples per light, over every light).
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
    /// The rays' far end, where an integrand's rays share one (AO, cones; shadows and
    /// reflections compute each ray's own). Nothing else of a kind's: its own inputs carry it
    /// (the shadows' cone samples count themselves, `arrayLength`).
    pub tmax: f32,
    pub _pad: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<IntegrandParamsGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(IntegrandParamsGpu, invocations_per_point) == 16);
const _: () = assert!(std::mem::offset_of!(IntegrandParamsGpu, tmax) == 28);

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
/// One integrand: its WGSL after the header (in order), its entry point, its own read-only
/// storage inputs and the slot of its rays-per-invocation budget in a visibility's
/// [`super::visibility::Kernels`].
pub struct Integrand {
    pub sources: &'static [&'static str],
    pub entry: &'static str,
    pub own: u32,
    pub slot: usize,
}

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
        let layout = ctx.group_layout(label, &entries);
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
                ctx.bind_group(self.label, &self.layout, &entries)
            },
        )
    }
}
