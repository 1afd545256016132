//! The 2010 kinds' secondary rays at their extremes (Gaitatzes, Andreadis, Papaioannou,
//! Chrysanthou, WSCG 2010, §4.2): sphere lights from r/d = 0.5 down to 1e-7 and point lights,
//! against f64 closed forms; lights grazing a caster's bounding sphere (field against ray
//! casting); a light below the receiving surface; Phong lobes by exponent decade; a mirror at
//! grazing incidence.
//!
//! The occluder of the light cases is an exact sphere ([`ExactSphere`], its crossings in f64), so
//! the rows measure the shadow rays (cone, directions, weights, far ends) and nothing of a
//! tessellation. Tolerances:
//!
//! - Unoccluded: the light fraction is exactly 1 with a positive unshadowed light, whose sum
//!   Σ w matches π · L · sin²θ_max (n on the axis) within the stratification's bound on the
//!   cone's mean cosine, (1 − cos θ_max) · 2/k, plus 1e-5 for the f32 directions; a point
//!   light's Σ w is I / d² within 1e-6.
//! - Behind a sphere occluder: coaxial (the occluder's cone of half-angle β inside the light's
//!   α), the lit share is the cap annulus 1 − sin²β / sin²α exactly, cosine weights included;
//!   off axis, 1 − Ω(cap ∩ cap) / Ω(cap) (Mazonka 2012's closed form of two caps' intersection;
//!   below α = 1e-3 the planar lens, off by O(α²); both within a few 1e-6 there), the cosine weight neglected, so
//!   within 2/k (strata the outline crosses) + (1 − cos α). A point light's shadow is hard:
//!   every receiver, 1e-4 or more from the shadow's edge, reads exactly 0 or 1.
//! - A light below the receiving surface (defined so): no shadow ray goes below the tangent
//!   plane; a light wholly below gives no light and the fraction 1, the value of a point facing
//!   away from every light, whatever is in the way.
//! - Phong lobes: E[1 − cos α] = 1/(e + 2) within 1% over 64² cell centres, each decade from
//!   1e-3 to 1e7 (the moment that collapses to 0 once cos α rounds to 1 in f32).
//! - Mirror at grazing incidence (n·v from 1e-1 to 1e-7): the reflected direction within 4e-7
//!   rad of the f64 mirror direction, and never dropped (n·r > 0).

use super::{max2, MaxOf, StabilityRow};
use crate::experiment::performance::floor::NoQuery;
use crate::render::reflect::{reflection_rays, square_to_phong, Gloss, ReflectOptions};
use crate::render::shadow::{shadow_at_points, unshadowed_light, ShadowOptions, SphereLight};
use crate::sampling::rays::RaySet;
use crate::visibility::{SurfaceHit, Visibility};
use glam::{DVec3, Vec2, Vec3};

/// The angular radii sin θ_max = r/d of the sphere-light rows.
pub(super) const SIZES: [f64; 8] = [0.5, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7];

/// k of the light cases' ray sets (k² = 1024 rays per light).
const K: u32 = 32;

/// An exact sphere occluder: the segment's crossings with it in f64.
pub struct ExactSphere {
    pub center: DVec3,
    pub radius: f64,
}

impl Visibility for ExactSphere {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.hit_distance(origin, dir, tmin, tmax).is_some()
    }

    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        let (o, d) = (origin.as_dvec3(), dir.as_dvec3().normalize());
        let oc = self.center - o;
        let b = d.dot(oc);
        let h2 = (oc - b * d).length_squared();
        let disc = self.radius * self.radius - h2;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        [b - s, b + s]
            .into_iter()
            .find(|&t| t >= tmin as f64 && t <= tmax as f64)
            .map(|t| t as f32)
    }

    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        self.hit_distance(origin, dir, tmin, tmax)
            .map(|t| SurfaceHit {
                t,
                normal: ((origin + t * dir).as_dvec3() - self.center)
                    .normalize()
                    .as_vec3(),
            })
    }
}

