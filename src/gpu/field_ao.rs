//! Vertex AO by field lookup on the GPU (Gaitatzes et al., WSCG 2008 Algorithm 2 and the WSCG
//! 2010 intra-object test), with the CPU path's ray directions and map selection.
//!
//! One thread per receiver point loops over the point's rays and over the instances
//! (shaders/field_ao.wgsl); the lookup is a line-by-line f32 port of `field::lookup` and
//! `field::scene`: the Slater / lat-long nearest point (the CPU's owner table, else its cube grid's
//! candidates, else 4 rings × 2 azimuths), the Duff frame, the three layouts' `to_texel` (the concentric one after the CPU's
//! texel table), the interpolated selection's triangle walk and bilinear
//! footprint. On lavapipe it reproduces the CPU AO bit for bit in the parity tests.
//!
//! Deviations from the CPU path: the world-space ray–sphere test and the entry point are
//! computed in f32 (the host uses f64), so near-tangent rays and near-ties between maps may
//! resolve differently; the interpolated selection's walk uses an f32 edge tolerance and, when
//! it does not settle within the host's step cap, reads the nearest map alone (the host scans
//! every triangle). Fibonacci point sets (no GPU nearest query) and jittered ray sets (no shared
//! directions) are refused with [`GpuError::Unsupported`]. Instances are tested in index order
//! (the host sorts them by entry distance); for the boolean AO query the order does not matter.
//!
//! A point's rays are spread over several invocations ([`FieldGpuOptions::rays_per_invocation`],
//! halved where the driver cuts long invocations short: src/gpu/loop_budget.rs), and the
//! receivers over several dispatches where their buffers would pass the adapter's binding
//! limit, so any ray count and any number of points run.

use super::context::{entry, storage_layout_entry, uniform_layout_entry, GpuContext};
use super::field_binding::{FieldBinding, FieldBindingOptions, FieldLayout};
use super::loop_budget::{free_fractions, Dispatched, COMPLETION_TRIPS};
use super::rays::{base_directions, receivers, ReceiverGpu};
use super::{GpuError, GpuTiming};
use crate::field::lookup::{IntraBias, LookupOptions};
use crate::field::scene::FieldInstance;
use crate::field::Selection;
use crate::render::ao::AoOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;
use std::sync::atomic::AtomicU32;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Options of a [`FieldAoKernel`].
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

/// Twin of WGSL `Params` (shaders/field_ao.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct AoParamsGpu {
    /// Receiver points in this dispatch.
    point_count: u32,
    /// Rays per point (the base directions).
    rays_per_point: u32,
    /// Field instances.
    instance_count: u32,
    /// Invocations per row of the dispatch grid.
    row_stride: u32,
    /// Selection ([`selection_code`]: 0 nearest, 1 interpolated).
    selection: u32,
    /// Rays one invocation traces.
    rays_per_invocation: u32,
    /// Invocations per point.
    invocations_per_point: u32,
    /// Trips of the completion loop ([`COMPLETION_TRIPS`]).
    completion_trips: u32,
    /// Ray origin offset along the normal.
    origin_offset: f32,
    /// Largest hit distance.
    tmax: f32,
    /// Intra-object bias: a fraction of 2R, or the scale of the field's own tolerance.
    intra_bias: f32,
    /// 1 when `intra_bias` scales the field's own tolerance ([`IntraBias::Auto`]), else 0.
    intra_auto: u32,
}
const _: () = assert!(std::mem::size_of::<AoParamsGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(AoParamsGpu, selection) == 16);
const _: () = assert!(std::mem::offset_of!(AoParamsGpu, origin_offset) == 32);

/// One lookup as the GPU answers it (see [`FieldAoKernel::probe`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookupProbe {
    /// Nearest map.
    pub map: u32,
    /// Texel of the direction in that map.
    pub texel: u32,
    /// Stored distance read with the nearest selection.
    pub nearest: f32,
    /// Stored distance read with the interpolated selection.
    pub interpolated: f32,
}

/// The kernel's own bindings (group 0; the fields are group
/// [`super::field_binding::FIELD_GROUP`]): params, receivers, output, ray directions.
const PARAMS_BINDING: u32 = 0;
const RECEIVERS_BINDING: u32 = 1;
const OUT_BINDING: u32 = 2;
const DIRECTIONS_BINDING: u32 = 3;
/// Storage buffers among them (receivers, output, ray directions).
const KERNEL_STORAGE_BUFFERS: u32 = 3;

