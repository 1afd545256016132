//! Plots (plotters, PNG, with the DejaVu Sans font shipped in `assets/fonts`, so no system fonts
//! are needed): figures of one or more panels of styled series on shared axes, each panel's
//! legend under it (never over the data), with ticks chosen in [`ticks`]; line plots in the
//! default palette ([`xy_plot`]); captioned image grids ([`image_grid`], and [`labelled_grid`]
//! with column and row heads).

mod grid;
pub mod ticks;

pub use grid::{labelled_grid, Grid, GridBlock, GridCell, RgbImage};

use super::{Error, Result};
use crate::render::image::GrayImage;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use ticks::{label_texts, AxisLayout, Ticks};

static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

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

/// The most series a panel of a figure holds: more are split into panels (faceted) by the
/// code that builds the figure.
pub const MAX_SERIES: usize = 8;

/// One labelled series of (x, y) points.
#[derive(Clone, Debug)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Join the points with a line (sorted by x) as well as marking them.
    pub line: bool,
}

impl Series {
    /// Points joined by a line.
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            label: label.into(),
            points,
            line: true,
        }
    }

    /// Points alone, not joined.
    pub fn scatter(label: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            label: label.into(),
            points,
            line: false,
        }
    }

    /// The series in `style`.
    pub fn styled(self, style: Style) -> Styled {
        Styled {
            series: self,
            style,
        }
    }
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

impl Axes {
    /// Linear axes with this title and these labels.
    pub fn new(title: impl Into<String>, x: impl Into<String>, y: impl Into<String>) -> Axes {
        Axes {
            title: title.into(),
            x_label: x.into(),
            y_label: y.into(),
            log_x: false,
            log_y: false,
        }
    }

    /// The x axis logarithmic.
    pub fn log_x(mut self) -> Axes {
        self.log_x = true;
        self
    }

    /// The y axis logarithmic.
    pub fn log_y(mut self) -> Axes {
        self.log_y = true;
        self
    }
}

/// The shape of a series' points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    Circle,
    Square,
    Up,
    Down,
    Diamond,
    Cross,
}

/// How a series is drawn: its colour, its points' shape, outlined (`hollow`) or filled, and
/// its line dashed or solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    pub color: RGBColor,
    pub marker: Marker,
    pub hollow: bool,
    pub dashed: bool,
}

impl Style {
    pub fn new(color: RGBColor, marker: Marker) -> Style {
        Style {
            color,
            marker,
            hollow: false,
            dashed: false,
        }
    }

    pub fn hollow(self) -> Style {
        Style {
            hollow: true,
            ..self
        }
    }

    pub fn dashed(self) -> Style {
        Style {
            dashed: true,
            ..self
        }
    }

    /// The `i`-th colour of the default palette (Tableau's ten, each dark enough on white,
    /// then plotters' 99), as filled circles.
    pub fn palette(i: usize) -> Style {
        const TEN: [(u8, u8, u8); 10] = [
            (31, 119, 180),
            (255, 127, 14),
            (44, 160, 44),
            (214, 39, 40),
            (148, 103, 189),
            (140, 86, 75),
            (227, 119, 194),
            (127, 127, 127),
            (188, 189, 34),
            (23, 190, 207),
        ];
        let color = match TEN.get(i) {
            Some(&(r, g, b)) => RGBColor(r, g, b),
            None => {
                let c = Palette99::pick(i).to_rgba();
                RGBColor(c.0, c.1, c.2)
            }
        };
        Style::new(color, Marker::Circle)
    }
}

/// A series with its style.
#[derive(Clone, Debug)]
pub struct Styled {
    pub series: Series,
    pub style: Style,
}

/// One panel of a figure: its series (at most [`MAX_SERIES`] by convention) and reference
/// lines, on the figure's shared axes.
#[derive(Clone, Debug, Default)]
pub struct Panel {
    pub title: String,
    pub series: Vec<Styled>,
    pub hlines: Vec<HLine>,
}

