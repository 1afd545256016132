//! Gielis supershapes: the superformula applied in longitude and latitude.

use super::latlong;
use crate::geometry::{GeometryError, Mesh};
use std::cmp::Reverse;
use std::f64::consts::{FRAC_PI_2, PI};

/// One superformula (Gielis, "A generic geometric transformation that unifies a wide range of
/// natural and abstract shapes", American Journal of Botany 90(3), 2003):
/// `r(a) = (|cos(m·a/4)/a_|^n2 + |sin(m·a/4)/b|^n3)^(−1/n1)`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Superformula {
    /// Rotational symmetry (number of lobes over a full turn).
    pub m: f64,
    pub a: f64,
    pub b: f64,
    pub n1: f64,
    pub n2: f64,
    pub n3: f64,
}

impl Superformula {
    /// The radius at angle `angle` (radians).
    pub fn radius(&self, angle: f64) -> f64 {
        let t = self.m * angle / 4.0;
        let c = (t.cos() / self.a).abs().powf(self.n2);
        let s = (t.sin() / self.b).abs().powf(self.n3);
        (c + s).powf(-1.0 / self.n1)
    }
}

/// A 3D supershape: the spherical product of two superformulas,
/// `p(θ, φ) = (r₁(θ)·cos θ · r₂(φ)·cos φ,  r₂(φ)·sin φ,  r₁(θ)·sin θ · r₂(φ)·cos φ)`
/// for longitude θ ∈ [−π, π) and latitude φ ∈ [−π/2, π/2], with y up (Bourke's formulation with
/// its z axis mapped to our y).
///
/// The 2010 paper renders a 261,120-triangle supershape without giving its parameters;
/// deviation from the paper: the parameters here are our own choice.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Supershape {
    /// r₁, applied over longitude θ.
    pub longitude: Superformula,
    /// r₂, applied over latitude φ.
    pub latitude: Superformula,
}

impl Default for Supershape {
    /// A seven-lobed star in longitude (m = 7, n1 = 0.2, n2 = n3 = 1.7) and a four-lobed profile
    /// in latitude: a closed shape with deep concavities between the lobes.
    fn default() -> Self {
        Supershape {
            longitude: Superformula {
                m: 7.0,
                a: 1.0,
                b: 1.0,
                n1: 0.2,
                n2: 1.7,
                n3: 1.7,
            },
            latitude: Superformula {
                m: 4.0,
                a: 1.0,
                b: 1.0,
                n1: 0.5,
                n2: 1.0,
                n3: 2.5,
            },
        }
    }
}

impl Supershape {
    /// The surface point at longitude `theta`, latitude `phi`.
    pub fn point(&self, theta: f64, phi: f64) -> glam::DVec3 {
        let r1 = self.longitude.radius(theta);
        let r2 = self.latitude.radius(phi);
        glam::DVec3::new(
            r1 * theta.cos() * r2 * phi.cos(),
            r2 * phi.sin(),
            r1 * theta.sin() * r2 * phi.cos(),
        )
    }
}

/// The (slices, stacks) lat-long grid used for a requested triangle count.
///
/// A grid of `slices` u ≥ 3 longitudes and `stacks` v ≥ 2 latitude bands closed by two pole fans
/// has exactly `2·u·(v − 1)` triangles, so the achievable counts are the even numbers
/// `2·u·k` (k = v − 1 ≥ 1). This picks the smallest achievable count ≥ `target` among grids with
/// `k ≤ u ≤ 4k` (falling back to any grid for tiny targets), breaking ties by the aspect closest
/// to u = 2k (square-ish quads) and then by more slices. 261,120 (the 2010 paper's count) gives
/// the 512 × 256 grid.
pub fn supershape_grid(target: usize) -> (usize, usize) {
    let target = target.max(6);
    // Grids ranked by (in the aspect range, fewer triangles, closer to u = 2k, more slices).
    type Rank = (bool, Reverse<usize>, Reverse<usize>, usize);
    let mut best: Option<(Rank, usize)> = None; // (rank, k)
    let mut k = 1;
    loop {
        let u = target.div_ceil(2 * k).max(3);
        if u < k {
            break;
        }
        let rank = (
            u <= 4 * k,
            Reverse(2 * u * k),
            Reverse(u.abs_diff(2 * k)),
            u,
        );
        if best.is_none_or(|(b, _)| rank > b) {
            best = Some((rank, k));
        }
        k += 1;
    }
    let ((_, _, _, u), k) = best.expect("k = 1 always yields a grid");
    (u, k + 1)
}

