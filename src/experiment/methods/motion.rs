//! Methods that follow motion: a per-frame method ([`Mover`]) brought to each frame of a moving
//! scene by [`Mover::update`], which applies the frame's transforms ([`FrameCasters`]: Embree
//! commits its instances, the field places its instances, our two-level caster rebuilds its top
//! level, a world caster rebuilds its BVH), then answers the frame's rays; each charged for the
//! update apart from the query ([`timed`]). A registered method that follows motion gives its
//! movers beside its still form (`raycast.rs`: `world_rebuild`; `two_level.rs`: `two_level`;
//! `embree.rs`: `embree_rebuild`, `embree_instances`); `experiment dynamic`'s crowd and every
//! animated spec run them the same way.
//!
//! The registry says which methods follow motion: a registered method lists its per-frame
//! forms ([`Method::frame_forms`], [`FrameForm`]: each CPU form with the GPU forms measured
//! beside it) and builds its CPU forms ([`Method::mover`]); the field, a spec's `fields` axis
//! rather than a registered method, has [`FIELD_FORMS`]. [`frame_forms`] gathers them for
//! animated specs and `experiment dynamic`, [`gpu_twins`] the GPU forms beside each CPU one.

use super::Method;
use crate::experiment::spec::Backend;
use crate::experiment::Result;
use crate::geometry::{Mesh, Similarity};
use crate::render::ao::{ao_at_points, AoOptions};
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use crate::visibility::Visibility;
use glam::Vec3;
use std::sync::Arc;
use std::time::Instant;

/// A method answering visibility in a moving scene.
pub trait Mover {
    fn name(&self) -> &'static str;
    /// Brings the method to this frame (timed apart as `update_s`).
    fn update(&mut self, frame: &FrameCasters) -> Result<()>;
    /// The frame's visibility (after [`Self::update`]).
    fn vis(&self) -> &dyn Visibility;
    /// Bytes kept for the scene, where known.
    fn bytes(&self) -> Option<u64>;
    /// Vertex AO at `points` (unit `normals`) on `rays`: the AO estimator through
    /// [`Self::vis`]; a method that answers AO with no rays (AO fields) answers it directly.
    fn ao(&self, points: &[Vec3], normals: &[Vec3], rays: &RaySet, opts: &AoOptions) -> Vec<f32> {
        ao_at_points(self.vis(), points, normals, rays, opts)
    }
    /// A render kind's estimate at `at` on `rays` (an animated spec's query): `est` through
    /// [`Self::vis`]; a method on the GPU runs its kernel instead.
    fn estimate(&self, est: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        Ok(est.estimate(self.vis(), at, rays))
    }
}

/// One frame's casters: each instance's mesh and transform.
pub struct FrameCasters<'a> {
    pub meshes: &'a [Arc<Mesh>],
    /// Per instance: its mesh (index into `meshes`) and its transform this frame.
    pub instances: &'a [(usize, Similarity)],
}

impl FrameCasters<'_> {
    /// Per instance, `make` of its mesh's entry of `per_mesh` (a field, a volume: one per mesh,
    /// shared by its instances) and its transform this frame.
    pub fn place<T, I>(&self, per_mesh: &[T], make: impl Fn(&T, Similarity) -> I) -> Vec<I> {
        (self.instances.iter())
            .map(|&(m, t)| make(&per_mesh[m], t))
            .collect()
    }

    /// Every instance's triangles moved to world space.
    pub fn world_triangles(&self) -> Vec<[Vec3; 3]> {
        let mut out = Vec::new();
        for &(m, t) in self.instances {
            let mesh = &self.meshes[m];
            out.extend(
                mesh.triangles
                    .iter()
                    .map(|tri| tri.map(|i| t.to_world_point(mesh.positions[i as usize]))),
            );
        }
        out
    }
}

/// One method on one frame: its update and its query timed apart.
pub struct Timed {
    /// Seconds of [`Mover::update`] (a mean over [`Timed::runs`]).
    pub update_s: f64,
    /// Seconds of the query (a mean over [`Timed::runs`]).
    pub query_s: f64,
    /// How many times the frame was updated and queried for the two means: 1, or more for a
    /// frame shorter than [`MIN_TIMED_S`].
    pub runs: u32,
    /// The query's values (of the first run).
    pub values: Vec<f32>,
}

/// The least wall time over which a frame is timed: a shorter frame (a few casters, a few
/// thousand rays: a fraction of a millisecond) is updated and queried again until its runs
/// add up to this, and the means are reported, so that the thread pool is awake for all of it
/// and every thread takes part, as in a long frame. Every method is timed by the same rule.
pub const MIN_TIMED_S: f64 = 0.05;

