//! The comparison of every method with the field (issue "the per-object peers"): `pareto.png`,
//! the error against the estimate's time, and `error_vs_bytes.png`, the error against what
//! each method stores, with the field's cells (`table.csv`), ray casting at every swept ray
//! count (`raycast_sweep.csv`) and every row of `methods.csv` (ray casters, distance fields
//! traced and cone traced, AO fields, and any method registered at run time).
//!
//! Each scene gets an overview panel (the best settings of each family: its Pareto front)
//! when the run has methods, the field's own panels (its settings by positional count, at
//! every ray count of `field_sweep.csv` on the time plot), the methods' panels (each family
//! beside ray casting and the field's front) and, on the time plot, a panel of the GPU rows
//! where the run has them. Panels hold at most [`MAX_SERIES`](crate::experiment::plot::MAX_SERIES)
//! series and share their axes.

use super::facet::{front, one_or_pack, pack, viridis, Family, Group};
use super::labels::Devices;
use super::{key_suffix, MethodRow, Metric, RunData};
use crate::experiment::outputs::SweepRow;
use crate::experiment::plot::{distinct, sorted_distinct, Figure, HLine, Marker, Panel};
use crate::experiment::plot::{Series, Style, Styled};
use crate::experiment::spec::Backend;
use crate::experiment::table::Row;

/// Bytes per unit of the bytes axis (MB).
const MB: f64 = 1e6;

/// `pareto.png`: the error against the estimate's time.
pub fn pareto(run: &RunData) -> Figure {
    let metric = Metric::of(&run.rows);
    let devices = Devices::of(&run.rows);
    let q = run.quantity();
    let mut panels = Vec::new();
    let mut notes = Vec::new();
    let scenes = run.scenes();
    for sc in &scenes {
        let prefix = scene_prefix(&scenes, sc);
        let rows: Vec<&Row> = run.rows.iter().filter(|r| &r.scene == sc).collect();
        let first = rows.first().map_or(Backend::Cpu, |r| r.backend);
        let on = |b: Backend| rows.iter().copied().filter(move |r| r.backend == b);
        let ray_cast = |b: Backend, shade: usize| {
            raycast_series(&run.sweep, sc, b, metric, |s| s.raycast_s, &devices)
                .map(|s| s.styled(Family::RayCast.style(shade, 0)))
        };
        // The field's points of one backend: each cell at the run's rays and at the field
        // sweep's.
        let cell_points = |r: &Row| -> Vec<(f64, f64)> {
            let mut pts: Vec<(f64, f64)> = metric
                .row(r)
                .map(|y| (r.estimate_s, y))
                .into_iter()
                .collect();
            if metric == Metric::Truth {
                for f in run.field_sweep.iter().filter(|f| f.cell == r.cell) {
                    if f.rays_per_point != r.rays_per_point {
                        pts.extend(f.rms_vs_truth.map(|y| (f.estimate_s, y)));
                    }
                }
            }
            pts
        };
        let field_front = |b: Backend, label: String, shade: usize| {
            let pts: Vec<(f64, f64)> = on(b).flat_map(cell_points).collect();
            Series::line(label, front(&pts)).styled(Family::Field.style(shade, 0))
        };
        let cpu_front = field_front(first, "field: best settings (Pareto front)".into(), 0);
        let rc = ray_cast(first, 0);
        let context: Vec<Styled> = rc.iter().cloned().chain([cpu_front.clone()]).collect();
        let (families, dropped) = method_groups(&run.methods, sc, metric, |m| m.estimate_s);
        notes.extend(dropped);

        // The overview: each family's front.
        panels.extend(overview(&families, &context, &prefix));
        // The field's settings, by positional count.
        let counts = sorted_distinct(on(first).map(|r| r.positional_samples));
        let all_res = res_ranks(&run.rows);
        // The settings other than the resolution (normal bits, precision, …), each a variant.
        let other = |r: &Row| key_suffix(&run.rows, r, &["scene", "res", "backend"]);
        let others = distinct(on(first).map(other));
        let groups: Vec<Group> = counts
            .iter()
            .map(|&c| Group {
                title: format!("field, {c} maps"),
                series: on(first)
                    .filter(|r| r.positional_samples == c)
                    .map(|r| {
                        let swept = run.field_sweep.iter().filter(|f| f.cell == r.cell);
                        let swept = swept.filter(|_| metric == Metric::Truth);
                        let rays = std::iter::once(r.rays_per_point)
                            .chain(swept.map(|f| f.rays_per_point));
                        let rays: Vec<String> =
                            sorted_distinct(rays).iter().map(u32::to_string).collect();
                        let other = other(r);
                        let variant = others.iter().position(|o| o == &other).unwrap_or(0);
                        let base =
                            Style::new(viridis(all_res.rank(r.directional_res)), Marker::Circle);
                        let label = format!(
                            "field {}×{}²{other} ({} rays)",
                            r.positional_samples,
                            r.directional_res,
                            rays.join("/")
                        );
                        Series::line(label, cell_points(r)).styled(variant_style(base, variant))
                    })
                    .collect(),
            })
            .collect();
        let title = format!("{prefix}visibility field ({})", devices.name(first));
        let rcs: Vec<Styled> = rc.iter().cloned().collect();
        panels.extend(one_or_pack(groups, &rcs, title, &prefix));
        // The methods, beside ray casting and the field's front.
        panels.extend(method_panels(&families, &context, &prefix));
        // The GPU rows.
        let gpu_rows = on(Backend::Gpu).count() > 0
            || run
                .sweep
                .iter()
                .any(|s| &s.scene == sc && s.backend == Backend::Gpu);
        if first == Backend::Cpu && gpu_rows {
            let g = devices.name(Backend::Gpu).to_string();
            let mut s: Vec<Styled> = context.clone();
            s.extend(ray_cast(Backend::Gpu, 1).map(|s| Styled {
                style: s.style.hollow().dashed(),
                ..s
            }));
            if on(Backend::Gpu).count() > 0 {
                let f = field_front(Backend::Gpu, format!("field, {g}: Pareto front"), 1);
                s.push(Styled {
                    style: f.style.hollow().dashed(),
                    ..f
                });
            }
            panels.push(Panel::new(
                format!("{prefix}GPU kernels on {g}, beside the CPU's"),
                s,
            ));
        }
    }
    add_floor(&mut panels, run, metric);
    if metric != Metric::Truth {
        notes.push(
            "no converged reference in this run: errors against the same-ray ray cast".into(),
        );
    }
    Figure {
        axes: metric.axes(
            format!("{}: error against the {q} estimate's time", run.title),
            format!("{q} estimate time, s (log)"),
        ),
        panels,
        notes,
    }
}

