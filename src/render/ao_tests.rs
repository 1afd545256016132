use super::*;
use crate::trace::test_scenes::{
    disk_fan, icosphere, random_point, random_soup, random_unit, square,
};
use crate::trace::Tracer;

/// Unoccluded ray fraction predicted for a point on the axis of a disk whose edge is seen at
/// sin θ₀ = s, with `RaySet::new(k, _)` (centred strata): the concentric map sends the square's
/// concentric square rings to disk rings, and Malley's projection keeps the disk radius as
/// sin θ, so the ray of cell (i, j) has sin θ = max(|a|, |b|) with (a, b) the cell centre in
/// [-1, 1]²: (2m+1)/k for ring m = 0 .. k/2-1, which holds 8m+4 cells. The rays blocked by the
/// disk are the rings with (2m+1)/k < s: `n` rings, (2n)² cells, so AO = 1 − (2n/k)².
fn stratified_disk_ao(k: u32, s: f64) -> f64 {
    let n = (0..k / 2)
        .filter(|&m| ((2 * m + 1) as f64 / k as f64) < s)
        .count() as f64;
    1.0 - (2.0 * n / k as f64).powi(2)
}

#[test]
fn unoccluded_plane_has_ao_one() {
    // Points on a large square, normal up, nothing above: every ray leaves, AO = 1 exactly.
    // Normal down: the plane is behind the offset origin and nothing is below, AO = 1 too.
    let tracer = Tracer::new(&square(10.0, 0.0));
    let points: Vec<Vec3> = (0..64)
        .map(|i| random_point(i, 1) * Vec3::new(5.0, 5.0, 0.0))
        .collect();
    let opts = AoOptions::for_scene_radius(10.0);
    for n in [Vec3::Z, -Vec3::Z] {
        let ao = ao_at_points(&tracer, &points, &vec![n; 64], &RaySet::new(16, 3), &opts);
        assert!(ao.iter().all(|&a| a == 1.0), "{ao:?}");
    }
}

#[test]
fn point_inside_a_closed_sphere_has_ao_zero() {
    // Every ray from the centre of a closed (watertight) sphere hits it: AO = 0 exactly,
    // whatever the normal.
    let tris = icosphere(3, 1.0, Vec3::ZERO); // 1280 triangles
    let tracer = Tracer::new(&tris);
    let normals: Vec<Vec3> = (0..8).map(|i| random_unit(i, 5)).collect();
    let points = vec![Vec3::ZERO; normals.len()];
    let ao = ao_at_points(
        &tracer,
        &points,
        &normals,
        &RaySet::new(16, 9),
        &AoOptions::for_scene_radius(1.0),
    );
    assert!(ao.iter().all(|&a| a == 0.0), "{ao:?}");
}

#[test]
fn under_a_disk_ao_matches_the_closed_form() {
    // A point at the origin, normal up, under a disk of radius r at height h. The disk subtends
    // the cone θ < θ₀ with sin²θ₀ = r²/(h²+r²); under the cosine density p(ω) = cos θ/π the
    // blocked fraction is ∫₀^θ₀ 2π cos θ sin θ dθ / π = sin²θ₀, so
    //     AO = 1 − r²/(h²+r²) = h²/(h²+r²).
    // With 64² centred strata the estimate is exactly 1 − (2n/64)² (see stratified_disk_ao),
    // which equals the closed form when sin θ₀ = m/32: those pairs must match to 1e-3 (they
    // match to rounding). The disk is a 512-segment fan whose polygon contains the disk and
    // lies within r/cos(π/512) = r(1 + 1.9e-5); the nearest rays pass sin θ = 1/64 away from
    // the rim, far outside that band.
    let k = 64;
    let rays = RaySet::new(k, 17);
    // (r, h) with sin θ₀ = r/sqrt(r²+h²) = 1/2, 1/4, 3/4.
    for (r, h) in [
        (1.0f32, 3.0f32.sqrt()),
        (1.0, 15.0f32.sqrt()),
        (3.0, 7.0f32.sqrt()),
    ] {
        let tracer = Tracer::new(&disk_fan(r, h, 512));
        let expected = (h * h / (h * h + r * r)) as f64;
        let opts = AoOptions::for_scene_radius(r.max(h));
        let ao = ao_at_points(&tracer, &[Vec3::ZERO; 4], &[Vec3::Z; 4], &rays, &opts);
        for a in ao {
            assert!(
                (a as f64 - expected).abs() < 1e-3,
                "r {r} h {h}: {a} vs {expected}"
            );
        }
    }
    // Generic pairs: the estimate equals the stratified prediction exactly and stays within
    // its quantisation bound (s + 1/k)² − s² of the closed form.
    for (r, h) in [(1.0f32, 1.0f32), (0.3, 2.0), (2.0, 0.5)] {
        let tracer = Tracer::new(&disk_fan(r, h, 512));
        let s = (r / (r * r + h * h).sqrt()) as f64;
        let predicted = stratified_disk_ao(k, s);
        let opts = AoOptions::for_scene_radius(r.max(h));
        let ao = ao_at_points(&tracer, &[Vec3::ZERO; 4], &[Vec3::Z; 4], &rays, &opts);
        let closed = (h * h / (h * h + r * r)) as f64;
        assert!((predicted - closed).abs() <= (s + 1.0 / k as f64).powi(2) - s * s);
        for a in ao {
            assert!(
                (a as f64 - predicted).abs() < 1e-6,
                "r {r} h {h}: {a} vs {predicted}"
            );
        }
    }
}

