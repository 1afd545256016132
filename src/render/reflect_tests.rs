//! Closed forms of the reflection query: the Phong lobe's moments, a mirror floor reflecting a
//! sphere (ray cast and field against the analytic hit and normal, with bounds derived from the
//! tessellation, the map spacing and the texel), and the lobe's limits.

use super::*;
use crate::field::bake::{bake_mesh_with_normals, BakeOptions};
use crate::field::lookup::{LookupOptions, NearestRead, Reads};
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::{FieldParams, Precision};
use crate::geometry::{procedural, Similarity};
use crate::sampling::{LayoutKind, SphereKind};
use crate::trace::Tracer;
use glam::Quat;
use std::sync::Arc;

/// The sphere's centre and radius; the floor is z = 0, the eye above and behind it.
const CENTRE: Vec3 = Vec3::new(0.0, 0.0, 1.2);
const RADIUS: f32 = 1.0;
const EYE: Vec3 = Vec3::new(0.0, -4.0, 2.5);

fn opts(gloss: Gloss) -> ReflectOptions {
    ReflectOptions {
        offset: 1e-5,
        eye: EYE,
        gloss,
        lights: vec![
            SphereLight {
                center: Vec3::new(3.0, -2.0, 6.0),
                radius: 0.5,
                intensity: 2.0,
            },
            SphereLight {
                center: Vec3::new(-4.0, 1.0, 3.0),
                radius: 0.5,
                intensity: 1.0,
            },
        ],
        albedo: 0.8,
        sky: 0.3,
    }
}

/// Floor points on a grid in front of and around the sphere, normal +z.
fn floor_points() -> (Vec<Vec3>, Vec<Vec3>) {
    let mut p = Vec::new();
    for i in 0..60 {
        for j in 0..60 {
            p.push(Vec3::new(
                -2.5 + 5.0 * i as f32 / 59.0,
                -3.0 + 5.0 * j as f32 / 59.0,
                0.0,
            ));
        }
    }
    let n = vec![Vec3::Z; p.len()];
    (p, n)
}

/// The exact sphere's first hit of a ray, if any.
fn analytic_hit(o: Vec3, d: Vec3) -> Option<SurfaceHit> {
    let f = o - CENTRE;
    let b = f.dot(d);
    let disc = b * b - (f.length_squared() - RADIUS * RADIUS);
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t > 0.0).then(|| SurfaceHit {
        t,
        normal: (o + t * d - CENTRE) / RADIUS,
    })
}

fn angle(a: Vec3, b: Vec3) -> f32 {
    // 2·asin(|a − b| / 2): accurate at small angles, unlike acos of a dot product.
    2.0 * ((a.normalize() - b.normalize()).length() / 2.0)
        .min(1.0)
        .asin()
}

#[test]
fn phong_samples_have_the_lobes_mean_cosine() {
    // Under a density ∝ cos^e over the hemisphere, E[cos α] = (e + 1) / (e + 2); 64² cell
    // centres reproduce it to 1e-3, and every sample lies in the upper hemisphere.
    let rays = RaySet::new(64, 5);
    let mut squares = Vec::new();
    rays.fill_square(3, &mut squares);
    for e in [1.0f32, 10.0, 200.0] {
        let z: Vec<f32> = squares.iter().map(|&u| square_to_phong(u, e).z).collect();
        assert!(z.iter().all(|&z| z > 0.0 && z <= 1.0));
        let mean = z.iter().map(|&z| z as f64).sum::<f64>() / z.len() as f64;
        let want = (e as f64 + 1.0) / (e as f64 + 2.0);
        assert!((mean - want).abs() < 1e-3, "e = {e}: {mean} vs {want}");
    }
}

/// 1 − cos α of a unit direction about +z, without cancellation: (x² + y²) / (1 + z), in f64.
fn one_minus_cos(d: Vec3) -> f64 {
    let (x, y, z) = (d.x as f64, d.y as f64, d.z as f64);
    (x * x + y * y) / (1.0 + z)
}