pub(super) fn opts(center: DVec3, radius: f64) -> ShadowOptions {
    ShadowOptions {
        offset: 0.0,
        lights: vec![SphereLight {
            center: center.as_vec3(),
            radius: radius as f32,
            intensity: 1.0,
        }],
    }
}

/// `n` receivers at the origin facing +z, each its own seeded rotation.
pub(super) fn at_origin(n: usize) -> (Vec<Vec3>, Vec<Vec3>) {
    (vec![Vec3::ZERO; n], vec![Vec3::Z; n])
}

/// 1 − cos of an angle whose sine is `s`, without cancellation.
fn one_minus_cos(s: f64) -> f64 {
    s * s / (1.0 + (1.0 - s * s).sqrt())
}

/// The solid angle of the intersection of two caps of angular radii `a`, `b` whose centres are
/// `g` apart (Mazonka 2012, eq. 52; below 1e-3 rad the planar lens, off by O(a²) relative, where the spherical form's cancellation, about
/// ε/a², reaches a few 1e-6).
pub fn cap_cap(a: f64, b: f64, g: f64) -> f64 {
    use std::f64::consts::PI;
    if g >= a + b {
        return 0.0;
    }
    if g <= (a - b).abs() {
        let m = a.min(b);
        return 2.0 * PI * one_minus_cos(m.sin());
    }
    if a.max(b) < 1e-3 {
        return lens(a, b, g);
    }
    let (ca, cb, cg) = (a.cos(), b.cos(), g.cos());
    let (sa, sb, sg) = (a.sin(), b.sin(), g.sin());
    2.0 * (PI
        - ((cg - ca * cb) / (sa * sb)).acos()
        - ((cb - cg * ca) / (sg * sa)).acos() * ca
        - ((ca - cg * cb) / (sg * sb)).acos() * cb)
}

/// The area of the lens of two discs of radii `a`, `b` whose centres are `g` apart, partly
/// overlapping: the small-angle limit of [`cap_cap`].
fn lens(a: f64, b: f64, g: f64) -> f64 {
    a * a * ((g * g + a * a - b * b) / (2.0 * g * a)).acos()
        + b * b * ((g * g + b * b - a * a) / (2.0 * g * b)).acos()
        - 0.5 * ((-g + a + b) * (g + a - b) * (g - a + b) * (g + a + b)).sqrt()
}

/// Unoccluded sphere and point lights: the fraction and the unshadowed light.
pub fn unoccluded() -> Vec<StabilityRow> {
    let case = "sphere_light_unoccluded";
    let rays = RaySet::new(K, 3);
    let (p, n) = at_origin(16);
    let (mut frac, mut rel) = (0.0f64, 0.0f64);
    let mut lights: Vec<(f64, f64)> = SIZES.iter().map(|&s| (3.0, s * 3.0)).collect();
    lights.push((1.5e11, 7e8)); // the sun
    for (d, r) in lights {
        let o = opts(DVec3::new(0.0, 0.0, d), r);
        let s = (r as f32 as f64) / d;
        let v = shadow_at_points(&NoQuery, &p, &n, &rays, &o);
        frac = max2(frac, worst(&v, 1.0));
        let want = std::f64::consts::PI * s * s;
        let t = one_minus_cos(s) * 2.0 / K as f64 + 1e-5;
        for e in unshadowed_light(&p, &n, &rays, &o) {
            // Relative to the allowance, so that one row carries every size.
            rel = max2(rel, (e / want - 1.0).abs() / t);
        }
    }
    let o = opts(DVec3::new(0.3, -0.2, 3.0), 0.0);
    let d2 = (o.lights[0].center.as_dvec3()).length_squared();
    let cos = 3.0 / d2.sqrt();
    let pt = max_rel(&unshadowed_light(&p, &n, &rays, &o), cos / d2);
    let pf = worst(&shadow_at_points(&NoQuery, &p, &n, &rays, &o), 1.0);
    vec![
        StabilityRow::new(
            case,
            "light fraction with nothing in the way, r/d = 0.5 … 1e-7, a sun (7e8 at 1.5e11) and a point light (|S − 1|)",
            max2(frac, pf),
            0.0,
        ),
        StabilityRow::new(
            case,
            "unshadowed light Σw against π L sin²θmax, r/d = 0.5 … 1e-7 and the sun (relative error over its allowance (1 − cos θmax)·2/k + 1e-5)",
            rel,
            1.0,
        ),
        StabilityRow::new(
            case,
            "point light: unshadowed light Σw against I cos/d² (relative)",
            pt,
            1e-6,
        ),
    ]
}

