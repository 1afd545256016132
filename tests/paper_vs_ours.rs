//! `paper_vs_ours.csv`: each paper cell beside the measurement of ours it names.
//!
//! The committed files are recomputed here from their folder's `table.csv`, `raycast_sweep.csv`
//! and `pairs.csv`, read as plain text columns and matched by this file's own reading of the
//! spec (not the library's), so a row that copies another cell's values, counts rays without
//! the lights, or divides by a cached bake fails. The pairing sources are tested on a small
//! table with numbers worked by hand, and their validation on bad specs.

mod common;

use std::collections::HashMap;
use std::path::Path;
use visfield::experiment::outputs::SweepRow;
use visfield::experiment::paper::{paper_vs_ours, RunTables};
use visfield::experiment::spec::{Backend, OursSource, PaperCell, PaperNumbers, Spec};
use visfield::experiment::table::{
    CellColumns, ErrorColumns, FieldColumns, Parts, Row, TimeColumns,
};
use visfield::field::{Precision, Selection};
use visfield::sampling::{LayoutKind, SphereKind};

type Csv = Vec<HashMap<String, String>>;

fn read(path: &Path) -> Csv {
    common::read_csv_maps(path)
}

fn read_optional(path: &Path) -> Csv {
    if path.exists() {
        read(path)
    } else {
        Vec::new()
    }
}

fn num(s: Option<&String>) -> Option<f64> {
    s.filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>().unwrap())
}

/// Column `name` of a row, or, in a table written before the names said what they hold for
/// every kind, the column it was called then.
fn col<'a>(r: &'a HashMap<String, String>, name: &str, was: &str) -> Option<&'a String> {
    r.get(name).or_else(|| r.get(was))
}

fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => Some(a / b),
        _ => None,
    }
}

/// Our side of one cell, as this test reads it.
#[derive(Debug, Default)]
struct Expected {
    cell: String,
    triangles: Option<f64>,
    rays_cast: Option<f64>,
    raycast_s: Option<f64>,
    bake_s: Option<f64>,
    bake_cached: Option<bool>,
    estimate_s: Option<f64>,
    rms_image: Option<f64>,
    rms_vertex: Option<f64>,
}

fn rays_of(r: &HashMap<String, String>) -> Option<f64> {
    num(r.get("rays_cast")).filter(|&n| n > 0.0)
}

fn cached(r: &HashMap<String, String>) -> bool {
    r["bake_cached"] == "true"
}

fn of_row(r: &HashMap<String, String>) -> Expected {
    Expected {
        cell: r["cell"].clone(),
        triangles: num(r.get("caster_triangles")),
        rays_cast: rays_of(r),
        raycast_s: num(r.get("raycast_s")),
        bake_s: num(r.get("bake_s")).filter(|_| !cached(r)),
        bake_cached: Some(cached(r)),
        estimate_s: num(col(r, "estimate_s", "ao_s")),
        rms_image: num(r.get("rms_image")),
        rms_vertex: num(r.get("rms_vertex")),
    }
}

/// The spec's cell (JSON) against one table row: every axis it sets, `scene` from `scene`.
fn row_matches(c: &serde_json::Value, scene: Option<&str>, r: &HashMap<String, String>) -> bool {
    let axes = [
        "sphere",
        "positional_samples",
        "directional_res",
        "layout",
        "precision",
        "selection",
    ];
    scene.is_none_or(|s| r["scene"] == s)
        && axes.iter().all(|a| match &c[*a] {
            serde_json::Value::Null => true,
            serde_json::Value::String(s) => r[*a] == *s,
            v => r[*a].parse::<u64>().ok() == v.as_u64(),
        })
}

