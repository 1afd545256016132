//! Per-scene state of a run: the AO points, the reference tracer, the G-buffer, the reference
//! AO and image, and the ray-cast times.

use super::super::backend::Points;
use super::super::progress::stage;
use super::super::scenes::BuiltScene;
use super::super::spec::{Backend, RenderKind, Spec};
use crate::render::ao::AoOptions;
use crate::render::contact::separate_contacts;
use crate::render::image::{rms_255, rms_vertex, GrayImage};
use crate::render::primary::{gbuffer, shade_vertex_ao, PixelHit, PrimaryScene};
use crate::render::receivers::Receivers;
use crate::render::truth::Truth;
use crate::trace::Tracer;
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// Where AO is evaluated in a scene, and the scene's reference state.
pub(super) struct SceneState {
    pub(super) points: Vec<Vec3>,
    pub(super) normals: Vec<Vec3>,
    /// Vertex AO: the receivers (for shading); image AO: the pixel of each point.
    pub(super) receivers: Option<Receivers>,
    pub(super) pixels: Vec<usize>,
    pub(super) triangles: Vec<[Vec3; 3]>,
    pub(super) tracer: Tracer,
    pub(super) opts: AoOptions,
    pub(super) gbuf: Option<(Vec<Option<PixelHit>>, u32, u32)>,
    pub(super) reference: Vec<f32>,
    pub(super) ref_image: Option<(GrayImage, Vec<bool>)>,
    /// Whether each AO point touches another surface (`render::contact`).
    pub(super) crease: Vec<bool>,
    /// The converged reference.
    pub(super) truth: Option<Truth>,
    /// Where the truth came from (cache file, or computed and how long it took).
    pub(super) truth_source: String,
    /// The same-ray reference on the seeds after the first: AO and image.
    pub(super) seed_refs: Vec<(Vec<f32>, Option<GrayImage>)>,
    /// RMS over points of the same-ray references against the truth, per seed.
    pub(super) reference_vs_truth: Vec<f64>,
    /// Ray-cast AO time per (backend, k).
    pub(super) raycast_s: HashMap<(Backend, u32), f64>,
    /// Ray-cast kernel time from GPU timestamps per (backend, k), where there are any.
    pub(super) raycast_kernel_s: HashMap<(Backend, u32), f64>,
}

impl SceneState {
    pub(super) fn new(spec: &Spec, bs: &BuiltScene) -> SceneState {
        let ((triangles, tracer), _) = stage(&format!("{}: caster BVH", bs.name), || {
            let t = bs.scene.caster_triangles();
            let tracer = Tracer::new(&t);
            (t, tracer)
        });
        let mut opts = AoOptions::for_scene(bs.bounds());
        opts.max_distance = spec.render.max_distance;
        opts.falloff = spec.render.falloff;
        let gbuf = spec.render.image.as_ref().map(|img| {
            let cam = bs.camera_in_frame(
                &img.camera
                    .unwrap_or_else(super::super::quickstart::corner_camera),
            );
            let ps = PrimaryScene::new(&bs.scene);
            let (g, _) = stage(&format!("{}: primary visibility", bs.name), || {
                gbuffer(&ps, &cam, img.width, img.height)
            });
            (g, img.width, img.height)
        });
        let (mut points, mut normals, mut pixels, mut receivers) = (vec![], vec![], vec![], None);
        match (spec.render.what, &gbuf) {
            (RenderKind::ImageAo, Some((g, _, _))) => {
                for (i, h) in g.iter().enumerate() {
                    if let Some(h) = h.filter(|h| bs.scene.instances[h.instance as usize].receiver)
                    {
                        points.push(h.position);
                        normals.push(h.normal);
                        pixels.push(i);
                    }
                }
            }
            _ => {
                let r = Receivers::of(&bs.scene);
                points = r.points.clone();
                normals = r.normals.clone();
                receivers = Some(r);
            }
        }
        // The contact convention: points on another surface are moved in front of it.
        let all: Vec<[Vec3; 3]> = bs
            .scene
            .instances
            .iter()
            .flat_map(|i| i.world_triangles())
            .collect();
        let contacts = separate_contacts(&points, &normals, &all, opts.offset, opts.offset);
        let points = contacts.points;
        SceneState {
            crease: contacts.crease,
            truth: None,
            truth_source: String::new(),
            seed_refs: Vec::new(),
            reference_vs_truth: Vec::new(),
            points,
            normals,
            receivers,
            pixels,
            triangles,
            tracer,
            opts,
            gbuf,
            reference: Vec::new(),
            ref_image: None,
            raycast_s: HashMap::new(),
            raycast_kernel_s: HashMap::new(),
        }
    }

    pub(super) fn at(&self) -> Points<'_> {
        Points {
            points: &self.points,
            normals: &self.normals,
        }
    }

    /// The image showing `ao`, and the mask of AO pixels.
    pub(super) fn image(&self, bs: &BuiltScene, ao: &[f32]) -> Option<(GrayImage, Vec<bool>)> {
        let (g, w, h) = self.gbuf.as_ref()?;
        Some(match &self.receivers {
            Some(r) => shade_vertex_ao(&bs.scene, g, *w, *h, &r.split(&bs.scene, ao)),
            None => {
                let none = vec![None; bs.scene.instances.len()];
                let (mut img, mut mask) = shade_vertex_ao(&bs.scene, g, *w, *h, &none);
                for (j, &px) in self.pixels.iter().enumerate() {
                    img.data[px] = ao[j];
                    mask[px] = true;
                }
                (img, mask)
            }
        })
    }

    /// (RMS per vertex, RMS per pixel) of `ao` against the reference.
    pub(super) fn errors(&self, bs: &BuiltScene, ao: &[f32]) -> (Option<f64>, Option<f64>) {
        let v = self
            .receivers
            .is_some()
            .then(|| rms_vertex(ao, &self.reference));
        let i = match (self.image(bs, ao), &self.ref_image) {
            (Some((img, _)), Some((r, mask))) => Some(rms_255(&img.data, &r.data, Some(mask))),
            _ => None,
        };
        (v, i)
    }
}

/// RMS over points of `ao` against the truth, 0–255: over all points, the crease points and
/// the other points (`None` for an empty subset).
pub(super) struct TruthErrors {
    pub(super) all: f64,
    pub(super) crease: Option<f64>,
    pub(super) interior: Option<f64>,
}

impl SceneState {
    /// [`TruthErrors`] of `ao`, `None` before the truth is known.
    pub(super) fn truth_errors(&self, ao: &[f32]) -> Option<TruthErrors> {
        let t = self.truth.as_ref()?;
        let rms = |want: Option<bool>| {
            let (mut sum, mut n) = (0.0f64, 0usize);
            for (i, (a, b)) in ao.iter().zip(&t.ao).enumerate() {
                if want.is_none_or(|w| self.crease[i] == w) {
                    sum += (255.0 * (*a as f64 - *b as f64)).powi(2);
                    n += 1;
                }
            }
            (n > 0).then(|| (sum / n as f64).sqrt())
        };
        Some(TruthErrors {
            all: rms(None).unwrap_or(0.0),
            crease: rms(Some(true)),
            interior: rms(Some(false)),
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

/// One evaluated cell, kept for the pair table and the per-vertex CSV.
pub(super) struct CellResult {
    pub(super) cell: usize,
    pub(super) ao: Vec<f32>,
    pub(super) image: Option<GrayImage>,
}

pub(super) fn io_err(p: &Path) -> impl Fn(std::io::Error) -> String + '_ {
    move |e| format!("{}: {e}", p.display())
}
