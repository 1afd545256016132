//! Methods that follow motion: a per-frame method ([`Mover`]) brought to each frame of a moving
//! scene by [`Mover::update`], which applies the frame's transforms ([`FrameCasters`]: Embree
//! commits its instances, the field places its instances, our two-level caster rebuilds its top
//! level, a world caster rebuilds its BVH), then answers the frame's rays; each charged for the
//! update apart from the query ([`timed`]). `experiment dynamic`'s crowd and every animated spec
//! run them the same way.
//!
//! The registry says which methods follow motion and builds their forms: a method lists its
//! per-frame forms ([`Method::frame_forms`], [`FrameForm`]: each CPU form with the GPU forms
//! measured beside it), builds its CPU forms ([`Method::mover`]) and its GPU forms
//! ([`Method::gpu_mover`]) in its own file, each over the moving scene's meshes
//! ([`MoverInputs`]; on the GPU [`GpuInputs`]). The field, a spec's `fields` axes rather than a
//! registered method, gives its forms the same way (`field.rs`, [`super::field::FIELD`]).
//! [`frame_forms`] gathers every method's at its default options for animated specs and
//! `experiment dynamic` (a method whose options have no default, `sdf` and `aofield`, is
//! given them by `experiment dynamic`, which measures them as the crowd's peers); [`movers`]
//! and [`gpu_movers`] build the forms a run names; [`gpu_twins`] pairs each CPU form with the
//! GPU forms beside it.

