//! The runner's ground truth: the converged reference of each scene (cached like fields), the
//! same-ray references on every seed, and the errors of a cell across seeds.

use super::state::{mean_sd, SceneState};
use super::steps::Runner;
use crate::experiment::backend::{Casters, ComputeBackend};
use crate::experiment::kinds::Kind;
use crate::experiment::meta::portable_path;
use crate::experiment::metrics::{rms_u8, rms_unquantised};
use crate::experiment::progress::stage;
use crate::experiment::truth_cache::{load_or_compute, TruthInputs, TruthOutcome};
use crate::experiment::{Error, Result};
use crate::render::image::Image;
use crate::render::truth::TruthOptions;
use crate::sampling::rays::RaySet;

/// A cell's RMS columns over its seeds: (mean, standard deviation) each.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct SeedErrors {
    pub(super) vertex: Option<(f64, Option<f64>)>,
    pub(super) image: Option<(f64, Option<f64>)>,
    pub(super) truth: Option<(f64, Option<f64>)>,
    /// Mean over seeds of the RMS against the truth at crease and at interior points.
    pub(super) crease: Option<f64>,
    /// The same over the points inside some caster's bounding sphere, and over the others.
    pub(super) in_spheres: Option<f64>,
    pub(super) outside_spheres: Option<f64>,
    pub(super) interior: Option<f64>,
    /// Mean over seeds of the same-ray RMS of the shaded images ([`SceneState::shaded_image`]).
    pub(super) shaded: Option<f64>,
}

/// The converged reference's options of `spec` (`reference.truth`).
pub(super) fn truth_options(spec: &crate::experiment::spec::Spec) -> TruthOptions {
    let t = &spec.reference.truth;
    TruthOptions {
        target_stderr_255: t.target_stderr,
        max_rays: t.max_rays,
        batches: t.batches,
        ..TruthOptions::default()
    }
}

impl Runner<'_> {
    /// The seeds of every cell: `seed`, `seed + 1`, … (`reference.seeds` of them).
    pub(super) fn seeds(&self) -> Vec<u64> {
        let r = &self.spec.reference;
        (0..r.seeds as u64)
            .map(|i| r.seed.wrapping_add(i))
            .collect()
    }

    /// The converged reference of scene `scene`, from the cache or computed.
    pub(super) fn truth(&mut self, scene: usize) -> Result<()> {
        let topts = truth_options(self.spec);
        let cache = self.opts.supply.cache.clone();
        let out = self.opts.out.clone();
        let scenes = self.scenes;
        let bs = &scenes.scenes[scene];
        let st = self.scene(scene);
        let msg = format!(
            "{}: converged reference (≤ {} rays/point)",
            bs.name, topts.max_rays
        );
        let (res, s) = stage(&msg, || {
            let inputs = TruthInputs {
                estimator: st.estimator.as_ref(),
                tracer: &st.tracer,
                casters: &st.triangles,
                at: st.at(),
            };
            load_or_compute(cache.as_deref(), &bs.name, &inputs, &topts)
        });
        let (truth, outcome) = res?;
        let source = match &outcome {
            TruthOutcome::Hit(p) => format!("cache {}", portable_path(p)),
            TruthOutcome::Computed { rejected, .. } => {
                if let Some(r) = rejected {
                    eprintln!("  truth cache file rejected ({r}); recomputed");
                }
                format!("computed in {s:.1} s")
            }
        };
        eprintln!(
            "  {}: truth {} rays/point, RMS stderr {:.3}, max {:.3} (0–255){}; {source}",
            bs.name,
            truth.rays_per_point,
            truth.rms_stderr_255(),
            truth.max_stderr_255(),
            if truth.converged(&topts) {
                ""
            } else {
                " (cap reached before the target)"
            }
        );
        st.truth_source = source;
        st.truth_image = st.image(bs, &truth.values).map(|(img, _)| img);
        if let Some(img) = &st.truth_image {
            let p = out.join(format!("images/{}-truth.png", bs.name));
            img.save_png(&p).map_err(Error::io(&p))?;
        }
        st.truth = Some(truth);
        Ok(())
    }

    /// The same-ray reference on the seeds after the first, and every seed's reference against
    /// the truth.
    pub(super) fn seed_references(&mut self, scene: usize, k: u32) -> Result<()> {
        let seeds = self.seeds();
        let bs = &self.scenes.scenes[scene];
        let st = self.states[scene].as_mut().expect("scene state");
        let casters = Casters {
            triangles: &st.triangles,
            tracer: &st.tracer,
        };
        let mut refs = Vec::new();
        for &sd in &seeds[1..] {
            let rays = RaySet::new(k, sd);
            let values = self
                .cpu
                .raycast_estimate(&casters, st.quantity(), st.at(), &rays)?;
            let img = st.image(bs, &values).map(|(i, _)| i);
            let shaded = st.shaded_image(bs, &values);
            refs.push((values, img, shaded));
        }
        st.seed_refs = refs;
        let mut vs = Vec::new();
        for v in std::iter::once(&st.reference).chain(st.seed_refs.iter().map(|(a, ..)| a)) {
            if let Some(e) = st.truth_errors(v) {
                vs.push(e.all);
            }
        }
        st.reference_vs_truth = vs;
        Ok(())
    }
}

