//! The runner's steps: ray-cast reference and sweep, bakes and derivations, and each cell's
//! estimate through its fields in three stages (evaluate → measure → write), all through the
//! render kind's [`crate::render::estimator::Estimator`].

use super::references::{raycast_truth_errors, seed_errors, SeedErrors};
use super::state::{mean_sd, CellResult, SceneState};
use super::RunOptions;
use crate::experiment::backend::{Casters, ComputeBackend, CpuBackend, Quantity};
use crate::experiment::columns::NamedRow;
use crate::experiment::fields::{derive, Supplied};
use crate::experiment::flip::{self, FlipMap, FlipStats};
use crate::experiment::kinds::Kind;
use crate::experiment::methods::Setting;
use crate::experiment::metrics::{
    grain, image_errors, rms_u8, rms_unquantised, vertex_errors, ErrorStats,
};
use crate::experiment::outputs::{FieldSweepRow, SweepRow};
use crate::experiment::plan::{Cell, Geometry, Plan, Step};
use crate::experiment::progress::stage_adaptive;
use crate::experiment::scenes::{BuiltScene, Scenes};
use crate::experiment::spec::{exact_sqrt, Backend, Spec};
use crate::experiment::table::{
    CellColumns, ErrorColumns, FieldColumns, Parts, Row, TableRow, TimeColumns,
};
use crate::experiment::{Error, Result};
use crate::field::normals::NormalField;
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::{FieldParams, Precision};
use crate::render::image::Image;
use crate::sampling::rays::RaySet;
use std::collections::HashMap;
use std::sync::Arc;

/// The state of a run between steps.
pub(super) struct Runner<'a> {
    pub(super) spec: &'a Spec,
    pub(super) kind: Box<dyn Kind>,
    pub(super) plan: &'a Plan,
    pub(super) scenes: &'a Scenes,
    pub(super) opts: &'a RunOptions,
    pub(super) cpu: CpuBackend,
    pub(super) backends: HashMap<Backend, Box<dyn ComputeBackend>>,
    pub(super) states: Vec<Option<SceneState>>,
    live: HashMap<(usize, FieldParams), Supplied>,
    /// The live normal fields per (mesh, field geometry, bits), for a kind that reads them.
    live_normals: HashMap<(usize, Geometry, u32), Arc<NormalField>>,
    pub(super) rows: Vec<(usize, TableRow)>,
    pub(super) sweep: Vec<SweepRow>,
    pub(super) field_sweep: Vec<FieldSweepRow>,
    pub(super) results: Vec<CellResult>,
    lookups: usize,
    done: usize,
    /// The spec's method settings ([`crate::experiment::methods::settings_of`]), whether this
    /// build runs each, and their rows.
    pub(super) methods: Vec<Setting>,
    pub(super) method_runs: Vec<bool>,
    pub(super) method_rows: Vec<NamedRow>,
    /// The method settings skipped on this run's device, and why (run.json).
    pub(super) skipped_methods: Vec<serde_json::Value>,
}

/// A cell's fields as the lookup reads them, and what their bakes cost.
struct CellFields {
    scene: FieldScene,
    columns: FieldColumns,
    bake_s: Option<f64>,
}

/// A cell evaluated on every seed: the first seed's values timed, the others not.
struct Evaluated {
    /// Values per seed, the timed seed first.
    values: Vec<Vec<f32>>,
    times: TimeColumns,
}

