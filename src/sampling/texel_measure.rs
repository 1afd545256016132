//! Exact measures of the hemisphere regions that layout cells cover: solid angle and projected
//! solid angle (∫ cos θ dω) in closed form, all in f64.
//!
//! Malley's projection lifts a disk region R to the hemisphere with dω = dA / cos θ and
//! cos θ = √(1 − x² − y²), so the solid angle of the lift is ∫∫_R dA / √(1 − x² − y²) and its
//! projected solid angle is the disk area of R.

use std::f64::consts::FRAC_PI_2;

/// asin(y / c) with the ratio clamped to [−1, 1] (c = 0 gives ±π/2, or 0 for y = 0).
#[inline]
fn asin_ratio(y: f64, c: f64) -> f64 {
    if c > 0.0 {
        (y / c).clamp(-1.0, 1.0).asin()
    } else {
        FRAC_PI_2 * y.signum() * (y != 0.0) as i32 as f64
    }
}

/// G(x, y) with ∂²G/∂x∂y = 1/√(1 − x² − y²) on the closed unit disk:
/// G = x asin(y/√(1−x²)) + y asin(x/√(1−y²)) − atan(xy/√(1−x²−y²)).
/// (Inner integral ∫ dy/√(c² − y²) = asin(y/c); integrating by parts in x and using
/// ∫ dx/((1 − x²)√(b² − x²)) = atan(x√(1 − b²)/√(b² − x²))/√(1 − b²) gives the rest.)
#[inline]
fn malley_primitive(x: f64, y: f64) -> f64 {
    let cx = (1.0 - x * x).max(0.0).sqrt();
    let cy = (1.0 - y * y).max(0.0).sqrt();
    let w = (1.0 - x * x - y * y).max(0.0).sqrt();
    x * asin_ratio(y, cx) + y * asin_ratio(x, cy) - (x * y).atan2(w)
}

/// Where the limit `y` of a column at `x` stands against the disk edge ±√(1 − x²).
#[derive(Clone, Copy, PartialEq)]
enum Clip {
    Inside,
    Top,
    Bottom,
}

fn clip(y: f64, x: f64) -> Clip {
    let c = (1.0 - x * x).max(0.0).sqrt();
    if y >= c {
        Clip::Top
    } else if y <= -c {
        Clip::Bottom
    } else {
        Clip::Inside
    }
}

/// ∫_{x0}^{x1} [T(x, y1) − T(x, y0)] dx where T(x, y) is the column integral up to y clipped to
/// the disk. `prim(state, x, y)` is an antiderivative in x of T on a stretch where the clip
/// state of y is constant; the stretches are cut where y = ±√(1 − x²).
fn integrate_clipped(
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    prim: impl Fn(Clip, f64, f64) -> f64,
) -> f64 {
    let (lo, hi) = (x0.max(-1.0), x1.min(1.0));
    if lo >= hi || y0 >= y1 {
        return 0.0;
    }
    let mut cuts = [lo, hi, lo, lo, lo, lo];
    let mut n = 2;
    for y in [y0, y1] {
        if y.abs() < 1.0 {
            let e = (1.0 - y * y).sqrt();
            for x in [-e, e] {
                if x > lo && x < hi {
                    cuts[n] = x;
                    n += 1;
                }
            }
        }
    }
    let cuts = &mut cuts[..n];
    cuts.sort_by(f64::total_cmp);
    let mut sum = 0.0;
    for w in cuts.windows(2) {
        let (p, q) = (w[0], w[1]);
        if q <= p {
            continue;
        }
        let mid = 0.5 * (p + q);
        for (y, sign) in [(y1, 1.0), (y0, -1.0)] {
            let s = clip(y, mid);
            sum += sign * (prim(s, q, y) - prim(s, p, y));
        }
    }
    sum
}