/// The ray-cast estimate of `k²` rays on every seed after the first (untimed), against the
/// truth: the RMS per seed, `first` (the timed seed's values) included.
pub(super) fn raycast_truth_errors(
    be: &dyn ComputeBackend,
    st: &SceneState,
    k: u32,
    seeds: &[u64],
    first: &[f32],
) -> Result<Vec<f64>> {
    let Some(e) = st.truth_errors(first) else {
        return Ok(Vec::new());
    };
    let mut out = vec![e.all];
    let casters = Casters {
        triangles: &st.triangles,
        tracer: &st.tracer,
    };
    for &sd in &seeds[1..] {
        let rays = RaySet::new(k, sd);
        let values = be.raycast_estimate(&casters, st.quantity(), st.at(), &rays)?;
        out.extend(st.truth_errors(&values).map(|e| e.all));
    }
    Ok(out)
}

/// The errors of a cell's values on every seed (`values[j]` on seed j, `first_image` the image of
/// seed 0's values), against the same-ray reference of that seed (the kind's metric columns)
/// and against the truth.
pub(super) fn seed_errors(
    kind: &dyn Kind,
    st: &SceneState,
    bs: &crate::experiment::scenes::BuiltScene,
    values: &[Vec<f32>],
    first_image: Option<&Image>,
) -> SeedErrors {
    let (mut v, mut im, mut t, mut c, mut i) = (vec![], vec![], vec![], vec![], vec![]);
    let (mut ins, mut outs, mut shaded) = (vec![], vec![], vec![]);
    for (j, vals) in values.iter().enumerate() {
        let (reference, ref_img, ref_shaded) = if j == 0 {
            (
                &st.reference,
                st.ref_image.as_ref().map(|(r, _)| r),
                st.ref_shaded.as_ref(),
            )
        } else {
            let (a, img, shaded) = &st.seed_refs[j - 1];
            (a, img.as_ref(), shaded.as_ref())
        };
        if kind.columns().vertex {
            v.push(rms_unquantised(vals, reference));
        }
        if let (Some(r), Some((_, mask))) = (ref_img, &st.ref_image) {
            let own;
            let img = if j == 0 {
                first_image
            } else {
                own = st.image(bs, vals).map(|(x, _)| x);
                own.as_ref()
            };
            if let Some(img) = img {
                im.push(rms_u8(&img.data, &r.data, Some(mask)));
            }
            if let Some(b) = ref_shaded {
                let a = st
                    .shaded_image(bs, vals)
                    .expect("a kind with a shaded reference");
                shaded.push(rms_u8(&a.data, &b.data, Some(mask)));
            }
        }
        if let Some(e) = st.truth_errors(vals) {
            t.push(e.all);
            c.extend(e.crease);
            i.extend(e.interior);
            ins.extend(e.in_spheres);
            outs.extend(e.outside_spheres);
        }
    }
    let ms = |x: &[f64]| (!x.is_empty()).then(|| mean_sd(x));
    SeedErrors {
        vertex: ms(&v),
        image: ms(&im),
        truth: ms(&t),
        crease: ms(&c).map(|m| m.0),
        interior: ms(&i).map(|m| m.0),
        in_spheres: ms(&ins).map(|m| m.0),
        outside_spheres: ms(&outs).map(|m| m.0),
        shaded: ms(&shaded).map(|m| m.0),
    }
}
