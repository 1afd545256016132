//! Vertex AO by field lookup on the GPU (Gaitatzes et al., WSCG 2008 Algorithm 2 and the WSCG
//! 2010 intra-object test), with the CPU path's ray directions and map selection.
//!
//! The AO integrand (shaders/ao.wgsl) on the field visibility (src/gpu/field_kernel.rs, which
//! says how it deviates from the CPU path), or by default the field's batched form of it
//! (shaders/field_ao.wgsl: each round of rays culled against the world spheres and the rays
//! that meet one answered by the workgroup; the same free-ray counts). The lookup is a
//! line-by-line f32 port of `field::lookup` and `field::scene`: the Slater / lat-long nearest
//! point (the CPU's owner table, else its cube grid's candidates, else 4 rings × 2 azimuths),
//! the Duff frame, the three layouts' `to_texel` (the concentric one after the CPU's texel
//! table), the interpolated selection's triangle walk and bilinear footprint. On lavapipe it
//! reproduces the CPU AO bit for bit in the parity tests.
//!
//! A point's rays are spread over several invocations ([`super::FieldGpuOptions::rays_per_invocation`],
//! halved where the driver cuts long invocations short: src/gpu/loop_budget.rs), and the
//! receivers over several dispatches where their buffers would pass the adapter's binding
//! limit, so any ray count and any number of points run.

use super::field_kernel::{Ao, FieldKernel, AO_QUEUE};
use super::integrand::{self, Integrand, IntegrandParamsGpu};
use super::rays::records;
use super::visibility::GpuVisibility;
use super::{GpuError, GpuTiming};
use crate::render::ao::AoOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;

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

/// Single lookups (shaders/field_ao.wgsl, `probe_main`).
const PROBE: Integrand = Integrand {
    entry: "probe_main",
    ..AO_QUEUE
};

/// Field-lookup vertex AO over a set of field instances, uploaded once (Gaitatzes et al., WSCG
/// 2008 Algorithm 2 and the WSCG 2010 intra-object test).
pub type FieldAoKernel<'a> = FieldKernel<'a, Ao>;

impl FieldKernel<'_, Ao> {
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
        let integrand = if self.queue_rays {
            &AO_QUEUE
        } else {
            &integrand::AO
        };
        integrand::ao_with(self, integrand, points, normals, rays, opts)
    }

    /// Single lookups on the field of the first instance: for unit sphere position `u[i]`
    /// (model space) and model direction `dirs[i]`, the nearest map, the texel, and the stored
    /// distance under both selections, for comparison with [`crate::field::VisibilityField`]'s
    /// `points.nearest`, `layout.to_texel` and `sample`.
    pub fn probe(&self, u: &[Vec3], dirs: &[Vec3]) -> Result<Vec<LookupProbe>, GpuError> {
        let recv = records(u, dirs, ("positions", "directions"), |_| (0.0, 0.0))?;
        let k = self.kernels().compiled(self, &PROBE)?;
        // The probe reads no ray directions; the shared layout wants a buffer all the same.
        let no_dirs = self.ctx.storage_buffer("no ray directions", &[]);
        let group = self.bind_group();
        let params = IntegrandParamsGpu::default();
        let (words, _, _) = (k.group).run(
            self.ctx,
            &k.pipeline,
            &[&group],
            params,
            &recv,
            &[&no_dirs],
            (1, 4),
        )?;
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
