//! `experiment relief`: the 2005 paper's Tables 1–3 (Kolb and Rezk-Salama, VMV 2005) on the
//! CPU: per-pixel displacement mapping of five maps, with 0, 1 and 2 safety-zone skips, over
//! viewing angles, sample rates and bisection counts; every image compared with the exact
//! intersection of the bilinear surface.
//!
//! Writes `renderings.csv` (one row per rendering and method; the pixels split into those whose ray
//! meets the surface, those whose ray leaves without meeting it and those culled at the entry,
//! each with its count and mean fetches), `paper_vs_ours.csv` (the paper's frame-rate gains
//! from skipping beside ours in time and in fetches over the surface pixels), plots (fetches
//! and time against viewing angle, error against angle and samples per unit, error against
//! time), image grids (the exact images at 60°; the paper's quality figures: samples per unit
//! × skips at 75° with difference images against the exact intersection) and `run.json`.
//!
//! Tables (`table` column): `angles` (Tables 1–2: every map, six angles, 75 samples per unit,
//! 2 bisections, the paper's δ and, for 1–2 skips, half of it), `rates` (Table 3: `relief`'s
//! close-up at 45°) and `quality` (the thin-spike and noise maps at 75° over samples per unit).
//! The `method` column names the caster (`paper-skips`: [`crate::relief::intersect`]); the
//! `angles` table also holds the modern peers' rows ([`peers`]: `cell-walk`, `max-mip`,
//! `cone-N`, `relaxed-N+B`; `skips` 0, `delta_rule` empty, a cone's steps in
//! `samples_per_unit` and its bisections in `bisections`, their structures' build time in
//! `setup_s`), plotted with the paper's search as error against fetches and against time.
//!
//! With an adapter (lavapipe or a GPU; `--no-gpu` to skip) every setting also runs on the
//! GPU caster (`gpu::ReliefKernel`) and its frame is compared with the CPU's (`gpu_*` columns).
//!
//! Deviation from the paper: frame rates on a 2005 GPU become CPU seconds per frame and texture
//! fetches per pixel (the cost the skips remove, independent of the machine); images are 256²
//! (the paper's 512²) from a distant eye ([`View`]); the "angel" map is replaced by the
//! procedural `relief` map.

mod paper;
pub mod peers;
mod plots;
mod score;

pub use paper::Comparison;
pub use peers::PEERS;
pub use score::{populations, score, Population, Scores, Tally, OFF_TEXELS};

use super::{Error, Result, ResultExt};
use crate::gpu::{
    AdapterPreference, GpuContext, GpuError, GpuTiming, ReliefKernel, ReliefPeersKernel,
};
use crate::relief::peers::PeerData;
use crate::relief::view::{render, render_gpu, ReliefFrame, View};
use crate::relief::{CastParams, Dataset, DeltaRule, HeightMap, SafetyZones, PAPER_BOXES};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// Displacement-map resolution.
pub const MAP_RES: usize = 256;
/// The viewing angles of Table 2 (degrees from the normal).
pub const ANGLES: [f32; 6] = [0.0, 15.0, 30.0, 45.0, 60.0, 75.0];
/// The `method` of this caster's rows.
pub const METHOD: &str = "paper-skips";
/// Table 3's (samples per unit, bisections) on `relief`'s close-up at 45°.
pub const RATE_SETTINGS: [(f32, u32); 5] = [(10.0, 0), (10.0, 2), (40.0, 2), (75.0, 2), (75.0, 0)];
/// The `quality` table: maps, grazing angle and samples per unit (2 bisections).
pub const QUALITY_DATASETS: [Dataset; 3] = [Dataset::Spikes, Dataset::Needles, Dataset::Noise];
pub const QUALITY_ANGLE: f32 = 75.0;
pub const QUALITY_RATES: [f32; 5] = [10.0, 20.0, 40.0, 75.0, 150.0];

