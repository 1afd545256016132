//! `{"method": "sdf", "res": [32, 64], "precision": ["f32", "u8"], "query": ["trace", "cone"]}`:
//! mesh signed distance fields (`crate::sdf`), one volume per caster mesh baked in model space
//! and instanced with the caster's transform, as engines keep them. One setting per (res,
//! precision, query), in that order:
//!
//! - `res`: samples along each mesh box's longest side (8–256);
//! - `precision`: how the volume is stored and read, `f32`, `f16` (UE4's half floats) or `u8`
//!   (UE5's band of four voxel diagonals) (default `["f32"]`; `crate::sdf::storage`);
//! - `query`: `trace`, the kind's own estimator through the volumes on the reference's rays
//!   (sphere tracing as a `Visibility`: AO, shadows and reflections), or `cone`, the engines'
//!   direct estimators (`crate::sdf::cone`: cone-traced AO for the AO kinds, one cone per
//!   spherical light for shadows; refused for reflections, which need a surface per ray, and
//!   for AO with a distance falloff) (default `["trace"]`).
//!
//! Scalar keys: `margin`, voxels of padding around each box (default 2, at least 1); `hit_voxels`,
//! the hit threshold in voxels (default 0.25); `start_voxels`, where each volume's trace starts
//! (default 2); `max_steps` per ray, cone and volume (default 256); `cones`, the AO cones
//! (default 9, UE's count); `step`, a cone's least step as a share of its radius (default 0.25).
//!
//! On the `gpu` backend (`"backends": ["cpu", "gpu"]`), `trace` answers AO and `cone` AO and
//! shadows through the SDF kernels (`gpu.rs`, `crate::gpu::SdfKernel`); sphere-traced shadows
//! and reflections are refused there.
//!
//! Its precompute is the bakes, or their loads from the run's cache (`crate::sdf::cache`: keyed
//! by the mesh's sha256, res, margin, precision and format version; a lower precision is
//! derived from the cached f32 volume); `precompute_cached` says no bake ran. Its bytes are the
//! volumes' stored samples, each distinct mesh once.

mod cone;
mod gpu;

use super::motion::{self, FrameCasters, FrameForm, Mover, MoverInputs};
use super::{Answer, Method, MethodContext, MethodEntry, MethodOptions, Precompute, Prepared};
use crate::experiment::kinds::Kind;
use crate::experiment::scenes::BuiltScene;
use crate::experiment::spec::{Spec, SpecError};
use crate::experiment::validate::Validator;
use crate::experiment::{Error, Result};
use crate::geometry::Mesh;
use crate::sdf::SdfTrace;
use crate::sdf::{cache, ConeSet, ConeTrace, DistanceVolume, Precision, SdfInstance, SdfScene};
use crate::visibility::Visibility;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;

pub const ENTRY: MethodEntry = MethodEntry {
    name: "sdf",
    about: "mesh signed distance fields, sphere traced or cone traced (one volume per caster mesh, instanced)",
    read: super::read_as::<SdfOptions>,
};

/// Its per-frame form ([`Method::frame_forms`]): `sdf`, the volumes placed by each frame's
/// transforms ([`Sdfs`]). `experiment dynamic`'s crowd measures it at its own `res` (the
/// options have no default, so animated specs do not list it).
pub const FRAME_FORMS: &[FrameForm] = &[FrameForm::cpu("sdf")];

/// The largest `res` a spec may ask for (256³ f32 samples: 64 MiB per mesh).
const MAX_RES: usize = 256;

/// How a setting answers the kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Query {
    /// The kind's estimator through sphere tracing, on the reference's rays.
    Trace,
    /// The engines' cone-traced direct estimators.
    Cone,
}

impl Query {
    fn name(self) -> &'static str {
        match self {
            Query::Trace => "trace",
            Query::Cone => "cone",
        }
    }
}

