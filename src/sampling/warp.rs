//! Square ↔ disk ↔ hemisphere warps, each with its exact inverse and its density side by side
//! (the pbrt-v4 / Mitsuba 3 habit). Squares are `[0, 1]²`; disks are the unit disk; hemisphere
//! directions are unit vectors with `z >= 0` in a local frame.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Shirley–Chiu concentric map, square `[0,1]²` → unit disk (Shirley, Chiu, "A Low Distortion
/// Map Between Disk and Square", JGT 1997). Area preserving up to a constant (π/4).
#[inline]
pub fn square_to_concentric_disk(u: Vec2) -> Vec2 {
    let a = 2.0 * u.x - 1.0;
    let b = 2.0 * u.y - 1.0;
    if a == 0.0 && b == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, FRAC_PI_2 - FRAC_PI_4 * (a / b))
    };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Exact inverse of [`square_to_concentric_disk`]: unit disk → square `[0,1]²`.
#[inline]
pub fn concentric_disk_to_square(p: Vec2) -> Vec2 {
    let r = p.length();
    if r == 0.0 {
        return Vec2::splat(0.5);
    }
    // φ in [-π/4, 7π/4): the four wedges of the concentric map.
    let mut phi = p.y.atan2(p.x);
    if phi < -FRAC_PI_4 {
        phi += 2.0 * PI;
    }
    let (a, b) = if phi < FRAC_PI_4 {
        (r, r * phi / FRAC_PI_4)
    } else if phi < 3.0 * FRAC_PI_4 {
        (r * (FRAC_PI_2 - phi) / FRAC_PI_4, r)
    } else if phi < 5.0 * FRAC_PI_4 {
        (-r, -r * (phi - PI) / FRAC_PI_4)
    } else {
        (-r * (3.0 * FRAC_PI_2 - phi) / FRAC_PI_4, -r)
    };
    Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0))
}

/// Malley's method: disk → hemisphere by vertical projection, z = sqrt(1 − x² − y²).
/// Uniform points on the disk become cosine-distributed directions.
#[inline]
pub fn disk_to_hemisphere(p: Vec2) -> Vec3 {
    let z = (1.0 - p.length_squared()).max(0.0).sqrt();
    Vec3::new(p.x, p.y, z)
}

/// Exact inverse of [`disk_to_hemisphere`]: drop z (directions below the horizon are first
/// clamped onto it, keeping their azimuth; straight down, which has no azimuth, goes to the
/// horizon point `(1, 0)`).
#[inline]
pub fn hemisphere_to_disk(d: Vec3) -> Vec2 {
    let p = Vec2::new(d.x, d.y);
    if d.z < 0.0 {
        p.try_normalize().unwrap_or(Vec2::X)
    } else {
        p
    }
}

/// Square → cosine-weighted hemisphere through the concentric map and Malley's method.
#[inline]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    disk_to_hemisphere(square_to_concentric_disk(u))
}

/// Exact inverse of [`square_to_cosine_hemisphere`].
#[inline]
pub fn cosine_hemisphere_to_square(d: Vec3) -> Vec2 {
    concentric_disk_to_square(hemisphere_to_disk(d))
}

/// Polar map, square → hemisphere uniform in the angles: θ = u.y · π/2 (from the pole),
/// φ = u.x · 2π.
#[inline]
pub fn square_to_polar_hemisphere(u: Vec2) -> Vec3 {
    let theta = u.y * FRAC_PI_2;
    let phi = u.x * 2.0 * PI;
    let (st, ct) = theta.sin_cos();
    Vec3::new(st * phi.cos(), st * phi.sin(), ct)
}

/// Exact inverse of [`square_to_polar_hemisphere`] (φ wrapped into [0, 2π)).
#[inline]
pub fn polar_hemisphere_to_square(d: Vec3) -> Vec2 {
    let theta = d.z.clamp(-1.0, 1.0).acos().min(FRAC_PI_2);
    Vec2::new(azimuth_fraction(d), theta / FRAC_PI_2)
}

/// φ / 2π of `d`'s azimuth, wrapped into [0, 1).
#[inline]
fn azimuth_fraction(d: Vec3) -> f32 {
    let mut phi = d.y.atan2(d.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let x = phi / (2.0 * PI);
    if x >= 1.0 {
        0.0
    } else {
        x
    }
}

/// Square → uniform sphere (Archimedes' hat-box: z uniform in [−1, 1], φ = 2π u.x).
#[inline]
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.y;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u.x).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Exact inverse of [`square_to_uniform_sphere`] (φ wrapped into [0, 2π)).
#[inline]
pub fn uniform_sphere_to_square(d: Vec3) -> Vec2 {
    Vec2::new(azimuth_fraction(d), (1.0 - d.z) * 0.5)
}