/// The largest |v − want| of `values` (f32 light fractions).
fn worst(values: &[f32], want: f64) -> f64 {
    values.iter().map(|&x| (x as f64 - want).abs()).max_of()
}

fn max_rel(values: &[f64], want: f64) -> f64 {
    values.iter().map(|&v| (v / want - 1.0).abs()).max_of()
}

/// A sphere light behind an exact sphere occluder: the caps' closed forms, and a point light's
/// hard shadow.
pub fn behind_sphere() -> Vec<StabilityRow> {
    let case = "sphere_light_behind_sphere_occluder";
    let rays = RaySet::new(K, 5);
    let (p, n) = at_origin(16);
    let (dl, d_o) = (10.0f64, 5.0f64);
    let (mut coax, mut off) = (0.0f64, 0.0f64);
    for &s in &SIZES {
        let alpha = s.asin();
        let o = opts(DVec3::new(0.0, 0.0, dl), s * dl);
        let s_l = (o.lights[0].radius as f64) / dl; // the f32 radius
                                                    // Coaxial: occluder's cone of sin β = 0.6 s.
        let beta_s = 0.6 * s;
        let occ = ExactSphere {
            center: DVec3::new(0.0, 0.0, d_o),
            radius: beta_s * d_o,
        };
        let want = 1.0 - (beta_s * beta_s) / (s_l * s_l);
        let v = shadow_at_points(&occ, &p, &n, &rays, &o);
        let t = 2.0 / K as f64 + 1e-5;
        coax = max2(coax, worst(&v, want) / t);
        // Off axis: the occluder's cone of angular radius 0.7 α, its axis 0.9 α off the light's.
        let (beta, gamma) = (0.7 * alpha, 0.9 * alpha);
        let dir = DVec3::new(gamma.sin(), 0.0, gamma.cos());
        let occ = ExactSphere {
            center: dir * d_o,
            radius: beta.sin() * d_o,
        };
        let alpha_l = s_l.asin();
        let want =
            1.0 - cap_cap(alpha_l, beta, gamma) / (2.0 * std::f64::consts::PI * one_minus_cos(s_l));
        let v = shadow_at_points(&occ, &p, &n, &rays, &o);
        let t = 2.0 / K as f64 + one_minus_cos(s) + 1e-5;
        off = max2(off, worst(&v, want) / t);
    }
    // A point light at (0, 0, 10) over a sphere of radius 1 at (0, 0, 5): receivers along x on
    // the floor z = 0; the shadow's edge is where the line to the light is tangent to the sphere.
    let light = DVec3::new(0.0, 0.0, dl);
    let occ = ExactSphere {
        center: DVec3::new(0.0, 0.0, d_o),
        radius: 1.0,
    };
    let o = opts(light, 0.0);
    let xs: Vec<f64> = (0..400).map(|i| 0.01 * i as f64 - 2.0 + 0.005).collect();
    let pts: Vec<Vec3> = xs.iter().map(|&x| Vec3::new(x as f32, 0.0, 0.0)).collect();
    // Tangent from (x, 0, 0) to the light: the distance of the sphere's centre from the line.
    let shadowed = |x: f64| {
        let q = DVec3::new(x, 0.0, 0.0);
        let u = (light - q).normalize();
        let h = (occ.center - q) - u.dot(occ.center - q) * u;
        (h.length() - occ.radius, h.length() < occ.radius)
    };
    let v = shadow_at_points(&occ, &pts, &vec![Vec3::Z; pts.len()], &rays, &o);
    let mut wrong = 0usize;
    let mut counted = 0usize;
    for (&x, &val) in xs.iter().zip(&v) {
        let (margin, dark) = shadowed(x);
        if margin.abs() < 1e-4 {
            continue;
        }
        counted += 1;
        wrong += (val != if dark { 0.0 } else { 1.0 }) as usize;
    }
    vec![
        StabilityRow::new(
            case,
            "coaxial: light fraction against the cap annulus 1 − sin²β/sin²α, r/d = 0.5 … 1e-7 (error over its allowance 2/k + 1e-5)",
            coax,
            1.0,
        ),
        StabilityRow::new(
            case,
            "off axis: light fraction against 1 − Ω(cap ∩ cap)/Ω(cap), r/d = 0.5 … 1e-7 (error over its allowance 2/k + (1 − cos α) + 1e-5)",
            off,
            1.0,
        ),
        StabilityRow::new(
            case,
            format!("point light: receivers not exactly 0 in the hard shadow or 1 outside (count of {counted})"),
            wrong as f64,
            0.0,
        ),
    ]
}

