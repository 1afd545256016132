//! Error metrics on the 0–255 scale of 8-bit images (the papers' scale). Every RMS of the
//! harness is computed here, and each name says whether the values are rounded first:
//! [`rms_u8`] rounds both sides to 8-bit levels (images as written to PNG), [`rms_unquantised`]
//! does not (per-point values). Over zero values an RMS is NaN, never 0: no point, no error
//! figure (`experiment check` fails a NaN).
//!
//! - Per receiver vertex ([`vertex_errors`]): the AO values themselves, unquantised, times 255.
//!   This is the error of the quantity the 2008 method computes (AO at the corner's vertices).
//! - Per image pixel ([`image_errors`]): the images as written to 8-bit PNG (each value rounded
//!   to 0..=255), over the pixels that show a receiver. This is the papers' RMS ("compared to the
//!   Reference image"): their images show vertex AO interpolated across triangles, so the
//!   per-pixel figure weighs vertices by their screen area and includes the 8-bit rounding.
//!
//! A kind with channels (several values per point, [`crate::render::estimator::Estimator::channels`])
//! is measured over every value: an RMS over points is over points × channels, an RMS over
//! pixels over the masked pixels × the image's channels (a mask has one flag per pixel, the
//! values `values.len() / mask.len()` per pixel), so one channel is the scalar figure, bit for
//! bit.

use crate::render::image::GrayImage;

/// RMS difference on the 0–255 scale after rounding both sides to 8-bit levels (images as
/// written to PNG: the papers' figure), over the pixels where `mask` is true (all when `None`),
/// every channel of a pixel (`a.len() / mask.len()` values per pixel). NaN when no value is
/// selected.
///
/// # Panics
/// If the lengths differ, or are not a multiple of the mask's.
pub fn rms_u8(a: &[f32], b: &[f32], mask: Option<&[bool]>) -> f64 {
    assert_eq!(a.len(), b.len(), "rms_u8: lengths differ");
    let c = per_pixel(a.len(), mask);
    let d = (0..a.len())
        .filter(|&i| mask.is_none_or(|m| m[i / c]))
        .map(|i| GrayImage::to_u8(a[i]) as f64 - GrayImage::to_u8(b[i]) as f64);
    rms_of(d)
}

/// Values per pixel of `n` values under `mask` (1 without a mask or a value).
///
/// # Panics
/// If `n` is not a multiple of the mask's length (values without pixels included).
fn per_pixel(n: usize, mask: Option<&[bool]>) -> usize {
    match mask {
        None => 1,
        Some(_) if n == 0 => 1,
        Some(m) => {
            assert!(
                !m.is_empty() && n.is_multiple_of(m.len()),
                "{n} values on {} pixels",
                m.len()
            );
            n / m.len()
        }
    }
}

/// RMS difference on the 0–255 scale of unrounded values (per-point AO), over the indices
/// `keep` selects. NaN when none is selected.
///
/// # Panics
/// If the lengths differ.
pub fn rms_unquantised_where(a: &[f32], b: &[f32], keep: impl Fn(usize) -> bool) -> f64 {
    assert_eq!(a.len(), b.len(), "rms_unquantised: lengths differ");
    let d = (0..a.len())
        .filter(|&i| keep(i))
        .map(|i| 255.0 * (a[i] as f64 - b[i] as f64));
    rms_of(d)
}

/// [`rms_unquantised_where`] over every value.
pub fn rms_unquantised(a: &[f32], b: &[f32]) -> f64 {
    rms_unquantised_where(a, b, |_| true)
}

/// Flicker between two frames: the RMS on the 0–255 scale, unquantised, over the pixels (or
/// points) where `keep` holds and their channels (`prev.len() / keep.len()` values each), of
/// the method's frame-to-frame change minus the converged reference's,
/// 255 · ((next − prev) − (truth_next − truth_prev)): motion itself (the reference's change)
/// costs nothing, only a change the reference does not make counts. A method that is the
/// reference plus a constant error flickers 0; one whose error steps by `d` on every kept
/// value between the frames flickers `255 · |d|`. NaN when `keep` selects nothing.
///
/// # Panics
/// If the four lengths differ, or are not a multiple of `keep`'s.
pub fn flicker(
    prev: &[f32],
    next: &[f32],
    truth_prev: &[f32],
    truth_next: &[f32],
    keep: &[bool],
) -> f64 {
    let n = prev.len();
    assert!(
        next.len() == n && truth_prev.len() == n && truth_next.len() == n,
        "flicker: lengths differ"
    );
    let c = per_pixel(n, Some(keep));
    let d = (0..n).filter(|&i| keep[i / c]).map(|i| {
        let change = next[i] as f64 - prev[i] as f64;
        let truth_change = truth_next[i] as f64 - truth_prev[i] as f64;
        255.0 * (change - truth_change)
    });
    rms_of(d)
}

