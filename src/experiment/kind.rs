//! Render kinds: what a spec's `render` computes, behind one interface ([`Kind`]) that the
//! planner, the runner, the backends and the row writer work through.
//!
//! A kind declares what it needs of a scene ([`Needs`]: a view with its G-buffer, normal
//! fields, lights), supplies its evaluation points and its [`Estimator`] for a built scene
//! ([`Kind::setup`]), and says which metric columns it fills ([`Columns`]). Everything else
//! (the same-ray reference, the seeds, the converged reference and its cache, the sweeps, the
//! images, the tables) is the runner's, the same for every kind. ARCHITECTURE.md lists the
//! steps that add a kind.

use super::scenes::BuiltScene;
use super::spec::{AoRender, ImageSpec, ReflectionRender, RenderSpec, ShadowRender};
use crate::field::lookup::{IntraBias, LookupOptions};
use crate::field::Selection;
use crate::render::ao::AoOptions;
use crate::render::estimator::{AoEstimator, Estimator};
use crate::render::points::{EvalPoints, GBuffer};
use crate::render::reflect::{Gloss, ReflectOptions, ReflectionEstimator};
use crate::render::shadow::{direct_light, ShadowEstimator, ShadowOptions, SphereLight};
use crate::sampling::rays::RaySet;

/// What a kind needs built before it can run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Needs {
    /// A camera and the G-buffer of its view (the points are pixels).
    pub view: bool,
    /// Normal fields beside the distance fields (reflections).
    pub normal_field: bool,
    /// Light sources (shadows).
    pub lights: bool,
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

/// A render kind.
pub trait Kind: Sync {
    /// The spec's name for it ("vertex_ao").
    fn name(&self) -> &'static str;
    /// What it needs built.
    fn needs(&self) -> Needs;
    /// Which metric columns it fills.
    fn columns(&self) -> Columns;
    /// Rays per evaluation point (k²).
    fn rays_per_point(&self) -> u32;
    /// Rays one evaluation casts per point (k², times the lights for shadows): the count the
    /// tables' rays per second are of.
    fn rays_cast_per_point(&self) -> u64 {
        self.rays_per_point() as u64
    }
    /// The image, when the spec renders one (a view kind always has one).
    fn image(&self) -> Option<&ImageSpec>;
    /// The most evaluation points a scene can have (the plan's ray counts, before any scene
    /// state is built).
    fn max_points(&self, scene: &BuiltScene) -> u64;
    /// Its points and estimator on `scene` (`view`: the G-buffer of the spec's image, when
    /// there is one).
    fn setup(&self, scene: &BuiltScene, view: Option<&GBuffer>) -> Setup;
    /// How fields are read for it, with the cell's map selection.
    fn lookup_options(&self, selection: Selection) -> LookupOptions;
    /// What is wrong with a built scene for this kind, before any work: (the spec field, why).
    fn scene_problem(&self, _scene: &BuiltScene) -> Option<(String, String)> {
        None
    }
    /// The normal field precisions (bits per component) the cells sweep, for a kind that reads
    /// normal fields ([`Needs::normal_field`]); empty for the others.
    fn normal_bits(&self) -> Vec<u32> {
        Vec::new()
    }
}

/// The kind of a spec's `render`.
pub fn of(render: &RenderSpec) -> Box<dyn Kind> {
    match render {
        RenderSpec::VertexAo(a) => Box::new(VertexAo(a.clone())),
        RenderSpec::ImageAo(a) => Box::new(ImageAo(a.clone())),
        RenderSpec::Shadows(r) => Box::new(Shadows(r.clone())),
        RenderSpec::Reflections(r) => Box::new(Reflections(r.clone())),
    }
}

/// The AO estimator of an AO spec: the spec's radius and falloff, and no ray offset of its
/// own (the points are the ray origins, each moved off its surface by its instance's offset:
/// [`EvalPoints::at`]).
fn ao_estimator(a: &AoRender) -> AoEstimator {
    AoEstimator {
        opts: AoOptions {
            max_distance: a.max_distance,
            offset: 0.0,
            falloff: a.falloff,
        },
    }
}

fn lookup(intra_bias: Option<f32>, selection: Selection) -> LookupOptions {
    LookupOptions {
        selection,
        intra_bias: intra_bias
            .map(IntraBias::Fixed)
            .unwrap_or(LookupOptions::default().intra_bias),
    }
}

/// The pixels of an image (none without one): the most points a per-pixel kind can have.
fn pixels(image: Option<&ImageSpec>) -> u64 {
    image.map_or(0, |i| i.width as u64 * i.height as u64)
}

/// Vertex AO (Gaitatzes, Chrysanthou, Papaioannou, WSCG 2008): AO at the receivers' vertices,
/// shown Gouraud-interpolated in the image.
pub struct VertexAo(pub AoRender);

impl Kind for VertexAo {
    fn name(&self) -> &'static str {
        "vertex_ao"
    }

    fn needs(&self) -> Needs {
        Needs::default()
    }

    fn columns(&self) -> Columns {
        Columns { vertex: true }
    }

    fn rays_per_point(&self) -> u32 {
        self.0.rays_per_point
    }

    fn image(&self) -> Option<&ImageSpec> {
        self.0.image.as_ref()
    }

    fn max_points(&self, scene: &BuiltScene) -> u64 {
        scene.receiver_vertices() as u64
    }

    fn setup(&self, scene: &BuiltScene, _view: Option<&GBuffer>) -> Setup {
        let points = EvalPoints::vertices(&scene.scene);
        Setup {
            offset: points.max_offset(),
            points,
            estimator: Box::new(ao_estimator(&self.0)),
            shading: None,
            second_reference: None,
        }
    }

    fn lookup_options(&self, selection: Selection) -> LookupOptions {
        lookup(self.0.intra_bias, selection)
    }
}