/// One rendering.
#[derive(Clone, Debug, Serialize)]
pub struct ReliefRow {
    /// `angles` (Tables 1–2), `rates` (Table 3) or `quality` (samples per unit at 75°).
    pub table: &'static str,
    /// The caster: `paper-skips` (the 2005 search) or a peer (`cell-walk`, `max-mip`,
    /// `cone-N`, `relaxed-N+B`).
    pub method: &'static str,
    pub dataset: &'static str,
    /// The view's angle from the normal in the world, and its rays' angle in prism
    /// coordinates (the prism [`crate::relief::view::DEPTH`] as high as wide).
    pub view_deg: f32,
    pub prism_deg: f32,
    /// Linear-search samples per unit length (a cone method's steps).
    pub samples_per_unit: f32,
    pub bisections: u32,
    pub skips: u32,
    /// δ of the zones: `paper` (the box size) or `half` (half of it); `paper` on 0-skip rows,
    /// which read no zone.
    pub delta_rule: &'static str,
    /// Pixels whose ray enters the prism, and their mean texture fetches (height samples and
    /// zone-map reads).
    pub pixels: usize,
    pub fetches_per_pixel: f64,
    /// Of those, the pixels whose ray meets the surface (by the exact intersection) and their
    /// mean fetches: the population the skip question is about.
    pub surface_pixels: usize,
    pub surface_fetches: f64,
    /// The pixels whose ray leaves the prism without meeting the surface, and their mean.
    pub no_hit_pixels: usize,
    pub no_hit_fetches: f64,
    /// The pixels whose ray enters below the surface (discarded, one fetch), and their mean.
    pub culled_pixels: usize,
    pub culled_fetches: f64,
    /// Fastest of the timed renders, seconds (CPU, all threads).
    pub time_s: f64,
    /// Build time of what the method reads besides the map (the peers' max mip or cone
    /// maps), seconds; empty for the paper's search.
    pub setup_s: Option<f64>,
    /// RMS (0–255) of the shaded image against the exact intersection's, over pixels hit by
    /// either.
    pub rms_vs_exact: f64,
    /// Pixels hit by one and missed by the other.
    pub hit_mismatches: usize,
    /// Share of the surface pixels missed or hit more than 2 texel widths from the exact hit.
    pub missed_share: f64,
    /// RMS distance of the found hits from the exact ones along the ray, texel widths.
    pub hit_rms_texels: f64,
    /// Time relative to the same settings without skips.
    pub time_speedup: f64,
    /// Mean fetches over the surface pixels, without skips over with.
    pub surface_fetch_reduction: f64,
    /// Mean fetches over all entering pixels, without skips over with.
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
    /// Build time of what the method reads besides the map (the peers' mips and cone maps).
    setup_s: Option<f64>,
    scores: Scores,
    gpu: GpuCells,
}

/// The exact frame of a view and its pixels' populations.
pub struct Reference {
    pub frame: ReliefFrame,
    pub populations: Vec<Population>,
}

impl Reference {
    /// The exact intersection of `view` on `map`.
    pub fn new(map: &HeightMap, view: &View) -> Reference {
        let frame = render(map, None, view, None);
        let populations = populations(map, view, &frame);
        Reference { frame, populations }
    }
}

/// Pixels hit by one frame only, and the RMS (0–255) over pixels hit by either.
fn compare_frames(a: &ReliefFrame, b: &ReliefFrame) -> (usize, f64) {
    let mask: Vec<bool> = a.hit.iter().zip(&b.hit).map(|(x, y)| *x || *y).collect();
    let rms = crate::experiment::metrics::rms_u8(&a.image.data, &b.image.data, Some(&mask));
    (
        a.hit.iter().zip(&b.hit).filter(|(x, y)| x != y).count(),
        rms,
    )
}

/// Mean fetches over the pixels whose ray entered the prism (those with a fetch).
fn mean_entering_fetches(f: &ReliefFrame) -> f64 {
    let (n, sum) = f
        .fetches
        .iter()
        .filter(|&&c| c > 0)
        .fold((0usize, 0u64), |(n, s), &c| (n + 1, s + c as u64));
    sum as f64 / n.max(1) as f64
}

