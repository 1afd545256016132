use super::*;
use crate::trace::test_scenes::{feature_rays, grid, map_vertices, random_point, Feature};
use glam::{Quat, Vec3};
use obvhs::{ray::Ray, triangle::Triangle};

fn a(v: Vec3) -> Vec3A {
    Vec3A::from(v)
}

fn to_a(tris: &[[Vec3; 3]]) -> Vec<[Vec3A; 3]> {
    tris.iter().map(|t| t.map(a)).collect()
}

/// Möller–Trumbore as implemented by obvhs (for comparison only).
fn moller_trumbore(tri: &[Vec3A; 3], o: Vec3A, d: Vec3A, tmin: f32, tmax: f32) -> Option<f32> {
    let t = Triangle {
        v0: tri[0],
        v1: tri[1],
        v2: tri[2],
    }
    .intersect(&Ray::new(o, d, tmin, tmax));
    t.is_finite().then_some(t)
}

#[test]
fn hit_has_the_right_distance_barycentrics_and_inclusive_range() {
    let tri = [
        Vec3A::new(0.0, 0.0, 1.0),
        Vec3A::new(2.0, 0.0, 1.0),
        Vec3A::new(0.0, 4.0, 1.0),
    ];
    let o = Vec3A::new(0.5, 1.0, -1.0);
    let d = Vec3A::Z;
    // The ray meets z = 1 at t = 2, at (0.5, 1) = v0 + 0.25·(v1-v0) + 0.25·(v2-v0).
    let h = intersect_triangle(o, d, &tri, 0.0, f32::INFINITY).expect("hit");
    assert_eq!(
        h,
        TriangleHit {
            t: 2.0,
            u: 0.25,
            v: 0.25
        }
    );
    // No backface culling: the reversed triangle hits at the same t with swapped barycentrics.
    let rev = [tri[0], tri[2], tri[1]];
    let r = intersect_triangle(o, d, &rev, 0.0, f32::INFINITY).expect("back hit");
    assert_eq!((r.t, r.u, r.v), (2.0, 0.25, 0.25));
    // Inclusive at both ends, exclusive one ulp beyond.
    assert!(intersect_triangle(o, d, &tri, 2.0, 2.0).is_some());
    assert!(intersect_triangle(o, d, &tri, 0.0, 2.0f32.next_down()).is_none());
    assert!(intersect_triangle(o, d, &tri, 2.0f32.next_up(), 10.0).is_none());
    // Behind the origin.
    assert!(intersect_triangle(o, -d, &tri, 0.0, f32::INFINITY).is_none());
    // A degenerate triangle never hits.
    let line = [tri[0], tri[1], tri[0] + 0.5 * (tri[1] - tri[0])];
    let ray_on_line = Vec3A::new(0.5, 0.0, -1.0);
    assert!(intersect_triangle(ray_on_line, d, &line, 0.0, f32::INFINITY).is_none());
}

#[test]
fn agrees_with_moller_trumbore_away_from_edges() {
    // Random rays against random triangles, not grazing (|n·d| >= 0.05): both tests must agree
    // on hit/miss whenever the hit point is not within 1e-3 (in barycentrics) of an edge, and on
    // t to 1e-5 relative.
    let mut hits = 0;
    for i in 0..20_000u32 {
        let tri = [
            random_point(3 * i, 1),
            random_point(3 * i + 1, 1),
            random_point(3 * i + 2, 1),
        ]
        .map(a);
        let o = a(2.0 * random_point(i, 2));
        // Aim at a point of the triangle's plane with barycentrics in [-0.2, 1.2]: about half
        // the rays hit, many near an edge.
        let (b1, b2) = (
            0.7 * random_point(i, 3).x + 0.5,
            0.7 * random_point(i, 3).y + 0.5,
        );
        let target = tri[0] + b1 * (tri[1] - tri[0]) + b2 * (tri[2] - tri[0]);
        let d = (target - o).normalize();
        // Skip grazing rays, where t and the barycentrics are ill-conditioned for both tests.
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
        if n.dot(d).abs() < 0.05 {
            continue;
        }
        let wt = intersect_triangle(o, d, &tri, 0.0, f32::INFINITY);
        let mt = moller_trumbore(&tri, o, d, 0.0, f32::INFINITY);
        match (wt, mt) {
            (Some(h), Some(t)) => {
                hits += 1;
                assert!(
                    (h.t - t).abs() <= 1e-5 * t.abs().max(1.0),
                    "t {} vs {t}",
                    h.t
                );
                let p = (1.0 - h.u - h.v) * tri[0] + h.u * tri[1] + h.v * tri[2];
                assert!(
                    (p - (o + h.t * d)).length() < 1e-4,
                    "barycentrics do not map to p"
                );
            }
            (Some(h), None) => {
                let m = h.u.min(h.v).min(1.0 - h.u - h.v);
                assert!(m < 1e-3 || h.t < 1e-4, "MT missed a clear hit {h:?}");
            }
            (None, Some(t)) => {
                // Recompute barycentrics of MT's hit point to see how close to an edge it is.
                let p = o + t * d;
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                let area = |x: Vec3A, y: Vec3A| (x - p).cross(y - p).dot(n) / n.length_squared();
                let m = area(tri[1], tri[2])
                    .min(area(tri[2], tri[0]))
                    .min(area(tri[0], tri[1]));
                assert!(
                    m < 1e-3 || t < 1e-4,
                    "watertight missed a clear hit at t {t}"
                );
            }
            (None, None) => {}
        }
    }
    assert!(
        hits > 3000,
        "too few hits ({hits}) for the comparison to mean anything"
    );
}

