//! Ray–sphere crossings ([`crate::field::lookup::sphere_crossing`]) on stiff inputs, against an
//! f64 reference: the roots of `|f + t d|² = r²` (f = origin − centre, d the f32 direction
//! normalised in f64) from the textbook quadratic, each polished by two Newton steps on
//! `g(t) = |f + t d|² − r²`, which removes the quadratic's cancellation for far origins.
//!
//! Errors are distances in units of R between the crossing points: the entry point the lookup
//! reads its map at (origins outside), and the exit point `(origin − c) + t1·dir` of the
//! intra-object test (origins inside; computed as the lookup computes it, in f32). The
//! requirement is 1e-5 R. The f32 exit point is not accurate for far origins (1.2e-4 R for
//! tangent rays from 1e3 R), which is why the lookup uses the f64 entry point outside.

use super::{max_of, StabilityRow};
use crate::field::lookup::sphere_crossing;
use crate::sampling::rays::seeded_sphere_direction;
use glam::{DVec3, Vec3};

/// Entry and exit points of the lookup must lie within this many R of the f64 ones.
pub const POINT_TOLERANCE_R: f64 = 1e-5;

/// The f64 reference: (t0, t1) or `None` for a miss, from the exact f32 inputs.
pub fn reference_roots(origin: Vec3, dir: Vec3, center: Vec3, radius: f32) -> Option<(f64, f64)> {
    let f = origin.as_dvec3() - center.as_dvec3();
    let d = dir.as_dvec3().normalize();
    let r = radius as f64;
    let b = f.dot(d);
    // The decision uses the perpendicular offset, which is exact to a few ulps of |f|.
    let l = f - b * d;
    if l.length_squared() > r * r {
        return None;
    }
    let c = f.length_squared() - r * r;
    let s = (b * b - c).max(0.0).sqrt();
    let polish = |mut t: f64| {
        for _ in 0..2 {
            let p = f + t * d;
            let g = p.length_squared() - r * r;
            let dg = 2.0 * p.dot(d);
            if dg != 0.0 {
                t -= g / dg;
            }
        }
        t
    };
    Some((polish(-b - s), polish(-b + s)))
}

/// Errors (in R) of one ray: entry point, exit point; or a classification mismatch.
enum Outcome {
    BothMiss,
    Mismatch,
    Points { entry: f64, exit: f64 },
}

fn compare(origin: Vec3, dir: Vec3, center: Vec3, radius: f32) -> Outcome {
    let got = sphere_crossing(origin, dir, center, radius);
    let want = reference_roots(origin, dir, center, radius);
    match (got, want) {
        (None, None) => Outcome::BothMiss,
        (Some(_), None) | (None, Some(_)) => Outcome::Mismatch,
        (Some(g), Some((t0, t1))) => {
            let f = origin.as_dvec3() - center.as_dvec3();
            let d = dir.as_dvec3().normalize();
            let r = radius as f64;
            let entry = (g.entry - (f + t0 * d)).length() / r;
            // The lookup's exit point, in f32 as in `VisibilityField::hit_distance`.
            let p1 = ((origin - center) + g.t1 * dir).as_dvec3();
            let exit = (p1 - (f + t1 * d)).length() / r;
            Outcome::Points { entry, exit }
        }
    }
}

/// Accumulates outcomes into the rows of one case.
#[derive(Default)]
struct Tally {
    entry: Vec<f64>,
    exit: Vec<f64>,
    mismatches: usize,
    rays: usize,
}

impl Tally {
    fn add(&mut self, o: Outcome) {
        self.rays += 1;
        match o {
            Outcome::BothMiss => {}
            Outcome::Mismatch => self.mismatches += 1,
            Outcome::Points { entry, exit } => {
                self.entry.push(entry);
                self.exit.push(exit);
            }
        }
    }

    fn rows(self, case: &str, what: &str, with_entry: bool, with_exit: bool) -> Vec<StabilityRow> {
        let mut rows = vec![StabilityRow::new(
            case,
            format!(
                "{what}: hit/miss disagreements with f64 (count of {})",
                self.rays
            ),
            self.mismatches as f64,
            0.0,
        )];
        let points = [
            ("entry", with_entry, self.entry),
            ("exit", with_exit, self.exit),
        ];
        for (point, _, errors) in points.into_iter().filter(|p| p.1) {
            let quantity = format!("{what}: {point} point error (R, {} hits)", errors.len());
            rows.push(StabilityRow::new(
                case,
                quantity,
                max_of(errors),
                POINT_TOLERANCE_R,
            ));
        }
        rows
    }
}

/// Spheres the cases use: near the origin, and far from it (coordinates ~1e4).
fn spheres() -> [(Vec3, f32); 2] {
    [
        (Vec3::new(0.3, -0.2, 0.5), 0.7),
        (Vec3::new(1.0e4, -2.5e3, 7.5e3), 3.0),
    ]
}

