//! Helpers shared by the integration tests: the tiny procedural spec and its run options.
#![allow(dead_code)]

pub mod batch_rays;
pub mod mesh_files;

use std::path::{Path, PathBuf};
use visfield::experiment::fields::FieldSupply;
use visfield::experiment::run::{LoadedSpec, RunOptions};
use visfield::field::{FieldParams, Precision};
use visfield::sampling::{LayoutKind, SphereKind};

/// A tiny procedural spec: a 2,000-triangle supershape fitted over a 9 × 9 corner, 290 Slater
/// maps × 16² concentric texels, 16 rays per vertex, a 32 × 32 image. `fields` and
/// `thresholds` are spliced in as JSON.
pub fn tiny(fields: &str, thresholds: &str) -> String {
    format!(
        r#"{{
  "reproduces": "test",
  "scenes": [{{
    "name": "tiny",
    "instances": [
      {{ "mesh": {{ "corner": {{ "n": 9 }} }}, "receiver": true }},
      {{ "mesh": {{ "supershape": {{ "triangles": 2000 }} }}, "caster": true,
         "transform": {{ "fit": {{ "center": [0.5, 0.45, 0.5], "radius": 0.35 }} }} }}
    ]
  }}],
  "fields": [{fields}],
  "render": {{ "rays_per_point": 16, "image": {{ "width": 32, "height": 32 }} }},
  "reference": {{ "rays_per_point": 16, "raycast_sweep": [4, 16], "field_rays_sweep": [16, 64] }},
  "thresholds": [{thresholds}],
  "quick": {{}}
}}"#
    )
}

/// The tiny spec on both backends, its field sweep reaching 4096 rays per point (past what one
/// lavapipe invocation can loop).
pub fn cpu_gpu_spec() -> String {
    tiny(ONE_FIELD, "")
        .replace(
            r#""reference": {"#,
            r#""backends": ["cpu", "gpu"], "reference": {"#,
        )
        .replace(
            r#""field_rays_sweep": [16, 64]"#,
            r#""field_rays_sweep": [16, 4096]"#,
        )
}

/// A field of `count` Slater maps × `res`² concentric texels at `precision` (the papers' sets).
pub fn slater_params(count: usize, res: u32, precision: Precision) -> FieldParams {
    FieldParams {
        sphere: SphereKind::Slater,
        count,
        layout: LayoutKind::Concentric,
        res,
        precision,
    }
}

pub const ONE_FIELD: &str = r#"{ "counts": [290], "resolutions": [16] }"#;

/// Run options without a cache, timing each stage once.
pub fn options(out: PathBuf) -> RunOptions {
    let mut o = RunOptions::new(out);
    o.supply = FieldSupply {
        cache: None,
        cache_limit: 0,
        memory_limit: 1 << 30,
    };
    o.repeats = 1;
    o
}

/// `text` written to `dir/tiny.json` and loaded.
pub fn loaded(dir: &Path, text: &str) -> LoadedSpec {
    let path = dir.join("tiny.json");
    std::fs::write(&path, text).unwrap();
    LoadedSpec::load(&path).unwrap()
}

/// The PNG at `path` holds exactly `img`'s 8-bit levels.
pub fn assert_png_is(path: &Path, img: &visfield::render::image::GrayImage) {
    let png = image::open(path).unwrap().to_luma8();
    for (i, px) in png.pixels().enumerate() {
        assert_eq!(
            px.0[0],
            visfield::render::image::GrayImage::to_u8(img.data[i]),
            "{}: pixel {i}",
            path.display()
        );
    }
}

/// The shared GPU device of a test binary, or `None` (with the skip message) when no Vulkan
/// adapter exists; any other GPU error fails the test.
pub fn gpu_context() -> Option<&'static visfield::gpu::GpuContext> {
    use std::sync::OnceLock;
    use visfield::gpu::{AdapterPreference, GpuContext, GpuError};
    static CTX: OnceLock<Option<GpuContext>> = OnceLock::new();
    CTX.get_or_init(|| match GpuContext::new(AdapterPreference::from_env()) {
        Ok(c) => {
            eprintln!("adapter: {}", c.adapter_label());
            Some(c)
        }
        Err(GpuError::NoAdapter) => None,
        Err(e) => panic!("GPU context: {e}"),
    })
    .as_ref()
    .or_else(|| {
        eprintln!("skipped: no Vulkan adapter (install mesa-vulkan-drivers)");
        None
    })
}

/// A caster of the GPU parity tests: the default superformula shape with about 2000
/// triangles, in model space, built once per test binary.
pub fn supershape_2000() -> &'static visfield::geometry::Mesh {
    use std::sync::OnceLock;
    use visfield::geometry::{procedural, Mesh};
    static MESH: OnceLock<Mesh> = OnceLock::new();
    MESH.get_or_init(|| {
        procedural::supershape(&procedural::Supershape::default(), 2000).expect("supershape")
    })
}

