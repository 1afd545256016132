//! Experiment specs: `experiments/*.json`, one per figure or table of a paper. Plain structs, a
//! doc comment per field, unknown keys rejected; every error names the file, the field path and
//! what was expected ([`SpecError`]). Reading a file (`Spec::load`, `Spec::parse`) and
//! validating it live in `experiment::spec_load`; the part checks in `experiment::validate`.
//!
//! A spec's name is its file stem (`experiments/figure6.json` is `figure6`). Its cells are
//! scenes × field settings × backends: each entry of `fields` is a cross product of its axes, and
//! the cells are the union of the entries (duplicates dropped), so that a figure comparing, say,
//! 1122 lat-long maps with 1090 Slater maps lists two entries.

pub mod mesh;

pub use super::error::SpecError;
use crate::field::{FieldParams, Precision, Selection};
use crate::render::camera::Camera;
use crate::sampling::{LayoutKind, SphereKind};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// One experiment: scenes, the field axes to sweep, what to render, how to measure.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// The figure or table reproduced, with its paper (e.g. "Gaitatzes et al. 2008, Figure 6").
    pub reproduces: String,
    /// What the experiment shows, and where it deviates from the paper.
    #[serde(default)]
    pub description: String,
    /// The scenes; every field setting is evaluated on each.
    pub scenes: Vec<SceneSpec>,
    /// The field axes: each entry is a cross product; the cells are the union of the entries.
    pub fields: Vec<FieldAxes>,
    /// What is rendered and how.
    pub render: RenderSpec,
    /// Where the AO is computed: "cpu" and/or "gpu".
    #[serde(default = "default_backends")]
    pub backends: Vec<Backend>,
    /// Other methods answering the kind on every scene, beside the field's cells and our ray
    /// cast reference (`[{"method": "embree"}, …]`, see `experiment::methods`): each setting
    /// is a row of `methods.csv`, measured as the field's cells are.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub methods: Vec<MethodSpec>,
    /// The ray-cast reference.
    pub reference: ReferenceSpec,
    /// The paper's own numbers for the cells reproduced.
    #[serde(default)]
    pub paper: Option<PaperNumbers>,
    /// RMS thresholds for `experiment check` (full profile).
    #[serde(default)]
    pub thresholds: Vec<Threshold>,
    /// The `--quick` profile (smaller axes, for CI and regression checks).
    pub quick: QuickProfile,
    /// Frames: every scene evaluated at each, its instances moved along their `motion`, every
    /// per-frame method measured (`frames.csv`, see `experiment::run`); none: one static frame
    /// (`table.csv`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub animation: Option<AnimationSpec>,
}

/// A spec's frames ([`Spec::animation`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnimationSpec {
    /// Frames (1 to `validate::MAX_FRAMES`); frame f is at time f · `time_step`.
    pub frames: u32,
    /// Seconds between frames (positive, finite).
    pub time_step: f64,
    /// The per-frame methods measured beside `world_rebuild` (the reference, always run), by
    /// name ([`FRAME_METHODS`]); default every one this build has.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub methods: Option<Vec<String>>,
}

/// Every per-frame method an animation may name, in the order their rows are written: the ray
/// casters (the world rebuild first: the reference of the others), then the fields: the CPU
/// forms of the registered methods that follow motion and the field's
/// (`experiment::methods::motion::frame_forms`, which a test holds this list to).
pub const FRAME_METHODS: [&str; 6] = [
    "world_rebuild",
    "two_level",
    "embree_rebuild",
    "embree_instances",
    "field_every_sphere",
    "field",
];

/// The CPU, where a spec (or a `methods` entry) lists no `backends`.
pub fn default_backends() -> Vec<Backend> {
    vec![Backend::Cpu]
}

/// A compute backend.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Backend {
    /// rayon over points, through the `Visibility` interface.
    Cpu,
    /// wgpu compute kernels (Vulkan; a hardware adapter where there is one, else lavapipe):
    /// field lookup and CWBVH ray casting on the same rays (`experiment::backend_gpu`).
    Gpu,
}

