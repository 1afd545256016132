//! Float images and their outputs: 8-bit PNG for looking, EXR where floats matter.
//! [`GrayImage`] has one channel; [`Image`], what a render kind's values show as, has one
//! (grey) or three (red, green, blue), chosen by the kind ([`ImageChannels`]).

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
        png_bytes::<image::Luma<u8>>(self.width, self.height, &self.data)
    }

    /// Writes an 8-bit PNG atomically.
    pub fn save_png(&self, path: &Path) -> std::io::Result<()> {
        crate::io::write_atomic(path, &self.png_bytes())
    }

    /// Writes a 32-bit float single-channel EXR (channel "Y") atomically; the same image always
    /// gives the same bytes.
    pub fn save_exr(&self, path: &Path) -> std::io::Result<()> {
        use exr::prelude::{SpecificChannels, Vec2};
        let w = self.width as usize;
        let data = &self.data;
        let channel = SpecificChannels::build()
            .with_channel("Y")
            .with_pixel_fn(|pos: Vec2<usize>| (data[pos.y() * w + pos.x()],));
        let image = exr::prelude::Image::from_channels((w, self.height as usize), channel);
        save_exr(path, &image)
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

/// Which of a render kind's channels an image shows, and how: one as grey, three as red,
/// green and blue (indices into a point's values).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageChannels {
    Gray(usize),
    Rgb([usize; 3]),
}

impl ImageChannels {
    /// The image of `channels` values per point when the kind says nothing else: grey for one,
    /// RGB for three; none for another count (the kind must choose).
    pub fn default_for(channels: usize) -> Option<ImageChannels> {
        match channels {
            1 => Some(ImageChannels::Gray(0)),
            3 => Some(ImageChannels::Rgb([0, 1, 2])),
            _ => None,
        }
    }

    /// The value channels shown, in the image's channel order.
    pub fn shown(&self) -> &[usize] {
        match self {
            ImageChannels::Gray(c) => std::slice::from_ref(c),
            ImageChannels::Rgb(c) => c,
        }
    }
}

/// A float image of one (grey) or three (red, green, blue) channels, row-major, row 0 at the
/// top, a pixel's channels together: pixel `p`'s channel `c` at `p * channels + c`.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub channels: usize,
    pub data: Vec<f32>,
}

impl From<GrayImage> for Image {
    fn from(g: GrayImage) -> Image {
        Image {
            width: g.width,
            height: g.height,
            channels: 1,
            data: g.data,
        }
    }
}

impl Image {
    /// The image of one channel per pixel from `planes` (one [`GrayImage`] per channel, of one
    /// size), interleaved.
    ///
    /// # Panics
    /// If there are neither one nor three planes, or their sizes differ.
    pub fn interleave(planes: Vec<GrayImage>) -> Image {
        assert!(
            planes.len() == 1 || planes.len() == 3,
            "an image has 1 or 3 channels, not {}",
            planes.len()
        );
        let (w, h) = (planes[0].width, planes[0].height);
        assert!(planes.iter().all(|p| (p.width, p.height) == (w, h)));
        if planes.len() == 1 {
            return planes.into_iter().next().expect("one plane").into();
        }
        let n = (w * h) as usize;
        let data = (0..n)
            .flat_map(|i| planes.iter().map(move |p| p.data[i]))
            .collect();
        Image {
            width: w,
            height: h,
            channels: planes.len(),
            data,
        }
    }

    /// Channel `c` as a [`GrayImage`].
    pub fn plane(&self, c: usize) -> GrayImage {
        GrayImage {
            width: self.width,
            height: self.height,
            data: self
                .data
                .iter()
                .skip(c)
                .step_by(self.channels)
                .copied()
                .collect(),
        }
    }

    /// PNG bytes: 8-bit grey for one channel (the bytes of [`GrayImage::png_bytes`]), 8-bit RGB
    /// for three.
    pub fn png_bytes(&self) -> Vec<u8> {
        if self.channels == 1 {
            return self.plane(0).png_bytes();
        }
        png_bytes::<image::Rgb<u8>>(self.width, self.height, &self.data)
    }

    /// Writes an 8-bit PNG atomically.
    pub fn save_png(&self, path: &Path) -> std::io::Result<()> {
        crate::io::write_atomic(path, &self.png_bytes())
    }

