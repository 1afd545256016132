//! The 2005 relief caster on the GPU (`shaders/relief.wgsl`): the linear search, bisection and
//! safety-zone skips of [`crate::relief::intersect`] (Kolb and Rezk-Salama, VMV 2005,
//! §3.1–3.4), one invocation per ray segment through the prism.
//!
//! The displacement map and the dilation/erosion zones are uploaded once as storage buffers
//! and read with the CPU's own filters, so the two paths take the same steps on the same
//! segments; they differ only where the driver rounds an expression differently (a fused
//! multiply-add), which moves a sample that lies within a rounding error of the surface to the
//! other side. `tests/gpu.rs` bounds how often that happens.
//!
//! Deviation from the paper: a compute shader over segments clipped on the host, not a pixel
//! shader over the rasterised prism; zones in f32, not 8-bit RGBA textures.

use super::context::{entry, GpuContext};
use super::integrand::timing;
use super::loop_budget::{COMPLETION_TRIPS, CUT_SHORT};
use super::{GpuError, GpuTiming};
use crate::relief::{Cast, CastParams, HeightMap, SafetyZones};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::time::{Duration, Instant};

/// Twin of WGSL `ReliefParams` (shaders/relief.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ReliefParamsGpu {
    /// Map width and height (texels).
    size: [u32; 2],
    /// Rays (segments) in this dispatch.
    count: u32,
    /// Invocations per row of the dispatch grid.
    stride: u32,
    /// Linear-search samples per unit of segment length.
    samples_per_unit: f32,
    /// Bisection steps after the linear search.
    bisections: u32,
    /// Rounds of safety-zone skips (0: none).
    skips: u32,
    /// Zone channels in use (entries of `deltas`).
    channels: u32,
    /// Half-widths δ of the zone channels (texture units).
    deltas: [f32; 4],
    /// Trips of the completion loop (`loops_completed`).
    trips: u32,
    /// `1 / samples_per_unit`, the search's lattice step, as the CPU computes it.
    step: f32,
    _pad1: u32,
    _pad2: u32,
}
const _: () = assert!(std::mem::size_of::<ReliefParamsGpu>() == 64);
const _: () = assert!(std::mem::offset_of!(ReliefParamsGpu, samples_per_unit) == 16);
const _: () = assert!(std::mem::offset_of!(ReliefParamsGpu, deltas) == 32);
const _: () = assert!(std::mem::offset_of!(ReliefParamsGpu, trips) == 48);

/// The hit word of a ray that misses, in both relief kernels.
const MISS: u32 = u32::MAX;

/// Loop iterations one invocation of either relief kernel may take: lavapipe ends every
/// invocation's loops after 65,535 iterations in all, silently (see `loop_budget`). Settings
/// that could need more are refused before the dispatch; an invocation cut short all the same
/// (the shared completion check, `loops_completed`) makes the call an error, never a wrong
/// answer.
pub(super) const MAX_ITERATIONS: f64 = 60_000.0;

/// One displacement map and its safety zones, uploaded.
pub struct ReliefKernel<'a> {
    ctx: &'a GpuContext,
    size: [u32; 2],
    channels: u32,
    deltas: [f32; 4],
    heights: wgpu::Buffer,
    dilation: wgpu::Buffer,
    erosion: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    setup: Duration,
}