/// Phong lobes at every decade of the exponent from 1e-3 to 1e7 (the GPU kernels trace these
/// same host directions, `gpu::reflect_rays::lobe_directions`, so this covers both backends):
///
/// - the moment: under density ∝ cos^e, E[1 − cos α] = 1/(e + 2); 64² cell centres give it
///   within 1% relative (it is the moment that collapses to 0 when cos α rounds to 1);
/// - a chi-square test: 20 000 pseudo-random squares, each direction's CDF value
///   F = cos^(e+1) α (from 1 − cos α through ln_1p) and azimuth binned 16 × 8; uniform bins
///   give χ² with 127 degrees of freedom, under 190 with probability 1 − 2e-4;
/// - a negative control: the e = 10 directions tested as if e were 11 must fail.
#[test]
fn phong_lobes_hold_their_distribution_at_every_exponent_decade() {
    let rays = RaySet::new(64, 5);
    let mut squares = Vec::new();
    rays.fill_square(3, &mut squares);
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        // splitmix64, to the open unit interval
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (((z ^ (z >> 31)) >> 40) as f32 + 0.5) / (1u64 << 24) as f32
    };
    let random: Vec<Vec2> = (0..20_000).map(|_| Vec2::new(next(), next())).collect();
    let chi2 = |dirs: &[Vec3], e: f64| {
        let (nf, np) = (16usize, 8usize);
        let mut bins = vec![0u32; nf * np];
        for &d in dirs {
            let f = ((e + 1.0) * (-one_minus_cos(d)).ln_1p()).exp();
            let phi = (d.y as f64)
                .atan2(d.x as f64)
                .rem_euclid(std::f64::consts::TAU);
            let i = ((f * nf as f64) as usize).min(nf - 1);
            let j = ((phi / std::f64::consts::TAU * np as f64) as usize).min(np - 1);
            bins[i * np + j] += 1;
        }
        let expect = dirs.len() as f64 / bins.len() as f64;
        bins.iter()
            .map(|&b| (b as f64 - expect).powi(2) / expect)
            .sum::<f64>()
    };
    for decade in -3..=7 {
        let e = 10f32.powi(decade);
        let cells: Vec<Vec3> = squares.iter().map(|&u| square_to_phong(u, e)).collect();
        assert!(cells
            .iter()
            .all(|d| d.z >= 0.0 && (d.length() - 1.0).abs() < 1e-6));
        let mean = cells.iter().map(|&d| one_minus_cos(d)).sum::<f64>() / cells.len() as f64;
        let want = 1.0 / (e as f64 + 2.0);
        assert!(
            (mean / want - 1.0).abs() < 1e-2,
            "e = {e}: E[1 − cos] {mean:e} vs {want:e}"
        );
        let dirs: Vec<Vec3> = random.iter().map(|&u| square_to_phong(u, e)).collect();
        let x2 = chi2(&dirs, e as f64);
        assert!(
            x2 < 190.0,
            "e = {e}: χ² {x2:.1} over 127 degrees of freedom"
        );
        if decade == 1 {
            let wrong = chi2(&dirs, 11.0);
            assert!(
                wrong > 190.0,
                "the χ² test cannot fail: {wrong:.1} for e = 11"
            );
        }
    }
}

