//! `{"method": "aofield", "res": [16, 32]}`: ambient occlusion fields (Kontkanen & Laine 2005,
//! the core's [`crate::aofield`]), one field per caster mesh baked in model space and instanced
//! with the caster's transform, answering AO directly ([`Answer::Direct`]: no ray; the AO of
//! a point is `Π (1 − Ãᵢ)` over the casters' caps). Its precompute is the bakes, cached in the
//! run's cache folder by mesh sha256 and bake parameters (the fit in f32; each precision is
//! stored from it on load); its bytes the stored fields'.
//!
//! Keys: `res`, texels per cube face side (an axis: one row per value, 2–256); `precision`,
//! the stored channels (an axis of `"f32"`, `"f16"`, `"u8"`; default `["f32"]`);
//! `radial_samples`, samples per texel (3–64, default 12); `rays`, rays per sample (a perfect
//! square, default 256); `reach`, the farthest sample in bounding radii (1.5–1000, default 8);
//! `inner_ao` and `inner_power`, the paper's A₀ and p inside the hull (defaults 1 and 1).
//!
//! On the `gpu` backend (`"backends": ["cpu", "gpu"]`) the fields are read by
//! [`crate::gpu::AoFieldKernel`] (the CPU's cube-map reads, the cap evaluated in f32).
//!
//! Refused, before any work: any kind but the AO kinds (an AO field casts no ray, so it has no
//! shadow or reflection to give), a finite `render.max_distance` or a distance falloff (the cap
//! counts the whole occluder at any distance), and a scene with an instance that is both caster
//! and receiver (an AO field does not model an occluder's occlusion of itself).

use super::motion::{self, FrameCasters, FrameForm, Mover, MoverInputs};
use super::{
    Answer, GpuMethod, Method, MethodContext, MethodEntry, MethodOptions, Precompute, Prepared,
};
use crate::aofield::cache::{load_or_bake, Outcome};
use crate::aofield::{AoField, AoFieldInstance, AoFieldScene, BakeParams, Inside, Precision};
use crate::experiment::backend::{Estimate, Eval};
use crate::experiment::backend_gpu::GpuQuantity;
use crate::experiment::kinds::{Answers, Kind};
use crate::experiment::scenes::BuiltScene;
use crate::experiment::spec::{Spec, SpecError};
use crate::experiment::validate::Validator;
use crate::experiment::{Error, Result};
use crate::geometry::Mesh;
use crate::gpu::{AoFieldKernel, GpuContext};
use crate::render::ao::{AoOptions, Falloff};
use crate::render::estimator::{Estimator, Points};
use crate::render::truth::{Truth, TruthOptions};
use crate::sampling::rays::RaySet;
use crate::visibility::Visibility;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;

pub const ENTRY: MethodEntry = MethodEntry {
    name: "aofield",
    about: "ambient occlusion fields (Kontkanen & Laine 2005): per caster mesh, a cube map of \
            radial functions giving its spherical cap; AO with no ray",
    read: super::read_as::<AoFieldOptions>,
};

/// Its per-frame form ([`Method::frame_forms`]): `aofield`, the fields placed by each frame's
/// transforms ([`AoFields`]). `experiment dynamic`'s crowd measures it at its own `res` (the
/// options have no default, so animated specs, which need rays for any kind, do not list it).
pub const FRAME_FORMS: &[FrameForm] = &[FrameForm::cpu("aofield")];

/// `aofield`'s keys.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AoFieldOptions {
    /// Texels per cube face side; one setting per value.
    pub res: Vec<usize>,
    /// Stored precision; one setting per value.
    #[serde(default = "default_precision")]
    pub precision: Vec<Precision>,
    #[serde(default = "default_radial_samples")]
    pub radial_samples: usize,
    #[serde(default = "default_rays")]
    pub rays: u32,
    #[serde(default = "default_reach")]
    pub reach: f32,
    #[serde(default = "default_inner_ao")]
    pub inner_ao: f32,
    #[serde(default = "default_inner_power")]
    pub inner_power: f32,
}

