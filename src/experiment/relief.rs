//! `experiment relief`: the 2005 paper's Tables 1–3 (Kolb and Rezk-Salama, VMV 2005) on the
//! CPU: per-pixel displacement mapping of three maps, with 0, 1 and 2 safety-zone skips, over
//! viewing angles, sample rates and bisection counts; every image compared with the exact
//! intersection of the bilinear surface.
//!
//! Writes `table.csv` (one row per rendering), `paper_vs_ours.csv` (the paper's frame-rate
//! gains from skipping beside ours in time and in texture fetches), plots (fetches and time
//! against viewing angle, error against time), an image grid and `run.json`.
//!
//! With an adapter (lavapipe or a GPU; `--no-gpu` to skip) every setting also runs on the
//! GPU caster (`gpu::ReliefKernel`) and its frame is compared with the CPU's (`gpu_*` columns).
//!
//! Deviation from the paper: frame rates on a 2005 GPU become CPU seconds per frame and texture
//! fetches per pixel (the cost the skips remove, independent of the machine); images are 256²
//! (the paper's 512²); the "angel" map is replaced by the procedural `relief` map.

use super::plot::{image_grid, xy_plot, Axes, Series};
use super::{Error, Result, ResultExt};
use crate::experiment::metrics::rms_u8;
use crate::gpu::{AdapterPreference, GpuContext, GpuError, ReliefKernel};
use crate::relief::view::{render, render_gpu, ReliefFrame, View};
use crate::relief::{CastParams, Dataset, SafetyZones, PAPER_BOXES};
use crate::render::image::GrayImage;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// Displacement-map resolution.
pub const MAP_RES: usize = 256;
/// The viewing angles of Table 2 (degrees from the normal).
pub const ANGLES: [f32; 6] = [0.0, 15.0, 30.0, 45.0, 60.0, 75.0];

/// One rendering.
#[derive(Clone, Debug, Serialize)]
pub struct ReliefRow {
    /// `angles` (Tables 1–2) or `rates` (Table 3).
    pub table: &'static str,
    pub dataset: &'static str,
    pub view_deg: f32,
    pub samples_per_unit: f32,
    pub bisections: u32,
    pub skips: u32,
    /// Pixels whose ray enters the prism.
    pub pixels: usize,
    /// Mean texture fetches per entering pixel (height samples + four-channel zone reads).
    pub fetches_per_pixel: f64,
    /// Fastest of the timed renders, seconds (CPU, all threads).
    pub time_s: f64,
    /// RMS (0–255) of the shaded image against the exact intersection's, over pixels hit by
    /// either.
    pub rms_vs_exact: f64,
    /// Pixels hit by one and missed by the other.
    pub hit_mismatches: usize,
    /// Time and fetches relative to the same settings without skips.
    pub time_speedup: f64,
    pub fetch_reduction: f64,
    /// The GPU caster on the same segments (empty where no adapter ran): adapter and driver,
    /// fastest kernel time (GPU timestamps) and wall time (upload, dispatch, read-back; the
    /// host's shading excluded), fetches per entering pixel, and the frame against the CPU's:
    /// pixels hit by one only, RMS (0–255) over pixels hit by either. On lavapipe the times are
    /// parity evidence, not speed.
    pub gpu_adapter: Option<String>,
    pub gpu_kernel_s: Option<f64>,
    pub gpu_wall_s: Option<f64>,
    pub gpu_fetches_per_pixel: Option<f64>,
    pub gpu_hit_mismatches_vs_cpu: Option<usize>,
    pub gpu_rms_vs_cpu: Option<f64>,
    /// GPU kernel time relative to the same settings without skips (the paper's frame-rate
    /// gain, where the adapter is a GPU).
    pub gpu_time_speedup: Option<f64>,
}

/// The GPU columns of a [`ReliefRow`].
#[derive(Clone, Debug, Default)]
struct GpuCells {
    adapter: Option<String>,
    kernel_s: Option<f64>,
    wall_s: Option<f64>,
    fetches_per_pixel: Option<f64>,
    hit_mismatches_vs_cpu: Option<usize>,
    rms_vs_cpu: Option<f64>,
}

/// What [`measure`] found for one setting.
struct Measured {
    time_s: f64,
    fetches_per_pixel: f64,
    pixels: usize,
    rms_vs_exact: f64,
    hit_mismatches: usize,
    gpu: GpuCells,
}