/// Origins from 1e-3 R to 1e6 R from the centre. Outside: aimed at points within 0.95 R of the
/// centre (clear hits; entry point checked). Inside: random directions (exit point checked).
pub fn far_and_near() -> Vec<StabilityRow> {
    let case = "ray_sphere_far_and_near";
    let (mut outside, mut inside) = (Tally::default(), Tally::default());
    let distances = [
        1e-3, 1e-2, 0.1, 0.5, 0.9, 0.999, 1.001, 1.1, 2.0, 10.0, 1e2, 1e3, 1e4, 1e5, 1e6,
    ];
    for (s, (c, r)) in spheres().into_iter().enumerate() {
        for (k, &dist) in distances.iter().enumerate() {
            for i in 0..2000u64 {
                let key = (s as u64 * 64 + k as u64) * 100_000 + i;
                let u = seeded_sphere_direction(key, 11).as_dvec3();
                let origin = (c.as_dvec3() + dist * r as f64 * u).as_vec3();
                if dist > 1.0 {
                    let aim = c + 0.95 * r * seeded_sphere_direction(key, 12) * uniform(key);
                    let dir = (aim - origin).normalize();
                    outside.add(compare(origin, dir, c, r));
                } else {
                    let dir = seeded_sphere_direction(key, 13);
                    inside.add(compare(origin, dir, c, r));
                }
            }
        }
    }
    let mut rows = outside.rows(case, "origins 1.001 R to 1e6 R", true, false);
    rows.extend(inside.rows(case, "origins 1e-3 R to 0.999 R", false, true));
    rows
}

/// A seeded value in [0, 1).
fn uniform(key: u64) -> f32 {
    0.5 * (seeded_sphere_direction(key, 14).x + 1.0)
}

/// Rays tangent to the sphere and one f32 ulp either side, along the axes (so that the
/// perpendicular offset is exactly R, next_up(R) or next_down(R) and the f64 answer is exact),
/// from 2 R and 1e3 R away; then seeded tangent rays in general position. The exactly tangent
/// ray and the one an ulp inside must hit, the one an ulp outside must miss.
pub fn grazing() -> Vec<StabilityRow> {
    let case = "ray_sphere_grazing";
    let mut axis = Tally::default();
    let mut general = Tally::default();
    for (c, r) in spheres() {
        for offset in [r, r.next_up(), r.next_down()] {
            for back in [2.0 * r, 1e3 * r] {
                for a in 0..3 {
                    for sign in [1.0f32, -1.0] {
                        let mut dir = Vec3::ZERO;
                        dir[a] = sign;
                        let mut perp = Vec3::ZERO;
                        perp[(a + 1) % 3] = offset;
                        let mut origin_rel = perp;
                        origin_rel[a] = -sign * back;
                        let origin = c + origin_rel;
                        // Keep only inputs that are exact in f32 (the offset must survive the
                        // addition of the centre).
                        if (origin - c).as_dvec3() != origin_rel.as_dvec3() {
                            continue;
                        }
                        axis.add(compare(origin, dir, c, r));
                    }
                }
            }
        }
        for i in 0..20_000u64 {
            let d = seeded_sphere_direction(i, 21).as_dvec3();
            let n = d.any_orthonormal_vector();
            let n = (n * (seeded_sphere_direction(i, 22).x as f64)
                + d.cross(n) * (seeded_sphere_direction(i, 22).y as f64))
                .normalize();
            let shrink = [1.0 - 1e-7, 1.0, 1.0 + 1e-7][(i % 3) as usize];
            let back = [2.0, 50.0, 1e3][(i / 3 % 3) as usize] * r as f64;
            let origin = (c.as_dvec3() + shrink * r as f64 * n - back * d).as_vec3();
            general.add(compare(origin, d.as_vec3(), c, r));
        }
    }
    // Outside origins: the lookup reads the entry point only (its f32 exit point serves origins
    // inside the sphere, checked by the other cases).
    let mut rows = axis.rows(case, "axis-aligned tangent ± 1 ulp", true, false);
    rows.extend(general.rows(case, "general tangent ± 1e-7 R", true, false));
    rows
}

/// Origins on the sphere (rounded to f32, so a hair inside or outside) and 2⁻²⁴ R, 2⁻²⁰ R and
/// 2⁻¹⁰ R inside it, with random directions: entry and exit points.
pub fn on_and_inside() -> Vec<StabilityRow> {
    let case = "ray_sphere_on_and_inside";
    let mut t = Tally::default();
    for (c, r) in spheres() {
        for (k, depth) in [0.0, 2f64.powi(-24), 2f64.powi(-20), 2f64.powi(-10)]
            .into_iter()
            .enumerate()
        {
            for i in 0..5000u64 {
                let key = k as u64 * 1_000_000 + i;
                let u: DVec3 = seeded_sphere_direction(key, 31).as_dvec3();
                let origin = (c.as_dvec3() + (1.0 - depth) * r as f64 * u).as_vec3();
                let dir = seeded_sphere_direction(key, 32);
                t.add(compare(origin, dir, c, r));
            }
        }
    }
    t.rows(case, "origins on and just inside", true, true)
}