fn default_precision() -> Vec<Precision> {
    vec![Precision::F32]
}

fn default_radial_samples() -> usize {
    BakeParams::default().radial_samples
}

fn default_rays() -> u32 {
    BakeParams::default().rays
}

fn default_reach() -> f32 {
    BakeParams::default().reach
}

fn default_inner_ao() -> f32 {
    Inside::default().ao
}

fn default_inner_power() -> f32 {
    Inside::default().power
}

impl AoFieldOptions {
    fn params(&self, res: usize) -> BakeParams {
        BakeParams {
            res,
            radial_samples: self.radial_samples,
            rays: self.rays,
            reach: self.reach,
        }
    }
}

impl MethodOptions for AoFieldOptions {
    fn validate(&self, at: &str, spec: &Spec, v: &Validator) -> Result<(), SpecError> {
        if self.res.is_empty() {
            return Err(v.err(&format!("{at}.res"), "needs at least one value".into()));
        }
        for (i, &r) in self.res.iter().enumerate() {
            if !(2..=crate::aofield::MAX_RES).contains(&r) {
                return Err(v.err(
                    &format!("{at}.res[{i}]"),
                    format!("{r} is outside 2..={}", crate::aofield::MAX_RES),
                ));
            }
        }
        if self.precision.is_empty() {
            return Err(v.err(
                &format!("{at}.precision"),
                "needs at least one value".into(),
            ));
        }
        // The bake's own ranges, each named by its key.
        let p = self.params(self.res[0]);
        let k = p.rays_per_side();
        let checks: [(&str, bool, String); 5] = [
            (
                "radial_samples",
                (3..=crate::aofield::MAX_RADIAL_SAMPLES).contains(&p.radial_samples),
                format!(
                    "{} is outside 3..={} (the solid angle has three parameters)",
                    p.radial_samples,
                    crate::aofield::MAX_RADIAL_SAMPLES
                ),
            ),
            (
                "rays",
                p.rays > 0 && p.rays <= crate::aofield::MAX_RAYS && k * k == p.rays,
                format!(
                    "{} is not a perfect square in 1..={}",
                    p.rays,
                    crate::aofield::MAX_RAYS
                ),
            ),
            (
                "reach",
                p.reach.is_finite() && (1.5..=1000.0).contains(&p.reach),
                format!("{} bounding radii is outside [1.5, 1000]", p.reach),
            ),
            (
                "inner_ao",
                (0.0..=1.0).contains(&self.inner_ao),
                format!("{} is outside [0, 1]", self.inner_ao),
            ),
            (
                "inner_power",
                self.inner_power.is_finite() && self.inner_power > 0.0 && self.inner_power <= 100.0,
                format!("{} is outside (0, 100]", self.inner_power),
            ),
        ];
        for (key, ok, why) in checks {
            if !ok {
                return Err(v.err(&format!("{at}.{key}"), why));
            }
        }
        for (si, scene) in spec.scenes.iter().enumerate() {
            for (ii, inst) in scene.instances.iter().enumerate() {
                if inst.caster && inst.receiver {
                    return Err(v.err(
                        at,
                        format!(
                            "\"aofield\" answers inter-object AO only: instance {ii} of scene \
                             `{}` (scenes[{si}]) is both caster and receiver, and an AO field \
                             does not model an occluder's occlusion of itself",
                            scene.name
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    fn settings(&self) -> Vec<Box<dyn Method>> {
        let mut out: Vec<Box<dyn Method>> = Vec::new();
        for &res in &self.res {
            for &precision in &self.precision {
                out.push(Box::new(AoFieldMethod {
                    params: self.params(res),
                    precision,
                    inside: Inside {
                        ao: self.inner_ao,
                        power: self.inner_power,
                    },
                }));
            }
        }
        out
    }
}

/// One resolution and precision's fields.
pub struct AoFieldMethod {
    params: BakeParams,
    precision: Precision,
    inside: Inside,
}

impl AoFieldMethod {
    /// The field of `mesh` (its fit from the cache in `cache` where it holds it) and whether
    /// no bake ran.
    fn field(
        &self,
        mesh: &Mesh,
        cache: Option<&Path>,
    ) -> std::result::Result<(Arc<AoField>, bool), String> {
        let tris: Vec<_> = (0..mesh.triangle_count())
            .map(|t| mesh.triangle(t))
            .collect();
        let sha = crate::experiment::scenes::mesh_sha256(mesh);
        let (fitted, outcome) =
            load_or_bake(cache, &sha, &tris, &self.params).map_err(|e| e.to_string())?;
        if let Outcome::Baked {
            rejected: Some(why),
            ..
        } = &outcome
        {
            eprintln!("aofield cache: {why}; rebaked");
        }
        let hit = !matches!(outcome, Outcome::Baked { .. });
        Ok((Arc::new(AoField::new(&fitted, self.precision)), hit))
    }
}

impl Method for AoFieldMethod {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn frame_forms(&self) -> &'static [FrameForm] {
        FRAME_FORMS
    }

    /// Its fields (one per mesh, from the cache where it holds them) placed by each frame's
    /// transforms.
    fn mover(&self, _form: &str, on: &MoverInputs) -> Result<Box<dyn Mover>> {
        let fields = motion::per_mesh(self, on, |mesh| Ok(self.field(mesh, on.cache)?.0))?;
        Ok(Box::new(AoFields {
            fields,
            scene: AoFieldScene {
                instances: Vec::new(),
                inside: self.inside,
            },
        }))
    }

    fn params(&self) -> Vec<(&'static str, String)> {
        vec![
            ("res", self.params.res.to_string()),
            ("radial_samples", self.params.radial_samples.to_string()),
            ("precision", self.precision.name().to_string()),
        ]
    }

    fn refuses(&self, kind: &dyn Kind) -> Option<String> {
        let Answers::Ao(ao) = kind.answers() else {
            return Some(
                "an AO field answers ambient occlusion only: it casts no ray, so it has no \
                 shadow or reflection to give"
                    .into(),
            );
        };
        if let Some(d) = ao.max_distance {
            return Some(format!(
                "render.max_distance = {d}: an AO field answers unbounded AO (the cap counts the \
                 whole occluder at any distance); drop render.max_distance"
            ));
        }
        if ao.falloff != Falloff::Step {
            return Some(format!(
                "render.falloff = {}: an AO field has no hit distance to weigh; use \"step\"",
                serde_json::json!(ao.falloff)
            ));
        }
        None
    }

    /// The kernel answers every kind the CPU answers ([`Method::refuses`]).
    fn refuses_on_gpu(&self, _kind: &dyn Kind) -> Option<String> {
        None
    }

    /// One field per distinct caster mesh: `6 · res²` texels × `radial_samples` × `rays` rays
    /// cast, the stored fields kept ([`AoField::bytes_for`]), and at the peak the bake's f32
    /// fit of one mesh twice over (its per-texel fits, then the fitted field it is stored from).
    fn precompute(&self, scene: &BuiltScene) -> std::result::Result<Option<Precompute>, String> {
        let meshes = scene.caster_meshes().len() as u64;
        let p = &self.params;
        let texels = 6 * (p.res as u64).pow(2);
        let fit = 2 * crate::aofield::storage::Stored::bytes_for(texels as usize, Precision::F32);
        let bytes = meshes * AoField::bytes_for(p.res, self.precision);
        Ok(Some(Precompute {
            what: format!(
                "bake {meshes} AO field(s): 6 × {}² texels × {} samples × {} rays ({})",
                p.res,
                p.radial_samples,
                p.rays,
                self.precision.name()
            ),
            rays: meshes * texels * p.radial_samples as u64 * u64::from(p.rays),
            bytes,
            peak_bytes: bytes + if meshes > 0 { fit } else { 0 },
        }))
    }

    fn prepare(&self, ctx: &MethodContext) -> Result<Prepared> {
        let scene = ctx.scene;
        let what = || {
            format!(
                "scene {}: method \"aofield\" (res {})",
                scene.name, self.params.res
            )
        };
        if let Some((i, _)) = scene
            .scene
            .instances
            .iter()
            .enumerate()
            .find(|(_, i)| i.caster && i.receiver)
        {
            return Err(Error::invalid(
                what(),
                format!(
                    "instance {i} is both caster and receiver: an AO field answers inter-object \
                     AO only"
                ),
            ));
        }
        // One field per mesh, shared by its instances.
        let fields = super::per_caster_mesh(scene, |mesh| self.field(mesh, ctx.cache.as_deref()))
            .map_err(|e| Error::invalid(what(), e))?;
        let cached = fields.cached;
        let fields = AoFieldScene {
            instances: (fields.casters.into_iter())
                .map(|(field, transform)| AoFieldInstance { field, transform })
                .collect(),
            inside: self.inside,
        };
        Ok(Prepared {
            bytes: Some(fields.bytes()),
            cached,
            columns: Vec::new(),
            gpu: Some(Box::new(AoFieldGpu {
                fields: fields.clone(),
            })),
            answer: Answer::Direct(Box::new(AoFieldEstimator { fields })),
        })
    }
}

/// AO from the fields at the kind's points; the rays are not used.
pub struct AoFieldEstimator {
    pub fields: AoFieldScene,
}

impl Estimator for AoFieldEstimator {
    fn name(&self) -> &'static str {
        "aofield"
    }

    fn estimate(&self, _vis: &dyn Visibility, at: Points, _rays: &RaySet) -> Vec<f32> {
        self.fields.ao_at_points(at.points, at.normals)
    }

    /// The fields' values are exact for the fields (no sampling): the estimate itself, with
    /// no spread.
    fn converged(&self, _vis: &dyn Visibility, at: Points, _t: &TruthOptions) -> Truth {
        Truth::exact(self.fields.ao_at_points(at.points, at.normals))
    }

    fn key(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = serde_json::Map::new();
        m.insert("inner_ao".into(), serde_json::json!(self.fields.inside.ao));
        m.insert(
            "inner_power".into(),
            serde_json::json!(self.fields.inside.power),
        );
        m
    }
}

/// The fields on the `gpu` backend ([`AoFieldKernel`]: the same cube-map reads, the cap in f32).
struct AoFieldGpu {
    fields: AoFieldScene,
}

impl GpuMethod for AoFieldGpu {
    fn upload<'a>(
        &'a self,
        ctx: &'a GpuContext,
        _: Option<&'a dyn GpuQuantity>,
    ) -> Result<Box<dyn Eval + 'a>> {
        Ok(Box::new(AoFieldKernel::new(ctx, &self.fields)?))
    }
}

impl Eval for AoFieldKernel<'_> {
    fn estimate(&self, at: Points, _rays: &RaySet) -> Result<Estimate> {
        let (values, t) = self.ao(at.points, at.normals)?;
        Ok(Estimate {
            values,
            kernel_s: t.kernel.map(|d| d.as_secs_f64()),
        })
    }

    fn setup_s(&self) -> Option<f64> {
        Some(self.setup_time().as_secs_f64())
    }
}

/// AO fields (one per mesh, shared by its instances) placed by the frame's transforms: AO at a
/// point with no ray, the casters blended multiplicatively ([`Mover::ao`]); the update is the
/// instance list. It answers AO only, and its [`Mover::vis`] refuses every ray.
pub struct AoFields {
    /// Per mesh, its field.
    pub fields: Vec<Arc<AoField>>,
    scene: AoFieldScene,
}

impl Mover for AoFields {
    fn name(&self) -> &'static str {
        FRAME_FORMS[0].name
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.scene.instances = frame.place(&self.fields, |f, transform| AoFieldInstance {
            field: f.clone(),
            transform,
        });
        Ok(())
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.fields.iter().map(|f| f.bytes()).sum())
    }

    fn ao(&self, points: &[Vec3], normals: &[Vec3], _: &RaySet, _: &AoOptions) -> Vec<f32> {
        self.scene.ao_at_points(points, normals)
    }
}
