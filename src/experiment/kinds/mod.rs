//! Render kinds as plug-ins: what a spec's `render` computes, behind one interface ([`Kind`])
//! that the planner, the runner, the backends and the row writer work through, and a registry
//! ([`KindEntry`], [`register`], [`lookup`]) that `render.what` is read through.
//!
//! A kind is one file of this folder (`vertex_ao.rs`, `image_ao.rs`, `shadows.rs`,
//! `reflections.rs`) and one line of [`BUILT_IN`]. It owns
//! - its options: the keys of `render` beside the four every kind reads ([`RenderSpec`]'s
//!   `what`, `rays_per_point`, `image`, `intra_bias`), read in a second step into the kind's
//!   own struct, unknown keys refused ([`KindEntry::read`], [`KindOptions`]);
//! - their validation ([`KindOptions::validate`], before any work);
//! - what it needs of a scene ([`Needs`]: a view with its G-buffer, normal fields);
//! - its evaluation points, its [`Estimator`] and, where one exists, its GPU kernels
//!   ([`Kind::setup`] → [`Setup`], with [`Setup::gpu`]);
//! - the metric columns it fills ([`Columns`]) and its own ([`Kind::own_metrics`]);
//! - how its values show as an image ([`Kind::image_channels`]).
//!
//! Everything else (the same-ray reference, the seeds, the converged reference and its cache,
//! the sweeps, the images, the tables) is the runner's, the same for every kind.
//! ARCHITECTURE.md lists the files that add a kind.
//!
//! Values per point are one scalar in \[0, 1\], or several for an estimator with channels
//! ([`crate::render::estimator::Estimator::channels`]: an RGB, a direction mapped into
//! \[0, 1\]³): the converged reference, the 0–255 RMS (over every channel) and the images
//! (grey or RGB) follow its count.

pub mod ao;
pub mod image_ao;
pub mod reflections;
pub mod shadows;
pub mod vertex_ao;

use super::backend_gpu::GpuQuantity;
use super::registry::{Entry, Registry};
use super::scenes::BuiltScene;
use super::spec::{ImageSpec, RenderSpec, Spec, SpecError};
use super::validate::Validator;
use crate::field::lookup::{IntraBias, LookupOptions};
use crate::field::Selection;
use crate::render::estimator::{Estimator, Quantity};
use crate::render::image::ImageChannels;
use crate::render::points::{EvalPoints, GBuffer};
use crate::render::truth::Truth;

/// What a kind needs built before it can run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Needs {
    /// A camera and the G-buffer of its view (the points are pixels).
    pub view: bool,
    /// Normal fields beside the distance fields (reflections).
    pub normal_field: bool,
}

/// The metric columns a kind fills beside the ones every kind has (`rms_vs_truth` and its
/// crease/interior split, over the evaluation points).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Columns {
    /// Per-point values whose unquantised RMS is `rms_vertex` (the 2008 paper's per-vertex AO).
    pub vertex: bool,
}

