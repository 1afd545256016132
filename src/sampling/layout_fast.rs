//! Square coordinates of the polar and concentric layouts without libm (a polynomial atan in
//! f32), and the certificate that keeps [`super::HemisphereLayout::to_texel`] identical to the
//! libm inverse ([`super::warp::polar_hemisphere_to_square`],
//! [`super::warp::cosine_hemisphere_to_square`]).
//!
//! Both inverses need an angle: the concentric map the angle of the disk point within its wedge
//! (|x| > |y|: b = r·(4/π)·atan(y/|x|), a = ±r; otherwise a = r·(4/π)·atan(x/|y|), b = ±r), the
//! polar map θ = atan2(√((1 − z)(1 + z)), z) (= acos z for the given z, not for the true angle of
//! a direction whose length is off by rounding) and φ = atan2(y, x). The fast and the libm
//! coordinates differ by at most [`SQUARE_MAX_DEVIATION`]: [`ATAN_F32_MAX_ERROR`] plus f32
//! rounding on this side (about 4e-7 in square units), libm's atan2f/acosf (one ulp) and rounding
//! on the other (about 3e-7). A texel coordinate whose fractional part lies more than
//! `SQUARE_MAX_DEVIATION · res` from an integer therefore floors the same way through both; the
//! rest (a fraction of about 4·10⁻⁶·res of directions per axis) fall back to libm.

use super::approx::{atan_unit_f32, ATAN_F32_MAX_ERROR};
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, PI, TAU};

/// Bound on the difference between the fast and the libm square coordinates (either axis),
/// about five times the error budget of the module doc; a test measures it.
pub(crate) const SQUARE_MAX_DEVIATION: f32 = 4e-6;

/// 4/π, the concentric map's angle scale.
pub(crate) const FOUR_OVER_PI: f32 = 4.0 / PI;

// The bound must leave room for the polynomial's own error (in square units).
const _: () = assert!(ATAN_F32_MAX_ERROR * FOUR_OVER_PI < 0.25 * SQUARE_MAX_DEVIATION);

/// Concentric square coordinates of unit `d` with z ≥ 0; `None` below the horizon and on the
/// axis (where the libm path clamps or special-cases).
#[inline]
pub(crate) fn concentric_square(d: Vec3) -> Option<Vec2> {
    let (x, y) = (d.x, d.y);
    // The same expression as `Vec2::length`, so ±r is bit-identical to the libm path's.
    let r = (x * x + y * y).sqrt();
    if !(d.z >= 0.0 && r > 0.0) {
        return None;
    }
    // Branch-free wedge choice (random directions would mispredict a branch): the angle
    // coordinate from the smaller over the larger |component|, the other one ±r.
    let x_wedge = x.abs() > y.abs();
    let (num, den, along) = if x_wedge {
        (y, x.abs(), x)
    } else {
        (x, y.abs(), y)
    };
    let angular = r * FOUR_OVER_PI * atan_unit_f32(num / den);
    let radial = r.copysign(along);
    let (a, b) = if x_wedge {
        (radial, angular)
    } else {
        (angular, radial)
    };
    Some(Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0)))
}

/// atan2(y, x) in [−π, π] from [`atan_unit_f32`] by octant reduction; `None` for (±0, ±0),
/// whose libm result depends on the zeros' signs.
#[inline]
fn atan2_f32(y: f32, x: f32) -> Option<f32> {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ax > ay { (ay, ax) } else { (ax, ay) };
    if hi.is_nan() || hi == 0.0 {
        return None;
    }
    let mut a = atan_unit_f32(lo / hi);
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    Some(if y < 0.0 { -a } else { a })
}

/// Polar square coordinates of unit `d` with 0 ≤ z ≤ 1 off the axis; `None` otherwise.
#[inline]
pub(crate) fn polar_square(d: Vec3) -> Option<Vec2> {
    let z = d.z;
    if !(0.0..=1.0).contains(&z) {
        return None;
    }
    let s = ((1.0 - z) * (1.0 + z)).sqrt();
    let theta = if s < z {
        atan_unit_f32(s / z)
    } else {
        FRAC_PI_2 - atan_unit_f32(z / s)
    };
    let mut phi = atan2_f32(d.y, d.x)?;
    if phi < 0.0 {
        phi += TAU;
    }
    let u = phi / TAU;
    Some(Vec2::new(if u >= 1.0 { 0.0 } else { u }, theta / FRAC_PI_2))
}

/// The margin of [`certified_cell`] in texel units: [`SQUARE_MAX_DEVIATION`] plus the two f32
/// roundings of the products square · res.
#[inline]
pub(crate) fn certificate_margin(res: u32) -> f32 {
    (SQUARE_MAX_DEVIATION + 2.0 * f32::EPSILON) * res as f32
}

