//! `images.png` and `differences.png`, laid out as the papers lay out their figures (2008
//! Figure 6, 2010 Figures 3 and 7): per scene, the ray-cast reference in the first column
//! beside the fields (a second reference, as the mirror of glossy reflections, under it), a
//! column per value of the axis with the most values (the directional resolution) under its
//! head, a row per positional count (and other setting) with its head, and under each image
//! its bake time, the estimate's time (every device's) and its RMS and bytes.
//!
//! Shadows show the shaded images (`-shaded.png`: the light fraction × the diffuse shading,
//! as the paper's figures), where the run wrote them; the RMS under them stays the light
//! fraction's. Pixels where the camera sees no surface (`images/SCENE-coverage.png`, written
//! by the run beside the reference) are tinted, so that empty space never reads as a fully
//! lit surface. One device's images are shown (the others' are the same to 1/255: GPU
//! parity). Images wider than [`GRID_CELL_MAX`] are shown reduced by an integer factor.

use super::labels::Devices;
use super::{key_suffix, metric, RunData, AXES};
use crate::experiment::plot::{distinct, labelled_grid, sorted_distinct, Grid, GridBlock};
use crate::experiment::plot::{GridCell, RgbImage};
use crate::experiment::spec::Backend;
use crate::experiment::table::Row;
use crate::experiment::{Error, Result};
use crate::render::points::GBuffer;
use std::path::{Path, PathBuf};

/// The widest a grid cell is drawn (pixels): larger images are shown box-filtered by the
/// smallest integer factor that fits, so that a figure of many 512 × 512 cells stays a
/// picture of a few MB (the full images are beside it in `images/`).
pub const GRID_CELL_MAX: u32 = 256;

/// The colour of empty space in the grids: a pale blue no grey value of a kind takes.
pub const EMPTY: [u8; 3] = [196, 214, 236];

/// The coverage image of a scene's view: white where the camera sees a surface, black where
/// it sees none (written by the run beside the reference image).
pub fn coverage_path(out: &Path, scene: &str) -> PathBuf {
    out.join(format!("images/{scene}-coverage.png"))
}

/// Writes the coverage of `gbuf` (see [`coverage_path`]) as an 8-bit grey PNG.
pub fn write_coverage(path: &Path, gbuf: &GBuffer) -> Result<()> {
    let data: Vec<u8> = gbuf
        .hits
        .iter()
        .map(|h| if h.is_some() { 255 } else { 0 })
        .collect();
    let img = image::GrayImage::from_raw(gbuf.width, gbuf.height, data)
        .ok_or_else(|| Error::plot(path)("G-buffer size mismatch"))?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(Error::image(path))?;
    crate::io::write_atomic(path, &bytes.into_inner()).map_err(Error::io(path))
}

/// A PNG as floats in [0, 1], three channels, reduced to fit [`GRID_CELL_MAX`].
#[derive(Clone, Debug, PartialEq)]
struct Picture {
    width: u32,
    height: u32,
    data: Vec<[f32; 3]>,
}

impl Picture {
    fn load(path: &Path) -> Result<Picture> {
        let img = image::open(path).map_err(Error::image(path))?.to_rgb8();
        let full = Picture {
            width: img.width(),
            height: img.height(),
            data: img
                .pixels()
                .map(|p| p.0.map(|c| c as f32 / 255.0))
                .collect(),
        };
        Ok(full.box_down(full.width.div_ceil(GRID_CELL_MAX).max(1)))
    }

    /// Reduced by the integer factor `f` (the mean of each f × f block; partial blocks at
    /// the right and bottom edges are dropped).
    fn box_down(&self, f: u32) -> Picture {
        if f <= 1 {
            return self.clone();
        }
        let (w, h) = (self.width / f, self.height / f);
        let mut data = vec![[0.0f32; 3]; (w * h) as usize];
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0.0f32; 3];
                for yy in y * f..(y + 1) * f {
                    for xx in x * f..(x + 1) * f {
                        let p = self.data[(yy * self.width + xx) as usize];
                        for c in 0..3 {
                            sum[c] += p[c];
                        }
                    }
                }
                data[(y * w + x) as usize] = sum.map(|s| s / (f * f) as f32);
            }
        }
        Picture {
            width: w,
            height: h,
            data,
        }
    }

    /// As 8-bit RGB, each pixel blended towards [`EMPTY`] by how much of it `coverage`
    /// (a picture of the same size) leaves uncovered.
    fn rgb(&self, coverage: Option<&Picture>) -> RgbImage {
        let cover = |i: usize| {
            coverage
                .filter(|c| c.width == self.width && c.height == self.height)
                .map_or(1.0, |c| c.data[i][0])
        };
        let data = self
            .data
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let k = cover(i);
                std::array::from_fn(|c| {
                    let v = p[c] * k + EMPTY[c] as f32 / 255.0 * (1.0 - k);
                    (v.clamp(0.0, 1.0) * 255.0).round() as u8
                })
            })
            .collect();
        RgbImage {
            width: self.width,
            height: self.height,
            data,
        }
    }
}

