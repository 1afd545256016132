//! What the two AO kinds share (Gaitatzes, Chrysanthou, Papaioannou, WSCG 2008; per pixel:
//! Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010): their options (`max_distance`,
//! `falloff`) and their validation, the estimator, and the GPU's AO kernels.

use super::super::backend::{Estimate, Eval};
use super::super::backend_gpu::{traced, GpuQuantity, KernelEval};
use super::super::spec::{Backend, Spec, SpecError};
use super::super::validate::Validator;
use super::super::Result;
use crate::field::scene::FieldScene;
use crate::gpu::{FieldAoKernel, FieldGpuOptions, GpuContext, GpuTracer};
use crate::render::ao::{AoOptions, Falloff};
use crate::render::estimator::{AoEstimator, Points};
use crate::sampling::rays::RaySet;
use serde::{Deserialize, Serialize};

/// The options of the AO kinds.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AoRender {
    /// AO radius in world units: farther hits do not occlude (none: unlimited, the papers).
    #[serde(default)]
    pub max_distance: Option<f32>,
    /// How a hit within `max_distance` occludes: "step" (binary, the papers' V; default) or
    /// "linear" (a hit at t occludes by 1 − t/max_distance; needs `max_distance`). Applied
    /// identically to the ray cast, the field lookup and the converged reference.
    #[serde(default)]
    pub falloff: Falloff,
}

impl AoRender {
    /// The AO estimator: the spec's radius and falloff, and no ray offset of its own (the
    /// points are the ray origins, each moved off its surface by its instance's offset:
    /// `EvalPoints::at`).
    pub fn estimator(&self) -> AoEstimator {
        AoEstimator {
            opts: AoOptions {
                max_distance: self.max_distance,
                offset: 0.0,
                falloff: self.falloff,
            },
        }
    }

    /// The GPU's AO kernels for [`Self::estimator`].
    pub fn gpu(&self) -> Box<dyn GpuQuantity> {
        Box::new(AoGpu(self.estimator().opts))
    }

    /// A positive finite radius; a distance falloff needs a radius and the CPU (the GPU
    /// kernels have binary visibility only).
    pub fn validate(&self, spec: &Spec, v: &Validator) -> std::result::Result<(), SpecError> {
        if let Some(d) = self.max_distance {
            if !(d > 0.0 && d.is_finite()) {
                return Err(v.err(
                    "render.max_distance",
                    format!("{d} must be positive and finite"),
                ));
            }
        }
        if self.falloff != Falloff::Step {
            if self.max_distance.is_none() {
                return Err(v.err(
                    "render.falloff",
                    "a distance falloff needs `render.max_distance`".into(),
                ));
            }
            if spec.backends.contains(&Backend::Gpu) {
                return Err(v.err(
                    "render.falloff",
                    "the GPU path has binary visibility only; use \"step\" or \"cpu\"".into(),
                ));
            }
        }
        Ok(())
    }
}

/// AO on the GPU: [`FieldAoKernel`] for field lookup, [`GpuTracer::ao`] for ray casting.
struct AoGpu(AoOptions);

impl GpuQuantity for AoGpu {
    fn fields<'s>(
        &'s self,
        ctx: &'s GpuContext,
        fields: &'s FieldScene,
        opts: &FieldGpuOptions,
    ) -> Result<Box<dyn Eval + 's>> {
        Ok(Box::new(KernelEval {
            kernel: FieldAoKernel::new(ctx, &fields.instances, opts)?,
            opts: self.0,
            run: |k, at, rays, o| k.vertex_ao(at.points, at.normals, rays, o),
            setup: FieldAoKernel::setup_time,
        }))
    }

    fn trace(&self, tracer: &GpuTracer, at: Points, rays: &RaySet) -> Result<Estimate> {
        traced(tracer.ao(at.points, at.normals, rays, &self.0))
    }
}
