//! Image grids laid out as the papers lay out their figures: per block (a scene), a row of
//! column heads (the directional resolutions), a head per row (the positional samples), the
//! images framed, each with its numbers under it.

use super::{register_font, write_rgb_png, PlotResult};
use crate::experiment::Error;
use crate::render::image::GrayImage;
use plotters::prelude::*;
use std::path::Path;

/// An 8-bit RGB image.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    pub data: Vec<[u8; 3]>,
}

impl RgbImage {
    /// A grey image as RGB (each value rounded to 8 bits as its PNG is).
    pub fn from_gray(img: &GrayImage) -> RgbImage {
        RgbImage {
            width: img.width,
            height: img.height,
            data: img.data.iter().map(|&v| [GrayImage::to_u8(v); 3]).collect(),
        }
    }
}

/// One cell: its image (none: an empty cell) and the lines under it.
#[derive(Clone, Debug, Default)]
pub struct GridCell {
    pub image: Option<RgbImage>,
    pub caption: Vec<String>,
}

/// A block of rows under one title, with column and row heads (either may be empty).
#[derive(Clone, Debug, Default)]
pub struct GridBlock {
    pub title: String,
    pub col_heads: Vec<String>,
    pub row_heads: Vec<String>,
    /// Rows of cells; rows shorter than the widest are padded with empty cells.
    pub rows: Vec<Vec<GridCell>>,
}

/// A titled figure of blocks, with notes under the title.
#[derive(Clone, Debug, Default)]
pub struct Grid {
    pub title: String,
    pub notes: Vec<String>,
    pub blocks: Vec<GridBlock>,
}

const PAD: u32 = 10;
const LINE: u32 = 19;
const HEAD: u32 = 24;
const CHAR_W: u32 = 9;

/// Draws `grid` to a PNG: every cell as large as the largest image, a grey frame around each
/// image.
pub fn labelled_grid(path: &Path, grid: &Grid) -> PlotResult {
    register_font();
    let cells = || grid.blocks.iter().flat_map(|b| b.rows.iter().flatten());
    let largest = |side: fn(&RgbImage) -> u32| {
        let sides = cells().filter_map(|c| c.image.as_ref().map(side));
        sides.max().unwrap_or(64)
    };
    let (cw, ch) = (largest(|i| i.width), largest(|i| i.height));
    let caption_h = cells().map(|c| c.caption.len()).max().unwrap_or(0) as u32 * LINE + 6;
    let ncols = grid
        .blocks
        .iter()
        .flat_map(|b| b.rows.iter().map(Vec::len).chain([b.col_heads.len()]))
        .max()
        .unwrap_or(1)
        .max(1) as u32;
    let head_w = grid
        .blocks
        .iter()
        .flat_map(|b| b.row_heads.iter().map(|h| h.chars().count()))
        .max()
        .map_or(0, |n| n as u32 * CHAR_W + PAD);
    let col_w = cw + PAD;
    let row_h = ch + caption_h + PAD;
    let widest_caption = cells()
        .flat_map(|c| c.caption.iter().map(|l| l.chars().count()))
        .max()
        .unwrap_or(0) as u32;
    // Captions wider than the image widen the column.
    let col_w = col_w.max(widest_caption * (CHAR_W - 1) + PAD);
    let top = 44 + grid.notes.len() as u32 * LINE;
    let block_h = |b: &GridBlock| {
        let title = if b.title.is_empty() { 0 } else { HEAD + 6 };
        let heads = if b.col_heads.is_empty() { 0 } else { HEAD };
        title + heads + b.rows.len() as u32 * row_h
    };
    let w = PAD + head_w + ncols * col_w;
    let h = top + grid.blocks.iter().map(block_h).sum::<u32>() + PAD;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    // The images and their frames, straight into the buffer.
    let mut y = top;
    let mut text: Vec<(String, i32, i32, u32)> = Vec::new();
    for b in &grid.blocks {
        if !b.title.is_empty() {
            text.push((b.title.clone(), PAD as i32, y as i32 + 4, 20));
            y += HEAD + 6;
        }
        if !b.col_heads.is_empty() {
            for (c, head) in b.col_heads.iter().enumerate() {
                let x = PAD + head_w + c as u32 * col_w;
                text.push((head.clone(), x as i32, y as i32 + 2, 17));
            }
            y += HEAD;
        }
        for (r, row) in b.rows.iter().enumerate() {
            if let Some(head) = b.row_heads.get(r) {
                text.push((head.clone(), PAD as i32, (y + ch / 2) as i32 - 9, 17));
            }
            for (c, cell) in row.iter().enumerate() {
                let x0 = PAD + head_w + c as u32 * col_w;
                if let Some(img) = &cell.image {
                    blit(&mut buf, w, (x0, y), img);
                    frame(&mut buf, w, (x0, y), (img.width, img.height));
                }
                for (l, line) in cell.caption.iter().enumerate() {
                    let ty = y + ch + 3 + l as u32 * LINE;
                    text.push((line.clone(), x0 as i32, ty as i32, 15));
                }
            }
            y += row_h;
        }
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let font = ("sans-serif", 22).into_font().color(&BLACK);
        root.draw_text(&grid.title, &font, (PAD as i32, 10))
            .map_err(Error::plot(path))?;
        let small = ("sans-serif", 15).into_font().color(&BLACK);
        for (l, note) in grid.notes.iter().enumerate() {
            root.draw_text(note, &small, (PAD as i32, 40 + (l as u32 * LINE) as i32))
                .map_err(Error::plot(path))?;
        }
        for (s, x, y, size) in &text {
            let f = ("sans-serif", *size).into_font().color(&BLACK);
            root.draw_text(s, &f, (*x, *y)).map_err(Error::plot(path))?;
        }
        root.present().map_err(Error::plot(path))?;
    }
    write_rgb_png(path, w, h, buf)
}

