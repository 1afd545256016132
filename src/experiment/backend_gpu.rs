//! The GPU backend of a run (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010: field
//! lookup on the GPU, compared there with a GPU BVH ray caster): field-lookup AO through
//! [`FieldAoKernel`] and ray-cast AO through [`GpuTracer`] (an obvhs CWBVH in WGSL), on the
//! rays of the CPU path (the same seeded k² cell centres, rotated per point by the same
//! angles, from the same offset origins).
//!
//! Each estimator runs on the kernel of its quantity: the AO estimators
//! ([`Estimator::ao_options`]) on the two AO kernels; an estimator without a kernel is refused
//! with [`GpuError::Unsupported`], naming it.
//!
//! Times: the runner times [`Eval::estimate`] on the host, which is the call's wall time
//! (receiver upload, dispatch, wait and read-back); the kernel alone, from GPU timestamps, comes
//! back in [`Estimate::kernel_s`]; packing and uploading the fields (or building and uploading
//! the CWBVH) and compiling the shaders is [`Eval::setup_s`], reported apart.

use super::backend::{Casters, ComputeBackend, Estimate, Eval};
use super::spec::Backend;
use super::Result;
use crate::field::scene::FieldScene;
use crate::gpu::{
    AdapterPreference, FieldAoKernel, FieldGpuOptions, FieldLayout, GpuContext, GpuError,
    GpuTiming, GpuTracer,
};
use crate::render::ao::AoOptions;
use crate::render::estimator::{Estimator, Points};
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
    pub fn open(pref: AdapterPreference) -> Result<GpuBackend> {
        let ctx = GpuContext::new(pref)?;
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

fn out(values: Vec<f32>, t: GpuTiming) -> Estimate {
    Estimate {
        values,
        kernel_s: t.kernel.map(|d| d.as_secs_f64()),
    }
}

/// The AO options of `est`, or the refusal naming it.
fn ao_options(est: &dyn Estimator) -> Result<AoOptions> {
    est.ao_options().copied().ok_or_else(|| {
        GpuError::Unsupported(format!("no GPU kernel computes \"{}\"", est.name())).into()
    })
}

struct FieldEval<'a> {
    kernel: FieldAoKernel<'a>,
    opts: AoOptions,
}

impl Eval for FieldEval<'_> {
    fn estimate(&self, at: Points, rays: &RaySet) -> Result<Estimate> {
        let (ao, t) = self
            .kernel
            .vertex_ao(at.points, at.normals, rays, &self.opts)?;
        Ok(out(ao, t))
    }

    fn setup_s(&self) -> Option<f64> {
        Some(self.kernel.setup_time().as_secs_f64())
    }
}

struct TraceEval<'a> {
    tracer: GpuTracer<'a>,
    opts: AoOptions,
}

impl Eval for TraceEval<'_> {
    fn estimate(&self, at: Points, rays: &RaySet) -> Result<Estimate> {
        let (ao, t) = self.tracer.ao(at.points, at.normals, rays, &self.opts)?;
        Ok(out(ao, t))
    }

    fn setup_s(&self) -> Option<f64> {
        Some(self.tracer.setup_time().as_secs_f64())
    }
}

impl ComputeBackend for GpuBackend {
    fn kind(&self) -> Backend {
        Backend::Gpu
    }

    /// "name | driver driver_info | Vulkan" ([`GpuContext::adapter_label`]).
    fn adapter(&self) -> String {
        self.ctx.adapter_label()
    }

    fn fields<'s>(
        &'s self,
        fields: &'s FieldScene,
        est: &'s dyn Estimator,
    ) -> Result<Box<dyn Eval + 's>> {
        let ao = ao_options(est)?;
        let opts = FieldGpuOptions {
            lookup: fields.options,
            layout: self.layout,
            ..Default::default()
        };
        let kernel = FieldAoKernel::new(&self.ctx, &fields.instances, &opts)?;
        Ok(Box::new(FieldEval { kernel, opts: ao }))
    }

    fn casters<'s>(
        &'s self,
        casters: &'s Casters<'s>,
        est: &'s dyn Estimator,
    ) -> Result<Box<dyn Eval + 's>> {
        let ao = ao_options(est)?;
        let tracer = GpuTracer::new(&self.ctx, casters.triangles)?;
        Ok(Box::new(TraceEval { tracer, opts: ao }))
    }
}
