//! The runner: executes a [`Plan`] step by step, streaming fields (bake, evaluate the cells that
//! read them, release), and writes the outputs of [`super::outputs`], the images, `run.json` and
//! the plots of [`super::figures`].
//!
//! Every lookup uses the reference's rays: the same seeded k² set, the same points, the same
//! offset; the lookup and the ray cast differ only in the [`crate::render::Visibility`] behind
//! them. Stages shorter than `short_stage_s` are timed as the best of `repeats` runs.

use super::backend::{self, AoBackend, Casters, CpuBackend, Points};
use super::fields::{derive, FieldSupply, Supplied};
use super::metrics::{image_errors, vertex_errors};
use super::outputs::{self, PairRow, Row, SweepRow};
use super::plan::{Plan, PlanLimits, Step};
use super::progress::{stage, stage_adaptive};
use super::scenes::{BuiltScene, Scenes};
use super::spec::{Backend, RenderKind, Spec, SpecError, Threshold};
use crate::field::lookup::LookupOptions;
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::FieldParams;
use crate::render::ao::AoOptions;
use crate::render::image::{rms_255, rms_vertex, GrayImage};
use crate::render::primary::{gbuffer, shade_vertex_ao, PixelHit, PrimaryScene};
use crate::render::receivers::Receivers;
use crate::sampling::rays::RaySet;
use crate::trace::Tracer;
use glam::Vec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A spec read from disk.
#[derive(Clone, Debug)]
pub struct LoadedSpec {
    /// The file stem.
    pub name: String,
    pub path: PathBuf,
    pub text: String,
    pub spec: Spec,
}

impl LoadedSpec {
    /// Reads, parses and validates `path`.
    pub fn load(path: &Path) -> Result<LoadedSpec, SpecError> {
        let text = std::fs::read_to_string(path).map_err(|source| SpecError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        let spec = Spec::parse(&text, path)?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "spec".into());
        Ok(LoadedSpec {
            name,
            path: path.to_path_buf(),
            text,
            spec,
        })
    }
}

/// How to run a spec.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Use the quick profile.
    pub quick: bool,
    /// Output folder.
    pub out: PathBuf,
    /// Fields served from and saved to the cache (see [`super::fields`]).
    pub supply: FieldSupply,
    /// Print the plan and stop.
    pub dry_run: bool,
    /// Stages faster than this (seconds) are repeated, the best run reported.
    pub short_stage_s: f64,
    /// Runs of a short stage.
    pub repeats: usize,
}

impl RunOptions {
    /// Defaults: full profile, the default cache (256 MiB per field at most), half the memory.
    pub fn new(out: PathBuf) -> RunOptions {
        RunOptions {
            quick: false,
            out,
            supply: FieldSupply {
                cache: Some(super::fields::default_cache_dir()),
                cache_limit: 256 << 20,
                memory_limit: crate::field::default_memory_limit(),
            },
            dry_run: false,
            short_stage_s: 2.0,
            repeats: 3,
        }
    }
}

/// What a run produced.
#[derive(Clone, Debug)]
pub struct RunReport {
    pub name: String,
    pub out: PathBuf,
    pub rows: Vec<Row>,
    /// The thresholds of the profile that ran.
    pub thresholds: Vec<Threshold>,
    /// The plan as printed by `--dry-run`.
    pub plan_text: String,
    pub seconds: f64,
}