/// An image of the run (`rel` relative to its folder), its shaded twin where `shaded` and the
/// twin exists.
fn image_path(out: &Path, rel: &str, shaded: bool) -> PathBuf {
    let twin = out.join(rel.replace(".png", "-shaded.png"));
    if shaded && twin.exists() {
        twin
    } else {
        out.join(rel)
    }
}

/// Draws `images.png` and `differences.png` (see the module's doc); nothing for a run without
/// images, or a folder that holds its tables without them.
pub fn grids(out: &Path, run: &RunData) -> Result<()> {
    let rows = &run.rows;
    let first = rows[0].backend;
    let shown: Vec<&Row> = rows
        .iter()
        .filter(|r| !r.image.is_empty() && r.backend == first)
        .collect();
    // A folder of CSV files alone (as `results/quick/`): no grids to draw.
    if shown.is_empty() || !out.join(&shown[0].image).exists() {
        return Ok(());
    }
    let (m, _) = metric(rows);
    let devices = Devices::of(rows);
    let owned: Vec<Row> = shown.iter().map(|r| (*r).clone()).collect();
    // The column axis: the one with the most values (ties to the earlier), from the
    // resolution on (never the scene, the sphere or the backend).
    let (col_name, col_fn) = AXES[2..]
        .iter()
        .rev()
        .copied()
        .filter(|(n, _)| *n != "backend")
        .max_by_key(|(_, f)| sorted_distinct(owned.iter().map(f)).len())
        .expect("axes");
    let columns = distinct(owned.iter().map(col_fn));
    // Shaded images where every shown cell and the references have them.
    let shaded = owned
        .iter()
        .all(|r| out.join(r.image.replace(".png", "-shaded.png")).exists());
    let backends = sorted_distinct(rows.iter().map(|r| r.backend));
    let q = run.quantity();
    let row_key = |r: &Row| {
        let other = key_suffix(&owned, r, &[col_name, "scene", "backend"]);
        format!("{} maps{other}", r.positional_samples)
    };
    let mut images = Grid {
        title: run.title.clone(),
        ..Grid::default()
    };
    let mut diffs = Grid {
        title: format!("{}: |field − reference| × 5", run.title),
        ..Grid::default()
    };
    if shaded {
        images.notes.push(format!(
            "shaded images ({q} × diffuse shading), as the paper shows; RMS of the {q} values"
        ));
    }
    if backends.len() > 1 {
        let names: Vec<&str> = backends.iter().map(|&b| devices.name(b)).collect();
        images.notes.push(format!(
            "images of the {} rows (the others' are the same to 1/255); {q} times: {}",
            devices.name(first),
            names.join(" / ")
        ));
    }
    let mut tinted = false;
    for sc in run.scenes() {
        let in_scene: Vec<&Row> = owned.iter().filter(|r| r.scene == sc).collect();
        if in_scene.is_empty() {
            continue;
        }
        let coverage = match coverage_path(out, sc) {
            p if p.exists() => Some(Picture::load(&p)?),
            _ => None,
        };
        tinted |= coverage.is_some();
        let pic = |p: &Path| -> Result<RgbImage> { Ok(Picture::load(p)?.rgb(coverage.as_ref())) };
        let groups = distinct(in_scene.iter().map(|r| row_key(r)));
        // The references: ray cast, then a second one (reflections' mirror) where written.
        let mut refs: Vec<GridCell> = Vec::new();
        let rc = run
            .sweep
            .iter()
            .filter(|s| s.scene == sc && s.backend == Backend::Cpu && s.rms_image == Some(0.0))
            .max_by_key(|s| s.rays_per_point);
        let mut cap = vec!["ray cast (reference)".to_string()];
        if let Some(s) = rc {
            cap.push(format!("{} rays, {:.3} s", s.rays_per_point, s.raycast_s));
        }
        refs.push(GridCell {
            image: Some(pic(&image_path(
                out,
                &format!("images/{sc}-reference.png"),
                shaded,
            ))?),
            caption: cap,
        });
        if let Some(name) = in_scene.iter().find_map(|r| r.second_reference.clone()) {
            let p = out.join(format!("images/{sc}-reference-{name}.png"));
            if p.exists() {
                refs.push(GridCell {
                    image: Some(pic(&p)?),
                    caption: vec![format!("{name} (second reference)")],
                });
            }
        }
        let heads = |first: &str| {
            let heads = columns.iter().map(|c| head(col_name, c));
            std::iter::once(first.to_string()).chain(heads).collect()
        };
        let mut block = GridBlock {
            title: if run.scenes().len() > 1 {
                sc.to_string()
            } else {
                String::new()
            },
            col_heads: heads("reference"),
            row_heads: groups.clone(),
            rows: Vec::new(),
        };
        let mut dblock = GridBlock {
            col_heads: heads(""),
            ..block.clone()
        };
        for (gi, g) in groups.iter().enumerate() {
            let mut row = vec![refs.get(gi).cloned().unwrap_or_default()];
            let mut drow = vec![GridCell::default()];
            for col in &columns {
                let Some(r) = in_scene
                    .iter()
                    .find(|r| &row_key(r) == g && &col_fn(r) == col)
                else {
                    row.push(GridCell::default());
                    drow.push(GridCell::default());
                    continue;
                };
                let bake = r.bake_s.map_or("-".into(), |b| format!("{b:.2} s"));
                let rms = m(r).map_or("-".into(), |v| format!("{v:.3}"));
                // Every device's time of this cell.
                let times: Vec<String> = backends
                    .iter()
                    .filter_map(|&b| {
                        rows.iter()
                            .find(|o| o.backend == b && o.scene == r.scene && same_cell(o, r))
                            .map(|o| format!("{:.3}", o.estimate_s))
                    })
                    .collect();
                row.push(GridCell {
                    image: Some(pic(&image_path(out, &r.image, shaded))?),
                    caption: vec![
                        format!("bake {bake}"),
                        format!("{q} {} s", times.join(" / ")),
                        format!(
                            "RMS {rms}, {:.1} MiB",
                            r.field_bytes as f64 / (1u64 << 20) as f64
                        ),
                    ],
                });
                let diff = out.join(r.image.replace(".png", "-diff_x5.png"));
                let share = r.share_pixels_off_1.unwrap_or(0.0) * 100.0;
                drow.push(GridCell {
                    image: Some(pic(&diff)?),
                    caption: vec![
                        format!("RMS {rms}, max {:.0}", r.max_error_image.unwrap_or(0.0)),
                        format!("{share:.1}% off by > 1/255"),
                    ],
                });
            }
            block.rows.push(row);
            dblock.rows.push(drow);
        }
        // A second reference with a single row of fields gets a row of its own.
        for extra in refs.iter().skip(groups.len()) {
            block.rows.push(vec![extra.clone()]);
            block.row_heads.push(String::new());
        }
        images.blocks.push(block);
        diffs.blocks.push(dblock);
    }
    if tinted {
        for g in [&mut images, &mut diffs] {
            g.notes
                .push("pale blue: no surface (empty space)".to_string());
        }
    }
    labelled_grid(&out.join("images.png"), &images)?;
    labelled_grid(&out.join("differences.png"), &diffs)
}

