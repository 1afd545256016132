//! The series each plot gets from given rows: Figure 6's shape (4 positional counts × 4
//! resolutions on the CPU and lavapipe, ray casting swept, every method of issue 29 in
//! `methods.csv`), built in memory.

use super::*;
use crate::experiment::plot::{Styled, MAX_SERIES};

const LAVAPIPE: &str =
    "llvmpipe (LLVM 15.0.6, 256 bits) | llvmpipe Mesa 22.3.6 (LLVM 15.0.6) | Vulkan";

/// `table.csv` rows from (scene, count, res, backend, rms_image, rms_vs_truth) as a run
/// writes them (read back by header name).
fn rows(cells: &[(&str, usize, u32, &str, f64, f64)]) -> Vec<Row> {
    let mut text = String::from(
        "scene,cell,positional_samples,directional_res,layout,precision,selection,backend,\
         adapter,estimate_s,field_bytes,sphere,rays_per_point,receiver_points,\
         caster_triangles,bake_rays,bake_cached,image,rms_image,rms_vs_truth,truth_stderr,\
         truth_rays,bake_s\n",
    );
    for &(sc, n, res, b, img, truth) in cells {
        let adapter = if b == "gpu" {
            LAVAPIPE
        } else {
            "CPU (2 threads)"
        };
        let cell = format!("{sc}-slater-{n}-concentric-{res}-u8-nearest-{b}");
        let t = 1e-3 * (1.0 + (n as f64).log10()) * if b == "gpu" { 3.0 } else { 1.0 };
        let bytes = n as u64 * (res * res) as u64;
        text.push_str(&format!(
            "{sc},{cell},{n},{res},concentric,u8,nearest,{b},\"{adapter}\",{t},{bytes},slater,\
             256,3267,38889,{bytes},false,,{img},{truth},0.13,16384,0.5\n"
        ));
    }
    csv::Reader::from_reader(text.as_bytes())
        .deserialize()
        .collect::<std::result::Result<Vec<Row>, _>>()
        .unwrap()
}

/// Figure 6's cells; the GPU's RMS is the CPU's × `gpu_factor`.
fn figure6_rows(gpu_factor: f64) -> Vec<Row> {
    let mut cells = Vec::new();
    for b in ["cpu", "gpu"] {
        for n in [290, 1090, 4226, 16642] {
            for res in [32, 64, 128, 256] {
                let rms = 2.0 / (n as f64 / 290.0).sqrt() + 8.0 / res as f64;
                let f = if b == "gpu" { gpu_factor } else { 1.0 };
                cells.push(("bunny", n, res, b, rms * f, rms * f * 0.9));
            }
        }
    }
    rows(&cells)
}

fn sweep() -> Vec<SweepRow> {
    [16, 64, 256, 1024]
        .iter()
        .map(|&k| SweepRow {
            scene: "bunny".into(),
            backend: Backend::Cpu,
            rays_per_point: k,
            raycast_s: k as f64 * 2e-4,
            rms_vertex: None,
            rms_image: Some(if k == 256 {
                0.0
            } else {
                40.0 / (k as f64).sqrt()
            }),
            raycast_kernel_s: None,
            rms_vs_truth: Some(40.0 / (k as f64).sqrt()),
            rms_vs_truth_sd: None,
            truth_stderr: Some(0.13),
            flip_mean: None,
            flip_mean_vs_truth: None,
        })
        .collect()
}

