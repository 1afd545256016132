//! docs/results.md's "Where FLIP orders the methods otherwise than RMS": every pair of images of
//! a committed run (the field's cells of `table.csv`, the per-object peers and ray casters of
//! `methods.csv`, the ray casts of `raycast_sweep.csv`) whose order under the mean FLIP differs
//! from their order under the RMS, recomputed from the files.

use super::{read, Claims, Row};
use visfield::experiment::outputs::{table_path, SWEEP_FRAMES_CSV};

/// The committed runs whose tables carry FLIP columns, with the images they compare.
pub const SPECS: [&str; 18] = [
    "selection",
    "figure5",
    "fibonacci",
    "storage",
    "figure6",
    "figure7",
    "figure7_linear",
    "figure7_unbounded",
    "figure8",
    "ao2010_figure3",
    "ao2010_figure4",
    "ao2010_figure5",
    "ao2010_models",
    "ao2010_sponza",
    "ao2010_elongated",
    "shadows2010_figure7",
    "shadows2010_figure8",
    "reflections2010_figure9",
];

/// Two images whose errors differ by less than this share (of the larger) under either measure
/// are a near tie.
const NEAR_TIE: f64 = 0.05;

/// One image of a run under both measures: (RMS, mean FLIP) against the same-ray ray cast and
/// against the converged reference, where the run compares it so.
struct Image {
    scene: String,
    label: String,
    vs_ray: Option<(f64, f64)>,
    vs_truth: Option<(f64, f64)>,
}

fn number(r: &Row, col: &str) -> Option<f64> {
    r.get(col).and_then(|v| v.parse().ok())
}

fn pair(r: &Row, rms: &str, flip: &str) -> Option<(f64, f64)> {
    Some((number(r, rms)?, number(r, flip)?))
}

/// The CPU images of a committed run: its cells, its methods and its ray-cast sweep.
fn images(name: &str) -> Vec<Image> {
    let dir = format!("results/{name}");
    let cpu = |r: &Row| r.get("backend").is_none_or(|b| b == "cpu");
    let mut out = Vec::new();
    for r in read(&format!("{dir}/table.csv")).iter().filter(|r| cpu(r)) {
        let cell = r["cell"].as_str();
        let cell = cell
            .strip_prefix(&format!("{}-", r["scene"]))
            .unwrap_or(cell);
        out.push(Image {
            scene: r["scene"].clone(),
            label: cell.strip_suffix("-cpu").unwrap_or(cell).to_string(),
            vs_ray: pair(r, "rms_image", "flip_mean"),
            vs_truth: pair(r, "rms_vs_truth", "flip_mean_vs_truth"),
        });
    }
    if super::root().join(&dir).join("methods.csv").exists() {
        for r in read(&format!("{dir}/methods.csv"))
            .iter()
            .filter(|r| cpu(r))
        {
            out.push(Image {
                scene: r["scene"].clone(),
                label: r["setting"].clone(),
                vs_ray: pair(r, "rms_image", "flip_mean"),
                vs_truth: pair(r, "rms_vs_truth", "flip_mean_vs_truth"),
            });
        }
    }
    if super::root().join(&dir).join("raycast_sweep.csv").exists() {
        for r in read(&format!("{dir}/raycast_sweep.csv"))
            .iter()
            .filter(|r| cpu(r))
        {
            out.push(Image {
                scene: r["scene"].clone(),
                label: format!("ray cast, {} rays", r["rays_per_point"]),
                // Against the same-ray reference a sweep's other ray counts are other rays.
                vs_ray: None,
                vs_truth: pair(r, "rms_vs_truth", "flip_mean_vs_truth"),
            });
        }
    }
    out
}

/// Whether `a` and `b` are ordered otherwise by FLIP than by RMS, and if so whether either
/// measure nearly ties them.
fn discordant(a: (f64, f64), b: (f64, f64)) -> Option<bool> {
    let apart = |x: f64, y: f64| (x - y).abs() / x.abs().max(y.abs());
    ((a.0 - b.0) * (a.1 - b.1) < 0.0)
        .then(|| apart(a.0, b.0) < NEAR_TIE || apart(a.1, b.1) < NEAR_TIE)
}

