//! Helpers of the AO cases: scenes from meshes and placements, ray-cast and field-lookup vertex
//! AO on them, and error measures.

use crate::field::bake::{bake, BakeOptions};
use crate::field::lookup::LookupOptions;
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::{FieldParams, Precision, VisibilityField};
use crate::geometry::rebase::{rebase, PlacedMesh, Placement, Rebased};
use crate::geometry::{Instance, Mesh, Scene, Similarity};
use crate::render::ao::{ao_at_points, AoOptions};
use crate::render::receivers::Receivers;
use crate::sampling::rays::RaySet;
use crate::sampling::{LayoutKind, SphereKind};
use crate::trace::Tracer;
use std::sync::Arc;

/// One placed mesh: (mesh, transform, caster, receiver).
pub type Placed = (Arc<Mesh>, Similarity, bool, bool);

/// A scene of placed meshes, each transform composed with `outer` (applied last) in f32, not
/// rebased.
pub fn scene(placed: &[Placed], outer: Similarity) -> Scene {
    Scene {
        instances: placed
            .iter()
            .map(|(mesh, t, caster, receiver)| Instance {
                mesh: mesh.clone(),
                transform: outer.compose(t),
                caster: *caster,
                receiver: *receiver,
            })
            .collect(),
    }
}

/// The placed meshes under the outer placement `translation + scale · p` (composed in f64),
/// rebased as the experiment runner's scenes are ([`crate::geometry::rebase`]).
pub fn rebased_scene(placed: &[Placed], scale: f32, translation: glam::DVec3) -> Rebased {
    let outer = Placement::new(glam::Quat::IDENTITY, translation, scale);
    let meshes: Vec<PlacedMesh> = placed
        .iter()
        .map(|(mesh, t, caster, receiver)| PlacedMesh {
            mesh: mesh.clone(),
            placement: outer.compose(t),
            caster: *caster,
            receiver: *receiver,
        })
        .collect();
    rebase(&meshes)
}

/// AO options of a scene: [`AoOptions::for_scene`] of its bounds.
pub fn options(scene: &Scene) -> AoOptions {
    AoOptions::for_scene(scene.bounding_sphere())
}

/// Ray-cast vertex AO at the receivers with `k²` rays per point (seed 1).
pub fn raycast_ao(scene: &Scene, k: u32) -> Vec<f32> {
    raycast_ao_with(scene, k, &options(scene))
}

/// [`raycast_ao`] with the given options.
pub fn raycast_ao_with(scene: &Scene, k: u32, opts: &AoOptions) -> Vec<f32> {
    let recv = Receivers::of(scene);
    let tracer = Tracer::new(&scene.caster_triangles());
    ao_at_points(
        &tracer,
        &recv.points,
        &recv.normals,
        &RaySet::new(k, 1),
        opts,
    )
}

/// The field parameters of the AO cases: 1090 Slater maps of 32² concentric texels, u8 (a
/// Figure 6 cell).
pub fn field_params() -> FieldParams {
    FieldParams {
        sphere: SphereKind::Slater,
        count: 1090,
        layout: LayoutKind::Concentric,
        res: 32,
        precision: Precision::U8,
    }
}

/// Bakes `mesh`'s field with [`field_params`].
pub fn bake_field(mesh: &Mesh) -> Arc<VisibilityField> {
    let (f, _) = bake(mesh, field_params(), &BakeOptions::default()).expect("field bakes");
    Arc::new(f)
}

/// The fields of the casters of `placed`, in order ([`bake_field`]).
pub fn bake_fields(placed: &[Placed]) -> Vec<Arc<VisibilityField>> {
    placed
        .iter()
        .filter(|p| p.2)
        .map(|p| bake_field(&p.0))
        .collect()
}

/// Field-lookup vertex AO at the receivers with `k²` rays per point: every caster answered by
/// its field from `fields` (same order as the scene's casters).
pub fn field_ao(scene: &Scene, fields: &[Arc<VisibilityField>], k: u32) -> Vec<f32> {
    let casters: Vec<_> = scene
        .casters()
        .zip(fields)
        .map(|((_, inst), f)| (f.clone(), inst.transform))
        .collect();
    field_ao_with(scene, &casters, k)
}

/// Field-lookup vertex AO at the receivers of `scene` with the fields placed as given (the
/// scene's own casters are ignored).
pub fn field_ao_with(
    scene: &Scene,
    casters: &[(Arc<VisibilityField>, Similarity)],
    k: u32,
) -> Vec<f32> {
    let recv = Receivers::of(scene);
    let instances = casters
        .iter()
        .map(|(f, t)| FieldInstance::new(f.clone(), *t))
        .collect();
    let fs = FieldScene {
        instances,
        options: LookupOptions::default(),
    };
    ao_at_points(
        &fs,
        &recv.points,
        &recv.normals,
        &RaySet::new(k, 1),
        &options(scene),
    )
}

/// Largest absolute difference.
pub fn max_diff(a: &[f32], b: &[f32]) -> f64 {
    assert_eq!(a.len(), b.len());
    super::max_of(a.iter().zip(b).map(|(x, y)| (*x as f64 - *y as f64).abs()))
}

/// `scene` with every instance's world vertices moved by `shift` (in f32) baked into its mesh,
/// identity transforms, and the world normals kept as they are: two calls with shifts that
/// differ by an exact f32 translation give scenes that differ by exactly that translation.
pub fn flattened(scene: &Scene, shift: glam::Vec3) -> Scene {
    Scene {
        instances: scene
            .instances
            .iter()
            .map(|inst| {
                let mut mesh = (*inst.mesh).clone();
                for (p, n) in mesh.positions.iter_mut().zip(mesh.normals.iter_mut()) {
                    *p = inst.transform.to_world_point(*p) + shift;
                    *n = inst.transform.to_world_dir(*n).normalize();
                }
                Instance {
                    mesh: Arc::new(mesh),
                    transform: Similarity::default(),
                    caster: inst.caster,
                    receiver: inst.receiver,
                }
            })
            .collect(),
    }
}
