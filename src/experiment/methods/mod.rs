//! Methods as plug-ins: *how* a render kind's values are answered on a scene's casters, beside
//! the visibility field the spec's `fields` axes sweep and our ray caster, the reference every
//! answer is measured against. A spec lists methods (`"methods": [{"method": "embree"}, …]`);
//! each entry is read in two steps, as `render` is: `method` names a registry entry
//! ([`MethodEntry`], [`BUILT_IN`], [`register`]), then that entry reads the remaining keys into
//! its own options struct, unknown keys refused ([`MethodEntry::read`], [`MethodOptions`]).
//!
//! A method's options expand to its settings (the cross product of its parameter axes), each a
//! [`Method`]: its precompute on a scene ([`Method::prepare`]: a BVH, a bake; timed by the
//! runner, with its bytes), then an [`Answer`]: a [`Visibility`] that the kind's own estimator
//! runs through on the reference's rays (a ray caster, a sphere tracer), or an estimator of
//! its own on the kind's points (an estimator that casts no ray, as cone tracing or an AO
//! field). The runner (`experiment::run`) gives every setting one row of `methods.csv` per scene:
//! the precompute's time and bytes, the estimate's time and rays per second, and the same
//! error columns as the field's rows, against the same same-ray reference and the same
//! converged reference.
//!
//! The field's cells stay in `table.csv` (their axes are the papers'); every other method is a
//! row of `methods.csv`. Every entry runs on the CPU backend; one whose method has kernels
//! (`sdf`, `aofield`) may also list `"backends": ["cpu", "gpu"]` (read here, beside `method`,
//! before the method's own keys): each setting then has a row per backend ([`Setting`]), the
//! `gpu` row answered by the kernels the prepared method hands over ([`Prepared::gpu`],
//! [`GpuMethod`]); a method without them, or without one for the kind, is refused by name
//! before any work ([`Method::refuses_on_gpu`]). `rayquery` runs on the `gpu` backend alone
//! ([`Method::refuses_on_cpu`]), and is skipped, saying why, on a device without ray queries
//! ([`Method::unavailable_on_gpu`]).

pub mod aofield;
pub mod embree;
pub mod field;
pub mod motion;
pub mod raycast;
pub mod rayquery;
pub mod sdf;
pub mod two_level;

use super::backend::Eval;
pub use super::backend::NoRays;
use super::backend_gpu::GpuQuantity;
use super::kinds::Kind;
use super::registry::{Entry, Registry};
use super::scenes::BuiltScene;
pub use super::spec::MethodSpec;
use super::spec::{default_backends, Backend, Spec, SpecError};
use super::validate::Validator;
use super::Result;
use crate::geometry::Similarity;
use crate::gpu::GpuContext;
use crate::render::estimator::Estimator;
use crate::visibility::Visibility;
use glam::Vec3;
use std::path::PathBuf;
use std::sync::Arc;

/// What a method precomputes from and answers through, on one scene.
pub struct MethodContext<'a> {
    pub scene: &'a BuiltScene,
    /// World triangles of every caster (the reference's).
    pub triangles: &'a [[Vec3; 3]],
    /// The kind's estimator on this scene.
    pub estimator: &'a dyn Estimator,
    /// The run's cache folder, for a method that caches its precompute (none: no cache).
    pub cache: Option<PathBuf>,
    /// The largest single allocation the run allows (bytes).
    pub memory_limit: u64,
}

/// How a prepared method answers the kind.
pub enum Answer {
    /// The kind's estimator through this, on the reference's rays (ray casters, sphere
    /// tracers): its values are comparable ray for ray with the reference's.
    Rays(Box<dyn Visibility + Send>),
    /// An estimator of the method's own on the kind's points (the rays are passed and may be
    /// ignored: an AO field casts none).
    Direct(Box<dyn Estimator + Send>),
}

/// What a method's precompute on one scene will cost, known from the spec and the built scene
/// before any work ([`Method::precompute`]): the plan's line for it, and what the memory limit
/// (`--max-memory-mib`) is held against, dry run included.
#[derive(Clone, Debug, PartialEq)]
pub struct Precompute {
    /// What it builds, for the plan ("bake 1 AO field(s): 6 × 32² texels × 12 samples × 256
    /// rays").
    pub what: String,
    /// Rays its bakes cast (0: none), where the cache serves nothing.
    pub rays: u64,
    /// Bytes it keeps and answers from ([`Prepared::bytes`], where the method reports them).
    pub bytes: u64,
    /// The most bytes alive at once while it runs (at least `bytes`).
    pub peak_bytes: u64,
}