/// The summary table (per run: images, pairs, discordant pairs, of them near ties) and the
/// table of the discordant pairs that are no near tie.
pub fn rankings(c: &mut Claims) {
    let mut summary = String::new();
    let mut clear = String::new();
    for name in SPECS {
        let images = images(name);
        assert!(
            images.iter().any(|i| i.vs_truth.is_some()),
            "results/{name}: no image with FLIP columns"
        );
        let (mut pairs, mut against, mut ties) = (0, 0, 0);
        for (i, a) in images.iter().enumerate() {
            for b in images[i + 1..].iter().filter(|b| b.scene == a.scene) {
                for (measure, x, y) in [
                    ("the ray cast", a.vs_ray, b.vs_ray),
                    ("the truth", a.vs_truth, b.vs_truth),
                ] {
                    let (Some(x), Some(y)) = (x, y) else { continue };
                    pairs += 1;
                    match discordant(x, y) {
                        None => {}
                        Some(true) => (against, ties) = (against + 1, ties + 1),
                        Some(false) => {
                            against += 1;
                            clear.push_str(&format!(
                                "| `{name}` | `{}` / `{}` | {measure} | {:.3} / {:.3} | {:.4} / {:.4} |\n",
                                a.label, b.label, x.0, y.0, x.1, y.1
                            ));
                        }
                    }
                }
            }
        }
        summary.push_str(&format!(
            "| `{name}` | {} | {pairs} | {against} | {ties} |\n",
            images.len()
        ));
    }
    c.quotes(
        "docs/results.md",
        &summary,
        "results/*/{table,methods,raycast_sweep}.csv",
    );
    c.quotes(
        "docs/results.md",
        &clear,
        "results/*/{table,methods,raycast_sweep}.csv",
    );
}

/// The header of a committed CSV file.
fn header(path: &std::path::Path) -> Vec<String> {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    r.headers().unwrap().iter().map(String::from).collect()
}

/// Every committed run that compares images or frames (under results/ and results/quick/) has
/// the FLIP columns (the cells' `table.csv` and `methods.csv` where the run wrote images, an
/// animated run's `frames.csv`) and an animated run the flicker columns; `experiment dynamic`'s
/// crowd, which answers vertices without an image, its flicker.
#[test]
fn every_committed_run_with_images_or_frames_has_flip_and_flicker() {
    let mut runs = Vec::new();
    for base in ["results", "results/quick"] {
        for e in std::fs::read_dir(super::root().join(base)).unwrap() {
            let dir = e.unwrap().path();
            if dir.join("run.json").exists() {
                runs.push(dir);
            }
        }
    }
    assert!(runs.len() > 40, "{} committed runs", runs.len());
    let mut checked = 0;
    for dir in &runs {
        let wants = |file: &str, cols: &[&str]| {
            let head = header(&table_path(dir, file));
            for c in cols {
                assert!(
                    head.iter().any(|h| h == c),
                    "{}/{file}: no `{c}`",
                    dir.display()
                );
            }
        };
        if dir.join("frames.csv").exists() {
            wants(
                "frames.csv",
                &[
                    "flip_mean_vs_truth",
                    "flicker",
                    "raycast_flicker",
                    "flip_frame_change",
                ],
            );
        } else if dir.join("images").is_dir() && dir.join("table.csv").exists() {
            wants("table.csv", &["flip_mean", "flip_mean_vs_truth"]);
            if dir.join("methods.csv").exists() {
                wants("methods.csv", &["flip_mean", "flip_mean_vs_truth"]);
            }
        } else if dir.file_name().is_some_and(|n| n == "dynamic") {
            wants(SWEEP_FRAMES_CSV, &["flicker", "raycast_flicker"]);
        } else {
            continue;
        }
        checked += 1;
    }
    assert!(checked > 30, "{checked} runs with images or frames");
}