/// The cell (column, row) of texel coordinates `p` (square · res, clamped to the map as
/// [`super::HemisphereLayout::to_cell`] does) when each coordinate lies more than
/// `SQUARE_MAX_DEVIATION · res` from every interior cell boundary, so that the libm coordinates
/// give the same cell; `None` otherwise. The outer boundaries need no margin: the clamp puts
/// both sides of them in the same cell.
#[inline]
pub(crate) fn certified_cell(p: Vec2, res: u32) -> Option<(u32, u32)> {
    let m = certificate_margin(res);
    let axis = |v: f32| {
        if v.is_nan() {
            return None;
        }
        // Saturating cast: negative → 0.
        let c = (v as u32).min(res - 1);
        let below = c == 0 || v - c as f32 > m;
        let above = c + 1 == res || (c + 1) as f32 - v > m;
        (below && above).then_some(c)
    };
    Some((axis(p.x)?, axis(p.y)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rays::seeded_sphere_direction;
    use crate::sampling::warp::{square_to_concentric_disk, square_to_polar_hemisphere};
    use crate::sampling::{HemisphereLayout, LayoutKind};

    const KINDS: [LayoutKind; 2] = [LayoutKind::Polar, LayoutKind::Concentric];

    fn hemisphere(count: u64, seed: u64) -> impl Iterator<Item = Vec3> {
        (0..count).map(move |i| {
            let d = seeded_sphere_direction(i, seed);
            Vec3::new(d.x, d.y, d.z.abs())
        })
    }

    /// Directions through the layout's grid lines (square coordinate k/res, nudged by a few
    /// ulps either way), where a floor is most fragile.
    fn grid_line_directions(layout: &HemisphereLayout) -> Vec<Vec3> {
        let res = layout.res;
        let forward = |u: Vec2| match layout.kind {
            LayoutKind::Polar => square_to_polar_hemisphere(u),
            _ => crate::sampling::warp::disk_to_hemisphere(square_to_concentric_disk(u)),
        };
        let mut v = Vec::new();
        for k in 0..=res {
            for j in 0..64 {
                let t = (j as f32 + 0.37) / 64.0;
                for e in [-2e-7f32, 0.0, 2e-7] {
                    let g = (k as f32 / res as f32 + e).clamp(0.0, 1.0);
                    v.push(forward(Vec2::new(g, t)));
                    v.push(forward(Vec2::new(t, g)));
                }
            }
        }
        v
    }

    #[test]
    fn fast_cells_equal_libm_cells() {
        for res in [1u32, 2, 3, 5, 8, 32, 64, 256, 1024, 4096] {
            for kind in KINDS {
                let l = HemisphereLayout::new(kind, res);
                let last = res - 1;
                let reference = |d: Vec3| {
                    let p = l.to_square_libm(d) * res as f32;
                    ((p.y.max(0.0) as u32).min(last)) * res + (p.x.max(0.0) as u32).min(last)
                };
                let mut dirs: Vec<Vec3> = hemisphere(100_000, res as u64).collect();
                dirs.extend(grid_line_directions(&l));
                // Below the horizon, the axis, the φ seam.
                dirs.extend([Vec3::Z, Vec3::NEG_Z, Vec3::X, Vec3::NEG_X, Vec3::Y]);
                dirs.extend((0..1000).map(|i| Vec3::new(0.8, -1e-7 * i as f32, 0.6)));
                dirs.extend((0..1000).map(|i| Vec3::new(0.6, 0.8, -1e-3 * i as f32)));
                for d in dirs {
                    assert_eq!(
                        l.to_cell(d),
                        reference(d),
                        "{kind:?} {res}: {d} ({:?} vs {:?})",
                        l.to_square(d),
                        l.to_square_libm(d)
                    );
                }
            }
        }
    }

    #[test]
    fn fast_square_is_within_its_bound_and_rarely_falls_back() {
        for kind in KINDS {
            let l = HemisphereLayout::new(kind, 32);
            let (mut worst, mut fallbacks) = (0.0f32, 0usize);
            let n = 400_000;
            for d in hemisphere(n, 5) {
                let fast = match kind {
                    LayoutKind::Polar => polar_square(d),
                    _ => concentric_square(d),
                }
                .expect("unit directions above the horizon take the fast path");
                worst = worst.max((fast - l.to_square_libm(d)).abs().max_element());
                if certified_cell(fast * 32.0, 32).is_none() {
                    fallbacks += 1;
                }
            }
            // Half the bound: the other half is margin.
            assert!(worst < 0.5 * SQUARE_MAX_DEVIATION, "{kind:?}: {worst}");
            // Margins of 2·(4e-6 + 2.4e-7)·32 around 31 interior boundaries per axis: about
            // 0.05 % of directions.
            assert!(
                fallbacks < n as usize / 500,
                "{kind:?}: {fallbacks} fallbacks"
            );
        }
    }
}