/// Per mesh, its model-space triangles.
pub type ModelTriangles = Vec<Vec<[Vec3; 3]>>;

/// Each distinct caster mesh of `scene` (one per mesh, as the methods bake them, in the order
/// of their first instance) as its model-space triangles, and every caster as (its mesh's
/// index there, its transform).
pub fn caster_instances(scene: &BuiltScene) -> (ModelTriangles, Vec<(usize, Similarity)>) {
    let meshes = scene.caster_meshes();
    let mut model = vec![Vec::new(); meshes.len()];
    let mut instances = Vec::new();
    for (i, inst) in scene.scene.casters() {
        let m = (meshes.iter().position(|&g| g == scene.mesh_of[i])).expect("a caster mesh");
        if model[m].is_empty() {
            model[m] = (0..inst.mesh.triangle_count())
                .map(|t| inst.mesh.triangle(t))
                .collect();
        }
        instances.push((m, inst.transform));
    }
    (model, instances)
}

/// A value per distinct caster mesh of a scene (a method's bake of it), shared by the mesh's
/// instances ([`per_caster_mesh`]).
pub struct PerMesh<T> {
    /// Every caster as (its mesh's value, its transform).
    pub casters: Vec<(Arc<T>, Similarity)>,
    /// The values, one per mesh.
    pub meshes: Vec<Arc<T>>,
    /// Whether the cache held every one.
    pub cached: bool,
}

/// `load` of each distinct caster mesh of `scene` (its value, and whether its cache held it),
/// called once per mesh in the order of its first instance.
pub fn per_caster_mesh<T, E>(
    scene: &BuiltScene,
    mut load: impl FnMut(&crate::geometry::Mesh) -> std::result::Result<(Arc<T>, bool), E>,
) -> std::result::Result<PerMesh<T>, E> {
    let mut loaded: Vec<(usize, Arc<T>)> = Vec::new();
    let mut instances = Vec::new();
    let mut cached = true;
    for (i, inst) in scene.scene.casters() {
        let mesh = scene.mesh_of[i];
        let value = match loaded.iter().find(|(m, _)| *m == mesh) {
            Some((_, v)) => v.clone(),
            None => {
                let (v, hit) = load(&inst.mesh)?;
                cached &= hit;
                loaded.push((mesh, v.clone()));
                v
            }
        };
        instances.push((value, inst.transform));
    }
    Ok(PerMesh {
        casters: instances,
        meshes: loaded.into_iter().map(|(_, v)| v).collect(),
        cached,
    })
}

/// A method prepared on one scene.
pub struct Prepared {
    pub answer: Answer,
    /// Bytes of what it precomputed and reads (none where the method cannot say: Embree's
    /// BVH is opaque).
    pub bytes: Option<u64>,
    /// The precompute came from a cache (its time is then the load's).
    pub cached: bool,
    /// Extra columns of the method's own, in order (name, value).
    pub columns: Vec<(String, String)>,
    /// Its kernels on the `gpu` backend, where it has them for this kind (none: the `gpu`
    /// backend is refused, [`Method::refuses_on_gpu`]).
    pub gpu: Option<Box<dyn GpuMethod>>,
}

/// A prepared method's kernels on the `gpu` backend: what it precomputed, ready to upload.
pub trait GpuMethod: Send + Sync {
    /// Uploads the precompute to `ctx` and compiles the kernels; the result answers the kind
    /// at its points on the reference's rays, as the CPU answer does ([`Eval::setup_s`]: the
    /// upload and compile, the row's `setup_s`). `quantity`: the kind's GPU kernels, for a
    /// method that runs the kind's integrand on a visibility of its own (`rayquery`,
    /// `two_level`).
    fn upload<'a>(
        &'a self,
        ctx: &'a GpuContext,
        quantity: Option<&'a dyn GpuQuantity>,
    ) -> Result<Box<dyn Eval + 'a>>;
}

/// The planner's bound on the bytes of a BVH over one triangle, the triangle included (the
/// scene's state holds two: `plan::scene_state_bytes`; a method's world BVH one).
pub const BVH_BYTES_PER_TRIANGLE: u64 = 128;