impl Backend {
    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
        }
    }
}

/// A named scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Short name used in tables and file names (letters, digits, `_`, `-`).
    pub name: String,
    /// The meshes placed in the scene.
    pub instances: Vec<InstanceSpec>,
    /// This scene's camera, in place of `render.image.camera` (several views of one scene
    /// are several scenes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<Camera>,
}

/// A mesh placed in the scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstanceSpec {
    /// A real mesh by name (see `data/models.json`), or a procedural mesh.
    pub mesh: MeshSource,
    /// Casts occlusion: it gets a field, and the reference traces its triangles.
    #[serde(default)]
    pub caster: bool,
    /// Receives occlusion: AO is evaluated at its vertices (or pixels).
    #[serde(default)]
    pub receiver: bool,
    /// Placement.
    #[serde(default)]
    pub transform: TransformSpec,
    /// Its rigid path over the spec's `animation` ([`crate::geometry::motion`]), relative to
    /// its placement; none: it stays where `transform` puts it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion: Option<crate::geometry::motion::Motion>,
}

/// Where a mesh comes from. Its JSON is one key naming the kind (`{"model": NAME}`,
/// `{"corner": {"n": 33}}`, ...), or a user's file with an optional pin
/// (`{"file": "PATH", "sha256": "…"}`); the (de)serialisation lives in `spec_mesh.rs`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(remote = "Self", rename_all = "snake_case", deny_unknown_fields)]
pub enum MeshSource {
    /// A model from the registry, by name (`{"model": "stanford-bunny_39k"}`).
    Model(String),
    /// A user's OBJ or PLY file (`{"file": "PATH", "sha256": "…"}`), PATH relative to the
    /// spec file's folder.
    #[serde(skip)]
    File(mesh::MeshFile),
    /// The 2008 paper's corner receiver: three unit squares, n × n vertices each.
    Corner { n: usize },
    /// A closed cube of side `size` with a square through-hole of side `hole`.
    CubeWithHole { size: f32, hole: f32 },
    /// The default Gielis supershape with about this many triangles.
    Supershape { triangles: usize },
    /// A UV sphere.
    Sphere {
        radius: f32,
        stacks: usize,
        slices: usize,
    },
    /// A square plane of side `size`, n × n vertices, facing +y.
    Plane { size: f32, n: usize },
    /// A lat-long ellipsoid with semi-axes `radii` (x, y, z) (e.g. [10, 1, 1]: a long thin
    /// caster).
    Ellipsoid {
        radii: Vec3,
        stacks: usize,
        slices: usize,
    },
}

impl MeshSource {
    /// A short label for tables ("stanford-bunny_39k", "corner33", ...).
    pub fn label(&self) -> String {
        match self {
            MeshSource::Model(m) => m.clone(),
            MeshSource::File(f) => f.label(),
            MeshSource::Corner { n } => format!("corner{n}"),
            MeshSource::CubeWithHole { size, hole } => format!("cube_with_hole{size}x{hole}"),
            MeshSource::Supershape { triangles } => format!("supershape{triangles}"),
            MeshSource::Sphere { stacks, slices, .. } => format!("sphere{stacks}x{slices}"),
            MeshSource::Plane { n, .. } => format!("plane{n}"),
            MeshSource::Ellipsoid { radii, .. } => {
                format!("ellipsoid{}x{}x{}", radii.x, radii.y, radii.z)
            }
        }
    }
}

