//! What the two AO kinds share (Gaitatzes, Chrysanthou, Papaioannou, WSCG 2008; per pixel:
//! Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010): their options (`max_distance`,
//! `falloff`) and their validation, the estimator, the GPU's AO kernels, and the kind itself
//! ([`AoKind`]), generic over where it evaluates ([`AoPoints`]: `vertex_ao.rs`, `image_ao.rs`).

use super::super::backend::{Estimate, Eval};
use super::super::backend_gpu::{traced, GpuQuantity, KernelEval};
use super::super::scenes::BuiltScene;
use super::super::spec::{Backend, RenderSpec, Spec, SpecError};
use super::super::validate::Validator;
use super::super::Result;
use super::{Answers, Columns, Kind, KindOptions, Needs, Setup};
use crate::field::scene::FieldScene;
use crate::gpu::{FieldAoKernel, FieldGpuOptions, GpuContext, GpuVisibility};
use crate::render::ao::{AoOptions, Falloff};
use crate::render::estimator::{AoEstimator, Points};
use crate::render::points::{EvalPoints, GBuffer};
use crate::sampling::rays::RaySet;
use serde::{Deserialize, Serialize};
use std::marker::PhantomData;

/// The options of the AO kinds.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AoRender {
    /// AO radius in world units: farther hits do not occlude (none: unlimited, the papers).
    pub max_distance: Option<f32>,
    /// How a hit within `max_distance` occludes: "step" (binary, the papers' V; default) or
    /// "linear" (a hit at t occludes by 1 − t/max_distance; needs `max_distance`). Applied
    /// identically to the ray cast, the field lookup and the converged reference.
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

/// AO on the GPU: [`FieldAoKernel`] for field lookup, the AO integrand ([`crate::gpu::ao`]) on
/// any GPU visibility for ray casting.
struct AoGpu(AoOptions);

impl GpuQuantity for AoGpu {
    fn fields<'s>(
        &'s self,
        ctx: &'s GpuContext,
        fields: &FieldScene,
        opts: &FieldGpuOptions,
    ) -> Result<Box<dyn Eval + 's>> {
        Ok(Box::new(KernelEval {
            kernel: FieldAoKernel::new(ctx, &fields.instances, opts)?,
            opts: self.0,
            run: |k, at, rays, o| k.ao(at.points, at.normals, rays, o),
            setup: FieldAoKernel::setup_time,
            place: FieldAoKernel::place,
        }))
    }

    fn trace(&self, vis: &dyn GpuVisibility, at: Points, rays: &RaySet) -> Result<Estimate> {
        traced(crate::gpu::ao(vis, at.points, at.normals, rays, &self.0))
    }
}

/// Where an AO kind evaluates, the one thing the AO kinds differ in.
pub trait AoPoints: Clone + std::fmt::Debug + Send + Sync + 'static {
    /// The kind's name (`render.what`).
    const NAME: &'static str;
    /// What it needs built.
    fn needs() -> Needs;
    /// Which metric columns it fills.
    fn columns() -> Columns;
    /// The most points a scene can have.
    fn max_points(render: &RenderSpec, scene: &BuiltScene) -> u64;
    /// The points on `scene` (`view`: the G-buffer, for a kind that needs one).
    fn points(scene: &BuiltScene, view: Option<&GBuffer>) -> EvalPoints;
}

/// The options of an AO kind evaluated at `P`: [`AoRender`]'s keys.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(transparent)]
pub struct AoKindOptions<P: AoPoints> {
    pub ao: AoRender,
    #[serde(skip)]
    points: PhantomData<P>,
}

impl<P: AoPoints> KindOptions for AoKindOptions<P> {
    fn validate(
        &self,
        _render: &RenderSpec,
        spec: &Spec,
        v: &Validator,
    ) -> std::result::Result<(), SpecError> {
        self.ao.validate(spec, v)
    }

    fn kind(&self, render: &RenderSpec) -> Box<dyn Kind> {
        Box::new(AoKind::<P> {
            render: render.clone(),
            ao: self.ao.clone(),
            points: PhantomData,
        })
    }
}

/// An AO kind on one spec's `render`, evaluated at `P`.
pub struct AoKind<P: AoPoints> {
    render: RenderSpec,
    ao: AoRender,
    points: PhantomData<P>,
}

impl<P: AoPoints> Kind for AoKind<P> {
    fn name(&self) -> &'static str {
        P::NAME
    }

    fn render(&self) -> &RenderSpec {
        &self.render
    }

    fn answers(&self) -> Answers<'_> {
        Answers::Ao(&self.ao)
    }

    fn needs(&self) -> Needs {
        P::needs()
    }

    fn columns(&self) -> Columns {
        P::columns()
    }

    fn max_points(&self, scene: &BuiltScene) -> u64 {
        P::max_points(&self.render, scene)
    }

    fn setup(&self, scene: &BuiltScene, view: Option<&GBuffer>) -> Setup {
        let points = P::points(scene, view);
        Setup {
            offset: points.max_offset(),
            points,
            estimator: Box::new(self.ao.estimator()),
            gpu: Some(self.ao.gpu()),
            shading: None,
            second_reference: None,
        }
    }
}
