//! Tests of [`SpherePoints`]: counts, exact `nearest` against brute force, `surrounding`,
//! triangulations and spacing.

use super::*;
use crate::sampling::rays::seeded_sphere_direction;

fn seeded(count: usize, seed: u64) -> Vec<Vec3> {
    (0..count as u64)
        .map(|i| seeded_sphere_direction(i, seed))
        .collect()
}

/// Directions that stress a nearest-point query: the points themselves, points nudged by tiny
/// angles, midpoints of triangle edges (on Voronoi edges when Delaunay), triangle circumcentres
/// (Voronoi vertices: three-way ties), the poles, the ±x seam and the equator.
fn adversarial(set: &SpherePoints) -> Vec<Vec3> {
    let mut v: Vec<Vec3> = set.points().to_vec();
    for (i, p) in set.points().iter().enumerate() {
        let nudge = Vec3::new(1e-4, -2e-4, 1.5e-4) * ((i % 7) as f32 - 3.0);
        v.push((*p + nudge).normalize());
    }
    for t in set.triangles() {
        let [a, b, c] = t.map(|i| set.point(i as usize));
        v.push((a + b).normalize());
        v.push((b - a).cross(c - a).normalize());
    }
    for i in 0..2000 {
        let t = std::f32::consts::PI * i as f32 / 2000.0;
        v.push(Vec3::new(-t.sin(), 1e-7, t.cos())); // the φ = ±π seam
        v.push(Vec3::new(t.cos(), t.sin(), 0.0)); // equator, φ ∈ [0, π)
        v.push(Vec3::new(-t.cos(), -t.sin(), 0.0));
    }
    v.extend([
        Vec3::Z,
        Vec3::NEG_Z,
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
    ]);
    v
}

/// At most `max` of [`adversarial`], evenly strided (the brute force costs N per direction).
fn adversarial_subset(set: &SpherePoints, max: usize) -> Vec<Vec3> {
    let all = adversarial(set);
    let stride = all.len().div_ceil(max);
    all.into_iter().step_by(stride).collect()
}

fn check_nearest(kind: SphereKind, count: usize, random: usize) {
    let set = SpherePoints::new(kind, count).unwrap();
    assert_eq!(set.len(), count);
    let dirs = seeded(random, 0x5eed ^ count as u64);
    // The analytic query (the grid's construction oracle) stays exact on its own.
    let some = &dirs[..dirs.len().min(100_000)];
    // ~10⁸ brute-force dot products per set at most.
    let adv = adversarial_subset(&set, (100_000_000 / count).min(50_000));
    for (what, all, analytic) in [
        ("random", &dirs[..], some),
        ("adversarial", &adv[..], &adv[..]),
    ] {
        let bad = set.nearest_mismatches(all);
        let name = kind.name();
        assert_eq!(
            bad,
            0,
            "{name} {count}: {bad} of {} {what} directions",
            all.len()
        );
        let bad = set.nearest_analytic_mismatches(analytic);
        assert_eq!(bad, 0, "{name} {count}: analytic, {bad} {what}");
    }
}

/// The papers' counts, with how many random directions each is checked on: 10⁶ for the small
/// sets, fewer for the large ones (the brute force costs N per direction); the report runs 10⁶
/// for every set.
const PAPER_COUNTS: [(usize, usize); 4] = [
    (290, 1_000_000),
    (1090, 1_000_000),
    (4226, 200_000),
    (16642, 20_000),
];

#[test]
fn slater_counts_are_the_papers() {
    // 2(2n² + 2n + 1) for n = 8, 16, 32, 64.
    for count in [290, 1090, 4226, 16642] {
        assert_eq!(
            SpherePoints::new(SphereKind::Slater, count).unwrap().len(),
            count
        );
    }
    assert_eq!(
        SpherePoints::new(SphereKind::LatLong, 1122).unwrap().len(),
        33 * 34
    );
}

