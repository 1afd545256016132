//! The methods of a moving scene, each charged for what a frame's motion costs it
//! ([`Mover::update`]) apart from the query on the frame's rays ([`timed`]): `experiment
//! dynamic`'s crowd and every animated spec measure them the same way.

use crate::aofield::{AoField, AoFieldInstance, AoFieldScene};
use crate::field::lookup::LookupOptions;
use crate::field::normals::NormalField;
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::sphere_bvh::SphereBvhScene;
use crate::field::VisibilityField;
use crate::geometry::{Mesh, Similarity, Sphere};
use crate::render::ao::{ao_at_points, AoOptions};
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use crate::sdf::{DistanceVolume, SdfInstance, SdfScene, SdfTrace};
use crate::trace::Tracer;
use crate::visibility::Visibility;
use glam::Vec3;
use std::sync::Arc;
use std::time::Instant;

/// Every per-frame method, in the order their rows are written: the ray casters (the world
/// rebuild first: the reference of the others), then the fields (the names a spec's
/// `animation.methods` may list, [`crate::experiment::spec::FRAME_METHODS`]).
pub use crate::experiment::spec::FRAME_METHODS as NAMES;

/// Why this build cannot run the method `name`, if it cannot (Embree's without the `embree`
/// feature).
pub fn unavailable(name: &str) -> Option<&'static str> {
    (name.starts_with("embree") && !cfg!(feature = "embree"))
        .then_some("this build lacks the `embree` feature (cargo build --features embree)")
}

/// The ray casters among `names` over `meshes` (in [`NAMES`] order, the per-mesh precompute
/// of the two-level and instanced ones done), each that this build runs; the world rebuild
/// always, first.
pub fn ray_casters(
    meshes: &[Arc<Mesh>],
    names: &[&str],
) -> crate::experiment::Result<Vec<Box<dyn Mover>>> {
    let mut v: Vec<Box<dyn Mover>> = vec![Box::<WorldRebuild>::default()];
    if names.contains(&"two_level") {
        v.push(Box::new(TwoLevelRebuild::new(meshes)));
    }
    #[cfg(feature = "embree")]
    {
        if names.contains(&"embree_rebuild") {
            v.push(Box::<EmbreeRebuild>::default());
        }
        if names.contains(&"embree_instances") {
            v.push(Box::new(EmbreeInstanced::new(meshes)?));
        }
    }
    Ok(v)
}

/// The field methods among `names` on one field per mesh (with its normal field, for a kind
/// that reads them), testing every sphere and with the sphere BVH, in [`NAMES`] order.
pub fn field_methods(
    fields: &[Arc<VisibilityField>],
    normals: &[Option<Arc<NormalField>>],
    options: LookupOptions,
    names: &[&str],
) -> Vec<Box<dyn Mover>> {
    [(false, "field_every_sphere"), (true, "field")]
        .into_iter()
        .filter(|(_, n)| names.contains(n))
        .map(|(bvh, _)| {
            let mut f = Fields::new(fields.to_vec(), options, bvh);
            f.normals = normals.to_vec();
            Box::new(f) as Box<dyn Mover>
        })
        .collect()
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
    query: impl Fn(&dyn Mover) -> crate::experiment::Result<Vec<f32>>,
) -> crate::experiment::Result<Timed> {
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

/// The field instances of a frame: each instance's field (one per mesh, and its normal field
/// where the kind reads them) placed by its transform.
pub fn field_instances(
    fields: &[Arc<VisibilityField>],
    normals: &[Option<Arc<NormalField>>],
    frame: &FrameCasters,
) -> Vec<FieldInstance> {
    frame
        .instances
        .iter()
        .map(|&(m, t)| {
            let f = FieldInstance::new(fields[m].clone(), t);
            match normals.get(m).cloned().flatten() {
                Some(n) => f.with_normals(n),
                None => f,
            }
        })
        .collect()
}

/// A method answering visibility in a moving scene.
pub trait Mover {
    fn name(&self) -> &'static str;
    /// Brings the method to this frame (timed apart as `update_s`).
    fn update(&mut self, frame: &FrameCasters) -> crate::experiment::Result<()>;
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
    fn estimate(
        &self,
        est: &dyn Estimator,
        at: Points,
        rays: &RaySet,
    ) -> crate::experiment::Result<Vec<f32>> {
        Ok(est.estimate(self.vis(), at, rays))
    }
}

/// Our ray caster over the world triangles, its BVH rebuilt every frame.
#[derive(Default)]
pub struct WorldRebuild {
    tracer: Option<Tracer>,
}

impl Mover for WorldRebuild {
    fn name(&self) -> &'static str {
        "world_rebuild"
    }

    fn update(&mut self, frame: &FrameCasters) -> crate::experiment::Result<()> {
        self.tracer = Some(Tracer::new(&frame.world_triangles()));
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        self.tracer.as_ref().expect("updated before the query")
    }

    fn bytes(&self) -> Option<u64> {
        self.tracer.as_ref().map(Tracer::bytes)
    }
}

