//! PNG plots of the sampling report: sphere point sets in an equal-area projection and layout
//! texel solid angles as heat maps. Rendered into memory with plotters, encoded with `image`
//! and written atomically.

use crate::experiment::plot::{register_font, write_rgb_png};
use crate::experiment::{Error, Result};
use crate::sampling::{HemisphereLayout, LayoutKind, SphereKind, SpherePoints};
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::Path;

/// Draws into a `w × h` RGB buffer with `draw`, then writes it to `path` as PNG.
fn render(
    path: &Path,
    (w, h): (u32, u32),
    draw: impl FnOnce(DrawingArea<BitMapBackend, plotters::coord::Shift>) -> Result<()>,
) -> Result<()> {
    register_font();
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(Error::plot(path))?;
        draw(root.clone())?;
        root.present().map_err(Error::plot(path))?;
    }
    write_rgb_png(path, w, h, buf)
}

fn title_of(set: &SpherePoints) -> String {
    let name = match set.kind {
        SphereKind::Slater => "Slater hemisphere subdivision",
        SphereKind::LatLong => "Lat-long grid",
        SphereKind::Fibonacci => "Spherical Fibonacci",
    };
    format!(
        "{name}, {} points (Lambert azimuthal equal-area)",
        set.len()
    )
}

/// Both hemispheres side by side in Lambert's azimuthal equal-area projection about each pole:
/// (x, y) · √(2 / (1 + |z|)), so the hemisphere fills a disk of radius √2 and equal areas on the
/// sphere stay equal in the plot. The southern view looks through the sphere from above
/// (x and y keep their signs).
pub fn plot_sphere_points(path: &Path, set: &SpherePoints) -> Result<()> {
    render(path, (1200, 660), |root| {
        let root = root
            .titled(&title_of(set), ("sans-serif", 26))
            .map_err(Error::plot(path))?;
        let halves = root.split_evenly((1, 2));
        for (area, north) in halves.iter().zip([true, false]) {
            let caption = if north {
                "northern hemisphere (z ≥ 0), seen from +z"
            } else {
                "southern hemisphere (z < 0), seen from +z"
            };
            let r = std::f64::consts::SQRT_2;
            let mut chart = ChartBuilder::on(area)
                .caption(caption, ("sans-serif", 18))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(50)
                .build_cartesian_2d(-1.5f64..1.5, -1.5f64..1.5)
                .map_err(Error::plot(path))?;
            chart
                .configure_mesh()
                .x_desc("projected x")
                .y_desc("projected y")
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 16))
                .light_line_style(WHITE)
                .draw()
                .map_err(Error::plot(path))?;
            let rim = (0..=360).map(|a| {
                let t = (a as f64).to_radians();
                (r * t.cos(), r * t.sin())
            });
            chart
                .draw_series(LineSeries::new(rim, BLACK.stroke_width(1)))
                .map_err(Error::plot(path))?;
            let pts = set
                .points()
                .iter()
                .filter(|p| (p.z >= 0.0) == north)
                .map(|p| {
                    let k = (2.0 / (1.0 + p.z.abs() as f64)).sqrt();
                    (p.x as f64 * k, p.y as f64 * k)
                });
            chart
                .draw_series(pts.map(|c| Circle::new(c, 2, BLUE.filled())))
                .map_err(Error::plot(path))?;
        }
        Ok(())
    })
}

fn layout_title(layout: &HemisphereLayout) -> String {
    let name = match layout.kind {
        LayoutKind::Polar => "Polar (uniform θ, φ)",
        LayoutKind::Rejection => "Rejection + Malley",
        LayoutKind::Concentric => "Concentric + Malley",
    };
    let unused = if layout.kind == LayoutKind::Rejection {
        ", grey = unused"
    } else {
        ""
    };
    format!("{name} {0}×{0}: texel solid angle (sr){unused}", layout.res)
}

/// Heat map of each texel's solid angle (viridis, own colour bar; unused texels grey).
pub fn plot_layout_solid_angle(path: &Path, layout: &HemisphereLayout) -> Result<()> {
    let res = layout.res;
    let n = layout.texel_count() as u32;
    let omega: Vec<f64> = (0..n).map(|t| layout.solid_angle(t)).collect();
    let used = |t: u32| layout.is_used(t);
    let used_omega = (0..n).filter(|&t| used(t)).map(|t| omega[t as usize]);
    let lo = used_omega.clone().fold(f64::INFINITY, f64::min);
    let hi = used_omega.fold(0.0, f64::max);
    let (col_desc, row_desc) = match layout.kind {
        LayoutKind::Polar => ("column (azimuth φ)", "row (polar angle θ, 0 = zenith)"),
        _ => ("column (u)", "row (v)"),
    };
    render(path, (900, 760), |root| {
        let root = root
            .titled(&layout_title(layout), ("sans-serif", 24))
            .map_err(Error::plot(path))?;
        let (map, bar) = root.split_horizontally(760);
        let mut chart = ChartBuilder::on(&map)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(55)
            .build_cartesian_2d(0f64..res as f64, 0f64..res as f64)
            .map_err(Error::plot(path))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(col_desc)
            .y_desc(row_desc)
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v:.0}"))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(Error::plot(path))?;
        let grey = RGBColor(200, 200, 200);
        chart
            .draw_series((0..n).map(|t| {
                let (c, r) = layout.col_row(t);
                let colour = if used(t) {
                    ViridisRGB::get_color_normalized(omega[t as usize], lo, hi)
                } else {
                    grey
                };
                let (c, r) = (c as f64, r as f64);
                Rectangle::new([(c, r), (c + 1.0, r + 1.0)], colour.filled())
            }))
            .map_err(Error::plot(path))?;
        let mut scale = ChartBuilder::on(&bar)
            .margin_top(12)
            .margin_bottom(57)
            .margin_right(10)
            .y_label_area_size(80)
            .caption("sr", ("sans-serif", 16))
            .build_cartesian_2d(0f64..1.0, lo..hi)
            .map_err(Error::plot(path))?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_label_formatter(&|v| format!("{v:.2e}"))
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(Error::plot(path))?;
        let steps = 200;
        scale
            .draw_series((0..steps).map(|i| {
                let a = lo + (hi - lo) * i as f64 / steps as f64;
                let b = lo + (hi - lo) * (i + 1) as f64 / steps as f64;
                let colour = ViridisRGB::get_color_normalized(0.5 * (a + b), lo, hi);
                Rectangle::new([(0.0, a), (1.0, b)], colour.filled())
            }))
            .map_err(Error::plot(path))?;
        Ok(())
    })
}