impl Panel {
    /// A panel of `series` without reference lines.
    pub fn new(title: impl Into<String>, series: Vec<Styled>) -> Panel {
        Panel {
            title: title.into(),
            series,
            hlines: Vec::new(),
        }
    }
}

/// The distinct values of `items` in the order they first come (a plot's series, panels and
/// columns keep the order of the rows).
pub fn distinct<T: PartialEq>(items: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut out = Vec::new();
    for x in items {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

/// The distinct values of `items`, sorted.
pub fn sorted_distinct<T: Ord>(items: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut out: Vec<T> = items.into_iter().collect();
    out.sort();
    out.dedup();
    out
}

/// Panels on shared axes (the same ranges in every panel, so that panels compare), one title,
/// and notes under them (what a plot leaves out, and why).
#[derive(Clone, Debug)]
pub struct Figure {
    pub axes: Axes,
    pub panels: Vec<Panel>,
    pub notes: Vec<String>,
}

/// The data range of one axis over `vals` (positive values only on a logarithmic axis),
/// padded; a logarithmic range spans at least a factor of 3.
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
        let (lo, hi) = (lo / 1.25, hi * 1.25);
        let short = (3.0 / (hi / lo)).max(1.0).sqrt();
        (lo / short, hi * short)
    } else {
        let pad = ((hi - lo) * 0.08).max(1e-9 * hi.abs().max(1.0));
        (lo - pad, hi + pad)
    }
}

/// Draws series (and horizontal lines) to a PNG, with log axes where asked: a one-panel
/// [`Figure`] in the default palette.
pub fn xy_plot(path: &Path, axes: &Axes, series: &[Series], hlines: &[HLine]) -> PlotResult {
    let styled = series.iter().enumerate();
    let panel = Panel {
        hlines: hlines.to_vec(),
        ..Panel::new(
            "",
            styled
                .map(|(i, s)| s.clone().styled(Style::palette(i)))
                .collect(),
        )
    };
    figure_plot(
        path,
        &Figure {
            axes: axes.clone(),
            panels: vec![panel],
            notes: Vec::new(),
        },
    )
}

/// The sizes of a figure's parts, in pixels.
struct Layout {
    cols: usize,
    panel_w: u32,
    title_h: u32,
    chart_h: u32,
    legend_cols: usize,
    legend_h: u32,
    top: u32,
    /// The notes, wrapped to the figure's width.
    notes: Vec<String>,
    notes_h: u32,
}

const LEGEND_ROW: u32 = 22;
const CHAR_W: f64 = 8.6;

impl Layout {
    fn of(fig: &Figure) -> Layout {
        let n = fig.panels.len().max(1);
        let cols = if n == 1 { 1 } else { 2 };
        let (panel_w, chart_h) = if n == 1 { (1000, 580) } else { (780, 440) };
        let entries = |p: &Panel| p.series.len() + p.hlines.len();
        let longest = fig
            .panels
            .iter()
            .flat_map(|p| {
                p.series
                    .iter()
                    .map(|s| s.series.label.chars().count())
                    .chain(p.hlines.iter().map(|h| h.label.chars().count()))
            })
            .max()
            .unwrap_or(0);
        // Two columns of entries where the longest label fits half the panel.
        let legend_cols = if (longest as f64 + 6.0) * CHAR_W < (panel_w / 2 - 40) as f64 {
            2
        } else {
            1
        };
        let rows = fig
            .panels
            .iter()
            .map(|p| entries(p).div_ceil(legend_cols))
            .max()
            .unwrap_or(0) as u32;
        let titled = fig.panels.iter().any(|p| !p.title.is_empty());
        let width = cols as u32 * panel_w;
        let chars = ((width - 32) as f64 / CHAR_W) as usize;
        let notes: Vec<String> = fig.notes.iter().flat_map(|n| wrap(n, chars)).collect();
        Layout {
            cols,
            panel_w,
            title_h: if titled { 30 } else { 0 },
            chart_h,
            legend_cols,
            legend_h: rows * LEGEND_ROW + 12,
            top: 46,
            notes_h: notes.len() as u32 * 21 + if notes.is_empty() { 0 } else { 8 },
            notes,
        }
    }

