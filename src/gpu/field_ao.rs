//! Vertex AO by field lookup on the GPU (Gaitatzes et al., WSCG 2008 Algorithm 2 and the WSCG
//! 2010 intra-object test), with the CPU path's ray directions and map selection.
//!
//! One thread per receiver point loops over the point's rays and over the instances
//! (shaders/field_ao.wgsl); the lookup is a line-by-line f32 port of `field::lookup` and
//! `field::scene`: the Slater / lat-long nearest point (4 rings × 2 azimuths), the Duff frame,
//! the three layouts' `to_texel`, the interpolated selection's triangle walk and bilinear
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

use super::context::entry;
use super::context::GpuContext;
use super::field_data::{field_words, PackedFields};
use super::loop_budget::{free_fractions, Dispatched, COMPLETION_TRIPS};
use super::rays::{base_directions, receivers, ReceiverGpu};
use super::texture::FieldTexture;
use super::{GpuError, GpuTiming};
use crate::field::lookup::{IntraBias, LookupOptions};
use crate::field::scene::FieldInstance;
use crate::field::Selection;
use crate::render::ao::AoOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;
use std::sync::atomic::AtomicU32;
use std::time::{Duration, Instant};

/// How the stored distances are bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FieldLayout {
    /// The stored words as they are on the host, in storage buffers bound in windows of at
    /// most the adapter's `max_storage_buffer_binding_size`.
    StorageBuffers,
    /// The 2010 paper's packing: maps as tiles of the slices of a 3D texture (r32float, r16uint,
    /// r8uint by precision; 1-bit maps as r32uint words), several maps per slice.
    Texture3d,
}

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
}