/// A similarity placement. Without `fit`: world = translate + scale · R · p. With `fit`, the
/// mesh's minimal bounding sphere (c, r) is first mapped onto the fit sphere (C, ρ):
/// world = translate + scale · (C + ρ/r · R · (p − c)), i.e. the rotation turns the mesh about
/// its own sphere centre (this is `geometry::procedural::over_corner` with C = (0.5, 0.45, 0.5),
/// ρ = 0.35).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TransformSpec {
    /// Fit the mesh's minimal bounding sphere to this sphere.
    pub fit: Option<FitSpec>,
    /// Rotation: angles in degrees about x, y and z, composed as R = R_y · R_x · R_z (glam's
    /// `EulerRot::YXZ`: yaw, then pitch, then roll).
    pub rotate_deg: Option<Vec3>,
    /// Uniform scale (positive).
    pub scale: Option<f32>,
    /// Translation (read in f64: a scene far from the origin keeps its exact placement, and
    /// the runner moves it next to the origin before forming f32 coordinates).
    pub translate: Option<glam::DVec3>,
}

/// A target sphere for [`TransformSpec::fit`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitSpec {
    /// World centre.
    pub center: Vec3,
    /// World radius (positive).
    pub radius: f32,
}

/// One cross product of field axes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldAxes {
    /// Positional sample sets: "slater" (the paper), "lat_long", "fibonacci".
    #[serde(default = "default_spheres")]
    pub spheres: Vec<SphereKind>,
    /// Positional sample counts (maps per field); each must be a valid count of every sphere.
    pub counts: Vec<usize>,
    /// Directional layouts: "concentric" (the paper), "polar", "rejection".
    #[serde(default = "default_layouts")]
    pub layouts: Vec<LayoutKind>,
    /// Directional resolutions (res × res texels per map).
    pub resolutions: Vec<u32>,
    /// Stored precisions: "u8" (the paper), "u16", "f32", "bit1".
    #[serde(default = "default_precisions")]
    pub precisions: Vec<Precision>,
    /// Map selection at lookup: "nearest" (the paper) or "interpolated".
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

impl FieldAxes {
    /// Every (field parameters, selection) of the cross product, in axis order.
    pub fn settings(&self) -> Vec<(FieldParams, Selection)> {
        let mut out = Vec::new();
        for &sphere in &self.spheres {
            for &count in &self.counts {
                for &layout in &self.layouts {
                    for &res in &self.resolutions {
                        for &precision in &self.precisions {
                            for &selection in &self.selections {
                                let params = FieldParams {
                                    sphere,
                                    count,
                                    layout,
                                    res,
                                    precision,
                                };
                                out.push((params, selection));
                            }
                        }
                    }
                }
            }
        }
        out
    }
}

/// What is rendered: the kind (`what`, a name in the kind registry of `experiment::kinds`;
/// default `"vertex_ao"`), the keys every kind reads (`rays_per_point`, `image`,
/// `intra_bias`), and the kind's own options, plain JSON: the kind registry reads `render`
/// (its `Deserialize` lives there), handing the kind's own keys to its plug-in, which refuses
/// a key it does not read and writes its options back here (`kinds::KindEntry::read`,
/// `kinds::options_of`).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSpec {
    /// The kind's name (`render.what`).
    pub what: &'static str,
    /// Rays per evaluation point, k² stratified directions (a perfect square; the papers use
    /// 256 for AO, 20 per light for shadows, 4 for reflections).
    pub rays_per_point: u32,
    /// The image (PNG and EXR, and the per-pixel RMS); none: per-point numbers only (a per-pixel
    /// kind needs one).
    pub image: Option<ImageSpec>,
    /// A fixed tolerance of the intra-object test (receivers that are casters), as a fraction
    /// of 2R (none: the field's own resolution-derived tolerance, `IntraBias::Auto`; see
    /// `field::lookup`).
    pub intra_bias: Option<f32>,
    /// The kind's own options, as its plug-in read and wrote them back.
    pub options: serde_json::Map<String, serde_json::Value>,
}