/// The paper's frame rates (fps) for 0, 1 and 2 skips: Table 1 (75 samples per unit, two
/// views) and Table 2 (angel, by viewing angle).
const PAPER_TABLE1: [(&str, &str, [f64; 3]); 6] = [
    ("simple", "perpendicular", [15.0, 20.0, 20.0]),
    ("simple", "tangential", [57.0, 59.0, 55.0]),
    ("angel", "perpendicular", [14.9, 20.0, 20.0]),
    ("angel", "tangential", [29.9, 30.0, 30.0]),
    ("spikes", "perpendicular", [10.0, 20.0, 15.0]),
    ("spikes", "tangential", [30.0, 30.0, 30.0]),
];
const PAPER_TABLE2: [(f32, [f64; 3]); 6] = [
    (0.0, [15.0, 20.0, 20.0]),
    (15.0, [15.0, 20.0, 20.0]),
    (30.0, [15.0, 20.0, 20.0]),
    (45.0, [15.0, 20.0, 20.0]),
    (60.0, [20.0, 30.0, 30.0]),
    (75.0, [30.0, 30.0, 30.0]),
];
/// Table 3: (samples per unit, bisections, skips, fps), close-up of the angel map.
const PAPER_TABLE3: [(f32, u32, u32, f64); 8] = [
    (10.0, 0, 0, 30.0),
    (10.0, 2, 0, 30.0),
    (40.0, 2, 0, 15.0),
    (40.0, 2, 1, 19.6),
    (40.0, 2, 2, 19.9),
    (75.0, 2, 0, 10.0),
    (75.0, 2, 1, 12.0),
    (75.0, 2, 2, 15.0),
];

/// A row of `paper_vs_ours.csv`: the gain of `skips` over none, the paper's in frame rate,
/// ours in time and in fetches.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    pub paper_table: &'static str,
    pub case: String,
    pub skips: u32,
    pub paper_fps_gain: f64,
    pub our_time_gain: f64,
    pub our_fetch_gain: f64,
    /// In GPU kernel time (empty without an adapter; lavapipe's is a CPU's).
    pub our_gpu_time_gain: Option<f64>,
}

fn view(angle: f32, size: u32, close_up: bool) -> View {
    View {
        angle_deg: angle,
        distance: if close_up { 0.9 } else { 1.6 },
        fov_deg: 40.0,
        width: size,
        height: size,
    }
}

/// Mean fetches over the pixels whose ray entered the prism (those with at least one fetch),
/// and their count.
fn fetches_per_entering_pixel(f: &ReliefFrame) -> (f64, usize) {
    let entering: Vec<u32> = f.fetches.iter().copied().filter(|&c| c > 0).collect();
    let mean = entering.iter().map(|&c| c as f64).sum::<f64>() / entering.len().max(1) as f64;
    (mean, entering.len())
}

/// RMS (0–255) of `a` against `b` over the pixels hit by either, and the pixels hit by one only.
fn compare_frames(a: &ReliefFrame, b_image: &GrayImage, b_hit: &[bool]) -> (f64, usize) {
    let mask: Vec<bool> = a.hit.iter().zip(b_hit).map(|(x, y)| *x || *y).collect();
    let rms = rms_u8(&a.image.data, &b_image.data, Some(&mask));
    let mismatches = a.hit.iter().zip(b_hit).filter(|(x, y)| x != y).count();
    (rms, mismatches)
}

