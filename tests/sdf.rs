//! Mesh signed distance fields (`sdf`) against closed forms: the baked distances of a sphere
//! and a box at every grid sample, their signs, the interpolated distance between samples,
//! sphere tracing against the analytic sphere (placed by a transform, too), AO rays against
//! our ray caster on the same convex caster, and the f16 and u8 volumes against the f32 one
//! (reads and traces). The bounds are derived in each test.

use glam::{Quat, Vec3};
use std::sync::Arc;
use visfield::geometry::procedural::uv_sphere;
use visfield::geometry::Similarity;
use visfield::sampling::rays::seeded_sphere_direction;
use visfield::sdf::storage::band;
use visfield::sdf::{DistanceVolume, Precision, SdfInstance, SdfScene, SdfTrace};
use visfield::trace::Tracer;
use visfield::visibility::Visibility;

mod common;
use common::triangles as tris;

/// The unit sphere, 64 stacks × 128 slices: every point of the mesh lies within
/// 1 − cos(π / 64) < 1.3·10⁻³ of the analytic sphere (the sagitta of a stack), so the mesh's
/// distance and the sphere's differ by less than that.
const SAGITTA: f32 = 1.3e-3;

fn sphere() -> Vec<[Vec3; 3]> {
    tris(&uv_sphere(1.0, 64, 128).unwrap())
}

fn grid_points(v: &DistanceVolume) -> impl Iterator<Item = (Vec3, f32)> + '_ {
    let [nx, ny, nz] = v.dims;
    (0..nx * ny * nz).map(move |n| (v.position(n), v.value(n)))
}

#[test]
fn a_sphere_bakes_to_its_distance_with_the_right_sign() {
    let v = DistanceVolume::bake(&sphere(), 32, 2).unwrap();
    assert_eq!(v.dims, [32, 32, 32]);
    let (mut worst, mut inside) = (0.0f32, 0);
    for (p, d) in grid_points(&v) {
        let exact = p.length() - 1.0;
        worst = worst.max((d - exact).abs());
        if exact.abs() > SAGITTA {
            assert_eq!(d < 0.0, exact < 0.0, "sign at {p}: {d} against {exact}");
        }
        inside += (d < 0.0) as usize;
    }
    // Two-sided: the tessellated sphere is not the analytic one.
    assert!(worst < SAGITTA && worst > 1e-4, "{worst}");
    // Each sample stands for the voxel-sized cube about it: the share inside is the sphere's
    // share of 32³ such cubes, (4/3)π / (32 voxels)³, up to the cubes the surface cuts.
    let side = v.voxel * 32.0;
    let share = inside as f32 / 32f32.powi(3);
    let expected = 4.0 / 3.0 * std::f32::consts::PI / side.powi(3);
    assert!(
        (share - expected).abs() < 0.02,
        "{share} against {expected}"
    );
    // Between the samples the trilinear value is a weighted mean of eight samples within a
    // voxel diagonal of the point, so within √3 voxels (plus the sagitta) of the distance.
    let bound = 3f32.sqrt() * v.voxel + SAGITTA;
    let mut worst = 0.0f32;
    for k in 0..20_000u64 {
        let p = seeded_sphere_direction(k, 5) * (1.1 * (k % 100) as f32 / 99.0);
        worst = worst.max((v.sample(p) - (p.length() - 1.0)).abs());
    }
    assert!(worst < bound && worst > 1e-4, "{worst} against {bound}");
}

/// The axis-aligned box of half-extents `h` about the origin, 12 outward triangles.
fn box_mesh(h: Vec3) -> Vec<[Vec3; 3]> {
    let c = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { -h.x } else { h.x },
            if i & 2 == 0 { -h.y } else { h.y },
            if i & 4 == 0 { -h.z } else { h.z },
        )
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    quads
        .iter()
        .flat_map(|q| [[c(q[0]), c(q[1]), c(q[2])], [c(q[0]), c(q[2]), c(q[3])]])
        .collect()
}

#[test]
fn a_box_bakes_to_its_exact_distance() {
    let h = Vec3::new(1.0, 0.5, 0.25);
    let v = DistanceVolume::bake(&box_mesh(h), 40, 3).unwrap();
    for (p, d) in grid_points(&v) {
        // The box's signed distance (the closed form).
        let q = p.abs() - h;
        let exact = q.max(Vec3::ZERO).length() + q.max_element().min(0.0);
        assert!((d - exact).abs() < 1e-5, "at {p}: {d} against {exact}");
        if exact.abs() > 1e-4 {
            assert_eq!(d < 0.0, exact < 0.0, "sign at {p}");
        }
    }
}

