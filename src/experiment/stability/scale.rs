//! Scale and position: one scene scaled by 1e-3, 1e3 and 1e4 and translated by 1e4 and 1e6 gives
//! the AO of the unit scene within 1/255 at every receiver vertex, both ray cast and by field
//! lookup. Placements are composed in f64 and the scene rebased next to the origin
//! ([`crate::geometry::rebase`]) as the experiment runner does; a scene left in f32 world
//! coordinates at 1e4 ([`unrebased`]) shows what rebasing avoids.
//!
//! The scene occludes itself: a cube with a hole (the concave caster), fitted in a sphere of
//! radius 0.3 at (0.5, 0.45, 0.5), is caster and receiver, over the corner receiver (17 × 17
//! vertices per face). Receiver rays start on a surface that is itself in the tracer, so an
//! origin offset that does not follow the scale, or that falls below the f32 spacing of the
//! coordinates (1e-3 at 1e4), shows as self-occlusion. 256 rays per point: one ray changing its
//! answer moves AO by 1/256, inside the tolerance; two do not.
//!
//! Bystanders ([`bystanders`]): the same scene with a small sphere 1000 away (a caster), and with
//! a receiver plane 1000× the corner's size far below it, evaluated at the harness's points
//! ([`crate::render::points::EvalPoints`]: each point moved off its surface by its own
//! instance's offset): the corner's and the cube's AO do not change.

use super::scene_ao::{
    bake_fields, field_ao, flattened, raycast_ao, raycast_ao_with, rebased_scene, scene, Placed,
};
use super::StabilityRow;
use crate::geometry::{procedural, Similarity};
use glam::{DVec3, Quat, Vec3};
use std::sync::Arc;

/// AO tolerance of the case (the 1/255).
pub const AO_TOLERANCE: f64 = 1.0 / 255.0;

/// The placed meshes of the case's unit scene.
pub fn unit_scene() -> Vec<Placed> {
    let corner = Arc::new(procedural::corner(17).expect("valid corner"));
    let cube = Arc::new(procedural::cube_with_hole(1.0, 0.4).expect("valid cube"));
    let s = cube.bounding_sphere();
    let rotation = Quat::from_euler(glam::EulerRot::YXZ, 0.5, 0.3, 0.1);
    let k = 0.3 / s.radius;
    let fit = Similarity::new(
        rotation,
        Vec3::new(0.5, 0.45, 0.5) - k * (rotation * s.center),
        k,
    );
    vec![
        (corner, Similarity::default(), false, true),
        (cube, fit, true, true),
    ]
}