impl Serialize for RenderSpec {
    fn serialize<S: serde::Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let own = &self.options;
        let mut m = ser.serialize_map(Some(3 + self.intra_bias.is_some() as usize + own.len()))?;
        m.serialize_entry("what", self.what)?;
        m.serialize_entry("rays_per_point", &self.rays_per_point)?;
        m.serialize_entry("image", &self.image)?;
        if let Some(b) = self.intra_bias {
            m.serialize_entry("intra_bias", &b)?;
        }
        for (k, v) in own {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// One entry of a spec's `methods`: the method's name, the backends it runs on and its own
/// options, plain JSON: the method registry reads each entry (its `Deserialize` lives in
/// `experiment::methods`), handing the method's own keys to its plug-in, which refuses a key
/// it does not read and writes its options back here.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodSpec {
    pub method: &'static str,
    /// The method's own options, as its plug-in read and wrote them back.
    pub options: serde_json::Map<String, serde_json::Value>,
    /// `backends` (default `["cpu"]`).
    pub backends: Vec<Backend>,
}

impl Serialize for MethodSpec {
    fn serialize<S: serde::Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let own = &self.options;
        let backends = self.backends != default_backends();
        let mut m = ser.serialize_map(Some(1 + backends as usize + own.len()))?;
        m.serialize_entry("method", self.method)?;
        if backends {
            m.serialize_entry("backends", &self.backends)?;
        }
        for (k, v) in own {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl RenderSpec {
    /// The image, if the spec renders one.
    pub fn image(&self) -> Option<&ImageSpec> {
        self.image.as_ref()
    }

    /// The kind's own options as `T`, when they are (tests and tools reading one kind's keys).
    pub fn options_as<T: serde::de::DeserializeOwned>(&self) -> Option<T> {
        serde_json::from_value(serde_json::Value::Object(self.options.clone())).ok()
    }
}

/// An image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageSpec {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The camera; none: the corner scenes' camera ([`Camera::corner`]).
    #[serde(default)]
    pub camera: Option<Camera>,
}

/// The ray-cast reference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    /// Rays per point of the reference (a perfect square). Equal to `render.rays_per_point`, the
    /// reference and the field lookup trace exactly the same rays.
    pub rays_per_point: u32,
    /// Seed of the per-point ray rotation (shared by the reference and the lookup).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Ray-cast AO with these ray counts too (perfect squares), for the error-against-time
    /// plot. Default 16, 36, 64, 144, 256: the k² stratified sets nearest the papers' 16, 32,
    /// 64, 128, 256.
    #[serde(default = "default_sweep")]
    pub raycast_sweep: Vec<u32>,
    /// Seeds per cell: the cell (and its same-ray reference) is evaluated with the per-point
    /// rotations of seeds `seed`, `seed + 1`, …; RMS columns are the mean over seeds, with
    /// their standard deviation beside them, and thresholds apply to the mean. Default 3.
    #[serde(default = "default_seeds")]
    pub seeds: u32,
    /// The converged reference every RMS `_vs_truth` is measured against.
    #[serde(default)]
    pub truth: TruthSpec,
    /// Field lookup with these ray counts too (perfect squares), against the converged
    /// reference only, for the error-against-time plot (a field makes extra rays cheap).
    #[serde(default)]
    pub field_rays_sweep: Vec<u32>,
}

/// The converged reference (see `render::truth`): jittered stratified rays in independent
/// batches, k doubled until the RMS standard error is below the target or the cap is reached.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TruthSpec {
    /// Target RMS over points of the per-point standard error, 0–255 scale. Default 0.25.
    #[serde(default = "default_truth_target")]
    pub target_stderr: f64,
    /// Most rays per point, all batches together. Default 16,384.
    #[serde(default = "default_truth_max_rays")]
    pub max_rays: u32,
    /// Independent batches per point (≥ 2; their spread is the error estimate). Default 4.
    #[serde(default = "default_truth_batches")]
    pub batches: u32,
}

impl Default for TruthSpec {
    fn default() -> Self {
        TruthSpec {
            target_stderr: default_truth_target(),
            max_rays: default_truth_max_rays(),
            batches: default_truth_batches(),
        }
    }
}