impl Default for FieldGpuOptions {
    fn default() -> Self {
        FieldGpuOptions {
            lookup: LookupOptions::default(),
            layout: FieldLayout::StorageBuffers,
            window_bytes: None,
            rays_per_invocation: super::loop_budget::DEFAULT_RAYS_PER_INVOCATION,
            max_texture_depth: None,
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

/// Bindings before the field's own (params, receivers, tables, mesh, instances, output, ray
/// directions).
const FIXED_BINDINGS: u32 = 7;
const STORAGE_BUFFERS_FIXED: u32 = 6;
/// The ray directions' binding (AO kernel only).
const DIRECTIONS_BINDING: u32 = 6;

/// The field's stored distances on the device.
enum FieldBinding {
    Windows(Vec<wgpu::Buffer>),
    Texture(FieldTexture),
}

/// Field-lookup vertex AO over a set of field instances, uploaded once.
pub struct FieldAoKernel<'a> {
    ctx: &'a GpuContext,
    ao: wgpu::ComputePipeline,
    probe: wgpu::ComputePipeline,
    tables: wgpu::Buffer,
    mesh: wgpu::Buffer,
    instances: wgpu::Buffer,
    instance_count: u32,
    field: FieldBinding,
    /// Rays per invocation, as last found to fit (`loop_budget::free_fractions`).
    rays_per_invocation: AtomicU32,
    field_bytes: u64,
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
        let mut packed = PackedFields::new(instances)?;
        let limits = ctx.limits();
        let (field, prelude, field_src, field_bytes) = match opts.layout {
            FieldLayout::StorageBuffers => {
                let (words, bases) = field_words(&packed.fields);
                packed.set_data_base(&bases);
                let max_binding = ctx.max_binding();
                let window_bytes = opts.window_bytes.unwrap_or(max_binding).min(max_binding);
                let window_words = ((window_bytes / 4) / 64 * 64).max(64) as usize;
                let windows_needed = words.len().div_ceil(window_words).max(1);
                let max_windows = limits
                    .max_storage_buffers_per_shader_stage
                    .saturating_sub(STORAGE_BUFFERS_FIXED)
                    as usize;
                if windows_needed > max_windows {
                    return Err(GpuError::TooLarge {
                        what: format!("fields in {windows_needed} storage windows"),
                        need: words.len() as u64 * 4,
                        limit: max_windows as u64 * window_words as u64 * 4,
                        limit_name: "max_storage_buffer_binding_size × free storage bindings",
                    });
                }
                let buffers: Vec<wgpu::Buffer> = (0..windows_needed)
                    .map(|w| {
                        let lo = (w * window_words).min(words.len());
                        let hi = ((w + 1) * window_words).min(words.len());
                        ctx.storage_buffer("field window", bytemuck::cast_slice(&words[lo..hi]))
                    })
                    .collect();
                (
                    FieldBinding::Windows(buffers),
                    window_prelude(windows_needed, window_words),
                    include_str!("../../shaders/field_storage.wgsl"),
                    words.len() as u64 * 4,
                )
            }
            FieldLayout::Texture3d => {
                let tex = FieldTexture::new(ctx, &packed.fields, opts.max_texture_depth)?;
                packed.set_data_base(tex.first_tiles());
                for (inst, &fi) in packed.instances.iter_mut().zip(&packed.field_of_instance) {
                    let (tx, per_slice) = tex.tiles(fi);
                    let (tile_w, tile_h) = tex.tile_shape(fi);
                    inst.tiles_per_row = tx;
                    inst.tiles_per_slice = per_slice;
                    inst.tile_width = tile_w;
                    inst.tile_height = tile_h;
                }
                let prelude = tex.prelude(FIXED_BINDINGS);
                let bytes = tex.bytes();
                (
                    FieldBinding::Texture(tex),
                    prelude,
                    include_str!("../../shaders/field_texture.wgsl"),
                    bytes,
                )
            }
        };
        let source = [
            prelude.as_str(),
            include_str!("../../shaders/frame.wgsl"),
            include_str!("../../shaders/receiver.wgsl"),
            include_str!("../../shaders/sphere_points.wgsl"),
            include_str!("../../shaders/layouts.wgsl"),
            include_str!("../../shaders/field_lookup.wgsl"),
            field_src,
            include_str!("../../shaders/loop_budget.wgsl"),
            include_str!("../../shaders/field_ao.wgsl"),
        ]
        .concat();
        let ao = ctx.compute_pipeline("field_ao", &source, "ao_main")?;
        let probe = ctx.compute_pipeline("field_probe", &source, "probe_main")?;
        let tables = ctx.storage_buffer("tables", bytemuck::cast_slice(&packed.tables));
        let mesh = ctx.storage_buffer("sphere mesh", bytemuck::cast_slice(&packed.mesh));
        let instances_buf =
            ctx.storage_buffer("instances", bytemuck::cast_slice(&packed.instances));
        Ok(FieldAoKernel {
            ctx,
            ao,
            probe,
            tables,
            mesh,
            instances: instances_buf,
            instance_count: packed.instances.len() as u32,
            field,
            rays_per_invocation: AtomicU32::new(
                (opts.rays_per_invocation / instances.len().max(1) as u32).max(1),
            ),
            field_bytes,
            upload: start.elapsed(),
            lookup: opts.lookup,
        })
    }

    /// Bytes of stored distances on the device.
    pub fn field_bytes(&self) -> u64 {
        self.field_bytes
    }

    /// Storage windows the fields occupy (storage layout), `None` for the texture layout.
    pub fn storage_windows(&self) -> Option<usize> {
        match &self.field {
            FieldBinding::Windows(w) => Some(w.len()),
            FieldBinding::Texture(_) => None,
        }
    }

    /// Slices of the field texture (texture layout), `None` for the storage layout.
    pub fn texture_depth(&self) -> Option<u32> {
        match &self.field {
            FieldBinding::Windows(_) => None,
            FieldBinding::Texture(t) => Some(t.depth()),
        }
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
        let (intra_bias, intra_auto) = match self.lookup.intra_bias {
            IntraBias::Auto { scale } => (scale, 1),
            IntraBias::Fixed(f) => (f, 0),
        };
        let mut params = AoParamsGpu {
            rays_per_point: base.len() as u32,
            instance_count: self.instance_count,
            selection: selection_code(self.lookup.selection),
            completion_trips: COMPLETION_TRIPS,
            origin_offset: opts.offset,
            tmax,
            intra_bias,
            intra_auto,
            ..Default::default()
        };
        let (ao, kernel, upload) = free_fractions(
            &self.rays_per_invocation,
            base.len() as u32,
            recv.len(),
            |per_invocation, per_point| {
                params.rays_per_invocation = per_invocation;
                params.invocations_per_point = per_point;
                self.run(&self.ao, params, &recv, Some(&dirs), per_point, 1)
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
            instance_count: self.instance_count,
            ..Default::default()
        };
        let (words, _, _) = self.run(&self.probe, params, &recv, None, 1, 4)?;
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
    /// ([`GpuContext::run_batched`]).
    fn run(
        &self,
        pipeline: &wgpu::ComputePipeline,
        mut params: AoParamsGpu,
        recv: &[ReceiverGpu],
        dirs: Option<&wgpu::Buffer>,
        threads_per_item: u32,
        words_per_thread: u32,
    ) -> Result<Dispatched, GpuError> {
        let shape = (threads_per_item, words_per_thread);
        self.ctx
            .run_batched(pipeline, recv, "receiver", shape, |part, stride, out| {
                params.point_count = part.len() as u32;
                params.row_stride = stride;
                let uniform = self
                    .ctx
                    .uniform_buffer("ao params", bytemuck::bytes_of(&params));
                let recv_buf = self
                    .ctx
                    .storage_buffer("receivers", bytemuck::cast_slice(part));
                let mut entries = vec![
                    entry(0, uniform.as_entire_binding()),
                    entry(1, recv_buf.as_entire_binding()),
                    entry(2, self.tables.as_entire_binding()),
                    entry(3, self.mesh.as_entire_binding()),
                    entry(4, self.instances.as_entire_binding()),
                    entry(5, out.as_entire_binding()),
                ];
                if let Some(d) = dirs {
                    entries.push(entry(DIRECTIONS_BINDING, d.as_entire_binding()));
                }
                let view;
                match &self.field {
                    FieldBinding::Windows(ws) => {
                        for (i, w) in ws.iter().enumerate() {
                            entries.push(entry(FIXED_BINDINGS + i as u32, w.as_entire_binding()));
                        }
                    }
                    FieldBinding::Texture(tex) => {
                        view = tex.view();
                        entries.push(entry(
                            FIXED_BINDINGS,
                            wgpu::BindingResource::TextureView(&view),
                        ));
                    }
                }
                self.ctx
                    .device
                    .create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("field ao"),
                        layout: &pipeline.get_bind_group_layout(0),
                        entries: &entries,
                    })
            })
    }
}

fn selection_code(s: Selection) -> u32 {
    match s {
        Selection::Nearest => 0,
        Selection::Interpolated => 1,
    }
}

/// `WINDOW_WORDS`, the window bindings and `load_word` for `n` windows.
fn window_prelude(n: usize, window_words: usize) -> String {
    let mut s = format!("const WINDOW_WORDS: u32 = {window_words}u;\n");
    for i in 0..n {
        s += &format!(
            "@group(0) @binding({}) var<storage, read> win{i}: array<u32>;\n",
            FIXED_BINDINGS as usize + i
        );
    }
    s += "fn load_word(address: u32) -> u32 {\n    let i = address % WINDOW_WORDS;\n    switch address / WINDOW_WORDS {\n";
    for i in 0..n {
        s += &format!("        case {i}u: {{ return win{i}[i]; }}\n");
    }
    s += "        default: { return 0u; }\n    }\n}\n";
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_prelude_declares_every_window_once() {
        let s = window_prelude(3, 1024);
        assert!(s.contains("const WINDOW_WORDS: u32 = 1024u;"));
        for i in 0..3 {
            let b = FIXED_BINDINGS + i;
            assert_eq!(s.matches(&format!("@binding({b})")).count(), 1);
            assert!(s.contains(&format!("case {i}u: {{ return win{i}[i]; }}")));
        }
        assert!(!s.contains("win3"));
    }
}