/// Copies `img` into the `w`-wide RGB buffer at `(x0, y0)`.
fn blit(buf: &mut [u8], w: u32, (x0, y0): (u32, u32), img: &RgbImage) {
    for y in 0..img.height {
        for x in 0..img.width {
            let o = (((y0 + y) * w + x0 + x) * 3) as usize;
            buf[o..o + 3].copy_from_slice(&img.data[(y * img.width + x) as usize]);
        }
    }
}

/// A one-pixel grey frame just outside the `size` rectangle at `(x0, y0)`.
fn frame(buf: &mut [u8], w: u32, (x0, y0): (u32, u32), (iw, ih): (u32, u32)) {
    let h = (buf.len() / 3) as u32 / w;
    let mut set = |x: i64, y: i64| {
        if x >= 0 && y >= 0 && (x as u32) < w && (y as u32) < h {
            let o = ((y as u32 * w + x as u32) * 3) as usize;
            buf[o..o + 3].fill(150);
        }
    };
    let (x0, y0, iw, ih) = (x0 as i64, y0 as i64, iw as i64, ih as i64);
    for x in x0 - 1..=x0 + iw {
        set(x, y0 - 1);
        set(x, y0 + ih);
    }
    for y in y0 - 1..=y0 + ih {
        set(x0 - 1, y);
        set(x0 + iw, y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_has_a_cell_per_column_and_frames_its_images() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("grid.png");
        let white = RgbImage::from_gray(&GrayImage::new(20, 10, 1.0));
        let cell = |cap: &str| GridCell {
            image: Some(white.clone()),
            caption: vec![cap.into()],
        };
        let grid = Grid {
            title: "t".into(),
            notes: vec![],
            blocks: vec![GridBlock {
                title: String::new(),
                col_heads: vec![],
                row_heads: vec![],
                rows: vec![vec![cell("a"), cell("b")]],
            }],
        };
        labelled_grid(&p, &grid).unwrap();
        let img = image::open(&p).unwrap().to_rgb8();
        // Two columns of 20 + PAD (the one-letter captions are narrower), a left pad.
        assert_eq!(img.width(), PAD + 2 * (20 + PAD));
        // The frame of the first image is grey, just outside it: a white image on a white
        // page still shows where it ends.
        let top = 44;
        assert_eq!(img.get_pixel(PAD - 1, top + 5).0, [150, 150, 150]);
        assert_eq!(img.get_pixel(PAD + 5, top + 5).0, [255, 255, 255]);
    }
}