/// A mirror floor reflecting a sphere, by ray casting on its tessellation: where the analytic
/// mirror ray meets the sphere at an incidence cosine above 0.2, the ray cast hits it too, its
/// point within the tessellation's sagitta h of the analytic one (a ray crossing the shell
/// between radii R − h and R travels at most h / cos before it must meet the mesh) and its
/// normal within the facets' largest angle to their vertices' radial directions; a miss by the
/// analytic sphere by more than the same margin is a miss. The shaded values then agree.
#[test]
fn a_mirror_floor_reflects_the_sphere_where_the_closed_form_says() {
    let mesh = procedural::uv_sphere(RADIUS, 48, 96).unwrap();
    let tris: Vec<[Vec3; 3]> = (0..mesh.triangle_count())
        .map(|i| mesh.triangle(i).map(|v| v + CENTRE))
        .collect();
    let (sagitta, facet_angle) = tessellation_bounds(&tris);
    let tracer = Tracer::new(&tris);
    let o = opts(Gloss::Mirror);
    let (p, n) = floor_points();
    let (mut squares, mut dirs) = (Vec::new(), Vec::new());
    let rays = RaySet::new(1, 0);
    let (mut hits, mut misses) = (0, 0);
    for (i, (&p, &n)) in p.iter().zip(&n).enumerate() {
        let origin = reflection_rays(i as u32, p, n, &rays, &o, &mut squares, &mut dirs);
        assert_eq!(dirs.len(), 1, "a mirror has one ray");
        let d = dirs[0];
        let exact = analytic_hit(origin, d);
        let cast = tracer.surface_hit(origin, d, 0.0, f32::INFINITY);
        match exact {
            Some(e) => {
                let cos = -d.dot(e.normal);
                if cos < 0.2 {
                    continue;
                }
                let c = cast.expect("the tessellation is hit where the sphere is");
                assert!(c.t >= e.t - 1e-5 && c.t <= e.t + sagitta / cos + 1e-5);
                let nc = if c.normal.dot(d) > 0.0 {
                    -c.normal
                } else {
                    c.normal
                };
                assert!(angle(nc, e.normal) <= facet_angle + 1e-4);
                hits += 1;
            }
            None => {
                // A clear miss: the line passes farther than R + h from the centre.
                let f = origin - CENTRE;
                let dist = (f - f.dot(d) * d).length();
                if dist > RADIUS + sagitta {
                    assert!(cast.is_none());
                    misses += 1;
                }
            }
        }
    }
    assert!(hits > 200 && misses > 200, "{hits} hits, {misses} misses");
}

/// The same floor and sphere through the sphere's field and normal field (4226 × 32², u16
/// distances, 16-bit normals). For a ray entering the field's sphere at û with direction d, the
/// lookup reads map m (at p̂_m) and the texel of direction d_t; it answers the entry point
/// moved by t_m, the stored distance of the map ray from p̂_m along d_t, and that ray's hit
/// normal. On a sphere the analytic hit is the entry point and its normal û, so, per ray:
///
/// - t_m is at most the length of the map ray inside the shell R − h … R (exact chord formula
///   at the map ray's own incidence), plus the u16 quantum 2R/65535;
/// - the normal is off û by at most the facet angle, plus the angle the map ray's hit sits from
///   p̂_m (t_m / (R − h)), plus angle(û, p̂_m) (the map spacing), plus the 16-bit octahedral
///   error (2e-4 rad).
#[test]
fn the_field_reflects_the_sphere_within_its_map_spacing_and_texel() {
    let mesh = procedural::uv_sphere(RADIUS, 48, 96).unwrap();
    let (sagitta, facet_angle) = tessellation_bounds(
        &(0..mesh.triangle_count())
            .map(|i| mesh.triangle(i))
            .collect::<Vec<_>>(),
    );
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 4226,
        layout: LayoutKind::Concentric,
        res: 32,
        precision: Precision::U16,
    };
    let (field, normals, _) =
        bake_mesh_with_normals(&mesh, params, 16, &BakeOptions::default()).unwrap();
    let (field, normals) = (Arc::new(field), Arc::new(normals));
    let bounds = field.bounds;
    let transform = Similarity::new(Quat::IDENTITY, CENTRE, 1.0);
    let fs = FieldScene {
        instances: vec![FieldInstance::new(field.clone(), transform).with_normals(normals)],
        options: LookupOptions::default(),
    };
    let o = opts(Gloss::Mirror);
    let (p, n) = floor_points();
    let (mut squares, mut dirs) = (Vec::new(), Vec::new());
    let rays = RaySet::new(1, 0);
    let r = bounds.radius;
    let mut checked = 0;
    for (i, (&p, &n)) in p.iter().zip(&n).enumerate() {
        let origin = reflection_rays(i as u32, p, n, &rays, &o, &mut squares, &mut dirs);
        let d = dirs[0];
        let Some(h) = fs.surface_hit(origin, d, 0.0, f32::INFINITY) else {
            continue;
        };
        // The entry into the field's sphere (model space: world − CENTRE).
        let f = origin - CENTRE - bounds.center;
        let b = f.dot(d);
        let t0 = -b - (b * b - (f.length_squared() - r * r)).max(0.0).sqrt();
        let u = (f + t0 * d) / r;
        let read = NearestRead::of(&field, u.normalize(), d);
        let m = read.map as usize;
        let pm = field.points.point(m);
        let dt = field.frames[m].to_world(field.layout.to_direction(read.texel).unwrap());
        let cos_m = (-dt.dot(pm)).max(1e-3);
        let c = (r - sagitta) / r;
        let chord = r * (cos_m - (cos_m * cos_m - (1.0 - c * c)).max(0.0).sqrt());
        let chord = if cos_m * cos_m < 1.0 - c * c {
            2.0 * r * cos_m
        } else {
            chord
        };
        let tm = h.t - t0;
        assert!(
            tm >= -1e-4 && tm <= chord + 2.0 * r / 65535.0 + 1e-4,
            "ray {i}: moved {tm} past the entry, bound {chord}"
        );
        let nf = if h.normal.dot(d) > 0.0 {
            -h.normal
        } else {
            h.normal
        };
        let bound = facet_angle + tm.max(0.0) / (r - sagitta) + angle(u, pm) + 2e-4;
        assert!(
            angle(nf, u) <= bound + 1e-4,
            "ray {i}: normal off by {} rad, bound {bound}",
            angle(nf, u)
        );
        checked += 1;
    }
    assert!(checked > 200, "only {checked} rays met the field");
}