impl<'a> Runner<'a> {
    /// Opens the backends the plan needs (a GPU device only when a cell asks for one).
    pub(super) fn new(
        spec: &'a Spec,
        plan: &'a Plan,
        scenes: &'a Scenes,
        opts: &'a RunOptions,
    ) -> Result<Runner<'a>> {
        let methods = crate::experiment::methods::settings_of(spec);
        let mut backends = HashMap::new();
        for &b in spec
            .backends
            .iter()
            .chain(methods.iter().map(|m| &m.backend))
        {
            if let std::collections::hash_map::Entry::Vacant(e) = backends.entry(b) {
                e.insert(crate::experiment::backend_gpu::open(b, &opts.adapter)?);
            }
        }
        Ok(Runner {
            spec,
            kind: crate::experiment::kinds::of(&spec.render),
            plan,
            scenes,
            opts,
            cpu: CpuBackend::new(),
            backends,
            states: (0..scenes.scenes.len()).map(|_| None).collect(),
            live: HashMap::new(),
            live_normals: HashMap::new(),
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
            methods,
            method_runs: Vec::new(),
            method_rows: Vec::new(),
            skipped_methods: Vec::new(),
        })
    }

    /// The state of scene `s`, built on first use.
    pub(super) fn scene(&mut self, s: usize) -> &mut SceneState {
        let (kind, scenes) = (self.kind.as_ref(), self.scenes);
        self.states[s].get_or_insert_with(|| SceneState::new(kind, &scenes.scenes[s]))
    }

    /// Builds scene `s`'s state and fails, naming the scene, when its kind has no point to
    /// evaluate there (an image that sees no receiver, a scene without receiver vertices): an
    /// error over no point is no measurement.
    fn has_points(&mut self, s: usize) -> Result<()> {
        if !self.scene(s).at.is_empty() {
            return Ok(());
        }
        let what = if self.kind.needs().view {
            "the image sees no receiver point"
        } else {
            "no receiver vertex"
        };
        Err(Error::invalid(
            format!("scene {}", self.scenes.scenes[s].name),
            format!("{what}: {} has nothing to evaluate", self.kind.name()),
        ))
    }

    /// Executes one step.
    pub(super) fn step(&mut self, step: &Step) -> Result<()> {
        match step {
            Step::Primary { scene, .. } => {
                self.scene(*scene);
            }
            // Every scene's first step after its G-buffer, before any field is baked.
            Step::Truth { scene, .. } => {
                self.has_points(*scene)?;
                self.truth(*scene)?
            }
            Step::Reference { scene, k, .. } => self.reference(*scene, *k)?,
            Step::Sweep { scene, k, .. } => self.raycast(*scene, *k, Backend::Cpu)?,
            Step::Raycast {
                scene, backend, k, ..
            } => self.raycast(*scene, *k, *backend)?,
            Step::Bake {
                mesh,
                params,
                normals: false,
                ..
            } => {
                let f = self
                    .opts
                    .supply
                    .obtain(&self.scenes.meshes[*mesh], *params)?;
                self.live.insert((*mesh, *params), f);
            }
            Step::Bake {
                mesh,
                params,
                normals: true,
                ..
            } => {
                let bits = self.kind.normal_bits();
                let (f, normals) = self.opts.supply.obtain_with_normals(
                    &self.scenes.meshes[*mesh],
                    *params,
                    &bits,
                )?;
                self.live.insert((*mesh, *params), f);
                for (b, n) in normals {
                    self.live_normals
                        .insert((*mesh, Geometry::of(params), b), n);
                }
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
                // Normal fields go with the last distance field of their mesh and geometry.
                let live = &self.live;
                self.live_normals.retain(|(m, g, _), _| {
                    live.keys()
                        .any(|(lm, lp)| lm == m && Geometry::of(lp) == *g)
                });
            }
            // Listed and checked by the planner; run by the method's step.
            Step::Precompute { .. } => {}
            Step::Method { scene, setting, .. } => self.method(*scene, *setting)?,
            Step::Lookup { cell, .. } => self.lookup(*cell)?,
        }
        Ok(())
    }

    /// The ray-cast reference of a scene (CPU), its image, and its point of the sweep.
    fn reference(&mut self, scene: usize, k: u32) -> Result<()> {
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
        let q = st.quantity();
        let (values, s, _) = stage_adaptive(&msg, short, reps, || {
            cpu.raycast_estimate(&casters, q, st.at(), &rays)
        })?;
        st.raycast_s.insert((Backend::Cpu, k), s);
        st.reference = values;
        st.ref_image = st.image(bs, &st.reference);
        if let Some((img, _)) = &st.ref_image {
            let p = out.join(format!("images/{}-reference.png", bs.name));
            img.save_png(&p).map_err(Error::io(&p))?;
            let p = out.join(format!("images/{}-reference.exr", bs.name));
            img.save_exr(&p).map_err(Error::io(&p))?;
            if let Some(view) = &st.view {
                let p = crate::experiment::figures::grids::coverage_path(&out, &bs.name);
                crate::experiment::figures::grids::write_coverage(&p, view)?;
            }
        }
        st.ref_shaded = st.shaded_image(bs, &st.reference);
        if let Some(shaded) = &st.ref_shaded {
            let p = out.join(format!("images/{}-reference-shaded.png", bs.name));
            shaded.save_png(&p).map_err(Error::io(&p))?;
        }
        if let Some((name, est)) = &st.second {
            let values =
                cpu.raycast_estimate(&casters, Quantity::cpu(est.as_ref()), st.at(), &rays)?;
            if let Some((img, _)) = st.image(bs, &values) {
                let p = out.join(format!("images/{}-reference-{name}.png", bs.name));
                img.save_png(&p).map_err(Error::io(&p))?;
                st.second_image = Some(img);
            }
        }
        let (rms_vertex, rms_image) = (
            self.kind.columns().vertex.then_some(0.0),
            st.ref_image.as_ref().map(|_| 0.0),
        );
        let ref_image = st.ref_image.as_ref().map(|(img, _)| img);
        let (flip_mean, flip_mean_vs_truth) = sweep_flips(st, ref_image);
        let name = bs.name.clone();
        self.seed_references(scene, k)?;
        let st = self.states[scene].as_ref().expect("scene state");
        let (t, t_sd) = mean_sd(&st.reference_vs_truth);
        let row = SweepRow {
            scene: name,
            backend: Backend::Cpu,
            rays_per_point: k * k,
            raycast_s: s,
            rms_vertex,
            rms_image,
            raycast_kernel_s: None,
            rms_vs_truth: st.truth.as_ref().map(|_| t),
            rms_vs_truth_sd: st.truth.as_ref().and(t_sd),
            truth_stderr: st.truth.as_ref().map(|t| t.rms_stderr_255()),
            flip_mean,
            flip_mean_vs_truth,
        };
        self.sweep.push(row);
        Ok(())
    }

    /// The estimate by ray casting with k² rays on a backend, timed, with its error against
    /// the reference.
    fn raycast(&mut self, scene: usize, k: u32, b: Backend) -> Result<()> {
        let (short, reps) = (self.opts.short_stage_s, self.opts.repeats);
        let seed = self.spec.reference.seed;
        let seeds = self.seeds();
        let scenes = self.scenes;
        let bs = &scenes.scenes[scene];
        self.scene(scene);
        let st = self.states[scene].as_mut().expect("scene state");
        let be: &dyn ComputeBackend = match b {
            Backend::Cpu => &self.cpu,
            _ => self.backends[&b].as_ref(),
        };
        let rays = RaySet::new(k, seed);
        let casters = Casters {
            triangles: &st.triangles,
            tracer: &st.tracer,
        };
        let msg = format!("{}: ray cast, {} rays ({})", bs.name, k * k, b.name());
        let eval = be.casters(&casters, st.quantity())?;
        let mut kernel_s = None;
        let (values, s, _) = stage_adaptive(&msg, short, reps, || {
            let o = eval.estimate(st.at(), &rays)?;
            kernel_s = min_time(kernel_s, o.kernel_s);
            Ok::<_, Error>(o.values)
        })?;
        drop(eval);
        st.raycast_s.insert((b, k), s);
        if let Some(ks) = kernel_s {
            st.raycast_kernel_s.insert((b, k), ks);
        }
        let (rms_vertex, rms_image) = st.errors(self.kind.as_ref(), bs, &values);
        let image = st.image(bs, &values).map(|(img, _)| img);
        let (flip_mean, flip_mean_vs_truth) = sweep_flips(st, image.as_ref());
        let vs = raycast_truth_errors(be, st, k, &seeds, &values)?;
        let (t, t_sd) = mean_sd(&vs);
        self.sweep.push(SweepRow {
            scene: bs.name.clone(),
            backend: b,
            rays_per_point: k * k,
            raycast_s: s,
            rms_vertex,
            rms_image,
            raycast_kernel_s: kernel_s,
            rms_vs_truth: (!vs.is_empty()).then_some(t),
            rms_vs_truth_sd: t_sd,
            truth_stderr: st.truth.as_ref().map(|t| t.rms_stderr_255()),
            flip_mean,
            flip_mean_vs_truth,
        });
        Ok(())
    }

    /// One cell: its estimate through its fields on the reference's rays (evaluate), its
    /// errors (measure), its images and row (write).
    fn lookup(&mut self, cell: usize) -> Result<()> {
        self.done += 1;
        let c = self.plan.cells[cell];
        let bs = &self.scenes.scenes[c.scene];
        self.scene(c.scene);
        let id = c.id(&bs.name);
        let fields = self.cell_fields(&c);
        let run = self.evaluate(&c, &fields, &id);
        let (ev, field_sweep) = run.map_err(|e| e.context(format!("cell {id}")))?;
        let st = self.states[c.scene].as_ref().expect("scene state");
        let img = st.image(bs, &ev.values[0]);
        let (errors, flips) = self.measure(st, bs, &ev.values, img.as_ref().map(|(i, _)| i));
        let image = self.write_images(&id, img.as_ref(), st, &flips)?;
        if let Some(shaded) = st.shaded_image(bs, &ev.values[0]) {
            let p = self.opts.out.join(format!("images/{id}-shaded.png"));
            shaded.save_png(&p).map_err(Error::io(&p))?;
        }
        let be = self.backends[&c.backend].as_ref();
        let parts = Parts {
            cell: self.cell_columns(&c, &id, st, be.adapter()),
            times: TimeColumns {
                bake_s: fields.bake_s,
                raycast_s: st.raycast_s.get(&(c.backend, self.plan.render_k)).copied(),
                raycast_kernel_s: st
                    .raycast_kernel_s
                    .get(&(c.backend, self.plan.render_k))
                    .copied(),
                ..ev.times
            },
            fields: fields.columns,
            errors: ErrorColumns { image, ..errors },
        };
        let row = TableRow {
            row: Row::from_parts(&parts),
            own: self.own_metrics(st, &ev.values[0]),
        };
        self.rows.push((cell, row));
        self.field_sweep.extend(field_sweep);
        let values = ev.values.into_iter().next().expect("the first seed");
        self.results.push(CellResult {
            cell,
            values,
            image: img.map(|(i, _)| i),
        });
        Ok(())
    }

    /// The fields of cell `c`'s casters (from the live set), as the lookup reads them.
    fn cell_fields(&self, c: &Cell) -> CellFields {
        let bs = &self.scenes.scenes[c.scene];
        let mut columns = FieldColumns {
            bake_cached: true,
            ..FieldColumns::default()
        };
        let mut bake_s = Some(0.0);
        let normals = |m: usize| {
            c.normal_bits
                .map(|b| self.live_normals[&(m, Geometry::of(&c.params), b)].clone())
        };
        for m in bs.caster_meshes() {
            let f = &self.live[&(m, c.params)];
            bake_s = bake_s.zip(f.bake_s).map(|(a, b)| a + b);
            columns.field_bytes += f.field.bytes() + normals(m).map_or(0, |n| n.bytes());
            columns.bake_rays += f.rays;
            columns.bake_cached &= f.cached;
        }
        let instances = bs
            .scene
            .casters()
            .map(|(i, inst)| {
                let m = bs.mesh_of[i];
                let f = &self.live[&(m, c.params)];
                let fi = FieldInstance::new(f.field.clone(), inst.transform);
                match normals(m) {
                    Some(n) => fi.with_normals(n),
                    None => fi,
                }
            })
            .collect();
        CellFields {
            scene: FieldScene {
                instances,
                options: self.kind.lookup_options(c.selection),
            },
            columns,
            bake_s,
        }
    }

    /// Evaluate: the estimate through the fields on every seed (the first timed), and the same
    /// fields with the field sweep's ray counts against the truth.
    fn evaluate(
        &self,
        c: &Cell,
        fields: &CellFields,
        id: &str,
    ) -> Result<(Evaluated, Vec<FieldSweepRow>)> {
        let st = self.states[c.scene].as_ref().expect("scene state");
        let be = self.backends[&c.backend].as_ref();
        let (spec, k) = (self.spec, self.plan.render_k);
        let (short, reps) = (self.opts.short_stage_s, self.opts.repeats);
        let msg = format!("[{}/{}] lookup {id}", self.done, self.lookups);
        let eval = be.fields(&fields.scene, st.quantity())?;
        let mut estimate_kernel_s = None;
        let rays = RaySet::new(k, spec.reference.seed);
        let (first, estimate_s, _) = stage_adaptive(&msg, short, reps, || {
            let o = eval.estimate(st.at(), &rays)?;
            estimate_kernel_s = min_time(estimate_kernel_s, o.kernel_s);
            Ok::<_, Error>(o.values)
        })?;
        let times = TimeColumns {
            estimate_s,
            estimate_kernel_s,
            setup_s: eval.setup_s(),
            ..TimeColumns::default()
        };
        // The other seeds (untimed), on the fields as prepared.
        let mut values = vec![first];
        for &sd in &self.seeds()[1..] {
            let rays = RaySet::new(k, sd);
            values.push(eval.estimate(st.at(), &rays)?.values);
        }
        // The same fields with more rays per point, against the truth only; timed like the
        // cell (the preparation, GPU upload and compilation, is not in the time).
        let mut sweep = Vec::new();
        for &n in &spec.reference.field_rays_sweep {
            let kn = exact_sqrt(n).ok_or_else(|| {
                Error::invalid("reference.field_rays_sweep", format!("{n} is not a square"))
            })?;
            let (other, s) = if kn == k {
                (None, estimate_s)
            } else {
                let rays = RaySet::new(kn, spec.reference.seed);
                let msg = format!("  lookup {id}, {n} rays");
                let (a, s, _) = stage_adaptive(&msg, short, reps, || {
                    Ok::<_, Error>(eval.estimate(st.at(), &rays)?.values)
                })?;
                (Some(a), s)
            };
            let e = st.truth_errors(other.as_deref().unwrap_or(&values[0]));
            sweep.push(FieldSweepRow {
                scene: self.scenes.scenes[c.scene].name.clone(),
                cell: id.to_string(),
                positional_samples: c.params.count,
                directional_res: c.params.res,
                precision: c.params.precision,
                selection: c.selection,
                backend: c.backend,
                rays_per_point: n,
                estimate_s: s,
                rms_vs_truth: e.map(|e| e.all),
                truth_stderr: st.truth.as_ref().map(|t| t.rms_stderr_255()),
            });
        }
        drop(eval);
        Ok((Evaluated { values, times }, sweep))
    }

    /// Measure: the kind's metric columns against the same-ray reference (the first seed's
    /// largest errors and share off by one level; the RMS columns over every seed) and the
    /// errors against the converged reference.
    pub(super) fn measure(
        &self,
        st: &SceneState,
        bs: &BuiltScene,
        values: &[Vec<f32>],
        first_image: Option<&Image>,
    ) -> (ErrorColumns, FlipMaps) {
        // FLIP over the pixels the image RMS is taken over (untimed, as every metric).
        let mask = st.ref_image.as_ref().map(|(_, m)| m.as_slice());
        let flips = FlipMaps {
            vs_reference: flip::compare(st.ref_image.as_ref().map(|(r, _)| r), first_image, mask),
            vs_truth: flip::compare(st.truth_image.as_ref(), first_image, mask),
        };
        let vertex: Option<ErrorStats> = self
            .kind
            .columns()
            .vertex
            .then(|| vertex_errors(&values[0], &st.reference));
        let image: Option<ErrorStats> = match (first_image, &st.ref_image) {
            (Some(a), Some((r, mask))) => Some(image_errors(&a.data, &r.data, mask)),
            _ => None,
        };
        let se: SeedErrors = seed_errors(self.kind.as_ref(), st, bs, values, first_image);
        let errors = ErrorColumns {
            seeds: values.len() as u32,
            rms_vertex: se.vertex,
            rms_image: se.image,
            max_error_vertex: vertex.map(|e| e.max),
            max_error_image: image.map(|e| e.max),
            share_pixels_off_1: image.map(|e| e.share_off_1),
            rms_vs_truth: se.truth,
            rms_vs_truth_crease: se.crease,
            rms_vs_truth_interior: se.interior,
            rms_vs_truth_in_spheres: se.in_spheres,
            rms_vs_truth_outside_spheres: se.outside_spheres,
            rms_outside_spheres: {
                let e = crate::experiment::metrics::rms_unquantised_where(
                    &values[0],
                    &st.reference,
                    |i| !st.in_spheres[st.point_of(i)],
                );
                (!e.is_nan()).then_some(e)
            },
            truth_stderr: st.truth.as_ref().map(|t| t.rms_stderr_255()),
            truth_rays: st.truth.as_ref().map(|t| t.rays_per_point),
            raycast_rms_vs_truth: (!st.reference_vs_truth.is_empty())
                .then(|| mean_sd(&st.reference_vs_truth).0),
            signal_rms: Some(rms_unquantised(
                &vec![1.0; st.reference.len()],
                &st.reference,
            )),
            grain: match (first_image, &st.ref_image) {
                (Some(a), Some((r, mask))) => Some(grain(&a.data, &r.data, mask, a.width as usize)),
                _ => None,
            },
            second_reference: st.second.as_ref().map(|(n, _)| n.to_string()),
            rms_image_vs_second: match (first_image, &st.second_image, &st.ref_image) {
                (Some(a), Some(s), Some((_, mask))) => Some(rms_u8(&a.data, &s.data, Some(mask))),
                _ => None,
            },
            rms_image_window: se.image.zip(st.window_share()).map(|(m, s)| m.0 * s.sqrt()),
            rms_image_shaded: se.shaded,
            flip: flips.vs_reference.as_ref().map(|f| f.0),
            flip_vs_truth: flips.vs_truth.as_ref().map(|f| f.0),
            image: String::new(),
        };
        (errors, flips)
    }

    /// Write: the cell's image, its difference from the reference ×5 and its FLIP maps
    /// (magma) against the reference (`-flip.png`) and the converged reference
    /// (`-flip_vs_truth.png`); the image's path relative to the output folder (empty without an
    /// image).
    pub(super) fn write_images(
        &self,
        id: &str,
        img: Option<&(Image, Vec<bool>)>,
        st: &SceneState,
        flips: &FlipMaps,
    ) -> Result<String> {
        let (Some((a, _)), Some((r, _))) = (img, &st.ref_image) else {
            return Ok(String::new());
        };
        let out = &self.opts.out;
        let image = format!("images/{id}.png");
        let p = out.join(&image);
        a.save_png(&p).map_err(Error::io(&p))?;
        let p = out.join(format!("images/{id}-diff_x5.png"));
        a.difference(r, 5.0).save_png(&p).map_err(Error::io(&p))?;
        for (suffix, f) in [
            ("flip", &flips.vs_reference),
            ("flip_vs_truth", &flips.vs_truth),
        ] {
            if let Some((_, map)) = f {
                let p = out.join(format!("images/{id}-{suffix}.png"));
                map.save_magma_png(&p).map_err(Error::io(&p))?;
            }
        }
        Ok(image)
    }

    /// The identity columns of cell `c`.
    fn cell_columns(&self, c: &Cell, id: &str, st: &SceneState, adapter: String) -> CellColumns {
        let bs = &self.scenes.scenes[c.scene];
        CellColumns {
            cell: id.to_string(),
            scene: bs.name.clone(),
            sphere: c.params.sphere,
            positional_samples: c.params.count,
            directional_res: c.params.res,
            layout: c.params.layout,
            precision: c.params.precision,
            selection: c.selection,
            backend: c.backend,
            adapter,
            rays_per_point: self.kind.rays_per_point(),
            normal_bits: c.normal_bits,
            rays_cast: st.at.len() as u64 * self.kind.rays_cast_per_point(),
            receiver_points: st.at.len(),
            crease_points: st.at.crease_count(),
            points_in_spheres: st.in_spheres.iter().filter(|&&b| b).count(),
            caster_triangles: bs.caster_triangles(),
            channels: st.channels as u32,
        }
    }

    /// The kind's own metric columns of `values` (the first seed's) on `st`.
    pub(super) fn own_metrics(&self, st: &SceneState, values: &[f32]) -> Vec<(String, f64)> {
        self.kind
            .own_metrics(values, &st.reference, st.truth.as_ref())
    }
}

/// A cell's FLIP against the same-ray reference's image and against the converged
/// reference's image: pooled, and the map.
pub(super) struct FlipMaps {
    pub(super) vs_reference: Option<(FlipStats, FlipMap)>,
    pub(super) vs_truth: Option<(FlipStats, FlipMap)>,
}

/// A ray cast's mean FLIP against the same-ray reference's image and against the converged
/// reference's, over the pixels the image RMS is taken over (untimed, as every metric).
fn sweep_flips(st: &SceneState, image: Option<&Image>) -> (Option<f64>, Option<f64>) {
    let mask = st.ref_image.as_ref().map(|(_, m)| m.as_slice());
    let mean =
        |reference: Option<&Image>| flip::compare(reference, image, mask).map(|(f, _)| f.mean);
    (
        mean(st.ref_image.as_ref().map(|(r, _)| r)),
        mean(st.truth_image.as_ref()),
    )
}

/// The smaller of two optional times (a kernel time is the best over the timed runs).
fn min_time(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}
