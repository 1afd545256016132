//! FLIP and flicker: the reference implementation's published values on its test pair, zero on
//! identical images and on a scene that does not move, the flicker formula on a synthetic
//! sequence with a known step, and the columns and maps a run writes (its cells' and its ray-cast
//! sweep's).

use std::path::Path;
use visfield::experiment::flip::{self, FlipMap};
use visfield::experiment::metrics::flicker;
use visfield::experiment::outputs::{read_csv, SweepRow};
use visfield::experiment::run::frames::FrameRow;
use visfield::experiment::run::run;
use visfield::experiment::table::Row;
use visfield::render::image::Image;

mod common;
use common::{animated, frames_of, loaded, options, tiny, ONE_FIELD, ORBIT};

fn rgb8(path: &Path) -> (u32, u32, Vec<u8>) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_rgb8();
    (img.width(), img.height(), img.into_raw())
}

/// The pair the `nv-flip` crate tests against (tests/data/flip/README.md): the FLIP tool's
/// printed mean 0.133285 and weighted median 0.333241 at 67 pixels per degree, to the printed
/// six digits, with every pixel pooled.
#[test]
fn flip_gives_the_reference_tools_printed_values_on_its_test_pair() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/flip");
    let (w, h, reference) = rgb8(&dir.join("tree-ref.png"));
    let (w2, h2, test) = rgb8(&dir.join("tree-test.png"));
    assert_eq!((w, h), (w2, h2));
    let map = flip::flip_rgb8(w, h, &reference, &test, flip::PIXELS_PER_DEGREE);
    let s = map.pool(None).unwrap();
    let printed = |v: f64| format!("{v:.6}");
    assert_eq!(printed(s.mean), "0.133285", "{s:?}");
    assert_eq!(printed(s.weighted_median), "0.333241", "{s:?}");
    // The largest error the tool prints.
    let max = map.values.iter().copied().fold(0.0f32, f32::max);
    assert_eq!(printed(max as f64), "0.983044");
}

/// Identical images give a map of zeros, whatever their content; FLIP of a real difference
/// lies in (0, 1].
#[test]
fn identical_images_give_flip_zero() {
    let (w, h) = (48u32, 40u32);
    let a = Image {
        width: w,
        height: h,
        channels: 3,
        data: (0..w * h * 3)
            .map(|i| ((i * 37) % 101) as f32 / 100.0)
            .collect(),
    };
    let map = flip::flip(&a, &a);
    assert!(map.values.iter().all(|&v| v == 0.0));
    let s = map.pool(None).unwrap();
    assert_eq!((s.mean, s.weighted_median), (0.0, 0.0));
    let mut b = a.clone();
    for v in b.data.iter_mut().take(3 * 200) {
        *v = 1.0 - *v;
    }
    let s = flip::flip(&a, &b).pool(None).unwrap();
    assert!(
        s.mean > 0.0 && s.weighted_median > 0.0 && s.weighted_median <= 1.0,
        "{s:?}"
    );
}

/// A synthetic sequence: the reference a gradient moving one step a frame, the method the
/// reference plus an error that steps by d_f on the left half of the image (and holds on the
/// right): the flicker is 255 · |d_f| · √(1/2) over every pixel, 255 · |d_f| over the left half,
/// and 0 for the reference plus a constant error.
#[test]
fn a_known_step_gives_the_flicker_the_formula_predicts() {
    let (w, h) = (64usize, 32usize);
    let truth = |f: usize| -> Vec<f32> {
        (0..w * h)
            .map(|i| ((i % w + 3 * f) % w) as f32 / w as f32)
            .collect()
    };
    // The error at frame f on the left half: the steps 0.01, 0.03, −0.02 between frames.
    let level = [0.0f32, 0.01, 0.04, 0.02];
    let method = |f: usize| -> Vec<f32> {
        (truth(f).iter().enumerate())
            .map(|(i, &t)| t + if i % w < w / 2 { level[f] } else { 0.0 } + 0.1)
            .collect()
    };
    let all = vec![true; w * h];
    let left: Vec<bool> = (0..w * h).map(|i| i % w < w / 2).collect();
    for f in 1..4 {
        let d = (level[f] - level[f - 1]) as f64;
        let (m0, m1, t0, t1) = (method(f - 1), method(f), truth(f - 1), truth(f));
        let over_all = flicker(&m0, &m1, &t0, &t1, &all);
        let over_left = flicker(&m0, &m1, &t0, &t1, &left);
        assert!(
            (over_all - 255.0 * d.abs() * 0.5f64.sqrt()).abs() < 1e-3,
            "{over_all}"
        );
        assert!((over_left - 255.0 * d.abs()).abs() < 1e-3, "{over_left}");
        // The reference plus a constant: only f32 rounding.
        let plus: Vec<f32> = t0.iter().map(|v| v + 0.1).collect();
        let plus1: Vec<f32> = t1.iter().map(|v| v + 0.1).collect();
        assert!(flicker(&plus, &plus1, &t0, &t1, &all) < 1e-4);
        // Identical frames of the reference itself: exactly 0.
        assert_eq!(flicker(&t1, &t1, &t1, &t1, &all), 0.0);
    }
}

