//! The other ray casters of a spec (`"raycasters": ["embree"]`): timed on the CPU reference's
//! rays, points and estimator, right after it, so that each CPU row carries Embree's time
//! (`embree_s`, `embree_mrays_s`) beside ours (`raycast_s`) and the field's (`ao_s`), and how
//! far Embree's estimate is from ours on those rays (`embree_rms_vs_raycast`, 0–255).
//!
//! A build without the `embree` feature leaves the columns empty and says so once per spec,
//! as `check` does for "gpu" rows without an adapter; `--require-embree` makes that an error.

use super::steps::Runner;
use super::{Error, LoadedSpec, Result, RunOptions};
use crate::experiment::spec::{Raycaster, Spec};

/// Whether this run times Embree: the spec asks for it and the build has it. Without the
/// feature: an error naming the spec field if `opts.require_embree`, else a printed note.
pub(super) fn embree_enabled(ls: &LoadedSpec, spec: &Spec, opts: &RunOptions) -> Result<bool> {
    if !spec.raycasters.contains(&Raycaster::Embree) {
        return Ok(false);
    }
    if cfg!(feature = "embree") {
        return Ok(true);
    }
    let why = "this build has no Embree (build with --features embree; needs libembree-dev)";
    if opts.require_embree {
        return Err(Error::invalid(
            format!("{}: raycasters [\"embree\"]", ls.path.display()),
            format!("{why}; --require-embree refuses to run without it"),
        ));
    }
    println!(
        "SKIPPED the Embree columns of {}: {why}; --require-embree fails instead",
        ls.name
    );
    Ok(false)
}

impl Runner<'_> {
    /// Embree on the reference's rays of scene `scene` (k² per point, the reference seed):
    /// its time and its estimate's RMS against the reference's, kept in the scene state.
    #[cfg(feature = "embree")]
    pub(super) fn embree_reference(&mut self, scene: usize, k: u32) -> Result<()> {
        use crate::experiment::metrics::rms_unquantised;
        use crate::experiment::progress::{stage, stage_adaptive};
        use crate::sampling::rays::RaySet;
        use crate::trace::embree::EmbreeTracer;
        let (short, reps) = (self.opts.short_stage_s, self.opts.repeats);
        let seed = self.spec.reference.seed;
        let name = &self.scenes.scenes[scene].name;
        let st = self.states[scene].as_mut().expect("scene state");
        let (tracer, _) = stage(&format!("{name}: Embree BVH"), || {
            EmbreeTracer::new(&st.triangles)
        });
        let tracer = tracer.map_err(|e| {
            Error::invalid(
                format!("scene {name}: raycasters [\"embree\"]"),
                e.to_string(),
            )
        })?;
        let rays = RaySet::new(k, seed);
        let msg = format!("{name}: Embree ray cast, {} rays", k * k);
        let est = st.estimator.as_ref();
        let (values, s, _) = stage_adaptive(&msg, short, reps, || {
            Ok::<_, Error>(est.estimate(&tracer, st.at(), &rays))
        })?;
        st.embree = Some((s, rms_unquantised(&values, &st.reference)));
        Ok(())
    }

    /// Never called: [`embree_enabled`] is false in a build without Embree.
    #[cfg(not(feature = "embree"))]
    pub(super) fn embree_reference(&mut self, _scene: usize, _k: u32) -> Result<()> {
        Err(Error::invalid(
            "raycasters [\"embree\"]",
            "this build has no Embree (build with --features embree)",
        ))
    }
}