/// `error_vs_bytes.png`: the error against stored bytes (fields' `field_bytes`, methods'
/// `bytes`; ray casting at its BVH's bytes where the `raycast` method recorded them).
pub fn bytes(run: &RunData) -> Figure {
    let metric = Metric::of(&run.rows);
    let devices = Devices::of(&run.rows);
    let mut panels = Vec::new();
    let mut notes = Vec::new();
    let scenes = run.scenes();
    for sc in &scenes {
        let prefix = scene_prefix(&scenes, sc);
        let rows: Vec<&Row> = run.rows.iter().filter(|r| &r.scene == sc).collect();
        let first = rows.first().map_or(Backend::Cpu, |r| r.backend);
        let fields: Vec<&Row> = rows
            .iter()
            .copied()
            .filter(|r| r.backend == first)
            .collect();
        let at = |r: &Row| metric.row(r).map(|y| (r.field_bytes as f64 / MB, y));
        // The field: a line over the directional resolution per other setting.
        let field_key = |r: &Row| {
            let other = key_suffix(&run.rows, r, &["scene", "res", "backend"]);
            format!("{} maps{other}", r.positional_samples)
        };
        let keys = distinct(fields.iter().map(|r| field_key(r)));
        let field_series: Vec<Styled> = keys
            .iter()
            .enumerate()
            .map(|(i, k)| {
                let these: Vec<&&Row> = fields.iter().filter(|r| &field_key(r) == k).collect();
                let mut res: Vec<String> = these
                    .iter()
                    .map(|r| r.directional_res.to_string())
                    .collect();
                res.dedup();
                let label = format!("field {k} ({}²)", res.join("/"));
                let color = viridis(i as f64 / (keys.len().max(2) - 1) as f64);
                Series::line(label, these.iter().filter_map(|r| at(r)).collect())
                    .styled(Style::new(color, Marker::Circle))
            })
            .collect();
        let all: Vec<(f64, f64)> = fields.iter().filter_map(|r| at(r)).collect();
        let field_front = Series::line("field: best settings (Pareto front)", front(&all))
            .styled(Family::Field.style(0, 0));
        // Ray casting at its BVH's bytes.
        let bvh = run
            .methods
            .iter()
            .find(|m| &m.scene == sc && m.method == "raycast")
            .and_then(|m| m.bytes);
        let rc = bvh.and_then(|b| {
            raycast_series(&run.sweep, sc, Backend::Cpu, metric, |_| b / MB, &devices).map(
                |mut s| {
                    s.label = format!("{} at its BVH's {:.1} MB", s.label, b / MB);
                    s.styled(Family::RayCast.style(0, 0))
                },
            )
        });
        if bvh.is_none() {
            notes.push(format!(
                "{prefix}ray casting is not on this plot: no raycast method row records its BVH's bytes"
            ));
        }
        let context: Vec<Styled> = rc.iter().cloned().chain([field_front.clone()]).collect();
        let (families, dropped) =
            method_groups(&run.methods, sc, metric, |m| m.bytes.map(|b| b / MB));
        notes.extend(dropped);
        panels.extend(overview(&families, &context, &prefix));
        panels.extend(pack(
            vec![Group {
                title: format!("visibility field ({})", devices.name(first)),
                series: field_series,
            }],
            &rc.iter().cloned().collect::<Vec<_>>(),
            &prefix,
        ));
        panels.extend(method_panels(&families, &context, &prefix));
        let without = distinct(
            run.methods
                .iter()
                .filter(|m| &m.scene == sc && m.bytes.is_none())
                .map(|m| m.method.as_str()),
        );
        if !without.is_empty() {
            notes.push(format!(
                "{prefix}not on this plot (no bytes recorded): {}",
                without.join(", ")
            ));
        }
    }
    add_floor(&mut panels, run, metric);
    Figure {
        axes: metric.axes(
            format!("{}: error against stored bytes", run.title),
            "stored MB (10⁶ bytes; log): fields, BVH, distance volumes, AO fields",
        ),
        panels,
        notes,
    }
}

