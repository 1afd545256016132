//! The cosine-weighted occlusion of a spherical cap above a surface point, clipped by the
//! point's horizon: Kontkanen & Laine 2005, their AO integral (eq. 1) with the cap's visibility `V_cap`,
//!
//! `Ã = 1/π ∫_cap ⌊ω·n⌋ dω`,
//!
//! for a cap of solid angle Ω (half-angle α, `cos α = 1 − Ω/2π`) whose axis makes angle θ with
//! the unit normal n. The paper reads it from a 2D texture indexed by Ω and the angle to the
//! normal; deviation from the paper: we evaluate the closed form instead (no table error).
//!
//! The closed form is that of a uniformly bright sphere's irradiance (J. M. Snyder, "Area Light
//! Sources for Real-Time Graphics", Microsoft Research MSR-TR-96-11, 1996; as written in
//! S. Lagarde, C. de Rousiers, "Moving Frostbite to Physically Based Rendering", SIGGRAPH 2014
//! course notes, eq. 19), which depends on the sphere only through the cap it subtends
//! (`sin α = R/d`), so it holds for any cap with α ≤ π/2:
//!
//! - θ ≤ π/2 − α (the cap wholly above the horizon): `Ã = sin²α cos θ`;
//! - θ ≥ π/2 + α (wholly below): `Ã = 0`;
//! - otherwise, with `x = cot α`, `y = −x cot θ`:
//!   `π Ã = (cos θ · acos y − x sin θ √(1 − y²)) sin²α + atan(sin θ √(1 − y²) / x)`.
//!
//! A cap larger than a hemisphere (α > π/2) is the sphere less the cap of half-angle π − α about
//! the opposite axis, and `∫_sphere ⌊ω·n⌋ dω = π`, so `Ã(α, θ) = 1 − Ã(π − α, π − θ)`.

use std::f64::consts::PI;

/// `1/π ∫_cap ⌊ω·n⌋ dω` for a cap of solid angle `omega` (clamped to [0, 4π]) whose axis has
/// `cos_theta` (clamped to [−1, 1]) with the normal; in [0, 1].
pub fn cap_occlusion(omega: f64, cos_theta: f64) -> f64 {
    let omega = omega.clamp(0.0, 4.0 * PI);
    let cos_t = cos_theta.clamp(-1.0, 1.0);
    let cos_a = 1.0 - omega / (2.0 * PI);
    if cos_a < 0.0 {
        1.0 - small_cap(-cos_a, -cos_t)
    } else {
        small_cap(cos_a, cos_t)
    }
}

/// [`cap_occlusion`] for a cap no larger than a hemisphere (`cos_a ≥ 0`).
fn small_cap(cos_a: f64, cos_t: f64) -> f64 {
    let sin2_a = (1.0 - cos_a * cos_a).max(0.0);
    if cos_t * cos_t >= sin2_a {
        // Wholly above (cos θ ≥ sin α) or wholly below (cos θ ≤ −sin α) the horizon.
        return sin2_a * cos_t.max(0.0);
    }
    // Here cos²θ < sin²α ≤ 1, so sin θ > 0 and sin α > 0, and |y| < 1.
    let sin_t = (1.0 - cos_t * cos_t).sqrt();
    let x = cos_a / sin2_a.sqrt();
    let y = (-x * cos_t / sin_t).clamp(-1.0, 1.0);
    let s = sin_t * (1.0 - y * y).max(0.0).sqrt();
    let e = (cos_t * y.acos() - x * s) * sin2_a + s.atan2(x);
    (e / PI).clamp(0.0, 1.0)
}