/// `sdf`'s keys.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SdfOptions {
    /// Samples along each mesh box's longest side; one setting per value.
    pub res: Vec<usize>,
    #[serde(default = "default_precision")]
    pub precision: Vec<Precision>,
    #[serde(default = "default_query")]
    pub query: Vec<Query>,
    #[serde(default = "default_margin")]
    pub margin: usize,
    #[serde(default = "default_hit_voxels")]
    pub hit_voxels: f32,
    #[serde(default = "default_start_voxels")]
    pub start_voxels: f32,
    #[serde(default = "default_max_steps")]
    pub max_steps: u32,
    #[serde(default = "default_cones")]
    pub cones: usize,
    #[serde(default = "default_step")]
    pub step: f32,
}

fn default_precision() -> Vec<Precision> {
    vec![Precision::F32]
}

fn default_query() -> Vec<Query> {
    vec![Query::Trace]
}

fn default_margin() -> usize {
    2
}

fn default_hit_voxels() -> f32 {
    SdfTrace::default().hit_voxels
}

fn default_start_voxels() -> f32 {
    SdfTrace::default().start_voxels
}

fn default_max_steps() -> u32 {
    SdfTrace::default().max_steps
}

fn default_cones() -> usize {
    9
}

fn default_step() -> f32 {
    ConeTrace::default().step
}

/// `values` has at least one value and none twice, else the error naming `at.key`.
fn axis<T: PartialEq + std::fmt::Debug>(
    values: &[T],
    at: &str,
    key: &str,
    v: &Validator,
) -> Result<(), SpecError> {
    if values.is_empty() {
        return Err(v.err(&format!("{at}.{key}"), "needs at least one value".into()));
    }
    for (i, x) in values.iter().enumerate() {
        if values[..i].contains(x) {
            return Err(v.err(&format!("{at}.{key}[{i}]"), format!("{x:?} listed twice")));
        }
    }
    Ok(())
}

impl MethodOptions for SdfOptions {
    fn validate(&self, at: &str, _spec: &Spec, v: &Validator) -> Result<(), SpecError> {
        axis(&self.res, at, "res", v)?;
        axis(&self.precision, at, "precision", v)?;
        axis(&self.query, at, "query", v)?;
        for (i, &r) in self.res.iter().enumerate() {
            if !(8..=MAX_RES).contains(&r) {
                return Err(v.err(
                    &format!("{at}.res[{i}]"),
                    format!("{r} is outside 8..={MAX_RES}"),
                ));
            }
            if self.margin == 0 || self.margin >= r / 4 {
                return Err(v.err(
                    &format!("{at}.margin"),
                    format!(
                        "{} voxels is not between 1 and a quarter of res {r}",
                        self.margin
                    ),
                ));
            }
        }
        let in_range = |x: f32, lo: f32, hi: f32| x.is_finite() && x > lo && x <= hi;
        if !in_range(self.hit_voxels, 0.0, 2.0) {
            return Err(v.err(
                &format!("{at}.hit_voxels"),
                format!("{} is not in (0, 2]", self.hit_voxels),
            ));
        }
        if !(self.start_voxels.is_finite() && (0.0..=16.0).contains(&self.start_voxels)) {
            return Err(v.err(
                &format!("{at}.start_voxels"),
                format!("{} is not in [0, 16]", self.start_voxels),
            ));
        }
        if !(1..=100_000).contains(&self.max_steps) {
            return Err(v.err(
                &format!("{at}.max_steps"),
                format!("{} is not in 1..=100000", self.max_steps),
            ));
        }
        if !(2..=ConeSet::MAX).contains(&self.cones) {
            return Err(v.err(
                &format!("{at}.cones"),
                format!("{} is not in 2..={}", self.cones, ConeSet::MAX),
            ));
        }
        if !in_range(self.step, 0.0, 4.0) {
            return Err(v.err(
                &format!("{at}.step"),
                format!("{} is not in (0, 4]", self.step),
            ));
        }
        Ok(())
    }

    fn settings(&self) -> Vec<Box<dyn Method>> {
        let mut out: Vec<Box<dyn Method>> = Vec::new();
        for &res in &self.res {
            for &precision in &self.precision {
                for &query in &self.query {
                    out.push(Box::new(Sdf {
                        res,
                        precision,
                        query,
                        margin: self.margin,
                        trace: SdfTrace {
                            hit_voxels: self.hit_voxels,
                            max_steps: self.max_steps,
                            start_voxels: self.start_voxels,
                        },
                        cones: self.cones,
                        cone: ConeTrace {
                            step: self.step,
                            max_steps: self.max_steps,
                        },
                    }));
                }
            }
        }
        out
    }
}

