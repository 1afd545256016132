//! Tests of [`HemisphereLayout`]: exact round trips, masks, measures and a chi-square test of
//! the cosine density.

use super::*;
use crate::sampling::rays::uniform;
use crate::sampling::warp::square_to_uniform_hemisphere;
use glam::DVec3;

const RESOLUTIONS: [u32; 4] = [32, 64, 128, 256];

fn layouts(res: u32) -> [HemisphereLayout; 3] {
    LayoutKind::ALL.map(|k| HemisphereLayout::new(k, res))
}

#[test]
fn round_trip_is_exact_on_every_used_texel() {
    // 3 · (32² + 64² + 128² + 256²) texel centres, plus small and odd sizes.
    for res in RESOLUTIONS.into_iter().chain(1..=9).chain([17, 33, 255]) {
        for layout in layouts(res) {
            for t in 0..layout.texel_count() as u32 {
                match layout.to_direction(t) {
                    Some(d) => {
                        assert!((d.length() - 1.0).abs() < 1e-5 && d.z >= 0.0);
                        let back = layout.to_texel(d);
                        assert_eq!(
                            back,
                            t,
                            "{:?} {res}: texel {t} {:?} -> {d} -> {back} {:?}",
                            layout.kind,
                            layout.col_row(t),
                            layout.col_row(back)
                        );
                    }
                    None => assert!(!layout.is_used(t)),
                }
            }
        }
    }
}

#[test]
fn unused_mask_follows_the_disk() {
    for res in RESOLUTIONS {
        let [polar, rejection, concentric] = layouts(res);
        assert_eq!(polar.used_count(), polar.texel_count());
        assert_eq!(concentric.used_count(), concentric.texel_count());
        let used = rejection.used_count();
        assert_eq!(
            used,
            (0..rejection.texel_count() as u32)
                .filter(|&t| rejection.to_direction(t).is_some())
                .count()
        );
        // Unused fraction → 1 − π/4 ≈ 21.46 %; the rim error is at most the cells the circle
        // crosses, fewer than 4·2·res of res².
        let unused = 1.0 - used as f64 / rejection.texel_count() as f64;
        assert!(
            (unused - (1.0 - PI / 4.0)).abs() < 8.0 / res as f64,
            "res {res}: {unused}"
        );
    }
    // Smallest cases by hand: res 2 has all four centres at (±½, ±½), inside the disk; res 3:
    // the corner centres (±⅔, ±⅔) have r² = 8/9 < 1, so all nine are used; at res 4 the corner
    // centres (±¾, ±¾) have r² = 9/8 > 1: 12 of 16 used.
    for (res, used) in [(2, 4), (3, 9), (4, 12)] {
        let layout = HemisphereLayout::new(LayoutKind::Rejection, res);
        assert_eq!(layout.used_count(), used, "res {res}");
    }
}

#[test]
fn solid_angles_sum_to_the_hemisphere() {
    for res in RESOLUTIONS {
        for layout in layouts(res) {
            let n = layout.texel_count() as u32;
            let omega: f64 = (0..n).map(|t| layout.solid_angle(t)).sum();
            let proj: f64 = (0..n).map(|t| layout.projected_solid_angle(t)).sum();
            assert!(
                (omega / TAU - 1.0).abs() < 1e-9,
                "{:?} {res}: Σω = {omega}",
                layout.kind
            );
            assert!(
                (proj / PI - 1.0).abs() < 1e-9,
                "{:?} {res}: Σ cos ω = {proj}",
                layout.kind
            );
            assert!((0..n).all(|t| layout.solid_angle(t) >= 0.0));
            let used: f64 = (0..n)
                .filter(|&t| layout.is_used(t))
                .map(|t| layout.solid_angle(t))
                .sum();
            let rim = layout.rim_solid_angle();
            assert!((used + rim - omega).abs() < 1e-9);
            if layout.kind == LayoutKind::Rejection {
                // Rim slivers: a band of width ~1/res in r under the 1/√(1 − r²) singularity,
                // so O(res^−½) sr: between 0.05 and 1.5 sr at these sizes.
                assert!(rim > 0.05 && rim < 1.5, "res {res}: rim {rim}");
            } else {
                assert_eq!(rim, 0.0);
            }
        }
    }
}