/// Renders one setting `repeats` times (the fastest time kept) and measures it against `exact`;
/// with `gpu`, renders it there as often and compares the GPU frame with the CPU's.
fn measure(
    map: &crate::relief::HeightMap,
    zones: &SafetyZones,
    v: &View,
    p: &CastParams,
    exact: &(GrayImage, Vec<bool>),
    repeats: usize,
    gpu: Option<(&ReliefKernel, &str)>,
) -> Result<Measured> {
    let mut best = f64::INFINITY;
    let mut frame = None;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let f = render(map, Some(zones), v, Some(p));
        best = best.min(t.elapsed().as_secs_f64());
        frame = Some(f);
    }
    let f = frame.expect("rendered once");
    let (fetches, pixels) = fetches_per_entering_pixel(&f);
    let (rms, mismatches) = compare_frames(&f, &exact.0, &exact.1);
    let mut cells = GpuCells::default();
    if let Some((kernel, adapter)) = gpu {
        let (mut kernel_s, mut wall_s) = (None::<f64>, f64::INFINITY);
        let mut gpu_frame = None;
        // At least twice: the first dispatch of a kernel also pays its driver-side compile.
        for _ in 0..repeats.max(2) {
            let (g, timing) = render_gpu(kernel, map, v, p).context(|| "relief".into())?;
            if let Some(k) = timing.kernel {
                let k = k.as_secs_f64();
                kernel_s = Some(kernel_s.map_or(k, |b| b.min(k)));
            }
            wall_s = wall_s.min(timing.wall.as_secs_f64());
            gpu_frame = Some(g);
        }
        let g = gpu_frame.expect("rendered once");
        let (rms_vs_cpu, mismatches_vs_cpu) = compare_frames(&g, &f.image, &f.hit);
        cells = GpuCells {
            adapter: Some(adapter.to_string()),
            kernel_s,
            wall_s: Some(wall_s),
            fetches_per_pixel: Some(fetches_per_entering_pixel(&g).0),
            hit_mismatches_vs_cpu: Some(mismatches_vs_cpu),
            rms_vs_cpu: Some(rms_vs_cpu),
        };
    }
    Ok(Measured {
        time_s: best,
        fetches_per_pixel: fetches,
        pixels,
        rms_vs_exact: rms,
        hit_mismatches: mismatches,
        gpu: cells,
    })
}

/// The GPU device for the relief columns: `None` when not asked for, or (with a note) when
/// no Vulkan driver is installed and no adapter was named (`Auto`); an adapter asked for by
/// name or kind that cannot be had is an error, as it is for a spec's "gpu" rows.
fn gpu_context(pref: Option<AdapterPreference>) -> Result<Option<GpuContext>> {
    let Some(pref) = pref else { return Ok(None) };
    let fallback = matches!(pref, AdapterPreference::Auto);
    match GpuContext::new(pref) {
        Ok(c) => Ok(Some(c)),
        Err(GpuError::NoAdapter) if fallback => {
            eprintln!(
                "relief: no Vulkan adapter, GPU columns left empty ({})",
                GpuError::NoAdapter
            );
            Ok(None)
        }
        Err(e) => Err(Error::Gpu(e).context("relief")),
    }
}

