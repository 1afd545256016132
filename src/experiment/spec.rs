//! Experiment specs: `experiments/*.json`, one per figure or table. Plain structs, a doc comment
//! per field, unknown keys rejected; an error names the file, the field path and what was
//! expected.

use crate::field::{Precision, Selection};
use crate::render::camera::Camera;
use crate::sampling::{LayoutKind, SphereKind};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A spec error, naming the file and the field.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    #[error("{file}: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: at `{path}`: {message}")]
    Parse {
        file: PathBuf,
        path: String,
        message: String,
    },
    #[error("{file}: field `{field}`: {message}")]
    Invalid {
        file: PathBuf,
        field: String,
        message: String,
    },
}

/// One experiment: a scene, the field axes to sweep, what to render, how to measure.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// Short name; the results go to `results/<name>/`.
    pub name: String,
    /// The figure or table reproduced, with its paper (e.g. "Gaitatzes et al. 2008, Figure 6").
    pub reproduces: String,
    /// One paragraph on what the experiment shows.
    #[serde(default)]
    pub description: String,
    /// The scene: instances of models or procedural meshes.
    pub scene: SceneSpec,
    /// The field axes; every combination is one cell.
    pub field: FieldAxes,
    /// What is rendered and how.
    pub render: RenderSpec,
    /// Where the AO is computed: "cpu" and/or "gpu".
    #[serde(default = "default_backends")]
    pub backends: Vec<Backend>,
    /// The ray-cast reference.
    pub reference: ReferenceSpec,
    /// The paper's own numbers for the cells reproduced.
    #[serde(default)]
    pub paper: Option<PaperNumbers>,
    /// RMS thresholds for `experiment check`.
    #[serde(default)]
    pub thresholds: Vec<Threshold>,
    /// Smaller axes for CI and regression checks (`--quick`): replaces the fields it names.
    #[serde(default)]
    pub quick: Option<QuickProfile>,
}

fn default_backends() -> Vec<Backend> {
    vec![Backend::Cpu]
}

/// A compute backend.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Backend {
    Cpu,
    Gpu,
}

/// The scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub instances: Vec<InstanceSpec>,
}

/// A mesh placed in the scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstanceSpec {
    /// A real mesh by name (see `data/models.json`), or a procedural mesh.
    pub mesh: MeshSource,
    /// Casts occlusion (gets a field).
    #[serde(default)]
    pub caster: bool,
    /// Receives occlusion (AO evaluated at its vertices).
    #[serde(default)]
    pub receiver: bool,
    /// Placement.
    #[serde(default)]
    pub transform: TransformSpec,
}

/// Where a mesh comes from.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum MeshSource {
    /// A model from the registry, by name.
    Model(String),
    /// The 2008 paper's corner receiver with n×n vertices per face.
    Corner { n: u32 },
    /// A closed cube of side `size` with a square through-hole of side `hole`.
    CubeWithHole { size: f32, hole: f32 },
    /// A Gielis supershape with about this many triangles.
    Supershape { triangles: usize },
    /// A UV sphere.
    Sphere {
        radius: f32,
        stacks: u32,
        slices: u32,
    },
    /// A square plane of side `size` with n×n vertices.
    Plane { size: f32, n: u32 },
}

/// A rigid placement: the mesh is first fitted (optional), then rotated, scaled, translated.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
    /// Fit the mesh's bounding sphere to this centre and radius before the rest.
    #[serde(default)]
    pub fit: Option<FitSpec>,
    /// Rotation, Euler angles in degrees, applied in x, y, z order.
    #[serde(default)]
    pub rotate_deg: Option<Vec3>,
    /// Uniform scale.
    #[serde(default)]
    pub scale: Option<f32>,
    /// Translation.
    #[serde(default)]
    pub translate: Option<Vec3>,
}

/// Fit a mesh's minimal bounding sphere to a given sphere.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitSpec {
    pub center: Vec3,
    pub radius: f32,
}

/// The field axes.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldAxes {
    /// Positional sample sets.
    #[serde(default = "default_spheres")]
    pub spheres: Vec<SphereKind>,
    /// Positional sample counts (maps per field).
    pub counts: Vec<usize>,
    /// Directional layouts.
    #[serde(default = "default_layouts")]
    pub layouts: Vec<LayoutKind>,
    /// Directional resolutions (res × res texels).
    pub resolutions: Vec<u32>,
    /// Stored precisions.
    #[serde(default = "default_precisions")]
    pub precisions: Vec<Precision>,
    /// Map selection at lookup.
    #[serde(default = "default_selections")]
    pub selections: Vec<Selection>,
}

fn default_spheres() -> Vec<SphereKind> {
    vec![SphereKind::Slater]
}
fn default_layouts() -> Vec<LayoutKind> {
    vec![LayoutKind::Concentric]
}
fn default_precisions() -> Vec<Precision> {
    vec![Precision::U8]
}
fn default_selections() -> Vec<Selection> {
    vec![Selection::Nearest]
}

/// What is rendered.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSpec {
    /// Receiver rays per point: k² with k = sqrt (must be a perfect square; the papers use 256).
    pub rays_per_point: u32,
    /// Per-vertex AO at the receivers (2008).
    #[serde(default = "yes")]
    pub vertex_ao: bool,
    /// An image of the scene with AO (PNG/EXR), if given.
    #[serde(default)]
    pub image: Option<ImageSpec>,
    /// AO radius: occluders further than this do not count (none: unlimited).
    #[serde(default)]
    pub max_distance: Option<f32>,
}

fn yes() -> bool {
    true
}

/// An image.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageSpec {
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
}

