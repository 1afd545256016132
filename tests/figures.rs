//! `experiment plots` on a small synthetic results folder: a folder written before
//! `methods.csv` existed still draws (and gets `error_vs_bytes.png`), one with `methods.csv`
//! draws its methods, and the image grids tint empty space where the run wrote its coverage.

use std::path::Path;
use visfield::experiment::figures::{self, grids, RunData};

const HEADER: &str = "scene,cell,positional_samples,directional_res,layout,precision,selection,\
backend,adapter,estimate_s,field_bytes,sphere,rays_per_point,receiver_points,caster_triangles,\
bake_rays,bake_cached,image,rms_image,rms_vs_truth,truth_stderr,truth_rays,bake_s";

/// A run of 2 positional counts × 2 resolutions on the CPU, with ray casting swept, images
/// where `images` (8 × 8 PNGs, the reference's left half empty space).
fn write_run(dir: &Path, images: bool) {
    let mut table = format!("{HEADER}\n");
    for (n, res, rms) in [
        (290, 16, 4.0),
        (290, 32, 3.5),
        (1090, 16, 3.0),
        (1090, 32, 2.5),
    ] {
        let cell = format!("s-slater-{n}-concentric-{res}-u8-nearest-cpu");
        let image = if images {
            format!("images/{cell}.png")
        } else {
            String::new()
        };
        table.push_str(&format!(
            "s,{cell},{n},{res},concentric,u8,nearest,cpu,CPU,0.01,{},slater,64,100,1000,1,\
             false,{image},{rms},{rms},0.1,4096,0.2\n",
            n * res * res
        ));
    }
    std::fs::write(dir.join("table.csv"), table).unwrap();
    let mut sweep = String::from(
        "scene,backend,rays_per_point,raycast_s,rms_vertex,rms_image,raycast_kernel_s,\
         rms_vs_truth,rms_vs_truth_sd,truth_stderr\n",
    );
    for (k, e) in [(16, 9.0), (64, 4.5)] {
        let same = if k == 64 { 0.0 } else { e };
        sweep.push_str(&format!(
            "s,cpu,{k},{},,{same},,{e},,0.1\n",
            k as f64 * 1e-3
        ));
    }
    std::fs::write(dir.join("raycast_sweep.csv"), sweep).unwrap();
    std::fs::write(
        dir.join("run.json"),
        r#"{"render": "image_ao", "quantity": "ao"}"#,
    )
    .unwrap();
    if images {
        std::fs::create_dir_all(dir.join("images")).unwrap();
        let grey = image::GrayImage::from_pixel(8, 8, image::Luma([255]));
        grey.save(dir.join("images/s-reference.png")).unwrap();
        for name in std::fs::read_to_string(dir.join("table.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(1).unwrap().to_string())
        {
            grey.save(dir.join(format!("images/{name}.png"))).unwrap();
            grey.save(dir.join(format!("images/{name}-diff_x5.png")))
                .unwrap();
        }
        let cover =
            image::GrayImage::from_fn(8, 8, |x, _| image::Luma([if x < 4 { 0 } else { 255 }]));
        cover.save(grids::coverage_path(dir, "s")).unwrap();
    }
}

fn write_methods(dir: &Path) {
    let mut csv = String::from(
        "scene,method,setting,res,precision,query,backend,precompute_s,bytes,estimate_s,rms_vs_truth,image\n",
    );
    csv.push_str("s,raycast,raycast,,,,cpu,0.05,2500000,0.064,4.5,\n");
    csv.push_str("s,embree,embree,,,,cpu,0.04,,0.03,4.5,\n");
    for res in [32, 64] {
        for q in ["trace", "cone"] {
            csv.push_str(&format!(
                "s,sdf,sdf-{res}-f16-{q},{res},f16,{q},cpu,0.5,{},0.02,{},\n",
                res * res * res * 2,
                if q == "cone" { 40.0 } else { 5.0 }
            ));
        }
    }
    std::fs::write(dir.join("methods.csv"), csv).unwrap();
}

#[test]
fn a_folder_without_methods_still_draws_every_plot() {
    let dir = tempfile::tempdir().unwrap();
    write_run(dir.path(), false);
    figures::draw_all(dir.path(), "synthetic").unwrap();
    for f in ["pareto.png", "error_vs_bytes.png", "rms_vs_positional.png"] {
        let img = image::open(dir.path().join(f)).unwrap();
        assert!(img.width() >= 1000, "{f}");
    }
    // No images: no grids.
    assert!(!dir.path().join("images.png").exists());
    // Without methods: no overview panel, the field beside ray casting.
    let run = RunData::load(dir.path(), "synthetic").unwrap();
    assert!(run.methods.is_empty());
    let pareto = figures::compare::pareto(&run);
    assert_eq!(pareto.panels.len(), 1);
    assert!(pareto.axes.x_label.starts_with("AO estimate time"));
}

#[test]
fn a_folder_with_methods_puts_them_on_both_comparison_plots() {
    let dir = tempfile::tempdir().unwrap();
    write_run(dir.path(), false);
    write_methods(dir.path());
    figures::draw_all(dir.path(), "synthetic").unwrap();
    let run = RunData::load(dir.path(), "synthetic").unwrap();
    assert_eq!(run.methods.len(), 6);
    assert_eq!(run.methods[2].param("query"), Some("trace"));
    let labels = |f: &visfield::experiment::plot::Figure| -> Vec<String> {
        f.panels
            .iter()
            .flat_map(|p| p.series.iter().map(|s| s.series.label.clone()))
            .collect()
    };
    // A label names the settings that vary among the method's rows: every row here is f16.
    let pareto = labels(&figures::compare::pareto(&run));
    for m in [
        "raycast",
        "embree",
        "sdf trace (res 32/64)",
        "sdf cone (res 32/64)",
    ] {
        assert!(pareto.iter().any(|l| l == m), "{m} not in {pareto:?}");
    }
    let bytes_fig = figures::compare::bytes(&run);
    let bytes = labels(&bytes_fig);
    assert!(bytes.iter().any(|l| l == "sdf trace (res 32/64)"));
    assert!(!bytes.iter().any(|l| l.starts_with("embree")));
    assert!(bytes_fig.notes.iter().any(|n| n.ends_with("embree")));
}

#[test]
fn the_image_grid_tints_empty_space() {
    let dir = tempfile::tempdir().unwrap();
    write_run(dir.path(), true);
    figures::draw_all(dir.path(), "synthetic").unwrap();
    let grid = image::open(dir.path().join("images.png"))
        .unwrap()
        .to_rgb8();
    // Every image is white; the reference's and the fields' uncovered halves show in the
    // empty-space colour, somewhere in the grid.
    let tinted = grid.pixels().filter(|p| p.0 == grids::EMPTY).count();
    // 5 images (the reference and 4 cells) × 32 uncovered pixels.
    assert_eq!(tinted, 5 * 32);
    assert!(dir.path().join("differences.png").exists());
}