impl<'a> ReliefKernel<'a> {
    /// Uploads `map` and `zones` (made from `map`) and compiles the kernel.
    pub fn new(
        ctx: &'a GpuContext,
        map: &HeightMap,
        zones: &SafetyZones,
    ) -> Result<ReliefKernel<'a>, GpuError> {
        let start = Instant::now();
        if zones.size() != (map.width, map.height) {
            return Err(GpuError::Invalid(format!(
                "safety zones of {:?} texels for a {}×{} map",
                zones.size(),
                map.width,
                map.height
            )));
        }
        let mut deltas = [0.0f32; 4];
        deltas[..zones.deltas.len()].copy_from_slice(&zones.deltas);
        let source = [
            include_str!("../../shaders/loop_budget.wgsl"),
            include_str!("../../shaders/height_map.wgsl"),
            include_str!("../../shaders/relief.wgsl"),
        ]
        .concat();
        Ok(ReliefKernel {
            ctx,
            size: [map.width as u32, map.height as u32],
            channels: zones.deltas.len() as u32,
            deltas,
            heights: ctx.storage_buffer("heights", bytemuck::cast_slice(&map.data)),
            dilation: ctx.storage_buffer("dilation", bytemuck::cast_slice(&zones.dilation)),
            erosion: ctx.storage_buffer("erosion", bytemuck::cast_slice(&zones.erosion)),
            pipeline: ctx.compute_pipeline_with_layout("relief", &source, "relief_main", None)?,
            setup: start.elapsed(),
        })
    }

    /// Host time of the upload and shader compilation.
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// [`crate::relief::intersect`] of every segment `(E, X)` (prism coordinates) with the
    /// zones always given (`params.skips` rounds of skips; 0 for none).
    pub fn cast(
        &self,
        segments: &[(Vec3, Vec3)],
        params: &CastParams,
    ) -> Result<(Vec<Cast>, GpuTiming), GpuError> {
        let start = Instant::now();
        if let Some(k) = segments
            .iter()
            .position(|(e, x)| !e.is_finite() || !x.is_finite())
        {
            return Err(GpuError::Invalid(format!(
                "relief segment {k} is not finite"
            )));
        }
        let longest = segments
            .iter()
            .map(|(e, x)| (*x - *e).length())
            .fold(0.0f32, f32::max);
        if !params.samples_per_unit.is_finite() || params.samples_per_unit <= 0.0 {
            return Err(GpuError::Invalid(format!(
                "samples per unit must be positive, got {}",
                params.samples_per_unit
            )));
        }
        // The linear search (its end sample included), the bisection, per round of skips the
        // round and a forward and a backward pass over the zone channels, the completion loop.
        let channels = self.channels as f64;
        let iterations = (longest as f64 * params.samples_per_unit as f64).ceil()
            + 1.0
            + params.bisections as f64
            + params.skips as f64 * (1.0 + 2.0 * channels)
            + COMPLETION_TRIPS as f64;
        if iterations > MAX_ITERATIONS {
            return Err(GpuError::Unsupported(format!(
                "{} samples per unit over a segment of {longest} and {} bisections need {iterations} \
                 loop iterations per ray; the GPU path allows {MAX_ITERATIONS}",
                params.samples_per_unit, params.bisections
            )));
        }
        let layout = self.pipeline.get_bind_group_layout(0);
        let maps = [&self.heights, &self.dilation, &self.erosion];
        let kernel = (&self.pipeline, &layout, "relief");
        cast_segments(self.ctx, kernel, maps, segments, start, |count, stride| {
            ReliefParamsGpu {
                size: self.size,
                count,
                stride,
                samples_per_unit: params.samples_per_unit,
                bisections: params.bisections,
                skips: params.skips,
                channels: self.channels,
                deltas: self.deltas,
                trips: COMPLETION_TRIPS,
                step: 1.0 / params.samples_per_unit,
                _pad1: 0,
                _pad2: 0,
            }
        })
    }
}

/// A segment as the relief kernels read it: entry point (w = 1) and exit point (w = 0).
pub(super) type SegmentGpu = [[f32; 4]; 2];

/// Runs a relief kernel (`shaders/relief.wgsl` or `shaders/relief_peers.wgsl`, which share the
/// segment input and the (hit, fetches) output) over `segments` in batches: `kernel` is its
/// pipeline, the layout of its group and the group's label, the group binds `params(count,
/// stride)` of a batch (a uniform at binding 0), `maps` (bindings 1 to 3), the batch's
/// segments and the output. The casts, or an error when the driver's loop budget cut any ray
/// short; `start` is when the caller began (the wall time includes its checks).
pub(super) fn cast_segments<P: bytemuck::Pod>(
    ctx: &GpuContext,
    (pipeline, layout, label): (&wgpu::ComputePipeline, &wgpu::BindGroupLayout, &str),
    maps: [&wgpu::Buffer; 3],
    segments: &[(Vec3, Vec3)],
    start: Instant,
    params: impl Fn(u32, u32) -> P,
) -> Result<(Vec<Cast>, GpuTiming), GpuError> {
    let data: Vec<SegmentGpu> = segments
        .iter()
        .map(|(e, x)| [e.extend(1.0).to_array(), x.extend(0.0).to_array()])
        .collect();
    let packed = start.elapsed();
    let bind = |part: &[SegmentGpu], stride, out: &wgpu::Buffer| {
        let uniform = params(part.len() as u32, stride);
        let uniform = ctx.uniform_buffer(label, bytemuck::bytes_of(&uniform));
        let rays = ctx.storage_buffer("segments", bytemuck::cast_slice(part));
        let mut entries = vec![entry(0, uniform.as_entire_binding())];
        entries.extend(
            (1..)
                .zip(maps)
                .map(|(i, m)| entry(i, m.as_entire_binding())),
        );
        entries.extend([
            entry(4, rays.as_entire_binding()),
            entry(5, out.as_entire_binding()),
        ]);
        ctx.bind_group(label, layout, &entries)
    };
    let (words, kernel, upload) =
        ctx.run_batched(pipeline, &[], &data, "relief segment", (1, 2), bind)?;
    let upload = packed + upload;
    let cut = words.chunks_exact(2).filter(|w| w[1] == CUT_SHORT).count();
    if cut > 0 {
        return Err(GpuError::Unsupported(format!(
            "{cut} of {} relief rays were cut short by the driver's loop budget per \
             invocation (lavapipe: 65,535 iterations)",
            segments.len()
        )));
    }
    let casts = words
        .chunks_exact(2)
        .map(|w| Cast {
            hit: (w[0] != MISS).then(|| f32::from_bits(w[0])),
            fetches: w[1],
        })
        .collect();
    Ok((casts, timing(kernel, upload, start)))
}

impl crate::relief::view::SegmentCaster<CastParams> for ReliefKernel<'_> {
    type Timing = GpuTiming;
    type Error = GpuError;

    fn cast_segments(
        &self,
        segments: &[(Vec3, Vec3)],
        params: &CastParams,
    ) -> Result<(Vec<Cast>, GpuTiming), GpuError> {
        self.cast(segments, params)
    }
}
