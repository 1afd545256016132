//! Methods that follow motion: a per-frame method ([`Mover`]) brought to each frame of a moving
//! scene by [`Mover::update`], which applies the frame's transforms ([`FrameCasters`]: Embree
//! commits its instances, the field places its instances, our two-level caster rebuilds its top
//! level, a world caster rebuilds its BVH), then answers the frame's rays; each charged for the
//! update apart from the query ([`timed`]). A registered method that follows motion gives its
//! movers beside its still form (`raycast.rs`: `world_rebuild`; `two_level.rs`: `two_level`;
//! `embree.rs`: `embree_rebuild`, `embree_instances`); `experiment dynamic`'s crowd and every
//! animated spec run them the same way.

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