fn default_seeds() -> u32 {
    3
}
fn default_truth_target() -> f64 {
    0.25
}
fn default_truth_max_rays() -> u32 {
    16_384
}
fn default_truth_batches() -> u32 {
    4
}

fn default_seed() -> u64 {
    1
}
fn default_sweep() -> Vec<u32> {
    vec![16, 36, 64, 144, 256]
}

/// The paper's numbers for the cells reproduced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperNumbers {
    /// Where they come from (e.g. "../shared/paper/2008_figure6.csv").
    pub source: String,
    /// The label of the cell that ratios are normalised to (default: the first cell).
    #[serde(default)]
    pub reference_cell: Option<String>,
    /// The cells.
    pub cells: Vec<PaperCell>,
}

/// A struct whose first fields are a cell's axes (each optional: absent, none) with their one
/// matcher, `matches`: a threshold and a paper cell pick cells by them. Fields of each struct,
/// not one struct flattened into both, so that serde's errors still name the field
/// (`thresholds[0].sphere`) and an unknown key is refused (`deny_unknown_fields`).
macro_rules! with_cell_axes {
    ($(#[$attr:meta])* pub struct $name:ident { $($fields:tt)* }) => {
        $(#[$attr])*
        pub struct $name {
            /// Scene name.
            pub scene: Option<String>,
            /// Positional sample set.
            pub sphere: Option<SphereKind>,
            /// Positional samples (maps).
            pub positional_samples: Option<usize>,
            /// Directional resolution (res × res).
            pub directional_res: Option<u32>,
            /// Directional layout.
            pub layout: Option<LayoutKind>,
            /// Stored precision.
            pub precision: Option<Precision>,
            /// Map selection.
            pub selection: Option<Selection>,
            /// Backend.
            pub backend: Option<Backend>,
            $($fields)*
        }

        impl $name {
            /// Whether the cell on scene `scene` of field `p`, read with selection `s` on backend
            /// `b`, has every axis this sets (an axis left out matches any value).
            pub fn matches(&self, scene: &str, p: &FieldParams, s: Selection, b: Backend) -> bool {
                self.scene.as_ref().is_none_or(|x| x == scene)
                    && self.sphere.is_none_or(|x| x == p.sphere)
                    && self.positional_samples.is_none_or(|x| x == p.count)
                    && self.directional_res.is_none_or(|x| x == p.res)
                    && self.layout.is_none_or(|x| x == p.layout)
                    && self.precision.is_none_or(|x| x == p.precision)
                    && self.selection.is_none_or(|x| x == s)
                    && self.backend.is_none_or(|x| x == b)
            }
        }
    };
}

with_cell_axes! {
    /// One cell of a paper's table, and which of our cells it corresponds to: the first row
    /// matching its axes (so the first backend's, unless `backend` names one).
    #[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct PaperCell {
        /// Row label in `paper_vs_ours.csv`.
        pub label: String,
        /// When set, the paper's RMS is between this cell and the same cell at this precision
        /// (the slides' 8 vs 16 bit), not against the reference.
        pub versus_precision: Option<Precision>,
        /// Which of our measurements the cell pairs with, where the table's first matching row
        /// is not it (default: that row).
        #[serde(default)]
        pub ours: OursSource,
        /// Triangles of the paper's model.
        pub triangles: Option<u64>,
        /// Rays the paper cast (receiver points × rays per point).
        pub rays_cast: Option<u64>,
        /// The paper's ray-cast time, seconds.
        pub raycast_s: Option<f64>,
        /// The paper's preprocessing (bake) time, seconds.
        pub preprocess_s: Option<f64>,
        /// The paper's time of the estimate through the field (AO, shadows or reflections),
        /// seconds (`ao_s` is read as this).
        #[serde(alias = "ao_s")]
        pub estimate_s: Option<f64>,
        /// The paper's RMS (0–255, on images).
        pub rms: Option<f64>,
        /// Remarks (uncertain cells, machines).
        pub note: Option<String>,
    }
}

/// Where a paper cell's `ours_*` values come from (see `experiment::paper`). Every source
/// starts from the table's first row matching the cell's axes (its scene and backend).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "from", rename_all = "snake_case", deny_unknown_fields)]
pub enum OursSource {
    /// That row (`"ours": {"from": "table"}`, the default).
    #[default]
    Table,
    /// The ray cast of `raycast_sweep.csv` at this ray count, on that row's scene and backend
    /// (a paper's sharp, one-ray shadows against our soft ones):
    /// `{"from": "raycast_sweep", "rays_per_point": 1}`.
    RaycastSweep { rays_per_point: u32 },
    /// The sum over these scenes of the row matching the cell's other axes, on the first
    /// scene's backend (a paper's frame of one pass per caster, each caster a scene of ours):
    /// `{"from": "sum_of_scenes", "scenes": ["bunny", "cow"]}`. Times, rays and triangles
    /// add; no RMS (no one image holds them).
    SumOfScenes { scenes: Vec<String> },
}

with_cell_axes! {
    /// An RMS threshold for `experiment check`, over the cells matching its axes (all when
    /// unset).
    #[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Threshold {
        /// Largest allowed per-vertex RMS (0–255).
        pub rms_vertex_max: Option<f64>,
        /// Largest allowed per-pixel RMS (0–255).
        pub rms_image_max: Option<f64>,
    }
}