/// The GPU columns of a setting: `render` run `repeats` times (at least twice: the first
/// dispatch of a kernel also pays its driver-side compile), the fastest kernel and wall times
/// kept, and the last frame compared with the CPU's `cpu`.
fn gpu_cells(
    adapter: &str,
    cpu: &ReliefFrame,
    repeats: usize,
    mut render: impl FnMut() -> Result<(ReliefFrame, GpuTiming)>,
) -> Result<GpuCells> {
    let (mut kernel_s, mut wall_s, mut frame) = (None::<f64>, f64::INFINITY, None);
    for _ in 0..repeats.max(2) {
        let (g, timing) = render()?;
        if let Some(k) = timing.kernel {
            let k = k.as_secs_f64();
            kernel_s = Some(kernel_s.map_or(k, |b| b.min(k)));
        }
        wall_s = wall_s.min(timing.wall.as_secs_f64());
        frame = Some(g);
    }
    let g = frame.expect("rendered at least twice");
    let (mismatches, rms) = compare_frames(&g, cpu);
    Ok(GpuCells {
        adapter: Some(adapter.to_string()),
        kernel_s,
        wall_s: Some(wall_s),
        fetches_per_pixel: Some(mean_entering_fetches(&g)),
        hit_mismatches_vs_cpu: Some(mismatches),
        rms_vs_cpu: Some(rms),
    })
}

/// Renders one setting of `pass` `repeats` times with `cpu` (the fastest time kept) and scores
/// it against the pass's reference; with `gpu` (its adapter and its render), renders it there as
/// often and compares the GPU frame with the CPU's.
fn measure(
    pass: &Pass,
    repeats: usize,
    mut cpu: impl FnMut() -> Result<ReliefFrame>,
    gpu: Option<(&str, impl FnMut() -> Result<(ReliefFrame, GpuTiming)>)>,
) -> Result<Measured> {
    let mut best = f64::INFINITY;
    let mut frame = None;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let f = cpu()?;
        best = best.min(t.elapsed().as_secs_f64());
        frame = Some(f);
    }
    let f = frame.expect("rendered once");
    let reference = &pass.reference;
    let scores = score(&f, &reference.frame, &reference.populations, pass.map.width);
    let cells = match gpu {
        Some((adapter, render)) => gpu_cells(adapter, &f, repeats, render)?,
        None => GpuCells::default(),
    };
    Ok(Measured {
        time_s: best,
        setup_s: None,
        scores,
        gpu: cells,
    })
}

/// The GPU device of a run's GPU columns or rows (`what`: the run, for the error's context):
/// `None` when not asked for, or (with the note `left_out`) when no Vulkan driver is installed
/// and no adapter was named (`Auto`); an adapter asked for by name or kind that cannot be had
/// is an error, as it is for a spec's "gpu" rows.
pub(crate) fn gpu_context(
    pref: Option<AdapterPreference>,
    what: &str,
    left_out: &str,
) -> Result<Option<GpuContext>> {
    let Some(pref) = pref else { return Ok(None) };
    let fallback = matches!(pref, AdapterPreference::Auto);
    match GpuContext::new(pref) {
        Ok(c) => Ok(Some(c)),
        Err(GpuError::NoAdapter) if fallback => {
            eprintln!("{left_out}");
            Ok(None)
        }
        Err(e) => Err(Error::Gpu(e).context(what)),
    }
}

/// One map's zones under a δ rule and, with an adapter, its GPU kernel.
struct Zoned<'a> {
    rule: DeltaRule,
    zones: SafetyZones,
    kernel: Option<ReliefKernel<'a>>,
}

/// The settings of one table pass over one map.
struct Pass<'a> {
    table: &'static str,
    dataset: Dataset,
    map: &'a HeightMap,
    view: View,
    reference: Reference,
}

impl<'a> Pass<'a> {
    /// The pass, with the exact reference of `view`.
    fn new(table: &'static str, dataset: Dataset, map: &'a HeightMap, view: View) -> Pass<'a> {
        let reference = Reference::new(map, &view);
        Pass {
            table,
            dataset,
            map,
            view,
            reference,
        }
    }
}

/// Appends `row`, its gains taken against the 0-skip row of the same table, method, map, view
/// and search settings.
fn push(rows: &mut Vec<ReliefRow>, mut r: ReliefRow) {
    let key = |r: &ReliefRow| {
        let search = (r.view_deg, r.samples_per_unit, r.bisections);
        (r.table, r.method, r.dataset, search)
    };
    if let Some(base) = rows
        .iter()
        .rev()
        .find(|b| b.skips == 0 && key(b) == key(&r))
    {
        r.time_speedup = base.time_s / r.time_s;
        r.surface_fetch_reduction = base.surface_fetches / r.surface_fetches;
        r.fetch_reduction = base.fetches_per_pixel / r.fetches_per_pixel;
        r.gpu_time_speedup = base.gpu_kernel_s.zip(r.gpu_kernel_s).map(|(b, t)| b / t);
    }
    rows.push(r);
}