/// A kind set up on one scene: its points, its estimator, its ray offset.
pub struct Setup {
    pub points: EvalPoints,
    pub estimator: Box<dyn Estimator>,
    /// The estimator's GPU kernels (field lookup and ray casting, on the CPU path's rays); none:
    /// the `gpu` backend refuses the kind, naming it.
    pub gpu: Option<Box<dyn GpuQuantity>>,
    /// The largest distance a ray origin moves along its normal (model units; each point's is
    /// its instance's, `render::ao::instance_epsilon`), for run.json.
    pub offset: f32,
    /// A per-point factor in \[0, 1\] that turns the kind's values into a shaded picture,
    /// written beside each value image as `-shaded.png` (shadows: the unshadowed direct light,
    /// so that value × factor is the shadowed image); none: no such picture.
    pub shading: Option<Vec<f32>>,
    /// A second reference the cells' images are also measured against (`rms_image_vs_second`):
    /// its name and its estimator, evaluated once per scene by ray casting on the first seed's
    /// rays (reflections: the perfect mirror beside the glossy lobe). None: no such column.
    pub second_reference: Option<(&'static str, Box<dyn Estimator>)>,
}

/// A render kind, bound to a spec's `render`.
pub trait Kind: Sync {
    /// The spec's name for it ("vertex_ao").
    fn name(&self) -> &'static str;
    /// The `render` it was made from (the keys every kind reads are there).
    fn render(&self) -> &RenderSpec;
    /// What its estimator computes, with the options a method needs to decide whether it
    /// can answer it before any scene is built ([`Answers`]).
    fn answers(&self) -> Answers<'_> {
        Answers::Other
    }
    /// What it needs built.
    fn needs(&self) -> Needs;
    /// Which metric columns it fills.
    fn columns(&self) -> Columns;
    /// Rays per evaluation point (k²).
    fn rays_per_point(&self) -> u32 {
        self.render().rays_per_point
    }
    /// Rays one evaluation casts per point (k², times the lights for shadows): the count the
    /// tables' rays per second are of.
    fn rays_cast_per_point(&self) -> u64 {
        self.rays_per_point() as u64
    }
    /// The image, when the spec renders one (a view kind always has one).
    fn image(&self) -> Option<&ImageSpec> {
        self.render().image.as_ref()
    }
    /// The most evaluation points a scene can have (the plan's ray counts, before any scene
    /// state is built).
    fn max_points(&self, scene: &BuiltScene) -> u64;
    /// Its points and estimator on `scene` (`view`: the G-buffer of the spec's image, when
    /// there is one).
    fn setup(&self, scene: &BuiltScene, view: Option<&GBuffer>) -> Setup;
    /// How fields are read for it, with the cell's map selection: `render.intra_bias` when the
    /// spec fixes it, else the field's own tolerance.
    fn lookup_options(&self, selection: Selection) -> LookupOptions {
        LookupOptions {
            selection,
            intra_bias: self
                .render()
                .intra_bias
                .map(IntraBias::Fixed)
                .unwrap_or(LookupOptions::default().intra_bias),
        }
    }
    /// What is wrong with a built scene for this kind, before any work: (the spec field, why).
    fn scene_problem(&self, _scene: &BuiltScene) -> Option<(String, String)> {
        None
    }
    /// The normal field precisions (bits per component) the cells sweep, for a kind that reads
    /// normal fields ([`Needs::normal_field`]); empty for the others.
    fn normal_bits(&self) -> Vec<u32> {
        Vec::new()
    }
    /// How its values show as an image, `channels` being its estimator's values per point:
    /// grey for one, red, green and blue for three ([`ImageChannels::default_for`]). A kind
    /// of another count that renders an image must choose (none: a bug of the kind, reported
    /// when its scene is set up).
    fn image_channels(&self, channels: usize) -> Option<ImageChannels> {
        ImageChannels::default_for(channels)
    }
    /// Its own metric columns of one evaluation (name, value), written after the standard
    /// ones of `table.csv` and `methods.csv`: `values` the first seed's, `reference` the
    /// same-ray reference's, `truth` the converged reference where there is one (each
    /// [`Estimator::channels`] values per point). None by default.
    fn own_metrics(
        &self,
        _values: &[f32],
        _reference: &[f32],
        _truth: Option<&Truth>,
    ) -> Vec<(String, f64)> {
        Vec::new()
    }
}

/// A kind's own options: the keys of `render` beside `what`, `rays_per_point`, `image` and
/// `intra_bias`, as its plug-in read them. Writing them back and copying them come with any
/// `Serialize + Clone` type ([`OptionsBase`]).
pub trait KindOptions: OptionsBase + std::fmt::Debug + Send + Sync {
    /// What serde cannot check, on one profile of `spec` (`render` is `spec.render`), each error
    /// naming the field (`v` names the file).
    fn validate(&self, render: &RenderSpec, spec: &Spec, v: &Validator) -> Result<(), SpecError>;
    /// The kind on `render` (whose `options` are these).
    fn kind(&self, render: &RenderSpec) -> Box<dyn Kind>;
}

/// What every kind's options do alike, given to any `Serialize + Clone` options type.
pub trait OptionsBase {
    /// Its keys as JSON (written back into `spec.json` and `run.json`; [`KindEntry::read`] of
    /// them gives the same options).
    fn to_json(&self) -> serde_json::Map<String, serde_json::Value>;
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn KindOptions>;
}

impl<T: KindOptions + serde::Serialize + Clone + 'static> OptionsBase for T {
    fn to_json(&self) -> serde_json::Map<String, serde_json::Value> {
        match serde_json::to_value(self) {
            Ok(serde_json::Value::Object(m)) => m,
            // Options are structs of plain values: they always write an object.
            other => unreachable!("kind options must serialise as an object, not {other:?}"),
        }
    }

    fn clone_box(&self) -> Box<dyn KindOptions> {
        Box::new(self.clone())
    }
}

/// What a kind's estimator computes, typed, with the options known before any scene: how a
/// method that answers some quantities by its own means (AO fields, SDF cones) decides whether
/// it can answer a kind, and what `run.json` records as its [`Quantity`]. No method or plot
/// reads a kind's name or its estimator's key for this.
#[derive(Clone, Copy, Debug)]
pub enum Answers<'a> {
    /// Ambient occlusion with these options (the AO kinds).
    Ao(&'a ao::AoRender),
    /// The light fraction of spherical lights.
    Shadow,
    /// Glossy reflections.
    Reflection,
    /// Anything else (a kind of a user's own).
    Other,
}

impl Answers<'_> {
    /// Its tag.
    pub fn quantity(&self) -> Quantity {
        match self {
            Answers::Ao(_) => Quantity::Ao,
            Answers::Shadow => Quantity::Shadow,
            Answers::Reflection => Quantity::Reflection,
            Answers::Other => Quantity::Other,
        }
    }

    /// Binary AO (falloff `step`): the AO whose rays a cone's or a cap's occlusion answers.
    pub fn binary_ao(&self) -> bool {
        matches!(self, Answers::Ao(ao) if ao.falloff == crate::render::ao::Falloff::Step)
    }
}