/// A closed supershape mesh with about `target_triangles` triangles (exactly
/// `2·u·(v − 1)` for the grid chosen by [`supershape_grid`]; read the actual count from the
/// mesh). Outward oriented.
///
/// Errors when the parameters give a non-finite or non-positive radius somewhere on the grid.
pub fn supershape(params: &Supershape, target_triangles: usize) -> Result<Mesh, GeometryError> {
    let (slices, stacks) = supershape_grid(target_triangles);
    let name = format!("supershape({slices}x{stacks})");
    for (label, f, lo, hi) in [
        ("longitude", &params.longitude, -PI, PI),
        ("latitude", &params.latitude, -FRAC_PI_2, FRAC_PI_2),
    ] {
        let n = 4096;
        for i in 0..=n {
            let angle = lo + (hi - lo) * i as f64 / n as f64;
            let r = f.radius(angle);
            if !(r.is_finite() && r > 0.0) {
                return Err(GeometryError::invalid(
                    &name,
                    format!("{label} superformula {f:?} gives radius {r} at angle {angle}"),
                ));
            }
        }
    }
    latlong(&name, slices, stacks, |theta, phi| {
        params.point(theta, phi).as_vec3()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_counts_are_exact_when_achievable() {
        // 261,120 = 2·512·255: the paper's count is reproduced exactly.
        assert_eq!(supershape_grid(261_120), (512, 256));
        // 10,000 = 2·100·50.
        assert_eq!(supershape_grid(10_000), (100, 51));
        for target in [6, 7, 100, 999, 5_000, 12_345, 40_000] {
            let (u, v) = supershape_grid(target);
            let count = 2 * u * (v - 1);
            assert!(u >= 3 && v >= 2);
            assert!(count >= target, "{target}: {u}x{v} gives {count}");
            // Nearest achievable above: never more than one row or column of extra quads.
            assert!(
                count - target < 2 * u.max(v - 1) + 2,
                "{target}: {u}x{v} -> {count}"
            );
        }
    }

    #[test]
    fn superformula_closed_forms() {
        // m = 0: r = (1/a^n2)^(−1/n1) = a^(n2/n1); with a = 1 a unit circle.
        let circle = Superformula {
            m: 0.0,
            a: 1.0,
            b: 1.0,
            n1: 3.0,
            n2: 2.0,
            n3: 5.0,
        };
        for i in 0..10 {
            assert!((circle.radius(i as f64 * 0.6) - 1.0).abs() < 1e-12);
        }
        // m = 4, n1 = n2 = n3 = 2: the unit circle again (cos² + sin² = 1).
        let c2 = Superformula {
            m: 4.0,
            n1: 2.0,
            n2: 2.0,
            n3: 2.0,
            ..circle
        };
        assert!((c2.radius(0.37) - 1.0).abs() < 1e-12);
        // m = 4, n1 = n2 = n3 = 1: r = 1/(|cos| + |sin|), the diamond |x| + |y| = 1; at 45° its edge
        // midpoint (½, ½), r = (2·√½)^(−1) = 1/√2.
        let c1 = Superformula {
            m: 4.0,
            n1: 1.0,
            n2: 1.0,
            n3: 1.0,
            ..circle
        };
        assert!((c1.radius(std::f64::consts::FRAC_PI_4) - 0.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn default_supershape_is_closed_outward_with_exact_count() {
        let m = supershape(&Supershape::default(), 10_000).unwrap();
        assert_eq!(m.triangle_count(), 10_000);
        assert_eq!(m.dropped_degenerate, 0);
        // u(v−1) + 2 vertices.
        assert_eq!(m.vertex_count(), 100 * 50 + 2);
        assert!(m.is_closed() && m.is_consistently_oriented());
        assert!(m.signed_volume() > 0.0);
        // Not convex: some face plane has vertices clearly on its outer side (a convex closed
        // mesh has every vertex on or behind every face plane).
        let r = f64::from(m.bounding_sphere().radius);
        let concave = (0..m.triangle_count()).step_by(7).any(|i| {
            let n = m.face_normal_f64(i).normalize();
            let a = m.triangle(i)[0].as_dvec3();
            m.positions
                .iter()
                .any(|p| n.dot(p.as_dvec3() - a) > 1e-2 * r)
        });
        assert!(concave);
    }

    #[test]
    fn paper_size_supershape_has_exactly_261120_triangles() {
        let m = supershape(&Supershape::default(), 261_120).unwrap();
        assert_eq!(m.triangle_count(), 261_120);
        assert!(m.is_closed());
    }

    #[test]
    fn sphere_parameters_give_a_sphere() {
        // m = 0, a = 1: r₁ = r₂ = 1, so every vertex is on the unit sphere.
        let unit = Superformula {
            m: 0.0,
            a: 1.0,
            b: 1.0,
            n1: 1.0,
            n2: 1.0,
            n3: 1.0,
        };
        let m = supershape(
            &Supershape {
                longitude: unit,
                latitude: unit,
            },
            2_000,
        )
        .unwrap();
        for p in &m.positions {
            assert!((p.length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn invalid_parameters_are_an_error() {
        let mut p = Supershape::default();
        p.longitude.n1 = 0.0; // r = x^(−∞)
        p.longitude.n2 = -1.0; // |cos|^−1 blows up at cos = 0
        let e = supershape(&p, 1000).unwrap_err().to_string();
        assert!(e.contains("supershape") && e.contains("longitude"), "{e}");
    }
}