/// The RMS of `d`; NaN when empty.
fn rms_of(d: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = d.fold((0.0f64, 0usize), |(s, n), x| (s + x * x, n + 1));
    if n == 0 {
        f64::NAN
    } else {
        (sum / n as f64).sqrt()
    }
}

/// Graininess of the error of image `a` against image `b` (row-major, `width` pixels a row,
/// `a.len() / mask.len()` channels a pixel): the RMS on the 0–255 scale, unquantised, of the
/// error's high-pass, the error at a pixel minus the mean error over its 3×3 neighbourhood
/// (channel by channel), over the pixels whose whole neighbourhood is in `mask`. An error that varies smoothly over the image (a bias, a soft blotch wider than
/// a few pixels) adds nothing; independent per-pixel noise of standard deviation σ gives
/// σ·√(8/9) ≈ 0.94σ; a ±d checkerboard gives 8d/9. This is the "grainy" look the 2010 paper
/// reports for intra-object AO with few maps, as a number. NaN when no pixel qualifies.
///
/// # Panics
/// If the lengths differ or are not a multiple of `width`.
pub fn grain(a: &[f32], b: &[f32], mask: &[bool], width: usize) -> f64 {
    assert!(
        a.len() == b.len() && width > 0 && mask.len().is_multiple_of(width),
        "grain: sizes differ"
    );
    let c = per_pixel(a.len(), Some(mask));
    assert_eq!(a.len(), c * mask.len(), "grain: sizes differ");
    let height = mask.len() / width;
    let e = |x: usize, y: usize, k: usize| {
        let i = (y * width + x) * c + k;
        a[i] as f64 - b[i] as f64
    };
    let mut d = Vec::new();
    for y in 1..height.saturating_sub(1) {
        for x in 1..width.saturating_sub(1) {
            let inside = (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| mask[yy * width + xx]));
            if !inside {
                continue;
            }
            for k in 0..c {
                let mean = (y - 1..=y + 1)
                    .flat_map(|yy| (x - 1..=x + 1).map(move |xx| (xx, yy)))
                    .map(|(xx, yy)| e(xx, yy, k))
                    .sum::<f64>()
                    / 9.0;
                d.push(255.0 * (e(x, y, k) - mean));
            }
        }
    }
    rms_of(d.into_iter())
}

/// RMS, largest error and the share of values off by more than one 8-bit level.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorStats {
    /// Root mean square difference (0–255).
    pub rms: f64,
    /// Largest absolute difference (0–255).
    pub max: f64,
    /// Share of values (vertices or pixels) whose difference exceeds 1/255.
    pub share_off_1: f64,
}

/// Errors between per-vertex AO vectors, unquantised, on the 0–255 scale.
///
/// # Panics
/// If the lengths differ.
pub fn vertex_errors(ao: &[f32], reference: &[f32]) -> ErrorStats {
    assert_eq!(ao.len(), reference.len(), "vertex_errors: lengths differ");
    let d = ao
        .iter()
        .zip(reference)
        .map(|(a, b)| 255.0 * (*a as f64 - *b as f64).abs());
    let (max, off) = d.fold((0.0f64, 0usize), |(m, n), e| {
        (m.max(e), n + (e > 1.0) as usize)
    });
    ErrorStats {
        rms: rms_unquantised(ao, reference),
        max,
        share_off_1: off as f64 / ao.len().max(1) as f64,
    }
}