    fn panel_h(&self) -> u32 {
        self.title_h + self.chart_h + self.legend_h
    }

    fn size(&self, panels: usize) -> (u32, u32) {
        let rows = panels.max(1).div_ceil(self.cols) as u32;
        (
            self.cols as u32 * self.panel_w,
            self.top + rows * self.panel_h() + self.notes_h + 6,
        )
    }
}

const MARGIN: u32 = 14;
const X_LABEL_AREA: u32 = 48;
const Y_LABEL_AREA: u32 = 72;

/// Draws a figure: its panels in one or two columns on shared axes, each with its legend
/// under it, then the notes.
pub fn figure_plot(path: &Path, fig: &Figure) -> PlotResult {
    register_font();
    let layout = Layout::of(fig);
    let (w, h) = layout.size(fig.panels.len());
    let axes = &fig.axes;
    let points = || {
        fig.panels
            .iter()
            .flat_map(|p| p.series.iter().flat_map(|s| s.series.points.iter()))
    };
    let (x0, x1) = range(points().map(|p| p.0), axes.log_x);
    let hl = fig.panels.iter().flat_map(|p| p.hlines.iter().map(|h| h.y));
    let (y0, y1) = range(points().map(|p| p.1).chain(hl), axes.log_y);
    let x_axis = axis_ticks(AxisLayout {
        lo: x0,
        hi: x1,
        log: axes.log_x,
        pixels: (layout.panel_w - Y_LABEL_AREA - 2 * MARGIN) as f64,
        min_gap: 0.0,
    });
    let y_axis = axis_ticks(AxisLayout {
        lo: y0,
        hi: y1,
        log: axes.log_y,
        pixels: (layout.chart_h - X_LABEL_AREA - 2 * MARGIN) as f64,
        min_gap: 26.0,
    });
    let mut buf = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(Error::plot(path))?;
        root.draw_text(
            &axes.title,
            &("sans-serif", 24).into_font().color(&BLACK),
            (16, 12),
        )
        .map_err(Error::plot(path))?;
        for (i, panel) in fig.panels.iter().enumerate() {
            let (c, r) = ((i % layout.cols) as u32, (i / layout.cols) as u32);
            let area = root.clone().shrink(
                (c * layout.panel_w, layout.top + r * layout.panel_h()),
                (layout.panel_w, layout.panel_h()),
            );
            draw_panel(path, &area, &layout, axes, panel, (&x_axis, &y_axis))?;
        }
        let small = ("sans-serif", 16).into_font().color(&BLACK);
        let rows = fig.panels.len().max(1).div_ceil(layout.cols) as u32;
        for (k, note) in layout.notes.iter().enumerate() {
            let y = layout.top + rows * layout.panel_h() + 4 + 21 * k as u32;
            root.draw_text(note, &small, (16, y as i32))
                .map_err(Error::plot(path))?;
        }
        root.present().map_err(Error::plot(path))?;
    }
    write_rgb_png(path, w, h, buf)
}

