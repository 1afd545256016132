//! The batched field queries (`Visibility::occluded_many` of a `FieldScene`, used by AO, and
//! `occluded_many_to`, used by shadow rays) against the per-ray query they replace: bit-identical answers on scenes of one and of several
//! overlapping instances, both selections, every precision, for rays from outside every sphere,
//! from inside spheres (intra-object) and from the caster's surface.

use glam::{Quat, Vec3};
use std::sync::Arc;
use visfield::field::bake::{bake, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision, Selection, VisibilityField};
use visfield::geometry::procedural::{supershape, Supershape};
use visfield::geometry::Similarity;
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::sampling::rays::{seeded_sphere_direction, RaySet};
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::visibility::{PerRay, Visibility};

const PRECISIONS: [Precision; 4] = [
    Precision::F32,
    Precision::U16,
    Precision::U8,
    Precision::Bit1,
];

/// A non-convex caster (so that rays from its surface can be blocked by itself).
fn caster() -> visfield::geometry::Mesh {
    supershape(&Supershape::default(), 2000).expect("supershape")
}

fn field(precision: Precision) -> Arc<VisibilityField> {
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 290,
        layout: LayoutKind::Concentric,
        res: 16,
        precision,
    };
    Arc::new(
        bake(&caster(), params, &BakeOptions::default())
            .expect("bake")
            .0,
    )
}

/// Three instances: two overlapping spheres and one apart, rotated and scaled.
fn transforms() -> [Similarity; 3] {
    [
        Similarity::default(),
        Similarity::new(
            Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.3, 1.1),
            Vec3::new(0.9, 0.2, -0.3),
            0.8,
        ),
        Similarity::new(Quat::from_rotation_z(2.0), Vec3::new(-3.0, 1.0, 2.0), 1.5),
    ]
}

struct Tally {
    rays: usize,
    hits: usize,
    inside_hits: usize,
}

/// Asserts `occluded_many` == per-ray `occluded` on 256 rays from each origin, for two
/// segments ([0, ∞) and a short one with tmin > 0), and `occluded_many_to` == per-ray
/// `occluded` with a far end of its own per ray; returns what was tested.
fn compare(scene: &FieldScene, origins: &[Vec3]) -> Tally {
    let mut tally = Tally {
        rays: 0,
        hits: 0,
        inside_hits: 0,
    };
    let mut out = vec![false; 256];
    for (k, &origin) in origins.iter().enumerate() {
        let dirs: Vec<Vec3> = (0..256)
            .map(|j| seeded_sphere_direction((k * 256 + j) as u64, 7))
            .collect();
        let inside = scene
            .instances
            .iter()
            .any(|i| (origin - i.world_center).length() < i.world_radius);
        for (tmin, tmax) in [(0.0, f32::INFINITY), (0.01, 0.6)] {
            scene.occluded_many(origin, &dirs, tmin, tmax, &mut out);
            for (j, &dir) in dirs.iter().enumerate() {
                let want = scene.occluded(origin, dir, tmin, tmax);
                assert_eq!(
                    out[j], want,
                    "{:?}: origin {origin}, dir {dir}, [{tmin}, {tmax}]",
                    scene.options.selection
                );
                tally.rays += 1;
                tally.hits += want as usize;
                tally.inside_hits += (want && inside) as usize;
            }
        }
        // Each ray its own far end (shadow rays to points on a light): `occluded_many_to`.
        let tmaxs: Vec<f32> = (0..256)
            .map(|j| match j % 5 {
                0 => f32::INFINITY,
                m => 0.15 * m as f32 * (1 + j % 7) as f32,
            })
            .collect();
        scene.occluded_many_to(origin, &dirs, 0.0, &tmaxs, &mut out);
        for (j, &dir) in dirs.iter().enumerate() {
            let want = scene.occluded(origin, dir, 0.0, tmaxs[j]);
            assert_eq!(
                out[j], want,
                "{:?}: origin {origin}, dir {dir}, [0, {}] (occluded_many_to)",
                scene.options.selection, tmaxs[j]
            );
            tally.rays += 1;
            tally.hits += want as usize;
            tally.inside_hits += (want && inside) as usize;
        }
    }
    tally
}

