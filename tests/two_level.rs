//! Two-level ray casting (`trace::two_level`) against the world-space tracer on every ray of a
//! moving scene: the same answers up to moving the ray instead of the triangles.

use glam::{Quat, Vec3};
use visfield::geometry::procedural::{supershape, uv_sphere, Supershape};
use visfield::geometry::Similarity;
use visfield::trace::two_level::TwoLevel;
use visfield::trace::Tracer;

mod common;
use common::{triangles as tris, unit};
use visfield::visibility::Visibility;

#[test]
fn two_levels_answer_as_the_world_tracer_on_every_ray_of_every_frame() {
    let meshes = [
        supershape(&Supershape::default(), 3000).unwrap(),
        uv_sphere(1.0, 12, 24).unwrap(),
    ];
    let model: Vec<Vec<[Vec3; 3]>> = meshes.iter().map(tris).collect();
    let mut tl = TwoLevel::new(&model);
    let (mut rays, mut hits, mut same_hit, mut dist_err) = (0usize, 0usize, 0usize, 0.0f32);
    for frame in 0..4u64 {
        // Nine instances on a 3 × 3 grid, each moved, turned and scaled per frame.
        let instances: Vec<(usize, Similarity)> = (0..9u64)
            .map(|i| {
                let a = 0.7 * frame as f32 + unit(i);
                let pos = Vec3::new((i % 3) as f32 * 2.5, 0.3 * a.sin(), (i / 3) as f32 * 2.5);
                let rot = Quat::from_axis_angle(Vec3::new(1.0, unit(i + 9), 0.5).normalize(), a);
                (
                    (i % 2) as usize,
                    Similarity::new(rot, pos, 0.6 + 0.3 * unit(i + 20)),
                )
            })
            .collect();
        tl.update(&instances);
        let world: Vec<[Vec3; 3]> = instances
            .iter()
            .flat_map(|&(m, t)| {
                model[m]
                    .iter()
                    .map(move |tri| tri.map(|v| t.to_world_point(v)))
            })
            .collect();
        let reference = Tracer::new(&world);
        for r in 0..4000u64 {
            let s = frame * 10_000 + r;
            let o = Vec3::new(-2.0 + 9.0 * unit(s), 3.0, -2.0 + 9.0 * unit(s + 1));
            let target = Vec3::new(5.0 * unit(s + 2), 0.0, 5.0 * unit(s + 3));
            let d = (target - o).normalize();
            rays += 1;
            let a = reference.hit_distance(o, d, 0.0, 20.0);
            let b = tl.hit_distance(o, d, 0.0, 20.0);
            assert_eq!(
                tl.occluded(o, d, 0.0, 20.0),
                b.is_some(),
                "occluded and hit_distance disagree"
            );
            if a.is_some() {
                hits += 1;
            }
            if a.is_some() == b.is_some() {
                same_hit += 1;
            }
            if let (Some(a), Some(b)) = (a, b) {
                dist_err = dist_err.max((a - b).abs() / a);
            }
        }
    }
    // The rays hit something often enough to mean something, and the two agree on all but
    // edge-grazing ones.
    assert!(hits > rays / 5 && hits < rays, "{hits} of {rays}");
    assert!(
        rays - same_hit <= rays / 1000,
        "{} of {rays} differ",
        rays - same_hit
    );
    assert!(
        dist_err < 1e-4,
        "largest relative distance error {dist_err}"
    );
}

#[test]
fn no_instances_miss_everything() {
    let mut tl = TwoLevel::new(&[tris(&uv_sphere(1.0, 8, 8).unwrap())]);
    tl.update(&[]);
    assert!(!tl.occluded(Vec3::ZERO, Vec3::Y, 0.0, f32::INFINITY));
    assert_eq!(tl.hit_distance(Vec3::ZERO, Vec3::Y, 0.0, 10.0), None);
}
