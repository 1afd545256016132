use super::*;
use crate::trace::test_scenes::{
    feature_rays, grid, icosphere, map_vertices, ploc_worst_cases, random_point, random_soup,
    random_unit,
};
use crate::trace::watertight::{intersect_triangle, TriangleHit};
use glam::Quat;

/// The brute-force reference: the watertight test over every triangle, smallest t wins
/// (lowest index on ties).
fn brute_closest(
    tris: &[[Vec3; 3]],
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
) -> Option<(u32, TriangleHit)> {
    let mut best: Option<(u32, TriangleHit)> = None;
    for (i, t) in tris.iter().enumerate() {
        let t = t.map(Vec3A::from);
        if let Some(h) = intersect_triangle(o.into(), d.into(), &t, tmin, tmax) {
            if best.is_none_or(|(_, b)| h.t < b.t) {
                best = Some((i as u32, h));
            }
        }
    }
    best
}

/// Asserts that the tracer's closest and any hit agree exactly with the brute-force loop.
fn assert_matches_brute_force(tracer: &Tracer, tris: &[[Vec3; 3]], q: &RayQuery) {
    let got = tracer.closest_hit(q.origin, q.dir, q.tmin, q.tmax);
    let want = brute_closest(tris, q.origin, q.dir, q.tmin, q.tmax);
    match (got, want) {
        (None, None) => {}
        (Some(h), Some((_, w))) => {
            assert_eq!(h.t, w.t, "closest t differs for {q:?}");
            // On ties the tracer may report another triangle: it must be hit at the same t,
            // with the barycentrics the watertight test gives for it.
            let tri = tris[h.triangle as usize].map(Vec3A::from);
            let own = intersect_triangle(q.origin.into(), q.dir.into(), &tri, q.tmin, q.tmax)
                .expect("reported triangle is not hit");
            assert_eq!((own.t, own.u, own.v), (h.t, h.u, h.v), "{q:?}");
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
            assert!((Vec3A::from(h.normal) - n).length() < 1e-6);
        }
        (g, w) => panic!("tracer {g:?} vs brute force {w:?} for {q:?}"),
    }
    assert_eq!(
        tracer.any_hit(q.origin, q.dir, q.tmin, q.tmax),
        want.is_some(),
        "any-hit differs for {q:?}"
    );
}

#[test]
fn empty_tracer_always_misses() {
    let tracer = Tracer::new(&[]);
    assert!(tracer.is_empty());
    assert_eq!(
        tracer.closest_hit(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY),
        None
    );
    assert!(!tracer.any_hit(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY));
    let q = RayQuery {
        origin: Vec3::ZERO,
        dir: Vec3::X,
        tmin: 0.0,
        tmax: 1.0,
    };
    assert_eq!(tracer.closest_hits(&[q; 3]), vec![None; 3]);
    assert_eq!(tracer.any_hits(&[q; 3]), vec![false; 3]);
}

#[test]
fn agrees_with_brute_force_on_a_random_soup() {
    let tris = random_soup(3000, 0.15, 11);
    let tracer = Tracer::new(&tris);
    assert_eq!(tracer.len(), tris.len());
    let mut hits = 0;
    for i in 0..10_000u32 {
        let q = RayQuery {
            origin: 1.5 * random_point(i, 12),
            dir: random_unit(i, 13),
            tmin: if i % 5 == 0 { 0.05 } else { 0.0 },
            tmax: if i % 3 == 0 { 0.7 } else { f32::INFINITY },
        };
        assert_matches_brute_force(&tracer, &tris, &q);
        hits += tracer.any_hit(q.origin, q.dir, q.tmin, q.tmax) as u32;
    }
    assert!(
        hits > 2000 && hits < 9000,
        "degenerate test: {hits} hits of 10000"
    );
}