#[test]
fn impossible_counts_list_valid_ones() {
    let err = SpherePoints::new(SphereKind::Slater, 1000)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("290") && err.contains("1090") && err.contains("[10, 26, 50"),
        "{err}"
    );
    let err = SpherePoints::new(SphereKind::LatLong, 1000)
        .unwrap_err()
        .to_string();
    assert!(err.contains("1122") && err.contains("[6, 12, 20"), "{err}");
    assert!(SpherePoints::new(SphereKind::Fibonacci, 3).is_err());
    assert!(SpherePoints::new(SphereKind::Slater, 0).is_err());
}

#[test]
fn slater_nearest_equals_brute_force() {
    for (count, random) in PAPER_COUNTS {
        check_nearest(SphereKind::Slater, count, random);
    }
    for n in 1..=6u64 {
        check_nearest(
            SphereKind::Slater,
            (2 * (2 * n * n + 2 * n + 1)) as usize,
            20_000,
        );
    }
}

#[test]
fn lat_long_nearest_equals_brute_force() {
    check_nearest(SphereKind::LatLong, 1122, 1_000_000);
    for rows in [2usize, 3, 7, 16, 64] {
        check_nearest(SphereKind::LatLong, rows * (rows + 1), 20_000);
    }
}

#[test]
fn fibonacci_nearest_equals_brute_force() {
    for (count, random) in PAPER_COUNTS {
        check_nearest(SphereKind::Fibonacci, count, random);
    }
    for n in [4usize, 5, 13, 21, 100, 1000, 1122] {
        check_nearest(SphereKind::Fibonacci, n, 20_000);
    }
}

#[test]
fn keinert_inverse_agrees_with_the_certified_query() {
    // Keinert et al.'s published four-corner inverse, checked against the certified query on
    // random directions, the adversarial set and the polar caps (where the zone basis is
    // coarsest and the pole reflection kicks in). It has never disagreed; the certificate makes
    // `nearest` exact without relying on that.
    for n in [20usize, 290, 1090, 4226, 16642] {
        let set = SpherePoints::new(SphereKind::Fibonacci, n).unwrap();
        let mut dirs = seeded(50_000, 11);
        dirs.extend(adversarial_subset(&set, 20_000));
        for i in 0..4000 {
            let (t, a) = (i as f32 * 5e-5, i as f32);
            let (s, c) = (t.sin(), t.cos());
            dirs.push(Vec3::new(s * a.cos(), s * a.sin(), c));
            dirs.push(Vec3::new(s * a.cos(), s * a.sin(), -c));
        }
        for &d in &dirs {
            let (k, e) = (set.nearest_keinert(d).unwrap(), set.nearest(d));
            let dd = d.as_dvec3();
            let gap = dd.dot(set.point(e).as_dvec3()) - dd.dot(set.point(k).as_dvec3());
            assert!(
                gap >= -1e-12,
                "n {n}: certified answer worse than Keinert's at {d}"
            );
            assert!(
                gap <= 1e-12,
                "n {n}: Keinert's inverse misses the nearest point at {d}"
            );
        }
    }
    assert!(SpherePoints::new(SphereKind::Slater, 290)
        .unwrap()
        .nearest_keinert(Vec3::Z)
        .is_none());
}

#[test]
fn triangulations_cover_the_sphere_once() {
    let cases: Vec<(SphereKind, usize)> = [290, 1090, 4226, 16642, 10, 26]
        .map(|c| (SphereKind::Slater, c))
        .into_iter()
        .chain([6, 12, 1122, 4160].map(|c| (SphereKind::LatLong, c)))
        .chain(
            [4, 5, 6, 7, 8, 13, 50, 290, 1090, 1122, 4226, 16642]
                .map(|c| (SphereKind::Fibonacci, c)),
        )
        .collect();
    for (kind, count) in cases {
        let set = SpherePoints::new(kind, count).unwrap();
        set.mesh()
            .validate(set.points(), 1e-7)
            .unwrap_or_else(|e| panic!("{} {count}: {e}", kind.name()));
        // A closed triangulation of V points on the sphere has 2V − 4 triangles.
        assert_eq!(
            set.triangles().len(),
            2 * count - 4,
            "{} {count}",
            kind.name()
        );
    }
}

