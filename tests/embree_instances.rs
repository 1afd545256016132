//! Embree with instance geometries (`trace::embree_instances`) against our two-level tracer
//! (`trace::two_level`) on every ray of a moving scene: the same answers up to each moving the
//! ray into the instance's space in its own f32 arithmetic. Ignored, with the reason, in a
//! build without the `embree` feature.

#[cfg(not(feature = "embree"))]
#[test]
#[ignore = "needs the `embree` cargo feature and libembree3 (Debian libembree-dev): cargo test --features embree"]
fn embree_instances_answer_as_two_level_ray_casting() {}

#[cfg(feature = "embree")]
#[test]
fn embree_instances_answer_as_two_level_ray_casting() {
    use glam::{Quat, Vec3};
    use visfield::geometry::procedural::{supershape, uv_sphere, Supershape};
    use visfield::geometry::{Mesh, Similarity};
    use visfield::sampling::rays::seeded_sphere_direction;
    use visfield::trace::embree_instances::EmbreeInstances;
    use visfield::trace::two_level::TwoLevel;
    use visfield::visibility::Visibility;

    fn tris(m: &Mesh) -> Vec<[Vec3; 3]> {
        m.triangles
            .iter()
            .map(|t| t.map(|i| m.positions[i as usize]))
            .collect()
    }
    let meshes = [
        supershape(&Supershape::default(), 3000).unwrap(),
        uv_sphere(1.0, 12, 24).unwrap(),
    ];
    let model: Vec<Vec<[Vec3; 3]>> = meshes.iter().map(tris).collect();
    let mut ours = TwoLevel::new(&model);
    let mut embree = EmbreeInstances::new(&model).expect("Embree");
    // Before any update, nothing to hit.
    assert!(!embree.occluded(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY));
    let (mut rays, mut hits, mut differ, mut dist_err, mut normal_err) = (0, 0, 0, 0.0f32, 0.0f32);
    for frame in 0..4u64 {
        // Nine instances on a 3 × 3 grid, moved, turned and scaled per frame; the fourth
        // frame has one instance fewer (a new top scene).
        let count = if frame == 3 { 8 } else { 9 };
        let instances: Vec<(usize, Similarity)> = (0..count)
            .map(|i: u64| {
                let a = 0.7 * frame as f32 + 0.37 * i as f32;
                let pos = Vec3::new((i % 3) as f32 * 2.5, 0.3 * a.sin(), (i / 3) as f32 * 2.5);
                let rot = Quat::from_axis_angle(seeded_sphere_direction(i, 5), a);
                let scale = 0.6 + 0.05 * i as f32;
                ((i % 2) as usize, Similarity::new(rot, pos, scale))
            })
            .collect();
        ours.update(&instances);
        embree.update(&instances).expect("update");
        for r in 0..4000u64 {
            let s = frame * 10_000 + r;
            let o = Vec3::new(2.5, 4.0, 2.5) + 3.0 * seeded_sphere_direction(s, 6);
            // Toward a point near one of the instances.
            let (_, t) = instances[(r % count) as usize];
            let target = t.translation + 0.9 * seeded_sphere_direction(s, 7);
            let d = (target - o).normalize();
            let a = ours.surface_hit(o, d, 0.0, f32::INFINITY);
            let b = embree.surface_hit(o, d, 0.0, f32::INFINITY);
            assert_eq!(
                embree.occluded(o, d, 0.0, f32::INFINITY),
                b.is_some(),
                "occluded and surface_hit disagree"
            );
            rays += 1;
            match (a, b) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    dist_err = dist_err.max((a.t - b.t).abs() / a.t);
                    normal_err = normal_err.max((a.normal - b.normal).length());
                }
                (None, None) => {}
                _ => differ += 1,
            }
        }
        // The batched queries (8-wide packets) answer as the single ones.
        let o = Vec3::new(2.5, 3.0, 2.5);
        let dirs: Vec<Vec3> = (0..256u64)
            .map(|j| {
                let d = seeded_sphere_direction(frame * 1000 + j, 8);
                if d.y > 0.0 {
                    -d
                } else {
                    d
                }
            })
            .collect();
        let mut out = vec![false; dirs.len()];
        embree.occluded_many(o, &dirs, 0.0, f32::INFINITY, &mut out);
        for (d, &hit) in dirs.iter().zip(&out) {
            assert_eq!(hit, embree.occluded(o, *d, 0.0, f32::INFINITY));
        }
    }
    // Most rays aimed at the instances hit one; the two casters part on at most a few grazing rays,
    // distances agree to f32 rounding and the normals are the same triangles' normals.
    assert!(hits > rays / 3 && hits < rays, "{hits} hits of {rays}");
    assert!(differ <= rays / 2000, "{differ} of {rays} rays differ");
    assert!(dist_err < 1e-4, "relative distance difference {dist_err}");
    assert!(normal_err < 1e-3, "normal difference {normal_err}");
}
