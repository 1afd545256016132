//! The modern peers of the 2005 relief search on the GPU (`shaders/relief_peers.wgsl`): the
//! exact cell walk, maximum mipmaps (Tevs, Ihrke, Seidel, I3D 2008) and cone / relaxed cone
//! stepping (Dummer 2006; Policarpo and Oliveira, GPU Gems 3, 2007), one invocation per
//! segment, the same f32 operations as [`crate::relief::peers`], with the fetch counts of the
//! CPU (see that module's doc).
//!
//! Map, max mip and cone ratios are uploaded once as storage buffers; the dispatch follows
//! [`super::ReliefKernel`] (batches through `GpuContext::run_batched`, the loop-budget
//! completion check of lavapipe).
//!
//! Deviation from the papers: compute shaders over host-clipped segments, storage buffers read
//! with the CPU's formulas instead of texture units (parity with the CPU, not speed).

use super::context::{storage_layout_entry, uniform_layout_entry, GpuContext};
use super::loop_budget::COMPLETION_TRIPS;
use super::relief::{cast_segments, MAX_ITERATIONS};
use super::{GpuError, GpuTiming};
use crate::relief::peers::{in_prism, Peer, PeerData};
use crate::relief::{Cast, HeightMap};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::time::{Duration, Instant};

/// Twin of WGSL `PeersParams` (shaders/relief_peers.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct PeersParamsGpu {
    /// Map width and height (texels).
    size: [u32; 2],
    /// Rays in this dispatch.
    count: u32,
    /// Invocations per row of the dispatch grid.
    stride: u32,
    /// Entries a side of max-mip level 0.
    mip_size: u32,
    /// Index of the max mip's root level.
    mip_top: u32,
    /// Cone steps.
    steps: u32,
    /// Bisection steps (relaxed cones).
    bisections: u32,
    /// 1: relaxed cones, 0: conservative.
    relaxed: u32,
    /// Trips of the completion loop (`loops_completed`).
    trips: u32,
    _pad0: u32,
    _pad1: u32,
    /// Offset of each max-mip level in the `mips` buffer (levels 0 ..= mip_top).
    offsets: [u32; MAX_LEVELS],
}
const _: () = assert!(std::mem::size_of::<PeersParamsGpu>() == 112);
const _: () = assert!(std::mem::offset_of!(PeersParamsGpu, mip_size) == 16);
const _: () = assert!(std::mem::offset_of!(PeersParamsGpu, trips) == 36);
const _: () = assert!(std::mem::offset_of!(PeersParamsGpu, offsets) == 48);

/// Max-mip levels the uniform holds: maps up to 32,766 texels a side.
const MAX_LEVELS: usize = 16;

/// One map and its peer structures, uploaded, with the three kernels compiled.
pub struct ReliefPeersKernel<'a> {
    ctx: &'a GpuContext,
    size: [u32; 2],
    mip_size: u32,
    mip_top: u32,
    offsets: [u32; MAX_LEVELS],
    group: wgpu::BindGroupLayout,
    heights: wgpu::Buffer,
    mips: wgpu::Buffer,
    conservative: wgpu::Buffer,
    relaxed: wgpu::Buffer,
    cellwalk: wgpu::ComputePipeline,
    maxmip: wgpu::ComputePipeline,
    cone: wgpu::ComputePipeline,
    setup: Duration,
}

