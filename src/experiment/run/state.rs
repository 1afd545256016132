//! Per-scene state of a run: the render kind's points and estimator, the reference tracer, the
//! G-buffer, the same-ray reference and its image, and the ray-cast times.

use super::super::kinds::Kind;
use super::super::progress::stage;
use super::super::scenes::BuiltScene;
use super::super::spec::Backend;
use crate::experiment::backend::Quantity;
use crate::experiment::backend_gpu::GpuQuantity;
use crate::experiment::metrics::{rms_u8, rms_unquantised, rms_unquantised_where};
use crate::render::estimator::{Estimator, Points};
use crate::render::image::{Image, ImageChannels};
use crate::render::points::{EvalPoints, GBuffer};
use crate::render::primary::{gbuffer, PrimaryScene};
use crate::render::truth::Truth;
use crate::trace::Tracer;
use glam::Vec3;
use std::collections::HashMap;

/// Where a scene's render kind is evaluated, and the scene's reference state.
pub(super) struct SceneState {
    /// The kind's evaluation points.
    pub(super) at: EvalPoints,
    /// The kind's estimator on this scene.
    pub(super) estimator: Box<dyn Estimator>,
    /// Its values per point ([`Estimator::channels`]); every value vector below has this many
    /// per point, point-major.
    pub(super) channels: usize,
    /// How they show as an image ([`crate::experiment::kinds::Kind::image_channels`]).
    pub(super) show: ImageChannels,
    /// Its GPU kernels ([`crate::experiment::kinds::Setup::gpu`]).
    pub(super) gpu: Option<Box<dyn GpuQuantity>>,
    /// The ray offset (model units).
    pub(super) offset: f32,
    /// The kind's shading factor per point ([`crate::experiment::kinds::Setup::shading`]).
    pub(super) shading: Option<Vec<f32>>,
    /// The kind's second reference ([`crate::experiment::kinds::Setup::second_reference`]) and
    /// its image on the first seed's rays, once the reference step has made it.
    pub(super) second: Option<(&'static str, Box<dyn Estimator>)>,
    pub(super) second_image: Option<Image>,
    pub(super) triangles: Vec<[Vec3; 3]>,
    pub(super) tracer: Tracer,
    /// The G-buffer of the spec's image.
    pub(super) view: Option<GBuffer>,
    pub(super) reference: Vec<f32>,
    pub(super) ref_image: Option<(Image, Vec<bool>)>,
    /// The same-ray reference's shaded picture ([`Self::shaded_image`]), where the kind has one.
    pub(super) ref_shaded: Option<Image>,
    /// The converged reference.
    pub(super) truth: Option<Truth>,
    /// The converged reference's image (the FLIP columns `flip_*_vs_truth` compare with it).
    pub(super) truth_image: Option<Image>,
    /// Where the truth came from (cache file, or computed and how long it took).
    pub(super) truth_source: String,
    /// The same-ray reference on the seeds after the first: values, image and shaded picture.
    pub(super) seed_refs: Vec<(Vec<f32>, Option<Image>, Option<Image>)>,
    /// RMS over points of the same-ray references against the truth, per seed.
    pub(super) reference_vs_truth: Vec<f64>,
    /// Ray-cast time per (backend, k).
    pub(super) raycast_s: HashMap<(Backend, u32), f64>,
    /// Ray-cast kernel time from GPU timestamps per (backend, k), where there are any.
    pub(super) raycast_kernel_s: HashMap<(Backend, u32), f64>,
    /// Per evaluation point: whether it lies inside some caster's world bounding sphere (where
    /// a field's lookup starts inside the sphere: the intra-object test for the caster's own
    /// points, the sphere-cutting case for a receiver's).
    pub(super) in_spheres: Vec<bool>,
}

impl SceneState {
    pub(super) fn new(kind: &dyn Kind, bs: &BuiltScene) -> SceneState {
        let ((triangles, tracer), _) = stage(&format!("{}: caster BVH", bs.name), || {
            let t = bs.scene.caster_triangles();
            let tracer = Tracer::new(&t);
            (t, tracer)
        });
        let view = kind.image().map(|img| {
            let cam = bs.view_camera(img);
            let ps = PrimaryScene::new(&bs.scene);
            let (hits, _) = stage(&format!("{}: primary visibility", bs.name), || {
                gbuffer(&ps, &cam, img.width, img.height)
            });
            GBuffer {
                hits,
                width: img.width,
                height: img.height,
            }
        });
        let setup = kind.setup(bs, view.as_ref());
        let channels = setup.estimator.channels();
        let show = kind.image_channels(channels);
        let show = match (show, &view) {
            (Some(s), _) => s,
            // No image is made: the map is never read.
            (None, None) => ImageChannels::Gray(0),
            (None, Some(_)) => panic!(
                "render kind \"{}\": {channels} channels per point and no image of them \
                 (Kind::image_channels)",
                kind.name()
            ),
        };
        if let Some((name, e)) = &setup.second_reference {
            assert_eq!(
                e.channels(),
                channels,
                "render kind \"{}\": its second reference \"{name}\" has other channels",
                kind.name()
            );
        }
        let spheres: Vec<crate::geometry::Sphere> = bs
            .scene
            .casters()
            .map(|(_, inst)| inst.world_bounding_sphere())
            .collect();
        let in_spheres = setup
            .points
            .points
            .iter()
            .map(|&p| spheres.iter().any(|s| p.distance(s.center) < s.radius))
            .collect();
        SceneState {
            at: setup.points,
            estimator: setup.estimator,
            channels,
            show,
            gpu: setup.gpu,
            offset: setup.offset,
            shading: setup.shading,
            second: setup.second_reference,
            second_image: None,
            truth: None,
            truth_image: None,
            truth_source: String::new(),
            seed_refs: Vec::new(),
            reference_vs_truth: Vec::new(),
            triangles,
            tracer,
            view,
            reference: Vec::new(),
            ref_image: None,
            ref_shaded: None,
            raycast_s: HashMap::new(),
            raycast_kernel_s: HashMap::new(),
            in_spheres,
        }
    }