/// Fails unless `dir` can be created and written to.
pub fn ensure_writable(dir: &Path) -> Result<(), String> {
    let fail = |e: std::io::Error| format!("output folder {} is not writable: {e}", dir.display());
    std::fs::create_dir_all(dir).map_err(fail)?;
    let probe = dir.join(format!(".write-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(fail)?;
    std::fs::remove_file(&probe).map_err(fail)
}

/// Where AO is evaluated in a scene, and the scene's reference state.
struct SceneState {
    points: Vec<Vec3>,
    normals: Vec<Vec3>,
    /// Vertex AO: the receivers (for shading); image AO: the pixel of each point.
    receivers: Option<Receivers>,
    pixels: Vec<usize>,
    triangles: Vec<[Vec3; 3]>,
    tracer: Tracer,
    opts: AoOptions,
    gbuf: Option<(Vec<Option<PixelHit>>, u32, u32)>,
    reference: Vec<f32>,
    ref_image: Option<(GrayImage, Vec<bool>)>,
    /// Ray-cast AO time per (backend, k).
    raycast_s: HashMap<(Backend, u32), f64>,
}

impl SceneState {
    fn new(spec: &Spec, bs: &BuiltScene) -> SceneState {
        let ((triangles, tracer), _) = stage(&format!("{}: caster BVH", bs.name), || {
            let t = bs.scene.caster_triangles();
            let tracer = Tracer::new(&t);
            (t, tracer)
        });
        let mut opts = AoOptions::for_scene_radius(bs.radius());
        opts.max_distance = spec.render.max_distance;
        let gbuf = spec.render.image.as_ref().map(|img| {
            let cam = img.camera.unwrap_or_else(super::quickstart::corner_camera);
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
        SceneState {
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
        }
    }

    fn at(&self) -> Points<'_> {
        Points {
            points: &self.points,
            normals: &self.normals,
        }
    }

    /// The image showing `ao`, and the mask of AO pixels.
    fn image(&self, bs: &BuiltScene, ao: &[f32]) -> Option<(GrayImage, Vec<bool>)> {
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
    fn errors(&self, bs: &BuiltScene, ao: &[f32]) -> (Option<f64>, Option<f64>) {
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

/// One evaluated cell, kept for the pair table and the per-vertex CSV.
struct CellResult {
    cell: usize,
    ao: Vec<f32>,
    image: Option<GrayImage>,
}

fn io_err(p: &Path) -> impl Fn(std::io::Error) -> String + '_ {
    move |e| format!("{}: {e}", p.display())
}

/// Runs `ls` (or prints its plan with `dry_run`).
pub fn run(ls: &LoadedSpec, opts: &RunOptions) -> Result<RunReport, String> {
    let started = std::time::Instant::now();
    let spec = ls.spec.profile(opts.quick);
    let profile = if opts.quick { "quick" } else { "full" };
    if !opts.dry_run {
        ensure_writable(&opts.out)?;
    }
    let scenes_path = if opts.quick && ls.spec.quick.scenes.is_some() {
        "quick.scenes"
    } else {
        "scenes"
    };
    eprintln!("{} ({profile}): {}", ls.name, spec.reproduces);
    let (scenes, _) = stage("load scenes", || {
        Scenes::build(&spec, &ls.path, scenes_path)
    });
    let scenes = scenes.map_err(|e| e.to_string())?;
    let limits = PlanLimits {
        memory_limit: opts.supply.memory_limit,
    };
    let plan =
        Plan::new(&spec, &scenes, limits).map_err(|e| format!("{}: {e}", ls.path.display()))?;
    let supply = &opts.supply;
    let plan_text = plan.describe(&ls.name, &scenes, &|m, p| {
        supply.state(&scenes.meshes[m], p)
    });
    if opts.dry_run {
        return Ok(RunReport {
            name: ls.name.clone(),
            out: opts.out.clone(),
            rows: Vec::new(),
            thresholds: spec.thresholds.clone(),
            plan_text,
            seconds: started.elapsed().as_secs_f64(),
        });
    }
    eprint!("{plan_text}");
    let cpu = CpuBackend::new();
    let mut backends: HashMap<Backend, Box<dyn AoBackend>> = HashMap::new();
    for &b in &spec.backends {
        backends.insert(b, backend::open(b)?);
    }
    let out = &opts.out;
    let img_dir = out.join("images");
    let render_rays = RaySet::new(plan.render_k, spec.reference.seed);
    let mut states: Vec<Option<SceneState>> = (0..scenes.scenes.len()).map(|_| None).collect();
    let mut live: HashMap<(usize, FieldParams), Supplied> = HashMap::new();
    let mut rows: Vec<(usize, Row)> = Vec::new();
    let mut sweep: Vec<SweepRow> = Vec::new();
    let mut results: Vec<CellResult> = Vec::new();
    let (short, reps) = (opts.short_stage_s, opts.repeats);
    let lookups = plan
        .steps
        .iter()
        .filter(|s| matches!(s, Step::Lookup { .. }))
        .count();
    let mut done = 0;

    for step in &plan.steps {
        let scene_of = |s: &Step| match s {
            Step::Primary { scene, .. }
            | Step::Reference { scene, .. }
            | Step::Sweep { scene, .. }
            | Step::Raycast { scene, .. } => Some(*scene),
            Step::Lookup { cell, .. } => Some(plan.cells[*cell].scene),
            _ => None,
        };
        if let Some(s) = scene_of(step) {
            if states[s].is_none() {
                states[s] = Some(SceneState::new(&spec, &scenes.scenes[s]));
            }
        }
        match step {
            Step::Primary { .. } => {}
            Step::Reference { scene, k, .. } => {
                let bs = &scenes.scenes[*scene];
                let st = states[*scene].as_mut().expect("scene state");
                let rays = RaySet::new(*k, spec.reference.seed);
                let casters = Casters {
                    triangles: &st.triangles,
                    tracer: &st.tracer,
                };
                let msg = format!("{}: ray-cast reference, {} rays", bs.name, k * k);
                let (ao, s, _) = stage_adaptive(&msg, short, reps, || {
                    cpu.raycast_ao(&casters, &st.at(), &rays, &st.opts)
                })?;
                st.raycast_s.insert((Backend::Cpu, *k), s);
                st.reference = ao;
                st.ref_image = st.image(bs, &st.reference);
                if let Some((img, _)) = &st.ref_image {
                    let p = img_dir.join(format!("{}-reference.png", bs.name));
                    img.save_png(&p).map_err(io_err(&p))?;
                    let p = img_dir.join(format!("{}-reference.exr", bs.name));
                    img.save_exr(&p).map_err(io_err(&p))?;
                }
                sweep.push(SweepRow {
                    scene: bs.name.clone(),
                    backend: Backend::Cpu,
                    rays_per_point: k * k,
                    ao_s: s,
                    rms_vertex: st.receivers.as_ref().map(|_| 0.0),
                    rms_image: st.ref_image.as_ref().map(|_| 0.0),
                });
            }
            Step::Sweep { scene, k, .. } | Step::Raycast { scene, k, .. } => {
                let b = match step {
                    Step::Raycast { backend, .. } => *backend,
                    _ => Backend::Cpu,
                };
                let be: &dyn AoBackend = if b == Backend::Cpu {
                    &cpu
                } else {
                    backends[&b].as_ref()
                };
                let bs = &scenes.scenes[*scene];
                let st = states[*scene].as_mut().expect("scene state");
                let rays = RaySet::new(*k, spec.reference.seed);
                let casters = Casters {
                    triangles: &st.triangles,
                    tracer: &st.tracer,
                };
                let msg = format!("{}: ray-cast AO, {} rays ({})", bs.name, k * k, b.name());
                let (ao, s, _) = stage_adaptive(&msg, short, reps, || {
                    be.raycast_ao(&casters, &st.at(), &rays, &st.opts)
                })?;
                st.raycast_s.insert((b, *k), s);
                let (rv, ri) = st.errors(bs, &ao);
                sweep.push(SweepRow {
                    scene: bs.name.clone(),
                    backend: b,
                    rays_per_point: k * k,
                    ao_s: s,
                    rms_vertex: rv,
                    rms_image: ri,
                });
            }
            Step::Bake { mesh, params, .. } => {
                let f = supply.obtain(&scenes.meshes[*mesh], *params)?;
                live.insert((*mesh, *params), f);
            }
            Step::Derive {
                mesh, geometry, to, ..
            } => {
                let src = &live[&(*mesh, geometry.with(crate::field::Precision::F32))];
                let d = derive(src, *to);
                live.insert((*mesh, geometry.with(*to)), d);
            }
            Step::Release { fields, .. } => {
                for k in fields {
                    live.remove(k);
                }
            }
            Step::Lookup { cell, .. } => {
                done += 1;
                let c = plan.cells[*cell];
                let bs = &scenes.scenes[c.scene];
                let st = states[c.scene].as_ref().expect("scene state");
                let id = c.id(&bs.name);
                let mut instances = Vec::new();
                let (mut bake_s, mut bytes, mut bake_rays, mut cached) = (Some(0.0), 0, 0, true);
                for m in bs.caster_meshes() {
                    let f = &live[&(m, c.params)];
                    bake_s = bake_s.zip(f.bake_s).map(|(a, b)| a + b);
                    bytes += f.field.bytes();
                    bake_rays += f.rays;
                    cached &= f.cached;
                }
                for (i, inst) in bs.scene.casters() {
                    let f = &live[&(bs.mesh_of[i], c.params)];
                    instances.push(FieldInstance::new(f.field.clone(), inst.transform));
                }
                let fs = FieldScene {
                    instances,
                    options: LookupOptions {
                        selection: c.selection,
                        intra_bias: spec
                            .render
                            .intra_bias
                            .unwrap_or(LookupOptions::default().intra_bias),
                    },
                };
                let be = backends[&c.backend].as_ref();
                let msg = format!("[{done}/{lookups}] lookup {id}");
                let (ao, ao_s, _) = stage_adaptive(&msg, short, reps, || {
                    be.field_ao(&fs, &st.at(), &render_rays, &st.opts)
                })?;
                let ve = st
                    .receivers
                    .as_ref()
                    .map(|_| vertex_errors(&ao, &st.reference));
                let img = st.image(bs, &ao);
                let ie = match (&img, &st.ref_image) {
                    (Some((a, _)), Some((r, mask))) => Some(image_errors(&a.data, &r.data, mask)),
                    _ => None,
                };
                let mut image = String::new();
                if let (Some((a, _)), Some((r, _))) = (&img, &st.ref_image) {
                    image = format!("images/{id}.png");
                    let p = out.join(&image);
                    a.save_png(&p).map_err(io_err(&p))?;
                    let p = img_dir.join(format!("{id}.exr"));
                    a.save_exr(&p).map_err(io_err(&p))?;
                    let p = img_dir.join(format!("{id}-diff_x5.png"));
                    a.difference(r, 5.0).save_png(&p).map_err(io_err(&p))?;
                }
                rows.push((
                    *cell,
                    Row {
                        positional_samples: c.params.count,
                        directional_res: c.params.res,
                        layout: c.params.layout,
                        precision: c.params.precision,
                        selection: c.selection,
                        backend: c.backend,
                        adapter: be.adapter(),
                        bake_s,
                        ao_s,
                        raycast_s: st.raycast_s.get(&(c.backend, plan.render_k)).copied(),
                        rms_vertex: ve.map(|e| e.rms),
                        rms_image: ie.map(|e| e.rms),
                        field_bytes: bytes,
                        scene: bs.name.clone(),
                        sphere: c.params.sphere,
                        rays_per_point: spec.render.rays_per_point,
                        receiver_points: st.points.len(),
                        caster_triangles: bs.caster_triangles(),
                        max_error_vertex: ve.map(|e| e.max),
                        max_error_image: ie.map(|e| e.max),
                        share_pixels_off_1: ie.map(|e| e.share_off_1),
                        bake_rays,
                        bake_cached: cached,
                        image,
                        cell: id,
                    },
                ));
                results.push(CellResult {
                    cell: *cell,
                    ao,
                    image: img.map(|(i, _)| i),
                });
            }
        }
    }
    rows.sort_by_key(|(c, _)| *c);
    let rows: Vec<Row> = rows.into_iter().map(|(_, r)| r).collect();
    results.sort_by_key(|r| r.cell);
    let pairs = pairs(&plan, &scenes, &states, &results);
    write_outputs(
        ls, &spec, opts, &plan, &scenes, &states, &results, &rows, &sweep, &pairs, &backends,
    )?;
    let seconds = started.elapsed().as_secs_f64();
    eprintln!(
        "{}: {} cells in {seconds:.1} s -> {}",
        ls.name,
        rows.len(),
        out.display()
    );
    Ok(RunReport {
        name: ls.name.clone(),
        out: out.clone(),
        rows,
        thresholds: spec.thresholds.clone(),
        plan_text,
        seconds,
    })
}

/// RMS between every two cells that differ only in precision.
fn pairs(
    plan: &Plan,
    scenes: &Scenes,
    states: &[Option<SceneState>],
    results: &[CellResult],
) -> Vec<PairRow> {
    let mut out = Vec::new();
    for (i, a) in results.iter().enumerate() {
        for b in &results[i + 1..] {
            let (ca, cb) = (plan.cells[a.cell], plan.cells[b.cell]);
            let same = ca.scene == cb.scene
                && ca.geometry() == cb.geometry()
                && ca.selection == cb.selection
                && ca.backend == cb.backend
                && ca.params.precision != cb.params.precision;
            if !same {
                continue;
            }
            let st = states[ca.scene].as_ref().expect("scene state");
            let rms_image = match (&a.image, &b.image, &st.ref_image) {
                (Some(x), Some(y), Some((_, mask))) => Some(rms_255(&x.data, &y.data, Some(mask))),
                _ => None,
            };
            out.push(PairRow {
                scene: scenes.scenes[ca.scene].name.clone(),
                sphere: ca.params.sphere,
                positional_samples: ca.params.count,
                directional_res: ca.params.res,
                layout: ca.params.layout,
                selection: ca.selection,
                backend: ca.backend,
                precision_a: ca.params.precision,
                precision_b: cb.params.precision,
                rms_vertex: st.receivers.as_ref().map(|_| rms_vertex(&a.ao, &b.ao)),
                rms_image,
            });
        }
    }
    out
}

#[allow(clippy::too_many_arguments)]
fn write_outputs(
    ls: &LoadedSpec,
    spec: &Spec,
    opts: &RunOptions,
    plan: &Plan,
    scenes: &Scenes,
    states: &[Option<SceneState>],
    results: &[CellResult],
    rows: &[Row],
    sweep: &[SweepRow],
    pairs: &[PairRow],
    backends: &HashMap<Backend, Box<dyn AoBackend>>,
) -> Result<(), String> {
    let out = &opts.out;
    outputs::write_csv(&out.join("table.csv"), rows)?;
    outputs::write_csv(&out.join("raycast_sweep.csv"), sweep)?;
    if !pairs.is_empty() {
        outputs::write_csv(&out.join("pairs.csv"), pairs)?;
    }
    if let Some(paper) = &spec.paper {
        let pv = outputs::paper_vs_ours(paper, rows, pairs);
        outputs::write_csv(&out.join("paper_vs_ours.csv"), &pv)?;
    }
    // Per-point AO of every vertex-AO scene: the reference and each cell, one column each.
    for (s, bs) in scenes.scenes.iter().enumerate() {
        let Some(st) = states[s].as_ref().filter(|st| st.receivers.is_some()) else {
            continue;
        };
        let cols: Vec<&CellResult> = results
            .iter()
            .filter(|r| plan.cells[r.cell].scene == s)
            .collect();
        let mut text = String::from("point,x,y,z,reference");
        for r in &cols {
            text.push(',');
            text.push_str(&plan.cells[r.cell].id(&bs.name));
        }
        text.push('\n');
        for (i, p) in st.points.iter().enumerate() {
            text.push_str(&format!("{i},{},{},{},{}", p.x, p.y, p.z, st.reference[i]));
            for r in &cols {
                text.push_str(&format!(",{}", r.ao[i]));
            }
            text.push('\n');
        }
        let p = out.join(format!("ao_{}.csv", bs.name));
        crate::io::write_atomic(&p, text.as_bytes()).map_err(io_err(&p))?;
    }
    let mut meta = super::meta::RunMeta::collect(Some(&ls.text));
    meta.gpu_adapter = backends
        .iter()
        .find(|(b, _)| **b == Backend::Gpu)
        .map(|(_, be)| be.adapter());
    let scene_info: Vec<_> = scenes
        .scenes
        .iter()
        .enumerate()
        .map(|(s, bs)| {
            let st = states[s].as_ref();
            serde_json::json!({
                "name": bs.name,
                "instances": bs.scene.instances.len(),
                "ao_points": st.map(|st| st.points.len()),
                "caster_triangles": bs.caster_triangles(),
                "ray_offset": st.map(|st| st.opts.offset),
                "raycast_s": st.map(|st| st.raycast_s.iter().map(|((b, k), s)| {
                    serde_json::json!({"backend": b, "rays_per_point": k * k, "seconds": s})
                }).collect::<Vec<_>>()),
            })
        })
        .collect();
    let summary = serde_json::json!({
        "spec": ls.name,
        "spec_file": ls.path,
        "reproduces": spec.reproduces,
        "profile": if opts.quick { "quick" } else { "full" },
        "meta": meta,
        "rays_per_point": spec.render.rays_per_point,
        "reference_rays_per_point": spec.reference.rays_per_point,
        "seed": spec.reference.seed,
        "timing": format!("stages under {} s: best of {} runs", opts.short_stage_s, opts.repeats),
        "cache": opts.supply.cache,
        "cache_limit_bytes": opts.supply.cache_limit,
        "plan": {
            "cells": plan.cells.len(),
            "bakes": plan.bakes(),
            "peak_field_bytes": plan.peak_field_bytes,
            "needs_gpu": plan.needs_gpu,
            "needs_normal_field": plan.needs_normal_field,
        },
        "scenes": scene_info,
        "effective_spec": spec,
    });
    let p = out.join("run.json");
    let json = serde_json::to_string_pretty(&summary).expect("run summary serialises");
    crate::io::write_atomic(&p, json.as_bytes()).map_err(io_err(&p))?;
    let p = out.join("spec.json");
    crate::io::write_atomic(&p, ls.text.as_bytes()).map_err(io_err(&p))?;
    let title = format!("{}{}", ls.name, if opts.quick { " (quick)" } else { "" });
    super::figures::draw_all(out, &title)
}