/// `text` in lines of at most `chars` characters, broken at spaces (a longer word on a line
/// of its own).
fn wrap(text: &str, chars: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > chars {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    lines.push(line);
    lines
}

/// An axis with its ticks and their texts: the ticks chosen with the least gap its own label
/// texts need (an x axis: the widest text and a margin; a y axis: `min_gap` as given).
struct AxisTicks {
    layout: AxisLayout,
    ticks: Ticks,
    texts: Vec<String>,
}

fn axis_ticks(mut layout: AxisLayout) -> AxisTicks {
    let x = layout.min_gap == 0.0;
    if x {
        layout.min_gap = 6.0 * CHAR_W + 14.0;
    }
    let mut t = ticks::ticks(&layout);
    let mut texts = label_texts(&t.labels);
    if x {
        let widest = texts.iter().map(|s| s.chars().count()).max().unwrap_or(1) as f64;
        let need = widest * CHAR_W + 14.0;
        if need > layout.min_gap {
            layout.min_gap = need;
            t = ticks::ticks(&layout);
            texts = label_texts(&t.labels);
        }
    }
    AxisTicks {
        layout,
        ticks: t,
        texts,
    }
}

impl AxisTicks {
    /// The text of a labelled value (the mesh asks for its bold key points only).
    fn text(&self, v: f64) -> String {
        self.ticks
            .labels
            .iter()
            .position(|&l| (l - v).abs() <= 1e-9 * l.abs().max(1e-300))
            .map_or_else(|| ticks::tick(v), |i| self.texts[i].clone())
    }
}

/// A linear or logarithmic axis whose key points are the chosen ticks (plotters' own
/// logarithmic axis picks its ticks itself, and its tick-bound wrapper loses the number
/// formatting the mesh needs).
struct Keyed {
    lo: f64,
    hi: f64,
    log: bool,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Keyed {
    fn of(a: &AxisTicks) -> Keyed {
        Keyed {
            lo: a.layout.lo,
            hi: a.layout.hi,
            log: a.layout.log,
            bold: a.ticks.labels.clone(),
            light: a.ticks.light.clone(),
        }
    }
}

impl Ranged for Keyed {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = if self.log {
            (v.max(f64::MIN_POSITIVE).ln() - self.lo.ln()) / (self.hi.ln() - self.lo.ln())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        let t = if t.is_finite() {
            t.clamp(-10.0, 10.0)
        } else {
            0.0
        };
        limit.0 + (t * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

fn draw_panel<DB: DrawingBackend>(
    path: &Path,
    area: &DrawingArea<DB, Shift>,
    layout: &Layout,
    axes: &Axes,
    panel: &Panel,
    (x, y): (&AxisTicks, &AxisTicks),
) -> PlotResult {
    if !panel.title.is_empty() {
        area.draw_text(
            &panel.title,
            &("sans-serif", 19).into_font().color(&BLACK),
            (Y_LABEL_AREA as i32 - 40, 8),
        )
        .map_err(Error::plot(path))?;
    }
    let chart_area = area
        .clone()
        .shrink((0, layout.title_h), (layout.panel_w, layout.chart_h));
    let (x0, x1) = (x.layout.lo, x.layout.hi);
    let mut chart = ChartBuilder::on(&chart_area)
        .margin(MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(Keyed::of(x), Keyed::of(y))
        .map_err(Error::plot(path))?;
    chart
        .configure_mesh()
        .x_desc(axes.x_label.as_str())
        .y_desc(axes.y_label.as_str())
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 15))
        .x_label_formatter(&|v| x.text(*v))
        .y_label_formatter(&|v| y.text(*v))
        .bold_line_style(BLACK.mix(0.16))
        .light_line_style(BLACK.mix(0.05))
        .draw()
        .map_err(Error::plot(path))?;
    for h in &panel.hlines {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x0, h.y), (x1, h.y)],
                8,
                6,
                BLACK.mix(0.6).stroke_width(1),
            ))
            .map_err(Error::plot(path))?;
    }
    for s in &panel.series {
        let mut pts = s.series.points.clone();
        pts.retain(|p| {
            p.0.is_finite()
                && p.1.is_finite()
                && (!axes.log_x || p.0 > 0.0)
                && (!axes.log_y || p.1 > 0.0)
        });
        let st = s.style;
        let color = st.color;
        if s.series.line && pts.len() > 1 {
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            if st.dashed {
                chart
                    .draw_series(DashedLineSeries::new(
                        pts.clone(),
                        10,
                        6,
                        color.stroke_width(2),
                    ))
                    .map_err(Error::plot(path))?;
            } else {
                chart
                    .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                    .map_err(Error::plot(path))?;
            }
        }
        draw_markers(path, chart.plotting_area(), pts, st)?;
    }
    draw_legend(path, area, layout, panel)
}

