//! The two radial models of an AO-field texel and their least-squares fits (Kontkanen & Laine
//! 2005, storing Ω and Υ and preprocessing), in units of the occluder's bounding radius (`s = r / R`):
//!
//! - solid angle, `Ω̃(s) = 1 / (a s² + b s + c)` (the solid angle an object subtends falls
//!   roughly as 1/r²), fitted by minimising the paper's `ε_Ω = Σᵢ (Ωᵢ − Ω̃(sᵢ))²`;
//! - average occluded direction, `Υ̃(s) = normalize(C − s ω)` (towards a point C of the
//!   texel's own), fitted by minimising the paper's `ε_Υ = Σᵢ (1 − Υᵢ · Υ̃(sᵢ))²`.
//!
//! Both are non-linear in their parameters. The paper does not say how it minimised them;
//! ours (deviation from the paper: the method is ours) is Levenberg–Marquardt (Marquardt's
//! diagonal scaling, steps accepted only when they lower the cost), started from a linearised
//! fit: `Σᵢ (Ωᵢ − Ωᵢ² q(sᵢ))²` (the residual of 1/Ω weighted by Ω², linear in a, b, c) and, for
//! C, the point nearest to the sample lines `sᵢω + t Υᵢ` (with a 10⁻³ pull towards the centre,
//! which makes the radially symmetric case, all Υᵢ = −ω, well posed: C = 0). Each fit also has a
//! second start (`a s² + 1/2π`; C = 0) and keeps the better result.
//!
//! C is kept within [`C_MAX`] bounding radii of the centre (deviation from the paper, which
//! does not bound it): where a texel's sampled directions barely change with s, the unbounded
//! optimum runs C off towards infinity along them (we saw |C| ≈ 10¹¹), which no 16- or 8-bit
//! channel holds; within the bound the fit is the best C there.
//!
//! Outside an object's convex hull the object lies in a half-space, so Ω ≤ 2π: the solid-angle
//! fit keeps `q ≥ 1/2π` on the whole ray `s ≥ s₀` beyond the hull (a ≥ 0 and the minimum of
//! the parabola there at least 1/2π), so Ω̃ is finite, positive and at most 2π everywhere it is
//! evaluated, including past the last sample.

use glam::DVec3;
use std::f64::consts::PI;

/// `q(s) = a s² + b s + c`, the reciprocal of the modelled solid angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadratic {
    pub a: f64,
    pub b: f64,
    pub c: f64,
}

/// The farthest the direction model's point C may lie from the centre, in bounding radii.
pub const C_MAX: f64 = 2.0;

/// The least `q` the solid-angle fit allows beyond the hull: Ω ≤ 2π there.
pub const Q_FLOOR: f64 = 1.0 / (2.0 * PI);

impl Quadratic {
    /// `q(s)`.
    #[inline]
    pub fn at(&self, s: f64) -> f64 {
        (self.a * s + self.b) * s + self.c
    }

    /// `Ω̃(s) = 1/q(s)`, clamped to [0, 4π] (a q at or below 1/4π reads as the whole sphere).
    #[inline]
    pub fn omega(&self, s: f64) -> f64 {
        let q = self.at(s);
        if q > 1.0 / (4.0 * PI) {
            1.0 / q
        } else {
            4.0 * PI
        }
    }

    /// Whether `q ≥ 1/2π` (up to 1e-9 relative) on the whole ray `s ≥ s0`.
    pub fn feasible(&self, s0: f64) -> bool {
        let floor = Q_FLOOR * (1.0 - 1e-9);
        if !(self.a.is_finite() && self.b.is_finite() && self.c.is_finite()) || self.a < 0.0 {
            return false;
        }
        let least = if self.a > 0.0 {
            let vertex = -self.b / (2.0 * self.a);
            if vertex > s0 {
                self.c - self.b * self.b / (4.0 * self.a)
            } else {
                self.at(s0)
            }
        } else if self.b < 0.0 {
            return false;
        } else {
            self.at(s0)
        };
        least >= floor
    }
}