#[test]
fn fibonacci_triangulation_is_delaunay_for_many_counts() {
    for n in (4..=300).chain([1000, 1090, 4226, 12345]) {
        let set = SpherePoints::new(SphereKind::Fibonacci, n).unwrap();
        set.mesh()
            .validate(set.points(), 1e-7)
            .unwrap_or_else(|e| panic!("n = {n}: {e}"));
        let v = set.mesh().max_delaunay_violation(set.points());
        assert!(
            v < 1e-9,
            "n = {n}: an apex lies {v} above a neighbour's plane"
        );
    }
}

#[test]
fn surrounding_weights_reproduce_the_direction() {
    for (kind, count) in [
        (SphereKind::Slater, 290),
        (SphereKind::Slater, 4226),
        (SphereKind::LatLong, 1122),
        (SphereKind::Fibonacci, 1090),
        (SphereKind::Fibonacci, 16642),
    ] {
        let set = SpherePoints::new(kind, count).unwrap();
        for &d in seeded(20_000, 3).iter().chain(&adversarial(&set)) {
            let (idx, w) = set.surrounding(d);
            assert!(
                w.iter().all(|&x| x >= -1e-6),
                "{} {count}: weights {w:?}",
                kind.name()
            );
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            // Planar barycentrics of the ray's hit: the blend is parallel to d.
            let err = blend(&set, idx, w).angle_between(d.as_dvec3().normalize());
            assert!(
                err < 1e-5,
                "{} {count}: blend off by {err} rad at {d}",
                kind.name()
            );
            // The triangle contains d, so the walk must not need its fallback.
            let start = set.nearest(d);
            let steps = 64 + 4 * (count as f64).sqrt() as usize;
            assert!(
                set.mesh()
                    .try_locate(set.points(), d.as_dvec3(), start, steps)
                    .is_some(),
                "{} {count}: walk did not settle at {d}",
                kind.name()
            );
        }
        for i in 0..count {
            let (idx, w) = set.surrounding(set.point(i));
            let k = idx
                .iter()
                .position(|&j| j == i)
                .expect("a point is a vertex of its triangle");
            assert!(
                (w[k] - 1.0).abs() < 1e-5,
                "{} {count}: point {i} weight {}",
                kind.name(),
                w[k]
            );
        }
    }
}

#[test]
fn spacing_matches_nearest_at_voronoi_vertices() {
    // The covering radius is attained at a Voronoi vertex: the circumcentre of some Delaunay
    // triangle, whose nearest point is then exactly one circumradius away.
    for (kind, count) in [
        (SphereKind::Slater, 1090),
        (SphereKind::LatLong, 1122),
        (SphereKind::Fibonacci, 1090),
    ] {
        let set = SpherePoints::new(kind, count).unwrap();
        let sp = set.spacing().unwrap();
        let del = set.mesh().delaunay(set.points(), 1e-9).unwrap();
        for (c, r) in del.circumradii(set.points()) {
            let near = set.point(set.nearest(c.as_vec3())).as_dvec3();
            let dist = near.dot(c).clamp(-1.0, 1.0).acos();
            assert!(
                (dist - r).abs() < 1e-5,
                "{}: circumradius {r}, nearest at {dist}",
                kind.name()
            );
        }
        // No random direction is farther than the covering radius from its nearest point.
        for d in seeded(100_000, 9) {
            let p = set.point(set.nearest(d)).as_dvec3();
            assert!(p.dot(d.as_dvec3()).clamp(-1.0, 1.0).acos() <= sp.max_gap + 1e-6);
        }
        assert!(sp.min_separation > 0.0 && sp.min_separation < sp.max_gap * 2.0);
    }
}

#[test]
fn lat_long_spacing_has_a_closed_form() {
    // 33 × 34 at cell centres: the closest pair is two neighbours on the first row,
    // 2·asin(sin θ₀ · sin(π/34)) apart with θ₀ = π/66.
    let set = SpherePoints::new(SphereKind::LatLong, 1122).unwrap();
    let t0 = std::f64::consts::PI / 66.0;
    let expect = 2.0 * (t0.sin() * (std::f64::consts::PI / 34.0).sin()).asin();
    let sp = set.spacing().unwrap();
    assert!(
        (sp.min_separation - expect).abs() < 1e-6,
        "{} vs {expect}",
        sp.min_separation
    );
}