/// `methods.csv` as issue 29's runs write it: raycast (BVH bytes), Embree (none), the SDF at
/// 3 resolutions × 3 precisions × 2 queries, AO fields at 3 × 3.
fn methods() -> Vec<MethodRow> {
    let row = |method: &str, params: &[(&str, String)], bytes: Option<f64>, t: f64, e: f64| {
        let mut r = NamedRow::new();
        let setting = std::iter::once(method.to_string())
            .chain(params.iter().map(|(_, v)| v.clone()))
            .collect::<Vec<_>>()
            .join("-");
        r.push("scene", "bunny")
            .push("method", method)
            .push("setting", setting);
        for name in ["res", "radial_samples", "precision", "query"] {
            let v = params
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, v)| v.clone());
            r.push_opt(name, v);
        }
        r.push("backend", "cpu")
            .push("precompute_s", 0.1)
            .push_opt("bytes", bytes)
            .push("estimate_s", t)
            .push("rms_vs_truth", e)
            .push("image", "");
        MethodRow::of(&r)
    };
    let mut out = vec![
        row("raycast", &[], Some(2.5e6), 0.054, 1.8),
        row("embree", &[], None, 0.03, 1.8),
    ];
    for res in [32, 64, 128] {
        for p in ["f32", "f16", "u8"] {
            for q in ["trace", "cone"] {
                let params = [
                    ("res", res.to_string()),
                    ("precision", p.to_string()),
                    ("query", q.to_string()),
                ];
                let e = if q == "cone" { 48.0 } else { 5.0 } + 1.0 / res as f64;
                let bytes = (res * res * res) as f64 * 2.0;
                out.push(row(
                    "sdf",
                    &params,
                    Some(bytes),
                    0.01 * res as f64 / 32.0,
                    e,
                ));
            }
        }
    }
    for res in [8, 16, 32] {
        for p in ["f32", "f16", "u8"] {
            let params = [
                ("res", res.to_string()),
                ("radial_samples", "12".to_string()),
                ("precision", p.to_string()),
            ];
            out.push(row("aofield", &params, Some(1e3 * res as f64), 3e-4, 3.2));
        }
    }
    out
}

fn figure6_run(gpu_factor: f64) -> RunData {
    RunData {
        title: "figure6".into(),
        quantity: Quantity::Ao,
        rows: figure6_rows(gpu_factor),
        sweep: sweep(),
        field_sweep: Vec::new(),
        methods: methods(),
        paper: Vec::new(),
    }
}

fn labels(p: &Panel) -> Vec<&str> {
    p.series.iter().map(|s| s.series.label.as_str()).collect()
}

#[test]
fn every_panel_of_every_figure_holds_eight_series_at_most() {
    let run = figure6_run(1.0);
    let figs = figures(&run);
    let names: Vec<&str> = figs.iter().map(|(n, _)| *n).collect();
    assert!(names.contains(&"pareto.png") && names.contains(&"error_vs_bytes.png"));
    for (name, fig) in &figs {
        assert!(!fig.panels.is_empty(), "{name}");
        for p in &fig.panels {
            assert!(
                p.series.len() <= MAX_SERIES,
                "{name}: {}: {:?}",
                p.title,
                labels(p)
            );
        }
    }
    // Every field cell of the CPU is a series of the Pareto plot: 16 of them, four panels.
    let pareto = &figs.iter().find(|(n, _)| *n == "pareto.png").unwrap().1;
    let fields: usize = pareto
        .panels
        .iter()
        .flat_map(|p| labels(p))
        .filter(|l| l.starts_with("field ") && l.contains('×'))
        .count();
    assert_eq!(fields, 16);
}

/// The points of every series of a figure.
fn points(fig: &Figure) -> Vec<(f64, f64)> {
    fig.panels
        .iter()
        .flat_map(|p| {
            p.series
                .iter()
                .flat_map(|s| s.series.points.iter().copied())
        })
        .collect()
}

#[test]
fn every_method_row_is_on_the_pareto_plot_and_those_with_bytes_on_the_bytes_plot() {
    let run = figure6_run(1.0);
    let pareto = compare::pareto(&run);
    let bytes = compare::bytes(&run);
    let (on_time, on_bytes) = (points(&pareto), points(&bytes));
    for m in &run.methods {
        let y = m.rms_vs_truth.unwrap();
        let t = (m.estimate_s.unwrap(), y);
        assert!(
            on_time.contains(&t),
            "{} missing from the Pareto plot",
            m.setting
        );
        match m.bytes {
            Some(b) => assert!(
                on_bytes.contains(&(b / 1e6, y)),
                "{} missing from the bytes plot",
                m.setting
            ),
            None => assert!(!bytes
                .panels
                .iter()
                .flat_map(labels)
                .any(|l| l.starts_with(&m.method))),
        }
    }
    // Embree records no bytes: a note says it is left out.
    assert!(
        bytes
            .notes
            .iter()
            .any(|n| n.contains("no bytes recorded): embree")),
        "{:?}",
        bytes.notes
    );
    // Ray casting sits at the BVH's bytes, every swept ray count.
    let rc: Vec<&Styled> = bytes
        .panels
        .iter()
        .flat_map(|p| p.series.iter())
        .filter(|s| s.series.label.starts_with("ray cast"))
        .collect();
    assert!(!rc.is_empty());
    assert!(rc
        .iter()
        .all(|s| s.series.points.len() == 4 && s.series.points.iter().all(|p| p.0 == 2.5)));
    // The SDF's settings: 6 lines of 3 resolutions, in one panel, its family's style.
    let sdf: Vec<&Styled> = pareto
        .panels
        .iter()
        .flat_map(|p| p.series.iter())
        .filter(|s| s.series.label.starts_with("sdf ") && s.series.label.contains("res"))
        .collect();
    assert_eq!(sdf.len(), 6);
    assert!(sdf.iter().all(|s| s.series.points.len() == 3));
    assert!(sdf
        .iter()
        .all(|s| s.style.marker == crate::experiment::plot::Marker::Up));
}

