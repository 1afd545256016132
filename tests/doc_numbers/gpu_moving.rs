//! The moving scenes' GPU rows beside their CPU twins (docs/results.md): each
//! per-frame method's mean update and query per frame in the GPU crowds (per pixel and per
//! vertex) and the animated 2008 Figure 8, and how far each GPU twin's answers are from its CPU
//! twin's.

use super::{f, read, Claims, Row};

/// The committed animated runs with GPU rows, as the table's columns name them.
const RUNS: [(&str, &str); 3] = [
    ("dynamic2010_crowd_gpu", "64 casters, per pixel"),
    ("dynamic2008_crowd_gpu", "64 casters, per vertex"),
    ("dynamic2008_figure8", "2008 Figure 8 animated"),
];

/// The per-frame methods in the table's order, each GPU twin after its CPU method.
const METHODS: [&str; 11] = [
    "world_rebuild",
    "world_rebuild@gpu",
    "embree_instances",
    "two_level",
    "two_level@gpu",
    "rayquery@gpu",
    "field_every_sphere",
    "field_every_sphere@gpu",
    "field",
    "field@gpu",
    "embree_rebuild",
];

/// The CPU method each GPU twin answers as.
const TWINS: [(&str, &str); 5] = [
    ("world_rebuild@gpu", "world_rebuild"),
    ("two_level@gpu", "two_level"),
    ("rayquery@gpu", "two_level"),
    ("field_every_sphere@gpu", "field_every_sphere"),
    ("field@gpu", "field"),
];

fn mean(rows: &[&Row], col: &str) -> f64 {
    rows.iter().map(|r| f(r, col)).sum::<f64>() / rows.len() as f64
}

/// The table of mean update and query per frame, and the twins' largest differences.
pub fn gpu_moving(c: &mut Claims) {
    let runs: Vec<Vec<Row>> = RUNS
        .iter()
        .map(|(name, _)| read(&format!("results/{name}/frames.csv")))
        .collect();
    let mut table = String::from("| method |");
    for (_, label) in RUNS {
        table.push_str(&format!(" {label}: update / query (s) |"));
    }
    table.push_str("\n|---|---|---|---|\n");
    for m in METHODS {
        let cells: Vec<String> = runs
            .iter()
            .map(|rows| {
                let of: Vec<&Row> = rows.iter().filter(|r| r["method"] == m).collect();
                if of.is_empty() {
                    "—".to_string()
                } else {
                    format!("{:.4} / {:.3}", mean(&of, "update_s"), mean(&of, "query_s"))
                }
            })
            .collect();
        if cells.iter().all(|c| c == "—") {
            continue;
        }
        table.push_str(&format!("| `{m}` | {} |\n", cells.join(" | ")));
    }
    let from =
        "results/{dynamic2010_crowd_gpu,dynamic2008_crowd_gpu,dynamic2008_figure8}/frames.csv";
    c.quotes("docs/results.md", &table, from);
    // Each GPU twin against its CPU method, frame by frame and cell by cell.
    let (mut d_rms, mut d_mean, mut pairs) = (0.0f64, 0.0f64, 0);
    for rows in &runs {
        let (r, m, n) = twin_gaps(rows, &TWINS);
        (d_rms, d_mean, pairs) = (d_rms.max(r), d_mean.max(m), pairs + n);
    }
    let text = format!(
        "over the {pairs} frames of a GPU twin in the three runs, its error against the same-ray \
         ray cast differs from its CPU twin's by at most {d_rms:.2e} (of 255) and its mean value \
         by at most {d_mean:.2e}"
    );
    c.quotes("docs/results.md", &text, from);
}

/// The largest differences between each GPU twin's rows of `rows` and its CPU method's (the
/// same frame and field cell): of the same-ray error, of the mean value, and how many rows.
pub fn twin_gaps(rows: &[Row], twins: &[(&str, &str)]) -> (f64, f64, usize) {
    let (mut d_rms, mut d_mean, mut pairs) = (0.0f64, 0.0f64, 0);
    for &(gpu, cpu) in twins {
        for g in rows.iter().filter(|r| r["method"] == gpu) {
            let twin = rows
                .iter()
                .find(|r| {
                    r["method"] == cpu
                        && r["frame"] == g["frame"]
                        && r["cell"] == g["cell"].replace("-gpu", "-cpu")
                })
                .unwrap_or_else(|| panic!("no {cpu} twin of {gpu} frame {}", g["frame"]));
            d_rms = d_rms.max((f(g, "rms_vs_raycast") - f(twin, "rms_vs_raycast")).abs());
            d_mean = d_mean.max((f(g, "mean_value") - f(twin, "mean_value")).abs());
            pairs += 1;
        }
    }
    (d_rms, d_mean, pairs)
}