/// A Phong lobe sharp enough that all its rays stay within a thousandth of a radian of the
/// mirror direction gives the mirror's image where the mirror ray is far from the sphere's
/// outline; with no caster every ray brings back the sky, at any lobe.
#[test]
fn lobe_limits_are_the_mirror_and_the_sky() {
    let tris = crate::trace::test_scenes::icosphere(4, RADIUS, CENTRE);
    let tracer = Tracer::new(&tris);
    let (p, n) = floor_points();
    let rays = RaySet::new(3, 7);
    let mirror = reflect_at_points(&tracer, &p, &n, &rays, &opts(Gloss::Mirror));
    let sharp = reflect_at_points(
        &tracer,
        &p,
        &n,
        &rays,
        &opts(Gloss::Phong { exponent: 1e8 }),
    );
    let mut compared = 0;
    for (i, (a, b)) in mirror.iter().zip(&sharp).enumerate() {
        let v = (p[i] - EYE).normalize();
        let r = v - 2.0 * v.dot(Vec3::Z) * Vec3::Z;
        let f = p[i] - CENTRE;
        let dist = (f - f.dot(r) * r).length();
        if (dist - RADIUS).abs() > 0.05 {
            assert!(
                (a - b).abs() < 0.01,
                "point {i}: mirror {a}, sharp lobe {b}"
            );
            compared += 1;
        }
    }
    assert!(compared > 3000);
    assert!(mirror.iter().any(|&v| v != 0.3) && mirror.contains(&0.3));
    let empty = Tracer::new(&[]);
    let glossy = reflect_at_points(&empty, &p, &n, &rays, &opts(Gloss::Phong { exponent: 5.0 }));
    assert!(glossy.iter().all(|&v| v == 0.3));
}

/// (sagitta, facet angle) of a triangulated sphere about CENTRE or the origin (its own
/// minimal bounding sphere's centre): the largest depth of a facet's plane below the
/// circumscribed radius, and the largest angle between a facet's normal and the radial
/// direction of its vertices (which bounds it over the facet: a cap of that radius about the
/// normal holds the vertices' spherical triangle).
fn tessellation_bounds(tris: &[[Vec3; 3]]) -> (f32, f32) {
    let centre = crate::geometry::minimal_bounding_sphere(
        &tris.iter().flatten().copied().collect::<Vec<_>>(),
    );
    let (mut sag, mut ang) = (0.0f32, 0.0f32);
    for t in tris {
        let nrm = (t[1] - t[0]).cross(t[2] - t[0]);
        if nrm.length_squared() == 0.0 {
            continue;
        }
        let nrm = nrm.normalize();
        let nrm = if nrm.dot(t[0] - centre.center) < 0.0 {
            -nrm
        } else {
            nrm
        };
        sag = sag.max(centre.radius - nrm.dot(t[0] - centre.center));
        for v in t {
            ang = ang.max(angle(nrm, *v - centre.center));
        }
    }
    (sag, ang)
}