/// What a row is of, besides its pass.
struct Setting {
    method: &'static str,
    samples_per_unit: f32,
    bisections: u32,
    skips: u32,
    delta_rule: &'static str,
}

/// The row of `pass` at `at`, measured `m` (gains 1 until [`push`] sets them).
fn row(pass: &Pass, at: &Setting, m: &Measured) -> ReliefRow {
    let s = &m.scores;
    ReliefRow {
        table: pass.table,
        method: at.method,
        dataset: pass.dataset.name(),
        view_deg: pass.view.angle_deg,
        prism_deg: (-pass.view.direction().z).acos().to_degrees(),
        samples_per_unit: at.samples_per_unit,
        bisections: at.bisections,
        skips: at.skips,
        delta_rule: at.delta_rule,
        pixels: s.all.pixels,
        fetches_per_pixel: s.all.mean_fetches,
        surface_pixels: s.surface.pixels,
        surface_fetches: s.surface.mean_fetches,
        no_hit_pixels: s.no_hit.pixels,
        no_hit_fetches: s.no_hit.mean_fetches,
        culled_pixels: s.culled.pixels,
        culled_fetches: s.culled.mean_fetches,
        time_s: m.time_s,
        setup_s: m.setup_s,
        rms_vs_exact: s.rms_vs_exact,
        hit_mismatches: s.hit_mismatches,
        missed_share: s.missed_share,
        hit_rms_texels: s.hit_rms_texels,
        time_speedup: 1.0,
        surface_fetch_reduction: 1.0,
        fetch_reduction: 1.0,
        gpu_adapter: m.gpu.adapter.clone(),
        gpu_kernel_s: m.gpu.kernel_s,
        gpu_wall_s: m.gpu.wall_s,
        gpu_fetches_per_pixel: m.gpu.fetches_per_pixel,
        gpu_hit_mismatches_vs_cpu: m.gpu.hit_mismatches_vs_cpu,
        gpu_rms_vs_cpu: m.gpu.rms_vs_cpu,
        gpu_time_speedup: m.gpu.kernel_s.map(|_| 1.0),
    }
}

/// Measures `pass` at `params` (every zone rule for 1+ skips, the first for none) and appends
/// the rows.
fn run_pass(
    pass: &Pass,
    zoned: &[Zoned],
    settings: &[(f32, u32)],
    repeats: usize,
    adapter: Option<&str>,
    rows: &mut Vec<ReliefRow>,
) -> Result<()> {
    for &(rate, bisections) in settings {
        for (z, skips) in zoned
            .iter()
            .enumerate()
            .flat_map(|(i, z)| (if i == 0 { 0 } else { 1 }..=2).map(move |s| (z, s)))
        {
            let p = CastParams {
                samples_per_unit: rate,
                bisections,
                skips,
            };
            let cpu = || Ok(render(pass.map, Some(&z.zones), &pass.view, Some(&p)));
            let gpu = z.kernel.as_ref().zip(adapter).map(|(kernel, adapter)| {
                let render = || render_gpu(kernel, pass.map, &pass.view, &p);
                (adapter, move || render().context(|| "relief".into()))
            });
            let m = measure(pass, repeats, cpu, gpu)?;
            let s = &m.scores;
            let gpu_note = match (m.gpu.kernel_s, m.gpu.hit_mismatches_vs_cpu) {
                (Some(k), Some(d)) => format!("; GPU kernel {k:.4} s, {d} pixel(s) differ"),
                (None, Some(d)) => format!("; GPU {d} pixel(s) differ"),
                _ => String::new(),
            };
            eprintln!(
                "relief: {} {} {}° rate {rate} bisections {bisections} skips {skips} δ {}: \
                 {:.1} fetches per surface pixel, {:.4} s, missed {:.2}%{gpu_note}",
                pass.table,
                pass.dataset.name(),
                pass.view.angle_deg,
                z.rule.name(),
                s.surface.mean_fetches,
                m.time_s,
                100.0 * s.missed_share,
            );
            let at = Setting {
                method: METHOD,
                samples_per_unit: rate,
                bisections,
                skips,
                delta_rule: z.rule.name(),
            };
            push(rows, row(pass, &at, &m));
        }
    }
    Ok(())
}