/// One setting of a method: what answers a kind, with its parameters fixed.
pub trait Method: Send + Sync {
    /// Its name in specs and tables (`method`).
    fn name(&self) -> &'static str;
    /// Its parameters (name, value), in order: the row's parameter columns and its id.
    fn params(&self) -> Vec<(&'static str, String)> {
        Vec::new()
    }
    /// Why it cannot answer `kind` (refused before any work, naming both), or none.
    fn refuses(&self, _kind: &dyn Kind) -> Option<String> {
        None
    }
    /// Why it cannot answer `kind` on the `gpu` backend, or none (refused before any work,
    /// naming both): by default, that it has no GPU kernel. A method that overrides it hands
    /// its kernels over in [`Prepared::gpu`].
    fn refuses_on_gpu(&self, _kind: &dyn Kind) -> Option<String> {
        Some(format!("method \"{}\" has no GPU kernel", self.name()))
    }
    /// Why this build cannot run it (a cargo feature it needs), or none: the runner skips it
    /// with that reason, or fails where the run requires it.
    fn unavailable(&self) -> Option<String> {
        None
    }
    /// Why it cannot answer on the `cpu` backend (refused before any work, naming the kind),
    /// or none: a method of the GPU alone (`rayquery`).
    fn refuses_on_cpu(&self, _kind: &dyn Kind) -> Option<String> {
        None
    }
    /// Why the device `ctx` cannot run it (a feature the adapter lacks: ray queries), or
    /// none: the runner skips its `gpu` rows with that reason (the run's output and
    /// run.json's `skipped_methods`).
    fn unavailable_on_gpu(&self, _ctx: &GpuContext) -> Option<String> {
        None
    }
    /// Its precompute on one scene (timed by the runner: the row's `precompute_s`).
    fn prepare(&self, ctx: &MethodContext) -> Result<Prepared>;
    /// Its forms in a moving scene ([`motion::FrameForm`]: the names a spec's
    /// `animation.methods` lists and the rows carry, and the GPU forms run beside them); none
    /// by default: a method that follows motion lists them and builds them in [`Self::mover`]
    /// and [`Self::gpu_mover`].
    fn frame_forms(&self) -> &'static [motion::FrameForm] {
        &[]
    }
    /// Its CPU form `form` (one of [`Self::frame_forms`]) over the moving scene (`on`: its
    /// meshes, the cache, the field's fields), its per-mesh precompute done; each frame's
    /// transforms are applied by [`motion::Mover::update`].
    fn mover(&self, form: &str, _on: &motion::MoverInputs) -> Result<Box<dyn motion::Mover>> {
        Err(no_frame_form(self.name(), form))
    }
    /// Its GPU form `form` (one of [`Self::frame_forms`]) over the moving scene, uploaded before
    /// the frames, or why this scene cannot run it (skipped there, saying why).
    fn gpu_mover<'a>(
        &self,
        form: &str,
        _on: &motion::MoverInputs,
        _gpu: &motion::GpuInputs<'a>,
    ) -> Result<motion::GpuMover<'a>> {
        Err(no_frame_form(self.name(), form))
    }
    /// Why this build cannot run its per-frame forms (a cargo feature), or none.
    fn frame_unavailable(&self) -> Option<&'static str> {
        None
    }
    /// Its answer over world triangles alone, where it is a ray caster over them (`raycast`,
    /// `embree`): what `experiment performance` times beside the field. None where it is not
    /// one or this build cannot run it; its builder's error otherwise.
    fn world_caster(
        &self,
        _triangles: &[[Vec3; 3]],
    ) -> Option<std::result::Result<Box<dyn Visibility + Send>, String>> {
        None
    }
    /// What [`Self::prepare`] will cost on `scene` ([`Precompute`]), from the spec and the
    /// built scene alone: the planner lists it and refuses it over the memory limit before
    /// any work. None where the method cannot say; an error (why) where the precompute would
    /// fail.
    fn precompute(&self, _scene: &BuiltScene) -> std::result::Result<Option<Precompute>, String> {
        Ok(None)
    }
}

/// The error of a method asked for a per-frame form it does not list.
fn no_frame_form(method: &str, form: &str) -> super::Error {
    super::Error::invalid(
        format!("method \"{method}\""),
        format!("has no per-frame form \"{form}\""),
    )
}

impl dyn Method + '_ {
    /// The setting's id: the name, then each parameter's value (`sdf-64-f16`).
    pub fn id(&self) -> String {
        let mut s = self.name().to_string();
        for (_, v) in self.params() {
            s.push('-');
            s.push_str(&v);
        }
        s
    }
}

