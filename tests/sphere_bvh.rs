//! The BVH over the casters' bounding spheres (`SphereBvhScene`) against testing every sphere
//! (`FieldScene`): the same answers bit for bit, per ray and batched, AO and shadow rays, hit
//! distances and normals, on crowds of 2 to 200 instances placed as a moving crowd would be
//! (apart, touching, overlapping), from origins outside, between and inside the spheres.

use glam::{Quat, Vec3};
use std::sync::Arc;
use visfield::field::bake::{bake_mesh_with_normals, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::normals::NormalField;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::sphere_bvh::{SphereBvh, SphereBvhScene};
use visfield::field::{FieldParams, Precision, Selection, VisibilityField};
use visfield::geometry::procedural::{supershape, Supershape};
use visfield::geometry::Similarity;
use visfield::sampling::rays::seeded_sphere_direction;
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::simd::Isa;
use visfield::visibility::Visibility;

fn baked() -> (Arc<VisibilityField>, Arc<NormalField>) {
    let mesh = supershape(&Supershape::default(), 1500).expect("supershape");
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 170,
        layout: LayoutKind::Concentric,
        res: 12,
        precision: Precision::U8,
    };
    let (field, normals, _) =
        bake_mesh_with_normals(&mesh, params, 8, &BakeOptions::default()).expect("bake");
    (Arc::new(field), Arc::new(normals))
}

/// `n` instances scattered in a box whose side grows with `n` (neighbours apart, touching or
/// overlapping), each rotated and scaled.
fn crowd(field: &Arc<VisibilityField>, normals: &Arc<NormalField>, n: usize) -> Vec<FieldInstance> {
    placed(field, normals, n, false)
}

/// [`crowd`], or with `flat` the same instances pressed into a layer one radius thick over the
/// plane y = 0, as a moving crowd over its receiver plane stands.
fn placed(
    field: &Arc<VisibilityField>,
    normals: &Arc<NormalField>,
    n: usize,
    flat: bool,
) -> Vec<FieldInstance> {
    let side = 2.0 * (n as f32).cbrt();
    (0..n as u64)
        .map(|i| {
            let mut p = seeded_sphere_direction(i, 11) * side * (((i * 37) % 100) as f32 / 100.0);
            if flat {
                p = Vec3::new(p.x * side.sqrt(), 0.6 + 0.1 * p.y / side, p.z * side.sqrt());
            }
            let q = Quat::from_axis_angle(seeded_sphere_direction(i, 12), 0.1 * i as f32);
            let s = 0.5 + ((i * 13) % 10) as f32 / 10.0;
            FieldInstance::new(field.clone(), Similarity::new(q, p, s))
                .with_normals(normals.clone())
        })
        .collect()
}

