//! The GPU backend of a run (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010: field
//! lookup on the GPU, compared there with a GPU BVH ray caster): field-lookup AO through
//! [`FieldAoKernel`], field-lookup soft shadows (§4.2) through [`FieldShadowKernel`],
//! field-lookup glossy reflections (§4.2, with the normal fields) through
//! [`FieldReflectKernel`], and ray-cast AO, shadows and reflections through [`GpuTracer`] (an
//! obvhs CWBVH in WGSL), on the rays of the CPU path (the same seeded k² cell centres, rotated
//! per point by the same angles, from the same offset origins; for shadows mapped into each
//! light's cone, for reflections into the Phong lobe about the mirror direction, as on the
//! CPU).
//!
//! Each estimator runs on the kernels of its quantity: the AO estimators
//! ([`Estimator::ao_options`]) on the two AO kernels, the shadow estimators
//! ([`Estimator::shadow_options`]) on the two shadow kernels, the reflection estimators
//! ([`Estimator::reflect_options`]) on the two reflection kernels (the field kernel needs every
//! instance's normal field, which the run attaches for reflections); an estimator without a
//! kernel is refused with [`GpuError::Unsupported`], naming it.
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
    AdapterPreference, FieldAoKernel, FieldGpuOptions, FieldLayout, FieldReflectKernel,
    FieldShadowKernel, GpuContext, GpuError, GpuTiming, GpuTracer,
};
use crate::render::ao::AoOptions;
use crate::render::estimator::{Estimator, Points};
use crate::render::reflect::ReflectOptions;
use crate::render::shadow::ShadowOptions;
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

/// The quantity of an estimator that has GPU kernels.
#[derive(Clone, Debug)]
enum Quantity {
    Ao(AoOptions),
    Shadow(ShadowOptions),
    Reflect(ReflectOptions),
}

/// The quantity `est` computes, or the refusal naming it.
fn quantity(est: &dyn Estimator) -> Result<Quantity> {
    if let Some(ao) = est.ao_options() {
        return Ok(Quantity::Ao(*ao));
    }
    if let Some(sh) = est.shadow_options() {
        return Ok(Quantity::Shadow(sh.clone()));
    }
    if let Some(r) = est.reflect_options() {
        return Ok(Quantity::Reflect(r.clone()));
    }
    Err(GpuError::Unsupported(format!("no GPU kernel computes \"{}\"", est.name())).into())
}

/// Field lookup on the kernel of the estimator's quantity.
enum FieldEval<'a> {
    Ao(FieldAoKernel<'a>, AoOptions),
    Shadow(FieldShadowKernel<'a>, ShadowOptions),
    Reflect(FieldReflectKernel<'a>, ReflectOptions),
}

impl Eval for FieldEval<'_> {
    fn estimate(&self, at: Points, rays: &RaySet) -> Result<Estimate> {
        let (values, t) = match self {
            FieldEval::Ao(k, o) => k.vertex_ao(at.points, at.normals, rays, o)?,
            FieldEval::Shadow(k, o) => k.light_fractions(at.points, at.normals, rays, o)?,
            FieldEval::Reflect(k, o) => k.reflections(at.points, at.normals, rays, o)?,
        };
        Ok(out(values, t))
    }

    fn setup_s(&self) -> Option<f64> {
        let setup = match self {
            FieldEval::Ao(k, _) => k.setup_time(),
            FieldEval::Shadow(k, _) => k.setup_time(),
            FieldEval::Reflect(k, _) => k.setup_time(),
        };
        Some(setup.as_secs_f64())
    }
}

/// Ray casting on the GPU tracer, the entry of the estimator's quantity.
struct TraceEval<'a> {
    tracer: GpuTracer<'a>,
    quantity: Quantity,
}

impl Eval for TraceEval<'_> {
    fn estimate(&self, at: Points, rays: &RaySet) -> Result<Estimate> {
        let (values, t) = match &self.quantity {
            Quantity::Ao(o) => self.tracer.ao(at.points, at.normals, rays, o)?,
            Quantity::Shadow(o) => self.tracer.shadows(at.points, at.normals, rays, o)?,
            Quantity::Reflect(o) => self.tracer.reflections(at.points, at.normals, rays, o)?,
        };
        Ok(out(values, t))
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
        let quantity = quantity(est)?;
        let opts = FieldGpuOptions {
            lookup: fields.options,
            layout: self.layout,
            ..Default::default()
        };
        let eval = match quantity {
            Quantity::Ao(ao) => {
                FieldEval::Ao(FieldAoKernel::new(&self.ctx, &fields.instances, &opts)?, ao)
            }
            Quantity::Shadow(sh) => FieldEval::Shadow(
                FieldShadowKernel::new(&self.ctx, &fields.instances, &opts)?,
                sh,
            ),
            Quantity::Reflect(r) => FieldEval::Reflect(
                FieldReflectKernel::new(&self.ctx, &fields.instances, &opts)?,
                r,
            ),
        };
        Ok(Box::new(eval))
    }

    fn casters<'s>(
        &'s self,
        casters: &'s Casters<'s>,
        est: &'s dyn Estimator,
    ) -> Result<Box<dyn Eval + 's>> {
        let quantity = quantity(est)?;
        let tracer = GpuTracer::new(&self.ctx, casters.triangles)?;
        Ok(Box::new(TraceEval { tracer, quantity }))
    }
}