/// One (res, precision, query) setting.
pub struct Sdf {
    res: usize,
    precision: Precision,
    query: Query,
    margin: usize,
    trace: SdfTrace,
    cones: usize,
    cone: ConeTrace,
}

impl Sdf {
    /// The volume of `mesh` (from the cache in `cache` where it holds it) and whether no bake
    /// ran.
    fn volume(
        &self,
        mesh: &Mesh,
        cache: Option<&Path>,
    ) -> std::result::Result<(Arc<DistanceVolume>, bool), crate::sdf::SdfError> {
        let tris: Vec<_> = (0..mesh.triangle_count())
            .map(|t| mesh.triangle(t))
            .collect();
        let sha = crate::experiment::scenes::mesh_sha256(mesh);
        let (v, outcome) =
            cache::load_or_bake_in(cache, &tris, &sha, (self.res, self.margin), self.precision)?;
        for why in outcome.iter().flat_map(|o| o.rejected()) {
            eprintln!("  sdf cache entry rejected, rebaking: {why}");
        }
        Ok((Arc::new(v), outcome.is_some_and(|o| o.cached())))
    }

    /// One volume per distinct caster mesh (from the cache where the run has one) and the
    /// instances; whether no bake ran.
    fn volumes(&self, ctx: &MethodContext, label: &str) -> Result<(SdfScene, u64, bool)> {
        let volumes =
            super::per_caster_mesh(ctx.scene, |mesh| self.volume(mesh, ctx.cache.as_deref()))
                .map_err(|e| Error::invalid(label.to_string(), e.to_string()))?;
        let bytes = volumes.meshes.iter().map(|v| v.bytes()).sum();
        let cached = volumes.cached && !volumes.meshes.is_empty();
        let scene = SdfScene {
            instances: (volumes.casters.into_iter())
                .map(|(volume, transform)| SdfInstance { volume, transform })
                .collect(),
            trace: self.trace,
        };
        Ok((scene, bytes, cached))
    }
}