/// A method's own options: the keys of its `methods` entry beside `method`.
pub trait MethodOptions: MethodOptionsBase + std::fmt::Debug + Send + Sync {
    /// What serde cannot check, each error naming the field under `at` (`methods[1]`).
    fn validate(&self, at: &str, spec: &Spec, v: &Validator) -> std::result::Result<(), SpecError>;
    /// Its settings: the cross product of its parameter axes, in order.
    fn settings(&self) -> Vec<Box<dyn Method>>;
}

/// What every method's options do alike, given to any `Serialize + Clone` options type.
pub trait MethodOptionsBase {
    /// Its keys as JSON (written back into `spec.json`).
    fn to_json(&self) -> serde_json::Map<String, serde_json::Value>;
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn MethodOptions>;
}

impl<T: MethodOptions + serde::Serialize + Clone + 'static> MethodOptionsBase for T {
    fn to_json(&self) -> serde_json::Map<String, serde_json::Value> {
        match serde_json::to_value(self) {
            Ok(serde_json::Value::Object(m)) => m,
            other => unreachable!("method options must serialise as an object, not {other:?}"),
        }
    }

    fn clone_box(&self) -> Box<dyn MethodOptions> {
        Box::new(self.clone())
    }
}

/// A method in the registry.
#[derive(Clone, Copy)]
pub struct MethodEntry {
    /// `method` in a spec's `methods`.
    pub name: &'static str,
    /// One line for `experiment list` and errors.
    pub about: &'static str,
    /// Reads the method's own keys (a JSON object without `method`), refusing a key it does
    /// not read.
    pub read:
        fn(serde_json::Value) -> std::result::Result<Box<dyn MethodOptions>, serde_json::Error>,
}

/// [`MethodEntry::read`] for an options type that serde reads (with `deny_unknown_fields`).
pub fn read_as<T>(
    v: serde_json::Value,
) -> std::result::Result<Box<dyn MethodOptions>, serde_json::Error>
where
    T: serde::de::DeserializeOwned + MethodOptions + 'static,
{
    Ok(Box::new(serde_json::from_value::<T>(v)?))
}

/// The options of a method without parameters, `M`: `{"method": NAME}` alone (any other key
/// refused), its one setting `M::default()`. [`MethodEntry::read`] is `read_as::<NoOptions<M>>`.
pub struct NoOptions<M>(std::marker::PhantomData<fn() -> M>);

/// What [`NoOptions`] reads and writes: no key.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct NoKeys {}

impl<M> Clone for NoOptions<M> {
    fn clone(&self) -> Self {
        NoOptions(std::marker::PhantomData)
    }
}

impl<M> std::fmt::Debug for NoOptions<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("NoOptions")
    }
}

impl<M> serde::Serialize for NoOptions<M> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        NoKeys {}.serialize(s)
    }
}

impl<'de, M> serde::Deserialize<'de> for NoOptions<M> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        NoKeys::deserialize(d).map(|NoKeys {}| NoOptions(std::marker::PhantomData))
    }
}

impl<M: Method + Default + 'static> MethodOptions for NoOptions<M> {
    fn validate(&self, _: &str, _: &Spec, _: &Validator) -> std::result::Result<(), SpecError> {
        Ok(())
    }

    fn settings(&self) -> Vec<Box<dyn Method>> {
        vec![Box::new(M::default())]
    }
}

/// The methods of this build.
pub const BUILT_IN: &[MethodEntry] = &[
    raycast::ENTRY,
    embree::ENTRY,
    sdf::ENTRY,
    aofield::ENTRY,
    two_level::ENTRY,
    rayquery::ENTRY,
];

/// The registry: [`BUILT_IN`], then the methods added at run time by [`register`].
static REGISTRY: Registry<MethodEntry> = Registry::new(BUILT_IN, "method");

impl Entry for MethodEntry {
    fn name(&self) -> &'static str {
        self.name
    }
}

/// Adds a method to the registry; refused when its name is taken.
pub fn register(entry: MethodEntry) -> std::result::Result<(), String> {
    REGISTRY.register(entry)
}

/// The registered method named `name`.
pub fn lookup(name: &str) -> Option<MethodEntry> {
    REGISTRY.lookup(name)
}

/// Every registered method's name, built-in ones first.
pub fn names() -> Vec<&'static str> {
    REGISTRY.names()
}

/// Every registered method's settings at its default options (`{"method": NAME}` alone), in
/// registry order; a method whose options the defaults do not read has none here.
pub fn default_settings() -> Vec<Box<dyn Method>> {
    names()
        .into_iter()
        .filter_map(lookup)
        .filter_map(|e| (e.read)(serde_json::Value::Object(Default::default())).ok())
        .flat_map(|o| o.settings())
        .collect()
}