/// The legend under a panel's chart: one entry per series (its line and point) and per
/// reference line, in one or two columns.
fn draw_legend<DB: DrawingBackend>(
    path: &Path,
    area: &DrawingArea<DB, Shift>,
    layout: &Layout,
    panel: &Panel,
) -> PlotResult {
    let col_w = (layout.panel_w - Y_LABEL_AREA) / layout.legend_cols as u32;
    let font = ("sans-serif", 15).into_font().color(&BLACK);
    let top = (layout.title_h + layout.chart_h) as i32 + 4;
    let at = |j: usize| {
        let (c, r) = (j % layout.legend_cols, j / layout.legend_cols);
        (
            Y_LABEL_AREA as i32 - 40 + (c as u32 * col_w) as i32,
            top + (r as u32 * LEGEND_ROW) as i32 + 10,
        )
    };
    for (j, s) in panel.series.iter().enumerate() {
        let (x, y) = at(j);
        let st = s.style;
        if s.series.line {
            let dashes: &[(i32, i32)] = if st.dashed {
                &[(0, 9), (17, 26)]
            } else {
                &[(0, 26)]
            };
            for (a, b) in dashes {
                let stroke = st.color.stroke_width(2);
                area.draw(&PathElement::new(vec![(x + a, y), (x + b, y)], stroke))
                    .map_err(Error::plot(path))?;
            }
        }
        draw_markers(path, area, [(x + 13, y)], st)?;
        area.draw_text(&s.series.label, &font, (x + 34, y - 9))
            .map_err(Error::plot(path))?;
    }
    for (k, h) in panel.hlines.iter().enumerate() {
        let (x, y) = at(panel.series.len() + k);
        let stroke = BLACK.mix(0.6).stroke_width(1);
        for (a, b) in [(0, 8), (12, 20), (24, 26)] {
            area.draw(&PathElement::new(vec![(x + a, y), (x + b, y)], stroke))
                .map_err(Error::plot(path))?;
        }
        area.draw_text(&h.label, &font, (x + 34, y - 9))
            .map_err(Error::plot(path))?;
    }
    Ok(())
}

/// Draws `st`'s marker at each of `at` on `area`: filled in its colour, or white inside its
/// outline where hollow.
fn draw_markers<DB: DrawingBackend, CT: CoordTranslate>(
    path: &Path,
    area: &DrawingArea<DB, CT>,
    at: impl IntoIterator<Item = CT::From>,
    st: Style,
) -> PlotResult
where
    CT::From: Clone,
{
    let shape = outline(st.marker, 6.0);
    let mut closed = shape.clone();
    closed.push(shape[0]);
    let fill = if st.hollow { WHITE } else { st.color };
    for p in at {
        area.draw(&(EmptyElement::at(p.clone()) + Polygon::new(shape.clone(), fill.filled())))
            .map_err(Error::plot(path))?;
        if st.hollow {
            let stroke = st.color.stroke_width(2);
            area.draw(&(EmptyElement::at(p) + PathElement::new(closed.clone(), stroke)))
                .map_err(Error::plot(path))?;
        }
    }
    Ok(())
}

