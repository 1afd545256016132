//! Minimal bounding spheres.

use glam::{DVec3, Vec3};

/// A sphere (centre, radius).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    /// Whether `p` lies inside or on the sphere, with a relative tolerance `rel_tol` on the
    /// radius (`|p − c| <= r·(1 + rel_tol)`).
    pub fn contains(&self, p: Vec3, rel_tol: f32) -> bool {
        p.as_dvec3().distance(self.center.as_dvec3())
            <= f64::from(self.radius) * (1.0 + f64::from(rel_tol))
    }
}

/// The exact minimal enclosing sphere of `points` (Welzl, "Smallest enclosing disks (balls and
/// ellipsoids)", LNCS 555, 1991), in its move-to-front form (Gärtner, "Fast and robust smallest
/// enclosing balls", ESA 1999): expected linear time after a shuffle.
///
/// The shuffle uses a fixed-seed generator, so the result is a pure function of the input.
/// Arithmetic is in f64; the returned f32 radius is rounded up so that every input point lies
/// inside the returned (f32) sphere. Degenerate support sets (coincident, collinear or coplanar
/// points) fall back to the smallest ball of that support set found by enumeration.
///
/// An empty input gives the sphere of radius 0 at the origin.
pub fn minimal_bounding_sphere(points: &[Vec3]) -> Sphere {
    if points.is_empty() {
        return Sphere {
            center: Vec3::ZERO,
            radius: 0.0,
        };
    }
    let mut pts: Vec<DVec3> = points.iter().map(|p| p.as_dvec3()).collect();
    shuffle(&mut pts, 0x9E37_79B9_7F4A_7C15);
    // Containment tolerance: relative to the squared extent of the input.
    let extent = pts
        .iter()
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()))
        .max(f64::MIN_POSITIVE);
    let tol = Tolerance {
        abs2: (extent * 1e-12).powi(2),
    };
    let mut support = Vec::with_capacity(4);
    let n = pts.len();
    let ball = move_to_front(&mut pts, n, &mut support, tol);
    let center = ball.center.as_vec3();
    // Round the radius up so that every point lies within the f32 sphere.
    let c = center.as_dvec3();
    let r = points
        .iter()
        .map(|p| p.as_dvec3().distance(c))
        .fold(ball.radius2.max(0.0).sqrt(), f64::max);
    let mut radius = r as f32;
    if f64::from(radius) < r {
        radius = radius.next_up();
    }
    Sphere { center, radius }
}

/// A ball in f64 with its squared radius; `radius2 < 0` is the empty ball.
#[derive(Clone, Copy, Debug)]
struct Ball {
    center: DVec3,
    radius2: f64,
}

#[derive(Clone, Copy, Debug)]
struct Tolerance {
    /// Absolute slack on squared distances.
    abs2: f64,
}

impl Ball {
    const EMPTY: Ball = Ball {
        center: DVec3::ZERO,
        radius2: -1.0,
    };

    fn contains(&self, p: DVec3, tol: Tolerance) -> bool {
        self.radius2 >= 0.0
            && p.distance_squared(self.center) <= self.radius2 * (1.0 + 1e-12) + tol.abs2
    }
}

/// Welzl's move-to-front recursion: the smallest ball containing `pts[..end]` with `support` on
/// its boundary. Recursion depth is bounded by the support size (at most 4).
fn move_to_front(pts: &mut [DVec3], end: usize, support: &mut Vec<DVec3>, tol: Tolerance) -> Ball {
    let mut ball = ball_on_boundary(support, tol);
    if support.len() == 4 {
        return ball;
    }
    for i in 0..end {
        let p = pts[i];
        if !ball.contains(p, tol) {
            support.push(p);
            ball = move_to_front(pts, i, support, tol);
            support.pop();
            pts[..=i].rotate_right(1);
        }
    }
    ball
}

/// The smallest ball with every point of `s` (at most 4) on its boundary: the circumball in the
/// affine hull of `s`. For an affinely dependent set (no such ball, or an unstable one) it returns
/// the smallest ball containing `s` instead, which keeps the algorithm's output a valid
/// enclosing ball.
fn ball_on_boundary(s: &[DVec3], tol: Tolerance) -> Ball {
    match s.len() {
        0 => Ball::EMPTY,
        1 => Ball {
            center: s[0],
            radius2: 0.0,
        },
        2 => diametral(s[0], s[1]),
        3 => circumcircle(s[0], s[1], s[2]).unwrap_or_else(|| smallest_containing(s, tol)),
        _ => circumsphere(s[0], s[1], s[2], s[3]).unwrap_or_else(|| smallest_containing(s, tol)),
    }
}

fn diametral(a: DVec3, b: DVec3) -> Ball {
    Ball {
        center: (a + b) * 0.5,
        radius2: a.distance_squared(b) * 0.25,
    }
}