/// Embree's scene over the world triangles, built and committed every frame.
#[cfg(feature = "embree")]
#[derive(Default)]
pub struct EmbreeRebuild {
    tracer: Option<crate::trace::embree::EmbreeTracer>,
}

#[cfg(feature = "embree")]
impl Mover for EmbreeRebuild {
    fn name(&self) -> &'static str {
        "embree_rebuild"
    }

    fn update(&mut self, frame: &FrameCasters) -> crate::experiment::Result<()> {
        let t = crate::trace::embree::EmbreeTracer::new(&frame.world_triangles()).map_err(|e| {
            crate::experiment::Error::invalid("dynamic: embree_rebuild", e.to_string())
        })?;
        self.tracer = Some(t);
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        self.tracer.as_ref().expect("updated before the query")
    }

    fn bytes(&self) -> Option<u64> {
        None
    }
}

/// Embree with instance geometries: each mesh's scene built once (the crowd's precompute), the
/// transforms set and the top scene committed every frame.
#[cfg(feature = "embree")]
pub struct EmbreeInstanced {
    pub tracer: crate::trace::embree_instances::EmbreeInstances,
}

#[cfg(feature = "embree")]
impl EmbreeInstanced {
    pub fn new(meshes: &[Arc<Mesh>]) -> crate::experiment::Result<EmbreeInstanced> {
        let tracer = crate::trace::embree_instances::EmbreeInstances::new(&model_triangles(meshes))
            .map_err(|e| {
                crate::experiment::Error::invalid("dynamic: embree_instances", e.to_string())
            })?;
        Ok(EmbreeInstanced { tracer })
    }
}

#[cfg(feature = "embree")]
impl Mover for EmbreeInstanced {
    fn name(&self) -> &'static str {
        "embree_instances"
    }

    fn update(&mut self, frame: &FrameCasters) -> crate::experiment::Result<()> {
        self.tracer.update(frame.instances).map_err(|e| {
            crate::experiment::Error::invalid("dynamic: embree_instances", e.to_string())
        })
    }

    fn vis(&self) -> &dyn Visibility {
        &self.tracer
    }

    fn bytes(&self) -> Option<u64> {
        None
    }
}

/// Each mesh's triangles in model space.
fn model_triangles(meshes: &[Arc<Mesh>]) -> Vec<Vec<[Vec3; 3]>> {
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

/// Our ray caster in two levels: each mesh's BVH built once in model space (the crowd's
/// precompute), the top level over the instances rebuilt every frame.
pub struct TwoLevelRebuild {
    pub tracer: crate::trace::two_level::TwoLevel,
}

impl TwoLevelRebuild {
    pub fn new(meshes: &[Arc<Mesh>]) -> TwoLevelRebuild {
        TwoLevelRebuild {
            tracer: crate::trace::two_level::TwoLevel::new(&model_triangles(meshes)),
        }
    }
}

impl Mover for TwoLevelRebuild {
    fn name(&self) -> &'static str {
        "two_level"
    }

    fn update(&mut self, frame: &FrameCasters) -> crate::experiment::Result<()> {
        self.tracer.update(frame.instances);
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        &self.tracer
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.tracer.bytes())
    }
}