impl<'a> ReliefPeersKernel<'a> {
    /// Uploads `map` and `data` (built from `map`) and compiles the kernels.
    pub fn new(
        ctx: &'a GpuContext,
        map: &HeightMap,
        data: &PeerData,
    ) -> Result<ReliefPeersKernel<'a>, GpuError> {
        let start = Instant::now();
        if (data.cones.width, data.cones.height) != (map.width, map.height) {
            return Err(GpuError::Invalid(format!(
                "peer data of {}×{} texels for a {}×{} map",
                data.cones.width, data.cones.height, map.width, map.height
            )));
        }
        if data.mip.offsets.len() > MAX_LEVELS {
            return Err(GpuError::Unsupported(format!(
                "a max mip of {} levels ({}×{} map); the GPU path holds {MAX_LEVELS}",
                data.mip.offsets.len(),
                map.width,
                map.height
            )));
        }
        let mut offsets = [0u32; MAX_LEVELS];
        for (o, &v) in offsets.iter_mut().zip(&data.mip.offsets) {
            *o = v as u32;
        }
        // One layout for the three entry points (each uses a subset of the bindings).
        let entries = [
            uniform_layout_entry(0),
            storage_layout_entry(1, true),
            storage_layout_entry(2, true),
            storage_layout_entry(3, true),
            storage_layout_entry(4, true),
            storage_layout_entry(5, false),
        ];
        let group = ctx.group_layout("relief peers", &entries);
        let layout = ctx
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("relief peers"),
                bind_group_layouts: &[Some(&group)],
                immediate_size: 0,
            });
        let source = [
            include_str!("../../shaders/loop_budget.wgsl"),
            include_str!("../../shaders/height_map.wgsl"),
            include_str!("../../shaders/relief_peers.wgsl"),
        ]
        .concat();
        let pipeline = |label: &str, entry: &str| {
            ctx.compute_pipeline_with_layout(label, &source, entry, Some(&layout))
        };
        Ok(ReliefPeersKernel {
            ctx,
            size: [map.width as u32, map.height as u32],
            mip_size: data.mip.size as u32,
            mip_top: data.mip.top() as u32,
            offsets,
            group,
            heights: ctx.storage_buffer("heights", bytemuck::cast_slice(&map.data)),
            mips: ctx.storage_buffer("max mip", bytemuck::cast_slice(&data.mip.data)),
            conservative: ctx.storage_buffer(
                "cone ratios",
                bytemuck::cast_slice(&data.cones.conservative),
            ),
            relaxed: ctx.storage_buffer(
                "relaxed cone ratios",
                bytemuck::cast_slice(&data.cones.relaxed),
            ),
            cellwalk: pipeline("relief cell walk", "cellwalk_main")?,
            maxmip: pipeline("relief max mip", "maxmip_main")?,
            cone: pipeline("relief cones", "cone_main")?,
            setup: start.elapsed(),
        })
    }

    /// Host time of the upload and shader compilation.
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// `peer` on every segment `(E, X)` (prism coordinates), as
    /// [`PeerData::cast`](crate::relief::peers::PeerData::cast).
    pub fn cast(
        &self,
        segments: &[(Vec3, Vec3)],
        peer: &Peer,
    ) -> Result<(Vec<Cast>, GpuTiming), GpuError> {
        let start = Instant::now();
        peer.validate().map_err(GpuError::Invalid)?;
        if let Some(k) = segments
            .iter()
            .position(|(e, x)| !in_prism(*e) || !in_prism(*x))
        {
            return Err(GpuError::Invalid(format!(
                "relief segment {k} ({}, {}) is not finite or leaves the prism [0, 1]³",
                segments[k].0, segments[k].1
            )));
        }
        // Loop iterations per ray: the cells crossed (a segment in the prism crosses at most
        // W + H + 2); for the max mip one advance per node left (each enters a new cell) and
        // at most one descent per ascent (one per advance) plus the first descent from the
        // root; the cone steps and bisections; the completion loop.
        let cells = (self.size[0] + self.size[1] + 2) as f64;
        let (pipeline, steps, bisections, relaxed) = match *peer {
            Peer::CellWalk => (&self.cellwalk, cells, 0, 0),
            Peer::MaxMip => (&self.maxmip, 2.0 * cells + self.mip_top as f64, 0, 0),
            Peer::Cone { steps } => (&self.cone, steps as f64, 0, 0),
            Peer::RelaxedCone { steps, bisections } => {
                (&self.cone, (steps + bisections) as f64, bisections, 1)
            }
        };
        let iterations = steps + COMPLETION_TRIPS as f64;
        if iterations > MAX_ITERATIONS {
            return Err(GpuError::Unsupported(format!(
                "{} needs up to {iterations} loop iterations per ray on a {}×{} map; the GPU \
                 path allows {MAX_ITERATIONS}",
                peer.label(),
                self.size[0],
                self.size[1]
            )));
        }
        let cones = if relaxed == 1 {
            &self.relaxed
        } else {
            &self.conservative
        };
        let cone_steps = match *peer {
            Peer::Cone { steps } | Peer::RelaxedCone { steps, .. } => steps,
            _ => 0,
        };
        let maps = [&self.heights, &self.mips, cones];
        let kernel = (pipeline, &self.group, "relief peers");
        cast_segments(self.ctx, kernel, maps, segments, start, |count, stride| {
            PeersParamsGpu {
                size: self.size,
                count,
                stride,
                mip_size: self.mip_size,
                mip_top: self.mip_top,
                steps: cone_steps,
                bisections,
                relaxed,
                trips: COMPLETION_TRIPS,
                _pad0: 0,
                _pad1: 0,
                offsets: self.offsets,
            }
        })
    }
}

impl crate::relief::view::SegmentCaster<Peer> for ReliefPeersKernel<'_> {
    type Timing = GpuTiming;
    type Error = GpuError;

    fn cast_segments(
        &self,
        segments: &[(Vec3, Vec3)],
        params: &Peer,
    ) -> Result<(Vec<Cast>, GpuTiming), GpuError> {
        self.cast(segments, params)
    }
}
