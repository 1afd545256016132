//! The GPU backend of a run (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010: field
//! lookup on the GPU, compared there with a GPU BVH ray caster): field-lookup AO through
//! [`FieldAoKernel`] and ray-cast AO through [`GpuTracer`] (an obvhs CWBVH in WGSL), on the
//! rays of the CPU path (the same seeded k² cell centres, rotated per point by the same
//! angles, from the same offset origins).
//!
//! Times: the runner times [`AoEval::ao`] on the host, which is the call's wall time (receiver
//! upload, dispatch, wait and read-back); the kernel alone, from GPU timestamps, comes back in
//! [`AoOut::kernel_s`]; packing and uploading the fields (or building and uploading the CWBVH)
//! and compiling the shaders is [`AoEval::setup_s`], reported apart.

use super::backend::{AoBackend, AoEval, AoOut, Casters, Points};
use super::spec::Backend;
use crate::field::scene::FieldScene;
use crate::gpu::{
    AdapterPreference, FieldAoKernel, FieldGpuOptions, FieldLayout, GpuContext, GpuError,
    GpuTiming, GpuTracer,
};
use crate::render::ao::AoOptions;
use crate::sampling::rays::RaySet;

/// The wgpu device a run's "gpu" cells use, opened once per run.
pub struct GpuBackend {
    ctx: GpuContext,
    /// How the fields are bound (the faster on our measurements is the default, see
    /// [`FieldGpuOptions::default`]).
    pub layout: FieldLayout,
}

impl GpuBackend {
    /// Opens the adapter `pref` selects; the error says which adapters exist.
    pub fn open(pref: AdapterPreference) -> Result<GpuBackend, String> {
        let ctx = GpuContext::new(pref).map_err(|e| format!("backend \"gpu\": {e}"))?;
        Ok(GpuBackend {
            ctx,
            layout: FieldGpuOptions::default().layout,
        })
    }

    /// The device.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }
}

fn gpu_err(e: GpuError) -> String {
    format!("backend \"gpu\": {e}")
}

fn out(ao: Vec<f32>, t: GpuTiming) -> AoOut {
    AoOut {
        ao,
        kernel_s: t.kernel.map(|d| d.as_secs_f64()),
    }
}

struct FieldEval<'a>(FieldAoKernel<'a>);

impl AoEval for FieldEval<'_> {
    fn ao(&self, at: &Points, rays: &RaySet, opts: &AoOptions) -> Result<AoOut, String> {
        let (ao, t) = self
            .0
            .vertex_ao(at.points, at.normals, rays, opts)
            .map_err(gpu_err)?;
        Ok(out(ao, t))
    }

    fn setup_s(&self) -> Option<f64> {
        Some(self.0.setup_time().as_secs_f64())
    }
}

struct TraceEval<'a>(GpuTracer<'a>);

impl AoEval for TraceEval<'_> {
    fn ao(&self, at: &Points, rays: &RaySet, opts: &AoOptions) -> Result<AoOut, String> {
        let (ao, t) = self
            .0
            .ao(at.points, at.normals, rays, opts)
            .map_err(gpu_err)?;
        Ok(out(ao, t))
    }

    fn setup_s(&self) -> Option<f64> {
        Some(self.0.setup_time().as_secs_f64())
    }
}

impl AoBackend for GpuBackend {
    fn kind(&self) -> Backend {
        Backend::Gpu
    }

    /// "name | driver driver_info | Vulkan" ([`GpuContext::adapter_label`]).
    fn adapter(&self) -> String {
        self.ctx.adapter_label()
    }

    fn fields<'s>(&'s self, fields: &'s FieldScene) -> Result<Box<dyn AoEval + 's>, String> {
        let opts = FieldGpuOptions {
            lookup: fields.options,
            layout: self.layout,
            ..Default::default()
        };
        let kernel = FieldAoKernel::new(&self.ctx, &fields.instances, &opts).map_err(gpu_err)?;
        Ok(Box::new(FieldEval(kernel)))
    }

    fn casters<'s>(&'s self, casters: &'s Casters<'s>) -> Result<Box<dyn AoEval + 's>, String> {
        let tracer = GpuTracer::new(&self.ctx, casters.triangles).map_err(gpu_err)?;
        Ok(Box::new(TraceEval(tracer)))
    }
}