/// The lights of the grazing case, one per gap (1e-1, 1e-3 and 1e-6 of the radius) above the
/// caster's bounding sphere `b`, each with its 200 receivers beside the sphere and their
/// normals towards the light.
pub(super) fn grazing_lights(
    b: &crate::geometry::Sphere,
) -> Vec<(ShadowOptions, Vec<Vec3>, Vec<Vec3>)> {
    [1e-1f32, 1e-3, 1e-6]
        .into_iter()
        .map(|gap| {
            let r = 0.5 * b.radius;
            let center = b.center + Vec3::Z * (b.radius * (1.0 + gap) + r);
            let o = ShadowOptions {
                offset: 1e-4,
                lights: vec![SphereLight {
                    center,
                    radius: r,
                    intensity: 1.0,
                }],
            };
            let p: Vec<Vec3> = (0..200)
                .map(|i| {
                    let x = 1.02 + 0.01 * i as f32;
                    b.center + b.radius * Vec3::new(x, 0.1 * (i % 5) as f32, -0.5)
                })
                .collect();
            let n: Vec<Vec3> = p.iter().map(|&q| (center - q).normalize()).collect();
            (o, p, n)
        })
        .collect()
}

/// Lights grazing a caster's bounding sphere (gaps of 1e-1, 1e-3 and 1e-6 of its radius): a
/// convex caster's field (a UV sphere, 1090 × 32² u8) answers the shadow rays, which pass the
/// caster and end at the light just outside its bounding sphere, as ray casting does on the
/// same rays, within the field's tolerances of `stability::hard` (RMS 6 on 0–255, 0.25 per point).
pub fn grazing_caster_sphere() -> Vec<StabilityRow> {
    use crate::field::scene::{FieldInstance, FieldScene};
    use crate::geometry::{procedural, Similarity};
    use crate::trace::Tracer;
    let case = "light_grazing_caster_sphere";
    let mesh = procedural::uv_sphere(1.0, 32, 64).expect("uv sphere");
    let field = super::scene_ao::bake_field(&mesh);
    let b = field.bounds;
    let fs = FieldScene {
        instances: vec![FieldInstance::new(field.clone(), Similarity::default())],
        options: Default::default(),
    };
    let tris: Vec<[Vec3; 3]> = (0..mesh.triangle_count())
        .map(|i| mesh.triangle(i))
        .collect();
    let tracer = Tracer::new(&tris);
    let rays = RaySet::new(8, 11);
    let (mut rms, mut max, mut shadowed) = (0.0f64, 0.0f64, 0usize);
    let mut total = 0usize;
    for (o, p, n) in grazing_lights(&b) {
        let exact = shadow_at_points(&tracer, &p, &n, &rays, &o);
        let approx = shadow_at_points(&fs, &p, &n, &rays, &o);
        for (a, e) in approx.iter().zip(&exact) {
            let d = (*a as f64 - *e as f64).abs();
            rms += (255.0 * d).powi(2);
            max = max2(max, d);
            shadowed += (*e < 0.99) as usize;
            total += 1;
        }
    }
    let rms = (rms / total as f64).sqrt();
    vec![
        StabilityRow::new(
            case,
            format!("field against ray casting on the same shadow rays, gaps 1e-1 … 1e-6 R (RMS 0–255, {total} points, {shadowed} shadowed)"),
            if shadowed * 10 >= total { rms } else { f64::NAN },
            super::hard::FIELD_RMS,
        ),
        StabilityRow::new(
            case,
            "field against ray casting, per point (light fraction)",
            max,
            super::hard::FIELD_MAX,
        ),
    ]
}