/// Runs the tables at `size`² pixels (`quick`: 64², one timing) and writes `out/`; with `gpu`,
/// every setting also runs on that adapter (the `gpu_*` columns).
pub fn run(out: &Path, quick: bool, gpu: Option<AdapterPreference>) -> Result<Vec<ReliefRow>> {
    crate::experiment::run::ensure_writable(out)?;
    let mut meta = crate::experiment::meta::RunMeta::collect(None);
    let ctx = gpu_context(gpu)?;
    let adapter = ctx.as_ref().map(|c| c.adapter_label());
    meta.gpu_adapter = adapter.clone();
    let (size, repeats) = if quick { (64, 1) } else { (256, 3) };
    let mut rows: Vec<ReliefRow> = Vec::new();
    let mut grid: Vec<(GrayImage, Vec<String>)> = Vec::new();
    let push = |rows: &mut Vec<ReliefRow>, mut r: ReliefRow| {
        if let Some(base) = rows.iter().rev().find(|b| {
            b.skips == 0
                && (
                    b.table,
                    b.dataset,
                    b.view_deg,
                    b.samples_per_unit,
                    b.bisections,
                ) == (
                    r.table,
                    r.dataset,
                    r.view_deg,
                    r.samples_per_unit,
                    r.bisections,
                )
        }) {
            r.time_speedup = base.time_s / r.time_s;
            r.fetch_reduction = base.fetches_per_pixel / r.fetches_per_pixel;
            r.gpu_time_speedup = base.gpu_kernel_s.zip(r.gpu_kernel_s).map(|(b, t)| b / t);
        }
        rows.push(r);
    };
    for dset in Dataset::ALL {
        let map = dset.map(MAP_RES);
        let zones = SafetyZones::new(&map, &PAPER_BOXES);
        let kernel = match &ctx {
            Some(c) => Some(ReliefKernel::new(c, &map, &zones).context(|| "relief".into())?),
            None => None,
        };
        let gpu = kernel.as_ref().zip(adapter.as_deref());
        let mut run_table = |table: &'static str,
                             angles: &[f32],
                             settings: &[(f32, u32)],
                             close_up: bool,
                             rows: &mut Vec<ReliefRow>|
         -> Result<()> {
            for &angle in angles {
                let v = view(angle, size, close_up);
                let ex = render(&map, None, &v, None);
                let exact = (ex.image, ex.hit);
                for &(rate, bisections) in settings {
                    for skips in 0..=2 {
                        let p = CastParams {
                            samples_per_unit: rate,
                            bisections,
                            skips,
                        };
                        let m = measure(&map, &zones, &v, &p, &exact, repeats, gpu)?;
                        let gpu_note = match (m.gpu.kernel_s, m.gpu.hit_mismatches_vs_cpu) {
                            (Some(k), Some(d)) => {
                                format!("; GPU kernel {k:.4} s, {d} pixel(s) differ")
                            }
                            (None, Some(d)) => format!("; GPU {d} pixel(s) differ"),
                            _ => String::new(),
                        };
                        eprintln!(
                            "relief: {table} {} {angle}° rate {rate} bisections {bisections} \
                             skips {skips}: {:.1} fetches/pixel, {:.4} s, RMS {:.2}{gpu_note}",
                            dset.name(),
                            m.fetches_per_pixel,
                            m.time_s,
                            m.rms_vs_exact,
                        );
                        push(
                            rows,
                            ReliefRow {
                                table,
                                dataset: dset.name(),
                                view_deg: angle,
                                samples_per_unit: rate,
                                bisections,
                                skips,
                                pixels: m.pixels,
                                fetches_per_pixel: m.fetches_per_pixel,
                                time_s: m.time_s,
                                rms_vs_exact: m.rms_vs_exact,
                                hit_mismatches: m.hit_mismatches,
                                time_speedup: 1.0,
                                fetch_reduction: 1.0,
                                gpu_adapter: m.gpu.adapter,
                                gpu_kernel_s: m.gpu.kernel_s,
                                gpu_wall_s: m.gpu.wall_s,
                                gpu_fetches_per_pixel: m.gpu.fetches_per_pixel,
                                gpu_hit_mismatches_vs_cpu: m.gpu.hit_mismatches_vs_cpu,
                                gpu_rms_vs_cpu: m.gpu.rms_vs_cpu,
                                gpu_time_speedup: m.gpu.kernel_s.map(|_| 1.0),
                            },
                        );
                    }
                }
                if table == "angles" && angle == 60.0 {
                    grid.push((exact.0.clone(), vec![format!("{} 60°: exact", dset.name())]));
                }
            }
            Ok(())
        };
        run_table("angles", &ANGLES, &[(75.0, 2)], false, &mut rows)?;
        if dset == Dataset::Relief {
            let settings = [(10.0, 0), (10.0, 2), (40.0, 2), (75.0, 2), (75.0, 0)];
            run_table("rates", &[45.0], &settings, true, &mut rows)?;
        }
    }
    super::outputs::write_csv(&out.join("table.csv"), &rows)?;
    super::outputs::write_csv(&out.join("paper_vs_ours.csv"), &compare(&rows))?;
    plots(out, &rows, size)?;
    let cells: Vec<(&GrayImage, Vec<String>)> = grid.iter().map(|(i, c)| (i, c.clone())).collect();
    image_grid(
        &out.join("images.png"),
        "exact intersection, 60°",
        &cells,
        3,
    )?;
    let json = out.join("run.json");
    crate::io::write_atomic(&json, meta.to_json().as_bytes()).map_err(Error::io(&json))?;
    println!("relief: {} row(s) -> {}", rows.len(), out.display());
    Ok(rows)
}