fn expected(c: &serde_json::Value, table: &Csv, sweep: &Csv, pairs: &Csv) -> Expected {
    let first = |scene: Option<&str>| table.iter().find(|r| row_matches(c, scene, r));
    let scene = c["scene"].as_str();
    match c["ours"]["from"].as_str().unwrap_or("table") {
        "table" => {
            let Some(r) = first(scene) else {
                return Expected::default();
            };
            let mut e = of_row(r);
            if let Some(v) = c["versus_precision"].as_str() {
                let same = |p: &HashMap<String, String>| {
                    ["scene", "sphere", "positional_samples", "directional_res"]
                        .iter()
                        .chain(&["layout", "selection", "backend"])
                        .all(|a| p[*a] == r[*a])
                        && ((p["precision_a"] == r["precision"] && p["precision_b"] == v)
                            || (p["precision_a"] == v && p["precision_b"] == r["precision"]))
                };
                let p = pairs.iter().find(|p| same(p));
                e.rms_image = p.and_then(|p| num(p.get("rms_image")));
                e.rms_vertex = p.and_then(|p| num(p.get("rms_vertex")));
            }
            e
        }
        "raycast_sweep" => {
            let k = c["ours"]["rays_per_point"].as_u64().unwrap();
            let Some(r) = first(scene) else {
                return Expected::default();
            };
            let s = sweep.iter().find(|s| {
                s["scene"] == r["scene"]
                    && s["backend"] == r["backend"]
                    && s["rays_per_point"] == k.to_string()
            });
            let Some(s) = s else {
                return Expected::default();
            };
            let per_ray = num(r.get("rays_per_point")).unwrap();
            Expected {
                cell: format!("raycast_sweep:{}:{}:{k}", s["scene"], s["backend"]),
                triangles: num(r.get("caster_triangles")),
                rays_cast: rays_of(r).map(|n| n / per_ray * k as f64),
                raycast_s: num(col(s, "raycast_s", "ao_s")),
                rms_image: num(s.get("rms_image")),
                rms_vertex: num(s.get("rms_vertex")),
                ..Expected::default()
            }
        }
        "sum_of_scenes" => {
            let names: Vec<&str> = c["ours"]["scenes"]
                .as_array()
                .unwrap()
                .iter()
                .map(|n| n.as_str().unwrap())
                .collect();
            let Some(head) = first(Some(names[0])) else {
                return Expected::default();
            };
            let rows: Option<Vec<_>> = names
                .iter()
                .map(|n| {
                    table
                        .iter()
                        .find(|r| r["backend"] == head["backend"] && row_matches(c, Some(n), r))
                })
                .collect();
            let Some(rows) = rows else {
                return Expected::default();
            };
            let sum = |f: &dyn Fn(&HashMap<String, String>) -> Option<f64>| {
                rows.iter().map(|r| f(r)).sum::<Option<f64>>()
            };
            Expected {
                cell: rows
                    .iter()
                    .map(|r| r["cell"].as_str())
                    .collect::<Vec<_>>()
                    .join("+"),
                triangles: sum(&|r| num(r.get("caster_triangles"))),
                rays_cast: sum(&rays_of),
                raycast_s: sum(&|r| num(r.get("raycast_s"))),
                bake_s: sum(&|r| num(r.get("bake_s")).filter(|_| !cached(r))),
                bake_cached: Some(rows.iter().any(|r| cached(r))),
                estimate_s: sum(&|r| num(col(r, "estimate_s", "ao_s"))),
                ..Expected::default()
            }
        }
        other => panic!("unknown source {other}"),
    }
}

fn same(a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() <= 1e-12 * a.abs().max(b.abs()),
        (None, None) => true,
        _ => false,
    }
}

