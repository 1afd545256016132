//! The 2005 paper's frame rates (Kolb and Rezk-Salama, VMV 2005, Tables 1–3) and our gains
//! beside them (`paper_vs_ours.csv`).

use super::{ReliefRow, METHOD};
use serde::Serialize;

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
pub const PAPER_TABLE3: [(f32, u32, u32, f64); 8] = [
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
/// ours in time and in fetches (the paper's δ).
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    pub paper_table: &'static str,
    pub case: String,
    pub skips: u32,
    pub paper_fps_gain: f64,
    pub our_time_gain: f64,
    /// Mean fetches over the pixels whose ray meets the surface (the skip question), without
    /// skips over with.
    pub our_surface_fetch_gain: f64,
    /// The same over every pixel whose ray enters the prism (rays leaving without a hit
    /// included).
    pub our_all_fetch_gain: f64,
    /// In GPU kernel time (empty without an adapter; lavapipe's is a CPU's).
    pub our_gpu_time_gain: Option<f64>,
}

/// The paper's gains beside ours (its "angel" against our `relief`; its perpendicular and
/// tangential views against our 0° and 75°).
pub fn compare(rows: &[ReliefRow]) -> Vec<Comparison> {
    let find = |table: &str, d: &str, angle: f32, rate: f32, b: u32, skips: u32| {
        rows.iter().find(|r| {
            r.method == METHOD
                && r.delta_rule == "paper"
                && (
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
    let row = |paper_table, case, skips, paper_fps_gain, r: &ReliefRow| Comparison {
        paper_table,
        case,
        skips,
        paper_fps_gain,
        our_time_gain: r.time_speedup,
        our_surface_fetch_gain: r.surface_fetch_reduction,
        our_all_fetch_gain: r.fetch_reduction,
        our_gpu_time_gain: r.gpu_time_speedup,
    };
    let mut out = Vec::new();
    for (d, v, fps) in PAPER_TABLE1 {
        let angle = if v == "perpendicular" { 0.0 } else { 75.0 };
        for skips in 1..=2u32 {
            if let Some(r) = find("angles", ours(d), angle, 75.0, 2, skips) {
                let case = format!("{d} {v} (ours: {} {angle}°)", ours(d));
                out.push(row("1", case, skips, fps[skips as usize] / fps[0], r));
            }
        }
    }
    for (angle, fps) in PAPER_TABLE2 {
        for skips in 1..=2u32 {
            if let Some(r) = find("angles", "relief", angle, 75.0, 2, skips) {
                let case = format!("angel {angle}° (ours: relief)");
                out.push(row("2", case, skips, fps[skips as usize] / fps[0], r));
            }
        }
    }
    for (rate, b, skips, fps) in PAPER_TABLE3.into_iter().filter(|c| c.2 > 0) {
        let base = PAPER_TABLE3
            .iter()
            .find(|c| (c.0, c.1, c.2) == (rate, b, 0))
            .map(|c| c.3);
        if let (Some(base), Some(r)) = (base, find("rates", "relief", 45.0, rate, b, skips)) {
            let case = format!("angel close-up, {rate} samples, {b} bisections (ours: relief 45°)");
            out.push(row("3", case, skips, fps / base, r));
        }
    }
    out
}
