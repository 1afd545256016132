//! `"reflections"`: glossy reflections per pixel (Gaitatzes, Andreadis, Papaioannou,
//! Chrysanthou, WSCG 2010, §4.2, Figure 9): the reflected radiance of `render::reflect` at every
//! receiver pixel, its reflection rays answered with a hit point and normal by ray casting or by
//! the distance and normal fields; the cells sweep the normal fields' precision, and a glossy
//! lobe is also measured against the perfect mirror (`second_reference`). Needs `image`,
//! `lights` and `gloss`.

use super::shadows::{lights_in_frame, validate_lights};
use super::{read_as, Answers, Columns, Kind, KindEntry, KindOptions, Needs, Setup};
use crate::experiment::backend::{Estimate, Eval};
use crate::experiment::backend_gpu::{traced, GpuQuantity, KernelEval};
use crate::experiment::scenes::BuiltScene;
use crate::experiment::spec::{RenderSpec, Spec, SpecError};
use crate::experiment::validate::Validator;
use crate::experiment::Result;
use crate::field::scene::FieldScene;
use crate::gpu::{FieldGpuOptions, FieldReflectKernel, GpuContext, GpuVisibility};
use crate::render::estimator::{Estimator, Points};
use crate::render::points::{EvalPoints, GBuffer};
use crate::render::reflect::{Gloss, ReflectOptions, ReflectionEstimator};
use crate::render::shadow::SphereLight;
use crate::sampling::rays::RaySet;
use serde::{Deserialize, Serialize};

/// The registry's line for this kind.
pub const ENTRY: KindEntry = KindEntry {
    name: "reflections",
    about:
        "glossy reflections through distance and normal fields at every receiver pixel (2010 §4.2)",
    read,
};

/// Reads the options, saying what `gloss` may be when it is missing.
fn read(v: serde_json::Value) -> Result<Box<dyn KindOptions>, serde_json::Error> {
    if v.get("gloss").is_none() {
        return Err(serde::de::Error::custom(
            "missing `gloss`, the receiver's lobe: \"mirror\" or {\"phong\": {\"exponent\": e}}",
        ));
    }
    read_as::<ReflectionRender>(v)
}

/// The default albedo of reflected surfaces.
pub const DEFAULT_ALBEDO: f32 = 0.8;
/// The default sky radiance of reflections.
pub const DEFAULT_SKY: f32 = 0.3;

fn default_albedo() -> f32 {
    DEFAULT_ALBEDO
}
fn default_sky() -> f32 {
    DEFAULT_SKY
}
fn default_normal_bits() -> Vec<u32> {
    vec![16]
}

/// The options of glossy reflections (`render::reflect`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReflectionRender {
    /// The lights shading the reflected surfaces (at least one; their centres light the hits).
    pub lights: Vec<SphereLight>,
    /// The receiver's lobe: `"mirror"` or `{"phong": {"exponent": e}}`.
    pub gloss: Gloss,
    /// Diffuse albedo of the reflected surfaces, in \[0, 1\] (default 0.8).
    #[serde(default = "default_albedo")]
    pub albedo: f32,
    /// Radiance of a reflection ray that meets nothing, in \[0, 1\] (default 0.3).
    #[serde(default = "default_sky")]
    pub sky: f32,
    /// Normal field precisions, bits per octahedral component (8 and/or 16; default \[16\]):
    /// a swept axis, one cell per precision.
    #[serde(default = "default_normal_bits")]
    pub normal_bits: Vec<u32>,
}

impl KindOptions for ReflectionRender {
    /// The lights as for shadows, a Phong exponent positive and finite, albedo and sky in
    /// \[0, 1\], normal precisions 8 or 16 bits, each once.
    fn validate(
        &self,
        _render: &RenderSpec,
        _spec: &Spec,
        v: &Validator,
    ) -> std::result::Result<(), SpecError> {
        validate_lights(ENTRY.name, &self.lights, v)?;
        if let Gloss::Phong { exponent } = self.gloss {
            if !(exponent > 0.0 && exponent.is_finite()) {
                return Err(v.err(
                    "render.gloss.phong.exponent",
                    format!("{exponent} must be positive and finite"),
                ));
            }
        }
        for (f, x) in [("render.albedo", self.albedo), ("render.sky", self.sky)] {
            if !(0.0..=1.0).contains(&x) {
                return Err(v.err(f, format!("{x} is outside [0, 1]")));
            }
        }
        if self.normal_bits.is_empty() {
            return Err(v.err("render.normal_bits", "is empty: list 8 and/or 16".into()));
        }
        for (i, &b) in self.normal_bits.iter().enumerate() {
            if !(b == 8 || b == 16) || self.normal_bits[..i].contains(&b) {
                return Err(v.err(
                    &format!("render.normal_bits[{i}]"),
                    format!("{b}: each of 8 and 16 bits per component at most once"),
                ));
            }
        }
        Ok(())
    }

