//! The rays made from shared terms, eight at a time, against the one-ray code that made them
//! before (kept here verbatim as the reference), bit for bit, on every instruction set.

use super::*;
use crate::render::reflect::{
    reflection_rays, reflection_rays_in, square_to_phong, Gloss, ReflectOptions, ReflectScratch,
};
use crate::render::shadow::{shadow_rays, ShadowOptions, ShadowScratch, SphereLight};
use crate::sampling::rays::{seeded_sphere_direction, uniform, RaySet};

/// The shadow rays of one point as `render::shadow` made them one ray at a time through
/// [`LightCone::direction`] (its concentric disk per square) and [`LightCone::far_end`]:
/// (origin, directions, far ends, weights).
fn shadow_reference(
    i: u32,
    p: Vec3,
    n: Vec3,
    rays: &RaySet,
    opts: &ShadowOptions,
) -> (Vec3, Vec<Vec3>, Vec<f32>, Vec<f64>) {
    let origin = p + opts.offset * n;
    let (s, c) = rays.rotation(i);
    let mut squares = Vec::new();
    rays.fill_square(i, &mut squares);
    let (mut dirs, mut tmaxs, mut weights) = (Vec::new(), Vec::new(), Vec::new());
    for light in &opts.lights {
        let Some(cone) = LightCone::new(light, origin, squares.len()) else {
            continue;
        };
        let samples = if cone.point {
            1.min(squares.len())
        } else {
            squares.len()
        };
        for &u in &squares[..samples] {
            let dir = cone.direction(u, s, c);
            let cos_n = n.dot(dir);
            if cos_n <= 0.0 {
                continue;
            }
            dirs.push(dir);
            tmaxs.push(cone.far_end(dir));
            weights.push(cone.weight_scale * cos_n as f64);
        }
    }
    (origin, dirs, tmaxs, weights)
}

fn bits3(v: &[Vec3]) -> Vec<[u32; 3]> {
    v.iter().map(|d| d.to_array().map(f32::to_bits)).collect()
}

/// Lights of radius 0 (point) to 3 about a point cloud near the origin: the light's angular
/// radius from about 1 (a light just beyond the point) down to 1e-20, axes in every octant
/// and along ±z (the two branches of the frame), one light behind the points' normals.
fn lights(seed: u64) -> Vec<SphereLight> {
    let mut v = Vec::new();
    for (j, radius) in [3.0f32, 0.3, 1e-2, 1e-4, 1e-8, 1e-20, 0.0]
        .into_iter()
        .enumerate()
    {
        let dir = seeded_sphere_direction(j as u64, seed);
        v.push(SphereLight {
            center: 2.0 * dir + Vec3::new(0.0, 0.0, 1.0),
            radius,
            intensity: 1.0 + j as f32,
        });
    }
    v.push(SphereLight {
        center: Vec3::new(1e-3, -2e-3, 5.0),
        radius: 0.7,
        intensity: 0.5,
    });
    v.push(SphereLight {
        center: Vec3::new(0.0, 0.0, -4.0),
        radius: 1.0,
        intensity: 1.0,
    });
    v
}

#[test]
fn shadow_rays_are_the_one_ray_code_bit_for_bit() {
    let mut compared = [0usize; 2];
    for (k, jitter) in [
        (1, false),
        (2, false),
        (3, false),
        (4, false),
        (4, true),
        (5, false),
        (6, false),
        (16, false),
        (7, true),
    ] {
        let rays = RaySet { k, seed: 9, jitter };
        for isa in Isa::all_available() {
            // One scratch across all points and lights: its disk samples are made once per
            // set without jitter and per point with it.
            let mut sc = ShadowScratch::default();
            for i in 0..300u32 {
                let p = 0.5 * seeded_sphere_direction(i as u64, 3) * uniform(i, 0, 0, 4);
                let n = seeded_sphere_direction(i as u64, 5);
                let n = if i % 3 == 0 {
                    (n + Vec3::Z).normalize_or(Vec3::Z)
                } else {
                    n
                };
                let opts = ShadowOptions {
                    offset: 1e-3,
                    lights: lights(i as u64 % 7),
                };
                let (o, dirs, tmaxs, weights) = shadow_reference(i, p, n, &rays, &opts);
                let got = shadow_rays(isa, i, p, n, &rays, &opts, &mut sc);
                let r = sc.rays();
                let what = format!("k {k} jitter {jitter} point {i} {isa:?}");
                assert_eq!(got, o, "{what}");
                assert_eq!(bits3(&r.dirs), bits3(&dirs), "{what}");
                assert_eq!(
                    r.tmaxs.iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
                    tmaxs.iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
                    "{what}"
                );
                assert_eq!(
                    r.weights.iter().map(|w| w.to_bits()).collect::<Vec<_>>(),
                    weights.iter().map(|w| w.to_bits()).collect::<Vec<_>>(),
                    "{what}"
                );
                compared[0] += dirs.len();
                compared[1] += opts.lights.len() * rays.len() - dirs.len();
            }
        }
    }
    // Both sides of the normal's cut are exercised: many rays kept, many dropped.
    assert!(
        compared[0] > 100_000 && compared[1] > 50_000,
        "{compared:?}"
    );
}