/// Per-pixel AO (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010): AO at the surface
/// point of every pixel that sees a receiver.
pub struct ImageAo(pub AoRender);

impl Kind for ImageAo {
    fn name(&self) -> &'static str {
        "image_ao"
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

    fn rays_per_point(&self) -> u32 {
        self.0.rays_per_point
    }

    fn image(&self) -> Option<&ImageSpec> {
        self.0.image.as_ref()
    }

    fn max_points(&self, _scene: &BuiltScene) -> u64 {
        pixels(self.0.image.as_ref())
    }

    fn setup(&self, scene: &BuiltScene, view: Option<&GBuffer>) -> Setup {
        let view = view.expect("image_ao: validation guarantees an image, and so a G-buffer");
        let points = EvalPoints::pixels(&scene.scene, view);
        Setup {
            offset: points.max_offset(),
            points,
            estimator: Box::new(ao_estimator(&self.0)),
            shading: None,
            second_reference: None,
        }
    }

    fn lookup_options(&self, selection: Selection) -> LookupOptions {
        lookup(self.0.intra_bias, selection)
    }
}

/// Soft shadows from spherical lights per pixel (Gaitatzes, Andreadis, Papaioannou,
/// Chrysanthou, WSCG 2010, §4.2, Figures 7–8): the light fraction of `render::shadow` at every
/// receiver pixel, its shadow rays answered by ray casting or by the fields.
pub struct Shadows(pub ShadowRender);

/// Lights in the scene's frame (moved as the camera is).
fn lights_in_frame(lights: &[SphereLight], scene: &BuiltScene) -> Vec<SphereLight> {
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
        "shadows"
    }

    fn needs(&self) -> Needs {
        Needs {
            view: true,
            lights: true,
            ..Needs::default()
        }
    }

    fn columns(&self) -> Columns {
        Columns { vertex: false }
    }

    fn rays_per_point(&self) -> u32 {
        self.0.rays_per_point
    }

    fn rays_cast_per_point(&self) -> u64 {
        // A point light (radius 0) casts one ray per point, a sphere light k².
        let k2 = self.0.rays_per_point as u64;
        self.0
            .lights
            .iter()
            .map(|l| if l.radius == 0.0 { 1 } else { k2 })
            .sum()
    }

    fn image(&self) -> Option<&ImageSpec> {
        self.0.image.as_ref()
    }

    fn max_points(&self, _scene: &BuiltScene) -> u64 {
        pixels(self.0.image.as_ref())
    }

    fn setup(&self, scene: &BuiltScene, view: Option<&GBuffer>) -> Setup {
        let view = view.expect("shadows: validation guarantees an image, and so a G-buffer");
        let lights = lights_in_frame(&self.0.lights, scene);
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
            estimator: Box::new(ShadowEstimator { opts }),
            shading: Some(shading),
            second_reference: None,
        }
    }

    fn lookup_options(&self, selection: Selection) -> LookupOptions {
        lookup(self.0.intra_bias, selection)
    }

    /// A light that overlaps a caster's bounding sphere would sit inside the field's domain
    /// (and likely inside the caster): refused, naming the light and the instance.
    fn scene_problem(&self, scene: &BuiltScene) -> Option<(String, String)> {
        for (i, l) in lights_in_frame(&self.0.lights, scene).iter().enumerate() {
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

/// Glossy reflections per pixel (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010,
/// §4.2, Figure 9): the reflected radiance of `render::reflect` at every receiver pixel, its
/// reflection rays answered with a hit point and normal by ray casting or by the distance and
/// normal fields; the cells sweep the normal fields' precision, and a glossy lobe is also
/// measured against the perfect mirror (`second_reference`).
pub struct Reflections(pub ReflectionRender);

impl Reflections {
    fn options(&self, scene: &BuiltScene) -> ReflectOptions {
        let r = &self.0;
        let image = r.image.as_ref().expect("validation guarantees an image");
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
        "reflections"
    }

    fn needs(&self) -> Needs {
        Needs {
            view: true,
            normal_field: true,
            lights: true,
        }
    }

    fn columns(&self) -> Columns {
        Columns { vertex: false }
    }

    fn rays_per_point(&self) -> u32 {
        self.0.rays_per_point
    }

    /// A mirror casts one ray per point whatever `rays_per_point` says.
    fn rays_cast_per_point(&self) -> u64 {
        match self.0.gloss {
            Gloss::Mirror => 1,
            Gloss::Phong { .. } => self.0.rays_per_point as u64,
        }
    }

    fn image(&self) -> Option<&ImageSpec> {
        self.0.image.as_ref()
    }

    fn max_points(&self, _scene: &BuiltScene) -> u64 {
        pixels(self.0.image.as_ref())
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
            estimator: Box::new(ReflectionEstimator { opts }),
            shading: None,
            second_reference,
        }
    }

    fn lookup_options(&self, selection: Selection) -> LookupOptions {
        lookup(self.0.intra_bias, selection)
    }

    fn normal_bits(&self) -> Vec<u32> {
        self.0.normal_bits.clone()
    }
}