#[test]
fn agrees_with_brute_force_on_a_closed_sphere_and_inside_rays_always_hit() {
    let centre = Vec3::new(0.1, -0.2, 0.3);
    let tris = icosphere(4, 1.0, centre); // 5120 triangles
    let tracer = Tracer::new(&tris);
    for i in 0..10_000u32 {
        // Inside: a point of the ball of radius 0.9 (the icosphere contains the ball of
        // radius cos(edge angle) > 0.99); every ray must leave through the closed surface.
        let p = random_point(i, 21);
        let origin = centre + 0.9 * p / p.length().max(1.0);
        let dir = random_unit(i, 22);
        assert!(
            tracer.any_hit(origin, dir, 0.0, f32::INFINITY),
            "ray {i} escaped"
        );
        let q = RayQuery {
            origin,
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        if i % 4 == 0 {
            assert_matches_brute_force(&tracer, &tris, &q);
        } else {
            let h = tracer
                .closest_hit(origin, dir, 0.0, f32::INFINITY)
                .expect("inside ray");
            assert!((0.0..2.0).contains(&h.t));
        }
        // Outside: a mix of hits and misses.
        let q = RayQuery {
            origin: centre + 2.0 * random_point(i, 23),
            dir: random_unit(i, 24),
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        if i % 4 == 0 {
            assert_matches_brute_force(&tracer, &tris, &q);
        }
    }
}

#[test]
fn t_range_is_inclusive_and_cuts_exactly() {
    let tris = random_soup(500, 0.2, 31);
    let tracer = Tracer::new(&tris);
    let mut checked = 0;
    for i in 0..2000u32 {
        let (o, d) = (1.5 * random_point(i, 32), random_unit(i, 33));
        let Some(h) = tracer.closest_hit(o, d, 0.0, f32::INFINITY) else {
            continue;
        };
        checked += 1;
        // tmax = t keeps the hit; one ulp less removes it, and nothing is closer.
        assert_eq!(tracer.closest_hit(o, d, 0.0, h.t).map(|x| x.t), Some(h.t));
        assert!(tracer.any_hit(o, d, 0.0, h.t));
        assert_eq!(tracer.closest_hit(o, d, 0.0, h.t.next_down()), None);
        // An empty or NaN range never hits.
        assert_eq!(tracer.closest_hit(o, d, h.t + 1.0, h.t), None);
        assert!(!tracer.any_hit(o, d, 0.0, f32::NAN));
        assert!(!tracer.any_hit(o, d, f32::NAN, f32::INFINITY));
        assert!(!tracer.any_hit(o, d, 0.0, h.t.next_down()));
        // tmin = t keeps it too; one ulp more gives the next hit of the brute-force loop.
        assert_eq!(
            tracer.closest_hit(o, d, h.t, f32::INFINITY).map(|x| x.t),
            Some(h.t)
        );
        let q = RayQuery {
            origin: o,
            dir: d,
            tmin: h.t.next_up(),
            tmax: f32::INFINITY,
        };
        assert_matches_brute_force(&tracer, &tris, &q);
    }
    assert!(checked > 200, "only {checked} rays hit");
}

/// Rays exactly through grid vertices and edges (including exactly axis-aligned ones, where
/// obvhs replaces the zero direction components by ±f32::EPSILON) must not be lost by the box
/// test: the tracer must report the brute-force closest t for every one, unit direction or not.
#[test]
fn box_test_does_not_lose_rays_through_grid_edges_and_vertices() {
    let (n, cell) = (64, 0.125);
    let rot = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let shift = Vec3::new(0.3, -1.7, 2.9);
    for (label, rot, shift) in [
        ("axis-aligned", Quat::IDENTITY, Vec3::ZERO),
        ("tilted", rot, shift),
        (
            "far off-centre",
            Quat::IDENTITY,
            Vec3::new(1024.0, -512.0, 64.0),
        ),
    ] {
        let f = |v: Vec3| rot * v + shift;
        let tris = map_vertices(&grid(n, cell), f);
        let tracer = Tracer::new(&tris);
        let unpadded = unpadded_obvhs::Unpadded::new(&tris);
        let mut unpadded_lost = 0;
        let rays = feature_rays(n, cell, 600);
        for &(p, d, _) in &rays {
            let (p, d) = (f(p), rot * d);
            for dir in [d, d.normalize()] {
                let q = RayQuery {
                    origin: p - 2.0 * dir,
                    dir,
                    tmin: 0.0,
                    tmax: f32::INFINITY,
                };
                assert_matches_brute_force(&tracer, &tris, &q);
                if !unpadded.any_hit(q.origin, q.dir) {
                    unpadded_lost += 1;
                    println!("  unpadded obvhs lost o {} d {}", q.origin, q.dir);
                }
            }
        }
        println!(
            "{label} grid: {} rays, padded+scaled tracer lost 0, unpadded obvhs boxes lost \
             {unpadded_lost}",
            2 * rays.len()
        );
    }
}

/// A scene far smaller than obvhs's absolute box epsilon (1e-4): the grid scaled by 2^-20
/// (cells of 2^-23) must give exactly the unscaled results scaled by 2^-20.
#[test]
fn results_scale_exactly_with_the_scene() {
    let s = 1.0 / (1u32 << 20) as f32;
    let big = grid(16, 0.125);
    let small = map_vertices(&big, |v| v * s);
    let (tb, ts) = (Tracer::new(&big), Tracer::new(&small));
    for (i, &(p, d, _)) in feature_rays(16, 0.125, 400).iter().enumerate() {
        let o = p - 2.0 * d + 0.01 * random_point(i as u32, 41);
        let hb = tb.closest_hit(o, d, 0.0, f32::INFINITY);
        let hs = ts.closest_hit(o * s, d, 0.0, f32::INFINITY);
        assert_eq!(hb.map(|h| h.t * s), hs.map(|h| h.t), "ray {i}");
        assert_eq!(hb.map(|h| (h.u, h.v)), hs.map(|h| (h.u, h.v)), "ray {i}");
        assert!(hb.is_some() == ts.any_hit(o * s, d, 0.0, f32::INFINITY));
    }
}

#[test]
fn batched_queries_equal_single_queries() {
    let tris = random_soup(1000, 0.2, 51);
    let tracer = Tracer::new(&tris);
    let rays: Vec<RayQuery> = (0..3000u32)
        .map(|i| RayQuery {
            origin: 1.5 * random_point(i, 52),
            dir: random_unit(i, 53),
            tmin: 0.0,
            tmax: if i % 2 == 0 { 1.0 } else { f32::INFINITY },
        })
        .collect();
    let closest = tracer.closest_hits(&rays);
    let any = tracer.any_hits(&rays);
    for (i, q) in rays.iter().enumerate() {
        assert_eq!(
            closest[i],
            tracer.closest_hit(q.origin, q.dir, q.tmin, q.tmax)
        );
        assert_eq!(any[i], closest[i].is_some());
    }
}

/// obvhs used as is (unpadded triangle boxes, unscaled scene), for comparison only.
mod unpadded_obvhs {
    use super::*;
    use obvhs::{cwbvh::builder::build_cwbvh_from_tris, triangle::Triangle, BvhBuildParams};
    use std::time::Duration;

    pub struct Unpadded {
        bvh: CwBvh,
        tris: Vec<[Vec3A; 3]>,
    }

    impl Unpadded {
        pub fn new(tris: &[[Vec3; 3]]) -> Self {
            let t: Vec<Triangle> = tris
                .iter()
                .map(|t| Triangle {
                    v0: t[0].into(),
                    v1: t[1].into(),
                    v2: t[2].into(),
                })
                .collect();
            let bvh =
                build_cwbvh_from_tris(&t, BvhBuildParams::medium_build(), &mut Duration::default());
            let tris = bvh
                .primitive_indices
                .iter()
                .map(|&i| tris[i as usize].map(Vec3A::from))
                .collect();
            Unpadded { bvh, tris }
        }

        pub fn any_hit(&self, o: Vec3, d: Vec3) -> bool {
            let w = WatertightRay::new(o.into(), d.into());
            !self
                .bvh
                .ray_traverse_miss(Ray::new_inf(o.into(), d.into()), |_, id| {
                    let [a, b, c] = self.tris[id];
                    match w.intersect(a, b, c, 0.0, f32::INFINITY) {
                        Some(_) => f32::NEG_INFINITY,
                        None => f32::INFINITY,
                    }
                })
        }
    }
}

/// A direction with a −0 component (`-Vec3::Z` is (−0, −0, −1)) hits what the same direction
/// with +0 hits: obvhs took the ray's octant from `d < 0` but its inverse from the sign, and
/// such rays missed everything.
#[test]
fn directions_with_negative_zero_components_hit() {
    let tris = grid(8, 0.25);
    let tracer = Tracer::new(&tris);
    let mut hits = 0;
    for (o, d) in [
        (Vec3::new(0.3, 0.7, 1.0), -Vec3::Z),
        (Vec3::new(0.3, 0.7, 1.0), Vec3::new(-0.0, 0.0, -1.0)),
        (Vec3::new(0.3, 0.7, 1.0), Vec3::new(0.0, -0.0, -1.0)),
        (Vec3::new(0.3, 0.7, -1.0), Vec3::new(-0.0, -0.0, 1.0)),
        (Vec3::new(0.3, 2.0, 0.0), Vec3::new(-0.0, -1.0, -0.0)),
    ] {
        let q = RayQuery {
            origin: o,
            dir: d,
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        assert_matches_brute_force(&tracer, &tris, &q);
        hits += tracer.any_hit(o, d, 0.0, f32::INFINITY) as u32;
    }
    assert_eq!(hits, 4, "the last ray runs in the grid's plane");
}

/// The inputs on which PLOC takes quadratic time build in well under a second at 20,000
/// triangles (PLOC took 18 s on 20,000 copies of one triangle) and answer as brute force does.
#[test]
fn ploc_worst_cases_build_fast_and_agree_with_brute_force() {
    for (name, tris) in ploc_worst_cases(20_000) {
        let t = std::time::Instant::now();
        let tracer = Tracer::new(&tris);
        let build = t.elapsed();
        assert!(build.as_secs_f64() < 2.0, "{name}: built in {build:?}");
        assert_eq!(tracer.len(), tris.len());
        for i in 0..16u32 {
            let q = RayQuery {
                origin: Vec3::new(0.05 + 0.06 * i as f32, 0.2, 1.0),
                dir: random_unit(i, 5) * 0.1 - Vec3::Z,
                tmin: 0.0,
                tmax: f32::INFINITY,
            };
            assert_matches_brute_force(&tracer, &tris, &q);
        }
        assert!(
            tracer.any_hit(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, 0.0, 2.0),
            "{name}"
        );
    }
}