/// The overview panel: `context` and each family's front (none without methods).
fn overview(families: &[FamilyGroup], context: &[Styled], prefix: &str) -> Option<Panel> {
    if families.is_empty() {
        return None;
    }
    let mut series = context.to_vec();
    series.extend(families.iter().map(|g| g.overview.clone()));
    let title = if families.iter().all(|f| f.group.series.len() == 1) {
        "every method"
    } else {
        "every method at its best settings"
    };
    Some(Panel::new(format!("{prefix}{title}"), series))
}

/// The families' panels beside `context`; none where every family is one series (the
/// overview shows them all).
fn method_panels(families: &[FamilyGroup], context: &[Styled], prefix: &str) -> Vec<Panel> {
    if families.iter().all(|f| f.group.series.len() == 1) {
        return Vec::new();
    }
    pack(
        families.iter().map(|f| f.group.clone()).collect(),
        context,
        prefix,
    )
}

/// "SCENE: " where the run has several scenes.
fn scene_prefix(scenes: &[&str], sc: &str) -> String {
    if scenes.len() > 1 {
        format!("{sc}: ")
    } else {
        String::new()
    }
}

/// The reference's noise floor as a dashed line in every panel (runs with a converged
/// reference).
fn add_floor(panels: &mut [Panel], run: &RunData, metric: Metric) {
    if metric != Metric::Truth {
        return;
    }
    let floor = run
        .rows
        .iter()
        .filter_map(|r| r.truth_stderr)
        .fold(0.0f64, f64::max);
    if floor > 0.0 {
        let rays = run.rows[0].truth_rays.unwrap_or(0);
        for p in panels {
            p.hlines.push(HLine {
                label: format!("converged reference's noise ({rays} rays)"),
                y: floor,
            });
        }
    }
}

/// Ray casting of scene `sc` on backend `b` at every swept ray count, at `x` (its time, or its
/// BVH's bytes).
fn raycast_series(
    sweep: &[SweepRow],
    sc: &str,
    b: Backend,
    metric: Metric,
    x: impl Fn(&SweepRow) -> f64,
    devices: &Devices,
) -> Option<Series> {
    let mut these: Vec<&SweepRow> = sweep
        .iter()
        .filter(|s| s.scene == sc && s.backend == b)
        .collect();
    these.sort_by_key(|s| s.rays_per_point);
    let points: Vec<(f64, f64)> = these
        .iter()
        .filter_map(|s| metric.sweep(s).map(|y| (x(s), y)))
        .collect();
    if points.is_empty() {
        return None;
    }
    let counts: Vec<String> = these.iter().map(|s| s.rays_per_point.to_string()).collect();
    let label = format!("ray cast, {} ({} rays)", devices.name(b), counts.join("/"));
    Some(Series::line(label, points))
}

/// One method family of a scene: its series (one per setting other than `res`, a line over
/// `res`) and its overview series (its front).
#[derive(Clone, Debug)]
pub struct FamilyGroup {
    pub group: Group,
    pub overview: Styled,
}