use super::field::MeshFields;
use super::Method;
use crate::experiment::backend_gpu::GpuQuantity;
use crate::experiment::spec::Backend;
use crate::experiment::Result;
use crate::geometry::{Mesh, Similarity, Sphere};
use crate::gpu::GpuContext;
use crate::render::ao::{ao_at_points, AoOptions};
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use crate::visibility::Visibility;
use glam::Vec3;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// A method answering visibility in a moving scene.
pub trait Mover {
    fn name(&self) -> &'static str;
    /// Brings the method to this frame (timed apart as `update_s`).
    fn update(&mut self, frame: &FrameCasters) -> Result<()>;
    /// The frame's visibility (after [`Self::update`]); by default [`super::NoRays`], for a
    /// method that answers without casting rays through it (its own [`Self::ao`] or
    /// [`Self::estimate`]).
    fn vis(&self) -> &dyn Visibility {
        &super::NoRays
    }
    /// Bytes kept for the scene, where known (by default not).
    fn bytes(&self) -> Option<u64> {
        None
    }
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
pub fn model_triangles(meshes: &[Arc<Mesh>]) -> super::ModelTriangles {
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

/// `bake` of each of `on`'s meshes (a form's per-mesh precompute: a volume, a field), an error
/// naming the method's setting and the mesh.
pub fn per_mesh<T>(
    method: &dyn Method,
    on: &MoverInputs,
    bake: impl Fn(&Mesh) -> std::result::Result<T, String>,
) -> Result<Vec<T>> {
    (on.meshes.iter())
        .map(|mesh| {
            bake(mesh).map_err(|e| {
                let at = format!("per-frame method {}: mesh {}", method.id(), mesh.name);
                crate::experiment::Error::invalid(at, e)
            })
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
    /// It reads the field (the field's forms): built once per field cell of an animated spec,
    /// over the cell's fields ([`MoverInputs::fields`]); the others once per scene.
    pub reads_field: bool,
}

impl FrameForm {
    /// A CPU form.
    pub const fn cpu(name: &'static str) -> FrameForm {
        FrameForm {
            name,
            backend: Backend::Cpu,
            beside: name,
            reads_field: false,
        }
    }

    /// A GPU form run beside the CPU form `beside`.
    pub const fn gpu(name: &'static str, beside: &'static str) -> FrameForm {
        FrameForm {
            name,
            backend: Backend::Gpu,
            beside,
            reads_field: false,
        }
    }

    /// This form, reading the field.
    pub const fn reading_field(self) -> FrameForm {
        FrameForm {
            reads_field: true,
            ..self
        }
    }
}

/// What a method's per-frame forms are built over, before the frames.
pub struct MoverInputs<'a> {
    /// The moving scene's distinct caster meshes (a frame's [`FrameCasters::meshes`]).
    pub meshes: &'a [Arc<Mesh>],
    /// The run's cache folder, for a form that bakes per mesh (none: no cache).
    pub cache: Option<&'a Path>,
    /// The field's per-mesh fields (a field cell's, the crowd's): where given, [`movers`] and
    /// [`gpu_movers`] build the forms that read them, and only those.
    pub fields: Option<&'a MeshFields>,
}

/// What a GPU form is built with, beside its [`MoverInputs`].
pub struct GpuInputs<'a> {
    pub ctx: &'a GpuContext,
    /// The kind's GPU kernels (its integrand on a visibility, its field kernel).
    pub kernels: &'a dyn GpuQuantity,
    /// The first frame's instances, each (mesh, transform): where a form that uploads its
    /// placements starts.
    pub first: &'a [(usize, Similarity)],
}

/// A GPU form built over a moving scene ([`Method::gpu_mover`]), or why this scene cannot run
/// it (a world past one storage binding of the adapter).
pub type GpuMover<'a> = std::result::Result<Box<dyn Mover + 'a>, String>;

/// Every per-frame form with its method: the registered methods' at their default options (in
/// registry order), then the field's.
pub fn frame_forms() -> Vec<(FrameForm, Arc<dyn Method>)> {
    let mut methods: Vec<Arc<dyn Method>> = (super::default_settings().into_iter())
        .map(Arc::from)
        .collect();
    methods.push(Arc::new(super::field::FIELD));
    (methods.iter())
        .flat_map(|m| m.frame_forms().iter().map(move |&f| (f, m.clone())))
        .collect()
}

/// The per-frame form named `name` and its method, if any.
pub fn form(name: &str) -> Option<(FrameForm, Arc<dyn Method>)> {
    frame_forms().into_iter().find(|(f, _)| f.name == name)
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

/// The forms among `names` on `backend` (in that order) that this build runs and `on` builds:
/// those that read the field where it has one, the others where it has none.
fn named(names: &[&str], backend: Backend, on: &MoverInputs) -> Vec<(FrameForm, Arc<dyn Method>)> {
    let forms = frame_forms();
    (names.iter())
        .filter_map(|n| forms.iter().find(|(f, _)| f.name == *n).cloned())
        .filter(|(f, m)| {
            f.backend == backend
                && f.reads_field == on.fields.is_some()
                && m.frame_unavailable().is_none()
        })
        .collect()
}

/// The CPU forms among `names` over `on` ([`Method::mover`]; see `named`).
pub fn movers(names: &[&str], on: &MoverInputs) -> Result<Vec<Box<dyn Mover>>> {
    (named(names, Backend::Cpu, on).iter())
        .map(|(f, m)| m.mover(f.name, on))
        .collect()
}

/// The GPU forms among `names` over `on` ([`Method::gpu_mover`]; see `named`), each named.
pub fn gpu_movers<'a>(
    names: &[&str],
    on: &MoverInputs,
    gpu: &GpuInputs<'a>,
) -> Result<Vec<(&'static str, GpuMover<'a>)>> {
    (named(names, Backend::Gpu, on).iter())
        .map(|(f, m)| Ok((f.name, m.gpu_mover(f.name, on, gpu)?)))
        .collect()
}

/// A frame's overlap counts: caster pairs whose world bounding spheres overlap, and points
/// inside the sphere of some caster other than their own (`owner`: the caster a point belongs
/// to, if any: a caster's own points always lie in its sphere, the intra-object case). Where
/// the papers' "non-penetrating" assumption stops holding. `spheres`: each caster's
/// (instance, world sphere); an overlap is a distance strictly below the sum of the radii.
pub fn overlaps(
    spheres: &[(usize, Sphere)],
    points: &[Vec3],
    owner: impl Fn(usize) -> Option<usize> + Sync,
) -> (usize, usize) {
    use rayon::prelude::*;
    let mut pairs = 0;
    for (i, (_, a)) in spheres.iter().enumerate() {
        for (_, b) in &spheres[i + 1..] {
            if a.center.distance(b.center) < a.radius + b.radius {
                pairs += 1;
            }
        }
    }
    let inside = (0..points.len())
        .into_par_iter()
        .filter(|&j| {
            let p = points[j];
            spheres
                .iter()
                .any(|(inst, s)| owner(j) != Some(*inst) && p.distance(s.center) < s.radius)
        })
        .count();
    (pairs, inside)
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
        assert_eq!(form("embree_instances").unwrap().1.name(), "embree");
        assert_eq!(form("field@gpu").unwrap().1.name(), "field");
        assert!(form("field").unwrap().0.reads_field && !form("two_level").unwrap().0.reads_field);
    }
}
