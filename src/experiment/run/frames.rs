//! The runner of an animated spec ([`crate::experiment::spec::Spec::animation`]): every scene
//! at every frame, its instances moved along their motions ([`crate::geometry::motion`]), the
//! render kind evaluated at that frame's points (its `setup` on the frame's scene: receiver
//! vertices, or the receiver pixels of the frame's G-buffer from the fixed camera) by every
//! per-frame method (the forms of [`crate::experiment::methods::motion::frame_forms`], each
//! built by its method) on the same seeded rays (the first seed's), each charged for the
//! frame's motion (`update_s`: a BVH rebuilt, a top level rebuilt, a scene committed, an
//! instance list) apart from the query (`query_s`).
//!
//! Per frame and method a row of `frames.csv` ([`FrameRow`], its view
//! [`crate::experiment::frame_row::FRAMES_CSV`]): the errors against the world
//! rebuild's ray cast on the same rays (`rms_vs_raycast`) and against the frame's converged
//! reference (`rms_vs_truth`, cached by frame: its key covers the frame's points and world
//! triangles), and the frame's overlap counts (caster pairs whose bounding spheres overlap,
//! points inside another caster's sphere), where the papers' non-penetrating assumption stops
//! holding. The ray casters are measured once per frame; the field methods once per field cell
//! of the spec's `fields`, each cell's fields (one per caster mesh, shared by its instances)
//! supplied once, before the frames. With the "gpu" backend, the GPU forms beside the CPU ones
//! asked for run too ([`motion::gpu_twins`], built by their methods: the GPU tracer's world BVH
//! rebuilt and uploaded each frame; the two levels' top level; hardware ray queries with their
//! TLAS rebuilt each frame, skipped with the reason on an adapter without them; each "gpu"
//! field cell's fields uploaded once and its instances moved on the device each frame).
//! `super::frames_write` writes the outputs.

use super::{LoadedSpec, RunOptions};
use crate::experiment::backend::ComputeBackend;
use crate::experiment::dynamic::animation::Frame;
use crate::experiment::flip;
use crate::experiment::kinds::Kind;
use crate::experiment::methods::field::MeshFields;
use crate::experiment::methods::motion::{self, FrameCasters, GpuInputs, Mover, MoverInputs};
use crate::experiment::metrics::{self, rms_unquantised};
use crate::experiment::plan::cells_of;
use crate::experiment::scenes::{BuiltScene, Scenes};
use crate::experiment::spec::{exact_sqrt, Backend, Spec, FRAME_METHODS};
use crate::experiment::truth_cache::{load_or_compute, TruthInputs};
use crate::experiment::{Error, Result};
use crate::geometry::{Mesh, Similarity, Sphere};
use crate::render::image::Image;
use crate::render::points::{EvalPoints, GBuffer, Support};
use crate::render::primary::{gbuffer, PrimaryScene};
use crate::render::truth::TruthOptions;
use crate::sampling::rays::RaySet;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

pub use crate::experiment::frame_row::FrameRow;

/// What the flicker and FLIP columns of one frame read of an answer (a method's, or the
/// converged reference's).
struct Signal {
    /// The image's values (with an image: `channels` per pixel) or the points' values.
    values: Vec<f32>,
    /// Per pixel (point): the instance it shows a value on, none where it shows none.
    shown: Vec<Option<usize>>,
    image: Option<Image>,
}

impl Signal {
    /// The pixels (points) that show a value in both frames, on the same instance: what the
    /// flicker is over. None where the frames' sizes differ.
    fn kept(&self, prev: &Signal) -> Option<Vec<bool>> {
        (self.shown.len() == prev.shown.len() && self.values.len() == prev.values.len()).then(
            || {
                (self.shown.iter().zip(&prev.shown))
                    .map(|(a, b)| a.is_some() && a == b)
                    .collect()
            },
        )
    }

    /// The mask of the pixels that show a value.
    fn mask(&self) -> Vec<bool> {
        self.shown.iter().map(Option::is_some).collect()
    }
}

