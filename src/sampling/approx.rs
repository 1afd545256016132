//! Cheap replacements for libm calls on the hot path of the nearest-point queries, each with a
//! stated error bound that the exactness arguments account for (the x86-64 baseline has no
//! rounding instruction, so `f64::floor` and `atan2` are library calls).

use std::f64::consts::{FRAC_PI_2, PI};

/// Upper bound (radians) on |[`atan2_approx`] − atan2| over all inputs; measured at about 1e-5
/// by a test over 4·10⁶ angles, which asserts this bound.
pub(crate) const ATAN2_MAX_ERROR: f64 = 2e-5;

/// atan2(y, x) in (−π, π] to within [`ATAN2_MAX_ERROR`]: an odd degree-11 polynomial for atan
/// on [0, 1] (Abramowitz–Stegun style minimax coefficients) with octant reduction.
#[inline]
pub(crate) fn atan2_approx(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ax > ay { (ay, ax) } else { (ax, ay) };
    if hi == 0.0 {
        return 0.0;
    }
    let a = lo / hi;
    let s = a * a;
    let mut r = (((((-0.011_721_20 * s + 0.052_653_32) * s - 0.116_432_87) * s + 0.193_543_46)
        * s
        - 0.332_623_47)
        * s
        + 0.999_977_26)
        * a;
    if ay > ax {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 {
        -r
    } else {
        r
    }
}

/// Upper bound (radians) on |[`atan_unit_f32`] − atan| for |t| ≤ 1, including f32 rounding;
/// a test over 2·10⁶ arguments measures about 1.3e-7 and asserts this bound.
pub(crate) const ATAN_F32_MAX_ERROR: f32 = 3e-7;

/// atan(t) for |t| ≤ 1 in f32 to within [`ATAN_F32_MAX_ERROR`]: t + t³ P(t²) with the
/// degree-7 minimax P of the ARM optimized-routines `atanf` (coefficients rounded to f32).
#[inline]
pub(crate) fn atan_unit_f32(t: f32) -> f32 {
    // Estrin's scheme: a dependency chain of five multiply–adds instead of Horner's eight.
    let c = ATAN_F32_COEFFS;
    let z = t * t;
    let z2 = z * z;
    let z4 = z2 * z2;
    let p01 = c[0] + z * c[1];
    let p23 = c[2] + z * c[3];
    let p45 = c[4] + z * c[5];
    let p67 = c[6] + z * c[7];
    let p = (p01 + z2 * p23) + z4 * (p45 + z2 * p67);
    t + t * z * p
}

/// The coefficients of [`atan_unit_f32`]'s P, lowest degree first (also evaluated eight lanes
/// at a time by `field::lanes`, in the same order).
pub(crate) const ATAN_F32_COEFFS: [f32; 8] = [
    -3.333_332_5e-1,
    1.999_881_1e-1,
    -1.425_878_9e-1,
    1.087_526_4e-1,
    -8.035_188e-2,
    4.927_194e-2,
    -2.027_806_6e-2,
    3.936_620_4e-3,
];

/// ⌊x⌋ as an integer, for |x| < 2⁶²; exact (truncation, corrected for negatives).
#[inline]
pub(crate) fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t - 1
    } else {
        t
    }
}

/// ⌈x⌉ as an integer, for |x| < 2⁶²; exact.
#[inline]
pub(crate) fn ceil_i64(x: f64) -> i64 {
    -floor_i64(-x)
}

/// log₂ x for x > 0 to within 0.09: exponent bits plus the linear mantissa term.
#[inline]
pub(crate) fn log2_approx(x: f64) -> f64 {
    let bits = x.to_bits();
    let e = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let m = f64::from_bits((bits & ((1u64 << 52) - 1)) | (1023u64 << 52));
    e as f64 + (m - 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atan2_error_is_within_its_bound() {
        let n = 4_000_000;
        let mut worst = 0.0f64;
        for i in 0..n {
            let t = -PI + std::f64::consts::TAU * (i as f64 + 0.37) / n as f64;
            for r in [1.0, 1e-3, 7.5] {
                let (y, x) = (r * t.sin(), r * t.cos());
                worst = worst.max((atan2_approx(y, x) - y.atan2(x)).abs());
            }
        }
        assert!(worst < ATAN2_MAX_ERROR, "max error {worst}");
        assert_eq!(atan2_approx(0.0, 0.0), 0.0);
        assert!((atan2_approx(0.0, -1.0) - PI).abs() < 1e-12);
        assert!((atan2_approx(1.0, 0.0) - FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn atan_f32_error_is_within_its_bound() {
        // Every f32 argument in [0, 1] would be 10⁹; 2·10⁶ evenly spaced ones plus the ends.
        let n = 2_000_000;
        let mut worst = 0.0f64;
        for i in 0..=n {
            let t = i as f32 / n as f32;
            for t in [t, -t] {
                let e = (atan_unit_f32(t) as f64 - (t as f64).atan()).abs();
                worst = worst.max(e);
            }
        }
        assert!(worst < ATAN_F32_MAX_ERROR as f64, "max error {worst}");
        assert_eq!(atan_unit_f32(0.0), 0.0);
        // Odd: the polynomial is t·(1 + z P(z)).
        assert_eq!(atan_unit_f32(-0.3), -atan_unit_f32(0.3));
    }

    #[test]
    fn floor_and_ceil_are_exact() {
        for x in [
            -2.5,
            -2.0,
            -1e-300,
            -0.0,
            0.0,
            0.5,
            1.0,
            3.999_999_999,
            -7.000_000_001,
            1e15 + 0.5,
        ] {
            assert_eq!(floor_i64(x), x.floor() as i64, "floor {x}");
            assert_eq!(ceil_i64(x), x.ceil() as i64, "ceil {x}");
        }
    }

    #[test]
    fn log2_is_close() {
        for i in 1..10_000 {
            let x = i as f64 * 0.37;
            assert!((log2_approx(x) - x.log2()).abs() < 0.09, "{x}");
        }
    }
}