/// The `--quick` profile: each field given replaces the spec's; `thresholds` always replace the
/// full profile's (absent: none), since the full profile's cells are not the quick ones.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct QuickProfile {
    /// Replaces `scenes`.
    pub scenes: Option<Vec<SceneSpec>>,
    /// Replaces `fields`.
    pub fields: Option<Vec<FieldAxes>>,
    /// Replaces both `render.rays_per_point` and `reference.rays_per_point`.
    pub rays_per_point: Option<u32>,
    /// Replaces `render.image`.
    pub image: Option<ImageSpec>,
    /// Replaces `reference.raycast_sweep`.
    pub raycast_sweep: Option<Vec<u32>>,
    /// Replaces `backends` (e.g. a GPU run too slow for the quick profile on lavapipe).
    pub backends: Option<Vec<Backend>>,
    /// Replaces `reference.field_rays_sweep`.
    pub field_rays_sweep: Option<Vec<u32>>,
    /// Replaces `reference.truth.max_rays`.
    pub truth_max_rays: Option<u32>,
    /// Replaces `animation.frames`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames: Option<u32>,
    /// The quick profile's thresholds.
    pub thresholds: Vec<Threshold>,
}

impl Spec {
    /// The spec with its quick profile applied (its `quick` left as is).
    pub fn quick(&self) -> Spec {
        let mut s = self.clone();
        let q = &self.quick;
        if let Some(sc) = &q.scenes {
            s.scenes = sc.clone();
        }
        if let Some(f) = &q.fields {
            s.fields = f.clone();
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
        if let Some(b) = &q.backends {
            s.backends = b.clone();
        }
        if let Some(sw) = &q.field_rays_sweep {
            s.reference.field_rays_sweep = sw.clone();
        }
        if let Some(m) = q.truth_max_rays {
            s.reference.truth.max_rays = m;
        }
        if let (Some(f), Some(a)) = (q.frames, s.animation.as_mut()) {
            a.frames = f;
        }
        s.thresholds = q.thresholds.clone();
        s
    }

    /// The profile asked for: [`Self::quick`] when `quick`, else a copy.
    pub fn profile(&self, quick: bool) -> Spec {
        if quick {
            self.quick()
        } else {
            self.clone()
        }
    }
}

/// The square root of a perfect square, `None` otherwise (and for 0).
pub fn exact_sqrt(n: u32) -> Option<u32> {
    let k = (n as f64).sqrt().round() as u32;
    (n > 0 && k.checked_mul(k) == Some(n)).then_some(k)
}
