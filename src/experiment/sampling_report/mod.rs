//! `experiment sampling`: measures the sphere point sets and hemisphere layouts and writes
//! `sphere_sets.csv`, `hemisphere_layouts.csv`, two supplementary tables, PNG plots and
//! `run.json` (date, CPU, threads, git commit).
//!
//! Exactness columns compare against brute force on 10⁶ seeded directions (sphere sets) and on
//! every used texel centre (layouts); they must be zero. Timings are single-threaded, the minimum
//! over five passes of 2·10⁵ seeded queries (the machine is shared, the minimum is the least
//! disturbed pass).

use super::outputs::write_csv;
use super::{Error, Result};
use crate::io::write_atomic;
use crate::sampling::rays::seeded_sphere_direction;
use crate::sampling::{HemisphereLayout, LayoutKind, SphereKind, SpherePoints};
use glam::Vec3;
use plots::{plot_layout_solid_angle, plot_sphere_points};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

mod plots;

/// Seed of the report's query directions.
const SEED: u64 = 0x5a4d_9e37;
/// Directions for the brute-force exactness check of each sphere set.
const CHECK_DIRECTIONS: usize = 1_000_000;
/// Queries per timing pass.
const TIMING_QUERIES: usize = 200_000;
const TIMING_PASSES: usize = 5;

/// The sphere sets measured: the paper's Slater counts and Figure 5 lat-long set, lat-long and
/// Fibonacci sets of comparable sizes.
const SPHERE_SETS: [(SphereKind, usize); 13] = [
    (SphereKind::Slater, 290),
    (SphereKind::Slater, 1090),
    (SphereKind::Slater, 4226),
    (SphereKind::Slater, 16642),
    (SphereKind::LatLong, 272),
    (SphereKind::LatLong, 1122),
    (SphereKind::LatLong, 4160),
    (SphereKind::LatLong, 16512),
    (SphereKind::Fibonacci, 290),
    (SphereKind::Fibonacci, 1090),
    (SphereKind::Fibonacci, 1122),
    (SphereKind::Fibonacci, 4226),
    (SphereKind::Fibonacci, 16642),
];

const LAYOUT_RESOLUTIONS: [u32; 4] = [32, 64, 128, 256];

#[derive(serde::Serialize)]
struct SphereRow {
    set: &'static str,
    count: usize,
    max_gap_deg: f64,
    min_separation_deg: f64,
    nearest_mismatches: usize,
    nearest_ns: f64,
}

#[derive(serde::Serialize)]
struct KeinertRow {
    count: usize,
    directions: usize,
    keinert_mismatches: usize,
    keinert_ns: f64,
    exact_ns: f64,
}

#[derive(serde::Serialize)]
struct LayoutRow {
    layout: &'static str,
    res: u32,
    texels: usize,
    unused_fraction: f64,
    roundtrip_mismatches: usize,
    to_texel_ns: f64,
}

#[derive(serde::Serialize)]
struct MeasureRow {
    layout: &'static str,
    res: u32,
    solid_angle_sum_sr: f64,
    projected_sum_sr: f64,
    used_solid_angle_sr: f64,
    rim_solid_angle_sr: f64,
    min_texel_sr: f64,
    max_texel_sr: f64,
    max_over_min: f64,
}

