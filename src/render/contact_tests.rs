use super::*;
use crate::geometry::procedural;
use crate::render::ao::{ao_at_points, scene_epsilon, AoOptions};
use crate::sampling::rays::RaySet;
use crate::trace::Tracer;

#[test]
fn closest_point_on_triangle_in_every_region() {
    let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
    // Face region: the foot of the perpendicular.
    assert_eq!(
        closest_point_on_triangle(Vec3::new(0.25, 0.25, 3.0), &t),
        Vec3::new(0.25, 0.25, 0.0)
    );
    // Vertex regions.
    assert_eq!(
        closest_point_on_triangle(Vec3::new(-1.0, -1.0, 0.0), &t),
        t[0]
    );
    assert_eq!(
        closest_point_on_triangle(Vec3::new(2.0, -0.5, 1.0), &t),
        t[1]
    );
    assert_eq!(
        closest_point_on_triangle(Vec3::new(-0.5, 2.0, 0.0), &t),
        t[2]
    );
    // Edge regions: below the x axis, left of the y axis, beyond the hypotenuse.
    assert_eq!(
        closest_point_on_triangle(Vec3::new(0.5, -1.0, 0.0), &t),
        Vec3::new(0.5, 0.0, 0.0)
    );
    assert_eq!(
        closest_point_on_triangle(Vec3::new(-2.0, 0.5, 0.0), &t),
        Vec3::new(0.0, 0.5, 0.0)
    );
    let q = closest_point_on_triangle(Vec3::new(1.0, 1.0, 0.0), &t);
    assert!((q - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6, "{q}");
}

/// The corner's mesh: its vertices (points, normals) and world triangles (model = world).
fn corner(n: usize) -> (Vec<Vec3>, Vec<Vec3>, Vec<[Vec3; 3]>) {
    let m = procedural::corner(n).unwrap();
    let tris = m
        .triangles
        .iter()
        .map(|t| t.map(|i| m.positions[i as usize]))
        .collect();
    (m.positions.clone(), m.normals.clone(), tris)
}

#[test]
fn corner_creases_are_found_exactly_and_moved_in_front_of_both_walls() {
    let n = 9;
    let (points, normals, tris) = corner(n);
    let eps = scene_epsilon(3f32.sqrt() / 2.0);
    let c = separate_contacts(&points, &normals, &tris, eps, eps);
    // Each face's vertices on its two edges shared with the other faces: 2n − 1 per face.
    assert_eq!(c.crease_count(), 3 * (2 * n - 1));
    for i in 0..points.len() {
        let (p, q, nrm) = (points[i], c.points[i], normals[i]);
        let on_other = [Vec3::X, Vec3::Y, Vec3::Z]
            .into_iter()
            .filter(|&a| a.dot(nrm) < 0.5 && a.dot(p) == 0.0)
            .collect::<Vec<_>>();
        assert_eq!(c.crease[i], !on_other.is_empty(), "point {p}");
        // Moved by eps along each touching wall's normal, never along its own.
        let expect = p + on_other.iter().map(|&a| eps * a).sum::<Vec3>();
        assert!((q - expect).length() < 1e-9, "point {p}: {q} vs {expect}");
    }
}

#[test]
fn crease_ao_is_the_limit_of_interior_ao_not_an_epsilon_accident() {
    // The corner occluding itself: at a floor crease vertex (x, 0, 0), half of the cosine
    // hemisphere looks into the back wall. The crease convention must give the limit of the AO
    // of floor points (x, 0, δ) approaching the crease, so compare with δ = 1e-3 (the limit
    // differs by O(δ)); at the three-way vertex compare with (δ, 0, δ).
    let n = 9;
    let (points, normals, tris) = corner(n);
    let tracer = Tracer::new(&tris);
    let eps = scene_epsilon(3f32.sqrt() / 2.0);
    let c = separate_contacts(&points, &normals, &tris, eps, eps);
    let floor: Vec<usize> = (0..points.len())
        .filter(|&i| normals[i] == Vec3::Y && points[i].z == 0.0 && points[i].x < 1.0)
        .collect();
    assert_eq!(floor.len(), n - 1);
    let delta = 1e-3;
    let interior: Vec<Vec3> = floor
        .iter()
        .map(|&i| {
            let p = points[i];
            let dx = if p.x == 0.0 { delta } else { 0.0 };
            p + Vec3::new(dx, 0.0, delta)
        })
        .collect();
    let crease: Vec<Vec3> = floor.iter().map(|&i| c.points[i]).collect();
    let nrm = vec![Vec3::Y; floor.len()];
    let opts = AoOptions::for_scene_radius(3f32.sqrt() / 2.0);
    let rays = RaySet::new(32, 5);
    let a = ao_at_points(&tracer, &crease, &nrm, &rays, &opts);
    let b = ao_at_points(&tracer, &interior, &nrm, &rays, &opts);
    for (j, (&x, &y)) in a.iter().zip(&b).enumerate() {
        let p = points[floor[j]];
        assert!((x - y).abs() < 0.02, "crease {p}: {x} vs interior {y}");
        // Neither 0 nor 1: the back wall blocks about half (and the side wall more).
        assert!((0.15..0.6).contains(&x), "crease {p}: AO {x}");
    }
}

#[test]
fn a_caster_resting_on_the_floor_encloses_the_points_under_it() {
    // A closed box [−0.2, 0.2] × [0, 0.3] × [−0.2, 0.2] on a plane of side 2 (21 × 21 vertices,
    // spacing 0.1): floor vertices strictly under the box touch its bottom face (facing them),
    // are not moved, and see only the box's inside: AO 0. Vertices on the footprint's border
    // touch it too; vertices off the footprint do not.
    let plane = procedural::plane(2.0, 21).unwrap();
    let (lo, hi) = (Vec3::new(-0.2, 0.0, -0.2), Vec3::new(0.2, 0.3, 0.2));
    let v = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let quads = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    // Outward winding (the convention's "front"): flip any triangle facing the box's centre.
    let centre = 0.5 * (lo + hi);
    let mut box_tris = Vec::new();
    for q in quads {
        for t in [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]] {
            let m = (t[1] - t[0]).cross(t[2] - t[0]);
            let c = (t[0] + t[1] + t[2]) / 3.0;
            box_tris.push(if m.dot(c - centre) < 0.0 {
                [t[0], t[2], t[1]]
            } else {
                t
            });
        }
    }
    let mut all = box_tris.clone();
    all.extend(
        plane
            .triangles
            .iter()
            .map(|t| t.map(|i| plane.positions[i as usize])),
    );
    let eps = scene_epsilon(1.5);
    let c = separate_contacts(&plane.positions, &plane.normals, &all, eps, eps);
    let tracer = Tracer::new(&box_tris);
    let ao = ao_at_points(
        &tracer,
        &c.points,
        &plane.normals,
        &RaySet::new(8, 1),
        &AoOptions::for_scene_radius(1.5),
    );
    let mut under = 0;
    for (i, &p) in plane.positions.iter().enumerate() {
        let inside = p.x.abs() < 0.19 && p.z.abs() < 0.19;
        let off = p.x.abs() > 0.21 || p.z.abs() > 0.21;
        if inside {
            under += 1;
            assert!(c.crease[i], "{p} lies under the box");
            assert_eq!(
                c.points[i], p,
                "{p}: a facing contact does not move the point"
            );
            assert_eq!(ao[i], 0.0, "{p}");
        }
        if off {
            assert!(!c.crease[i], "{p} is off the box");
        }
    }
    assert_eq!(under, 9);
}
