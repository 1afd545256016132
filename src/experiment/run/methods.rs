//! The spec's methods ([`crate::experiment::methods`]) on each scene: the precompute timed,
//! then the kind through the method on every seed (the first timed), measured against the same
//! same-ray reference and converged reference as the field's cells, one `methods.csv` row per
//! scene, setting and backend, built from named parts ([`crate::experiment::columns`]). On the
//! `gpu` backend the prepared method's kernels ([`crate::experiment::methods::GpuMethod`]) are
//! uploaded (the row's `setup_s`) and answer in place of the CPU answer; the row adds the
//! kernels' own time (`estimate_kernel_s`).

use super::steps::Runner;
use super::{Error, LoadedSpec, Result, RunOptions};
use crate::experiment::backend::Eval;
use crate::experiment::columns::NamedRow;
use crate::experiment::methods::{Answer, Method, MethodContext, NoRays};
use crate::experiment::metrics::rms_unquantised;
use crate::experiment::progress::{stage, stage_adaptive};
use crate::experiment::spec::{Backend, Spec};
use crate::render::estimator::Points;
use crate::sampling::rays::RaySet;

/// The spec's method settings this run evaluates: those this build cannot run are skipped,
/// saying why, or refused where `opts.require_embree` asks for every one.
pub(super) fn runnable(ls: &LoadedSpec, spec: &Spec, opts: &RunOptions) -> Result<Vec<bool>> {
    let settings = crate::experiment::methods::settings_of(spec);
    let mut out = Vec::with_capacity(settings.len());
    for s in &settings {
        match s.method.unavailable() {
            None => out.push(true),
            Some(why) if opts.require_embree => {
                return Err(Error::invalid(
                    format!("{}: methods \"{}\"", ls.path.display(), s.method.name()),
                    format!("{why}; --require-embree refuses to run without it"),
                ))
            }
            Some(why) => {
                println!(
                    "SKIPPED method \"{}\" of {}: {why}; --require-embree fails instead",
                    s.label(),
                    ls.name
                );
                out.push(false);
            }
        }
    }
    Ok(out)
}