/// Runs the report into `out` (created if missing).
pub fn run(out: &Path) -> Result<()> {
    crate::experiment::progress::begin_run();
    // An output folder that cannot be written fails before the work, not after it.
    crate::experiment::run::ensure_writable(out)?;
    // Timings depend on what else runs on the machine: the metadata records the load average.
    let meta = super::meta::RunMeta::collect(None);
    let dirs: Vec<Vec3> = (0..CHECK_DIRECTIONS as u64)
        .map(|i| seeded_sphere_direction(i, SEED))
        .collect();
    let timing = &dirs[..TIMING_QUERIES];

    let mut sphere_rows = Vec::new();
    let mut keinert_rows = Vec::new();
    for (kind, count) in SPHERE_SETS {
        let what = || format!("sphere set {} {count}", kind.name());
        let set = SpherePoints::new(kind, count).map_err(Error::sampling(what()))?;
        let spacing = set.spacing().map_err(Error::sampling(what()))?;
        let mismatches = set.nearest_mismatches(&dirs);
        let nearest_ns = time_per_query(timing, |&d| set.nearest(d));
        eprintln!(
            "sampling: {} {count}: gap {:.3}°, {mismatches} mismatches, {nearest_ns:.1} ns",
            kind.name(),
            spacing.max_gap.to_degrees()
        );
        sphere_rows.push(SphereRow {
            set: kind.name(),
            count,
            max_gap_deg: spacing.max_gap.to_degrees(),
            min_separation_deg: spacing.min_separation.to_degrees(),
            nearest_mismatches: mismatches,
            nearest_ns,
        });
        if kind == SphereKind::Fibonacci {
            keinert_rows.push(keinert_row(&set, &dirs, nearest_ns));
        }
    }
    write_csv(&out.join("sphere_sets.csv"), &sphere_rows)?;
    write_csv(&out.join("fibonacci_keinert_inverse.csv"), &keinert_rows)?;

    let hemi: Vec<Vec3> = timing
        .iter()
        .map(|d| Vec3::new(d.x, d.y, d.z.abs()))
        .collect();
    let mut layout_rows = Vec::new();
    let mut measure_rows = Vec::new();
    for kind in LayoutKind::ALL {
        for res in LAYOUT_RESOLUTIONS {
            let layout = HemisphereLayout::try_new(kind, res)
                .map_err(Error::sampling(format!("layout {} {res}", kind.name())))?;
            let n = layout.texel_count() as u32;
            let roundtrip_mismatches = (0..n)
                .filter(|&t| {
                    layout
                        .to_direction(t)
                        .is_some_and(|d| layout.to_texel(d) != t)
                })
                .count();
            let to_texel_ns = time_per_query(&hemi, |&d| layout.to_texel(d) as usize);
            layout_rows.push(LayoutRow {
                layout: kind.name(),
                res,
                texels: layout.texel_count(),
                unused_fraction: 1.0 - layout.used_count() as f64 / layout.texel_count() as f64,
                roundtrip_mismatches,
                to_texel_ns,
            });
            measure_rows.push(measure_row(&layout));
        }
    }
    write_csv(&out.join("hemisphere_layouts.csv"), &layout_rows)?;
    write_csv(&out.join("layout_measures.csv"), &measure_rows)?;

    for (kind, count) in [
        (SphereKind::Slater, 1090),
        (SphereKind::LatLong, 1122),
        (SphereKind::Fibonacci, 1090),
    ] {
        let set = SpherePoints::new(kind, count).map_err(Error::sampling(format!(
            "sphere set {} {count}",
            kind.name()
        )))?;
        let path = out.join(format!("sphere_points_{}_{count}.png", kind.name()));
        plot_sphere_points(&path, &set)?;
    }
    for kind in LayoutKind::ALL {
        let layout = HemisphereLayout::try_new(kind, 32)
            .map_err(Error::sampling(format!("layout {} 32", kind.name())))?;
        let path = out.join(format!("layout_solid_angle_{}_32.png", kind.name()));
        plot_layout_solid_angle(&path, &layout)?;
    }

    let run = serde_json::json!({
        "meta": meta.timed(),
        "check_directions": CHECK_DIRECTIONS,
        "timing": format!(
            "single thread, minimum over {TIMING_PASSES} passes of {TIMING_QUERIES} seeded queries"
        ),
        "seed": SEED,
    });
    let path = out.join("run.json");
    let text = serde_json::to_string_pretty(&run).unwrap_or_default() + "\n";
    write_atomic(&path, text.as_bytes()).map_err(Error::io(&path))?;
    Ok(())
}

fn keinert_row(set: &SpherePoints, dirs: &[Vec3], exact_ns: f64) -> KeinertRow {
    use rayon::prelude::*;
    let keinert_mismatches = dirs
        .par_iter()
        .filter(|&&d| {
            let (k, e) = (set.nearest_keinert(d).unwrap_or(0), set.nearest(d));
            let dd = d.as_dvec3();
            dd.dot(set.point(e).as_dvec3()) - dd.dot(set.point(k).as_dvec3()) > 1e-12
        })
        .count();
    KeinertRow {
        count: set.len(),
        directions: dirs.len(),
        keinert_mismatches,
        keinert_ns: time_per_query(&dirs[..TIMING_QUERIES], |&d| {
            set.nearest_keinert(d).unwrap_or(0)
        }),
        exact_ns,
    }
}

fn measure_row(layout: &HemisphereLayout) -> MeasureRow {
    let n = layout.texel_count() as u32;
    let omega: Vec<f64> = (0..n).map(|t| layout.solid_angle(t)).collect();
    let used: Vec<f64> = (0..n)
        .filter(|&t| layout.is_used(t))
        .map(|t| omega[t as usize])
        .collect();
    let min = used.iter().copied().fold(f64::INFINITY, f64::min);
    let max = used.iter().copied().fold(0.0, f64::max);
    MeasureRow {
        layout: layout.kind.name(),
        res: layout.res,
        solid_angle_sum_sr: omega.iter().sum(),
        projected_sum_sr: (0..n).map(|t| layout.projected_solid_angle(t)).sum(),
        used_solid_angle_sr: used.iter().sum(),
        rim_solid_angle_sr: layout.rim_solid_angle(),
        min_texel_sr: min,
        max_texel_sr: max,
        max_over_min: max / min,
    }
}

/// Nanoseconds per call of `f`, single-threaded: the fastest of several passes.
fn time_per_query<T>(items: &[T], f: impl Fn(&T) -> usize) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..TIMING_PASSES {
        let start = Instant::now();
        let mut acc = 0usize;
        for x in items {
            acc = acc.wrapping_add(f(black_box(x)));
        }
        black_box(acc);
        best = best.min(start.elapsed().as_secs_f64() * 1e9 / items.len() as f64);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_has_the_specified_header() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.csv");
        let row = SphereRow {
            set: "slater",
            count: 290,
            max_gap_deg: 1.0,
            min_separation_deg: 0.5,
            nearest_mismatches: 0,
            nearest_ns: 20.0,
        };
        write_csv(&path, &[row]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with(
            "set,count,max_gap_deg,min_separation_deg,nearest_mismatches,nearest_ns\n"
        ));
    }
}
