//! The runner's steps: ray-cast reference and sweep, bakes and derivations, field-lookup AO per
//! cell with its metrics and images.

use super::state::{io_err, mean_sd, CellResult, SceneState};
use super::truth::{raycast_truth_errors, seed_errors};
use super::RunOptions;
use crate::experiment::backend::{self, AoBackend, Casters, CpuBackend};
use crate::experiment::fields::{derive, Supplied};
use crate::experiment::metrics::{image_errors, vertex_errors};
use crate::experiment::outputs::{FieldSweepRow, Row, SweepRow};
use crate::experiment::plan::{Plan, Step};
use crate::experiment::progress::stage_adaptive;
use crate::experiment::scenes::Scenes;
use crate::experiment::spec::{exact_sqrt, Backend, Spec};
use crate::field::lookup::{IntraBias, LookupOptions};
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::{FieldParams, Precision};
use crate::sampling::rays::RaySet;
use std::collections::HashMap;

/// The state of a run between steps.
pub(super) struct Runner<'a> {
    pub(super) spec: &'a Spec,
    pub(super) plan: &'a Plan,
    pub(super) scenes: &'a Scenes,
    pub(super) opts: &'a RunOptions,
    pub(super) cpu: CpuBackend,
    pub(super) backends: HashMap<Backend, Box<dyn AoBackend>>,
    pub(super) states: Vec<Option<SceneState>>,
    live: HashMap<(usize, FieldParams), Supplied>,
    pub(super) rows: Vec<(usize, Row)>,
    pub(super) sweep: Vec<SweepRow>,
    pub(super) field_sweep: Vec<FieldSweepRow>,
    pub(super) results: Vec<CellResult>,
    lookups: usize,
    done: usize,
}