/// The outline of a marker of radius `r` around (0, 0), in pixels.
fn outline(m: Marker, r: f64) -> Vec<(i32, i32)> {
    let poly = |n: usize, phase: f64, radius: f64| -> Vec<(i32, i32)> {
        (0..n)
            .map(|k| {
                let a = phase + std::f64::consts::TAU * k as f64 / n as f64;
                (
                    (radius * a.cos()).round() as i32,
                    (-radius * a.sin()).round() as i32,
                )
            })
            .collect()
    };
    use std::f64::consts::FRAC_PI_2;
    match m {
        Marker::Circle => poly(16, 0.0, r),
        Marker::Square => poly(4, FRAC_PI_2 / 2.0, r * 1.2),
        Marker::Diamond => poly(4, 0.0, r * 1.25),
        Marker::Up => poly(3, FRAC_PI_2, r * 1.3),
        Marker::Down => poly(3, -FRAC_PI_2, r * 1.3),
        Marker::Cross => {
            let (a, b) = ((r * 0.38).round() as i32, (r * 1.15).round() as i32);
            vec![
                (-a, -b),
                (a, -b),
                (a, -a),
                (b, -a),
                (b, a),
                (a, a),
                (a, b),
                (-a, b),
                (-a, a),
                (-b, a),
                (-b, -a),
                (-a, -a),
            ]
        }
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

    fn axes(log_x: bool, log_y: bool) -> Axes {
        Axes {
            log_x,
            log_y,
            ..Axes::new("error against time", "estimate time, s", "RMS (0-255)")
        }
    }

    #[test]
    fn plots_write_decodable_pngs_of_the_expected_size() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("pareto.png");
        let s = vec![Series::line(
            "field",
            vec![(0.01, 2.0), (0.1, 1.0), (1.0, 0.5)],
        )];
        let floor = HLine {
            label: "floor".into(),
            y: 0.3,
        };
        xy_plot(&p, &axes(true, false), &s, &[floor]).unwrap();
        let img = image::open(&p).unwrap();
        assert_eq!(img.width(), 1000);
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

    #[test]
    fn panels_share_one_figure_two_to_a_row() {
        let dir = tempfile::tempdir().unwrap();
        let panel = |t: &str, k: usize| {
            let series = (0..k).map(|i| {
                let points = vec![(1.0 + i as f64, 2.0), (3.0, 0.5 + i as f64)];
                Series::line(format!("s{i}"), points).styled(Style::palette(i).hollow())
            });
            Panel::new(t, series.collect())
        };
        let fig = Figure {
            axes: axes(true, true),
            panels: vec![panel("a", 3), panel("b", 8), panel("c", 1)],
            notes: vec!["a note".into()],
        };
        let p = dir.path().join("f.png");
        figure_plot(&p, &fig).unwrap();
        let img = image::open(&p).unwrap();
        let layout = Layout::of(&fig);
        // Three panels: two columns, two rows.
        assert_eq!(layout.cols, 2);
        assert_eq!((img.width(), img.height()), layout.size(3));
        assert_eq!(img.width(), 2 * layout.panel_w);
        // The legend has room for the fullest panel's 8 entries, two to a row.
        assert_eq!(layout.legend_h, 4 * LEGEND_ROW + 12);
    }

    #[test]
    fn markers_are_closed_shapes_of_about_their_radius() {
        for m in [
            Marker::Circle,
            Marker::Square,
            Marker::Up,
            Marker::Down,
            Marker::Diamond,
            Marker::Cross,
        ] {
            let o = outline(m, 6.0);
            assert!(o.len() >= 3, "{m:?}");
            let r = o
                .iter()
                .map(|&(x, y)| ((x * x + y * y) as f64).sqrt())
                .fold(0.0, f64::max);
            assert!((5.0..=9.0).contains(&r), "{m:?}: {r}");
        }
    }

    #[test]
    fn notes_wrap_at_spaces() {
        assert_eq!(wrap("aa bb cc", 5), ["aa bb", "cc"]);
        assert_eq!(wrap("aaaaaaa b", 3), ["aaaaaaa", "b"]);
        assert_eq!(wrap("short", 80), ["short"]);
    }

    #[test]
    fn log_ranges_span_a_factor_of_three_at_least() {
        let (lo, hi) = range([2.0, 2.0].into_iter(), true);
        assert!(hi / lo >= 3.0 - 1e-9 && lo < 2.0 && hi > 2.0);
        let (lo, hi) = range([0.01, 10.0, -1.0, f64::NAN].into_iter(), true);
        assert!((lo - 0.008).abs() < 1e-12 && (hi - 12.5).abs() < 1e-9);
    }
}
