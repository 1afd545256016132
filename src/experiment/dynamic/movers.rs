//! The methods of a moving scene, each charged for what a frame's motion costs it
//! ([`Mover::update`]) apart from the query on the frame's rays ([`timed`]): `experiment
//! dynamic`'s crowd and every animated spec measure them the same way. The seam
//! (`methods::motion`) and the ray casters' per-frame forms live beside their still methods
//! (`methods::raycast`, `methods::two_level`, `methods::embree`); here, the fields' and the
//! per-object peers', and the lists a run draws from.

use crate::aofield::{AoField, AoFieldInstance, AoFieldScene};
use crate::field::lookup::LookupOptions;
use crate::field::normals::NormalField;
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::sphere_bvh::SphereBvhScene;
use crate::field::VisibilityField;
use crate::geometry::{Mesh, Sphere};
use crate::render::ao::AoOptions;
use crate::sampling::rays::RaySet;
use crate::sdf::{DistanceVolume, SdfInstance, SdfScene, SdfTrace};
use crate::visibility::Visibility;
use glam::Vec3;
use std::sync::Arc;

#[cfg(feature = "embree")]
pub use crate::experiment::methods::embree::{EmbreeInstanced, EmbreeRebuild};
use crate::experiment::methods::motion;
pub use crate::experiment::methods::motion::{timed, FrameCasters, Mover, Timed, MIN_TIMED_S};
pub use crate::experiment::methods::raycast::WorldRebuild;
pub use crate::experiment::methods::two_level::TwoLevelRebuild;

/// Every per-frame method, in the order their rows are written: the ray casters (the world
/// rebuild first: the reference of the others), then the fields (the names a spec's
/// `animation.methods` may list, [`crate::experiment::spec::FRAME_METHODS`]).
pub use crate::experiment::spec::FRAME_METHODS as NAMES;

/// Why this build cannot run the per-frame method `name`, if it cannot (Embree's without the
/// `embree` feature): its registered method's answer ([`crate::experiment::methods::Method::frame_unavailable`]).
pub fn unavailable(name: &str) -> Option<&'static str> {
    motion::method_of(name).and_then(|m| m.frame_unavailable())
}

/// The ray casters among `names` over `meshes` (in [`NAMES`] order, the per-mesh precompute
/// of the two-level and instanced ones done), each a registered method's CPU form that this
/// build runs; the world rebuild always, first.
pub fn ray_casters(
    meshes: &[Arc<Mesh>],
    names: &[&str],
) -> crate::experiment::Result<Vec<Box<dyn Mover>>> {
    let mut v = Vec::new();
    for name in NAMES {
        if name != "world_rebuild" && !names.contains(&name) {
            continue;
        }
        if let Some(m) = motion::method_of(name).filter(|m| m.frame_unavailable().is_none()) {
            v.push(m.mover(name, meshes)?);
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