/// Runs the tables at 256² pixels (`quick`: 64², one timing) and writes `out/`; with `gpu`,
/// every setting also runs on that adapter (the `gpu_*` columns).
pub fn run(out: &Path, quick: bool, gpu: Option<AdapterPreference>) -> Result<Vec<ReliefRow>> {
    crate::experiment::progress::begin_run();
    crate::experiment::run::ensure_writable(out)?;
    let mut meta = crate::experiment::meta::RunMeta::collect(None);
    let left_out = format!(
        "relief: no Vulkan adapter, GPU columns left empty ({})",
        GpuError::NoAdapter
    );
    let ctx = gpu_context(gpu, "relief", &left_out)?;
    let adapter = ctx.as_ref().map(|c| c.adapter_label());
    meta.gpu_adapter = adapter.clone();
    let (size, repeats) = if quick { (64, 1) } else { (256, 3) };
    let mut rows: Vec<ReliefRow> = Vec::new();
    let mut exact_60 = Vec::new();
    for dset in Dataset::ALL {
        let map = dset.map(MAP_RES);
        let zoned = DeltaRule::ALL
            .into_iter()
            .map(|rule| -> Result<Zoned> {
                let zones = SafetyZones::with_rule(&map, &PAPER_BOXES, rule);
                let kernel = ctx.as_ref().map(|c| ReliefKernel::new(c, &map, &zones));
                let kernel = kernel.transpose().context(|| "relief".into())?;
                Ok(Zoned {
                    rule,
                    zones,
                    kernel,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let adapter = adapter.as_deref();
        // The peers on every map (the quick profile: `simple` only).
        let peer_data = (!quick || dset == Dataset::Simple).then(|| {
            let d = PeerData::new(&map);
            eprintln!(
                "relief: {} peer data: max mip {:.3} s, cones {:.2} s, relaxed cones {:.2} s",
                dset.name(),
                d.mip_time.as_secs_f64(),
                d.cone_time.as_secs_f64(),
                d.relaxed_time.as_secs_f64()
            );
            d
        });
        let peer_kernel = ctx.as_ref().zip(peer_data.as_ref());
        let peer_kernel = peer_kernel.map(|(c, d)| ReliefPeersKernel::new(c, &map, d));
        let peer_kernel = peer_kernel.transpose().context(|| "relief peers".into())?;
        for angle in ANGLES {
            let pass = Pass::new("angles", dset, &map, View::lid(angle, size));
            run_pass(&pass, &zoned, &[(75.0, 2)], repeats, adapter, &mut rows)?;
            if let Some(data) = &peer_data {
                let gpu = peer_kernel.as_ref().zip(adapter);
                peers::run_peers(&pass, data, gpu, repeats, &mut rows)?;
            }
            if angle == 60.0 {
                exact_60.push((pass.reference.frame.image, dset));
            }
        }
        if dset == Dataset::Relief {
            let pass = Pass::new("rates", dset, &map, View::close_up(45.0, size));
            run_pass(
                &pass,
                &zoned[..1],
                &RATE_SETTINGS,
                repeats,
                adapter,
                &mut rows,
            )?;
        }
        if QUALITY_DATASETS.contains(&dset) {
            let pass = Pass::new("quality", dset, &map, View::lid(QUALITY_ANGLE, size));
            let settings = QUALITY_RATES.map(|r| (r, 2));
            run_pass(&pass, &zoned[..1], &settings, repeats, adapter, &mut rows)?;
        }
    }
    super::outputs::write_csv(&out.join(super::outputs::RENDERINGS_CSV), &rows)?;
    super::outputs::write_csv(&out.join("paper_vs_ours.csv"), &paper::compare(&rows))?;
    plots::plots(out, &rows, size)?;
    plots::exact_grid(&out.join("images.png"), &exact_60)?;
    plots::quality_grids(out, size)?;
    let json = out.join("run.json");
    let meta = meta.timed();
    crate::io::write_atomic(&json, meta.to_json().as_bytes()).map_err(Error::io(&json))?;
    Ok(rows)
}