impl<'a> Runner<'a> {
    /// Opens the backends the plan needs (a GPU device only when a cell asks for one).
    pub(super) fn new(
        spec: &'a Spec,
        plan: &'a Plan,
        scenes: &'a Scenes,
        opts: &'a RunOptions,
    ) -> Result<Runner<'a>, String> {
        let mut backends = HashMap::new();
        for &b in &spec.backends {
            backends.insert(b, backend::open(b, &opts.adapter)?);
        }
        Ok(Runner {
            spec,
            plan,
            scenes,
            opts,
            cpu: CpuBackend::new(),
            backends,
            states: (0..scenes.scenes.len()).map(|_| None).collect(),
            live: HashMap::new(),
            rows: Vec::new(),
            sweep: Vec::new(),
            field_sweep: Vec::new(),
            results: Vec::new(),
            lookups: plan
                .steps
                .iter()
                .filter(|s| matches!(s, Step::Lookup { .. }))
                .count(),
            done: 0,
        })
    }

    /// The state of scene `s`, built on first use.
    pub(super) fn scene(&mut self, s: usize) -> &mut SceneState {
        let (spec, scenes) = (self.spec, self.scenes);
        self.states[s].get_or_insert_with(|| SceneState::new(spec, &scenes.scenes[s]))
    }

    /// Executes one step.
    pub(super) fn step(&mut self, step: &Step) -> Result<(), String> {
        match step {
            Step::Primary { scene, .. } => {
                self.scene(*scene);
            }
            Step::Truth { scene, .. } => self.truth(*scene)?,
            Step::Reference { scene, k, .. } => self.reference(*scene, *k)?,
            Step::Sweep { scene, k, .. } => self.raycast(*scene, *k, Backend::Cpu)?,
            Step::Raycast {
                scene, backend, k, ..
            } => self.raycast(*scene, *k, *backend)?,
            Step::Bake { mesh, params, .. } => {
                let f = self
                    .opts
                    .supply
                    .obtain(&self.scenes.meshes[*mesh], *params)?;
                self.live.insert((*mesh, *params), f);
            }
            Step::Derive {
                mesh, geometry, to, ..
            } => {
                let src = &self.live[&(*mesh, geometry.with(Precision::F32))];
                let d = derive(src, *to);
                self.live.insert((*mesh, geometry.with(*to)), d);
            }
            Step::Release { fields, .. } => {
                for k in fields {
                    self.live.remove(k);
                }
            }
            Step::Lookup { cell, .. } => self.lookup(*cell)?,
        }
        Ok(())
    }

    /// The ray-cast reference of a scene (CPU), its image, and its point of the sweep.
    fn reference(&mut self, scene: usize, k: u32) -> Result<(), String> {
        let (short, reps) = (self.opts.short_stage_s, self.opts.repeats);
        let seed = self.spec.reference.seed;
        let out = self.opts.out.clone();
        let scenes = self.scenes;
        let bs = &scenes.scenes[scene];
        self.scene(scene);
        let st = self.states[scene].as_mut().expect("scene state");
        let cpu = &self.cpu;
        let rays = RaySet::new(k, seed);
        let casters = Casters {
            triangles: &st.triangles,
            tracer: &st.tracer,
        };
        let msg = format!("{}: ray-cast reference, {} rays", bs.name, k * k);
        let (ao, s, _) = stage_adaptive(&msg, short, reps, || {
            cpu.raycast_ao(&casters, &st.at(), &rays, &st.opts)
        })?;
        st.raycast_s.insert((Backend::Cpu, k), s);
        st.reference = ao;
        st.ref_image = st.image(bs, &st.reference);
        if let Some((img, _)) = &st.ref_image {
            let p = out.join(format!("images/{}-reference.png", bs.name));
            img.save_png(&p).map_err(io_err(&p))?;
            let p = out.join(format!("images/{}-reference.exr", bs.name));
            img.save_exr(&p).map_err(io_err(&p))?;
        }
        let (rms_vertex, rms_image) = (
            st.receivers.as_ref().map(|_| 0.0),
            st.ref_image.as_ref().map(|_| 0.0),
        );
        let name = bs.name.clone();
        self.seed_references(scene, k)?;
        let st = self.states[scene].as_ref().expect("scene state");
        let (t, t_sd) = mean_sd(&st.reference_vs_truth);
        let row = SweepRow {
            scene: name,
            backend: Backend::Cpu,
            rays_per_point: k * k,
            ao_s: s,
            rms_vertex,
            rms_image,
            kernel_s: None,
            rms_vs_truth: st.truth.as_ref().map(|_| t),
            rms_vs_truth_sd: st.truth.as_ref().and(t_sd),
            truth_stderr: st.truth.as_ref().map(|t| t.rms_stderr_255()),
        };
        self.sweep.push(row);
        Ok(())
    }

    /// Ray-cast AO with k² rays on a backend, timed, with its error against the reference.
    fn raycast(&mut self, scene: usize, k: u32, b: Backend) -> Result<(), String> {
        let (short, reps) = (self.opts.short_stage_s, self.opts.repeats);
        let seed = self.spec.reference.seed;
        let seeds = self.seeds();
        let scenes = self.scenes;
        let bs = &scenes.scenes[scene];
        self.scene(scene);
        let st = self.states[scene].as_mut().expect("scene state");
        let be: &dyn AoBackend = match b {
            Backend::Cpu => &self.cpu,
            _ => self.backends[&b].as_ref(),
        };
        let rays = RaySet::new(k, seed);
        let casters = Casters {
            triangles: &st.triangles,
            tracer: &st.tracer,
        };
        let msg = format!("{}: ray-cast AO, {} rays ({})", bs.name, k * k, b.name());
        let eval = be.casters(&casters)?;
        let mut kernel_s = None;
        let (ao, s, _) = stage_adaptive(&msg, short, reps, || {
            let o = eval.ao(&st.at(), &rays, &st.opts)?;
            kernel_s = min_time(kernel_s, o.kernel_s);
            Ok::<_, String>(o.ao)
        })?;
        st.raycast_s.insert((b, k), s);
        if let Some(ks) = kernel_s {
            st.raycast_kernel_s.insert((b, k), ks);
        }
        let (rms_vertex, rms_image) = st.errors(bs, &ao);
        let vs = raycast_truth_errors(be, st, k, &seeds, &ao)?;
        let (t, t_sd) = mean_sd(&vs);
        self.sweep.push(SweepRow {
            scene: bs.name.clone(),
            backend: b,
            rays_per_point: k * k,
            ao_s: s,
            rms_vertex,
            rms_image,
            kernel_s,
            rms_vs_truth: (!vs.is_empty()).then_some(t),
            rms_vs_truth_sd: t_sd,
            truth_stderr: st.truth.as_ref().map(|t| t.rms_stderr_255()),
        });
        Ok(())
    }

    /// Field-lookup AO of one cell on the reference's rays: time, errors, images, table row.
    fn lookup(&mut self, cell: usize) -> Result<(), String> {
        self.done += 1;
        let (spec, plan) = (self.spec, self.plan);
        let c = plan.cells[cell];
        let scenes = self.scenes;
        let bs = &scenes.scenes[c.scene];
        self.scene(c.scene);
        let st = self.states[c.scene].as_ref().expect("scene state");
        let id = c.id(&bs.name);
        let (mut bake_s, mut bytes, mut bake_rays, mut cached) = (Some(0.0), 0, 0, true);
        for m in bs.caster_meshes() {
            let f = &self.live[&(m, c.params)];
            bake_s = bake_s.zip(f.bake_s).map(|(a, b)| a + b);
            bytes += f.field.bytes();
            bake_rays += f.rays;
            cached &= f.cached;
        }
        let instances = bs
            .scene
            .casters()
            .map(|(i, inst)| {
                let f = &self.live[&(bs.mesh_of[i], c.params)];
                FieldInstance::new(f.field.clone(), inst.transform)
            })
            .collect();
        let default = LookupOptions::default();
        let fs = FieldScene {
            instances,
            options: LookupOptions {
                selection: c.selection,
                intra_bias: spec
                    .render
                    .intra_bias
                    .map(IntraBias::Fixed)
                    .unwrap_or(default.intra_bias),
            },
        };
        let be = self.backends[&c.backend].as_ref();
        let rays = RaySet::new(plan.render_k, spec.reference.seed);
        let msg = format!("[{}/{}] lookup {id}", self.done, self.lookups);
        let (short, reps) = (self.opts.short_stage_s, self.opts.repeats);
        let eval = be.fields(&fs)?;
        let mut ao_kernel_s = None;
        let (ao, ao_s, _) = stage_adaptive(&msg, short, reps, || {
            let o = eval.ao(&st.at(), &rays, &st.opts)?;
            ao_kernel_s = min_time(ao_kernel_s, o.kernel_s);
            Ok::<_, String>(o.ao)
        })?;
        let setup_s = eval.setup_s();
        drop(eval);
        let ve = st
            .receivers
            .as_ref()
            .map(|_| vertex_errors(&ao, &st.reference));
        let img = st.image(bs, &ao);
        let ie = match (&img, &st.ref_image) {
            (Some((a, _)), Some((r, mask))) => Some(image_errors(&a.data, &r.data, mask)),
            _ => None,
        };
        // The other seeds (untimed), and every seed's errors.
        let mut aos = vec![ao];
        for &sd in &self.seeds()[1..] {
            let rays = RaySet::new(plan.render_k, sd);
            aos.push(be.field_ao(&fs, &st.at(), &rays, &st.opts)?);
        }
        let se = seed_errors(st, bs, &aos, img.as_ref().map(|(i, _)| i));
        let seeds = aos.len() as u32;
        let ao = aos.swap_remove(0);
        // The same field with more rays per point, against the truth only.
        let mut field_sweep = Vec::new();
        for &n in &spec.reference.field_rays_sweep {
            let k = exact_sqrt(n).ok_or("field_rays_sweep: not a square")?;
            let (ao_k, s) = if k == plan.render_k {
                (None, ao_s)
            } else {
                let rays = RaySet::new(k, spec.reference.seed);
                let msg = format!("  lookup {id}, {n} rays");
                let (a, s, _) = stage_adaptive(&msg, short, reps, || {
                    be.field_ao(&fs, &st.at(), &rays, &st.opts)
                })?;
                (Some(a), s)
            };
            let e = st.truth_errors(ao_k.as_deref().unwrap_or(&ao));
            field_sweep.push(FieldSweepRow {
                scene: bs.name.clone(),
                cell: id.clone(),
                positional_samples: c.params.count,
                directional_res: c.params.res,
                precision: c.params.precision,
                selection: c.selection,
                backend: c.backend,
                rays_per_point: n,
                ao_s: s,
                rms_vs_truth: e.map(|e| e.all),
                truth_stderr: st.truth.as_ref().map(|t| t.rms_stderr_255()),
            });
        }
        let mut image = String::new();
        if let (Some((a, _)), Some((r, _))) = (&img, &st.ref_image) {
            let out = &self.opts.out;
            image = format!("images/{id}.png");
            let p = out.join(&image);
            a.save_png(&p).map_err(io_err(&p))?;
            let p = out.join(format!("images/{id}-diff_x5.png"));
            a.difference(r, 5.0).save_png(&p).map_err(io_err(&p))?;
        }
        let row = Row {
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
            rms_vertex: se.vertex.map(|m| m.0),
            rms_image: se.image.map(|m| m.0),
            field_bytes: bytes,
            rms_vs_truth: se.truth.map(|m| m.0),
            truth_stderr: st.truth.as_ref().map(|t| t.rms_stderr_255()),
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
            ao_kernel_s,
            raycast_kernel_s: st
                .raycast_kernel_s
                .get(&(c.backend, plan.render_k))
                .copied(),
            setup_s,
            seeds,
            rms_vertex_sd: se.vertex.and_then(|m| m.1),
            rms_image_sd: se.image.and_then(|m| m.1),
            rms_vs_truth_sd: se.truth.and_then(|m| m.1),
            raycast_rms_vs_truth: (!st.reference_vs_truth.is_empty())
                .then(|| mean_sd(&st.reference_vs_truth).0),
            truth_rays: st.truth.as_ref().map(|t| t.rays_per_point),
            crease_points: st.crease.iter().filter(|&&c| c).count(),
            rms_vs_truth_crease: se.crease,
            rms_vs_truth_interior: se.interior,
        };
        self.rows.push((cell, row));
        self.field_sweep.extend(field_sweep);
        self.results.push(CellResult {
            cell,
            ao,
            image: img.map(|(i, _)| i),
        });
        Ok(())
    }
}

/// The smaller of two optional times (a kernel time is the best over the timed runs).
fn min_time(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}
