//! Closed forms of the light fraction, and field against ray casting on shadow rays.

use super::*;
use crate::field::bake::{bake, BakeOptions};
use crate::field::lookup::LookupOptions;
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::{FieldParams, Precision};
use crate::geometry::{procedural, Similarity};
use crate::render::truth::TruthOptions;
use crate::sampling::{LayoutKind, SphereKind};
use crate::trace::test_scenes::icosphere;
use crate::trace::Tracer;
use glam::Quat;
use std::sync::Arc;

/// One light of radius 2 straight above the origin at height 10 (sin θ_max = 0.2).
fn light_above() -> ShadowOptions {
    ShadowOptions {
        offset: 1e-5,
        lights: vec![SphereLight {
            center: Vec3::new(0.0, 0.0, 10.0),
            radius: 2.0,
            intensity: 1.0,
        }],
    }
}

/// Points near the origin facing +z (each its own seeded rotation).
fn points(n: usize) -> (Vec<Vec3>, Vec<Vec3>) {
    let p = (0..n)
        .map(|i| Vec3::new(1e-4 * i as f32, -1e-4 * i as f32, 0.0))
        .collect();
    (p, vec![Vec3::Z; n])
}

/// The converged light fraction and its RMS standard error (0–1).
fn truth(vis: &dyn Visibility, p: &[Vec3], n: &[Vec3], opts: &ShadowOptions) -> (Vec<f32>, f64) {
    let est = ShadowEstimator { opts: opts.clone() };
    let t = TruthOptions {
        target_stderr_255: 0.5,
        max_rays: 4096,
        ..TruthOptions::default()
    };
    let tr = est.converged(
        vis,
        Points {
            points: p,
            normals: n,
        },
        &t,
    );
    let se = tr.rms_stderr_255() / 255.0;
    (tr.values, se)
}

#[test]
fn cone_samples_stay_in_the_cone_and_cover_its_solid_angle_evenly() {
    // Uniform in solid angle: the share of cells with cos θ ≥ c is (1 − c)/(1 − cos θ_max).
    let cos_max = 0.8f32;
    let k = 64u32;
    let rays = RaySet::new(k, 3);
    let mut sq = Vec::new();
    rays.fill_square(0, &mut sq);
    let dirs: Vec<Vec3> = sq
        .iter()
        .map(|&u| square_to_cone(u, 1.0 - cos_max))
        .collect();
    assert!(dirs
        .iter()
        .all(|d| (d.length() - 1.0).abs() < 1e-5 && d.z >= cos_max - 1e-6));
    let c = 0.9f32;
    let share = dirs.iter().filter(|d| d.z >= c).count() as f64 / dirs.len() as f64;
    let exact = (1.0 - c as f64) / (1.0 - cos_max as f64);
    assert!((share - exact).abs() < 2.0 / k as f64, "{share} vs {exact}");
}

#[test]
fn nothing_in_the_way_is_fully_lit_and_a_point_facing_away_is_unshadowed() {
    // A square far below the points blocks nothing above them.
    let tracer = Tracer::new(&crate::trace::test_scenes::square(5.0, -3.0));
    let (p, n) = points(8);
    let rays = RaySet::new(4, 1);
    let lit = shadow_at_points(&tracer, &p, &n, &rays, &light_above());
    assert!(lit.iter().all(|&v| v == 1.0), "{lit:?}");
    // Facing −z, the light is behind the surface: no weight, S = 1 (no light, no shadow),
    // even under a blocker.
    let tracer = Tracer::new(&crate::trace::test_scenes::square(50.0, 5.0));
    let away = shadow_at_points(&tracer, &p, &[-Vec3::Z; 8], &rays, &light_above());
    assert!(away.iter().all(|&v| v == 1.0), "{away:?}");
    // A blocker covering the whole light: every ray is blocked.
    let dark = shadow_at_points(&tracer, &p, &n, &rays, &light_above());
    assert!(dark.iter().all(|&v| v == 0.0), "{dark:?}");
}

#[test]
fn a_blocker_behind_the_light_does_not_shadow() {
    // Shadow rays end at the light: a plane above it (z = 20) is not in the way.
    let tracer = Tracer::new(&crate::trace::test_scenes::square(50.0, 20.0));
    let (p, n) = points(8);
    let v = shadow_at_points(&tracer, &p, &n, &RaySet::new(4, 1), &light_above());
    assert!(v.iter().all(|&x| x == 1.0), "{v:?}");
}