/// The paper's gains beside ours (its "angel" against our `relief`; its perpendicular and
/// tangential views against our 0° and 75°).
fn compare(rows: &[ReliefRow]) -> Vec<Comparison> {
    let find = |table: &str, d: &str, angle: f32, rate: f32, b: u32, skips: u32| {
        rows.iter().find(|r| {
            (
                r.table,
                r.dataset,
                r.view_deg,
                r.samples_per_unit,
                r.bisections,
                r.skips,
            ) == (table, d, angle, rate, b, skips)
        })
    };
    fn ours(d: &'static str) -> &'static str {
        if d == "angel" {
            "relief"
        } else {
            d
        }
    }
    let mut out = Vec::new();
    for (d, v, fps) in PAPER_TABLE1 {
        let angle = if v == "perpendicular" { 0.0 } else { 75.0 };
        for skips in 1..=2u32 {
            if let Some(r) = find("angles", ours(d), angle, 75.0, 2, skips) {
                out.push(Comparison {
                    paper_table: "1",
                    case: format!("{d} {v} (ours: {} {angle}°)", ours(d)),
                    skips,
                    paper_fps_gain: fps[skips as usize] / fps[0],
                    our_time_gain: r.time_speedup,
                    our_fetch_gain: r.fetch_reduction,
                    our_gpu_time_gain: r.gpu_time_speedup,
                });
            }
        }
    }
    for (angle, fps) in PAPER_TABLE2 {
        for skips in 1..=2u32 {
            if let Some(r) = find("angles", "relief", angle, 75.0, 2, skips) {
                out.push(Comparison {
                    paper_table: "2",
                    case: format!("angel {angle}° (ours: relief)"),
                    skips,
                    paper_fps_gain: fps[skips as usize] / fps[0],
                    our_time_gain: r.time_speedup,
                    our_fetch_gain: r.fetch_reduction,
                    our_gpu_time_gain: r.gpu_time_speedup,
                });
            }
        }
    }
    for (rate, b, skips, fps) in PAPER_TABLE3.into_iter().filter(|c| c.2 > 0) {
        let base = PAPER_TABLE3
            .iter()
            .find(|c| (c.0, c.1, c.2) == (rate, b, 0))
            .map(|c| c.3);
        if let (Some(base), Some(r)) = (base, find("rates", "relief", 45.0, rate, b, skips)) {
            out.push(Comparison {
                paper_table: "3",
                case: format!("angel close-up, {rate} samples, {b} bisections (ours: relief 45°)"),
                skips,
                paper_fps_gain: fps / base,
                our_time_gain: r.time_speedup,
                our_fetch_gain: r.fetch_reduction,
                our_gpu_time_gain: r.gpu_time_speedup,
            });
        }
    }
    out
}

fn plots(out: &Path, rows: &[ReliefRow], size: u32) -> Result<()> {
    let series = |f: &dyn Fn(&ReliefRow) -> f64| -> Vec<Series> {
        let mut s = Vec::new();
        for d in Dataset::ALL {
            for skips in 0..=2u32 {
                s.push(Series {
                    label: format!("{} · {skips} skip(s)", d.name()),
                    points: rows
                        .iter()
                        .filter(|r| {
                            r.table == "angles" && r.dataset == d.name() && r.skips == skips
                        })
                        .map(|r| (r.view_deg as f64, f(r)))
                        .collect(),
                    line: true,
                });
            }
        }
        s
    };
    let axes = |title: &str, y: &str| Axes {
        title: title.into(),
        x_label: "viewing angle from the normal (degrees)".into(),
        y_label: y.into(),
        log_x: false,
        log_y: false,
    };
    xy_plot(
        &out.join("fetches_vs_angle.png"),
        &axes(
            "Texture fetches per pixel (Table 2's setting: 75 samples/unit, 2 bisections)",
            "fetches per pixel",
        ),
        &series(&|r| r.fetches_per_pixel),
        &[],
    )?;
    xy_plot(
        &out.join("time_vs_angle.png"),
        &axes(&format!("CPU time per {size}² frame"), "seconds"),
        &series(&|r| r.time_s),
        &[],
    )?;
    let angle_rows = rows.iter().filter(|r| r.table == "angles");
    if let Some(adapter) = angle_rows.clone().find_map(|r| r.gpu_adapter.as_deref()) {
        if angle_rows.clone().all(|r| r.gpu_kernel_s.is_some()) {
            let name = adapter.split(" | ").next().unwrap_or(adapter);
            let note = if name.contains("llvmpipe") {
                ": a CPU, parity not speed"
            } else {
                ""
            };
            xy_plot(
                &out.join("gpu_time_vs_angle.png"),
                &axes(
                    &format!("GPU kernel time per {size}² frame ({name}{note})"),
                    "seconds",
                ),
                &series(&|r| r.gpu_kernel_s.unwrap_or(f64::NAN)),
                &[],
            )?;
        }
    }
    let pareto: Vec<Series> = (0..=2u32)
        .map(|skips| Series {
            label: format!("relief 45° close-up · {skips} skip(s)"),
            points: rows
                .iter()
                .filter(|r| r.table == "rates" && r.skips == skips)
                .map(|r| (r.time_s, r.rms_vs_exact))
                .collect(),
            line: false,
        })
        .collect();
    xy_plot(
        &out.join("pareto.png"),
        &Axes {
            title: "Error against time (Table 3's settings; RMS vs the exact intersection)".into(),
            x_label: "seconds per frame".into(),
            y_label: "RMS (0–255)".into(),
            log_x: true,
            log_y: false,
        },
        &pareto,
        &[],
    )
}