/// Field-lookup vertex AO over a set of field instances, uploaded once (Gaitatzes et al., WSCG
/// 2008 Algorithm 2 and the WSCG 2010 intra-object test): its own bindings in group 0, the
/// fields in a `FieldBinding` (src/gpu/field_binding.rs).
pub struct FieldAoKernel<'a> {
    ctx: &'a GpuContext,
    /// The AO pipeline per selection code ([`selection_code`]), compiled on first use: the
    /// selection is a shader constant (`AO_SELECTION`) so that the compiler drops the other's
    /// code, which llvmpipe would run masked for every ray.
    ao: Mutex<[Option<wgpu::ComputePipeline>; 2]>,
    /// Kernel source without `AO_SELECTION`, its entry point and pipeline layout.
    ao_source: (String, &'static str, wgpu::PipelineLayout),
    probe: wgpu::ComputePipeline,
    /// Layout of the kernel's own group (0).
    group_layout: wgpu::BindGroupLayout,
    field: FieldBinding,
    /// Rays per invocation, as last found to fit (`loop_budget::free_fractions`).
    rays_per_invocation: AtomicU32,
    upload: Duration,
    /// Selection and intra-object bias of the lookups (may be changed between calls).
    pub lookup: LookupOptions,
}

impl<'a> FieldAoKernel<'a> {
    /// Packs and uploads `instances` (their distinct fields once each) and compiles the kernels.
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
                label: Some("field ao"),
                entries: &[
                    uniform_layout_entry(PARAMS_BINDING),
                    storage_layout_entry(RECEIVERS_BINDING, true),
                    storage_layout_entry(OUT_BINDING, false),
                    storage_layout_entry(DIRECTIONS_BINDING, true),
                ],
            });
        let mut source = field.shader_source(&[
            include_str!("../../shaders/receiver.wgsl"),
            include_str!("../../shaders/loop_budget.wgsl"),
            include_str!("../../shaders/field_ao.wgsl"),
        ]);
        let layout = field.pipeline_layout(ctx, &group_layout);
        let entry = if opts.queue_rays {
            "ao_main"
        } else {
            "ao_main_direct"
        };
        let probe = ctx.compute_pipeline_with_layout(
            "field_probe",
            &(ao_selection_const(0) + &source),
            "probe_main",
            Some(&layout),
        )?;
        source.shrink_to_fit();
        let kernel = FieldAoKernel {
            ctx,
            ao: Mutex::new([None, None]),
            ao_source: (source, entry, layout),
            probe,
            group_layout,
            rays_per_invocation: opts.start_rays_per_invocation(instances.len()),
            field,
            upload: Duration::ZERO,
            lookup: opts.lookup,
        };
        kernel.ao_pipeline(selection_code(opts.lookup.selection))?;
        Ok(FieldAoKernel {
            upload: start.elapsed(),
            ..kernel
        })
    }

    /// The AO pipeline of selection code `code`, compiled on first use.
    fn ao_pipeline(&self, code: u32) -> Result<wgpu::ComputePipeline, GpuError> {
        let mut cache = self.ao.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = &cache[code as usize] {
            return Ok(p.clone());
        }
        let (source, entry, layout) = &self.ao_source;
        let p = self.ctx.compute_pipeline_with_layout(
            "field_ao",
            &(ao_selection_const(code) + source),
            entry,
            Some(layout),
        )?;
        cache[code as usize] = Some(p.clone());
        Ok(p)
    }

    /// Bytes of stored distances on the device.
    pub fn field_bytes(&self) -> u64 {
        self.field.field_bytes()
    }

    /// Storage windows the fields occupy (storage layout), `None` for the texture layout.
    pub fn storage_windows(&self) -> Option<usize> {
        self.field.storage_windows()
    }

    /// Slices of the field texture (texture layout), `None` for the storage layout.
    pub fn texture_depth(&self) -> Option<u32> {
        self.field.texture_depth()
    }

    /// Rays per invocation the next call starts with: the options' value divided by the
    /// instance count, or less where a driver cut an earlier call's invocations short.
    pub fn rays_per_invocation(&self) -> u32 {
        self.rays_per_invocation
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Host time of packing, uploading and compiling in [`Self::new`].
    pub fn setup_time(&self) -> Duration {
        self.upload
    }

    /// AO at every point (point `i` uses the directions of point index `i` of `rays`), as
    /// [`crate::render::ao::ao_at_points`] computes it over a [`crate::field::scene::FieldScene`] of
    /// the same instances and lookup options.
    pub fn vertex_ao(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        let start = Instant::now();
        let base = base_directions(rays)?;
        let recv = receivers(points, normals, rays)?;
        let max_binding = self.ctx.max_binding();
        let dir_bytes = base.len() as u64 * 16;
        if dir_bytes > max_binding {
            return Err(GpuError::TooLarge {
                what: format!("{} ray directions", base.len()),
                need: dir_bytes,
                limit: max_binding,
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        let dirs = self
            .ctx
            .storage_buffer("ray directions", bytemuck::cast_slice(&base));
        let tmax = opts.max_distance.unwrap_or(f32::MAX).min(f32::MAX);
        let (intra_bias, intra_auto) = intra_terms(self.lookup.intra_bias);
        let mut params = AoParamsGpu {
            rays_per_point: base.len() as u32,
            instance_count: self.field.instance_count(),
            selection: selection_code(self.lookup.selection),
            completion_trips: COMPLETION_TRIPS,
            origin_offset: opts.offset,
            tmax,
            intra_bias,
            intra_auto,
            ..Default::default()
        };
        let pipeline = self.ao_pipeline(params.selection)?;
        let (ao, kernel, upload) = free_fractions(
            &self.rays_per_invocation,
            base.len() as u32,
            recv.len(),
            |per_invocation, per_point| {
                params.rays_per_invocation = per_invocation;
                params.invocations_per_point = per_point;
                self.run(&pipeline, params, &recv, &dirs, per_point, 1)
            },
        )?;
        Ok((
            ao,
            GpuTiming {
                kernel,
                upload,
                wall: start.elapsed(),
            },
        ))
    }

    /// Single lookups on the field of the first instance: for unit sphere position `u[i]`
    /// (model space) and model direction `dirs[i]`, the nearest map, the texel, and the stored
    /// distance under both selections, for comparison with [`crate::field::VisibilityField`]'s
    /// `points.nearest`, `layout.to_texel` and `sample`.
    pub fn probe(&self, u: &[Vec3], dirs: &[Vec3]) -> Result<Vec<LookupProbe>, GpuError> {
        if u.len() != dirs.len() {
            return Err(GpuError::Invalid(format!(
                "{} positions but {} directions",
                u.len(),
                dirs.len()
            )));
        }
        let recv: Vec<ReceiverGpu> = u
            .iter()
            .zip(dirs)
            .map(|(p, d)| ReceiverGpu {
                position: p.to_array(),
                normal: d.to_array(),
                ..Default::default()
            })
            .collect();
        let params = AoParamsGpu {
            point_count: u.len() as u32,
            instance_count: self.field.instance_count(),
            ..Default::default()
        };
        // The probe reads no ray directions; the shared layout wants a buffer all the same.
        let no_dirs = self.ctx.storage_buffer("no ray directions", &[]);
        let (words, _, _) = self.run(&self.probe, params, &recv, &no_dirs, 1, 4)?;
        Ok(words
            .chunks_exact(4)
            .map(|w| LookupProbe {
                map: w[0],
                texel: w[1],
                nearest: f32::from_bits(w[2]),
                interpolated: f32::from_bits(w[3]),
            })
            .collect())
    }

    /// Uploads the per-call buffers, dispatches `threads_per_item` threads per receiver, each
    /// writing `words_per_thread` words, and reads the words back, receiver-major, in batches
    /// ([`GpuContext::run_batched`]), with the fields bound as their own group.
    fn run(
        &self,
        pipeline: &wgpu::ComputePipeline,
        mut params: AoParamsGpu,
        recv: &[ReceiverGpu],
        dirs: &wgpu::Buffer,
        threads_per_item: u32,
        words_per_thread: u32,
    ) -> Result<Dispatched, GpuError> {
        let ctx = self.ctx;
        let shape = (threads_per_item, words_per_thread);
        let field_group = [self.field.bind_group()];
        ctx.run_batched(
            pipeline,
            &field_group,
            recv,
            "receiver",
            shape,
            |part, stride, out| {
                params.point_count = part.len() as u32;
                params.row_stride = stride;
                let uniform = ctx.uniform_buffer("ao params", bytemuck::bytes_of(&params));
                let recv_buf = ctx.storage_buffer("receivers", bytemuck::cast_slice(part));
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("field ao"),
                    layout: &self.group_layout,
                    entries: &[
                        entry(PARAMS_BINDING, uniform.as_entire_binding()),
                        entry(RECEIVERS_BINDING, recv_buf.as_entire_binding()),
                        entry(OUT_BINDING, out.as_entire_binding()),
                        entry(DIRECTIONS_BINDING, dirs.as_entire_binding()),
                    ],
                })
            },
        )
    }
}

/// WGSL `AO_SELECTION`, the AO kernel's selection code.
fn ao_selection_const(code: u32) -> String {
    format!("const AO_SELECTION: u32 = {code}u;\n")
}

/// WGSL `intra_bias` and `intra_auto` of a lookup's intra-object bias.
pub(super) fn intra_terms(b: IntraBias) -> (f32, u32) {
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