/// An animation whose scene does not move: every method's answer and the converged
/// reference's are the same every frame, so every method flickers exactly 0 from frame 1 on
/// (per vertex and per pixel), the frames' FLIP change is 0, and frame 0 has no flicker.
#[test]
fn a_static_scene_flickers_zero_for_every_method() {
    let dir = tempfile::tempdir().unwrap();
    let still = animated("", "", r#"{ "frames": 3, "time_step": 0.5 }"#);
    for what in ["vertex_ao", "image_ao"] {
        let text = still.replace(
            r#""render": { "#,
            &format!(r#""render": {{ "what": "{what}", "#),
        );
        let rows = frames_of(dir.path(), &text, &format!("still-{what}"));
        assert!(rows.iter().any(|r| r.method.starts_with("field")));
        for r in &rows {
            if r.frame == 0 {
                assert_eq!((r.flicker, r.raycast_flicker), (None, None), "{r:?}");
                assert_eq!(
                    (r.flip_frame_change, r.truth_flip_frame_change),
                    (None, None)
                );
                continue;
            }
            assert_eq!(r.flicker, Some(0.0), "{what}: {r:?}");
            assert_eq!(r.raycast_flicker, Some(0.0), "{what}: {r:?}");
            assert!(r.flicker_points.unwrap() > 0);
            assert_eq!(r.flip_frame_change, Some(0.0), "{what}: {r:?}");
            assert_eq!(r.truth_flip_frame_change, Some(0.0), "{what}: {r:?}");
        }
    }
}

/// A moving caster: the ray cast's flicker is `world_rebuild`'s own, the fields' flicker is
/// positive, every FLIP lies in [0, 1] and the ray cast's FLIP against itself is 0.
#[test]
fn a_moving_scene_has_flicker_and_flip_columns() {
    let dir = tempfile::tempdir().unwrap();
    let text = animated(ORBIT, "", r#"{ "frames": 3, "time_step": 0.5 }"#);
    let rows: Vec<FrameRow> = frames_of(dir.path(), &text, "moving");
    for r in &rows {
        let unit = |v: Option<f64>| v.is_some_and(|v| (0.0..=1.0).contains(&v));
        assert!(
            unit(r.flip_mean_vs_raycast) && unit(r.flip_mean_vs_truth),
            "{r:?}"
        );
        assert!(unit(r.flip_weighted_median_vs_truth), "{r:?}");
        if r.method == "world_rebuild" {
            assert_eq!(r.flip_mean_vs_raycast, Some(0.0));
            assert_eq!(r.flicker, r.raycast_flicker);
        }
        if r.frame > 0 && r.method.starts_with("field") {
            assert!(r.flicker.unwrap() > 0.0, "{r:?}");
            assert!(unit(r.flip_frame_change), "{r:?}");
        }
    }
    let out = dir.path().join("moving");
    for plot in ["flicker-tiny.png", "flip-tiny.png", "flip_change-tiny.png"] {
        assert!(out.join(plot).is_file(), "{plot}");
    }
}

/// A static run's table: the FLIP columns against the same-ray reference and the converged
/// one for every cell with an image, in [0, 1], and each written map the magma colouring of
/// FLIP recomputed from the written PNGs (the cell's image against the reference's).
#[test]
fn a_runs_table_has_the_flip_columns_and_maps_of_its_pngs() {
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &tiny(ONE_FIELD, ""));
    let out = dir.path().join("run");
    let rows: Vec<Row> = run(&ls, &options(out.clone())).unwrap().rows;
    assert!(!rows.is_empty());
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(json["flip"]["pixels_per_degree"], 67.0);
    for r in &rows {
        for v in [
            r.flip_mean,
            r.flip_weighted_median,
            r.flip_mean_vs_truth,
            r.flip_weighted_median_vs_truth,
        ] {
            assert!(v.is_some_and(|v| (0.0..=1.0).contains(&v)), "{r:?}");
        }
        assert!(r.flip_mean.unwrap() > 0.0, "a field's image differs: {r:?}");
        let (w, h, cell) = rgb8(&out.join(&r.image));
        let (_, _, reference) = rgb8(&out.join(format!("images/{}-reference.png", r.scene)));
        let (_, _, truth) = rgb8(&out.join(format!("images/{}-truth.png", r.scene)));
        for (against, suffix) in [(&reference, "flip"), (&truth, "flip_vs_truth")] {
            let map: FlipMap = flip::flip_rgb8(w, h, against, &cell, flip::PIXELS_PER_DEGREE);
            let written = out.join(r.image.replace(".png", &format!("-{suffix}.png")));
            let (_, _, magma) = rgb8(&written);
            assert_eq!(magma, map.magma_rgb8(), "{}", written.display());
        }
    }
    // The ray-cast sweep (4 and 16 rays; 16 is the reference's count): the reference's row
    // shows no difference from itself; 4 rays do, and against the converged reference their
    // noise shows more than 16 rays'.
    let sweep: Vec<SweepRow> = read_csv(&out.join("raycast_sweep.csv")).unwrap();
    let at = |k: u32| {
        (sweep.iter().find(|s| s.rays_per_point == k)).unwrap_or_else(|| panic!("{k}: {sweep:?}"))
    };
    let (four, sixteen) = (at(4), at(16));
    assert_eq!(sixteen.flip_mean, Some(0.0), "{sixteen:?}");
    assert!(
        four.flip_mean.is_some_and(|f| f > 0.0 && f <= 1.0),
        "{four:?}"
    );
    let vs_truth = |s: &SweepRow| {
        s.flip_mean_vs_truth
            .filter(|f| *f > 0.0 && *f <= 1.0)
            .unwrap()
    };
    assert!(vs_truth(four) > vs_truth(sixteen), "{four:?}\n{sixteen:?}");
}