/// A kind in the registry: its name in specs and how its options are read.
#[derive(Clone, Copy)]
pub struct KindEntry {
    /// `render.what`.
    pub name: &'static str,
    /// One line for `experiment --help` and errors.
    pub about: &'static str,
    /// Reads the kind's own keys (a JSON object without the four every kind reads), refusing a
    /// key it does not read.
    pub read: fn(serde_json::Value) -> Result<Box<dyn KindOptions>, serde_json::Error>,
}

/// [`KindEntry::read`] for an options type that serde reads (with `deny_unknown_fields`).
pub fn read_as<T>(v: serde_json::Value) -> Result<Box<dyn KindOptions>, serde_json::Error>
where
    T: serde::de::DeserializeOwned + KindOptions + 'static,
{
    Ok(Box::new(serde_json::from_value::<T>(v)?))
}

/// The kinds of this build, the first being the default `what`.
pub const BUILT_IN: &[KindEntry] = &[
    vertex_ao::ENTRY,
    image_ao::ENTRY,
    shadows::ENTRY,
    reflections::ENTRY,
];

/// The registry: [`BUILT_IN`], then the kinds added at run time by [`register`].
static REGISTRY: Registry<KindEntry> = Registry::new(BUILT_IN, "render kind");

impl Entry for KindEntry {
    fn name(&self) -> &'static str {
        self.name
    }
}

/// Adds a kind to the registry; refused when its name is taken.
pub fn register(entry: KindEntry) -> std::result::Result<(), String> {
    REGISTRY.register(entry)
}

/// The registered kind named `name`.
pub fn lookup(name: &str) -> Option<KindEntry> {
    REGISTRY.lookup(name)
}

/// Every registered kind's name, built-in ones first.
pub fn names() -> Vec<&'static str> {
    REGISTRY.names()
}

/// The options of a spec's `render`, read by its kind's plug-in from the keys it wrote back
/// (a `render` the registry read: its kind is registered and its keys read back).
pub fn options_of(render: &RenderSpec) -> Box<dyn KindOptions> {
    let entry = lookup(render.what)
        .unwrap_or_else(|| panic!("render kind \"{}\" is not registered", render.what));
    (entry.read)(serde_json::Value::Object(render.options.clone())).unwrap_or_else(|e| {
        panic!(
            "render kind \"{}\" does not read back its own options: {e}",
            render.what
        )
    })
}

/// The kind of a spec's `render`.
pub fn of(render: &RenderSpec) -> Box<dyn Kind> {
    options_of(render).kind(render)
}

impl<'de> serde::Deserialize<'de> for RenderSpec {
    /// Two steps: the keys every kind reads, each typed where it stands (so that an error names
    /// its path, `render.rays_per_point`), then the rest by the kind's plug-in, whose options
    /// are written back as the spec's plain JSON.
    fn deserialize<D: serde::Deserializer<'de>>(de: D) -> Result<RenderSpec, D::Error> {
        de.deserialize_map(RenderVisitor)
    }
}

struct RenderVisitor;

impl<'de> serde::de::Visitor<'de> for RenderVisitor {
    type Value = RenderSpec;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a render object: `what`, `rays_per_point` and the kind's keys")
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut m: A) -> Result<RenderSpec, A::Error> {
        use serde::de::Error;
        let (mut what, mut rays, mut image, mut intra_bias) = (None, None, None, None);
        let mut own = serde_json::Map::new();
        while let Some(key) = m.next_key::<String>()? {
            let twice = || A::Error::custom(format!("`{key}` given twice"));
            match key.as_str() {
                "what" if what.is_some() => return Err(twice()),
                "what" => what = Some(m.next_value::<String>()?),
                "rays_per_point" if rays.is_some() => return Err(twice()),
                "rays_per_point" => rays = Some(m.next_value::<u32>()?),
                "image" if image.is_some() => return Err(twice()),
                "image" => image = Some(m.next_value::<Option<ImageSpec>>()?),
                "intra_bias" if intra_bias.is_some() => return Err(twice()),
                "intra_bias" => intra_bias = Some(m.next_value::<Option<f32>>()?),
                _ if own.contains_key(&key) => return Err(twice()),
                _ => {
                    let v = m.next_value::<serde_json::Value>()?;
                    own.insert(key, v);
                }
            }
        }
        let what = what.unwrap_or_else(|| BUILT_IN[0].name.to_string());
        let entry = REGISTRY
            .lookup_for("what", &what)
            .map_err(A::Error::custom)?;
        let rays_per_point = rays.ok_or_else(|| A::Error::missing_field("rays_per_point"))?;
        // Read again by `options_of` from the keys written back here.
        let options = super::registry::read_and_write_back(
            "render",
            entry.name,
            entry.read,
            |o| o.to_json(),
            own,
        )
        .map_err(A::Error::custom)?;
        Ok(RenderSpec {
            what: entry.name,
            rays_per_point,
            image: image.flatten(),
            intra_bias: intra_bias.flatten(),
            options,
        })
    }
}

/// The pixels of an image (none without one): the most points a per-pixel kind can have.
pub fn pixels(image: Option<&ImageSpec>) -> u64 {
    image.map_or(0, |i| i.width as u64 * i.height as u64)
}