    fn kind(&self, render: &RenderSpec) -> Box<dyn Kind> {
        Box::new(Reflections {
            render: render.clone(),
            opts: self.clone(),
        })
    }
}

/// Glossy reflections on one spec's `render`.
pub struct Reflections {
    render: RenderSpec,
    opts: ReflectionRender,
}

impl Reflections {
    fn options(&self, scene: &BuiltScene) -> ReflectOptions {
        let r = &self.opts;
        let image = self.image().expect("validation guarantees an image");
        ReflectOptions {
            // The points are the ray origins (EvalPoints::at).
            offset: 0.0,
            eye: scene.view_camera(image).eye,
            gloss: r.gloss,
            lights: lights_in_frame(&r.lights, scene),
            albedo: r.albedo,
            sky: r.sky,
        }
    }
}

impl Kind for Reflections {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn render(&self) -> &RenderSpec {
        &self.render
    }

    fn answers(&self) -> Answers<'_> {
        Answers::Reflection
    }

    fn needs(&self) -> Needs {
        Needs {
            view: true,
            normal_field: true,
        }
    }

    fn columns(&self) -> Columns {
        Columns { vertex: false }
    }

    /// A mirror casts one ray per point whatever `rays_per_point` says.
    fn rays_cast_per_point(&self) -> u64 {
        match self.opts.gloss {
            Gloss::Mirror => 1,
            Gloss::Phong { .. } => self.rays_per_point() as u64,
        }
    }

    fn max_points(&self, _scene: &BuiltScene) -> u64 {
        super::pixels(self.render.image.as_ref())
    }

    fn setup(&self, scene: &BuiltScene, view: Option<&GBuffer>) -> Setup {
        let opts = self.options(scene);
        let view = view.expect("reflections: validation guarantees an image, and so a G-buffer");
        let points = EvalPoints::pixels(&scene.scene, view);
        let second_reference = (opts.gloss != Gloss::Mirror).then(|| {
            let mirror: Box<dyn Estimator> = Box::new(ReflectionEstimator {
                opts: opts.mirror(),
            });
            ("mirror", mirror)
        });
        Setup {
            offset: points.max_offset(),
            points,
            gpu: Some(Box::new(ReflectGpu(opts.clone()))),
            estimator: Box::new(ReflectionEstimator { opts }),
            shading: None,
            second_reference,
        }
    }

    fn normal_bits(&self) -> Vec<u32> {
        self.opts.normal_bits.clone()
    }
}

/// Reflections on the GPU: [`FieldReflectKernel`] for field lookup (it needs every instance's
/// normal field, which the run attaches), the reflection integrand ([`crate::gpu::reflections`])
/// on any GPU visibility for ray casting.
struct ReflectGpu(ReflectOptions);

impl GpuQuantity for ReflectGpu {
    fn fields<'s>(
        &'s self,
        ctx: &'s GpuContext,
        fields: &FieldScene,
        opts: &FieldGpuOptions,
    ) -> Result<Box<dyn Eval + 's>> {
        Ok(Box::new(KernelEval {
            kernel: FieldReflectKernel::new(ctx, &fields.instances, opts)?,
            opts: self.0.clone(),
            run: |k, at, rays, o| crate::gpu::reflections(k, at.points, at.normals, rays, o),
            setup: FieldReflectKernel::setup_time,
            place: FieldReflectKernel::place,
        }))
    }

    fn trace(&self, vis: &dyn GpuVisibility, at: Points, rays: &RaySet) -> Result<Estimate> {
        traced(crate::gpu::reflections(
            vis, at.points, at.normals, rays, &self.0,
        ))
    }
}