/// The paper's `ε_Ω`: `Σ (Ωᵢ − 1/q(sᵢ))²`.
pub fn solid_angle_cost(q: &Quadratic, s: &[f64], omega: &[f64]) -> f64 {
    s.iter()
        .zip(omega)
        .map(|(&s, &o)| (o - 1.0 / q.at(s)).powi(2))
        .sum()
}

/// The least-squares `Ω̃` through the samples `(sᵢ, Ωᵢ)`, feasible on `s ≥ s0` (see the module).
///
/// # Panics
/// If `s` and `omega` differ in length.
pub fn fit_solid_angle(s: &[f64], omega: &[f64], s0: f64) -> Quadratic {
    assert_eq!(s.len(), omega.len(), "one solid angle per radius");
    let last = s.len().saturating_sub(1);
    let far = match (s.get(last), omega.get(last)) {
        (Some(&sl), Some(&ol)) if ol > 0.0 && sl > 0.0 => 1.0 / (ol * sl * sl),
        _ => 1.0,
    };
    let mut starts = vec![Quadratic {
        a: far,
        b: 0.0,
        c: Q_FLOOR,
    }];
    // The linearised fit: rows Ωᵢ²·(sᵢ², sᵢ, 1), targets Ωᵢ.
    let mut m = [[0.0; 3]; 3];
    let mut rhs = [0.0; 3];
    for (&si, &oi) in s.iter().zip(omega) {
        let x = [oi * oi * si * si, oi * oi * si, oi * oi];
        for r in 0..3 {
            for c in 0..3 {
                m[r][c] += x[r] * x[c];
            }
            rhs[r] += x[r] * oi;
        }
    }
    if let Some(p) = solve3(m, rhs) {
        let q = Quadratic {
            a: p[0],
            b: p[1],
            c: p[2],
        };
        if q.feasible(s0) {
            starts.push(q);
        }
    }
    starts
        .into_iter()
        .map(|q| refine_solid_angle(q, s, omega, s0))
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .map(|(q, _)| q)
        .expect("at least one start")
}

/// Levenberg–Marquardt on `ε_Ω` from a feasible start; every accepted step stays feasible and
/// lowers the cost.
fn refine_solid_angle(start: Quadratic, s: &[f64], omega: &[f64], s0: f64) -> (Quadratic, f64) {
    let quadratic = |[a, b, c]: [f64; 3]| Quadratic { a, b, c };
    let (p, cost) = levenberg_marquardt(
        [start.a, start.b, start.c],
        solid_angle_cost(&start, s, omega),
        200,
        |p, rows| {
            let q = quadratic(p);
            for (&si, &oi) in s.iter().zip(omega) {
                let qi = q.at(si);
                rows(
                    [si * si / (qi * qi), si / (qi * qi), 1.0 / (qi * qi)],
                    oi - 1.0 / qi,
                );
            }
        },
        |p| {
            let q = quadratic(p);
            if q.feasible(s0) {
                solid_angle_cost(&q, s, omega)
            } else {
                f64::INFINITY
            }
        },
    );
    (quadratic(p), cost)
}