#[test]
fn sphere_tracing_hits_the_analytic_sphere_within_its_bound() {
    let v = Arc::new(DistanceVolume::bake(&sphere(), 48, 2).unwrap());
    let trace = SdfTrace::default();
    for (tr, label) in [
        (Similarity::default(), "in place"),
        (
            Similarity::new(Quat::from_rotation_y(0.7), Vec3::new(3.0, -1.0, 2.0), 2.0),
            "moved, turned, scaled by 2",
        ),
    ] {
        let scene = SdfScene {
            instances: vec![SdfInstance {
                volume: v.clone(),
                transform: tr,
            }],
            trace,
        };
        let (c, r) = (tr.translation, tr.scale);
        // A stop reads a distance below eps, so the true distance there is below eps + err
        // (err: √3 voxels + sagitta, the interpolation's bound); a step never passes the
        // surface by more than err. Along rays at most 45° from the normal, t is then within
        // √2 (eps + err), in world units (× scale).
        let err = 3f32.sqrt() * v.voxel + SAGITTA;
        let bound = 2f32.sqrt() * (trace.hit_voxels * v.voxel + err) * r;
        let (mut hits, mut misses) = (0, 0);
        for k in 0..4000u64 {
            let o = c + 3.0 * r * seeded_sphere_direction(k, 7);
            let target = c + 1.6 * r * seeded_sphere_direction(k, 8) * ((k % 10) as f32 / 9.0);
            let d = (target - o).normalize();
            // The analytic hit.
            let b = (c - o).dot(d);
            let miss2 = (c - o).length_squared() - b * b;
            let got = scene.hit_distance(o, d, 0.0, f32::INFINITY);
            assert_eq!(got.is_some(), scene.occluded(o, d, 0.0, f32::INFINITY));
            if miss2.sqrt() < 0.7 * r {
                let t = b - (r * r - miss2).sqrt();
                let got = got.unwrap_or_else(|| panic!("{label}: ray {k} missed"));
                assert!(
                    (got - t).abs() < bound,
                    "{label}: {got} against {t} (bound {bound})"
                );
                let n = scene.surface_hit(o, d, 0.0, f32::INFINITY).unwrap().normal;
                let exact = (o + t * d - c).normalize();
                assert!(n.dot(exact) > 0.99, "{label}: normal {n} against {exact}");
                hits += 1;
            } else if miss2.sqrt() > r + (err + v.voxel) * r {
                assert!(got.is_none(), "{label}: ray {k} hit nothing there is");
                misses += 1;
            }
        }
        assert!(
            hits > 500 && misses > 500,
            "{label}: {hits} hits, {misses} misses"
        );
    }
}

#[test]
fn ao_rays_agree_with_ray_casting_away_from_the_outline() {
    let tris = sphere();
    let v = Arc::new(DistanceVolume::bake(&tris, 48, 2).unwrap());
    let tr = Similarity::new(Quat::IDENTITY, Vec3::new(0.0, 1.3, 0.0), 1.0);
    let scene = SdfScene {
        instances: vec![SdfInstance {
            volume: v.clone(),
            transform: tr,
        }],
        trace: SdfTrace::default(),
    };
    let world: Vec<[Vec3; 3]> = tris
        .iter()
        .map(|t| t.map(|p| tr.to_world_point(p)))
        .collect();
    let tracer = Tracer::new(&world);
    let margin = 3f32.sqrt() * v.voxel + SAGITTA + v.voxel;
    let (mut rays, mut occluded, mut near_outline, mut differ) = (0, 0, 0, 0);
    for i in 0..40 {
        for j in 0..40 {
            let o = Vec3::new(-2.0 + 0.1 * i as f32, 0.0, -2.0 + 0.1 * j as f32);
            for k in 0..32u64 {
                let mut d = seeded_sphere_direction((i * 40 + j) as u64 * 32 + k, 9);
                d.y = d.y.abs();
                let b = (tr.translation - o).dot(d);
                let miss = ((tr.translation - o).length_squared() - b * b)
                    .max(0.0)
                    .sqrt();
                let a = tracer.occluded(o, d, 1e-4, f32::INFINITY);
                let s = scene.occluded(o, d, 1e-4, f32::INFINITY);
                rays += 1;
                occluded += a as usize;
                if (miss - 1.0).abs() < margin {
                    near_outline += 1;
                    differ += (a != s) as usize;
                } else {
                    assert_eq!(a, s, "ray from {o} along {d}, {miss} from the centre");
                }
            }
        }
    }
    // Both answers in quantity; the rays near the outline may part, never most of them.
    assert!(
        occluded > rays / 20 && occluded < rays / 2,
        "{occluded} of {rays}"
    );
    assert!(
        differ * 2 < near_outline.max(1),
        "{differ} of {near_outline}"
    );
}

#[test]
fn bad_bakes_are_refused() {
    assert!(DistanceVolume::bake(&[], 32, 2).is_err());
    assert!(DistanceVolume::bake(&sphere(), 3, 0).is_err());
    assert!(DistanceVolume::bake(&sphere(), 513, 2).is_err());
    assert!(DistanceVolume::bake(&sphere(), 16, 8).is_err());
    let nan = [[Vec3::NAN, Vec3::X, Vec3::Y]];
    assert!(DistanceVolume::bake(&nan, 16, 2).is_err());
}