/// A placement of the unit scene: (label, scale, translation).
pub type Placement = (&'static str, f32, DVec3);

/// The scaled placements compared with the unit scene.
pub fn scaled() -> Vec<Placement> {
    vec![
        ("scaled 1e-3", 1e-3, DVec3::ZERO),
        ("scaled 1e3", 1e3, DVec3::ZERO),
        ("scaled 1e4", 1e4, DVec3::ZERO),
    ]
}

/// The translated placements: by 1e4, 1e6, 1e12 and 1e15 on every axis (the rebased frame
/// removes each exactly, the fit's offsets kept apart from it), and by 1e4 plus an offset that
/// the rebased frame keeps (the scene then sits at (0.375, −0.25, 0.125) from its origin, so
/// its f32 coordinates differ from the unit scene's).
pub fn translated() -> Vec<Placement> {
    vec![
        ("translated 1e4", 1.0, DVec3::splat(1e4)),
        (
            "translated 1e4 + (0.375, -0.25, 0.125)",
            1.0,
            DVec3::new(1e4 + 0.375, 1e4 - 0.25, 1e4 + 0.125),
        ),
        ("translated 1e6", 1.0, DVec3::splat(1e6)),
        ("translated 1e12", 1.0, DVec3::splat(1e12)),
        ("translated 1e15", 1.0, DVec3::splat(1e15)),
    ]
}

/// The scale case: [`scaled`].
pub fn scale() -> Vec<StabilityRow> {
    compare("scale", scaled())
}

/// The position case: [`translated`], and a mesh whose own coordinates lie at 1e4
/// ([`far_mesh_coordinates`]).
pub fn position() -> Vec<StabilityRow> {
    let mut rows = compare("position", translated());
    rows.push(StabilityRow::new(
        "position",
        "mesh coordinates at 1e4: ray-cast AO, max difference from the same mesh moved back",
        far_mesh_coordinates(),
        AO_TOLERANCE,
    ));
    rows
}

/// The unit scene under `outer` in true world coordinates, without rebasing: f32 composition
/// and f32 world coordinates.
pub fn unrebased(outer_translation: f32) -> crate::geometry::Scene {
    scene(
        &unit_scene(),
        Similarity::new(Quat::IDENTITY, Vec3::splat(outer_translation), 1.0),
    )
}

/// Ray-cast AO of the unit scene translated by 1e4 (f32 world coordinates, not rebased)
/// against itself moved back, both with the ray-origin offset `offset` (model units): the
/// self-intersection check of the offset.
pub fn translated_raycast_difference(offset: f32) -> f64 {
    let sc = unrebased(1e4);
    let opts = crate::render::ao::AoOptions {
        max_distance: None,
        offset,
        falloff: crate::render::ao::Falloff::Step,
    };
    let here = raycast_ao_with(&flattened(&sc, Vec3::ZERO), 16, &opts);
    let back = raycast_ao_with(&flattened(&sc, Vec3::splat(-1e4)), 16, &opts);
    super::scene_ao::max_diff(&here, &back)
}

/// A scene whose meshes carry their world coordinates at 1e4 (the unit scene translated and
/// flattened into f32 vertices: identity transforms), rebased, against the same vertices moved
/// back by the exact translation. The vertices are the input here, rounded to the f32 spacing
/// at 1e4 (1e-3) in both; rebasing removes the translation exactly, so only the tracing
/// differs.
pub fn far_mesh_coordinates() -> f64 {
    let sc = unrebased(1e4);
    let here = flattened(&sc, Vec3::ZERO).rebased();
    assert_ne!(here.origin, glam::DVec3::ZERO, "the far scene is rebased");
    let back = flattened(&sc, Vec3::splat(-1e4));
    super::scene_ao::max_diff(&raycast_ao(&here.scene, 16), &raycast_ao(&back, 16))
}

/// The bystanders case: ray-cast AO at the unit scene's receiver vertices, as the harness
/// evaluates them (per-instance ray offsets, [`crate::render::ao::instance_epsilon`]), with a
/// sphere of radius 0.1 at 1000 (a caster) and with a 1000-wide receiver plane 2000 below the
/// corner added, against the unit scene alone: both differences must be 0 (the former
/// scene-wide offset rose to 0.05 with the far sphere and changed the AO by up to 0.375).
pub fn bystanders() -> Vec<StabilityRow> {
    use crate::render::ao::{ao_at_points, AoOptions};
    use crate::render::points::EvalPoints;
    use crate::sampling::rays::RaySet;
    use crate::trace::Tracer;
    let unit = unit_scene();
    let ao = |placed: &[Placed]| -> Vec<f32> {
        let sc = rebased_scene(placed, 1.0, DVec3::ZERO).scene;
        let pts = EvalPoints::vertices(&sc);
        let opts = AoOptions {
            offset: 0.0,
            ..AoOptions::for_scene_radius(1.0)
        };
        let tracer = Tracer::new(&sc.caster_triangles());
        let at = pts.at();
        // The unit scene's receivers come first: compare those points only.
        ao_at_points(&tracer, at.points, at.normals, &RaySet::new(16, 1), &opts)
    };
    let reference = ao(&unit);
    let n = reference.len();
    let sphere = Arc::new(procedural::uv_sphere(0.1, 8, 16).expect("valid sphere"));
    let plane = Arc::new(procedural::plane(1000.0, 2).expect("valid plane"));
    let mut far_sphere = unit.clone();
    far_sphere.push((
        sphere,
        Similarity::new(Quat::IDENTITY, Vec3::new(1000.0, 0.0, 0.0), 1.0),
        true,
        false,
    ));
    let mut big_receiver = unit.clone();
    big_receiver.push((
        plane,
        Similarity::new(Quat::IDENTITY, Vec3::new(0.0, -2000.0, 0.0), 1.0),
        false,
        true,
    ));
    [
        ("a caster sphere of radius 0.1 at 1000", far_sphere),
        ("a 1000-wide receiver plane 2000 below", big_receiver),
    ]
    .into_iter()
    .map(|(label, placed)| {
        let with = ao(&placed);
        StabilityRow::new(
            "bystanders",
            format!("{label}: ray-cast AO at the unit scene's {n} vertices, max difference"),
            super::scene_ao::max_diff(&with[..n], &reference),
            0.0,
        )
    })
    .collect()
}

/// The case: ray-cast and field AO of each placement against the unit scene's.
///
/// Every placement is composed in f64 and rebased ([`crate::geometry::rebase`]), as the
/// experiment runner builds its scenes, and compared with the unit scene directly.
fn compare(case: &str, placements: Vec<Placement>) -> Vec<StabilityRow> {
    let placed = unit_scene();
    let k = 16;
    let unit = scene(&placed, Similarity::default());
    let fields = bake_fields(&placed);
    let mut rows = Vec::new();
    for (label, s, t) in placements {
        let sc = rebased_scene(&placed, s, t).scene;
        let (ray, ray_ref, field, field_ref) = (
            raycast_ao(&sc, k),
            raycast_ao(&unit, k),
            field_ao(&sc, &fields, k),
            field_ao(&unit, &fields, k),
        );
        rows.push(StabilityRow::new(
            case,
            format!(
                "{label}: ray-cast AO, max difference from unit scale ({} vertices)",
                ray.len()
            ),
            super::scene_ao::max_diff(&ray, &ray_ref),
            AO_TOLERANCE,
        ));
        rows.push(StabilityRow::new(
            case,
            format!("{label}: field AO, max difference from unit scale"),
            super::scene_ao::max_diff(&field, &field_ref),
            AO_TOLERANCE,
        ));
    }
    rows
}