#[test]
fn concentric_texels_have_equal_projected_solid_angle() {
    // The concentric map preserves fractional area: each texel's disk area is π/res².
    let l = HemisphereLayout::new(LayoutKind::Concentric, 64);
    let expect = PI / (64.0 * 64.0);
    for t in 0..l.texel_count() as u32 {
        assert_eq!(l.projected_solid_angle(t), expect);
    }
    // Polar: a row's texels share Δφ (cos θ₀ − cos θ₁); row 0 at res 4: (2π/4)(1 − cos(π/8)).
    let p = HemisphereLayout::new(LayoutKind::Polar, 4);
    let expect = TAU / 4.0 * (1.0 - (PI / 8.0).cos());
    assert!((p.solid_angle(0) - expect).abs() < 1e-15 && (p.solid_angle(3) - expect).abs() < 1e-15);
}

/// Solid angle of the image of texel t's cell as a spherical polygon: the cell boundary is
/// mapped point by point with an f64 copy of the forward map (k points per side) and the polygon's area summed
/// as a fan of spherical triangles around the texel direction (Van Oosterom–Strackee). It uses
/// only the forward map, so it checks the closed forms independently.
fn polygon_solid_angle(layout: &HemisphereLayout, t: u32, k: usize) -> f64 {
    let (c, r) = layout.col_row(t);
    let res = layout.res as f64;
    // The forward maps again, in f64: near the horizon f32 rounding of 1 − r² lifts rim points
    // by up to ~3e-4 rad, which would bias rim texels by ~1e-4 relative.
    let map = |u: f64, v: f64| -> DVec3 {
        let lift = |x: f64, y: f64| DVec3::new(x, y, (1.0 - x * x - y * y).max(0.0).sqrt());
        match layout.kind {
            LayoutKind::Polar => {
                let (t, p) = (v * FRAC_PI_2, u * TAU);
                DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
            }
            LayoutKind::Rejection => lift(2.0 * u - 1.0, 2.0 * v - 1.0),
            LayoutKind::Concentric => {
                // Shirley–Chiu: r = max(|a|, |b|), angle linear along each square ring.
                let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
                let (r, phi) = if a == 0.0 && b == 0.0 {
                    (0.0, 0.0)
                } else if a.abs() > b.abs() {
                    (a, std::f64::consts::FRAC_PI_4 * (b / a))
                } else {
                    (b, FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a / b))
                };
                lift(r * phi.cos(), r * phi.sin())
            }
        }
        .normalize()
    };
    let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0)];
    let mut ring = Vec::new();
    for w in corners.windows(2) {
        for i in 0..k {
            // Points cluster at the corners (s ≈ (πi/2k)² there): where a side meets the rim,
            // z ∝ √(1 − r) would otherwise make the first chord cut a large corner off.
            let s = 0.5 * (1.0 - (std::f64::consts::PI * i as f64 / k as f64).cos());
            let (a, b) = (
                w[0].0 + s * (w[1].0 - w[0].0),
                w[0].1 + s * (w[1].1 - w[0].1),
            );
            ring.push(map((c as f64 + a) / res, (r as f64 + b) / res));
        }
    }
    let o = map((c as f64 + 0.5) / res, (r as f64 + 0.5) / res);
    let mut area = 0.0;
    for i in 0..ring.len() {
        let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
        let det = o.dot(a.cross(b));
        area += 2.0 * det.atan2(1.0 + o.dot(a) + a.dot(b) + b.dot(o));
    }
    area.abs()
}