/// The half-plane x < 0 at height `z` (two triangles 50 on a side).
fn half_plane(z: f32) -> Tracer {
    Tracer::new(&[
        [
            Vec3::new(-50.0, -50.0, z),
            Vec3::new(0.0, -50.0, z),
            Vec3::new(0.0, 50.0, z),
        ],
        [
            Vec3::new(-50.0, -50.0, z),
            Vec3::new(0.0, 50.0, z),
            Vec3::new(-50.0, 50.0, z),
        ],
    ])
}

/// A half-plane at z = 5 over x < 0, its edge through the light's axis: the mirror x → −x maps
/// the light's cone and the weight n·ω (n on the axis) onto themselves, so exactly half of the
/// weighted light is hidden. A stratified k² estimate is off by at most the cells the edge
/// crosses, about k of k² cells on either side: 2/k (the bound of the AO closed forms,
/// `stability::hard`); the converged reference within 4 of its standard errors.
#[test]
fn a_half_plane_through_the_lights_axis_hides_half_of_it() {
    let z = 5.0;
    let tracer = half_plane(z);
    // Points on the axis (x = 0 exactly, so the edge stays through the cone's axis).
    let p: Vec<Vec3> = (0..16)
        .map(|i| Vec3::new(0.0, 1e-4 * i as f32, 0.0))
        .collect();
    let n = vec![Vec3::Z; 16];
    let k = 16;
    let v = shadow_at_points(&tracer, &p, &n, &RaySet::new(k, 7), &light_above());
    for (i, &x) in v.iter().enumerate() {
        assert!((x - 0.5).abs() <= 2.0 / k as f32, "point {i}: {x}");
    }
    let (t, se) = truth(&tracer, &p, &n, &light_above());
    let mean = t.iter().map(|&x| x as f64).sum::<f64>() / t.len() as f64;
    assert!((mean - 0.5).abs() < 4.0 * se + 1e-3, "{mean} ± {se}");
}

/// A sphere of radius r_o at distance D_o on the axis of a spherical light (radius r_L at
/// distance D_L), in front of it: the occluder hides the cone of half-angle α_o, sin α_o =
/// r_o/D_o, of the light's cone α_L. With n on the axis the weight is cos θ and the solid angle
/// sin θ dθ dφ, so the lit fraction is the spherical-cap annulus
///
///   ∫_{α_o}^{α_L} cos θ sin θ dθ / ∫_0^{α_L} cos θ sin θ dθ = 1 − sin²α_o / sin²α_L,
///
/// here 1 − (0.5/5)² / (2/10)² = 0.75. The icosphere (5 subdivisions) is inscribed in the
/// sphere: its outline is smaller by under 0.1%, which moves the fraction by under 5e-4.
#[test]
fn an_occluding_sphere_leaves_the_spherical_cap_annulus_lit() {
    let occluder = icosphere(5, 0.5, Vec3::new(0.0, 0.0, 5.0));
    let tracer = Tracer::new(&occluder);
    let (p, n) = points(32);
    let exact = 0.75f64;
    let k = 16;
    let v = shadow_at_points(&tracer, &p, &n, &RaySet::new(k, 5), &light_above());
    for (i, &x) in v.iter().enumerate() {
        assert!((x as f64 - exact).abs() <= 2.0 / k as f64, "point {i}: {x}");
    }
    let (t, se) = truth(&tracer, &p, &n, &light_above());
    let mean = t.iter().map(|&x| x as f64).sum::<f64>() / t.len() as f64;
    assert!(
        (mean - exact).abs() < 4.0 * se / (t.len() as f64).sqrt() + 1e-3,
        "{mean} ± {se}"
    );
}

