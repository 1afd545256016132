//! Plots (plotters, PNG, with the DejaVu Sans font shipped in `assets/fonts`, so no system fonts
//! are needed): error-against-time Pareto plots, line plots and captioned image grids.

use super::{Error, Result};
use crate::render::image::GrayImage;
use plotters::prelude::*;
use std::path::Path;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Registers the shipped font as "sans-serif" (once per process): the one registration of
/// every plot the harness draws (these, the figures, relief and the sampling report).
pub fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("the shipped DejaVuSans.ttf is a valid font"));
    });
}

type PlotResult = Result<()>;

/// One labelled series of (x, y) points.
#[derive(Clone, Debug)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Join the points with a line (sorted by x) as well as marking them.
    pub line: bool,
}

/// A horizontal reference line (e.g. the reference's noise floor).
#[derive(Clone, Debug)]
pub struct HLine {
    pub label: String,
    pub y: f64,
}

/// Axis options of an x–y plot.
#[derive(Clone, Debug)]
pub struct Axes {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
}

fn range(vals: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / 1.5, hi * 1.5)
    } else {
        let pad = ((hi - lo) * 0.08).max(1e-9);
        ((lo - pad).min(0.0f64.max(lo - pad)), hi + pad)
    }
}

/// Draws series (and horizontal lines) to a PNG, with log axes where asked.
pub fn xy_plot(path: &Path, axes: &Axes, series: &[Series], hlines: &[HLine]) -> PlotResult {
    register_font();
    let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let ys = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .chain(hlines.iter().map(|h| h.y));
    let (x0, x1) = range(xs, axes.log_x);
    let (y0, y1) = range(ys, axes.log_y);
    let legend_corner = emptiest_corner(series, (x0, x1, axes.log_x), (y0, y1, axes.log_y));
    // Many entries: the legend goes beside the plot, where it hides nothing.
    let outside = series.len() + hlines.len() > 8;
    let width: u32 = if outside { 1450 } else { 1000 };
    let mut buf = vec![0u8; width as usize * 700 * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, 700)).into_drawing_area();
        root.fill(&WHITE).map_err(Error::plot(path))?;
        let (plot, side) = root.split_horizontally(1000);
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(axes.x_label.as_str())
                    .y_desc(axes.y_label.as_str())
                    .label_style(("sans-serif", 16))
                    .x_label_formatter(&|v| tick(snap_zero(*v, x1 - x0)))
                    .y_label_formatter(&|v| tick(snap_zero(*v, y1 - y0)))
                    .light_line_style(BLACK.mix(0.04))
                    .draw()
                    .map_err(Error::plot(path))?;
                for (i, s) in series.iter().enumerate() {
                    let color = Palette99::pick(i).to_rgba();
                    let mut pts = s.points.clone();
                    pts.retain(|p| p.0.is_finite() && p.1.is_finite());
                    if s.line {
                        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                        chart
                            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                            .map_err(Error::plot(path))?;
                    }
                    chart
                        .draw_series(pts.iter().map(|&p| Circle::new(p, 5, color.filled())))
                        .map_err(Error::plot(path))?
                        .label(s.label.as_str())
                        .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
                }
                for h in hlines {
                    let style = BLACK.mix(0.6).stroke_width(1);
                    chart
                        .draw_series(DashedLineSeries::new(
                            vec![(x0, h.y), (x1, h.y)],
                            8,
                            6,
                            style,
                        ))
                        .map_err(Error::plot(path))?
                        .label(h.label.as_str())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.6))
                        });
                }
                if !outside {
                    chart
                        .configure_series_labels()
                        .background_style(WHITE.mix(0.85))
                        .border_style(BLACK)
                        .label_font(("sans-serif", 15))
                        .position(legend_corner.clone())
                        .draw()
                        .map_err(Error::plot(path))?;
                }
            }};
        }
        if outside {
            // One row per entry: the series' dot or the line's stroke, then its label.
            let labels = series
                .iter()
                .map(|s| &s.label)
                .chain(hlines.iter().map(|h| &h.label));
            for (i, label) in labels.enumerate() {
                let y = 70 + 24 * i as i32;
                if i < series.len() {
                    let color = Palette99::pick(i).to_rgba();
                    side.draw(&Circle::new((12, y), 5, color.filled()))
                } else {
                    side.draw(&PathElement::new(vec![(2, y), (22, y)], BLACK.mix(0.6)))
                }
                .map_err(Error::plot(path))?;
                side.draw(&Text::new(label.as_str(), (26, y - 9), ("sans-serif", 15)))
                    .map_err(Error::plot(path))?;
            }
        }
        let mut builder = ChartBuilder::on(&plot);
        builder
            .caption(axes.title.as_str(), ("sans-serif", 24))
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(70);
        match (axes.log_x, axes.log_y) {
            (true, true) => draw!(builder
                .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(Error::plot(path))?),
            (true, false) => draw!(builder
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(Error::plot(path))?),
            (false, true) => draw!(builder
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(Error::plot(path))?),
            (false, false) => {
                draw!(builder
                    .build_cartesian_2d(x0..x1, y0..y1)
                    .map_err(Error::plot(path))?)
            }
        }
        root.present().map_err(Error::plot(path))?;
    }
    write_rgb_png(path, width, 700, buf)
}