/// Solid angle of the Malley lift of [x0, x1] × [y0, y1] ∩ unit disk: exact (closed form on
/// each stretch between the points where the rectangle's edges cross the circle).
pub(crate) fn malley_rect_solid_angle(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    integrate_clipped(x0, x1, y0, y1, |s, x, y| match s {
        Clip::Inside => malley_primitive(x, y),
        Clip::Top => FRAC_PI_2 * x,
        Clip::Bottom => -FRAC_PI_2 * x,
    })
}

/// Area of [x0, x1] × [y0, y1] ∩ unit disk (the projected solid angle of its Malley lift): exact.
pub(crate) fn disk_rect_area(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    // ∫ √(1 − x²) dx = (x √(1 − x²) + asin x) / 2.
    let half_disk = |x: f64| 0.5 * (x * (1.0 - x * x).max(0.0).sqrt() + x.clamp(-1.0, 1.0).asin());
    integrate_clipped(x0, x1, y0, y1, |s, x, y| match s {
        Clip::Inside => y * x,
        Clip::Top => half_disk(x),
        Clip::Bottom => -half_disk(x),
    })
}

/// Length of [lo, hi] ∩ [−m, m] and its slope in m, at m.
#[inline]
fn clipped_len(lo: f64, hi: f64, m: f64) -> (f64, f64) {
    let len = hi.min(m) - lo.max(-m);
    if len <= 0.0 {
        return (0.0, 0.0);
    }
    let slope = (m < hi) as i32 as f64 + (-m > lo) as i32 as f64;
    (len, slope)
}

