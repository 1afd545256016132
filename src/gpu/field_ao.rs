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

use super::context::GpuContext;
use super::field_kernel::{selection_code, FieldGpuOptions, FieldKernel, KernelParamsGpu};
use super::loop_budget::free_fractions;
use super::rays::{base_directions, receivers, ReceiverGpu};
use super::{GpuError, GpuTiming};
use crate::field::lookup::LookupOptions;
use crate::field::scene::FieldInstance;
use crate::render::ao::AoOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;
use std::sync::Mutex;
use std::time::{Duration, Instant};

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

/// The kernel's own input (after the shared header's bindings): the ray directions.
const DIRECTIONS: u32 = 1;

/// Field-lookup vertex AO over a set of field instances, uploaded once (Gaitatzes et al., WSCG
/// 2008 Algorithm 2 and the WSCG 2010 intra-object test): its own bindings in group 0, the
/// fields in a `FieldBinding` (src/gpu/field_binding.rs).
pub struct FieldAoKernel<'a> {
    core: FieldKernel<'a>,
    /// The AO pipeline per selection code ([`selection_code`]), compiled on first use: the
    /// selection is a shader constant (`AO_SELECTION`) so that the compiler drops the other's
    /// code, which llvmpipe would run masked for every ray.
    ao: Mutex<[Option<wgpu::ComputePipeline>; 2]>,
    /// Kernel source without `AO_SELECTION`, and its entry point.
    ao_source: (String, &'static str),
    probe: wgpu::ComputePipeline,
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
        let core = FieldKernel::new(ctx, instances, opts, "field ao", DIRECTIONS)?;
        let mut source = core.source(&[include_str!("../../shaders/field_ao.wgsl")]);
        let entry = if opts.queue_rays {
            "ao_main"
        } else {
            "ao_main_direct"
        };
        let probe = core.pipeline(
            "field_probe",
            &(ao_selection_const(0) + &source),
            "probe_main",
        )?;
        source.shrink_to_fit();
        let kernel = FieldAoKernel {
            core,
            ao: Mutex::new([None, None]),
            ao_source: (source, entry),
            probe,
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
        let (source, entry) = &self.ao_source;
        let p = self
            .core
            .pipeline("field_ao", &(ao_selection_const(code) + source), entry)?;
        cache[code as usize] = Some(p.clone());
        Ok(p)
    }

    /// Bytes of stored distances on the device.
    pub fn field_bytes(&self) -> u64 {
        self.core.field.field_bytes()
    }

    /// Storage windows the fields occupy (storage layout), `None` for the texture layout.
    pub fn storage_windows(&self) -> Option<usize> {
        self.core.field.storage_windows()
    }

    /// Slices of the field texture (texture layout), `None` for the storage layout.
    pub fn texture_depth(&self) -> Option<u32> {
        self.core.field.texture_depth()
    }

    /// Rays per invocation the next call starts with: the options' value divided by the
    /// instance count, or less where a driver cut an earlier call's invocations short.
    pub fn rays_per_invocation(&self) -> u32 {
        self.core.rays_per_invocation()
    }

    /// Moves the instances to `instances`' transforms, the fields staying on the device (the
    /// same fields, instance by instance, as at `new`): a moving rigid object's per-frame cost.
    pub fn place(&self, instances: &[FieldInstance]) -> Result<(), GpuError> {
        self.core.place(instances)
    }

    /// Host time of packing, uploading and compiling in [`Self::new`].
    pub fn setup_time(&self) -> Duration {
        self.upload
    }

    /// AO at every point (point `i` uses the directions of point index `i` of `rays`), as
    /// [`crate::render::ao::ao_at_points`] computes it over a [`crate::field::scene::FieldScene`] of
    /// the same instances and lookup options.
    pub fn ao(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        let start = Instant::now();
        let base = base_directions(rays)?;
        let recv = receivers(points, normals, rays)?;
        let max_binding = self.core.ctx.max_binding();
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
            .core
            .ctx
            .storage_buffer("ray directions", bytemuck::cast_slice(&base));
        let mut params = KernelParamsGpu {
            tmax: opts.max_distance.unwrap_or(f32::MAX).min(f32::MAX),
            ..self
                .core
                .params(&self.lookup, base.len() as u32, opts.offset)
        };
        let pipeline = self.ao_pipeline(params.selection)?;
        let (ao, kernel, upload) = free_fractions(
            &self.core.rays_per_invocation,
            base.len() as u32,
            recv.len(),
            |per_invocation, per_point| {
                params.rays_per_invocation = per_invocation;
                params.invocations_per_point = per_point;
                self.core
                    .run(&pipeline, params, &recv, &[&dirs], (per_point, 1))
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
        let params = KernelParamsGpu {
            point_count: u.len() as u32,
            instance_count: self.core.field.instance_count(),
            ..Default::default()
        };
        // The probe reads no ray directions; the shared layout wants a buffer all the same.
        let no_dirs = self.core.ctx.storage_buffer("no ray directions", &[]);
        let (words, _, _) = self
            .core
            .run(&self.probe, params, &recv, &[&no_dirs], (1, 4))?;
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
}

/// WGSL `AO_SELECTION`, the AO kernel's selection code.
fn ao_selection_const(code: u32) -> String {
    format!("const AO_SELECTION: u32 = {code}u;\n")
}
