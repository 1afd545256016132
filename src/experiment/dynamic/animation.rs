//! An animated PNG (APNG) of a moving scene's frames: the ray-cast reference, the field and
//! their difference ×5 side by side, each panel a `width × height` grid of values scaled up by
//! whole pixels (`experiment dynamic`: the plane's vertex AO seen from above, one vertex a
//! pixel; an animated spec: its image, one pixel a pixel).

use crate::experiment::{Error, Result};
use std::path::Path;

/// One frame: the reference's and the field's values on the `width × height` grid, row-major.
pub struct Frame {
    pub reference: Vec<f32>,
    pub field: Vec<f32>,
}

fn level(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The three panels of `f` as one 8-bit grey image, `3·w·scale` × `h·scale`.
fn panels(f: &Frame, (w, h): (usize, usize), scale: usize) -> Vec<u8> {
    let row_len = 3 * w * scale;
    let mut img = vec![0u8; row_len * h * scale];
    for y in 0..h * scale {
        for x in 0..w * scale {
            let i = (y / scale) * w + x / scale;
            let (r, v) = (f.reference[i], f.field[i]);
            let row = y * row_len;
            img[row + x] = level(r);
            img[row + w * scale + x] = level(v);
            img[row + 2 * w * scale + x] = level(5.0 * (v - r).abs());
        }
    }
    img
}

/// Writes `frames`, each on a `width × height` grid, as an APNG at `path` (atomically),
/// `delay_ms` per frame, looping; panels at least 256 pixels on their longer side.
pub fn write(
    path: &Path,
    frames: &[Frame],
    (width, height): (usize, usize),
    delay_ms: u16,
) -> Result<()> {
    if frames.is_empty() {
        return Ok(());
    }
    let scale = (256 / width.max(height).max(1)).max(1);
    let (w, h) = ((3 * width * scale) as u32, (height * scale) as u32);
    let mut bytes = Vec::new();
    let encode = |bytes: &mut Vec<u8>| -> std::result::Result<(), png::EncodingError> {
        let mut enc = png::Encoder::new(&mut *bytes, w, h);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_animated(frames.len() as u32, 0)?;
        enc.set_frame_delay(delay_ms, 1000)?;
        let mut writer = enc.write_header()?;
        for f in frames {
            writer.write_image_data(&panels(f, (width, height), scale))?;
        }
        writer.finish()
    };
    encode(&mut bytes).map_err(|e| Error::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    crate::io::write_atomic(path, &bytes).map_err(Error::io(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panels_place_reference_field_and_difference() {
        let f = Frame {
            reference: vec![0.0, 1.0, 0.5, 0.5],
            field: vec![0.1, 1.0, 0.5, 0.375],
        };
        let img = panels(&f, (2, 2), 1);
        assert_eq!(img.len(), 6 * 2);
        assert_eq!(&img[0..6], &[0, 255, 26, 255, 128, 0]);
        assert_eq!(&img[6..12], &[128, 128, 128, 96, 0, 159]);
    }

    #[test]
    fn an_apng_of_every_frame_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        let frames: Vec<Frame> = (0..3)
            .map(|k| Frame {
                reference: vec![k as f32 / 3.0; 16],
                field: vec![0.5; 16],
            })
            .collect();
        write(&p, &frames, (4, 4), 100).unwrap();
        let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&p).unwrap()));
        let reader = dec.read_info().unwrap();
        let info = reader.info();
        assert_eq!(info.animation_control.map(|a| a.num_frames), Some(3));
        assert_eq!((info.width, info.height), (3 * 4 * 64, 4 * 64));
        // A wide grid: scaled by its longer side.
        let wide: Vec<Frame> = (0..2)
            .map(|_| Frame {
                reference: vec![0.5; 8 * 2],
                field: vec![0.25; 8 * 2],
            })
            .collect();
        write(&p, &wide, (8, 2), 100).unwrap();
        let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&p).unwrap()));
        let reader = dec.read_info().unwrap();
        assert_eq!(
            (reader.info().width, reader.info().height),
            (3 * 8 * 32, 2 * 32)
        );
    }
}