/// One row source of `methods.csv`: a method's setting on a backend.
pub struct Setting {
    pub method: Box<dyn Method>,
    pub backend: Backend,
}

impl Setting {
    /// The setting's id (`dyn Method`'s `id`; the `setting` column, the same on every backend).
    pub fn id(&self) -> String {
        self.method.id()
    }

    /// Why it cannot answer `kind` on its backend ([`Method::refuses`], and on the GPU
    /// [`Method::refuses_on_gpu`]), as "cannot answer render …", naming a backend other than
    /// the CPU; none where it can.
    pub fn refuses(&self, kind: &dyn Kind) -> Option<String> {
        let why = self.method.refuses(kind).or_else(|| match self.backend {
            Backend::Cpu => self.method.refuses_on_cpu(kind),
            Backend::Gpu => self.method.refuses_on_gpu(kind),
        })?;
        let on = match self.backend {
            Backend::Cpu => String::new(),
            b => format!(" on backend \"{}\"", b.name()),
        };
        Some(format!(
            "cannot answer render \"{}\"{on}: {why}",
            kind.name()
        ))
    }

    /// The id with the backend where it is not the CPU (`sdf-64-f16-trace@gpu`): what names
    /// the row in plans, images and checks.
    pub fn label(&self) -> String {
        match self.backend {
            Backend::Cpu => self.id(),
            b => format!("{}@{}", self.id(), b.name()),
        }
    }
}

/// Every setting of a spec's `methods` on each of its entry's backends, in order: each entry's
/// settings in its own order, each on its backends in theirs.
pub fn settings_of(spec: &Spec) -> Vec<Setting> {
    spec.methods.iter().flat_map(|m| m.settings()).collect()
}

impl MethodSpec {
    /// Its options, read by its method's plug-in from the keys it wrote back (an entry the
    /// registry read: its method is registered and its keys read back).
    pub fn read_options(&self) -> Box<dyn MethodOptions> {
        let entry = lookup(self.method)
            .unwrap_or_else(|| panic!("method \"{}\" is not registered", self.method));
        (entry.read)(serde_json::Value::Object(self.options.clone())).unwrap_or_else(|e| {
            panic!(
                "method \"{}\" does not read back its own options: {e}",
                self.method
            )
        })
    }

    /// Its settings ([`MethodOptions::settings`]), each on its backends.
    pub fn settings(&self) -> Vec<Setting> {
        let mut out = Vec::new();
        let options = self.read_options();
        for &backend in &self.backends {
            for (i, method) in options.settings().into_iter().enumerate() {
                out.push((i, Setting { method, backend }));
            }
        }
        // Setting-major, each setting's backends in the entry's order.
        out.sort_by_key(|(i, _)| *i);
        out.into_iter().map(|(_, s)| s).collect()
    }
}

impl<'de> serde::Deserialize<'de> for MethodSpec {
    /// Two steps: `method` and `backends`, then the rest by that method's plug-in, whose
    /// options are written back as the spec's plain JSON.
    fn deserialize<D: serde::Deserializer<'de>>(
        de: D,
    ) -> std::result::Result<MethodSpec, D::Error> {
        use serde::de::Error;
        let mut own = serde_json::Map::<String, serde_json::Value>::deserialize(de)?;
        let name = match own.remove("method") {
            Some(serde_json::Value::String(s)) => s,
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "`method`: expected a method's name, got {other}"
                )))
            }
            None => return Err(D::Error::missing_field("method")),
        };
        let entry = REGISTRY
            .lookup_for("method", &name)
            .map_err(D::Error::custom)?;
        let backends = match own.remove("backends") {
            None => default_backends(),
            Some(v) => {
                let b: Vec<Backend> = serde_json::from_value(v).map_err(|e| {
                    D::Error::custom(format!("\"{}\": `backends`: {e}", entry.name))
                })?;
                if b.is_empty() {
                    return Err(D::Error::custom(format!(
                        "\"{}\": `backends` needs at least one of \"cpu\", \"gpu\"",
                        entry.name
                    )));
                }
                b
            }
        };
        // Read again by `MethodSpec::read_options` from the keys written back here.
        let options = super::registry::read_and_write_back(
            "method",
            entry.name,
            entry.read,
            |o| o.to_json(),
            own,
        )
        .map_err(D::Error::custom)?;
        Ok(MethodSpec {
            method: entry.name,
            options,
            backends,
        })
    }
}