/// Every committed `results/NAME/paper_vs_ours.csv` of a spec with a paper section, every
/// `ours_*` column recomputed from the folder's tables.
#[test]
fn every_committed_paper_vs_ours_row_is_computed_from_the_cell_it_names() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut checked = 0;
    let mut specs: Vec<_> = std::fs::read_dir(root.join("experiments"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    specs.sort();
    for path in specs {
        let spec: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let Some(cells) = spec["paper"]["cells"].as_array() else {
            continue;
        };
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let dir = root.join("results").join(&name);
        let table = read(&dir.join("table.csv"));
        let sweep = read_optional(&dir.join("raycast_sweep.csv"));
        let pairs = read_optional(&dir.join("pairs.csv"));
        let got = read(&dir.join("paper_vs_ours.csv"));
        assert_eq!(got.len(), cells.len(), "{name}: one row per paper cell");
        let exp: Vec<Expected> = cells
            .iter()
            .map(|c| expected(c, &table, &sweep, &pairs))
            .collect();
        let ref_i = spec["paper"]["reference_cell"]
            .as_str()
            .map_or(0, |l| cells.iter().position(|c| c["label"] == l).unwrap());
        let re = &exp[ref_i];
        for ((c, e), g) in cells.iter().zip(&exp).zip(&got) {
            let at = format!("{name}, `{}`", g["label"]);
            assert_eq!(g["label"], c["label"].as_str().unwrap(), "{at}");
            assert_eq!(g["cell"], e.cell, "{at}: cell");
            let cols = [
                ("ours_triangles", "", e.triangles),
                ("ours_rays_cast", "", e.rays_cast),
                ("ours_raycast_s", "", e.raycast_s),
                ("ours_bake_s", "", e.bake_s),
                ("ours_estimate_s", "ours_ao_s", e.estimate_s),
                ("ours_rms_image", "", e.rms_image),
                ("ours_rms_vertex", "", e.rms_vertex),
                ("ours_raycast_rel", "", ratio(e.raycast_s, re.raycast_s)),
                ("ours_bake_rel", "", ratio(e.bake_s, re.bake_s)),
                (
                    "ours_estimate_rel",
                    "ours_ao_rel",
                    ratio(e.estimate_s, re.estimate_s),
                ),
            ];
            for (name, was, want) in cols {
                let have = num(col(g, name, was));
                assert!(
                    same(have, want),
                    "{at}: {name} is {have:?}, the tables give {want:?}"
                );
            }
            let bc = g.get("ours_bake_cached").filter(|s| !s.is_empty());
            assert_eq!(
                bc.map(|s| s == "true"),
                e.bake_cached,
                "{at}: ours_bake_cached"
            );
            checked += 1;
        }
    }
    assert!(checked >= 40, "only {checked} paper rows checked");
}

fn cell_columns(scene: &str, count: usize, backend: Backend, rays: u64) -> CellColumns {
    CellColumns {
        cell: format!("{scene}-{count}-{}", backend.name()),
        scene: scene.into(),
        sphere: SphereKind::Slater,
        positional_samples: count,
        directional_res: 32,
        layout: LayoutKind::Concentric,
        precision: Precision::U8,
        selection: Selection::Nearest,
        backend,
        adapter: String::new(),
        rays_per_point: 16,
        normal_bits: None,
        rays_cast: rays,
        receiver_points: 100,
        crease_points: 0,
        points_in_spheres: 0,
        caster_triangles: 1000 * count / 290,
        channels: 1,
    }
}

fn row(scene: &str, count: usize, backend: Backend, bake: (f64, bool), ao: f64) -> Row {
    // 100 points × 16 rays × 3 lights.
    Row::from_parts(&Parts {
        cell: cell_columns(scene, count, backend, 4800),
        times: TimeColumns {
            bake_s: Some(bake.0),
            estimate_s: ao,
            raycast_s: Some(10.0 * ao),
            ..TimeColumns::default()
        },
        fields: FieldColumns {
            bake_cached: bake.1,
            ..FieldColumns::default()
        },
        errors: ErrorColumns {
            rms_image: Some((count as f64 / 100.0, None)),
            ..ErrorColumns::default()
        },
    })
}

fn paper_cell(
    label: &str,
    scene: Option<&str>,
    count: Option<usize>,
    ours: OursSource,
) -> PaperCell {
    PaperCell {
        label: label.into(),
        scene: scene.map(String::from),
        positional_samples: count,
        ours,
        estimate_s: Some(1.0),
        preprocess_s: Some(2.0),
        ..PaperCell::default()
    }
}

#[test]
fn each_source_reads_its_own_measurement_and_ratios_go_to_the_reference_cell() {
    use Backend::{Cpu, Gpu};
    let rows = [
        row("a", 290, Cpu, (2.0, false), 0.1),
        row("a", 290, Gpu, (2.0, false), 0.01),
        row("a", 1090, Cpu, (76.0, true), 0.3),
        row("b", 290, Cpu, (1.0, false), 0.2),
    ];
    let sweep = [SweepRow {
        scene: "a".into(),
        backend: Cpu,
        rays_per_point: 1,
        raycast_s: 0.05,
        rms_vertex: None,
        rms_image: Some(9.0),
        raycast_kernel_s: None,
        rms_vs_truth: None,
        rms_vs_truth_sd: None,
        truth_stderr: None,
        flip_mean: None,
        flip_mean_vs_truth: None,
    }];
    let paper = PaperNumbers {
        source: "test".into(),
        reference_cell: Some("small".into()),
        cells: vec![
            paper_cell("big", Some("a"), Some(1090), OursSource::Table),
            paper_cell("small", Some("a"), Some(290), OursSource::Table),
            paper_cell(
                "sharp",
                Some("a"),
                Some(290),
                OursSource::RaycastSweep { rays_per_point: 1 },
            ),
            paper_cell(
                "per caster",
                None,
                Some(290),
                OursSource::SumOfScenes {
                    scenes: vec!["a".into(), "b".into()],
                },
            ),
            paper_cell("none", Some("a"), Some(4226), OursSource::Table),
        ],
    };
    let t = RunTables {
        rows: &rows,
        sweep: &sweep,
        pairs: &[],
    };
    let pv = paper_vs_ours(&paper, &t);
    let [big, small, sharp, sum, none] = &pv[..] else {
        panic!("{} rows", pv.len());
    };
    // The table row: rays with the lights (100 × 16 × 3); a cached bake is not a measurement.
    assert_eq!(big.cell, "a-1090-cpu");
    assert_eq!(big.ours_rays_cast, Some(4800));
    assert_eq!((big.ours_bake_s, big.ours_bake_cached), (None, Some(true)));
    assert_eq!(big.ours_bake_rel, None);
    assert_eq!(big.ours_rms_image, Some(10.9));
    assert!((big.ours_estimate_rel.unwrap() - 3.0).abs() < 1e-12);
    assert_eq!(big.paper_preprocess_rel, Some(1.0));
    // The first backend's row (CPU), its own bake.
    assert_eq!(
        (small.cell.as_str(), small.ours_bake_s),
        ("a-290-cpu", Some(2.0))
    );
    assert_eq!(small.ours_bake_rel, Some(1.0));
    // The sweep at 1 ray per light: 100 × 1 × 3 rays, its own time and error, no field.
    assert_eq!(sharp.cell, "raycast_sweep:a:cpu:1");
    assert_eq!(sharp.ours_rays_cast, Some(300));
    assert_eq!(
        (sharp.ours_raycast_s, sharp.ours_rms_image),
        (Some(0.05), Some(9.0))
    );
    assert_eq!((sharp.ours_estimate_s, sharp.ours_bake_s), (None, None));
    assert!((sharp.ours_raycast_rel.unwrap() - 0.05).abs() < 1e-12);
    // The sum over scenes a and b on the CPU: 0.1 + 0.2 s, 2 + 1 s of bake, no RMS.
    assert_eq!(sum.cell, "a-290-cpu+b-290-cpu");
    assert!((sum.ours_estimate_s.unwrap() - 0.3).abs() < 1e-12);
    assert_eq!(
        (sum.ours_bake_s, sum.ours_rays_cast),
        (Some(3.0), Some(9600))
    );
    assert_eq!((sum.ours_rms_image, sum.ours_triangles), (None, Some(2000)));
    assert_eq!(sum.ours_bake_rel, Some(1.5));
    // No 4226 row: ours empty.
    assert_eq!((none.cell.as_str(), none.ours_estimate_s), ("", None));
}

#[test]
fn a_table_from_before_rays_cast_leaves_ours_rays_cast_empty() {
    let mut r = row("a", 290, Backend::Cpu, (1.0, false), 0.1);
    r.rays_cast = 0;
    let paper = PaperNumbers {
        source: "test".into(),
        reference_cell: None,
        cells: vec![paper_cell("x", None, None, OursSource::Table)],
    };
    let t = RunTables {
        rows: &[r],
        sweep: &[],
        pairs: &[],
    };
    assert_eq!(paper_vs_ours(&paper, &t)[0].ours_rays_cast, None);
}

fn error_of(text: &str) -> String {
    Spec::parse(text, Path::new("t.json"))
        .expect_err("the spec should be refused")
        .to_string()
}

fn with_paper(cell: &str) -> String {
    common::tiny(r#"{ "counts": [290], "resolutions": [16] }"#, "").replace(
        r#""quick": {}"#,
        &format!(r#""paper": {{ "source": "t", "cells": [{cell}] }}, "quick": {{}}"#),
    )
}

#[test]
fn a_paper_source_is_validated_naming_the_field_and_value() {
    let ok =
        with_paper(r#"{ "label": "x", "ours": { "from": "raycast_sweep", "rays_per_point": 4 } }"#);
    Spec::parse(&ok, Path::new("t.json")).unwrap();
    let e = error_of(&with_paper(
        r#"{ "label": "x", "ours": { "from": "raycast_sweep", "rays_per_point": 9 } }"#,
    ));
    assert!(
        e.contains("paper.cells[0].ours.rays_per_point") && e.contains("9 rays"),
        "{e}"
    );
    let e = error_of(&with_paper(
        r#"{ "label": "x", "ours": { "from": "sum_of_scenes", "scenes": ["tiny", "nope"] } }"#,
    ));
    assert!(
        e.contains("paper.cells[0].ours.scenes[1]") && e.contains("nope"),
        "{e}"
    );
    let e = error_of(&with_paper(
        r#"{ "label": "x", "ours": { "from": "sum_of_scenes", "scenes": ["tiny"] } }"#,
    ));
    assert!(
        e.contains("paper.cells[0].ours.scenes") && e.contains("at least two"),
        "{e}"
    );
    let e = error_of(&with_paper(r#"{ "label": "x", "scene": "nope" }"#));
    assert!(
        e.contains("paper.cells[0].scene") && e.contains("nope"),
        "{e}"
    );
    let e = error_of(&with_paper(
        r#"{ "label": "x", "ours": { "from": "elsewhere" } }"#,
    ));
    assert!(e.contains("elsewhere"), "{e}");
}

/// A real run of the tiny spec with paper cells of each source: the runner's file pairs the
/// sharp cell with `raycast_sweep.csv`'s 4-ray cast, and rewriting it from the run's CSV
/// files (what `experiment plots` does) gives the same bytes.
#[test]
fn a_run_writes_each_source_and_a_rewrite_from_its_csvs_is_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let text = with_paper(
        r#"{ "label": "field", "estimate_s": 2.0 },
           { "label": "sharp", "raycast_s": 20.0,
             "ours": { "from": "raycast_sweep", "rays_per_point": 4 } }"#,
    );
    let ls = common::loaded(dir.path(), &text);
    let out = dir.path().join("out");
    visfield::experiment::run::run(&ls, &common::options(out.clone())).unwrap();
    let written = std::fs::read(out.join("paper_vs_ours.csv")).unwrap();
    let pv = read(&out.join("paper_vs_ours.csv"));
    let table = read(&out.join("table.csv"));
    let sweep = read(&out.join("raycast_sweep.csv"));
    let s4 = sweep
        .iter()
        .find(|s| s["rays_per_point"] == "4" && s["backend"] == "cpu")
        .unwrap();
    assert_eq!(pv[0]["cell"], table[0]["cell"]);
    assert_eq!(pv[0]["ours_rays_cast"], table[0]["rays_cast"]);
    assert_eq!(pv[1]["cell"], "raycast_sweep:tiny:cpu:4");
    assert_eq!(pv[1]["ours_raycast_s"], s4["raycast_s"]);
    assert_eq!(pv[1]["ours_rms_image"], s4["rms_image"]);
    // 16 rays per point in the table, 4 in the sweep: a quarter of its rays.
    let rays: u64 = table[0]["rays_cast"].parse().unwrap();
    assert_eq!(pv[1]["ours_rays_cast"], (rays / 4).to_string());
    // Uncached (no cache in the test): the bake is the run's own.
    assert_eq!(pv[0]["ours_bake_cached"], "false");
    assert_eq!(pv[0]["ours_bake_s"], table[0]["bake_s"]);
    std::fs::remove_file(out.join("paper_vs_ours.csv")).unwrap();
    let paper = ls.spec.paper.as_ref().unwrap();
    assert!(visfield::experiment::paper::rewrite(&out, paper).unwrap());
    assert_eq!(
        std::fs::read(out.join("paper_vs_ours.csv")).unwrap(),
        written
    );
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let dest = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &dest);
        } else {
            std::fs::copy(e.path(), dest).unwrap();
        }
    }
}

/// `experiment plots --dir` on a copy of a committed run whose paper_vs_ours.csv is stale
/// writes the committed file back, from the copy's CSVs and the spec's paper section.
#[test]
fn experiment_plots_rewrites_a_stale_paper_vs_ours_from_the_runs_csvs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let committed = root.join("results/shadows2010_figure8");
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("shadows2010_figure8");
    copy_dir(&committed, &copy);
    let stale = "label,cell\nGPU BVH,copied\n";
    std::fs::write(copy.join("paper_vs_ours.csv"), stale).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_experiment"))
        .args(["plots", "--dir"])
        .arg(&copy)
        .current_dir(root)
        .env_remove("VISFIELD_EXPERIMENTS")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("rewrote"));
    // The committed file, under the names of this build where it was written before they
    // said what they hold for every kind (the same bytes once the run is regenerated).
    let renamed = |r: HashMap<String, String>| -> HashMap<String, String> {
        r.into_iter()
            .map(|(k, v)| {
                let k = match k.as_str() {
                    "paper_ao_s" => "paper_estimate_s".into(),
                    "ours_ao_s" => "ours_estimate_s".into(),
                    "paper_ao_rel" => "paper_estimate_rel".into(),
                    "ours_ao_rel" => "ours_estimate_rel".into(),
                    _ => k,
                };
                (k, v)
            })
            .collect()
    };
    let want: Csv = read(&committed.join("paper_vs_ours.csv"))
        .into_iter()
        .map(renamed)
        .collect();
    assert_eq!(read(&copy.join("paper_vs_ours.csv")), want);
}