#[test]
fn max_distance_under_a_plane_matches_the_closed_form() {
    // A point under an (effectively infinite) plane at height h with rays cut at distance d:
    // a ray at angle θ meets the plane at h / cos θ, so it is unoccluded iff cos θ < h/d.
    // Under the cosine density P(sin θ ≤ x) = x², so AO = P(cos θ < c) = c² with c = h/d.
    // With sin θ at the cut = sqrt(1 − c²) = m/32 the 64² strata give c² exactly.
    let h = 1.0f32;
    let tracer = Tracer::new(&square(1000.0, h));
    let rays = RaySet::new(64, 23);
    for s in [0.25f32, 0.5, 0.75] {
        let c = (1.0 - s * s).sqrt();
        let opts = AoOptions {
            max_distance: Some(h / c),
            offset: scene_epsilon(1.0),
            falloff: Falloff::Step,
        };
        let ao = ao_at_points(&tracer, &[Vec3::ZERO; 2], &[Vec3::Z; 2], &rays, &opts);
        for a in ao {
            assert!((a - c * c).abs() < 1e-3, "s {s}: {a} vs {}", c * c);
        }
    }
}

#[test]
fn linear_falloff_under_a_plane_matches_the_closed_form() {
    // Under a plane at height h with AO radius d and V = t/d for a hit at t ≤ d: a ray at
    // μ = cos θ ≥ c = h/d hits at t = h/μ and occludes by 1 − c/μ. Under the cosine density
    // 2μ dμ the occlusion is ∫_c^1 (1 − c/μ) 2μ dμ = (1 − c²) − 2c(1 − c) = (1 − c)², so
    // AO = 1 − (1 − c)². The converged estimate must agree within its error bars, and the
    // step falloff on the same scene gives c².
    let h = 0.5f32;
    let tracer = Tracer::new(&square(1000.0, h));
    let n = 50;
    let points: Vec<Vec3> = (0..n)
        .map(|i| Vec3::new(0.1 * i as f32, 0.0, 0.0))
        .collect();
    let normals = vec![Vec3::Z; n];
    for (falloff, exact) in [(Falloff::Linear, 0.75f64), (Falloff::Step, 0.25)] {
        let opts = AoOptions {
            max_distance: Some(1.0),
            offset: 1e-6,
            falloff,
        };
        let t = crate::render::truth::TruthOptions {
            max_rays: 4096,
            ..Default::default()
        };
        let truth = crate::render::truth::converged_ao(&tracer, &points, &normals, &opts, &t);
        let mean = truth.values.iter().map(|&a| a as f64).sum::<f64>() / n as f64;
        // The mean of 50 points: its standard error is the RMS stderr / √50.
        let se = truth.rms_stderr_255() / 255.0 / (n as f64).sqrt();
        assert!(
            (mean - exact).abs() < 4.0 * se + 1e-4,
            "{falloff:?}: {mean} vs {exact} (stderr {se})"
        );
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let mut tris = random_soup(400, 0.3, 61);
    tris.extend(icosphere(2, 0.5, Vec3::new(0.2, 0.1, -0.3)));
    let tracer = Tracer::new(&tris);
    let points: Vec<Vec3> = (0..300).map(|i| 1.2 * random_point(i, 62)).collect();
    let normals: Vec<Vec3> = (0..300).map(|i| random_unit(i, 63)).collect();
    let rays = RaySet {
        k: 8,
        seed: 64,
        jitter: true,
    };
    let opts = AoOptions::for_scene_radius(1.5);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| ao_at_points(&tracer, &points, &normals, &rays, &opts))
    };
    let (one, two) = (run(1), run(2));
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&one), bits(&two));
    // Not a trivial scene: some points are partly occluded.
    assert!(one.iter().any(|&a| a > 0.0 && a < 1.0));
}

#[test]
fn tracer_visibility_queries_agree() {
    let tracer = Tracer::new(&square(1.0, 2.0));
    let o = Vec3::ZERO;
    assert_eq!(tracer.hit_distance(o, Vec3::Z, 0.0, 5.0), Some(2.0));
    assert!(tracer.occluded(o, Vec3::Z, 0.0, 2.0));
    assert!(!tracer.occluded(o, Vec3::Z, 0.0, 1.5));
    assert_eq!(tracer.hit_distance(o, -Vec3::Z, 0.0, 5.0), None);
}