/// Two rows of one cell on different backends: every axis but the backend equal.
fn same_cell(a: &Row, b: &Row) -> bool {
    AXES.iter()
        .filter(|(n, _)| *n != "backend")
        .all(|(_, f)| f(a) == f(b))
        && a.positional_samples == b.positional_samples
}

/// A column's head: "32 × 32 directions" for a resolution, the value otherwise.
fn head(axis: &str, value: &str) -> String {
    match (axis, value.strip_suffix('²')) {
        ("res", Some(n)) => format!("{n} × {n} directions"),
        _ => value.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_down_averages_blocks_and_drops_partial_ones() {
        // 5 × 2 pixels, factor 2: two full 2 × 2 blocks, the fifth column dropped.
        let grey = [0.0, 1.0, 0.5, 0.5, 0.9, 1.0, 0.0, 0.5, 0.5, 0.9];
        let img = Picture {
            width: 5,
            height: 2,
            data: grey.iter().map(|&v| [v; 3]).collect(),
        };
        let d = img.box_down(2);
        assert_eq!((d.width, d.height), (2, 1));
        assert_eq!(d.data, vec![[0.5; 3], [0.5; 3]]);
        assert_eq!(img.box_down(1), img);
    }

    #[test]
    fn uncovered_pixels_take_the_empty_colour() {
        // A white pixel on a surface stays white; a white pixel of empty space turns pale
        // blue; half covered, half way.
        let img = Picture {
            width: 3,
            height: 1,
            data: vec![[1.0; 3]; 3],
        };
        let cov = Picture {
            width: 3,
            height: 1,
            data: vec![[1.0; 3], [0.0; 3], [0.5; 3]],
        };
        let rgb = img.rgb(Some(&cov));
        assert_eq!(rgb.data[0], [255, 255, 255]);
        assert_eq!(rgb.data[1], EMPTY);
        let half: [u8; 3] =
            std::array::from_fn(|c| ((1.0 + EMPTY[c] as f32 / 255.0) / 2.0 * 255.0).round() as u8);
        assert_eq!(rgb.data[2], half);
        // Without a coverage image, nothing is tinted.
        assert_eq!(img.rgb(None).data[1], [255, 255, 255]);
    }
}