#[test]
fn closed_form_solid_angles_match_spherical_polygons() {
    for layout in layouts(32) {
        for t in (0..1024u32).step_by(37).chain([0, 31, 496, 527, 1023]) {
            let (c, r) = layout.col_row(t);
            // Rejection: only cells wholly inside the disk (corners within radius 1).
            let far = |i: u32| {
                ((2 * i as i64 - 32).abs().max((2 * i as i64 + 2 - 32).abs())) as f64 / 32.0
            };
            if layout.kind == LayoutKind::Rejection && far(c).hypot(far(r)) >= 1.0 {
                continue;
            }
            let exact = layout.solid_angle(t);
            // 1024 chords per side: the polygon converges as k⁻², to ~1e-7 relative here.
            let poly = polygon_solid_angle(&layout, t, 1024);
            assert!(
                (exact - poly).abs() < 1e-6 * exact,
                "{:?} texel {t}: closed form {exact}, polygon {poly}",
                layout.kind
            );
        }
    }
}

#[test]
fn rejection_rim_goes_to_the_nearest_used_texel() {
    for res in [4u32, 5, 8, 32] {
        let l = HemisphereLayout::new(LayoutKind::Rejection, res);
        let used: Vec<u32> = (0..l.texel_count() as u32)
            .filter(|&t| l.is_used(t))
            .collect();
        let mut rim_hits = 0;
        for i in 0..20_000u32 {
            // Directions near the horizon (and a few below it) hit the rim slivers.
            let phi = std::f32::consts::TAU * uniform(i, 0, 0, 7);
            let z = 0.2 * uniform(i, 1, 0, 7) - 0.02;
            let s = (1.0 - z * z).sqrt();
            let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
            let t = l.to_texel(d);
            assert!(l.is_used(t), "res {res}: {d} -> unused {t}");
            if l.is_used(l.to_cell(d)) {
                assert_eq!(t, l.to_cell(d));
                continue;
            }
            rim_hits += 1;
            let p = l.to_texel_continuous(d);
            let dist = |t: u32| {
                let (c, r) = l.col_row(t);
                (Vec2::new(c as f32 + 0.5, r as f32 + 0.5) - p).length_squared()
            };
            let best = used.iter().map(|&u| dist(u)).fold(f32::INFINITY, f32::min);
            assert!(
                dist(t) <= best + 1e-6,
                "res {res}: {d} -> {t}, not the nearest used texel"
            );
        }
        assert!(
            rim_hits > 100,
            "res {res}: the test must reach the rim ({rim_hits})"
        );
    }
}

#[test]
fn below_horizon_and_continuous_coordinates() {
    for layout in layouts(64) {
        // Below the horizon: same texel as the horizon direction of the same azimuth.
        for i in 0..360 {
            let a = (i as f32).to_radians();
            let below = Vec3::new(a.cos() * 0.8, a.sin() * 0.8, -0.6);
            let horizon = Vec3::new(a.cos(), a.sin(), 0.0);
            assert_eq!(
                layout.to_texel(below),
                layout.to_texel(horizon),
                "{:?} at {i}°",
                layout.kind
            );
        }
        assert!(layout.is_used(layout.to_texel(Vec3::NEG_Z)));
        for t in (0..layout.texel_count() as u32).filter(|&t| layout.is_used(t)) {
            let d = layout.to_direction(t).unwrap();
            let p = layout.to_texel_continuous(d);
            let (c, r) = layout.col_row(t);
            assert!(
                (p - Vec2::new(c as f32 + 0.5, r as f32 + 0.5))
                    .abs()
                    .max_element()
                    < 1e-2
            );
        }
    }
    assert!(HemisphereLayout::try_new(LayoutKind::Polar, 0).is_err());
    assert!(HemisphereLayout::try_new(LayoutKind::Polar, MAX_LAYOUT_RES + 1).is_err());
}

/// Upper p-quantile of χ²(k) by the Wilson–Hilferty approximation, z the normal quantile.
fn chi_square_quantile(k: f64, z: f64) -> f64 {
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

/// Pearson's statistic of `counts` against probabilities `prob` (bins with expected count below
/// 5 are pooled), and its degrees of freedom.
fn chi_square(counts: &[u64], prob: &[f64], m: u64) -> (f64, f64) {
    let (mut stat, mut bins) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (&o, &p) in counts.iter().zip(prob) {
        let e = p * m as f64;
        if e < 5.0 {
            pool_o += o as f64;
            pool_e += e;
            continue;
        }
        stat += (o as f64 - e).powi(2) / e;
        bins += 1;
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e).powi(2) / pool_e.max(1e-12);
        bins += 1;
    }
    (stat, bins as f64 - 1.0)
}