    /// The kind's quantity: its estimator and GPU kernels.
    pub(super) fn quantity(&self) -> Quantity<'_> {
        Quantity {
            estimator: self.estimator.as_ref(),
            gpu: self.gpu.as_deref(),
        }
    }

    /// The evaluation points.
    pub(super) fn at(&self) -> Points<'_> {
        self.at.at()
    }

    /// The image showing `values`, and the mask of the pixels that show them.
    pub(super) fn image(&self, bs: &BuiltScene, values: &[f32]) -> Option<(Image, Vec<bool>)> {
        let view = self.view.as_ref()?;
        Some(
            self.at
                .values_image(&bs.scene, view, values, self.channels, self.show),
        )
    }

    /// The share of the window's active pixels (those that see a surface) that show values:
    /// the evaluated pixels over the active ones; none without an image.
    pub(super) fn window_share(&self) -> Option<f64> {
        let view = self.view.as_ref()?;
        let (_, mask) = self.ref_image.as_ref()?;
        let active = view.hits.iter().filter(|h| h.is_some()).count();
        let shown = mask.iter().filter(|&&m| m).count();
        (active > 0).then(|| shown as f64 / active as f64)
    }

    /// The shaded picture of `values` (each channel × the point's shading factor), where the
    /// kind has one and there is an image.
    pub(super) fn shaded_image(&self, bs: &BuiltScene, values: &[f32]) -> Option<Image> {
        let f = self.shading.as_ref()?;
        let c = self.channels;
        let shaded: Vec<f32> = values
            .iter()
            .enumerate()
            .map(|(i, v)| v * f[i / c])
            .collect();
        self.image(bs, &shaded).map(|(img, _)| img)
    }

    /// The point value `i` belongs to ([`Self::channels`] values per point): the index into
    /// the per-point flags (`crease`, `in_spheres`).
    pub(super) fn point_of(&self, i: usize) -> usize {
        i / self.channels
    }

    /// (RMS per vertex, RMS per pixel) of `values` against the same-ray reference: the
    /// per-vertex column where the kind has one, the per-pixel one where there is an image.
    pub(super) fn errors(
        &self,
        kind: &dyn Kind,
        bs: &BuiltScene,
        values: &[f32],
    ) -> (Option<f64>, Option<f64>) {
        let v = kind
            .columns()
            .vertex
            .then(|| rms_unquantised(values, &self.reference));
        let i = match (self.image(bs, values), &self.ref_image) {
            (Some((img, _)), Some((r, mask))) => Some(rms_u8(&img.data, &r.data, Some(mask))),
            _ => None,
        };
        (v, i)
    }
}

/// RMS over points (and their channels) of the values against the truth, 0–255, unquantised:
/// over all points (NaN when there are none), the crease points and the other points (`None`
/// for an empty subset).
pub(super) struct TruthErrors {
    pub(super) all: f64,
    pub(super) crease: Option<f64>,
    pub(super) interior: Option<f64>,
    /// Over the points inside some caster's bounding sphere, and over the others.
    pub(super) in_spheres: Option<f64>,
    pub(super) outside_spheres: Option<f64>,
}

impl SceneState {
    /// [`TruthErrors`] of `values`, `None` before the truth is known.
    pub(super) fn truth_errors(&self, values: &[f32]) -> Option<TruthErrors> {
        let t = self.truth.as_ref()?;
        let part = |mask: &[bool], want: bool| {
            let e = rms_unquantised_where(values, &t.values, |i| mask[self.point_of(i)] == want);
            (!e.is_nan()).then_some(e)
        };
        Some(TruthErrors {
            all: rms_unquantised(values, &t.values),
            crease: part(&self.at.crease, true),
            interior: part(&self.at.crease, false),
            in_spheres: part(&self.in_spheres, true),
            outside_spheres: part(&self.in_spheres, false),
        })
    }
}

/// Mean and sample standard deviation (`None` for one value).
pub(super) fn mean_sd(v: &[f64]) -> (f64, Option<f64>) {
    let n = v.len().max(1) as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = (v.len() > 1)
        .then(|| (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt());
    (mean, sd)
}

/// One evaluated cell, kept for the pair table and the per-point CSV.
pub(super) struct CellResult {
    pub(super) cell: usize,
    pub(super) values: Vec<f32>,
    pub(super) image: Option<Image>,
}