impl Runner<'_> {
    /// Setting `setting` of the spec's methods on scene `scene`: its precompute, its values on
    /// every seed, its errors and images, its row.
    pub(super) fn method(&mut self, scene: usize, setting: usize) -> Result<()> {
        if !self.method_runs[setting] {
            return Ok(());
        }
        self.scene(scene);
        let backend = self.methods[setting].backend;
        // A method the device cannot run (ray queries the adapter lacks): skipped, saying why,
        // once for the run.
        if let Some(ctx) = (backend == Backend::Gpu)
            .then(|| self.backends[&backend].gpu_context())
            .flatten()
        {
            if let Some(why) = self.methods[setting].method.unavailable_on_gpu(ctx) {
                let label = self.methods[setting].label();
                println!("SKIPPED method \"{label}\": {why}");
                self.skipped_methods
                    .push(serde_json::json!({"method": label, "why": why}));
                self.method_runs[setting] = false;
                return Ok(());
            }
        }
        let m: &dyn Method = self.methods[setting].method.as_ref();
        let bs = &self.scenes.scenes[scene];
        let st = self.states[scene].as_ref().expect("scene state");
        let id = format!("{}-{}", bs.name, self.methods[setting].label());
        let ctx = MethodContext {
            scene: bs,
            triangles: &st.triangles,
            estimator: st.estimator.as_ref(),
            cache: self.opts.supply.cache.clone(),
            memory_limit: self.opts.supply.memory_limit,
        };
        let context = |e: Error| e.context(format!("method {id}"));
        if let Some(why) = self.methods[setting].refuses(self.kind.as_ref()) {
            return Err(Error::invalid(format!("methods \"{}\"", m.name()), why));
        }
        let (prepared, precompute_s) = stage(&format!("{id}: precompute"), || m.prepare(&ctx));
        let prepared = prepared.map_err(context)?;
        if let Answer::Direct(e) = &prepared.answer {
            if e.channels() != st.channels {
                return Err(Error::invalid(
                    format!("methods \"{}\"", m.name()),
                    format!(
                        "its estimator \"{}\" gives {} values per point, render \"{}\" {}",
                        e.name(),
                        e.channels(),
                        self.kind.name(),
                        st.channels
                    ),
                ));
            }
        }
        // On the GPU: the prepared method's kernels, uploaded once.
        let be = match backend {
            Backend::Cpu => &self.cpu as &dyn crate::experiment::backend::ComputeBackend,
            b => self.backends[&b].as_ref(),
        };
        let gpu: Option<Box<dyn Eval + '_>> = match backend {
            Backend::Cpu => None,
            Backend::Gpu => {
                let device = be.gpu_context().expect("the gpu backend has a device");
                let kernels = prepared.gpu.as_ref().ok_or_else(|| {
                    Error::invalid(
                        format!("methods \"{}\"", m.name()),
                        format!("prepared no GPU kernel for render \"{}\"", self.kind.name()),
                    )
                })?;
                Some(kernels.upload(device, st.gpu.as_deref()).map_err(context)?)
            }
        };
        let kernel_s = std::cell::Cell::new(None::<f64>);
        let estimate = |at: Points, rays: &RaySet| -> Result<Vec<f32>> {
            Ok(match (&gpu, &prepared.answer) {
                (Some(g), _) => {
                    let e = g.estimate(at, rays)?;
                    if let Some(k) = e.kernel_s {
                        kernel_s.set(Some(kernel_s.get().map_or(k, |b: f64| b.min(k))));
                    }
                    e.values
                }
                (None, Answer::Rays(v)) => st.estimator.estimate(v.as_ref(), at, rays),
                (None, Answer::Direct(e)) => e.estimate(&NoRays, at, rays),
            })
        };
        let (short, reps) = (self.opts.short_stage_s, self.opts.repeats);
        let k = self.plan.render_k;
        let rays = RaySet::new(k, self.spec.reference.seed);
        let (first, estimate_s, _) =
            stage_adaptive(&format!("{id}: estimate"), short, reps, || {
                estimate(st.at(), &rays).map_err(context)
            })?;
        let estimate_kernel_s = kernel_s.get();
        let mut values = vec![first];
        for &sd in &self.seeds()[1..] {
            values.push(estimate(st.at(), &RaySet::new(k, sd)).map_err(context)?);
        }
        let setup_s = gpu.as_ref().and_then(|g| g.setup_s());
        drop(gpu);
        let img = st.image(bs, &values[0]);
        let (errors, flips) = self.measure(st, bs, &values, img.as_ref().map(|(i, _)| i));
        let image = self.write_images(&id, img.as_ref(), st, &flips)?;
        if let Some(shaded) = st.shaded_image(bs, &values[0]) {
            let p = self.opts.out.join(format!("images/{id}-shaded.png"));
            shaded.save_png(&p).map_err(Error::io(&p))?;
        }
        let rays_cast = st.at.len() as u64 * self.kind.rays_cast_per_point();
        let mut row = NamedRow::new();
        // The cell: scene, method and its parameters, backend.
        row.push("scene", &bs.name)
            .push("method", m.name())
            .push("setting", m.id());
        for (name, value) in m.params() {
            row.push(name, value);
        }
        row.push("backend", backend.name())
            .push("adapter", be.adapter())
            .push("rays_per_point", self.kind.rays_per_point())
            .push("rays_cast", rays_cast)
            .push("points", st.at.len())
            .push("crease_points", st.at.crease_count())
            .push(
                "points_in_spheres",
                st.in_spheres.iter().filter(|&&b| b).count(),
            )
            .push("caster_triangles", bs.caster_triangles());
        // The method: its precompute and what it keeps.
        row.push(
            "through",
            match prepared.answer {
                Answer::Rays(_) => "rays",
                Answer::Direct(_) => "direct",
            },
        )
        .push("precompute_s", precompute_s)
        .push("precompute_cached", prepared.cached)
        .push_opt("bytes", prepared.bytes);
        for (name, value) in &prepared.columns {
            row.push(name.clone(), value);
        }
        // The times (on the GPU also the upload and compile, and the kernels alone).
        if backend == Backend::Gpu {
            row.push_opt("setup_s", setup_s);
        }
        row.push("estimate_s", estimate_s).push_opt(
            "estimate_mrays_s",
            (estimate_s > 0.0).then(|| rays_cast as f64 / estimate_s / 1e6),
        );
        if backend == Backend::Gpu {
            row.push_opt("estimate_kernel_s", estimate_kernel_s);
        }
        // The metrics, the same as the field cells'.
        errors.push_to(&mut row);
        row.push("rms_vs_raycast", rms_unquantised(&values[0], &st.reference))
            .push("image", image);
        // The kind's own metrics, as in `table.csv`.
        for (name, v) in self.own_metrics(st, &values[0]) {
            row.push(name, v);
        }
        self.method_rows.push(row);
        Ok(())
    }
}