/// Field lookup answers shadow rays as ray casting does on a convex caster: a UV sphere's own
/// field (290 × 16², u8) between points and a light. On a caster that fills its bounding
/// sphere every stored distance is about 0, so only rays grazing the polygonal outline can get
/// another answer; over 200 points, a fifth of them in its penumbra or umbra, the light
/// fractions agree within an RMS of 2/255.
#[test]
fn field_and_ray_casting_agree_on_shadow_rays_of_a_convex_caster() {
    let mesh = procedural::uv_sphere(1.0, 32, 64).unwrap();
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 290,
        layout: LayoutKind::Concentric,
        res: 16,
        precision: Precision::U8,
    };
    let field = Arc::new(bake(&mesh, params, &BakeOptions::default()).unwrap().0);
    // The sphere of radius 0.6 at height 4, partly between the points and the light.
    let transform = Similarity::new(Quat::IDENTITY, Vec3::new(0.4, 0.0, 4.0), 0.6);
    let fs = FieldScene {
        instances: vec![FieldInstance::new(field, transform)],
        options: LookupOptions::default(),
    };
    let world: Vec<[Vec3; 3]> = (0..mesh.triangle_count())
        .map(|i| mesh.triangle(i).map(|v| transform.to_world_point(v)))
        .collect();
    let tracer = Tracer::new(&world);
    let p: Vec<Vec3> = (0..200)
        .map(|i| {
            Vec3::new(
                -1.0 + 0.01 * i as f32,
                0.3 * ((i % 7) as f32 - 3.0) / 3.0,
                0.0,
            )
        })
        .collect();
    let n = vec![Vec3::Z; p.len()];
    let rays = RaySet::new(6, 2);
    let exact = shadow_at_points(&tracer, &p, &n, &rays, &light_above());
    let approx = shadow_at_points(&fs, &p, &n, &rays, &light_above());
    let shadowed = exact.iter().filter(|&&x| x < 0.9).count();
    assert!(shadowed > 20, "the caster shadows {shadowed} points");
    let rms = 255.0
        * (approx
            .iter()
            .zip(&exact)
            .map(|(a, b)| (*a as f64 - *b as f64).powi(2))
            .sum::<f64>()
            / p.len() as f64)
            .sqrt();
    assert!(rms < 2.0, "RMS {rms} (0–255)");
}

/// 1 − cos θ_max against f64 references that share none of its arithmetic: the series
/// q/2 + q²/8 + q³/16 + 5q⁴/128 (truncation under q⁵) below q = 1e-4, 1 − √(1 − q) in f64 above
/// (an absolute error of 1e-16, relative 1e-12 there). The f64 form within 4 ulp (plus the
/// reference's 1e-16 above q = 1e-4) all the way down to q = 1e-300, the f32 form within 4 f32 ulp down to f32's normal range.
#[test]
fn one_minus_cos_max_holds_to_the_point_light_limit() {
    let reference = |q: f64| {
        if q < 1e-4 {
            q / 2.0 + q * q / 8.0 + q * q * q / 16.0 + 5.0 * q.powi(4) / 128.0
        } else {
            1.0 - (1.0 - q).sqrt()
        }
    };
    for e in 0..=300 {
        for m in [1.0, 3.7] {
            let q = m * 10f64.powi(-e);
            if q > 1.0 {
                continue;
            }
            let want = reference(q);
            let got = one_minus_cos_max(q);
            let tol = 4.0 * f64::EPSILON * want + if q < 1e-4 { 0.0 } else { 2.3e-16 };
            assert!((got - want).abs() <= tol, "q {q:e}: {got:e} vs {want:e}");
            let q32 = q as f32;
            if q32 >= f32::MIN_POSITIVE {
                let want = reference(q32 as f64);
                let got = one_minus_cos_max_f32(q32) as f64;
                let tol = 4.0 * f32::EPSILON as f64 * want;
                assert!(
                    (got - want).abs() <= tol,
                    "f32 q {q:e}: {got:e} vs {want:e}"
                );
            }
        }
    }
    assert_eq!(one_minus_cos_max(0.0), 0.0);
    assert_eq!(one_minus_cos_max(1.0), 1.0);
}

/// In a cone of half-angle θ_max from 1e-2 down to 1e-9 rad, far below where cos θ_max rounds to
/// 1 in f32 (3.5e-4), the directions stay in the cone, reach out to the outermost cell centres
/// (ρ = 1 − 1/k) and cover it evenly: the share inside θ_max/√2 is the solid angle's half
/// within the stratification's 2/k.
#[test]
fn cone_directions_keep_their_spread_down_to_tiny_cones() {
    let k = 16u32;
    let rays = RaySet::new(k, 3);
    let mut sq = Vec::new();
    rays.fill_square(0, &mut sq);
    for theta_max in [1e-2f64, 1e-4, 1e-6, 1e-9] {
        let omc = one_minus_cos_max_f32(theta_max.sin().powi(2) as f32);
        let angles: Vec<f64> = sq
            .iter()
            .map(|&u| {
                let d = square_to_cone(u, omc);
                (d.x as f64).hypot(d.y as f64).atan2(d.z as f64)
            })
            .collect();
        let widest = angles.iter().copied().fold(0.0, f64::max);
        assert!(
            widest <= theta_max * (1.0 + 1e-5),
            "θ_max {theta_max:e}: {widest:e}"
        );
        let outer = 1.0 - 1.0 / k as f64;
        assert!(
            widest >= 0.99 * outer * theta_max,
            "θ_max {theta_max:e}: widest {widest:e}"
        );
        let inner = angles
            .iter()
            .filter(|&&a| a <= theta_max / 2f64.sqrt())
            .count() as f64
            / angles.len() as f64;
        assert!(
            (inner - 0.5).abs() <= 2.0 / k as f64,
            "θ_max {theta_max:e}: {inner}"
        );
    }
}