/// The flicker between `prev` and `next` against the reference's frames, the pixels it is
/// over, and the mean FLIP of the frame change: none where no pixel is kept.
fn frame_change(
    prev: &Signal,
    next: &Signal,
    truth_prev: &Signal,
    truth_next: &Signal,
) -> Option<(f64, usize, Option<f64>)> {
    let keep = next.kept(prev)?;
    let truth_keep = truth_next.kept(truth_prev)?;
    let keep: Vec<bool> = keep
        .iter()
        .zip(&truth_keep)
        .map(|(a, b)| *a && *b)
        .collect();
    let n = keep.iter().filter(|&&k| k).count();
    if n == 0 || truth_prev.values.len() != prev.values.len() {
        return None;
    }
    let f = metrics::flicker(
        &prev.values,
        &next.values,
        &truth_prev.values,
        &truth_next.values,
        &keep,
    );
    let flip = flip::compare(prev.image.as_ref(), next.image.as_ref(), Some(&keep));
    Some((f, n, flip.map(|(s, _)| s.mean)))
}

/// What an animated run produced, for [`super::frames_write`].
pub(super) struct FramesRun {
    pub(super) rows: Vec<FrameRow>,
    /// Per scene with an image: its name, the image's size and the frames of its animation
    /// (the reference and the first field method).
    pub(super) pictures: Vec<(String, (usize, usize), Vec<Frame>)>,
    /// The methods run, and those this build skipped with the reason.
    pub(super) methods: Vec<&'static str>,
    pub(super) skipped: Vec<Skipped>,
    /// Per scene: seconds of the ray casters' per-mesh precompute and of the fields' supply.
    pub(super) precompute: Vec<serde_json::Value>,
}

/// A method this run skips, and why.
type Skipped = (&'static str, String);

/// The per-frame methods the spec asks for (`animation.methods`, default every one) that this
/// build runs, and the ones it skips with the reason (`--require-embree` fails instead).
fn methods(spec: &Spec, opts: &RunOptions) -> Result<(Vec<&'static str>, Vec<Skipped>)> {
    let asked = spec.animation.as_ref().and_then(|a| a.methods.as_ref());
    let (mut run, mut skipped) = (Vec::new(), Vec::new());
    for name in FRAME_METHODS {
        if name != "world_rebuild" && asked.is_some_and(|m| !m.iter().any(|m| m == name)) {
            continue;
        }
        match motion::form(name).and_then(|(_, m)| m.frame_unavailable()) {
            Some(why) if opts.require_embree => {
                return Err(Error::invalid(format!("animation method {name}"), why))
            }
            Some(why) => {
                eprintln!("SKIPPED per-frame method {name}: {why}");
                skipped.push((name, why.to_string()));
            }
            None => run.push(name),
        }
    }
    Ok((run, skipped))
}

/// Runs every scene of the animated `spec` frame by frame (outputs left to
/// [`super::frames_write`]).
pub(super) fn run(
    ls: &LoadedSpec,
    spec: &Spec,
    scenes: &Scenes,
    opts: &RunOptions,
) -> Result<FramesRun> {
    let anim = spec
        .animation
        .as_ref()
        .expect("an animated spec has its animation");
    let k = exact_sqrt(spec.render.rays_per_point)
        .ok_or_else(|| Error::invalid("render.rays_per_point", "not a perfect square"))?;
    let (mut names, mut skipped) = methods(spec, opts)?;
    let kind = crate::experiment::kinds::of(&spec.render);
    let gpu = if spec.backends.contains(&Backend::Gpu) {
        let be = crate::experiment::backend_gpu::open(Backend::Gpu, &opts.adapter)?;
        let ctx = be.gpu_context().expect("the gpu backend has a device");
        // The GPU twins of the CPU methods asked for, where the device runs their methods.
        for (cpu, twin) in motion::gpu_twins(&FRAME_METHODS) {
            if !names.contains(&cpu) {
                continue;
            }
            match motion::form(twin).and_then(|(_, m)| m.unavailable_on_gpu(ctx)) {
                Some(why) => {
                    eprintln!("SKIPPED per-frame method {twin}: {why}");
                    skipped.push((twin, why));
                }
                None => names.push(twin),
            }
        }
        Some(be)
    } else {
        None
    };
    let runner = SceneRunner {
        spec,
        opts,
        gpu: gpu.as_deref(),
        kind: kind.as_ref(),
        rays: RaySet::new(k, spec.reference.seed),
        names: &names,
        truth: super::references::truth_options(spec),
        dt: anim.time_step,
    };
    let mut out = FramesRun {
        rows: Vec::new(),
        pictures: Vec::new(),
        methods: names.clone(),
        skipped,
        precompute: Vec::new(),
    };
    for (s, bs) in scenes.scenes.iter().enumerate() {
        runner
            .scene(scenes, s, bs, &mut out)
            .map_err(|e| e.context(format!("{}: scene {}", ls.path.display(), bs.name)))?;
    }
    Ok(out)
}

/// What every scene of a run shares.
struct SceneRunner<'a> {
    spec: &'a Spec,
    opts: &'a RunOptions,
    /// The GPU backend, where the spec asks for it (its methods' GPU forms).
    gpu: Option<&'a dyn ComputeBackend>,
    kind: &'a dyn Kind,
    rays: RaySet,
    names: &'a [&'static str],
    truth: TruthOptions,
    dt: f64,
}