/// Levenberg–Marquardt on three parameters from `start` (of cost `cost`), at most `steps`
/// steps: `rows(p, add)` adds each residual's Jacobian row and residual at `p` (`add(J_i, r_i)`,
/// the normal equations `JᵀJ`, `Jᵀr` summed in that order); `cost_of` is a candidate's cost,
/// infinite where it is not allowed. Every accepted step lowers the cost; the loop ends where a
/// step gains nothing (relative 1e-15) or none is found within 12 dampings.
fn levenberg_marquardt(
    start: [f64; 3],
    cost: f64,
    steps: usize,
    rows: impl Fn([f64; 3], &mut dyn FnMut([f64; 3], f64)),
    cost_of: impl Fn([f64; 3]) -> f64,
) -> ([f64; 3], f64) {
    let (mut p, mut cost) = (start, cost);
    let mut lambda = 1e-3;
    for _ in 0..steps {
        let mut jtj = [[0.0; 3]; 3];
        let mut g = [0.0; 3];
        rows(p, &mut |d, r| {
            for a in 0..3 {
                for b in 0..3 {
                    jtj[a][b] += d[a] * d[b];
                }
                g[a] += d[a] * r;
            }
        });
        let mut accepted = false;
        for _ in 0..12 {
            let mut m = jtj;
            // Marquardt's scaling, with a floor so that a direction the cost does not yet
            // see (a zero diagonal) still gets a damped step.
            let floor = 1e-9 * (jtj[0][0] + jtj[1][1] + jtj[2][2]).max(1e-300);
            for (k, row) in m.iter_mut().enumerate() {
                row[k] += lambda * jtj[k][k].max(floor);
            }
            let Some(step) = solve3(m, g) else {
                lambda *= 10.0;
                continue;
            };
            let cand = [p[0] - step[0], p[1] - step[1], p[2] - step[2]];
            let c = cost_of(cand);
            if c < cost {
                let gain = cost - c;
                p = cand;
                cost = c;
                lambda = (lambda / 10.0).max(1e-12);
                accepted = gain > 1e-15 * cost.max(1e-300);
                break;
            }
            lambda *= 10.0;
        }
        if !accepted {
            break;
        }
    }
    (p, cost)
}

/// `Υ̃(s) = normalize(C − s ω)`, `−ω` where C − sω vanishes.
#[inline]
pub fn model_direction(c: DVec3, s: f64, w: DVec3) -> DVec3 {
    (c - s * w).try_normalize().unwrap_or(-w)
}

/// The paper's `ε_Υ`: `Σ (1 − Υᵢ · Υ̃(sᵢ))²`.
pub fn direction_cost(c: DVec3, s: &[f64], dirs: &[DVec3], w: DVec3) -> f64 {
    s.iter()
        .zip(dirs)
        .map(|(&si, &d)| (1.0 - d.dot(model_direction(c, si, w))).powi(2))
        .sum()
}

/// The least-squares C of `Υ̃` through the samples `(sᵢ, Υᵢ)` along the unit direction `w`
/// (none: C = 0, towards the centre).
///
/// # Panics
/// If `s` and `dirs` differ in length.
pub fn fit_centre(s: &[f64], dirs: &[DVec3], w: DVec3) -> DVec3 {
    assert_eq!(s.len(), dirs.len(), "one direction per radius");
    if s.is_empty() {
        return DVec3::ZERO;
    }
    // The point nearest to the lines sᵢω + t Υᵢ, pulled towards 0 by μ.
    let mu = 1e-3 * s.len() as f64;
    let mut m = [[0.0; 3]; 3];
    let mut rhs = [0.0; 3];
    for (&si, &d) in s.iter().zip(dirs) {
        let p = si * w;
        for r in 0..3 {
            for c in 0..3 {
                let proj = f64::from(r == c) - d[r] * d[c];
                m[r][c] += proj;
                rhs[r] += proj * p[c];
            }
        }
    }
    for (k, row) in m.iter_mut().enumerate() {
        row[k] += mu;
    }
    let start = solve3(m, rhs).map_or(DVec3::ZERO, DVec3::from_array);
    // Onto the ball of radius C_MAX (just inside it).
    let start = if start.length() > C_MAX {
        start * (C_MAX * (1.0 - 1e-9) / start.length())
    } else {
        start
    };
    // The nearest point may lie behind the samples (on the lines at negative t, every
    // direction reversed): the centre, the far field's answer, is the second start.
    let a = refine_centre(start, s, dirs, w);
    let b = refine_centre(DVec3::ZERO, s, dirs, w);
    if direction_cost(a, s, dirs, w) <= direction_cost(b, s, dirs, w) {
        a
    } else {
        b
    }
}

