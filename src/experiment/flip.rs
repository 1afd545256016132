//! FLIP, the perceptual error of an image against a reference (Andersson, Nilsson,
//! Akenine-Möller, Oskarsson, Åström, Fairchild, "FLIP: A Difference Evaluator for Alternating
//! Images", HPG 2020), beside the RMS columns on every image a run compares.
//!
//! The error map is NVIDIA's reference C++ (LDR-FLIP, the `nv-flip` crate's bindings to it,
//! built with `cc`): for each pixel a value in \[0, 1\] from the colour difference after the
//! contrast sensitivity filters and the feature (edge and point) difference, under a viewing
//! condition of [`PIXELS_PER_DEGREE`] pixels per degree of visual angle (the reference's
//! default, 67: a 0.7 m distance from a 24-inch 4K monitor). The images are the 8-bit values
//! the run's PNGs hold, read as sRGB as the reference reads LDR images; a grey image is fed as
//! equal red, green and blue.
//!
//! Pooling ([`FlipMap::pool`]) follows the reference's `pooling` class (`pooling.h`), in its
//! f32 arithmetic: the mean of the map, and its weighted median (the smallest error value `e`
//! at which the running sum of the sorted values passes half the total: half of the map's total
//! error lies at or below `e`; the FLIP tool's "Weighted median"). Deviation from the reference
//! tool: the pool is taken over the pixels a run's RMS is taken over (the pixels that show
//! values, a mask) rather than every pixel; the map itself is computed over the whole image, as
//! the filters need each pixel's neighbourhood. With every pixel in the mask the pool is the
//! tool's to its printed digits (tests/flip.rs, on the pair the `nv-flip` crate tests against
//! the tool's output).

use crate::render::image::{GrayImage, Image};
use std::path::Path;

/// The viewing condition: pixels per degree of visual angle (the reference's default, 67).
pub const PIXELS_PER_DEGREE: f32 = 67.0;

/// A FLIP error map: one value in \[0, 1\] per pixel, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    pub width: u32,
    pub height: u32,
    pub values: Vec<f32>,
}

/// A pooled FLIP error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlipStats {
    /// The mean over the pooled pixels.
    pub mean: f64,
    /// The weighted median (see the module's doc).
    pub weighted_median: f64,
}

/// The 8-bit RGB bytes FLIP reads of `img`: each channel as its PNG writes it
/// ([`GrayImage::to_u8`]), a grey channel repeated three times.
///
/// # Panics
/// If the image has neither one nor three channels.
pub fn rgb8_of(img: &Image) -> Vec<u8> {
    assert!(
        img.channels == 1 || img.channels == 3,
        "FLIP reads images of 1 or 3 channels, not {}",
        img.channels
    );
    let q: Vec<u8> = img.data.iter().map(|&v| GrayImage::to_u8(v)).collect();
    if img.channels == 3 {
        return q;
    }
    q.iter().flat_map(|&v| [v, v, v]).collect()
}

/// The FLIP map of `test` against `reference` (8-bit sRGB, `width` × `height` × 3 bytes each).
///
/// # Panics
/// If a buffer's length is not `width · height · 3`, or the image is empty.
pub fn flip_rgb8(width: u32, height: u32, reference: &[u8], test: &[u8], ppd: f32) -> FlipMap {
    let n = width as usize * height as usize * 3;
    assert!(n > 0, "FLIP of an empty image");
    assert_eq!(reference.len(), n, "FLIP: the reference's size");
    assert_eq!(test.len(), n, "FLIP: the test image's size");
    let r = nv_flip::FlipImageRgb8::with_data(width, height, reference);
    let t = nv_flip::FlipImageRgb8::with_data(width, height, test);
    let map = nv_flip::flip(r, t, ppd);
    FlipMap {
        width,
        height,
        values: map.to_vec(),
    }
}

/// The FLIP map of `test` against `reference` at [`PIXELS_PER_DEGREE`].
///
/// # Panics
/// If their sizes or channel counts differ.
pub fn flip(reference: &Image, test: &Image) -> FlipMap {
    assert_eq!(
        (reference.width, reference.height, reference.channels),
        (test.width, test.height, test.channels),
        "FLIP compares images of one size"
    );
    flip_rgb8(
        reference.width,
        reference.height,
        &rgb8_of(reference),
        &rgb8_of(test),
        PIXELS_PER_DEGREE,
    )
}

/// [`FlipStats`] of `values` in row-major order (none when there is none), as the
/// reference's `pooling` takes them, in its f32 arithmetic: the mean the running f32 sum over
/// the count; the weighted median `getPercentile(0.5, true)`, the first of the sorted values at
/// which their running f32 sum passes half the total (0 where none does: every value 0).
pub fn pool_values(mut values: Vec<f32>) -> Option<FlipStats> {
    if values.is_empty() {
        return None;
    }
    let total: f32 = values.iter().fold(0.0f32, |s, &v| s + v);
    let mean = total / values.len() as f32;
    values.sort_by(f32::total_cmp);
    let mut running = 0.0f32;
    let mut weighted_median = 0.0f32;
    for &v in &values {
        running += v;
        if running > 0.5 * total {
            weighted_median = v;
            break;
        }
    }
    Some(FlipStats {
        mean: mean as f64,
        weighted_median: weighted_median as f64,
    })
}