/// f16 and u8 reads against the f32 ones at the same points, within the quantisation's bounds
/// (`sdf::storage`): a trilinear read is a convex combination of its eight decoded samples, so
/// it keeps their bound. f16: 2⁻¹¹ of the largest sample (the read plus the cell's spread, at
/// most √3 voxels for a 1-Lipschitz distance) plus 2⁻²⁵ voxel. u8: M / 255 where the eight
/// samples lie in the band (the read at least √3 voxels inside it), and M where all of them lie
/// past it (the code 255 reads M exactly; outside the grid both reads add the distance to it).
#[test]
fn quantised_volumes_read_within_their_bounds() {
    let v32 = DistanceVolume::bake(&sphere(), 32, 2).unwrap();
    let (v16, v8) = (
        v32.with_precision(Precision::F16),
        v32.with_precision(Precision::U8),
    );
    let n = v32.dims.iter().product::<usize>() as u64;
    assert_eq!((v32.bytes(), v16.bytes(), v8.bytes()), (4 * n, 2 * n, n));
    assert_eq!(v8.precision(), Precision::U8);
    let (h, m) = (v32.voxel, band(v32.voxel));
    let (mut worst16, mut worst8, mut capped) = (0.0f32, 0.0f32, 0);
    // Points filling the grid's box (the R3 low-discrepancy sequence), and a band past it.
    let (lo, size) = (
        v32.lo - Vec3::splat(0.2),
        v32.hi() - v32.lo + Vec3::splat(0.4),
    );
    for k in 0..40_000u64 {
        let u = (k as f64 * glam::DVec3::new(0.819_172_5, 0.671_043_6, 0.549_700_5)).fract_gl();
        let p = lo + size * u.as_vec3();
        let (r32, r16, r8) = (v32.sample(p), v16.sample(p), v8.sample(p));
        let rounding = 1e-6 * (1.0 + r32.abs());
        let b16 = 2f32.powi(-11) * (r32.abs() + 3f32.sqrt() * h) + 2f32.powi(-25) * h;
        assert!(
            (r16 - r32).abs() <= b16 + rounding,
            "f16 at {p}: {r16} against {r32}"
        );
        worst16 = worst16.max((r16 - r32).abs() / b16);
        // Outside the grid both reads add the distance to its box to the read on its face.
        let out = p.distance(p.clamp(v32.lo, v32.hi()));
        if (r32 - out).abs() <= m - 3f32.sqrt() * h {
            assert!((r8 - r32).abs() <= m / 255.0 + rounding, "u8 at {p}");
            worst8 = worst8.max((r8 - r32).abs() / (m / 255.0));
        } else if r32 - out >= m + 3f32.sqrt() * h {
            assert!((r8 - out - m).abs() <= rounding, "u8 at {p}: past the band");
            capped += 1;
        }
    }
    // Two-sided: the errors reach a good part of their bounds, and the cap is met.
    assert!(worst8 > 0.5 && worst16 > 0.05, "{worst8} {worst16}");
    assert!(capped > 1000, "{capped}");
    // Re-encoding an encoded volume changes nothing.
    assert_eq!(v8.with_precision(Precision::U8), v8);
}

#[test]
fn quantised_volumes_sphere_trace_within_their_bound() {
    // As the f32 test, the read error grown by the quantisation's: a hit reads below the
    // threshold, so the true distance there is below it plus the read error; u8's far reads
    // are capped at the band, so its steps are short but never past the true distance by
    // more than the read error.
    let v32 = DistanceVolume::bake(&sphere(), 48, 2).unwrap();
    let trace = SdfTrace::default();
    for precision in [Precision::F16, Precision::U8] {
        let v = Arc::new(v32.with_precision(precision));
        let quant = match precision {
            Precision::U8 => band(v.voxel) / 255.0,
            _ => 2f32.powi(-11) * 3.0 * v.voxel,
        };
        let scene = SdfScene {
            instances: vec![SdfInstance {
                volume: v.clone(),
                transform: Similarity::default(),
            }],
            trace,
        };
        let err = 3f32.sqrt() * v.voxel + SAGITTA + quant;
        let bound = 2f32.sqrt() * (trace.hit_voxels * v.voxel + err);
        let mut hits = 0;
        for k in 0..2000u64 {
            let o = 3.0 * seeded_sphere_direction(k, 7);
            let target = 0.6 * seeded_sphere_direction(k, 8);
            let d = (target - o).normalize();
            let b = (-o).dot(d);
            let miss2 = o.length_squared() - b * b;
            if miss2.sqrt() < 0.7 {
                let t = b - (1.0 - miss2).sqrt();
                let got = scene
                    .hit_distance(o, d, 0.0, f32::INFINITY)
                    .unwrap_or_else(|| panic!("{precision:?}: ray {k} missed"));
                assert!((got - t).abs() < bound, "{precision:?}: {got} against {t}");
                let n = scene.surface_hit(o, d, 0.0, f32::INFINITY).unwrap().normal;
                assert!(
                    n.dot((o + t * d).normalize()) > 0.99,
                    "{precision:?}: normal {n}"
                );
                hits += 1;
            }
        }
        assert!(hits > 500, "{precision:?}: {hits}");
    }
}
