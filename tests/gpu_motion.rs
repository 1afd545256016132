//! The GPU path per frame (an animated spec with `"backends": ["cpu", "gpu"]`): the GPU twins
//! of the world rebuild (the GPU tracer's BVH rebuilt and uploaded each frame), of the two
//! levels (each mesh's BVH uploaded once, the top level each frame), of the field testing every
//! sphere (the fields uploaded once, the instances moved on the device each frame) and of the
//! field with the BVH over its spheres (the tree rebuilt and uploaded each frame) against their
//! CPU twins on the same rays, frame by frame, for AO, shadows and
//! reflections; and a world too large for one storage binding refused by name.
//!
//! The bound: the GPU kernels reproduce the CPU values to the f32 differences the GPU tests
//! bound (tests/gpu.rs, tests/gpu_shadow.rs, tests/gpu_reflect.rs: at most a ray flipped
//! here and there among thousands, near-tangent sphere tests in f32), so each GPU row's error
//! against the same-ray ray cast and its mean differ from its CPU twin's by under 0.5 and
//! 0.002 (0–255 and 0–1). A device that failed to move the instances would answer every frame
//! as the first: lifting the caster moves the CPU's mean by more than that between the
//! frames, which the test checks too, so a frozen GPU row cannot pass. Only a missing Vulkan
//! driver skips these tests (reported as ignored, with the reason).

use visfield::experiment::run::frames::FrameRow;

mod common;
use common::{animated, frames_of};

/// Every frame's GPU rows against their CPU twins, cell by cell (see the module
/// documentation).
fn twins_agree(rows: &[FrameRow], what: &str) {
    let of = |m: &str| -> Vec<&FrameRow> { rows.iter().filter(|r| r.method == m).collect() };
    for (cpu, gpu) in [
        ("world_rebuild", "world_rebuild@gpu"),
        ("two_level", "two_level@gpu"),
        ("field_every_sphere", "field_every_sphere@gpu"),
        ("field", "field@gpu"),
    ] {
        let (c, g) = (of(cpu), of(gpu));
        assert!(
            !c.is_empty() && c.len() == g.len(),
            "{what}: {cpu} and {gpu} rows"
        );
        for c in c {
            let g = g
                .iter()
                .find(|g| g.frame == c.frame && g.cell == c.cell.replace("-cpu", "-gpu"))
                .unwrap_or_else(|| panic!("{what}: no {gpu} twin of {c:?}"));
            assert_eq!((c.points, c.rays), (g.points, g.rays), "{what} {gpu}");
            assert!(
                (c.rms_vs_raycast - g.rms_vs_raycast).abs() < 0.5
                    && (c.mean_value - g.mean_value).abs() < 0.002,
                "{what} frame {}: {c:?}\n{g:?}",
                c.frame
            );
            if c.frame == 1 {
                let first = (of(cpu).into_iter())
                    .find(|f| f.frame == 0 && f.cell == c.cell)
                    .unwrap();
                assert!(
                    (first.mean_value - c.mean_value).abs() > 0.004,
                    "{what} {cpu}: the lift must move the answer for the test to see a \
                     frozen device"
                );
            }
        }
    }
}

fn gpu_rows_match_their_cpu_twins_every_frame() {
    let lights = r#""lights": [{ "center": [2, 3, 2.5], "radius": 0.2, "intensity": 1 }]"#;
    let dir = tempfile::tempdir().unwrap();
    // The caster lifted by 0.3 between the frames, so that every kind's answer moves.
    let lift = r#"{ "keyframes": [{ "time": 0 }, { "time": 1, "translate": [0, 0.3, 0] }] }"#;
    for (what, own) in [
        ("vertex_ao", String::new()),
        ("shadows", lights.to_string() + ", "),
        (
            "reflections",
            format!(
                r#"{lights}, "gloss": {{ "phong": {{ "exponent": 50 }} }}, "normal_bits": [8], "#
            ),
        ),
    ] {
        let mut text = animated(lift, "", r#"{ "frames": 2, "time_step": 1 }"#).replace(
            r#""quick": {}"#,
            r#""backends": ["cpu", "gpu"], "quick": {}"#,
        );
        if what != "vertex_ao" {
            text = text.replace(
                r#""render": { "#,
                &format!(r#""render": {{ "what": "{what}", {own}"#),
            );
        }
        let rows = frames_of(dir.path(), &text, what);
        twins_agree(&rows, what);
    }
}

/// A world whose triangles pass one storage binding is refused by name before the BVH is
/// built (three vec4 a triangle), not handed to the device to fail there: what a moving
/// crowd too large for the adapter meets every frame.
fn a_world_past_the_binding_limit_is_refused_by_name() {
    use visfield::gpu::{AdapterPreference, GpuContext, GpuError, GpuTracer};
    let ctx = GpuContext::new(AdapterPreference::from_env()).unwrap();
    let fit = (ctx.max_binding() / 48) as usize;
    let tri = [glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y];
    match GpuTracer::new(&ctx, &vec![tri; fit + 1]) {
        Err(GpuError::TooLarge {
            what, need, limit, ..
        }) => {
            assert!(what.contains("triangle vertices"), "{what}");
            assert_eq!((need, limit), (48 * (fit as u64 + 1), ctx.max_binding()));
        }
        Err(e) => panic!("refused for another reason: {e}"),
        Ok(_) => panic!("{} triangles accepted past the binding limit", fit + 1),
    }
}

/// The harness: run where a Vulkan adapter exists, reported as ignored with the reason where
/// none does.
fn main() {
    common::run_gpu_trials(
        "gpu_motion",
        &[
            (
                "gpu_rows_match_their_cpu_twins_every_frame",
                gpu_rows_match_their_cpu_twins_every_frame,
            ),
            (
                "a_world_past_the_binding_limit_is_refused_by_name",
                a_world_past_the_binding_limit_is_refused_by_name,
            ),
        ],
        &[],
    )
}
