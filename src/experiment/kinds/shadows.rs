//! `"shadows"`: soft shadows from spherical lights per pixel (Gaitatzes, Andreadis,
//! Papaioannou, Chrysanthou, WSCG 2010, §4.2, Figures 7–8): the light fraction of
//! `render::shadow` at every receiver pixel, its shadow rays answered by ray casting or by the
//! fields; needs `image` and `lights`.

use super::{read_as, Answers, Columns, Kind, KindEntry, KindOptions, Needs, Setup};
use crate::experiment::backend::{Estimate, Eval};
use crate::experiment::backend_gpu::{traced, GpuQuantity, KernelEval};
use crate::experiment::scenes::BuiltScene;
use crate::experiment::spec::{RenderSpec, Spec, SpecError};
use crate::experiment::validate::Validator;
use crate::experiment::Result;
use crate::field::scene::FieldScene;
use crate::gpu::{FieldGpuOptions, FieldShadowKernel, GpuContext, GpuVisibility};
use crate::render::estimator::Points;
use crate::render::points::{EvalPoints, GBuffer};
use crate::render::shadow::{direct_light, ShadowEstimator, ShadowOptions, SphereLight};
use crate::sampling::rays::RaySet;
use serde::{Deserialize, Serialize};

/// The registry's line for this kind.
pub const ENTRY: KindEntry = KindEntry {
    name: "shadows",
    about: "soft shadows from spherical lights at every receiver pixel (2010 §4.2)",
    read: read_as::<ShadowRender>,
};

/// The options of soft shadows (`render::shadow`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShadowRender {
    /// The spherical lights (at least one), in the spec's world coordinates.
    pub lights: Vec<SphereLight>,
}

impl KindOptions for ShadowRender {
    fn validate(
        &self,
        _render: &RenderSpec,
        _spec: &Spec,
        v: &Validator,
    ) -> std::result::Result<(), SpecError> {
        validate_lights(ENTRY.name, &self.lights, v)
    }

    fn kind(&self, render: &RenderSpec) -> Box<dyn Kind> {
        Box::new(Shadows {
            render: render.clone(),
            opts: self.clone(),
        })
    }
}

/// Soft shadows on one spec's `render`.
pub struct Shadows {
    render: RenderSpec,
    opts: ShadowRender,
}

/// A kind's lights: at least one, each valid ([`Validator::lights`]).
pub fn validate_lights(
    kind: &str,
    lights: &[SphereLight],
    v: &Validator,
) -> std::result::Result<(), SpecError> {
    if lights.is_empty() {
        return Err(v.err(
            "render.lights",
            format!("is empty: \"{kind}\" needs at least one light"),
        ));
    }
    v.lights(lights)
}

/// Lights in the scene's frame (moved as the camera is).
pub fn lights_in_frame(lights: &[SphereLight], scene: &BuiltScene) -> Vec<SphereLight> {
    lights
        .iter()
        .map(|l| SphereLight {
            center: crate::geometry::rebase::to_frame(scene.origin, l.center),
            ..*l
        })
        .collect()
}

impl Kind for Shadows {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn render(&self) -> &RenderSpec {
        &self.render
    }

    fn answers(&self) -> Answers<'_> {
        Answers::Shadow
    }

    fn needs(&self) -> Needs {
        Needs {
            view: true,
            ..Needs::default()
        }
    }

    fn columns(&self) -> Columns {
        Columns { vertex: false }
    }

    /// A point light (radius 0) casts one ray per point, a sphere light k².
    fn rays_cast_per_point(&self) -> u64 {
        let k2 = self.rays_per_point() as u64;
        self.opts
            .lights
            .iter()
            .map(|l| if l.radius == 0.0 { 1 } else { k2 })
            .sum()
    }

    fn max_points(&self, _scene: &BuiltScene) -> u64 {
        super::pixels(self.render.image.as_ref())
    }

    fn setup(&self, scene: &BuiltScene, view: Option<&GBuffer>) -> Setup {
        let view = view.expect("shadows: validation guarantees an image, and so a G-buffer");
        let lights = lights_in_frame(&self.opts.lights, scene);
        let points = EvalPoints::pixels(&scene.scene, view);
        // The points are the ray origins (EvalPoints::at): no offset of the estimator's own.
        let opts = ShadowOptions {
            offset: 0.0,
            lights,
        };
        // The direct light on a white diffuse receiver, from 8² centred rays per light.
        let at = points.at();
        let shading = direct_light(at.points, at.normals, &RaySet::new(8, 1), &opts);
        Setup {
            offset: points.max_offset(),
            points,
            gpu: Some(Box::new(ShadowGpu(opts.clone()))),
            estimator: Box::new(ShadowEstimator { opts }),
            shading: Some(shading),
            second_reference: None,
        }
    }

    /// A light that overlaps a caster's bounding sphere would sit inside the field's domain
    /// (and likely inside the caster): refused, naming the light and the instance.
    fn scene_problem(&self, scene: &BuiltScene) -> Option<(String, String)> {
        for (i, l) in lights_in_frame(&self.opts.lights, scene).iter().enumerate() {
            for (ii, inst) in scene.scene.casters() {
                let s = inst.world_bounding_sphere();
                if l.center.distance(s.center) < s.radius + l.radius {
                    return Some((
                        format!("render.lights[{i}]"),
                        format!(
                            "overlaps the bounding sphere of caster instance {ii} of scene `{}` \
                             (centre {}, radius {}): a light must lie outside every caster's sphere",
                            scene.name, s.center, s.radius
                        ),
                    ));
                }
            }
        }
        None
    }
}

/// Soft shadows on the GPU: [`FieldShadowKernel`] for field lookup, the shadow integrand
/// ([`crate::gpu::shadows`]) on any GPU visibility for ray casting.
struct ShadowGpu(ShadowOptions);

impl GpuQuantity for ShadowGpu {
    fn fields<'s>(
        &'s self,
        ctx: &'s GpuContext,
        fields: &FieldScene,
        opts: &FieldGpuOptions,
    ) -> Result<Box<dyn Eval + 's>> {
        Ok(Box::new(KernelEval {
            kernel: FieldShadowKernel::new(ctx, &fields.instances, opts)?,
            opts: self.0.clone(),
            run: |k, at, rays, o| crate::gpu::shadows(k, at.points, at.normals, rays, o),
            setup: FieldShadowKernel::setup_time,
            place: FieldShadowKernel::place,
        }))
    }

    fn trace(&self, vis: &dyn GpuVisibility, at: Points, rays: &RaySet) -> Result<Estimate> {
        traced(crate::gpu::shadows(
            vis, at.points, at.normals, rays, &self.0,
        ))
    }
}