/// The casters' fields (one per mesh, shared by its instances) placed by the frame's
/// transforms; nothing is rebuilt but, with `sphere_bvh`, the BVH over the instances' bounding
/// spheres ([`SphereBvhScene`]; without it every ray tests every sphere, as 2008 Algorithm 2).
pub struct Fields {
    /// Per mesh, its field.
    pub fields: Vec<Arc<VisibilityField>>,
    /// Per mesh, its normal field (reflections read them; empty or `None`: none).
    pub normals: Vec<Option<Arc<NormalField>>>,
    pub options: LookupOptions,
    pub sphere_bvh: bool,
    /// The frame's scene: without the tree, or with it.
    plain: FieldScene,
    tree: SphereBvhScene,
}

impl Fields {
    pub fn new(
        fields: Vec<Arc<VisibilityField>>,
        options: LookupOptions,
        sphere_bvh: bool,
    ) -> Fields {
        Fields {
            fields,
            normals: Vec::new(),
            options,
            sphere_bvh,
            plain: FieldScene::default(),
            tree: SphereBvhScene::default(),
        }
    }
}

impl Mover for Fields {
    fn name(&self) -> &'static str {
        if self.sphere_bvh {
            "field"
        } else {
            "field_every_sphere"
        }
    }

    fn update(&mut self, frame: &FrameCasters) -> crate::experiment::Result<()> {
        let scene = FieldScene {
            instances: field_instances(&self.fields, &self.normals, frame),
            options: self.options,
        };
        if self.sphere_bvh {
            self.tree = SphereBvhScene::new(scene);
        } else {
            self.plain = scene;
        }
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        if self.sphere_bvh {
            &self.tree
        } else {
            &self.plain
        }
    }

    fn bytes(&self) -> Option<u64> {
        let normals: u64 = self.normals.iter().flatten().map(|n| n.bytes()).sum();
        Some(self.fields.iter().map(|f| f.bytes()).sum::<u64>() + normals + self.tree.bvh().bytes())
    }
}

/// Mesh signed distance fields as engines keep them for moving rigid objects (`crate::sdf`:
/// one volume per mesh, shared by its instances) placed by the frame's transforms and sphere
/// traced on the same rays; the update is the instance list, nothing is rebuilt. `experiment
/// dynamic`'s crowd measures it (`sdf`); animated specs do not list it.
pub struct Sdfs {
    /// Per mesh, its volume.
    pub volumes: Vec<Arc<DistanceVolume>>,
    scene: SdfScene,
}

impl Sdfs {
    pub fn new(volumes: Vec<Arc<DistanceVolume>>) -> Sdfs {
        Sdfs {
            volumes,
            scene: SdfScene {
                instances: Vec::new(),
                trace: SdfTrace::default(),
            },
        }
    }
}

impl Mover for Sdfs {
    fn name(&self) -> &'static str {
        "sdf"
    }

    fn update(&mut self, frame: &FrameCasters) -> crate::experiment::Result<()> {
        self.scene.instances = frame.place(&self.volumes, |v, transform| SdfInstance {
            volume: v.clone(),
            transform,
        });
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        &self.scene
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.volumes.iter().map(|v| v.bytes()).sum())
    }
}

/// Ambient occlusion fields (Kontkanen and Laine, I3D 2005; `crate::aofield`: one per mesh,
/// shared by its instances) placed by the frame's transforms: AO at a point with no ray, the
/// casters blended multiplicatively ([`Mover::ao`]); the update is the instance list.
/// `experiment dynamic`'s crowd measures it (`aofield`); it answers AO only, so animated specs
/// (any kind) do not list it, and its [`Mover::vis`] refuses every ray.
pub struct AoFields {
    /// Per mesh, its field.
    pub fields: Vec<Arc<AoField>>,
    scene: AoFieldScene,
}

impl AoFields {
    pub fn new(fields: Vec<Arc<AoField>>) -> AoFields {
        AoFields {
            fields,
            scene: AoFieldScene::default(),
        }
    }
}

impl Mover for AoFields {
    fn name(&self) -> &'static str {
        "aofield"
    }

    fn update(&mut self, frame: &FrameCasters) -> crate::experiment::Result<()> {
        self.scene.instances = frame.place(&self.fields, |f, transform| AoFieldInstance {
            field: f.clone(),
            transform,
        });
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        &crate::experiment::backend::NoRays
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.fields.iter().map(|f| f.bytes()).sum())
    }

    fn ao(&self, points: &[Vec3], normals: &[Vec3], _: &RaySet, _: &AoOptions) -> Vec<f32> {
        self.scene.ao_at_points(points, normals)
    }
}