#[test]
fn coinciding_cpu_and_lavapipe_lines_are_drawn_once_and_named() {
    // The GPU within 0.1% of the CPU: one line per resolution, labelled with both devices.
    let run = figure6_run(1.001);
    let fig = positional::figure(&run);
    let all: Vec<&str> = fig.panels.iter().flat_map(labels).collect();
    assert_eq!(all.len(), 4, "{all:?}");
    assert!(
        all.iter().all(|l| l.ends_with("(CPU = lavapipe (CPU))")),
        "{all:?}"
    );
    assert!(fig.notes.iter().any(|n| n.contains("lavapipe (CPU) agree")));
    // 3% apart: a line each.
    let run = figure6_run(1.03);
    let fig = positional::figure(&run);
    let all: Vec<&str> = fig.panels.iter().flat_map(labels).collect();
    assert_eq!(all.len(), 8, "{all:?}");
    assert!(all.contains(&"32², lavapipe (CPU)") && all.contains(&"32², CPU"));
    assert!(fig.panels.iter().all(|p| p.series.len() <= MAX_SERIES));
}

#[test]
fn the_gpu_panel_names_lavapipe_and_the_axis_names_the_quantity() {
    let mut run = figure6_run(1.0);
    let pareto = compare::pareto(&run);
    assert!(pareto
        .panels
        .iter()
        .any(|p| p.title.contains("lavapipe (CPU)")));
    assert!(pareto.axes.x_label.starts_with("AO estimate time"));
    run.quantity = Quantity::Shadow;
    let pareto = compare::pareto(&run);
    assert!(pareto.axes.x_label.starts_with("shadow estimate time"));
    assert!(!pareto.axes.title.contains("AO") && !pareto.axes.x_label.contains("AO"));
}

#[test]
fn the_papers_values_share_the_axes_of_ours() {
    let mut run = figure6_run(1.0);
    run.methods.clear();
    let cell = |n: usize, res: u32| format!("bunny-slater-{n}-concentric-{res}-u8-nearest-cpu");
    // A row of the paper's RMS alone (the columns not named are empty).
    let paper = |n: usize, res: u32, rms: f64| -> PaperRow {
        let (label, cell) = (format!("{n}x{res}"), cell(n, res));
        let row = serde_json::json!({"label": label, "cell": cell, "paper_rms": rms, "note": ""});
        serde_json::from_value(row).unwrap()
    };
    run.paper = vec![
        paper(290, 32, 2.8207),
        paper(1090, 32, 1.0653),
        paper(290, 64, 2.4118),
    ];
    let fig = positional::figure(&run);
    let series: Vec<&Styled> = fig.panels.iter().flat_map(|p| p.series.iter()).collect();
    let p32 = series
        .iter()
        .find(|s| s.series.label == "paper: 32²")
        .expect("the paper's 32² line");
    assert_eq!(p32.series.points, [(290.0, 2.8207), (1090.0, 1.0653)]);
    // Outlined, in the colour of ours.
    let ours = series
        .iter()
        .find(|s| s.series.label.starts_with("32²"))
        .unwrap();
    assert!(p32.style.hollow && p32.style.color == ours.style.color);
    assert!(series.iter().any(|s| s.series.label == "paper: 64²"));
    assert!(fig.notes.iter().any(|n| n.starts_with("paper:")));
}

#[test]
fn a_run_without_methods_draws_the_field_and_ray_casting_only() {
    let mut run = figure6_run(1.0);
    run.methods.clear();
    let pareto = compare::pareto(&run);
    // No overview panel without methods: the field's four panels and the GPU's.
    assert_eq!(
        pareto.panels.len(),
        5,
        "{:?}",
        pareto.panels.iter().map(|p| &p.title).collect::<Vec<_>>()
    );
    let bytes = compare::bytes(&run);
    assert_eq!(bytes.panels.len(), 1);
    assert!(bytes
        .notes
        .iter()
        .any(|n| n.contains("no raycast method row")));
}