/// Errors between two images as 8-bit values, over the pixels where `mask` is true (every
/// channel of a pixel; `share_off_1` is a share of those values).
///
/// # Panics
/// If the lengths differ, or are not a multiple of the mask's.
pub fn image_errors(a: &[f32], b: &[f32], mask: &[bool]) -> ErrorStats {
    assert!(a.len() == b.len(), "image_errors: sizes differ");
    let c = per_pixel(a.len(), Some(mask));
    let (mut max, mut off, mut n) = (0.0f64, 0usize, 0usize);
    for i in (0..a.len()).filter(|&i| mask[i / c]) {
        let e = (GrayImage::to_u8(a[i]) as f64 - GrayImage::to_u8(b[i]) as f64).abs();
        max = max.max(e);
        off += (e > 1.0) as usize;
        n += 1;
    }
    ErrorStats {
        rms: rms_u8(a, b, Some(mask)),
        max,
        share_off_1: off as f64 / n.max(1) as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flicker_closed_forms() {
        // The reference itself, and the reference plus a constant error: no flicker.
        let t0 = [0.2f32, 0.4, 0.6, 0.8];
        let t1 = [0.3f32, 0.1, 0.6, 0.9];
        let keep = [true; 4];
        assert_eq!(flicker(&t0, &t1, &t0, &t1, &keep), 0.0);
        let plus = |t: &[f32], e: f32| t.iter().map(|v| v + e).collect::<Vec<f32>>();
        let f = flicker(&plus(&t0, 0.05), &plus(&t1, 0.05), &t0, &t1, &keep);
        assert!(f.abs() < 1e-4, "{f}");
        // An error stepping by d = 0.02 on every value: 255 · 0.02 = 5.1.
        let f = flicker(&plus(&t0, 0.01), &plus(&t1, 0.03), &t0, &t1, &keep);
        assert!((f - 5.1).abs() < 1e-4, "{f}");
        // A step of 0.04 on one of two kept pixels (two channels each, both stepping):
        // sqrt((2 · 10.2²) / 4) = 10.2 / sqrt(2).
        let a0 = [0.5f32; 6];
        let mut a1 = a0;
        a1[0] += 0.04;
        a1[1] += 0.04;
        a1[4] += 0.9; // pixel 2: not kept
        let f = flicker(&a0, &a1, &a0, &a0, &[true, true, false]);
        assert!((f - 10.2 / 2f64.sqrt()).abs() < 1e-3, "{f}");
        assert!(flicker(&a0, &a1, &a0, &a0, &[false; 3]).is_nan());
    }

    #[test]
    fn rms_u8_closed_form_and_rounding() {
        // One pixel off by 1.0 (255 levels) out of four: sqrt(255²/4) = 127.5.
        let a = [0.0, 0.5, 1.0, 0.25];
        let b = [1.0, 0.5, 1.0, 0.25];
        assert!((rms_u8(&a, &b, None) - 127.5).abs() < 1e-9);
        assert_eq!(rms_u8(&a, &b, Some(&[false, true, true, true])), 0.0);
        // Within one 8-bit level: 0 rounded, 0.3 unrounded.
        let (x, y) = ([10.2f32 / 255.0], [10.4f32 / 255.0]);
        assert_eq!(rms_u8(&x, &y, None), 0.0);
        assert!((rms_unquantised(&x, &y) - 0.2).abs() < 1e-4);
    }

    #[test]
    fn an_rms_over_no_values_is_nan_not_zero() {
        assert!(rms_u8(&[0.5], &[0.0], Some(&[false])).is_nan());
        assert!(rms_unquantised(&[], &[]).is_nan());
        assert!(rms_unquantised_where(&[1.0, 0.0], &[0.0, 0.0], |i| i == 1) == 0.0);
        assert!((rms_unquantised_where(&[1.0, 0.0], &[0.0, 0.0], |i| i == 0) - 255.0).abs() < 1e-9);
    }

    #[test]
    fn grain_closed_forms() {
        let (w, h) = (6usize, 5usize);
        let b = vec![0.5f32; w * h];
        let all = vec![true; w * h];
        // A constant or linearly varying error is not grain.
        let bias: Vec<f32> = (0..w * h).map(|i| 0.5 + 0.01 * (i % w) as f32).collect();
        assert!(grain(&bias, &b, &all, w).abs() < 1e-4);
        // A ±d checkerboard: the 3×3 mean is ±d/9, the high-pass ±8d/9.
        let d = 4.0f32 / 255.0;
        let check: Vec<f32> = (0..w * h)
            .map(|i| 0.5 + if (i % w + i / w) % 2 == 0 { d } else { -d })
            .collect();
        assert!((grain(&check, &b, &all, w) - 32.0 / 9.0).abs() < 1e-4);
        // Only pixels whose whole neighbourhood is in the mask count; none here.
        let mut mask = all.clone();
        for y in 0..h {
            mask[y * w + 2] = false;
            mask[y * w + 3] = false;
        }
        assert!(grain(&check, &b, &mask, w).is_nan());
    }

    #[test]
    fn vertex_errors_closed_form() {
        // Differences 0, 2/255, 0.5/255, 1: on the 0–255 scale 0, 2, 0.5, 255.
        // RMS = sqrt((0 + 4 + 0.25 + 65025) / 4); max 255; two of four exceed 1.
        let a = [0.5, 2.0 / 255.0, 0.5 / 255.0, 1.0];
        let b = [0.5, 0.0, 0.0, 0.0];
        let e = vertex_errors(&a, &b);
        let rms = ((4.0 + 0.25 + 65025.0) / 4.0f64).sqrt();
        assert!((e.rms - rms).abs() < 1e-3, "{e:?}");
        assert!((e.max - 255.0).abs() < 1e-4);
        assert_eq!(e.share_off_1, 0.5);
    }

    #[test]
    fn image_errors_quantise_and_respect_the_mask() {
        // 8-bit levels: a = 10, 12, 0, 255; b = 10, 10, 1, 0. Masked out: the last pixel.
        // Differences 0, 2, 1 → RMS sqrt(5/3), max 2, one of three exceeds 1.
        let l = |v: f32| v / 255.0;
        let a = [l(10.0), l(12.0), l(0.0), 1.0];
        let b = [l(10.0), l(10.0), l(1.0), 0.0];
        let e = image_errors(&a, &b, &[true, true, true, false]);
        assert!((e.rms - (5.0f64 / 3.0).sqrt()).abs() < 1e-12, "{e:?}");
        assert_eq!(e.max, 2.0);
        assert!((e.share_off_1 - 1.0 / 3.0).abs() < 1e-12);
        // Values within the same 8-bit level do not count.
        let e = image_errors(&[l(3.0) + 1e-4], &[l(3.0)], &[true]);
        assert_eq!((e.rms, e.max, e.share_off_1), (0.0, 0.0, 0.0));
    }

    #[test]
    fn channels_are_measured_over_every_value_of_a_masked_pixel() {
        // Two pixels of three channels, the second masked out. Levels of a: 10, 12, 0 | 255 ×3;
        // of b: 10, 10, 1 | 0 ×3. Over the first pixel's three values: differences 0, 2, 1.
        let l = |v: f32| v / 255.0;
        let a = [l(10.0), l(12.0), l(0.0), 1.0, 1.0, 1.0];
        let b = [l(10.0), l(10.0), l(1.0), 0.0, 0.0, 0.0];
        let mask = [true, false];
        assert!((rms_u8(&a, &b, Some(&mask)) - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
        let e = image_errors(&a, &b, &mask);
        assert_eq!(e.max, 2.0);
        assert!((e.share_off_1 - 1.0 / 3.0).abs() < 1e-12);
        // Grain channel by channel: a checkerboard in one channel of three gives the
        // one-channel figure over a third of the values, ×√(1/3).
        let (w, h) = (6usize, 5usize);
        let d = 4.0f32 / 255.0;
        let check: Vec<f32> = (0..w * h)
            .map(|i| 0.5 + if (i % w + i / w) % 2 == 0 { d } else { -d })
            .collect();
        let flat = vec![0.5f32; w * h];
        let all = vec![true; w * h];
        let one = grain(&check, &flat, &all, w);
        let three: Vec<f32> = check.iter().flat_map(|&v| [0.5, v, 0.5]).collect();
        let g = grain(&three, &vec![0.5; 3 * w * h], &all, w);
        assert!((g - one / 3.0f64.sqrt()).abs() < 1e-9, "{g} vs {one}");
    }
}