impl FlipMap {
    /// The pooled error over the pixels of `mask` (every pixel without one); none when the
    /// mask selects no pixel.
    ///
    /// # Panics
    /// If the mask's length is not the pixel count.
    pub fn pool(&self, mask: Option<&[bool]>) -> Option<FlipStats> {
        if let Some(m) = mask {
            assert_eq!(m.len(), self.values.len(), "FLIP pool: the mask's length");
        }
        let values: Vec<f32> = (self.values.iter().enumerate())
            .filter(|&(i, _)| mask.is_none_or(|m| m[i]))
            .map(|(_, &v)| v)
            .collect();
        pool_values(values)
    }

    /// The map in the reference's magma colouring (the value × 255, rounded, indexes its
    /// 256-entry table), 8-bit RGB, row-major.
    pub fn magma_rgb8(&self) -> Vec<u8> {
        let map = nv_flip::FlipImageFloat::with_data(self.width, self.height, &self.values);
        map.apply_color_lut(&nv_flip::magma_lut()).to_vec()
    }

    /// Writes the magma-coloured map as a PNG, atomically: indexed (the table's colours the
    /// map uses as its palette, a third of the RGB file's bytes), the same pixels as
    /// [`FlipMap::magma_rgb8`] when read back.
    pub fn save_magma_png(&self, path: &Path) -> std::io::Result<()> {
        let bytes = indexed_png(self.width, self.height, &self.magma_rgb8())
            .expect("the magma table has 256 colours");
        crate::io::write_atomic(path, &bytes)
    }
}

/// 8-bit RGB pixels (row-major) as an indexed PNG whose palette holds their colours in order of
/// first use; `None` where they have more than 256 colours.
pub fn indexed_png(width: u32, height: u32, rgb: &[u8]) -> Option<Vec<u8>> {
    let mut palette: Vec<[u8; 3]> = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut pixels = Vec::with_capacity(rgb.len() / 3);
    for px in rgb.chunks_exact(3) {
        let c = [px[0], px[1], px[2]];
        let i = *index.entry(c).or_insert_with(|| {
            palette.push(c);
            palette.len() - 1
        });
        pixels.push(u8::try_from(i).ok()?);
    }
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, width, height);
    enc.set_color(png::ColorType::Indexed);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_palette(palette.concat());
    enc.set_compression(png::Compression::High);
    let mut writer = enc.write_header().ok()?;
    writer.write_image_data(&pixels).ok()?;
    writer.finish().ok()?;
    Some(out)
}

/// The pooled FLIP of `test` against `reference` over `mask` (the pixels that show values),
/// with its map: `None` where either image is missing or the mask selects nothing.
pub fn compare(
    reference: Option<&Image>,
    test: Option<&Image>,
    mask: Option<&[bool]>,
) -> Option<(FlipStats, FlipMap)> {
    let map = flip(reference?, test?);
    Some((map.pool(mask)?, map))
}

/// The viewing assumption and pooling of the FLIP columns, as `run.json` states them.
pub fn metadata() -> serde_json::Value {
    serde_json::json!({
        "pixels_per_degree": PIXELS_PER_DEGREE,
        "implementation": "LDR-FLIP, NVIDIA's reference C++ through the nv-flip 0.1.2 crate",
        "input": "the 8-bit PNG values read as sRGB; grey images as equal red, green and blue",
        "pooling": "mean and weighted median over the pixels that show values (the pixels \
                    of the image RMS); the map over the whole image",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gray(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> Image {
        let data = (0..h).flat_map(|y| (0..w).map(move |x| (x, y)));
        Image {
            width: w,
            height: h,
            channels: 1,
            data: data.map(|(x, y)| f(x, y)).collect(),
        }
    }

    #[test]
    fn identical_images_give_zero() {
        let a = gray(32, 24, |x, y| ((x * 7 + y * 3) % 17) as f32 / 16.0);
        let map = flip(&a, &a);
        assert!(map.values.iter().all(|&v| v == 0.0));
        let s = map.pool(None).unwrap();
        assert_eq!((s.mean, s.weighted_median), (0.0, 0.0));
    }

    #[test]
    fn grey_is_equal_rgb() {
        let a = gray(16, 16, |x, _| x as f32 / 15.0);
        let b = gray(16, 16, |_, y| y as f32 / 15.0);
        let rgb = |g: &Image| Image {
            channels: 3,
            data: g.data.iter().flat_map(|&v| [v, v, v]).collect(),
            ..g.clone()
        };
        assert_eq!(flip(&a, &b), flip(&rgb(&a), &rgb(&b)));
        assert!(flip(&a, &b).pool(None).unwrap().mean > 0.0);
    }

    #[test]
    fn pooling_closed_forms() {
        // Mean 0.25; sorted 0, 0, 0.25, 0.75: the running sums 0, 0, 0.25, 1 pass half the
        // total (0.5) at 0.75.
        let s = pool_values(vec![0.75, 0.0, 0.25, 0.0]).unwrap();
        assert_eq!((s.mean, s.weighted_median), (0.25, 0.75));
        assert_eq!(pool_values(Vec::new()), None);
        let m = FlipMap {
            width: 2,
            height: 2,
            values: vec![0.75, 0.0, 0.25, 0.0],
        };
        let s = m.pool(Some(&[false, true, true, true])).unwrap();
        assert!((s.mean - 0.25 / 3.0).abs() < 1e-7);
        assert_eq!(s.weighted_median, 0.25);
        assert_eq!(m.pool(Some(&[false; 4])), None);
    }

    #[test]
    fn magma_ends() {
        let m = FlipMap {
            width: 2,
            height: 1,
            values: vec![0.0, 1.0],
        };
        let c = m.magma_rgb8();
        // Magma runs from near black to a pale yellow.
        assert!(c[..3].iter().all(|&v| v < 10));
        assert!(c[3] > 240 && c[4] > 240 && c[5] > 150);
    }
}