/// Square → uniform hemisphere `z >= 0` (z uniform in [0, 1], φ = 2π u.x).
#[inline]
pub fn square_to_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = 1.0 - u.y;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u.x).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Exact inverse of [`square_to_uniform_hemisphere`] (z < 0 clamped to the horizon).
#[inline]
pub fn uniform_hemisphere_to_square(d: Vec3) -> Vec2 {
    let u = uniform_sphere_to_square(d);
    Vec2::new(u.x, (1.0 - d.z.max(0.0)).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: u32) -> impl Iterator<Item = Vec2> {
        (0..n * n).map(move |i| {
            Vec2::new(
                ((i % n) as f32 + 0.5) / n as f32,
                ((i / n) as f32 + 0.5) / n as f32,
            )
        })
    }

    /// The mean of `f` over `grid(n)`.
    fn grid_mean(n: u32, f: impl Fn(Vec2) -> f64) -> f64 {
        grid(n).map(f).sum::<f64>() / (n * n) as f64
    }

    /// `back`, what `u` came back as through `via`, is within `tol` of it.
    fn round_trip(u: Vec2, via: String, back: Vec2, tol: f32) {
        assert!(
            (u - back).abs().max_element() < tol,
            "u {u} -> {via} -> u' {back}"
        );
    }

    #[test]
    fn concentric_round_trip_on_a_dense_grid() {
        for u in grid(257) {
            let p = square_to_concentric_disk(u);
            assert!(p.length() <= 1.0 + 1e-6);
            round_trip(u, format!("p {p}"), concentric_disk_to_square(p), 2e-6);
        }
    }

    #[test]
    fn cosine_hemisphere_round_trip_and_unit_length() {
        for u in grid(128) {
            let d = square_to_cosine_hemisphere(u);
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z >= 0.0);
            round_trip(u, format!("d {d}"), cosine_hemisphere_to_square(d), 1e-5);
        }
    }

    #[test]
    fn polar_round_trip() {
        for u in grid(128) {
            let d = square_to_polar_hemisphere(u);
            round_trip(u, format!("d {d}"), polar_hemisphere_to_square(d), 1e-5);
        }
    }

    #[test]
    fn concentric_is_area_preserving() {
        // The mean of r² over uniform square samples equals ∫ r² dA / π = 1/2 on the unit disk.
        let mean = grid_mean(512, |u| {
            square_to_concentric_disk(u).length_squared() as f64
        });
        assert!((mean - 0.5).abs() < 1e-4, "mean r² = {mean}");
    }

    #[test]
    fn cosine_hemisphere_integrates_cos_correctly() {
        // E[cos θ] under the cosine density is ∫ cos² θ dω / π = 2/3.
        let mean = grid_mean(512, |u| square_to_cosine_hemisphere(u).z as f64);
        assert!((mean - 2.0 / 3.0).abs() < 1e-4, "mean cos = {mean}");
    }

    #[test]
    fn below_horizon_directions_clamp_to_the_horizon() {
        // Keeps the azimuth of (3, 4, −1): (0.6, 0.8); straight down has none and goes to (1, 0).
        let p = hemisphere_to_disk(Vec3::new(3.0, 4.0, -1.0));
        assert!((p - Vec2::new(0.6, 0.8)).length() < 1e-6, "{p}");
        assert_eq!(hemisphere_to_disk(Vec3::NEG_Z), Vec2::X);
        assert_eq!(hemisphere_to_disk(Vec3::Z), Vec2::ZERO);
    }

    #[test]
    fn uniform_sphere_and_hemisphere_round_trip() {
        for u in grid(128) {
            let d = square_to_uniform_sphere(u);
            assert!((d.length() - 1.0).abs() < 1e-5);
            round_trip(u, format!("d {d}"), uniform_sphere_to_square(d), 1e-5);
            let h = square_to_uniform_hemisphere(u);
            assert!(h.z >= 0.0 && (h.length() - 1.0).abs() < 1e-5);
            round_trip(u, format!("h {h}"), uniform_hemisphere_to_square(h), 1e-5);
        }
    }

    #[test]
    fn uniform_sphere_moments() {
        // Under the uniform density E[z] = 0 and E[z²] = 1/3; hemisphere: E[z] = 1/2.
        let n = 256;
        let (mut m1, mut m2, mut h1) = (0.0f64, 0.0f64, 0.0f64);
        for u in grid(n) {
            let z = square_to_uniform_sphere(u).z as f64;
            m1 += z;
            m2 += z * z;
            h1 += square_to_uniform_hemisphere(u).z as f64;
        }
        let k = (n * n) as f64;
        assert!((m1 / k).abs() < 1e-5 && (m2 / k - 1.0 / 3.0).abs() < 1e-4);
        assert!((h1 / k - 0.5).abs() < 1e-5);
    }
}