/// Circumcircle of a triangle (centre in its plane); `None` when (nearly) collinear.
fn circumcircle(a: DVec3, b: DVec3, c: DVec3) -> Option<Ball> {
    let u = b - a;
    let v = c - a;
    let w = u.cross(v);
    let w2 = w.length_squared();
    if w2 <= 1e-20 * u.length_squared() * v.length_squared() || w2 == 0.0 {
        return None;
    }
    // a + (|u|² (v × w) + |v|² (w × u)) / (2 |w|²): equidistant from a, b, c and in their plane.
    let offset = (u.length_squared() * v.cross(w) + v.length_squared() * w.cross(u)) / (2.0 * w2);
    Some(Ball {
        center: a + offset,
        radius2: offset.length_squared(),
    })
}

/// Circumsphere of a tetrahedron; `None` when (nearly) coplanar.
fn circumsphere(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Option<Ball> {
    let u = b - a;
    let v = c - a;
    let w = d - a;
    let det = u.dot(v.cross(w));
    let scale = u.length() * v.length() * w.length();
    if det.abs() <= 1e-10 * scale || det == 0.0 {
        return None;
    }
    // Solves 2 [u v w]ᵀ x = (|u|², |v|², |w|²) by Cramer's rule.
    let offset = (u.length_squared() * v.cross(w)
        + v.length_squared() * w.cross(u)
        + w.length_squared() * u.cross(v))
        / (2.0 * det);
    Some(Ball {
        center: a + offset,
        radius2: offset.length_squared(),
    })
}

/// The smallest ball containing the (at most 4) points of `s`, by enumerating the candidate
/// balls of their 1-, 2- and 3-point subsets.
fn smallest_containing(s: &[DVec3], tol: Tolerance) -> Ball {
    let contains_all = |b: &Ball| s.iter().all(|&p| b.contains(p, tol));
    let mut best: Option<Ball> = None;
    let mut consider = |b: Ball| {
        if contains_all(&b) && best.is_none_or(|x| b.radius2 < x.radius2) {
            best = Some(b);
        }
    };
    for i in 0..s.len() {
        consider(Ball {
            center: s[i],
            radius2: 0.0,
        });
        for j in i + 1..s.len() {
            consider(diametral(s[i], s[j]));
            for k in j + 1..s.len() {
                if let Some(b) = circumcircle(s[i], s[j], s[k]) {
                    consider(b);
                }
            }
        }
    }
    // The diametral ball of the farthest pair always contains a degenerate (collinear) set up to
    // rounding; it is the fallback if tolerance rejected everything.
    best.unwrap_or_else(|| {
        let mut far = diametral(s[0], s[0]);
        for i in 0..s.len() {
            for j in i + 1..s.len() {
                let b = diametral(s[i], s[j]);
                if b.radius2 > far.radius2 {
                    far = b;
                }
            }
        }
        far
    })
}

/// Fisher–Yates with SplitMix64: deterministic for a given seed.
fn shuffle<T>(v: &mut [T], seed: u64) {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    for i in (1..v.len()).rev() {
        let j = (next() % (i as u64 + 1)) as usize;
        v.swap(i, j);
    }
}

/// The closest point to `p` on triangle `t` (Ericson, *Real-Time Collision Detection*, §5.1.5).
pub fn closest_point_on_triangle(p: Vec3, t: &[Vec3; 3]) -> Vec3 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small deterministic generator for test inputs.
    fn points(seed: u64, n: usize) -> Vec<Vec3> {
        let mut s = seed;
        let mut f = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32) / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        (0..n).map(|_| Vec3::new(f(), f(), f() * 0.5)).collect()
    }

    /// Brute force: the smallest ball among all 1-, 2-, 3- and 4-point circumballs that contains
    /// every point. The minimal ball is determined by at most 4 support points (Welzl 1991), so
    /// this is exact.
    fn brute_force(points: &[Vec3]) -> f64 {
        let p: Vec<DVec3> = points.iter().map(|p| p.as_dvec3()).collect();
        let tol = Tolerance { abs2: 1e-18 };
        let ok = |b: &Ball| p.iter().all(|&q| b.contains(q, tol));
        let mut best = f64::INFINITY;
        let n = p.len();
        let mut consider = |b: Option<Ball>| {
            if let Some(b) = b {
                if ok(&b) {
                    best = best.min(b.radius2.sqrt());
                }
            }
        };
        for i in 0..n {
            consider(Some(Ball {
                center: p[i],
                radius2: 0.0,
            }));
            for j in i + 1..n {
                consider(Some(diametral(p[i], p[j])));
                for k in j + 1..n {
                    consider(circumcircle(p[i], p[j], p[k]));
                    for l in k + 1..n {
                        consider(circumsphere(p[i], p[j], p[k], p[l]));
                    }
                }
            }
        }
        best
    }

    fn assert_encloses(s: &Sphere, pts: &[Vec3]) {
        for (i, p) in pts.iter().enumerate() {
            assert!(
                s.contains(*p, 1e-6),
                "point {i} {p} outside {s:?} by {}",
                p.distance(s.center) - s.radius
            );
        }
    }

    /// The minimal sphere of `pts` encloses them and has the brute force's radius.
    fn check_against_brute_force(pts: &[Vec3], what: &str) {
        let s = minimal_bounding_sphere(pts);
        assert_encloses(&s, pts);
        let expected = brute_force(pts);
        let rel = (f64::from(s.radius) - expected).abs() / expected.max(1e-30);
        assert!(
            rel < 1e-6,
            "{what}: radius {} vs brute force {expected}",
            s.radius
        );
    }

    #[test]
    fn matches_brute_force_on_small_random_sets() {
        for seed in 0..40u64 {
            let n = 8 + (seed as usize % 5);
            check_against_brute_force(&points(seed, n), &format!("seed {seed}"));
        }
    }

    #[test]
    fn matches_brute_force_on_degenerate_lattice_sets() {
        // Subsets of the integer lattice {0,1,2}³ (with repeats): many coplanar, collinear and
        // cospherical quadruples. The minimal ball always has an affinely independent support
        // set, so the brute force (which skips degenerate circumballs) stays exact.
        let mut s = 12345u64;
        for case in 0..40 {
            let pts: Vec<Vec3> = (0..10)
                .map(|_| {
                    s = s
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    let c = |k: u32| ((s >> (33 + 2 * k)) % 3) as f32;
                    Vec3::new(c(0), c(1), c(2))
                })
                .collect();
            check_against_brute_force(&pts, &format!("case {case}"));
        }
    }

    #[test]
    fn single_point_has_radius_zero() {
        let p = Vec3::new(1.5, -2.0, 3.25);
        let s = minimal_bounding_sphere(&[p]);
        assert_eq!(s.center, p);
        assert_eq!(s.radius, 0.0);
        // Repeated copies of one point: still radius 0.
        let s = minimal_bounding_sphere(&[p; 7]);
        assert_eq!(s.radius, 0.0);
    }

    #[test]
    fn unit_cube_corners_give_half_diagonal() {
        // The 8 corners of [0,1]³ lie on the sphere about (½,½,½) with radius √3/2.
        let pts: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let s = minimal_bounding_sphere(&pts);
        assert!((s.radius - 3f32.sqrt() / 2.0).abs() < 1e-6, "{s:?}");
        assert!(s.center.distance(Vec3::splat(0.5)) < 1e-6, "{s:?}");
        assert_encloses(&s, &pts);
    }

    #[test]
    fn regular_tetrahedron_gives_circumradius() {
        // Alternate corners of the cube [-1,1]³: edge 2√2, circumradius √3 (= edge·√6/4), centred
        // at the origin. Interior points do not change the answer.
        let mut pts = vec![
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
        ];
        pts.extend(points(7, 20).iter().map(|p| *p * 0.5));
        let s = minimal_bounding_sphere(&pts);
        assert!((s.radius - 3f32.sqrt()).abs() < 1e-6, "{s:?}");
        assert!(s.center.length() < 1e-6, "{s:?}");
    }

    #[test]
    fn degenerate_collinear_and_coplanar_sets() {
        // Collinear: the diametral ball of the extreme points, radius 2.
        let line: Vec<Vec3> = (0..9)
            .map(|i| Vec3::new(i as f32 * 0.5, 0.0, 0.0))
            .collect();
        let s = minimal_bounding_sphere(&line);
        assert!((s.radius - 2.0).abs() < 1e-6 && s.center.distance(Vec3::X * 2.0) < 1e-6);
        // Coplanar: a regular 12-gon of radius 3 in the z = 1 plane: its circumcircle.
        let ring: Vec<Vec3> = (0..12)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / 12.0;
                Vec3::new(3.0 * a.cos(), 3.0 * a.sin(), 1.0)
            })
            .collect();
        let s = minimal_bounding_sphere(&ring);
        assert!((s.radius - 3.0).abs() < 1e-5, "{s:?}");
        assert!(s.center.distance(Vec3::Z) < 1e-5, "{s:?}");
        assert_encloses(&s, &ring);
        // Points on a sphere's grid (many cospherical quadruples).
        let grid: Vec<Vec3> = (0..8)
            .flat_map(|i| (0..8).map(move |j| (i, j)))
            .map(|(i, j)| {
                let (t, p) = (i as f32 * 0.7, j as f32 * 0.4 - 1.4);
                Vec3::new(t.cos() * p.cos(), p.sin(), t.sin() * p.cos()) * 2.0
            })
            .collect();
        let s = minimal_bounding_sphere(&grid);
        assert_encloses(&s, &grid);
        assert!(s.radius <= 2.0 + 1e-5, "{s:?}");
    }

    #[test]
    fn empty_input_is_radius_zero_at_origin() {
        assert_eq!(
            minimal_bounding_sphere(&[]),
            Sphere {
                center: Vec3::ZERO,
                radius: 0.0
            }
        );
    }

    #[test]
    fn result_is_independent_of_input_order_and_deterministic() {
        let pts = points(99, 500);
        let a = minimal_bounding_sphere(&pts);
        let b = minimal_bounding_sphere(&pts);
        assert_eq!(a, b);
        let mut rev = pts.clone();
        rev.reverse();
        let c = minimal_bounding_sphere(&rev);
        assert!((a.radius - c.radius).abs() <= 1e-6 * a.radius);
        assert_encloses(&a, &pts);
    }
}