/// The reflection rays of one point as `render::reflect` made them one ray at a time:
/// (origin, directions).
fn reflect_reference(
    i: u32,
    p: Vec3,
    n: Vec3,
    rays: &RaySet,
    opts: &ReflectOptions,
) -> (Vec3, Vec<Vec3>) {
    let origin = p + opts.offset * n;
    let v = (p - opts.eye).normalize_or_zero();
    let r = (v - 2.0 * v.dot(n) * n).normalize_or_zero();
    let mut dirs = Vec::new();
    match opts.gloss {
        Gloss::Mirror => {
            if n.dot(r) > 0.0 {
                dirs.push(r);
            }
        }
        Gloss::Phong { exponent } => {
            let (s, c) = rays.rotation(i);
            let mut squares = Vec::new();
            rays.fill_square(i, &mut squares);
            let frame = Frame::from_normal(r);
            for &u in squares.iter() {
                let l = square_to_phong(u, exponent);
                let l = Vec3::new(c * l.x - s * l.y, s * l.x + c * l.y, l.z);
                let dir = frame.to_world(l).normalize();
                if n.dot(dir) > 0.0 {
                    dirs.push(dir);
                }
            }
        }
    }
    (origin, dirs)
}

#[test]
fn reflection_rays_are_the_one_ray_code_bit_for_bit() {
    let glosses = [
        Gloss::Mirror,
        Gloss::Phong { exponent: 1e-3 },
        Gloss::Phong { exponent: 1.0 },
        Gloss::Phong { exponent: 50.0 },
        Gloss::Phong { exponent: 1e7 },
    ];
    let mut compared = [0usize; 2];
    for (k, jitter) in [
        (1, false),
        (2, false),
        (3, false),
        (4, true),
        (5, false),
        (6, false),
        (16, false),
    ] {
        let rays = RaySet { k, seed: 4, jitter };
        for isa in Isa::all_available() {
            // One scratch across all points and lobes: the lobe is made once per set and
            // exponent without jitter, per point with it.
            let mut sc = ReflectScratch::default();
            let (mut squares, mut dirs) = (Vec::new(), Vec::new());
            for i in 0..200u32 {
                let p = 0.5 * seeded_sphere_direction(i as u64, 3) * uniform(i, 0, 0, 4);
                let n = seeded_sphere_direction(i as u64, 5);
                let opts = ReflectOptions {
                    offset: 1e-3,
                    eye: 3.0 * seeded_sphere_direction(i as u64 / 7, 6),
                    gloss: glosses[i as usize % glosses.len()],
                    lights: Vec::new(),
                    albedo: 0.8,
                    sky: 0.2,
                };
                let (o, want) = reflect_reference(i, p, n, &rays, &opts);
                let what = format!("k {k} jitter {jitter} point {i} {:?} {isa:?}", opts.gloss);
                let got = reflection_rays_in(isa, i, p, n, &rays, &opts, &mut sc);
                assert_eq!(got, o, "{what}");
                assert_eq!(bits3(sc.dirs()), bits3(&want), "{what}");
                let got = reflection_rays(i, p, n, &rays, &opts, &mut squares, &mut dirs);
                assert_eq!(got, o, "{what}");
                assert_eq!(bits3(&dirs), bits3(&want), "{what}");
                let total = if opts.gloss == Gloss::Mirror {
                    1
                } else {
                    rays.len()
                };
                compared[0] += want.len();
                compared[1] += total - want.len();
            }
        }
    }
    // Rays on both sides of the surface: many kept, many dropped.
    assert!(compared[0] > 20_000 && compared[1] > 5_000, "{compared:?}");
}