/// The ray-cast reference.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    /// Rays per point of the reference (the same rays as the field lookup when equal).
    pub rays_per_point: u32,
    /// Seed of the per-point ray rotation.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Ray-cast AO at these ray counts too, for the error-against-time plot.
    #[serde(default)]
    pub raycast_sweep: Vec<u32>,
}

fn default_seed() -> u64 {
    1
}

/// The paper's numbers for the cells reproduced.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperNumbers {
    /// Where they come from (e.g. "../shared/paper/2008_figure6.csv").
    pub source: String,
    pub cells: Vec<PaperCell>,
}

/// One cell of a paper's table.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperCell {
    pub positional_samples: Option<usize>,
    pub directional_res: Option<u32>,
    #[serde(default)]
    pub label: Option<String>,
    pub preprocess_s: Option<f64>,
    pub ao_s: Option<f64>,
    pub rms: Option<f64>,
}

/// An RMS threshold for `experiment check`, for the cells matching its axes (all when unset).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Threshold {
    pub positional_samples: Option<usize>,
    pub directional_res: Option<u32>,
    pub precision: Option<Precision>,
    /// Maximum per-vertex RMS (0–255 scale).
    pub rms_vertex_max: Option<f64>,
    /// Maximum per-pixel RMS (0–255 scale).
    pub rms_image_max: Option<f64>,
}

/// The `--quick` profile: each field given replaces the spec's.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuickProfile {
    pub field: Option<FieldAxes>,
    pub rays_per_point: Option<u32>,
    pub image: Option<ImageSpec>,
    pub raycast_sweep: Option<Vec<u32>>,
    pub scene: Option<SceneSpec>,
}

impl Spec {
    /// Parses and validates a spec file.
    pub fn load(path: &Path) -> Result<Spec, SpecError> {
        let text = std::fs::read_to_string(path).map_err(|source| SpecError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses and validates spec text; `file` is used in messages.
    pub fn parse(text: &str, file: &Path) -> Result<Spec, SpecError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let spec: Spec = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            SpecError::Parse {
                file: file.to_path_buf(),
                path: if path.is_empty() { ".".into() } else { path },
                message: e.into_inner().to_string(),
            }
        })?;
        spec.validate(file)?;
        Ok(spec)
    }

    /// The spec with its quick profile applied.
    pub fn quick(&self) -> Spec {
        let mut s = self.clone();
        if let Some(q) = &self.quick {
            if let Some(f) = &q.field {
                s.field = f.clone();
            }
            if let Some(r) = q.rays_per_point {
                s.render.rays_per_point = r;
                s.reference.rays_per_point = r;
            }
            if let Some(i) = &q.image {
                s.render.image = Some(i.clone());
            }
            if let Some(sw) = &q.raycast_sweep {
                s.reference.raycast_sweep = sw.clone();
            }
            if let Some(sc) = &q.scene {
                s.scene = sc.clone();
            }
        }
        s.quick = None;
        s
    }

    fn validate(&self, file: &Path) -> Result<(), SpecError> {
        let err = |field: &str, message: String| SpecError::Invalid {
            file: file.to_path_buf(),
            field: field.to_string(),
            message,
        };
        let check = |s: &Spec, prefix: &str| -> Result<(), SpecError> {
            let f = &s.field;
            for (name, empty) in [
                ("field.spheres", f.spheres.is_empty()),
                ("field.counts", f.counts.is_empty()),
                ("field.layouts", f.layouts.is_empty()),
                ("field.resolutions", f.resolutions.is_empty()),
                ("field.precisions", f.precisions.is_empty()),
                ("field.selections", f.selections.is_empty()),
            ] {
                if empty {
                    return Err(err(&format!("{prefix}{name}"), "must not be empty".into()));
                }
            }
            for (i, &c) in f.counts.iter().enumerate() {
                for &k in &f.spheres {
                    if let Err(e) = crate::sampling::SpherePoints::validate_count(k, c) {
                        return Err(err(&format!("{prefix}field.counts[{i}]"), e.to_string()));
                    }
                }
            }
            for (i, &r) in f.resolutions.iter().enumerate() {
                if !(2..=4096).contains(&r) {
                    return Err(err(
                        &format!("{prefix}field.resolutions[{i}]"),
                        format!("{r} is outside 2..=4096"),
                    ));
                }
            }
            for (name, n) in [
                ("render.rays_per_point", s.render.rays_per_point),
                ("reference.rays_per_point", s.reference.rays_per_point),
            ] {
                let k = (n as f64).sqrt().round() as u32;
                if n == 0 || k * k != n {
                    return Err(err(
                        &format!("{prefix}{name}"),
                        format!("{n} is not a positive perfect square (k² stratified rays)"),
                    ));
                }
            }
            if let Some(d) = s.render.max_distance {
                if !(d > 0.0 && d.is_finite()) {
                    return Err(err(
                        &format!("{prefix}render.max_distance"),
                        format!("{d} must be positive and finite"),
                    ));
                }
            }
            if s.scene.instances.is_empty() {
                return Err(err(&format!("{prefix}scene.instances"), "no instances".into()));
            }
            if !s.scene.instances.iter().any(|i| i.receiver) {
                return Err(err(&format!("{prefix}scene.instances"), "no receiver".into()));
            }
            if !s.scene.instances.iter().any(|i| i.caster) {
                return Err(err(&format!("{prefix}scene.instances"), "no caster".into()));
            }
            for (i, inst) in s.scene.instances.iter().enumerate() {
                if let MeshSource::Model(name) = &inst.mesh {
                    if let Err(e) = crate::geometry::models::ModelRegistry::embedded().entry(name)
                    {
                        return Err(err(
                            &format!("{prefix}scene.instances[{i}].mesh.model"),
                            e.to_string(),
                        ));
                    }
                }
            }
            Ok(())
        };
        check(self, "")?;
        check(&self.quick(), "quick.")?;
        Ok(())
    }
}