/// The far end of every shadow ray lies between the light's near pole and its tangent points,
/// t ∈ [d − r, √(d² − r²)] (to 4 f32 ulp), down to r = 1e-6 at d = 3, where the root in its
/// textbook form b − √(b² − (d² − r²)) cancels in f32 (b² − (d² − r²) ≈ 1e-12 against an
/// ulp of 9, 1e-6) and ends up to 1e-3 short. Where the light is larger than the f32 direction's
/// own error, t also matches that root taken in f64 along the direction normalised in f64,
/// within 4 ulp and the root's conditioning (an error δ in h² moves it by δ / 2√(r² − h²)).
#[test]
fn the_far_end_is_the_near_root_without_cancellation() {
    let origin = Vec3::new(0.1, -0.2, 0.05);
    let rays = RaySet::new(6, 9);
    let mut sq = Vec::new();
    rays.fill_square(4, &mut sq);
    let (s, c) = rays.rotation(4);
    let eps = f32::EPSILON as f64;
    for radius in [0.5f32, 1e-2, 1e-3, 1e-6, 1e-20, 0.0] {
        let light = SphereLight {
            center: Vec3::new(1.0, 2.0, 2.0),
            radius,
            intensity: 1.0,
        };
        let cone = LightCone::new(&light, origin, sq.len()).unwrap();
        let to = cone.to.as_dvec3();
        let d = to.length();
        let r2 = (radius as f64).powi(2);
        for &u in &sq {
            let dir = cone.direction(u, s, c);
            let got = cone.far_end(dir) as f64;
            let (lo, hi) = (d - radius as f64, (d * d - r2).sqrt());
            assert!(
                got >= lo * (1.0 - 4.0 * eps) && got <= hi * (1.0 + 4.0 * eps),
                "r {radius}: {got} outside [{lo}, {hi}]"
            );
            if radius >= 1e-3 {
                let unit = dir.as_dvec3();
                let b = unit.dot(to) / unit.length();
                let disc = (b * b - (d * d - r2)).max(eps * r2);
                let want = b - disc.sqrt();
                let got = got * unit.length();
                let tol = 4.0 * eps * d + 2.0 * eps * d * d / disc.sqrt();
                assert!((got - want).abs() <= tol, "r {radius}: {got} vs {want}");
            }
        }
    }
}

/// A point light (radius 0) at (0, 0, 10) over the half-plane z = 5, x < 0: the ray from (x, y, 0)
/// crosses the plane at x/2, so a point is lit exactly when x > 0, the hard shadow. One ray per
/// point: the unshadowed light is (n·ω)/d² = 10/d³, whatever k, and a sphere light of radius
/// 1e-6 gives the same shadow.
#[test]
fn a_point_light_casts_the_exact_hard_shadow_with_one_ray() {
    let z = 5.0;
    let tracer = half_plane(z);
    let p: Vec<Vec3> = (1..=40)
        .map(|i| {
            let x = 0.01 * (i as f32 - 20.5);
            Vec3::new(x, 0.003 * i as f32, 0.0)
        })
        .collect();
    let n = vec![Vec3::Z; p.len()];
    let mut opts = light_above();
    opts.lights[0].radius = 0.0;
    for k in [1u32, 4] {
        let v = shadow_at_points(&tracer, &p, &n, &RaySet::new(k, 3), &opts);
        for (q, &x) in p.iter().zip(&v) {
            assert_eq!(x, if q.x > 0.0 { 1.0 } else { 0.0 }, "k {k}, point {q}");
        }
    }
    let light = |k| direct_light(&p, &n, &RaySet::new(k, 3), &opts);
    assert_eq!(light(1), light(5));
    let exact: Vec<f64> = p
        .iter()
        .map(|q| {
            10.0 / ((q.as_dvec3() - glam::DVec3::new(0.0, 0.0, 10.0))
                .length()
                .powi(3))
        })
        .collect();
    let top = exact.iter().copied().fold(0.0, f64::max);
    for (e, g) in exact.iter().zip(light(4)) {
        assert!((e / top - g as f64).abs() < 1e-6, "{e} {g}");
    }
    opts.lights[0].radius = 1e-6;
    let small = shadow_at_points(&tracer, &p, &n, &RaySet::new(4, 3), &opts);
    assert!(p
        .iter()
        .zip(&small)
        .all(|(q, &x)| x == if q.x > 0.0 { 1.0 } else { 0.0 }));
}