/// A light below the receiving surface: wholly below (no light, S = 1 under a blocker) and
/// straddling the tangent plane (no ray below it).
pub fn below_surface() -> Vec<StabilityRow> {
    let case = "light_below_receiver";
    let rays = RaySet::new(K, 7);
    let (p, n) = at_origin(16);
    let blocker = ExactSphere {
        center: DVec3::new(0.0, 0.0, -5.0),
        radius: 2.0,
    };
    let mut dev = 0.0f64;
    let mut light = 0.0f64;
    for r in [1.0, 1e-4, 0.0] {
        let o = opts(DVec3::new(0.0, 0.0, -10.0), r);
        let v = shadow_at_points(&blocker, &p, &n, &rays, &o);
        dev = max2(dev, worst(&v, 1.0));
        light = max2(
            light,
            unshadowed_light(&p, &n, &rays, &o).into_iter().max_of(),
        );
    }
    // Straddling: a light centred on the tangent plane, half its cone (11.5°) below it, and a
    // blocker under the surface covering elevations −30° … −3.4° of the lower half: the
    // fraction is exactly 1, since no counted ray goes below the plane (rays below it would
    // be blocked, a share of about a third).
    let o = opts(DVec3::new(10.0, 0.0, 0.0), 2.0);
    let under = ExactSphere {
        center: DVec3::new(5.0, 0.0, -1.5),
        radius: 1.2,
    };
    let v = shadow_at_points(&under, &p, &n, &rays, &o);
    let straddle = worst(&v, 1.0);
    let below = shadow_at_points(&under, &p, &[Vec3::X; 16], &rays, &o);
    let control = below.iter().map(|&x| x as f64).fold(1.0, f64::min);
    let half = unshadowed_light(&p, &n, &rays, &o);
    vec![
        StabilityRow::new(
            case,
            "light wholly below the tangent plane, a blocker between: |S − 1| (no light, no shadow), radii 1, 1e-4, 0",
            dev,
            0.0,
        ),
        StabilityRow::new(case, "light wholly below: unshadowed light Σw", light, 0.0),
        StabilityRow::new(
            case,
            "light straddling the tangent plane, a blocker under the surface: |S − 1| (rays below the plane would be blocked)",
            straddle,
            0.0,
        ),
        StabilityRow::new(
            case,
            "negative control: a receiver facing the light (normal +x) is shadowed by the same blocker (1 when it is not)",
            if control < 1.0 { 0.0 } else { 1.0 },
            0.0,
        ),
        StabilityRow::new(
            case,
            "light straddling the tangent plane: points with no unshadowed light (count of 16)",
            half.iter().filter(|&&e| e <= 0.0).count() as f64,
            0.0,
        ),
    ]
}