/// Solid angle of the concentric-map + Malley image of the square cell [a0, a1] × [b0, b1] ⊂
/// [−1, 1]²: exact.
///
/// The concentric map preserves fractional area (disk area = π/4 · square area) and sends the
/// square ring max(|a|, |b|) = m to the circle r = m, so the solid angle is
/// (π/4) ∫∫ da db / √(1 − max(|a|, |b|)²) = (π/4) ∫₀¹ A′(m) / √(1 − m²) dm with A(m) the area
/// of the cell inside [−m, m]². A is piecewise quadratic between the breakpoints |a0|, |a1|,
/// |b0|, |b1|; on each piece A′ = β + 2γm integrates to β [asin m] − 2γ [√(1 − m²)].
pub(crate) fn concentric_rect_solid_angle(a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    let mut bps = [0.0, 1.0, a0.abs(), a1.abs(), b0.abs(), b1.abs()];
    bps.sort_by(f64::total_cmp);
    let mut sum = 0.0;
    for w in bps.windows(2) {
        let (p, q) = (w[0].min(1.0), w[1].min(1.0));
        if q <= p {
            continue;
        }
        let mid = 0.5 * (p + q);
        let (la, qa) = clipped_len(a0, a1, mid);
        let (lb, qb) = clipped_len(b0, b1, mid);
        // la(m) = pa + qa m on the piece (and likewise for b).
        let (pa, pb) = (la - qa * mid, lb - qb * mid);
        let beta = qa * pb + qb * pa;
        let gamma = qa * qb;
        sum += beta * (q.asin() - p.asin())
            + 2.0 * gamma * ((1.0 - p * p).max(0.0).sqrt() - (1.0 - q * q).max(0.0).sqrt());
    }
    std::f64::consts::FRAC_PI_4 * sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{PI, TAU};

    /// Midpoint rule over an n × n grid of the cell, integrand f(x, y) (0 outside the disk).
    fn midpoint(x0: f64, x1: f64, y0: f64, y1: f64, n: usize, f: impl Fn(f64, f64) -> f64) -> f64 {
        let (hx, hy) = ((x1 - x0) / n as f64, (y1 - y0) / n as f64);
        let mut s = 0.0;
        for i in 0..n {
            for j in 0..n {
                s += f(x0 + (i as f64 + 0.5) * hx, y0 + (j as f64 + 0.5) * hy);
            }
        }
        s * hx * hy
    }

    fn malley_density(x: f64, y: f64) -> f64 {
        let r2 = x * x + y * y;
        if r2 < 1.0 {
            1.0 / (1.0 - r2).sqrt()
        } else {
            0.0
        }
    }

    #[test]
    fn whole_disk_gives_hemisphere() {
        // The square [−1, 1]² lifts to the whole hemisphere: 2π sr, disk area π.
        assert!((malley_rect_solid_angle(-1.0, 1.0, -1.0, 1.0) - TAU).abs() < 1e-12);
        assert!((disk_rect_area(-1.0, 1.0, -1.0, 1.0) - PI).abs() < 1e-12);
        assert!((concentric_rect_solid_angle(-1.0, 1.0, -1.0, 1.0) - TAU).abs() < 1e-12);
        // A quadrant: a quarter of each.
        assert!((malley_rect_solid_angle(0.0, 1.0, 0.0, 1.0) - TAU / 4.0).abs() < 1e-12);
        assert!((disk_rect_area(-1.0, 0.0, 0.0, 1.0) - PI / 4.0).abs() < 1e-12);
        assert!((concentric_rect_solid_angle(0.0, 1.0, -1.0, 0.0) - TAU / 4.0).abs() < 1e-12);
    }

    #[test]
    fn closed_forms_match_quadrature() {
        // Cells inside, across and outside the rim; the midpoint rule with 400² points is good
        // to ~1e-5 inside, worse where a cell straddles the rim singularity, hence two tolerances.
        let cells = [
            (0.1, 0.3, -0.2, 0.4, 1e-6),
            (-0.5, 0.2, -0.6, -0.1, 1e-6),
            (0.6, 0.9, 0.3, 0.7, 2e-3),
            (0.9, 1.0, -0.1, 0.1, 2e-3),
            (-1.0, -0.95, -0.3, 0.0, 2e-3),
            (0.8, 1.0, 0.8, 1.0, 0.0),
        ];
        for (x0, x1, y0, y1, tol) in cells {
            let exact = malley_rect_solid_angle(x0, x1, y0, y1);
            let quad = midpoint(x0, x1, y0, y1, 400, malley_density);
            assert!(
                (exact - quad).abs() <= tol * quad.max(1e-3),
                "Ω {exact} vs {quad}"
            );
            let area = disk_rect_area(x0, x1, y0, y1);
            let quad = midpoint(x0, x1, y0, y1, 400, |x, y| {
                (x * x + y * y < 1.0) as i32 as f64
            });
            assert!(
                (area - quad).abs() < 2e-4 * (x1 - x0) * (y1 - y0) + 1e-12,
                "A {area} vs {quad}"
            );
        }
        // Concentric: integrand 1/√(1 − max(|a|,|b|)²) times π/4.
        for (a0, a1, b0, b1) in [
            (0.1, 0.3, -0.2, 0.4),
            (-0.9, -0.7, 0.5, 0.8),
            (-0.2, 0.2, -0.1, 0.3),
        ] {
            let exact = concentric_rect_solid_angle(a0, a1, b0, b1);
            let quad = std::f64::consts::FRAC_PI_4
                * midpoint(a0, a1, b0, b1, 400, |a, b| {
                    1.0 / (1.0 - a.abs().max(b.abs()).powi(2)).sqrt()
                });
            assert!(
                (exact - quad).abs() < 1e-5 * quad,
                "concentric {exact} vs {quad}"
            );
        }
    }

    #[test]
    fn cells_tile_additively() {
        // Splitting a cell in two must add up (checks the stretch bookkeeping at rim crossings).
        for (x0, xm, x1, y0, y1) in [(0.5, 0.75, 1.0, 0.2, 0.9), (-1.0, -0.6, 0.1, -1.0, -0.3)] {
            let whole = malley_rect_solid_angle(x0, x1, y0, y1);
            let parts =
                malley_rect_solid_angle(x0, xm, y0, y1) + malley_rect_solid_angle(xm, x1, y0, y1);
            assert!((whole - parts).abs() < 1e-12, "{whole} vs {parts}");
            let whole = disk_rect_area(x0, x1, y0, y1);
            let parts = disk_rect_area(x0, xm, y0, y1) + disk_rect_area(xm, x1, y0, y1);
            assert!((whole - parts).abs() < 1e-12);
        }
    }
}