impl Method for Sdf {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn frame_forms(&self) -> &'static [FrameForm] {
        FRAME_FORMS
    }

    /// Its volumes (one per mesh, from the cache where it holds them) placed by each frame's
    /// transforms and sphere traced (`query` aside).
    fn mover(&self, _form: &str, on: &MoverInputs) -> Result<Box<dyn Mover>> {
        let volumes = motion::per_mesh(self, on, |mesh| {
            Ok(self.volume(mesh, on.cache).map_err(|e| e.to_string())?.0)
        })?;
        Ok(Box::new(Sdfs {
            volumes,
            scene: SdfScene {
                instances: Vec::new(),
                trace: self.trace,
            },
        }))
    }

    fn params(&self) -> Vec<(&'static str, String)> {
        vec![
            ("res", self.res.to_string()),
            ("precision", self.precision.name().to_string()),
            ("query", self.query.name().to_string()),
        ]
    }

    fn refuses(&self, kind: &dyn Kind) -> Option<String> {
        match self.query {
            Query::Trace => None,
            Query::Cone => cone::refusal(kind),
        }
    }

    fn refuses_on_gpu(&self, kind: &dyn Kind) -> Option<String> {
        match self.query {
            Query::Trace => (!kind.answers().binary_ao()).then(|| {
                "query \"trace\" on the gpu backend answers ambient occlusion (falloff \
                     \"step\") only: the SDF kernels trace no shadow or reflection rays; use \
                     query \"cone\" for shadows, or the cpu backend"
                    .to_string()
            }),
            Query::Cone => cone::refusal(kind),
        }
    }

    /// One volume per distinct caster mesh, sized by the bake's own grid
    /// ([`DistanceVolume::grid`]): its samples at the stored precision kept, the sign rays
    /// cast, and at the peak the f32 volume each bake (or cached f32 load) makes before a
    /// lower precision is stored.
    fn precompute(&self, scene: &BuiltScene) -> std::result::Result<Option<Precompute>, String> {
        let (meshes, _) = super::caster_instances(scene);
        let (mut samples, mut largest) = (0u64, 0u64);
        for tris in &meshes {
            let n = DistanceVolume::samples_for(tris, self.res, self.margin)
                .map_err(|e| e.to_string())?;
            samples += n;
            largest = largest.max(n);
        }
        let bytes = samples * self.precision.bytes_per_sample() as u64;
        let transient = match self.precision {
            Precision::F32 => 0,
            _ => largest * Precision::F32.bytes_per_sample() as u64,
        };
        Ok(Some(Precompute {
            what: format!(
                "bake {} distance volume(s) at res {}: {samples} samples ({}), {} sign rays each",
                meshes.len(),
                self.res,
                self.precision.name(),
                DistanceVolume::SIGN_RAYS_PER_SAMPLE
            ),
            rays: samples * DistanceVolume::SIGN_RAYS_PER_SAMPLE,
            bytes,
            peak_bytes: bytes + transient,
        }))
    }

    fn prepare(&self, ctx: &MethodContext) -> Result<Prepared> {
        let label = format!(
            "scene {}: method \"sdf\" ({})",
            ctx.scene.name,
            (self as &dyn Method).id()
        );
        // The bake holds f32 samples, whatever the precision stored.
        let most = (self.res as u64).pow(3) * 4;
        if most > ctx.memory_limit {
            return Err(Error::invalid(
                label,
                format!(
                    "a volume may take {most} bytes, above the run's memory limit of {}",
                    ctx.memory_limit
                ),
            ));
        }
        // What the cones answer, read before any bake.
        let quantity = match self.query {
            Query::Trace => None,
            Query::Cone => Some(
                cone::quantity_of(ctx.estimator).map_err(|e| Error::invalid(label.clone(), e))?,
            ),
        };
        let (scene, bytes, cached) = self.volumes(ctx, &label)?;
        // The kernels where the kind has one: the cones' quantity, or AO for the trace.
        let gpu = match &quantity {
            None => cone::quantity_of(ctx.estimator)
                .ok()
                .and_then(|q| gpu::GpuQuery::trace(&q)),
            Some(q) => Some(gpu::GpuQuery::cone(
                q,
                ConeSet::hemisphere(self.cones),
                self.cone,
            )),
        }
        .map(|query| -> Box<dyn super::GpuMethod> {
            Box::new(gpu::SdfGpu {
                scene: scene.clone(),
                query,
            })
        });
        let (answer, columns) = match quantity {
            None => (Answer::Rays(Box::new(scene)), Vec::new()),
            Some(quantity) => {
                let cones = match quantity {
                    cone::Quantity::Ao { .. } => self.cones.to_string(),
                    cone::Quantity::Light { ref lights, .. } => lights.len().to_string(),
                };
                let est = cone::ConeEstimator {
                    scene,
                    cones: ConeSet::hemisphere(self.cones),
                    trace: self.cone,
                    quantity,
                };
                (
                    Answer::Direct(Box::new(est)),
                    vec![("cones".to_string(), cones)],
                )
            }
        };
        Ok(Prepared {
            bytes: Some(bytes),
            cached,
            columns,
            answer,
            gpu,
        })
    }
}

/// Mesh signed distance fields as engines keep them for moving rigid objects (one volume per
/// mesh, shared by its instances) placed by the frame's transforms and sphere traced on the
/// same rays; the update is the instance list, nothing is rebuilt.
pub struct Sdfs {
    /// Per mesh, its volume.
    pub volumes: Vec<Arc<DistanceVolume>>,
    scene: SdfScene,
}

impl Mover for Sdfs {
    fn name(&self) -> &'static str {
        FRAME_FORMS[0].name
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.scene.instances = frame.place(&self.volumes, |v, transform| SdfInstance {
            volume: v.clone(),
            transform,
        });
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        &self.scene
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.volumes.iter().map(|v| v.bytes()).sum())
    }
}