/// Levenberg–Marquardt on `ε_Υ` within |C| ≤ [`C_MAX`]; accepted steps lower the cost.
fn refine_centre(start: DVec3, s: &[f64], dirs: &[DVec3], w: DVec3) -> DVec3 {
    let valid = |c: DVec3| c.length() <= C_MAX && s.iter().all(|&si| (c - si * w).length() > 1e-9);
    let c = if valid(start) { start } else { DVec3::ZERO };
    let (p, _) = levenberg_marquardt(
        c.to_array(),
        direction_cost(c, s, dirs, w),
        100,
        |p, rows| {
            let c = DVec3::from_array(p);
            for (&si, &d) in s.iter().zip(dirs) {
                let v = c - si * w;
                let len = v.length();
                let u = v / len;
                // ∂e/∂C = −(d − (d·u) u) / |C − sω|.
                rows((-(d - d.dot(u) * u) / len).to_array(), 1.0 - d.dot(u));
            }
        },
        |p| {
            let cand = DVec3::from_array(p);
            if valid(cand) {
                direction_cost(cand, s, dirs, w)
            } else {
                f64::INFINITY
            }
        },
    );
    DVec3::from_array(p)
}

/// Solves the 3 × 3 system `m x = rhs` by Gaussian elimination with partial pivoting; none when
/// it is singular to working precision.
fn solve3(mut m: [[f64; 3]; 3], mut rhs: [f64; 3]) -> Option<[f64; 3]> {
    let scale = m
        .iter()
        .flatten()
        .fold(0.0f64, |a, &b| a.max(b.abs()))
        .max(1e-300);
    for col in 0..3 {
        let piv = (col..3).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if m[piv][col].abs() <= 1e-14 * scale || !m[piv][col].is_finite() {
            return None;
        }
        m.swap(col, piv);
        rhs.swap(col, piv);
        let pivot_row = m[col];
        for r in col + 1..3 {
            let f = m[r][col] / pivot_row[col];
            for (x, p) in m[r][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * p;
            }
            rhs[r] -= f * rhs[col];
        }
    }
    let mut x = [0.0; 3];
    for r in (0..3).rev() {
        let mut v = rhs[r];
        for k in r + 1..3 {
            v -= m[r][k] * x[k];
        }
        x[r] = v / m[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aofield::cap::sphere_solid_angle;

    fn radii(s0: f64, far: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| s0 * (far / s0).powf(i as f64 / (n - 1) as f64))
            .collect()
    }

    #[test]
    fn data_from_the_model_give_back_its_coefficients() {
        let truth = Quadratic {
            a: 0.31,
            b: -0.12,
            c: 0.27,
        };
        assert!(truth.feasible(1.0));
        let s = radii(1.0, 8.0, 10);
        let omega: Vec<f64> = s.iter().map(|&x| 1.0 / truth.at(x)).collect();
        let q = fit_solid_angle(&s, &omega, 1.0);
        for (got, want) in [(q.a, truth.a), (q.b, truth.b), (q.c, truth.c)] {
            assert!((got - want).abs() < 1e-7, "{q:?} vs {truth:?}");
        }
        let c = DVec3::new(0.2, -0.35, 0.1);
        let w = DVec3::new(1.0, 2.0, -0.5).normalize();
        let dirs: Vec<DVec3> = s.iter().map(|&x| model_direction(c, x, w)).collect();
        let got = fit_centre(&s, &dirs, w);
        assert!(got.distance(c) < 1e-6, "{got} vs {c}");
    }

    /// A sphere's exact Ω(s) is not a reciprocal quadratic, so the fit has a residual; the
    /// least-squares optimum is at least as good as any feasible quadratic, in particular the
    /// sphere's own far-field expansion q*(s) = (2s² − ½)/(2π) (from 1/Ω = (s² + s√(s² − 1))/2π
    /// for the unit sphere, √(s² − 1) = s − 1/(2s) − …), which is feasible for s ≥ 1.
    #[test]
    fn fit_of_a_sphere_is_no_worse_than_its_far_field_expansion() {
        for s0 in [1.05, 1.5] {
            let s = radii(s0, 10.0, 12);
            let omega: Vec<f64> = s.iter().map(|&x| sphere_solid_angle(1.0, x)).collect();
            let expansion = Quadratic {
                a: 1.0 / PI,
                b: 0.0,
                c: -1.0 / (4.0 * PI),
            };
            assert!(expansion.feasible(s0));
            let q = fit_solid_angle(&s, &omega, s0);
            assert!(q.feasible(s0));
            let ours = solid_angle_cost(&q, &s, &omega);
            let theirs = solid_angle_cost(&expansion, &s, &omega);
            assert!(ours <= theirs, "s0 {s0}: ours {ours} > expansion {theirs}");
            // Not exact: 1/Ω of a sphere is not a quadratic (its residual is that of the
            // far-field expansion's remainder, −1/(16π s²) − …, which no quadratic cancels).
            assert!(ours > 0.0);
        }
    }

    /// Directions that do not change with s: the unbounded optimum is C at infinity along them;
    /// the fit stays within C_MAX and still lowers the cost from its start.
    #[test]
    fn constant_directions_keep_c_within_its_bound() {
        let s = radii(1.0, 8.0, 10);
        let w = DVec3::new(0.0, 0.0, 1.0);
        let d = DVec3::new(0.6, 0.0, -0.8);
        let dirs = vec![d; s.len()];
        let c = fit_centre(&s, &dirs, w);
        assert!(c.length() <= C_MAX, "{c}");
        assert!(direction_cost(c, &s, &dirs, w) < direction_cost(DVec3::ZERO, &s, &dirs, w));
    }

    #[test]
    fn radially_symmetric_directions_give_the_centre() {
        let s = radii(1.0, 6.0, 8);
        let w = DVec3::new(0.0, 0.6, 0.8);
        let dirs = vec![-w; s.len()];
        let c = fit_centre(&s, &dirs, w);
        assert!(c.length() < 1e-9, "{c}");
        assert!(direction_cost(c, &s, &dirs, w) < 1e-20);
    }

    #[test]
    fn the_fit_stays_feasible_on_hostile_data() {
        let s = radii(0.5, 8.0, 6);
        // Zero, rising and over-2π solid angles: no reciprocal quadratic fits them.
        for omega in [
            vec![0.0; 6],
            vec![0.1, 0.2, 0.4, 0.8, 1.6, 3.2],
            vec![12.0, 0.0, 12.0, 0.0, 12.0, 0.0],
        ] {
            let q = fit_solid_angle(&s, &omega, 0.5);
            assert!(q.feasible(0.5), "{omega:?}: {q:?}");
            for &x in &s {
                let o = q.omega(x);
                assert!(o > 0.0 && o <= 2.0 * PI * (1.0 + 1e-6));
            }
        }
    }

    #[test]
    fn feasibility_is_the_minimum_over_the_ray() {
        // Vertex beyond s0: the parabola's minimum decides.
        let q = Quadratic {
            a: 1.0,
            b: -4.0,
            c: 4.0 + Q_FLOOR,
        };
        assert!(q.feasible(0.0));
        let low = Quadratic {
            c: 4.0 + 0.9 * Q_FLOOR,
            ..q
        };
        assert!(!low.feasible(0.0));
        // Vertex before s0: q(s0) decides.
        assert!(low.feasible(2.5));
        assert!(!Quadratic {
            a: -1e-6,
            b: 1.0,
            c: 1.0
        }
        .feasible(1.0));
    }
}