/// Counts, over every triangle, the watertight hits and the Möller–Trumbore hits of each ray
/// and asserts that no ray falls through; returns the number of rays Möller–Trumbore lost.
fn assert_no_fall_through(
    tris: &[[Vec3A; 3]],
    rays: &[(Vec3A, Vec3A, Feature)],
    label: &str,
) -> usize {
    let mut mt_lost = 0;
    let mut histogram = [0usize; 9];
    for (r, &(o, d, feature)) in rays.iter().enumerate() {
        let wray = WatertightRay::new(o, d);
        let wt = tris
            .iter()
            .filter(|t| {
                wray.intersect(t[0], t[1], t[2], 0.0, f32::INFINITY)
                    .is_some()
            })
            .count();
        let mt = tris
            .iter()
            .filter(|t| moller_trumbore(t, o, d, 0.0, f32::INFINITY).is_some())
            .count();
        assert!(
            wt >= 1 && wt <= feature.max_hits(),
            "{label}: ray {r} ({feature:?}) o {o} d {d}: {wt} watertight hits"
        );
        histogram[wt] += 1;
        mt_lost += (mt == 0) as usize;
    }
    println!(
        "{label}: {} rays, watertight hit counts {histogram:?}, Möller–Trumbore fell through {mt_lost}",
        rays.len()
    );
    mt_lost
}

#[test]
fn rays_through_shared_edges_and_vertices_of_an_axis_aligned_grid_never_fall_through() {
    // 64 × 64 cells of side 1/8: every vertex and every test point is dyadic, so each ray
    // o + t·d with o = p - 2d passes exactly through p (at t = 2).
    let (n, cell) = (64, 0.125);
    let tris = to_a(&grid(n, cell));
    let rays: Vec<_> = feature_rays(n, cell, 2400)
        .into_iter()
        .map(|(p, d, f)| (a(p - 2.0 * d), a(d), f))
        .collect();
    assert_no_fall_through(&tris, &rays, "axis-aligned grid");
}

#[test]
fn rays_through_shared_edges_and_vertices_of_a_tilted_grid_never_fall_through() {
    // The same grid rotated about a generic axis and moved off the origin, so that no edge is
    // axis aligned and the vertices are rounded. Targets are mapped with the same function, so
    // vertex targets are exactly the mesh vertices and edge targets lie within rounding of the
    // edge: every ray crosses the grid's interior, hence must hit.
    let (n, cell) = (64, 0.125);
    let rot = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let shift = Vec3::new(0.3, -1.7, 2.9);
    let f = |v: Vec3| rot * v + shift;
    let tris = to_a(&map_vertices(&grid(n, cell), f));
    let rays: Vec<_> = feature_rays(n, cell, 2400)
        .into_iter()
        .map(|(p, d, feat)| {
            let p = f(p);
            let d = rot * d;
            (a(p - 2.0 * d), a(d), feat)
        })
        .collect();
    assert_no_fall_through(&tris, &rays, "tilted grid");
}

#[test]
fn a_ray_through_a_shared_edge_hits_from_the_front_and_from_the_back() {
    // Two triangles sharing the edge from (0,0,0) to (1,1,0); the ray crosses that edge at
    // (0.5, 0.5, 0), coming from above (front) and from below (back).
    let tris = [
        [
            Vec3A::ZERO,
            Vec3A::new(1.0, 0.0, 0.0),
            Vec3A::new(1.0, 1.0, 0.0),
        ],
        [
            Vec3A::ZERO,
            Vec3A::new(1.0, 1.0, 0.0),
            Vec3A::new(0.0, 1.0, 0.0),
        ],
    ];
    let p = Vec3A::new(0.5, 0.5, 0.0);
    for d in [
        Vec3A::new(0.25, -0.5, -1.0),
        Vec3A::new(0.25, -0.5, 1.0),
        Vec3A::new(0.0, 0.0, -1.0),
        Vec3A::new(0.0, 0.0, 1.0),
        Vec3A::new(1.0, -1.0, -0.125),
        Vec3A::new(-1.0, 1.0, 0.125),
    ] {
        let o = p - 2.0 * d;
        let hits: Vec<_> = tris
            .iter()
            .filter_map(|t| intersect_triangle(o, d, t, 0.0, f32::INFINITY))
            .collect();
        assert!(
            !hits.is_empty(),
            "ray with d {d} fell through the shared edge"
        );
        for h in hits {
            assert_eq!(h.t, 2.0, "d {d}");
        }
    }
}