    /// Writes a 32-bit float EXR atomically: channel "Y" for one channel (the bytes of
    /// [`GrayImage::save_exr`]), "R", "G", "B" for three; the same image always gives the
    /// same bytes.
    pub fn save_exr(&self, path: &Path) -> std::io::Result<()> {
        use exr::prelude::{SpecificChannels, Vec2};
        if self.channels == 1 {
            return self.plane(0).save_exr(path);
        }
        let w = self.width as usize;
        let data = &self.data;
        let px = |pos: Vec2<usize>| {
            let i = 3 * (pos.y() * w + pos.x());
            (data[i], data[i + 1], data[i + 2])
        };
        let channels = SpecificChannels::rgb(px);
        save_exr(
            path,
            &exr::prelude::Image::from_channels((w, self.height as usize), channels),
        )
    }

    /// |a − b| × `gain` per channel, clamped to 1 (see [`GrayImage::difference`]).
    pub fn difference(&self, other: &Image, gain: f32) -> Image {
        assert_eq!(
            (self.width, self.height, self.channels),
            (other.width, other.height, other.channels)
        );
        Image {
            data: self
                .data
                .iter()
                .zip(&other.data)
                .map(|(a, b)| ((a - b).abs() * gain).min(1.0))
                .collect(),
            ..self.clone()
        }
    }
}

/// The 8-bit PNG of `data` ([`GrayImage::to_u8`] of each value), pixels of type `P`.
fn png_bytes<P>(width: u32, height: u32, data: &[f32]) -> Vec<u8>
where
    P: image::PixelWithColorType<Subpixel = u8>,
{
    let buf: Vec<u8> = data.iter().map(|&v| GrayImage::to_u8(v)).collect();
    let img = image::ImageBuffer::<P, _>::from_raw(width, height, buf)
        .expect("buffer matches dimensions");
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .expect("PNG encoding to memory cannot fail");
    out.into_inner()
}

/// Writes the 32-bit float EXR `image` atomically.
fn save_exr<'a, L>(path: &Path, image: &'a exr::prelude::Image<L>) -> std::io::Result<()>
where
    L: exr::image::write::layers::WritableLayers<'a>,
{
    let mut cursor = std::io::Cursor::new(Vec::new());
    // One thread: the parallel writer stores the compressed blocks in the order they finish,
    // so the same image gave different bytes from run to run.
    exr::prelude::WritableImage::write(image)
        .non_parallel()
        .to_buffered(&mut cursor)
        .map_err(|e| std::io::Error::other(e.to_string()))?;
    crate::io::write_atomic(path, &cursor.into_inner())
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

    #[test]
    fn an_image_of_one_channel_writes_the_gray_bytes_and_three_write_rgb() {
        let dir = tempfile::tempdir().unwrap();
        let mut g = GrayImage::new(5, 4, 0.0);
        for (i, v) in g.data.iter_mut().enumerate() {
            *v = i as f32 / 19.0;
        }
        let one = Image::from(g.clone());
        assert_eq!(one.png_bytes(), g.png_bytes());
        let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
        one.save_exr(&a).unwrap();
        g.save_exr(&b).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        // Three planes interleave per pixel; the PNG is RGB with each plane's 8-bit levels.
        let planes = vec![
            g.clone(),
            GrayImage::new(5, 4, 0.5),
            g.difference(&GrayImage::new(5, 4, 1.0), 1.0),
        ];
        let rgb = Image::interleave(planes.clone());
        assert_eq!((rgb.channels, rgb.data.len()), (3, 60));
        assert_eq!(&rgb.data[3 * 7..3 * 8], &[g.data[7], 0.5, 1.0 - g.data[7]]);
        for (c, p) in planes.iter().enumerate() {
            assert_eq!(&rgb.plane(c), p);
        }
        let p = dir.path().join("rgb.png");
        rgb.save_png(&p).unwrap();
        let back = image::open(&p).unwrap();
        assert_eq!(back.color(), image::ColorType::Rgb8);
        for (i, px) in back.to_rgb8().pixels().enumerate() {
            for (c, plane) in planes.iter().enumerate() {
                assert_eq!(px.0[c], GrayImage::to_u8(plane.data[i]));
            }
        }
        let e = dir.path().join("rgb.exr");
        rgb.save_exr(&e).unwrap();
        let read = exr::prelude::read_first_flat_layer_from_file(&e).unwrap();
        let names: Vec<String> = read
            .layer_data
            .channel_data
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect();
        // EXR stores channels sorted by name.
        assert_eq!(names, ["B", "G", "R"]);
        let red: Vec<f32> = read.layer_data.channel_data.list[2]
            .sample_data
            .values_as_f32()
            .collect();
        assert_eq!(red, g.data);
        // The difference is per channel.
        let d = rgb.difference(
            &Image::interleave(vec![g.clone(), g.clone(), g.clone()]),
            2.0,
        );
        assert_eq!(d.plane(0).data, vec![0.0; 20]);
        assert_eq!(d.plane(1), planes[1].difference(&g, 2.0));
    }
}