#[test]
fn batched_occlusion_is_bit_identical_to_per_ray() {
    let mesh = caster();
    for precision in PRECISIONS {
        let field = field(precision);
        let (c, r) = (field.bounds.center, field.bounds.radius);
        for several in [false, true] {
            let instances: Vec<FieldInstance> = transforms()
                .iter()
                .take(if several { 3 } else { 1 })
                .map(|&t| FieldInstance::new(field.clone(), t))
                .collect();
            // Origins: around the scene (outside and inside spheres), far away, and on the
            // first instance's surface (vertices pushed out by 1e-3 R, intra-object rays).
            let mut origins: Vec<Vec3> = (0..40u64)
                .map(|i| c + 3.0 * r * seeded_sphere_direction(i, 3) * ((i % 10) as f32 / 9.0))
                .collect();
            origins.extend((0..4u64).map(|i| c + 200.0 * r * seeded_sphere_direction(i, 4)));
            origins.extend((0..mesh.positions.len()).step_by(97).map(|v| {
                let p = mesh.positions[v];
                p + 1e-3 * r * (p - c).normalize_or_zero()
            }));
            for selection in [Selection::Nearest, Selection::Interpolated] {
                let scene = FieldScene {
                    instances: instances.clone(),
                    options: LookupOptions {
                        selection,
                        ..LookupOptions::default()
                    },
                };
                let t = compare(&scene, &origins);
                // Both answers occur, and intra-object rays are among the hits.
                assert!(
                    t.hits > t.rays / 20 && t.hits < t.rays * 19 / 20,
                    "{precision:?} {selection:?} several={several}: {} hits of {}",
                    t.hits,
                    t.rays
                );
                assert!(
                    t.inside_hits > 100,
                    "{precision:?} {selection:?} several={several}: {} inside hits",
                    t.inside_hits
                );
            }
        }
    }
}

#[test]
fn batched_ao_is_bit_identical_to_per_ray_ao() {
    let field = field(Precision::U8);
    let (c, r) = (field.bounds.center, field.bounds.radius);
    let instances: Vec<FieldInstance> = transforms()
        .iter()
        .map(|&t| FieldInstance::new(field.clone(), t))
        .collect();
    // Receivers on a floor under the instances, and points around the first caster.
    let mut points = Vec::new();
    let mut normals = Vec::new();
    for i in 0..30 {
        for j in 0..30 {
            points.push(Vec3::new(
                -4.0 + 0.2 * i as f32,
                c.y - 1.2 * r,
                -3.0 + 0.2 * j as f32,
            ));
            normals.push(Vec3::Y);
        }
    }
    for i in 0..200u64 {
        let n = seeded_sphere_direction(i, 9);
        points.push(c + r * (0.3 + 0.9 * (i % 7) as f32 / 6.0) * n);
        normals.push(n);
    }
    let rays = RaySet::new(16, 5);
    let opts = AoOptions::for_scene_radius(5.0);
    for selection in [Selection::Nearest, Selection::Interpolated] {
        let scene = FieldScene {
            instances: instances.clone(),
            options: LookupOptions {
                selection,
                ..LookupOptions::default()
            },
        };
        let batched = ao_at_points(&scene, &points, &normals, &rays, &opts);
        let per_ray = ao_at_points(&PerRay(&scene), &points, &normals, &rays, &opts);
        assert_eq!(batched, per_ray, "{selection:?}");
        // Not trivially all open or all closed.
        let open = batched.iter().filter(|&&a| a == 1.0).count();
        let shaded = batched.iter().filter(|&&a| a < 0.9).count();
        assert!(
            open > 0 && shaded > 0,
            "{selection:?}: {open} open, {shaded} shaded"
        );
    }
}