/// The method rows of scene `sc` as families, with `x` their x value (none: left out, the
/// caller says why), and a note per family naming its rows left out for want of an error.
pub fn method_groups(
    methods: &[MethodRow],
    sc: &str,
    metric: Metric,
    x: impl Fn(&MethodRow) -> Option<f64>,
) -> (Vec<FamilyGroup>, Vec<String>) {
    // The CPU rows: a method's GPU rows (the same values from its kernels) are in methods.csv,
    // and their times are the adapter's, not comparable on one axis with the CPU's.
    let rows: Vec<&MethodRow> = methods
        .iter()
        .filter(|m| m.scene == sc && matches!(m.backend.as_str(), "" | "cpu"))
        .collect();
    let names = distinct(rows.iter().map(|m| m.method.as_str()));
    let mut others = Vec::new();
    let mut out = Vec::new();
    let mut notes = Vec::new();
    for name in names {
        let family = Family::of_method(name, &mut others);
        let these: Vec<&MethodRow> = rows.iter().copied().filter(|m| m.method == name).collect();
        // Parameters that vary within the family (other than `res`, the line's axis).
        let varying: Vec<String> = {
            let mut v: Vec<String> = Vec::new();
            for m in &these {
                for (p, _) in &m.params {
                    if p != "res"
                        && !v.contains(p)
                        && these.iter().any(|o| o.param(p) != m.param(p))
                    {
                        v.push(p.clone());
                    }
                }
            }
            v
        };
        let variant_key = |m: &MethodRow| -> Vec<String> {
            varying
                .iter()
                .map(|p| m.param(p).unwrap_or("").to_string())
                .collect()
        };
        let variants = distinct(these.iter().map(|m| variant_key(m)));
        let precision_at = varying.iter().position(|p| p == "precision");
        let rest = |k: &Vec<String>| -> Vec<String> {
            k.iter()
                .enumerate()
                .filter(|(i, _)| Some(*i) != precision_at)
                .map(|(_, v)| v.clone())
                .collect()
        };
        let rests = distinct(variants.iter().map(rest));
        let mut dropped: Vec<&str> = Vec::new();
        let mut series = Vec::new();
        let mut all: Vec<(f64, f64)> = Vec::new();
        for k in &variants {
            let mut ms: Vec<&&MethodRow> = these.iter().filter(|m| &variant_key(m) == k).collect();
            ms.sort_by(|a, b| {
                let res = |m: &MethodRow| m.param("res").and_then(|r| r.parse::<f64>().ok());
                res(a)
                    .partial_cmp(&res(b))
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
            let mut points = Vec::new();
            let mut res = Vec::new();
            for m in &ms {
                match (x(m), metric.method(m)) {
                    (Some(x), Some(y)) if x > 0.0 => {
                        points.push((x, y));
                        res.extend(m.param("res").map(str::to_string));
                    }
                    (Some(_), None) => dropped.push(&m.setting),
                    _ => {}
                }
            }
            if points.is_empty() {
                continue;
            }
            all.extend(&points);
            let mut label = name.to_string();
            for v in k.iter().filter(|v| !v.is_empty()) {
                label.push(' ');
                label.push_str(v);
            }
            if !res.is_empty() {
                label.push_str(&format!(" (res {})", res.join("/")));
            }
            let shade = precision_at.map_or(0, |i| precision_rank(&k[i]));
            let variant = rests.iter().position(|r| r == &rest(k)).unwrap_or(0);
            // The raycast method is ray casting's sweep at the run's rays with its BVH's
            // build: outlined, so that it shows on the sweep's line.
            let style = match family {
                Family::RayCast => family.style(1, 3),
                _ => family.style(shade, variant),
            };
            series.push(Series::line(label, points).styled(style));
        }
        if !dropped.is_empty() {
            notes.push(format!(
                "{sc}: not on this plot (no error recorded): {}",
                dropped.join(", ")
            ));
        }
        if series.is_empty() {
            continue;
        }
        let overview = if series.len() == 1 {
            series[0].clone()
        } else {
            let label = format!("{name}: best settings (Pareto front)");
            Series::line(label, front(&all)).styled(family.style(0, 0))
        };
        out.push(FamilyGroup {
            group: Group {
                title: name.to_string(),
                series,
            },
            overview,
        });
    }
    (out, notes)
}

/// `base` as variant `v`: 0 as it is, 1 outlined and dashed, 2 dashed, 3 outlined.
pub fn variant_style(base: Style, v: usize) -> Style {
    match v % 4 {
        0 => base,
        1 => base.hollow().dashed(),
        2 => base.dashed(),
        _ => base.hollow(),
    }
}

/// Darker for more bits: f32, then f16 and u16, then u8 and fewer.
fn precision_rank(p: &str) -> usize {
    match p {
        "f32" => 0,
        "f16" | "u16" => 1,
        _ => 2,
    }
}

/// The rank of each directional resolution among a run's (for a colour per resolution that
/// is the same in every panel).
pub struct ResRanks(Vec<u32>);

impl ResRanks {
    /// `r`'s place in [0, 1].
    pub fn rank(&self, r: u32) -> f64 {
        let i = self.0.iter().position(|&v| v == r).unwrap_or(0);
        i as f64 / (self.0.len().max(2) - 1) as f64
    }
}

pub fn res_ranks(rows: &[Row]) -> ResRanks {
    ResRanks(sorted_distinct(rows.iter().map(|r| r.directional_res)))
}