/// Phong lobes by exponent decade, 1e-3 … 1e7: E[1 − cos α] = 1/(e + 2).
pub fn phong_lobes() -> Vec<StabilityRow> {
    let rays = RaySet::new(64, 5);
    let mut squares: Vec<Vec2> = Vec::new();
    rays.fill_square(3, &mut squares);
    (-3..=7)
        .map(|decade| {
            let e = 10f32.powi(decade);
            let mean = squares
                .iter()
                .map(|&u| {
                    let d = square_to_phong(u, e);
                    let (x, y, z) = (d.x as f64, d.y as f64, d.z as f64);
                    (x * x + y * y) / (1.0 + z)
                })
                .sum::<f64>()
                / squares.len() as f64;
            let want = 1.0 / (e as f64 + 2.0);
            StabilityRow::new(
                "phong_lobe_by_exponent",
                format!(
                    "exponent 1e{decade}: E[1 − cos α] against 1/(e + 2) (relative, 64² cells)"
                ),
                (mean / want - 1.0).abs(),
                1e-2,
            )
        })
        .collect()
}

/// A mirror at grazing incidence: n·v from 1e-1 down to 1e-7.
pub fn mirror_grazing() -> Vec<StabilityRow> {
    let case = "mirror_grazing";
    let rays = RaySet::new(1, 1);
    let (mut angle, mut dropped, mut total) = (0.0f64, 0usize, 0usize);
    for e in 1..=7 {
        let c = 10f64.powi(-e);
        for az in 0..8 {
            let phi = az as f64 * 0.7;
            // The eye far off along the view, which meets the floor z = 0 at grazing cosine c.
            let v = DVec3::new(
                (1.0 - c * c).sqrt() * phi.cos(),
                (1.0 - c * c).sqrt() * phi.sin(),
                -c,
            );
            let point = DVec3::new(0.1, 0.2, 0.0);
            let eye = point - 10.0 * v;
            let opts = ReflectOptions {
                offset: 0.0,
                eye: eye.as_vec3(),
                gloss: Gloss::Mirror,
                lights: Vec::new(),
                albedo: 1.0,
                sky: 1.0,
            };
            let (mut sq, mut dirs) = (Vec::new(), Vec::new());
            reflection_rays(
                0,
                point.as_vec3(),
                Vec3::Z,
                &rays,
                &opts,
                &mut sq,
                &mut dirs,
            );
            // The f64 mirror of the f32 view the ray set sees.
            let v32 = (point.as_vec3() - opts.eye).as_dvec3().normalize();
            let want = DVec3::new(v32.x, v32.y, -v32.z);
            total += 1;
            match dirs.first() {
                Some(d) => angle = max2(angle, d.as_dvec3().normalize().cross(want).length()),
                None => dropped += 1,
            }
        }
    }
    vec![
        StabilityRow::new(
            case,
            format!("n·v = 1e-1 … 1e-7: angle of the mirror ray to the f64 mirror direction (rad, {total} rays)"),
            angle,
            4e-7,
        ),
        StabilityRow::new(
            case,
            format!("n·v = 1e-1 … 1e-7: mirror rays dropped as below the surface (count of {total})"),
            dropped as f64,
            0.0,
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cap_cap_has_its_limits() {
        use std::f64::consts::PI;
        // Disjoint, nested, and the spherical and planar forms agree where both hold.
        assert_eq!(cap_cap(0.1, 0.1, 0.3), 0.0);
        let nested = cap_cap(0.3, 0.1, 0.05);
        assert!((nested - 2.0 * PI * (1.0 - 0.1f64.cos())).abs() < 1e-15);
        // At 0.05 the spherical form exceeds the planar lens by its O(a²) curvature (and its
        // cancellation, about ε/a², is far smaller); at the switch, 1e-3, both meet within 1e-4
        // (there the cancellation dominates: a few 1e-6).
        let gap = |a: f64| {
            let (b, g) = (0.7 * a, 0.9 * a);
            (cap_cap(a, b, g) / lens(a, b, g) - 1.0).abs()
        };
        let g = gap(0.05);
        assert!(g > 0.0 && g < 0.05 * 0.05, "{g:e}");
        assert!(
            gap(1e-3 * (1.0 + 1e-9)) < 1e-4,
            "{:e}",
            gap(1e-3 * (1.0 + 1e-9))
        );
    }
}