/// The harness of a GPU test binary (`harness = false`): the `gpu` tests run where a Vulkan
/// adapter exists and are reported as ignored, with the reason printed, where none does (a
/// skipped test never shows as passed); the `always` tests run everywhere.
pub fn run_gpu_trials(
    binary: &str,
    gpu: &[(&'static str, fn())],
    always: &[(&'static str, fn())],
) -> ! {
    use visfield::gpu::{AdapterPreference, GpuContext, GpuError};
    let args = libtest_mimic::Arguments::from_args();
    let missing = match GpuContext::new(AdapterPreference::from_env()) {
        Err(GpuError::NoAdapter) => {
            eprintln!(
                "{binary} tests ignored: no Vulkan adapter (install mesa-vulkan-drivers for \
                 lavapipe)"
            );
            true
        }
        _ => false,
    };
    let trial = |(name, f): (&'static str, fn()), ignored: bool| {
        libtest_mimic::Trial::test(name, move || {
            f();
            Ok(())
        })
        .with_ignored_flag(ignored)
    };
    let trials = gpu
        .iter()
        .map(|&t| trial(t, missing))
        .chain(always.iter().map(|&t| trial(t, false)))
        .collect();
    libtest_mimic::run(&args, trials).exit()
}

/// A test that needs real models: its name, the models it needs (computed when the harness
/// starts) and its body.
pub type ModelTrial = (&'static str, fn() -> Vec<String>, fn());

/// The harness of a test binary whose tests need real models (`harness = false`): each test
/// runs where every model it needs is in a model folder (`geometry::models::search_dirs`,
/// looked up when the tests run, so a model fetched after the build counts), and is reported
/// as ignored where one is missing, the reason naming the models and the command that fetches
/// them ("needs stanford-bunny_39k: `experiment models fetch stanford-bunny_39k`"); a skipped
/// test never shows as passed.
pub fn run_model_trials(trials: &[ModelTrial]) -> ! {
    use visfield::geometry::models::{fetch_hint, missing_models};
    let args = libtest_mimic::Arguments::from_args();
    let trials = trials
        .iter()
        .map(|&(name, needs, f)| {
            libtest_mimic::Trial::ignorable_test(name, move || {
                let needs = needs();
                let missing = missing_models(needs.iter().map(String::as_str));
                if !missing.is_empty() {
                    return Ok(libtest_mimic::Completion::ignored_with(fetch_hint(
                        &missing,
                    )));
                }
                f();
                Ok(libtest_mimic::Completion::Completed)
            })
        })
        .collect();
    libtest_mimic::run(&args, trials).exit()
}

/// A CSV file's rows as column → text maps (the committed results, read without their types).
pub fn read_csv_maps(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let head: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            head.iter()
                .cloned()
                .zip(rec.iter().map(String::from))
                .collect()
        })
        .collect()
}

/// The tiny spec's caster, and the same with `motion` (JSON) after its transform.
pub const CASTER: &str =
    r#""transform": { "fit": { "center": [0.5, 0.45, 0.5], "radius": 0.35 } }"#;

/// The tiny spec with `motion` on its caster, `receiver_motion` on its corner and `animation`
/// (JSON members spliced in; empty strings leave them out).
pub fn animated(motion: &str, receiver_motion: &str, animation: &str) -> String {
    let mut t = tiny(ONE_FIELD, "");
    if !motion.is_empty() {
        t = t.replace(CASTER, &format!("{CASTER}, \"motion\": {motion}"));
    }
    if !receiver_motion.is_empty() {
        t = t.replace(
            r#""receiver": true }"#,
            &format!(r#""receiver": true, "motion": {receiver_motion} }}"#),
        );
    }
    if !animation.is_empty() {
        t = t.replace(
            r#""quick": {}"#,
            &format!(r#""animation": {animation}, "quick": {{}}"#),
        );
    }
    // No field sweep: an animated spec has none.
    t.replace(r#", "field_rays_sweep": [16, 64]"#, "")
}

/// Two frames half a second apart, and a small orbit of the caster about its own centre.
pub const TWO_FRAMES: &str = r#"{ "frames": 2, "time_step": 0.5 }"#;
pub const ORBIT: &str = r#"{ "orbit": { "axis": [0, 1, 0], "radius": 0.05, "period": 4 } }"#;

/// The animated spec `text` run into `dir/name`: its `frames.csv`, read back (equal to the
/// run's report).
pub fn frames_of(
    dir: &Path,
    text: &str,
    name: &str,
) -> Vec<visfield::experiment::run::frames::FrameRow> {
    let ls = loaded(dir, text);
    let out = dir.join(name);
    let report = visfield::experiment::run::run(&ls, &options(out.clone())).unwrap();
    let rows: Vec<visfield::experiment::run::frames::FrameRow> =
        visfield::experiment::outputs::read_csv(&out.join("frames.csv")).unwrap();
    assert_eq!(rows, report.frames);
    rows
}

/// A mesh's triangles as their three vertex positions, in the mesh's order.
pub fn triangles(m: &visfield::geometry::Mesh) -> Vec<[glam::Vec3; 3]> {
    (0..m.triangle_count()).map(|i| m.triangle(i)).collect()
}

/// A seeded value in [0, 1) (a 64-bit mix of `i`, its top 24 bits).
pub fn unit(i: u64) -> f32 {
    let mut x = i.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 29;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    ((x >> 40) as f32) / (1u64 << 24) as f32
}
