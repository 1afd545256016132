//! Scale and position: one scene scaled by 1e-3, 1e3 and 1e4 and translated by 1e4 gives the AO
//! of the unit scene within 1/255 at every receiver vertex, both ray cast and by field lookup.
//!
//! The scene occludes itself: a cube with a hole (the concave caster), fitted in a sphere of
//! radius 0.3 at (0.5, 0.45, 0.5), is caster and receiver, over the corner receiver (17 × 17
//! vertices per face). Receiver rays start on a surface that is itself in the tracer, so an
//! origin offset that does not follow the scale, or that falls below the f32 spacing of the
//! coordinates (1e-3 at 1e4), shows as self-occlusion. 256 rays per point: one ray changing its
//! answer moves AO by 1/256, inside the tolerance; two do not.

use super::scene_ao::{
    bake_field, field_ao, field_ao_with, flattened, raycast_ao, raycast_ao_with, scene, Placed,
};
use super::Row;
use crate::geometry::{procedural, Similarity};
use glam::{Quat, Vec3};
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

/// The scaled placements compared with the unit scene: (label, scale, translation).
pub fn scaled() -> Vec<(&'static str, f32, f32)> {
    vec![
        ("scaled 1e-3", 1e-3, 0.0),
        ("scaled 1e3", 1e3, 0.0),
        ("scaled 1e4", 1e4, 0.0),
    ]
}

/// The translated placement.
pub fn translated() -> Vec<(&'static str, f32, f32)> {
    vec![("translated 1e4", 1.0, 1e4)]
}

/// The scale case: [`scaled`].
pub fn scale() -> Vec<Row> {
    compare("scale", scaled())
}

/// The position case: [`translated`].
pub fn position() -> Vec<Row> {
    compare("position", translated())
}

/// Ray-cast AO of the unit scene translated by 1e4 against itself moved back, both with the
/// ray-origin offset `offset` (model units): the self-intersection check of the offset.
pub fn translated_raycast_difference(offset: f32) -> f64 {
    let sc = scene(
        &unit_scene(),
        Similarity::new(Quat::IDENTITY, Vec3::splat(1e4), 1.0),
    );
    let opts = crate::render::ao::AoOptions {
        max_distance: None,
        offset,
        falloff: crate::render::ao::Falloff::Step,
    };
    let here = raycast_ao_with(&flattened(&sc, Vec3::ZERO), 16, &opts);
    let back = raycast_ao_with(&flattened(&sc, Vec3::splat(-1e4)), 16, &opts);
    super::scene_ao::max_diff(&here, &back)
}

/// The case: ray-cast and field AO of each placement against the unit scene's.
///
/// A scaled scene is compared with the unit scene. A translated scene is compared with itself
/// moved back by the (exact) inverse translation: at 1e4 the f32 vertices are quantised to
/// 1e-3, which moves the caster's outline and changes AO by a few rays of 256 whatever the
/// tracer does; moving back is exact (Sterbenz), so the comparison isolates the effect of
/// position on tracing and offsets from that of the input's own rounding.
fn compare(case: &str, placements: Vec<(&'static str, f32, f32)>) -> Vec<Row> {
    let placed = unit_scene();
    let k = 16;
    let unit = scene(&placed, Similarity::default());
    let fields: Vec<_> = placed
        .iter()
        .filter(|p| p.2)
        .map(|p| bake_field(&p.0))
        .collect();
    let casters = |sc: &crate::geometry::Scene| -> Vec<_> {
        sc.casters()
            .zip(&fields)
            .map(|((_, inst), f)| (f.clone(), inst.transform))
            .collect()
    };
    let mut rows = Vec::new();
    for (label, s, t) in placements {
        let outer = Similarity::new(Quat::IDENTITY, Vec3::splat(t), s);
        let sc = scene(&placed, outer);
        let (ray, ray_ref, field, field_ref) = if t == 0.0 {
            (
                raycast_ao(&sc, k),
                raycast_ao(&unit, k),
                field_ao(&sc, &fields, k),
                field_ao(&unit, &fields, k),
            )
        } else {
            let here = flattened(&sc, Vec3::ZERO);
            let back = flattened(&sc, Vec3::splat(-t));
            let moved_back: Vec<_> = casters(&unit);
            (
                raycast_ao(&here, k),
                raycast_ao(&back, k),
                field_ao_with(&here, &casters(&sc), k),
                field_ao_with(&back, &moved_back, k),
            )
        };
        rows.push(Row::new(
            case,
            format!(
                "{label}: ray-cast AO, max difference from unit scale ({} vertices)",
                ray.len()
            ),
            super::scene_ao::max_diff(&ray, &ray_ref),
            AO_TOLERANCE,
        ));
        rows.push(Row::new(
            case,
            format!("{label}: field AO, max difference from unit scale"),
            super::scene_ao::max_diff(&field, &field_ref),
            AO_TOLERANCE,
        ));
    }
    rows
}