/// The solid angle of a sphere of radius `radius` seen from distance `distance` from its centre:
/// `2π(1 − √(1 − R²/d²))`, and 4π from inside it.
pub fn sphere_solid_angle(radius: f64, distance: f64) -> f64 {
    if distance <= radius {
        return 4.0 * PI;
    }
    let s = radius / distance;
    // 1 − √(1 − s²) without cancellation for small s.
    2.0 * PI * s * s / (1.0 + (1.0 - s * s).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `1/π ∫_cap ⌊ω·n⌋ dω` by the midpoint rule on an `n × n` grid in the cap's own polar
    /// coordinates (ψ from the axis, φ about it), with its error bound.
    ///
    /// The integrand g(ψ, φ) = ⌊sin ψ cos φ sin θ + cos ψ cos θ⌋ · sin ψ is Lipschitz with
    /// |∂g/∂ψ| ≤ 2 and |∂g/∂φ| ≤ 1 (⌊·⌋ is 1-Lipschitz, each factor and derivative is at most
    /// 1 in magnitude). On a cell the midpoint rule errs by at most the cell's area times the
    /// mean distance to the midpoint along each axis (Δ/4) times that axis's constant, so
    /// over the whole domain (area α·2π) the error is at most α·2π·(2Δψ + Δφ)/4, then / π.
    fn numerical(alpha: f64, theta: f64, n: usize) -> (f64, f64) {
        let dpsi = alpha / n as f64;
        let dphi = 2.0 * PI / n as f64;
        let (st, ct) = theta.sin_cos();
        let mut sum = 0.0;
        for i in 0..n {
            let psi = (i as f64 + 0.5) * dpsi;
            let (sp, cp) = psi.sin_cos();
            let mut ring = 0.0;
            for j in 0..n {
                let phi = (j as f64 + 0.5) * dphi;
                ring += (sp * phi.cos() * st + cp * ct).max(0.0);
            }
            sum += ring * sp;
        }
        let value = sum * dpsi * dphi / PI;
        let bound = alpha * 2.0 * PI * (2.0 * dpsi + dphi) / 4.0 / PI;
        (value, bound)
    }

    #[test]
    fn closed_form_matches_numerical_integration_above_clipped_below_and_large_caps() {
        let alphas = [0.05, 0.3, 0.7, 1.2, PI / 2.0, 2.0, 2.8];
        let thetas = [0.0, 0.4, 0.9, 1.3, PI / 2.0, 1.9, 2.6, PI];
        for &alpha in &alphas {
            for &theta in &thetas {
                let omega = 2.0 * PI * (1.0 - alpha.cos());
                let ours = cap_occlusion(omega, theta.cos());
                let (num, bound) = numerical(alpha, theta, 1500);
                assert!(
                    (ours - num).abs() <= bound,
                    "α {alpha} θ {theta}: closed form {ours}, numerical {num} ± {bound}"
                );
            }
        }
    }

    #[test]
    fn limits_are_exact() {
        // The whole sphere occludes every direction of the hemisphere.
        assert!((cap_occlusion(4.0 * PI, 0.3) - 1.0).abs() < 1e-12);
        assert_eq!(cap_occlusion(0.0, 1.0), 0.0);
        // A hemisphere cap about the normal covers the whole hemisphere; about the tangent,
        // half of it: (1 + cos θ)/2.
        assert!((cap_occlusion(2.0 * PI, 1.0) - 1.0).abs() < 1e-12);
        assert!((cap_occlusion(2.0 * PI, 0.0) - 0.5).abs() < 1e-12);
        assert!((cap_occlusion(2.0 * PI, -0.6) - 0.2).abs() < 1e-12);
        // Wholly above the horizon: sin²α cos θ.
        let alpha: f64 = 0.4;
        let omega = 2.0 * PI * (1.0 - alpha.cos());
        let ct = 0.8;
        assert!((cap_occlusion(omega, ct) - alpha.sin().powi(2) * ct).abs() < 1e-12);
    }

    #[test]
    fn continuous_across_the_horizon_cases_and_monotone_in_both_arguments() {
        let alpha: f64 = 0.6;
        let omega = 2.0 * PI * (1.0 - alpha.cos());
        for edge in [PI / 2.0 - alpha, PI / 2.0 + alpha] {
            let a = cap_occlusion(omega, (edge - 1e-9).cos());
            let b = cap_occlusion(omega, (edge + 1e-9).cos());
            assert!((a - b).abs() < 1e-7, "jump at θ = {edge}: {a} vs {b}");
        }
        let mut last = -1.0;
        for k in 0..=200 {
            let v = cap_occlusion(omega, -1.0 + k as f64 / 100.0);
            assert!(v >= last - 1e-15);
            last = v;
        }
        let mut last = -1.0;
        for k in 0..=200 {
            let v = cap_occlusion(4.0 * PI * k as f64 / 200.0, 0.2);
            assert!(v >= last - 1e-15);
            last = v;
        }
    }

    #[test]
    fn sphere_solid_angle_is_the_cap_of_half_angle_asin_r_over_d() {
        for (r, d) in [(1.0f64, 1.5f64), (0.2, 7.0), (3.0, 3.01)] {
            let alpha = (r / d).asin();
            let cap = 2.0 * PI * (1.0 - alpha.cos());
            assert!((sphere_solid_angle(r, d) - cap).abs() < 1e-12);
        }
        assert_eq!(sphere_solid_angle(1.0, 0.5), 4.0 * PI);
    }
}