/// Probability that a cosine-distributed direction lands in each texel through `to_texel`:
/// the texel's own cell, plus, for the rejection layout, its share of the rim slivers of unused
/// cells (sub-cells of 1/96 texel side assigned by their centre, weighted by exact disk area;
/// misassigned area stays below 1/96 of a texel, a few counts against a σ of ~14 at res 32).
fn to_texel_probabilities(l: &HemisphereLayout) -> Vec<f64> {
    let n = l.texel_count() as u32;
    let mut p: Vec<f64> = (0..n)
        .map(|t| {
            if l.is_used(t) {
                l.cosine_probability(t)
            } else {
                0.0
            }
        })
        .collect();
    let sub = 96u32;
    let res = l.res as f64;
    for t in (0..n).filter(|&t| !l.is_used(t)) {
        let (c, r) = l.col_row(t);
        for j in 0..sub {
            for i in 0..sub {
                let x0 = 2.0 * (c as f64 + i as f64 / sub as f64) / res - 1.0;
                let y0 = 2.0 * (r as f64 + j as f64 / sub as f64) / res - 1.0;
                let h = 2.0 / (res * sub as f64);
                let area = disk_rect_area(x0, x0 + h, y0, y0 + h);
                if area == 0.0 {
                    continue;
                }
                let q = Vec2::new((x0 + 0.5 * h) as f32, (y0 + 0.5 * h) as f32);
                let q = if q.length_squared() > 1.0 {
                    q.normalize()
                } else {
                    q
                };
                p[l.to_texel(super::disk_to_hemisphere(q)) as usize] += area / PI;
            }
        }
    }
    p
}

#[test]
fn texels_sample_the_cosine_density() {
    // Cosine directions from an independent sampler (sin θ = √u₁, φ = 2π u₂, not the concentric
    // map) binned by to_texel must match each texel's probability: χ² below its p = 1e-3 quantile
    // (z = 3.0902). Uniform-hemisphere directions must fail the same test.
    let m = 200_000u64;
    let cosine = |i: u32| {
        let (u1, u2) = (uniform(i, 0, 0, 99), uniform(i, 0, 1, 99));
        let (s, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
        Vec3::new(s * phi.cos(), s * phi.sin(), (1.0 - u1).sqrt())
    };
    let flat = |i: u32| {
        square_to_uniform_hemisphere(Vec2::new(uniform(i, 0, 0, 99), uniform(i, 0, 1, 99)))
    };
    for res in [16u32, 32] {
        for layout in layouts(res) {
            let prob = to_texel_probabilities(&layout);
            assert!((prob.iter().sum::<f64>() - 1.0).abs() < 1e-6);
            let bin = |f: &dyn Fn(u32) -> Vec3| {
                let mut counts = vec![0u64; layout.texel_count()];
                for i in 0..m as u32 {
                    counts[layout.to_texel(f(i)) as usize] += 1;
                }
                counts
            };
            let (stat, df) = chi_square(&bin(&cosine), &prob, m);
            let limit = chi_square_quantile(df, 3.0902);
            assert!(
                stat < limit,
                "{:?} {res}: χ² = {stat:.1} ≥ {limit:.1} (df {df})",
                layout.kind
            );
            let (stat, df) = chi_square(&bin(&flat), &prob, m);
            let limit = chi_square_quantile(df, 3.0902);
            assert!(
                stat > limit,
                "{:?} {res}: uniform samples pass (χ² = {stat:.1})",
                layout.kind
            );
        }
    }
}

#[test]
fn wilson_hilferty_matches_tables() {
    // χ²(100) upper 0.1 % quantile is 149.449 (standard tables); χ²(255): 330.52.
    assert!((chi_square_quantile(100.0, 3.0902) - 149.449).abs() < 0.3);
    assert!((chi_square_quantile(255.0, 3.0902) - 330.52).abs() < 0.6);
}