#[test]
fn the_sphere_bvh_answers_as_testing_every_sphere() {
    let (field, normals) = baked();
    let mut total = (0usize, 0usize);
    for (n, flat) in [2usize, 3, 7, 40, 200]
        .map(|n| (n, false))
        .into_iter()
        .chain([(64, true), (150, true)])
    {
        let instances = placed(&field, &normals, n, flat);
        for selection in [Selection::Nearest, Selection::Interpolated] {
            let plain = FieldScene {
                instances: instances.clone(),
                options: LookupOptions {
                    selection,
                    ..LookupOptions::default()
                },
            };
            let tree = SphereBvhScene::new(plain.clone());
            let side = 2.0 * (n as f32).cbrt();
            // Origins through and around the crowd: inside spheres, between them, far away; over
            // a flat crowd also on its floor, the receiver points of a moving crowd.
            let origins: Vec<Vec3> = (0..24u64)
                .map(|k| seeded_sphere_direction(k, 21) * side * 1.5 * (k as f32 / 23.0))
                .chain((0..3u64).map(|k| 50.0 * side * seeded_sphere_direction(k, 22)))
                .chain((0..if flat { 12u64 } else { 0 }).map(|k| {
                    let p = seeded_sphere_direction(k, 24) * side.sqrt() * side;
                    Vec3::new(p.x, 0.0, p.z)
                }))
                .collect();
            for (k, &o) in origins.iter().enumerate() {
                // Batches of a few windows, the last one partial.
                let m = 100 + 37 * (k % 3);
                let dirs: Vec<Vec3> = (0..m as u64)
                    .map(|j| {
                        let d = seeded_sphere_direction(k as u64 * 256 + j, 23);
                        // Over the floor, the upper hemisphere, as AO rays leave a receiver.
                        if flat && o.y == 0.0 {
                            Vec3::new(d.x, d.y.abs(), d.z)
                        } else {
                            d
                        }
                    })
                    .collect();
                let tmaxs: Vec<f32> = (0..m).map(|j| 0.1 + (j % 9) as f32 * side / 4.0).collect();
                let (mut a, mut b) = (vec![false; m], vec![false; m]);
                plain.occluded_many(o, &dirs, 1e-4, f32::INFINITY, &mut a);
                tree.occluded_many(o, &dirs, 1e-4, f32::INFINITY, &mut b);
                assert_eq!(a, b, "N={n} {selection:?} origin {o}: occluded_many");
                for isa in Isa::all_available() {
                    plain.occluded_many_to_on(isa, o, &dirs, 1e-4, &tmaxs, &mut a);
                    tree.occluded_many_to_on(isa, o, &dirs, 1e-4, &tmaxs, &mut b);
                    assert_eq!(
                        a, b,
                        "N={n} {selection:?} {isa:?} origin {o}: occluded_many_to_on"
                    );
                }
                total.0 += a.iter().filter(|&&h| h).count();
                total.1 += a.len();
                plain.occluded_many_to(o, &dirs, 1e-4, &tmaxs, &mut a);
                tree.occluded_many_to(o, &dirs, 1e-4, &tmaxs, &mut b);
                assert_eq!(a, b, "N={n} {selection:?} origin {o}: occluded_many_to");
                for (j, &d) in dirs.iter().enumerate().step_by(4) {
                    assert_eq!(
                        plain.occluded(o, d, 1e-4, tmaxs[j]),
                        tree.occluded(o, d, 1e-4, tmaxs[j]),
                        "N={n} origin {o} dir {d}: occluded"
                    );
                    let (h0, h1) = (
                        plain.hit_distance(o, d, 1e-4, f32::INFINITY),
                        tree.hit_distance(o, d, 1e-4, f32::INFINITY),
                    );
                    assert_eq!(
                        h0.map(f32::to_bits),
                        h1.map(f32::to_bits),
                        "N={n}: hit_distance"
                    );
                    let (s0, s1) = (
                        plain.surface_hit(o, d, 1e-4, f32::INFINITY),
                        tree.surface_hit(o, d, 1e-4, f32::INFINITY),
                    );
                    assert_eq!(
                        s0.map(|s| (s.t.to_bits(), s.normal.to_array().map(f32::to_bits))),
                        s1.map(|s| (s.t.to_bits(), s.normal.to_array().map(f32::to_bits))),
                        "N={n}: surface_hit"
                    );
                }
            }
        }
    }
    // Both answers occur in quantity.
    assert!(
        total.0 > total.1 / 10 && total.0 < total.1 * 9 / 10,
        "{} of {} rays occluded",
        total.0,
        total.1
    );
}

/// Whether the ray from `o` along unit `d` meets the ball (`c`, `r`) at some t >= 0, in f64.
fn meets_ball(o: Vec3, d: Vec3, c: Vec3, r: f32) -> bool {
    let (o, d, c) = (o.as_dvec3(), d.as_dvec3(), c.as_dvec3());
    let f = c - o;
    let b = f.dot(d);
    let l2 = (f - b * d).length_squared();
    let r = r as f64;
    l2 <= r * r && b + (r * r - l2).sqrt() >= 0.0
}

#[test]
fn the_tree_keeps_every_sphere_a_ray_meets_and_few_others() {
    let (field, normals) = baked();
    let n = 256;
    let instances = crowd(&field, &normals, n);
    let tree = SphereBvh::new(&instances);
    let side = 2.0 * (n as f32).cbrt();
    let (mut kept, mut needed, mut rays) = (0usize, 0usize, 0usize);
    for k in 0..2000u64 {
        let o = seeded_sphere_direction(k, 31) * side * 1.2 * ((k % 10) as f32 / 9.0);
        let d = seeded_sphere_direction(k, 32);
        let c = tree.candidates(o, d, 0.0);
        let mut sorted = c.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), c.len(), "an instance named twice");
        for (i, inst) in instances.iter().enumerate() {
            if meets_ball(o, d, inst.world_center, inst.world_radius) {
                assert!(
                    c.contains(&i),
                    "ray {k}: instance {i}'s sphere is met but was culled"
                );
                needed += 1;
            }
        }
        kept += c.len();
        rays += 1;
    }
    // The tree keeps more than the spheres a ray meets (its boxes are larger) but far fewer
    // than all of them: under a sixteenth of the 256.
    assert!(
        kept >= needed && kept < rays * n / 16 && needed > rays,
        "{kept} kept, {needed} needed, of {} tests without the tree",
        rays * n
    );
}