/// The corner of the plot where a legend box of the series' size covers the fewest points (axes
/// in plot scale; the box about 45% of the width and 3% of the height per entry).
fn emptiest_corner(
    series: &[Series],
    (x0, x1, log_x): (f64, f64, bool),
    (y0, y1, log_y): (f64, f64, bool),
) -> SeriesLabelPosition {
    let unit = |v: f64, lo: f64, hi: f64, log: bool| {
        if log {
            (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
        } else {
            (v - lo) / (hi - lo)
        }
    };
    let (w, h) = (0.45, (0.03 * series.len() as f64 + 0.03).min(1.0));
    // Upper right, upper left, lower right, lower left: points under a legend there.
    let mut count = [0usize; 4];
    for &(x, y) in series.iter().flat_map(|s| s.points.iter()) {
        let (u, v) = (unit(x, x0, x1, log_x), unit(y, y0, y1, log_y));
        if !(u.is_finite() && v.is_finite()) {
            continue;
        }
        let (right, left, top, bottom) = (u >= 1.0 - w, u <= w, v >= 1.0 - h, v <= h);
        count[0] += (right && top) as usize;
        count[1] += (left && top) as usize;
        count[2] += (right && bottom) as usize;
        count[3] += (left && bottom) as usize;
    }
    let best = (0..4).min_by_key(|&k| count[k]).unwrap_or(0);
    [
        SeriesLabelPosition::UpperRight,
        SeriesLabelPosition::UpperLeft,
        SeriesLabelPosition::LowerRight,
        SeriesLabelPosition::LowerLeft,
    ][best]
        .clone()
}

/// A compact tick label: 3 significant digits, no float noise.
/// `v` as 0 where it is 0 up to the rounding of a tick step on an axis spanning `span` (a
/// linear axis through 0 otherwise labels it `-1.1e-16`).
fn snap_zero(v: f64, span: f64) -> f64 {
    if v.abs() <= 1e-9 * span.abs() {
        0.0
    } else {
        v
    }
}

fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let digits = (2 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Encodes a `w × h` RGB buffer as PNG and writes it to `path` atomically.
pub fn write_rgb_png(path: &Path, w: u32, h: u32, buf: Vec<u8>) -> PlotResult {
    let img = image::RgbImage::from_raw(w, h, buf)
        .ok_or_else(|| Error::plot(path)("buffer size mismatch"))?;
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(Error::image(path))?;
    crate::io::write_atomic(path, &out.into_inner()).map_err(Error::io(path))
}

/// A captioned grid of grey images (the papers' figure layout: numbers under each image).
pub fn image_grid(
    path: &Path,
    title: &str,
    cells: &[(&GrayImage, Vec<String>)],
    columns: usize,
) -> PlotResult {
    register_font();
    let columns = columns.max(1);
    let (cw, ch) = cells
        .first()
        .map(|(img, _)| (img.width, img.height))
        .unwrap_or((1, 1));
    let lines = cells.iter().map(|(_, c)| c.len()).max().unwrap_or(0) as u32;
    let caption_h = 20 * lines + 8;
    let rows = cells.len().div_ceil(columns) as u32;
    let pad = 8u32;
    let title_h = 40u32;
    let w = columns as u32 * (cw + pad) + pad;
    let h = title_h + rows * (ch + caption_h + pad) + pad;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    for (i, (img, _)) in cells.iter().enumerate() {
        let x0 = pad + (i % columns) as u32 * (cw + pad);
        let y0 = title_h + (i / columns) as u32 * (ch + caption_h + pad);
        for y in 0..img.height.min(ch) {
            for x in 0..img.width.min(cw) {
                let v = GrayImage::to_u8(img.data[(y * img.width + x) as usize]);
                let o = (((y0 + y) * w + x0 + x) * 3) as usize;
                buf[o..o + 3].fill(v);
            }
        }
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let font = ("sans-serif", 22).into_font().color(&BLACK);
        root.draw_text(title, &font, (pad as i32, 10))
            .map_err(Error::plot(path))?;
        let small = ("sans-serif", 15).into_font().color(&BLACK);
        for (i, (_, caption)) in cells.iter().enumerate() {
            let x0 = pad + (i % columns) as u32 * (cw + pad);
            let y0 = title_h + (i / columns) as u32 * (ch + caption_h + pad) + ch + 4;
            for (l, line) in caption.iter().enumerate() {
                root.draw_text(line, &small, (x0 as i32, (y0 + 20 * l as u32) as i32))
                    .map_err(Error::plot(path))?;
            }
        }
        root.present().map_err(Error::plot(path))?;
    }
    write_rgb_png(path, w, h, buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_compact() {
        assert_eq!(tick(0.23000000000004), "0.23");
        assert_eq!(tick(0.01), "0.01");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(4000.0), "4000");
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(2.5e-5), "2.5e-5");
        // A tick at 0 up to the step's rounding is 0; a small value on a small axis is not.
        assert_eq!(tick(snap_zero(-1.1e-16, 1.0)), "0");
        assert_eq!(tick(snap_zero(2.5e-5, 1e-4)), "2.5e-5");
    }

    #[test]
    fn plots_write_decodable_pngs_of_the_expected_size() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("pareto.png");
        let axes = Axes {
            title: "error against time".into(),
            x_label: "AO time (s)".into(),
            y_label: "RMS (0-255)".into(),
            log_x: true,
            log_y: false,
        };
        let s = vec![Series {
            label: "field".into(),
            points: vec![(0.01, 2.0), (0.1, 1.0), (1.0, 0.5)],
            line: true,
        }];
        xy_plot(
            &p,
            &axes,
            &s,
            &[HLine {
                label: "floor".into(),
                y: 0.3,
            }],
        )
        .unwrap();
        let img = image::open(&p).unwrap();
        assert_eq!((img.width(), img.height()), (1000, 700));
        // Something besides white was drawn.
        assert!(img.to_rgb8().pixels().any(|px| px.0 != [255, 255, 255]));

        let g = GrayImage::new(16, 12, 0.5);
        let q = dir.path().join("grid.png");
        image_grid(
            &q,
            "grid",
            &[(&g, vec!["a".into()]), (&g, vec!["b".into(), "c".into()])],
            2,
        )
        .unwrap();
        let img = image::open(&q).unwrap();
        // 2 columns: 2·(16 + 8) + 8 wide; one row: 40 + 12 + (2·20 + 8) + 8 + 8 high.
        assert_eq!((img.width(), img.height()), (56, 40 + 12 + 48 + 8 + 8));
    }
}

#[cfg(test)]
mod legend_tests {
    use super::*;

    #[test]
    fn legend_goes_to_the_corner_without_points() {
        let s = |pts: &[(f64, f64)]| Series {
            label: "s".into(),
            points: pts.to_vec(),
            line: false,
        };
        // A falling log–log line: its ends fill the upper left and lower right.
        let falling = [(0.01, 10.0), (0.03, 3.0), (0.3, 0.3), (1.0, 0.1)];
        let corner = emptiest_corner(&[s(&falling)], (0.01, 1.0, true), (0.1, 10.0, true));
        assert!(matches!(corner, SeriesLabelPosition::UpperRight));
        let rising = [(0.0, 0.0), (0.2, 0.3), (0.8, 0.7), (1.0, 1.0), (0.9, 0.95)];
        let corner = emptiest_corner(&[s(&rising)], (0.0, 1.0, false), (0.0, 1.0, false));
        assert!(
            matches!(corner, SeriesLabelPosition::UpperLeft),
            "{corner:?}"
        );
    }
}
