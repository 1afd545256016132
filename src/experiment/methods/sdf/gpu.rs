//! The `sdf` method on the `gpu` backend: the scene's distance volumes uploaded once
//! ([`SdfKernel`]), answering what the setting answers on the CPU with the same arithmetic
//! (src/gpu/sdf_kernel.rs): `trace`, AO by sphere tracing the reference's rays; `cone`,
//! cone-traced AO and the cone-traced light fraction. Sphere-traced shadows and reflections
//! have no kernel: the setting refuses those kinds on the `gpu` backend, by name.

use super::cone::Quantity;
use crate::experiment::backend::{Estimate, Eval};
use crate::experiment::backend_gpu::GpuQuantity;
use crate::experiment::methods::GpuMethod;
use crate::experiment::Result;
use crate::gpu::{GpuContext, GpuTiming, SdfKernel};
use crate::render::ao::{AoOptions, Falloff};
use crate::render::estimator::Points;
use crate::sampling::rays::RaySet;
use crate::sdf::{ConeLight, ConeSet, ConeTrace, SdfScene};

/// What the kernels answer.
pub(super) enum GpuQuery {
    /// AO through sphere tracing, on the reference's rays.
    TraceAo(AoOptions),
    /// Cone-traced AO from `point + offset · normal`, each cone to `tmax`.
    ConeAo {
        offset: f32,
        tmax: f32,
        cones: ConeSet,
        trace: ConeTrace,
    },
    /// The cone-traced light fraction.
    ConeLight {
        offset: f32,
        lights: Vec<ConeLight>,
        trace: ConeTrace,
    },
}

impl GpuQuery {
    /// The trace query's kernel for the kind's quantity: AO only.
    pub(super) fn trace(q: &Quantity) -> Option<GpuQuery> {
        match q {
            Quantity::Ao { offset, tmax } => Some(GpuQuery::TraceAo(AoOptions {
                max_distance: tmax.is_finite().then_some(*tmax),
                offset: *offset,
                falloff: Falloff::Step,
            })),
            Quantity::Light { .. } => None,
        }
    }

    /// The cone query's kernel for the kind's quantity.
    pub(super) fn cone(q: &Quantity, cones: ConeSet, trace: ConeTrace) -> GpuQuery {
        match q {
            Quantity::Ao { offset, tmax } => GpuQuery::ConeAo {
                offset: *offset,
                tmax: *tmax,
                cones,
                trace,
            },
            Quantity::Light { offset, lights } => GpuQuery::ConeLight {
                offset: *offset,
                lights: lights.clone(),
                trace,
            },
        }
    }
}

/// The prepared volumes and what they answer, ready to upload.
pub(super) struct SdfGpu {
    pub scene: SdfScene,
    pub query: GpuQuery,
}

impl GpuMethod for SdfGpu {
    fn upload<'a>(
        &'a self,
        ctx: &'a GpuContext,
        _: Option<&'a dyn GpuQuantity>,
    ) -> Result<Box<dyn Eval + 'a>> {
        Ok(Box::new(SdfEval {
            kernel: SdfKernel::new(ctx, &self.scene)?,
            query: &self.query,
        }))
    }
}

struct SdfEval<'a> {
    kernel: SdfKernel<'a>,
    query: &'a GpuQuery,
}

impl Eval for SdfEval<'_> {
    fn estimate(&self, at: Points, rays: &RaySet) -> Result<Estimate> {
        let (p, n) = (at.points, at.normals);
        let (values, t): (Vec<f32>, GpuTiming) = match self.query {
            GpuQuery::TraceAo(opts) => self.kernel.ao(p, n, rays, opts)?,
            GpuQuery::ConeAo {
                offset,
                tmax,
                cones,
                trace,
            } => self.kernel.cone_ao(p, n, cones, (*offset, *tmax), trace)?,
            GpuQuery::ConeLight {
                offset,
                lights,
                trace,
            } => self
                .kernel
                .cone_light_fractions(p, n, lights, *offset, trace)?,
        };
        Ok(Estimate {
            values,
            kernel_s: t.kernel.map(|d| d.as_secs_f64()),
        })
    }

    fn setup_s(&self) -> Option<f64> {
        Some(self.kernel.setup_time().as_secs_f64())
    }
}
