//! Float images and their outputs: 8-bit PNG for looking, EXR where floats matter.

use std::path::Path;

/// A single-channel float image, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct GrayImage {
    pub width: u32,
    pub height: u32,
    pub data: Vec<f32>,
}

impl GrayImage {
    pub fn new(width: u32, height: u32, fill: f32) -> Self {
        GrayImage {
            width,
            height,
            data: vec![fill; (width * height) as usize],
        }
    }

    /// The 0–255 value of `v` as written to an 8-bit image (round to nearest, clamped).
    #[inline]
    pub fn to_u8(v: f32) -> u8 {
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    }

    /// PNG bytes (8-bit grey).
    pub fn png_bytes(&self) -> Vec<u8> {
        let buf: Vec<u8> = self.data.iter().map(|&v| Self::to_u8(v)).collect();
        let img = image::GrayImage::from_raw(self.width, self.height, buf)
            .expect("buffer matches dimensions");
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png)
            .expect("PNG encoding to memory cannot fail");
        out.into_inner()
    }

    /// Writes an 8-bit PNG atomically.
    pub fn save_png(&self, path: &Path) -> std::io::Result<()> {
        crate::io::write_atomic(path, &self.png_bytes())
    }

    /// Writes a 32-bit float single-channel EXR (channel "Y") atomically; the same image always
    /// gives the same bytes.
    pub fn save_exr(&self, path: &Path) -> std::io::Result<()> {
        use exr::prelude::*;
        let w = self.width as usize;
        let data = &self.data;
        let channel = SpecificChannels::build()
            .with_channel("Y")
            .with_pixel_fn(|pos: Vec2<usize>| (data[pos.y() * w + pos.x()],));
        let image = Image::from_channels((w, self.height as usize), channel);
        let mut cursor = std::io::Cursor::new(Vec::new());
        // One thread: the parallel writer stores the compressed blocks in the order they finish,
        // so the same image gave different bytes from run to run.
        image
            .write()
            .non_parallel()
            .to_buffered(&mut cursor)
            .map_err(|e| std::io::Error::other(e.to_string()))?;
        crate::io::write_atomic(path, &cursor.into_inner())
    }

    /// |a − b| × `gain`, the papers' exaggerated difference image (×5 in 2008 Figure 5).
    pub fn difference(&self, other: &GrayImage, gain: f32) -> GrayImage {
        assert_eq!((self.width, self.height), (other.width, other.height));
        GrayImage {
            width: self.width,
            height: self.height,
            data: self
                .data
                .iter()
                .zip(&other.data)
                .map(|(a, b)| ((a - b).abs() * gain).min(1.0))
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Results are committed: writing the same image again must give the same file, or every
    /// rerun would change the EXRs under `results/` without a pixel changing.
    #[test]
    fn exr_bytes_are_the_same_on_every_write() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = GrayImage::new(512, 384, 0.0);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = ((i as f32 * 0.618).sin() * 0.5 + 0.5) * (i % 7) as f32;
        }
        let bytes = |k: usize| {
            let p = dir.path().join(format!("{k}.exr"));
            img.save_exr(&p).unwrap();
            std::fs::read(p).unwrap()
        };
        let first = bytes(0);
        for k in 1..6 {
            assert!(bytes(k) == first, "write {k} differs from the first");
        }
    }

    #[test]
    fn png_and_exr_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = GrayImage::new(7, 5, 0.0);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = i as f32 / 34.0;
        }
        let p = dir.path().join("a.png");
        img.save_png(&p).unwrap();
        let back = image::open(&p).unwrap().to_luma8();
        assert_eq!(back.dimensions(), (7, 5));
        for (i, px) in back.pixels().enumerate() {
            assert_eq!(px.0[0], GrayImage::to_u8(img.data[i]));
        }
        let e = dir.path().join("a.exr");
        img.save_exr(&e).unwrap();
        let read = exr::prelude::read_first_flat_layer_from_file(&e).unwrap();
        let vals: Vec<f32> = read.layer_data.channel_data.list[0]
            .sample_data
            .values_as_f32()
            .collect();
        assert_eq!(vals, img.data);
    }
}