/// A field cell's CPU methods on one scene, and its fields (per caster mesh, with its normal
/// field where the kind reads them), which they and the GPU's read.
struct CellMovers {
    id: String,
    /// A "gpu" cell: its methods are the GPU's, `movers` empty.
    gpu: bool,
    movers: Vec<Box<dyn Mover>>,
    fields: MeshFields,
}

/// The instance each point lies on (vertices: their receiver's; pixels: the G-buffer hit's).
fn point_owners(at: &EvalPoints, view: Option<&GBuffer>) -> Vec<Option<usize>> {
    match &at.support {
        Support::Vertices(r) => {
            let mut owners = vec![None; at.len()];
            for &(inst, start, count) in &r.ranges {
                owners[start..start + count].fill(Some(inst));
            }
            owners
        }
        Support::Pixels(pixels) => pixels
            .iter()
            .map(|&px| view.and_then(|v| v.hits[px]).map(|h| h.instance as usize))
            .collect(),
    }
}

impl SceneRunner<'_> {
    /// The G-buffer of the spec's image on the scene at one frame (the camera fixed).
    fn view(&self, fbs: &BuiltScene) -> Option<GBuffer> {
        let img = self.kind.image()?;
        let cam = fbs.view_camera(img);
        Some(GBuffer {
            hits: gbuffer(&PrimaryScene::new(&fbs.scene), &cam, img.width, img.height),
            width: img.width,
            height: img.height,
        })
    }

    /// Every frame of scene `s`, every method.
    fn scene(&self, scenes: &Scenes, s: usize, bs: &BuiltScene, out: &mut FramesRun) -> Result<()> {
        let global = bs.caster_meshes();
        let meshes: Vec<Arc<Mesh>> = global
            .iter()
            .map(|&m| scenes.meshes[m].mesh.clone())
            .collect();
        let local = |m: usize| global.iter().position(|&g| g == m).expect("a caster mesh");
        let model_spheres: Vec<Sphere> = bs
            .scene
            .instances
            .iter()
            .map(|i| i.mesh.bounding_sphere())
            .collect();
        let t = Instant::now();
        let on = MoverInputs {
            meshes: &meshes,
            cache: self.opts.supply.cache.as_deref(),
            fields: None,
        };
        let mut casters = motion::movers(self.names, &on)?;
        let raycast_precompute_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut cells = self.cells(scenes, s, bs, &global)?;
        for c in cells.iter_mut().filter(|c| !c.gpu) {
            let on = MoverInputs {
                fields: Some(&c.fields),
                ..on
            };
            c.movers = motion::movers(self.names, &on)?;
        }
        let fields_s = t.elapsed().as_secs_f64();
        let frame_instances = |fbs: &BuiltScene| -> Vec<(usize, Similarity)> {
            (fbs.scene.casters())
                .map(|(i, inst)| (local(bs.mesh_of[i]), inst.transform))
                .collect()
        };
        // The GPU forms: the kind's kernels as the first frame sets them up (their options;
        // rigid motion changes none), each built by its method, placed as in the first frame.
        let first = bs.at_frame(0);
        let first_setup = (self.gpu).map(|_| self.kind.setup(&first, self.view(&first).as_ref()));
        let first_instances = frame_instances(&first);
        let t = Instant::now();
        let mut gpu_casters: Vec<Box<dyn Mover + '_>> = Vec::new();
        let mut gpu_cells: Vec<Vec<Box<dyn Mover + '_>>> = Vec::new();
        if let (Some(be), Some(setup)) = (self.gpu, &first_setup) {
            let Some(kernels) = setup.gpu.as_deref() else {
                return Err(Error::invalid(
                    "backends",
                    format!("no GPU kernel computes \"{}\"", self.kind.name()),
                ));
            };
            let gpu = GpuInputs {
                ctx: be.gpu_context().expect("the gpu backend has a device"),
                kernels,
                first: &first_instances,
            };
            // Each cell's forms, the scene's first; a form this scene cannot run is skipped.
            let mut built = |on: &MoverInputs| -> Result<Vec<Box<dyn Mover + '_>>> {
                let mut v = Vec::new();
                for (name, mover) in motion::gpu_movers(self.names, on, &gpu)? {
                    match mover {
                        Ok(m) => v.push(m),
                        Err(why) => {
                            eprintln!(
                                "SKIPPED per-frame method {name} on scene {}: {why}",
                                bs.name
                            );
                            out.methods.retain(|&m| m != name);
                            if !out.skipped.iter().any(|s| s.0 == name) {
                                out.skipped
                                    .push((name, format!("scene {}: {why}", bs.name)));
                            }
                        }
                    }
                }
                Ok(v)
            };
            gpu_casters = built(&on)?;
            for c in &cells {
                let on = MoverInputs {
                    fields: Some(&c.fields),
                    ..on
                };
                gpu_cells.push(if c.gpu { built(&on)? } else { Vec::new() });
            }
        }
        out.precompute.push(serde_json::json!({
            "scene": bs.name,
            "ray_casters_s": raycast_precompute_s,
            "fields_s": fields_s,
            "gpu_fields_s": self.gpu.map(|_| t.elapsed().as_secs_f64()),
            "gpu_adapter": self.gpu.map(|be| be.adapter()),
        }));
        let mut pictures = Vec::new();
        let tris = bs.caster_triangles();
        // The previous frame's signals per (method, cell), and the converged reference's.
        let mut prev: HashMap<(String, String), Signal> = HashMap::new();
        let mut prev_truth: Option<Signal> = None;
        for f in 0..bs.frame_count() {
            let fbs = bs.at_frame(f);
            let t = Instant::now();
            let view = self.view(&fbs);
            let setup = self.kind.setup(&fbs, view.as_ref());
            let points_s = t.elapsed().as_secs_f64();
            if setup.points.is_empty() {
                return Err(Error::invalid(
                    format!("scene {} frame {f}", bs.name),
                    format!(
                        "no point to evaluate: {} has nothing there",
                        self.kind.name()
                    ),
                ));
            }
            let instances = frame_instances(&fbs);
            let spheres: Vec<(usize, Sphere)> = fbs
                .scene
                .casters()
                .map(|(i, inst)| (i, inst.transform.to_world_sphere(&model_spheres[i])))
                .collect();
            let owners = point_owners(&setup.points, view.as_ref());
            let (sphere_overlaps, points_in_spheres) =
                motion::overlaps(&spheres, &setup.points.points, |j| owners[j]);
            let frame = FrameCasters {
                meshes: &meshes,
                instances: &instances,
            };
            let at = setup.points.at();
            let est = setup.estimator.as_ref();
            let query = |m: &dyn Mover| m.estimate(est, at, &self.rays);
            // The ray casters, the world rebuild first: the frame's reference and the tracer
            // of its converged reference.
            let mut measured: Vec<(&'static str, String, motion::Timed, Option<u64>)> = Vec::new();
            let mut truth = None;
            for m in casters.iter_mut() {
                let r = motion::timed(m.as_mut(), &frame, query)?;
                if truth.is_none() {
                    let world = frame.world_triangles();
                    let inputs = TruthInputs {
                        estimator: est,
                        tracer: m.vis(),
                        casters: &world,
                        at,
                    };
                    let name = format!("{}-f{f}", bs.name);
                    let cache = self.opts.supply.cache.as_deref();
                    truth = Some(load_or_compute(cache, &name, &inputs, &self.truth)?.0);
                }
                measured.push((m.name(), String::new(), r, m.bytes()));
            }
            for m in gpu_casters.iter_mut() {
                let r = motion::timed(m.as_mut(), &frame, query)?;
                measured.push((m.name(), String::new(), r, m.bytes()));
            }
            for c in cells.iter_mut() {
                for m in c.movers.iter_mut() {
                    let r = motion::timed(m.as_mut(), &frame, query)?;
                    measured.push((m.name(), c.id.clone(), r, m.bytes()));
                }
            }
            for (c, gpu) in cells.iter().zip(gpu_cells.iter_mut()) {
                for m in gpu.iter_mut() {
                    let r = motion::timed(m.as_mut(), &frame, query)?;
                    measured.push((m.name(), c.id.clone(), r, m.bytes()));
                }
            }
            let truth = truth.expect("the world rebuild runs first");
            let reference = measured[0].2.values.clone();
            // The flicker and FLIP columns (untimed): each answer's image, or its values.
            let channels = est.channels();
            let show = view
                .as_ref()
                .and_then(|_| self.kind.image_channels(channels));
            let signal = |values: &[f32]| -> Signal {
                match (&view, show) {
                    (Some(v), Some(show)) => {
                        let (img, mask) =
                            (setup.points).values_image(&fbs.scene, v, values, channels, show);
                        let shown = (mask.iter().zip(&v.hits))
                            .map(|(&m, h)| h.filter(|_| m).map(|h| h.instance as usize))
                            .collect();
                        Signal {
                            values: img.data.clone(),
                            shown,
                            image: Some(img),
                        }
                    }
                    _ => Signal {
                        values: values.to_vec(),
                        shown: owners
                            .iter()
                            .map(|o| Some(o.unwrap_or(usize::MAX)))
                            .collect(),
                        image: None,
                    },
                }
            };
            let truth_now = signal(&truth.values);
            let reference_now = signal(&reference);
            let key = |method: &str, cell: &str| (method.to_string(), cell.to_string());
            let change = |p: Option<&Signal>, now: &Signal| match (p, &prev_truth) {
                (Some(p), Some(pt)) => frame_change(p, now, pt, &truth_now),
                _ => None,
            };
            let raycast_change = change(prev.get(&key(measured[0].0, "")), &reference_now);
            let truth_flip_change = (prev_truth.as_ref())
                .and_then(|pt| truth_now.kept(pt).map(|keep| (pt, keep)))
                .and_then(|(pt, keep)| {
                    flip::compare(pt.image.as_ref(), truth_now.image.as_ref(), Some(&keep))
                })
                .map(|(s, _)| s.mean);
            let rays = setup.points.len() as u64 * self.kind.rays_cast_per_point();
            let mut line = format!(
                "{} frame {f}: {} points, overlaps {sphere_overlaps}/{points_in_spheres};",
                bs.name,
                setup.points.len()
            );
            // Each method's image and FLIP figures, the methods in parallel (FLIP's C++ runs
            // on one thread).
            let figures: Vec<_> = (measured.par_iter())
                .map(|(method, cell, r, _)| {
                    let sig = signal(&r.values);
                    let mask = sig.mask();
                    let vs = |other: &Signal| {
                        flip::compare(other.image.as_ref(), sig.image.as_ref(), Some(&mask))
                            .map(|(s, _)| s)
                    };
                    let (vs_raycast, vs_truth) = (vs(&reference_now), vs(&truth_now));
                    let k = key(method, cell);
                    let moved = change(prev.get(&k), &sig);
                    (k, sig, vs_raycast, vs_truth, moved)
                })
                .collect();
            let mut now: Vec<((String, String), Signal)> = Vec::new();
            for ((method, cell, r, bytes), (k, sig, vs_raycast, vs_truth, moved)) in
                measured.iter().zip(figures)
            {
                let rms = rms_unquantised(&r.values, &reference);
                line.push_str(&format!(
                    " {method} {:.4} s ({rms:.2})",
                    r.update_s + r.query_s
                ));
                out.rows.push(FrameRow {
                    scene: bs.name.clone(),
                    frame: f,
                    time_s: Some(f as f64 * self.dt),
                    method: method.to_string(),
                    cell: cell.clone(),
                    points: setup.points.len(),
                    crease_points: Some(setup.points.crease_count()),
                    rays,
                    caster_triangles: tris,
                    points_s: Some(points_s),
                    update_s: r.update_s,
                    query_s: r.query_s,
                    frame_s: r.update_s + r.query_s,
                    mrays_s: rays as f64 / r.query_s.max(1e-12) / 1e6,
                    rms_vs_raycast: rms,
                    rms_vs_truth: rms_unquantised(&r.values, &truth.values),
                    truth_stderr: truth.rms_stderr_255(),
                    mean_value: r.values.iter().map(|&v| v as f64).sum::<f64>()
                        / r.values.len().max(1) as f64,
                    bytes: *bytes,
                    sphere_overlaps,
                    points_in_spheres,
                    flip_mean_vs_raycast: vs_raycast.map(|s| s.mean),
                    flip_weighted_median_vs_raycast: vs_raycast.map(|s| s.weighted_median),
                    flip_mean_vs_truth: vs_truth.map(|s| s.mean),
                    flip_weighted_median_vs_truth: vs_truth.map(|s| s.weighted_median),
                    flicker: moved.map(|m| m.0),
                    raycast_flicker: raycast_change.map(|m| m.0),
                    flicker_points: moved.map(|m| m.1),
                    flip_frame_change: moved.and_then(|m| m.2),
                    truth_flip_frame_change: truth_flip_change,
                    gap_radii: None,
                    mesh_clearance: None,
                    casters: None,
                });
                now.push((k, sig));
            }
            prev.extend(now);
            prev_truth = Some(truth_now);
            eprintln!("{line}");
            // The animation: the reference and the first field method, where there is an image.
            if let (Some(v), Some(field)) = (&view, measured.iter().find(|m| !m.1.is_empty())) {
                let img = |values: &[f32]| setup.points.image(&fbs.scene, v, values).0.data;
                pictures.push(Frame {
                    reference: img(&reference),
                    field: img(&field.2.values),
                });
            }
        }
        if let Some(img) = self.kind.image() {
            let size = (img.width as usize, img.height as usize);
            out.pictures.push((bs.name.clone(), size, pictures));
        }
        Ok(())
    }

    /// Every field cell of scene `s` (its methods made by the caller), each cell's fields supplied once
    /// (one per caster mesh, `global`: the meshes' indices in `scenes`; their bytes were held
    /// against the memory limit before any work, `plan::check_animated_fields`).
    fn cells(
        &self,
        scenes: &Scenes,
        s: usize,
        bs: &BuiltScene,
        global: &[usize],
    ) -> Result<Vec<CellMovers>> {
        let cells: Vec<_> = cells_of(self.spec)
            .into_iter()
            .filter(|c| c.scene == s)
            .collect();
        let reads_field = |n: &&str| motion::form(n).is_some_and(|(f, _)| f.reads_field);
        if !self.names.iter().any(reads_field) {
            return Ok(Vec::new());
        }
        let mut out = Vec::new();
        for c in cells {
            let (mut fields, mut normals) = (Vec::new(), Vec::new());
            for &m in global {
                let mesh = &scenes.meshes[m];
                match c.normal_bits {
                    Some(b) => {
                        let (f, n) = self.opts.supply.obtain_with_normals(mesh, c.params, &[b])?;
                        fields.push(f.field);
                        normals.push(n.into_iter().next().map(|(_, n)| n));
                    }
                    None => {
                        fields.push(self.opts.supply.obtain(mesh, c.params)?.field);
                        normals.push(None);
                    }
                }
            }
            let fields = MeshFields {
                fields,
                normals,
                options: self.kind.lookup_options(c.selection),
            };
            out.push(CellMovers {
                id: c.id(&bs.name),
                gpu: c.backend == Backend::Gpu,
                movers: Vec::new(),
                fields,
            });
        }
        Ok(out)
    }
}