/// Brings `mover` to `frame` and answers `query` through it, each timed (all threads); a frame
/// shorter than [`MIN_TIMED_S`] is updated and queried again until the runs add up to it (at
/// most 10,000 runs), and the mean of each part is reported. Updates and queries are pure
/// functions of the frame, so the repeats answer the same values.
pub fn timed(
    mover: &mut dyn Mover,
    frame: &FrameCasters,
    query: impl Fn(&dyn Mover) -> Result<Vec<f32>>,
) -> Result<Timed> {
    let (mut update_s, mut query_s, mut runs) = (0.0, 0.0, 0u32);
    let mut values = None;
    while values.is_none() || (update_s + query_s < MIN_TIMED_S && runs < 10_000) {
        let t = Instant::now();
        mover.update(frame)?;
        update_s += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let v = query(&*mover)?;
        query_s += t.elapsed().as_secs_f64();
        runs += 1;
        values.get_or_insert(v);
    }
    Ok(Timed {
        update_s: update_s / runs as f64,
        query_s: query_s / runs as f64,
        runs,
        values: values.expect("one run at least"),
    })
}

/// Each mesh's triangles in model space.
pub fn model_triangles(meshes: &[Arc<Mesh>]) -> Vec<Vec<[Vec3; 3]>> {
    meshes
        .iter()
        .map(|m| {
            m.triangles
                .iter()
                .map(|t| t.map(|i| m.positions[i as usize]))
                .collect()
        })
        .collect()
}

/// One per-frame form of a method (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameForm {
    /// Its name: in a spec's `animation.methods` (the CPU forms) and the rows' `method`.
    pub name: &'static str,
    pub backend: Backend,
    /// The CPU form it runs beside, where that one is asked for: itself on the CPU; a GPU
    /// form's CPU twin (`rayquery@gpu` beside `two_level`).
    pub beside: &'static str,
}

impl FrameForm {
    /// A CPU form.
    pub const fn cpu(name: &'static str) -> FrameForm {
        FrameForm {
            name,
            backend: Backend::Cpu,
            beside: name,
        }
    }

    /// A GPU form run beside the CPU form `beside`.
    pub const fn gpu(name: &'static str, beside: &'static str) -> FrameForm {
        FrameForm {
            name,
            backend: Backend::Gpu,
            beside,
        }
    }
}

/// The field's per-frame forms: testing every sphere, and with the BVH over the spheres
/// (`experiment::dynamic::movers::Fields`), each with its GPU twin (`gpu_movers::GpuFields`).
pub const FIELD_FORMS: &[FrameForm] = &[
    FrameForm::cpu("field_every_sphere"),
    FrameForm::gpu("field_every_sphere@gpu", "field_every_sphere"),
    FrameForm::cpu("field"),
    FrameForm::gpu("field@gpu", "field"),
];

/// Every per-frame form: the registered methods' (in registry order, each with its method),
/// then the field's (no method).
pub fn frame_forms() -> Vec<(FrameForm, Option<Arc<dyn Method>>)> {
    let mut out: Vec<(FrameForm, Option<Arc<dyn Method>>)> = Vec::new();
    for m in super::default_settings() {
        let m: Arc<dyn Method> = Arc::from(m);
        out.extend(m.frame_forms().iter().map(|&f| (f, Some(m.clone()))));
    }
    out.extend(FIELD_FORMS.iter().map(|&f| (f, None)));
    out
}

/// The registered method whose CPU form is `name`, if any (the field's forms have none).
pub fn method_of(name: &str) -> Option<Arc<dyn Method>> {
    frame_forms()
        .into_iter()
        .find(|(f, _)| f.backend == Backend::Cpu && f.name == name)
        .and_then(|(_, m)| m)
}

/// Each CPU form among `order` with a GPU form beside it, and that form's name: for each name
/// of `order` in turn, the GPU forms beside it in registry order, the field's last.
pub fn gpu_twins(order: &[&str]) -> Vec<(&'static str, &'static str)> {
    let forms = frame_forms();
    let mut out = Vec::new();
    for &cpu in order {
        for (f, _) in &forms {
            if f.backend == Backend::Gpu && f.beside == cpu {
                out.push((f.beside, f.name));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::spec::FRAME_METHODS;

    #[test]
    fn the_registry_gives_every_frame_method_and_the_gpu_twins_in_row_order() {
        let cpu: Vec<&str> = (frame_forms().iter())
            .filter(|(f, _)| f.backend == Backend::Cpu)
            .map(|(f, _)| f.name)
            .collect();
        let mut sorted = cpu.clone();
        sorted.sort_unstable();
        let mut names = FRAME_METHODS.to_vec();
        names.sort_unstable();
        assert_eq!(sorted, names);
        assert_eq!(
            gpu_twins(&FRAME_METHODS),
            [
                ("world_rebuild", "world_rebuild@gpu"),
                ("two_level", "two_level@gpu"),
                ("two_level", "rayquery@gpu"),
                ("field_every_sphere", "field_every_sphere@gpu"),
                ("field", "field@gpu"),
            ]
        );
        assert_eq!(method_of("embree_instances").unwrap().name(), "embree");
        assert!(method_of("field").is_none());
    }
}
