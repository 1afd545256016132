//! GPU parity: the wgpu kernels against the CPU path on the same fields and rays (on lavapipe
//! in CI; on whatever `VISFIELD_ADAPTER` selects elsewhere).
//!
//! Only a missing Vulkan driver skips these tests; every other GPU failure fails them. On a
//! parity failure the actual / expected / difference values are written as CSV to a temporary
//! folder whose path is printed.

use glam::{Quat, Vec3};
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};
use visfield::field::bake::{bake, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision, Selection, VisibilityField};
use visfield::geometry::{procedural, Mesh, Similarity};
use visfield::gpu::{AdapterPreference, FieldAoKernel, FieldGpuOptions, FieldLayout, GpuContext};
use visfield::gpu::{GpuError, GpuTracer};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::sampling::rays::{seeded_sphere_direction, RaySet};
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::trace::{RayQuery, Tracer};

/// The shared device, or `None` (with the skip message) when no Vulkan adapter exists.
fn context() -> Option<&'static GpuContext> {
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

/// Writes `rows` (CSV with `header`) to a fresh temporary folder and returns the file's path.
fn dump(name: &str, header: &str, rows: impl IntoIterator<Item = String>) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("visfield-gpu-{}", std::process::id()));
    let path = dir.join(format!("{name}.csv"));
    let mut text = format!("{header}\n");
    for r in rows {
        text += &r;
        text.push('\n');
    }
    visfield::io::write_atomic(&path, text.as_bytes()).expect("write failure dump");
    path
}

/// The caster: the default superformula shape with about 2000 triangles, in model space.
fn caster() -> &'static Mesh {
    static MESH: OnceLock<Mesh> = OnceLock::new();
    MESH.get_or_init(|| {
        procedural::supershape(&procedural::Supershape::default(), 2000).expect("supershape")
    })
}

fn params(count: usize, res: u32, precision: Precision, layout: LayoutKind) -> FieldParams {
    FieldParams {
        sphere: SphereKind::Slater,
        count,
        layout,
        res,
        precision,
    }
}

fn baked(p: FieldParams) -> Arc<VisibilityField> {
    Arc::new(bake(caster(), p, &BakeOptions::default()).expect("bake").0)
}

/// Places the caster's field like the default scene: bounding radius 0.35 at (0.5, 0.45, 0.5),
/// tilted, inside the corner receiver.
fn placed(field: &Arc<VisibilityField>) -> FieldInstance {
    let s = field.bounds;
    let rotation = Quat::from_euler(glam::EulerRot::YXZ, 0.4, 0.25, 0.0);
    let scale = 0.35 / s.radius;
    let translation = Vec3::new(0.5, 0.45, 0.5) - scale * (rotation * s.center);
    FieldInstance::new(field.clone(), Similarity::new(rotation, translation, scale))
}

/// Receivers: the corner's vertices (inter-object lookups) and the placed caster's own
/// vertices (intra-object lookups), with unit normals.
fn receivers(inst: &FieldInstance) -> (Vec<Vec3>, Vec<Vec3>) {
    let corner = procedural::corner(25).expect("corner");
    let mut p = corner.positions.clone();
    let mut n = corner.normals.clone();
    let c = caster();
    for (q, m) in c.positions.iter().zip(&c.normals).step_by(2) {
        p.push(inst.transform.to_world_point(*q));
        n.push(inst.transform.to_world_dir(*m).normalize());
    }
    (p, n)
}

/// Per-vertex and image statistics of a parity comparison on the 0–255 scale.
struct Parity {
    max_diff: f32,
    rms_255: f64,
    over_one_step: usize,
}

fn parity(gpu: &[f32], cpu: &[f32]) -> Parity {
    let mut max_diff = 0.0f32;
    let mut sq = 0.0f64;
    let mut over = 0;
    for (g, c) in gpu.iter().zip(cpu) {
        let d = (g - c).abs();
        max_diff = max_diff.max(d);
        sq += (255.0 * d as f64).powi(2);
        if d > 1.0 / 255.0 + 1e-6 {
            over += 1;
        }
    }
    Parity {
        max_diff,
        rms_255: (sq / gpu.len().max(1) as f64).sqrt(),
        over_one_step: over,
    }
}

fn dump_ao(name: &str, gpu: &[f32], cpu: &[f32]) -> PathBuf {
    dump(
        name,
        "vertex,gpu,cpu,difference",
        gpu.iter()
            .zip(cpu)
            .enumerate()
            .map(|(i, (g, c))| format!("{i},{g},{c},{}", g - c)),
    )
}

#[test]
fn adapter_is_labelled() {
    let Some(ctx) = context() else { return };
    let label = ctx.adapter_label();
    // "name | driver driver_info | backend": three fields, backend Vulkan.
    assert_eq!(label.split(" | ").count(), 3, "{label}");
    assert!(label.ends_with("Vulkan"), "{label}");
    assert!(!ctx.adapter_info().name.is_empty());
}

#[test]
fn slater_nearest_texel_and_samples_agree_with_the_cpu() {
    let Some(ctx) = context() else { return };
    for (count, layout) in [
        (290, LayoutKind::Concentric),
        (1090, LayoutKind::Polar),
        (290, LayoutKind::Rejection),
    ] {
        let field = baked(params(count, 16, Precision::F32, layout));
        let inst = FieldInstance::new(field.clone(), Similarity::default());
        let kernel = FieldAoKernel::new(ctx, &[inst], &FieldGpuOptions::default()).unwrap();
        let n = 100_000u64;
        let u: Vec<Vec3> = (0..n).map(|i| seeded_sphere_direction(i, 5)).collect();
        // Inward directions: any direction with a negative component along u.
        let dirs: Vec<Vec3> = (0..n)
            .map(|i| {
                let d = seeded_sphere_direction(i, 6);
                if d.dot(u[i as usize]) > 0.0 {
                    -d
                } else {
                    d
                }
            })
            .collect();
        let probes = kernel.probe(&u, &dirs).unwrap();
        let (mut map_miss, mut tie_miss, mut texel_miss, mut sample_miss) = (0, 0, 0, 0);
        let mut bad = Vec::new();
        for i in 0..n as usize {
            let g = probes[i];
            let m = field.points.nearest(u[i]);
            if g.map as usize != m {
                map_miss += 1;
                // A mismatch must be a near-tie: both points equally near in f64.
                let dd = u[i].as_dvec3();
                let (a, b) = (
                    dd.dot(field.points.point(m).as_dvec3()),
                    dd.dot(field.points.point(g.map as usize).as_dvec3()),
                );
                if (a - b).abs() > 1e-6 {
                    tie_miss += 1;
                    bad.push(format!("{i},{},{},{m},{}", u[i], dirs[i], g.map));
                }
                continue;
            }
            let local = field.frames[m].to_local(dirs[i]);
            let t = field.layout.to_texel(local);
            if g.texel != t {
                texel_miss += 1;
                continue;
            }
            if g.nearest != field.storage.get(m, t as usize) {
                sample_miss += 1;
            }
        }
        let label = format!("{count} maps {layout:?}");
        eprintln!(
            "{label}: nearest mismatches {map_miss} / {n} (non-ties {tie_miss}), texel \
             mismatches {texel_miss}, sample mismatches {sample_miss}"
        );
        if tie_miss > 0 || map_miss * 10_000 > n as usize {
            let path = dump(
                "nearest",
                "index,u,dir,cpu_map,gpu_map",
                bad.into_iter(),
            );
            panic!("{label}: {map_miss} nearest mismatches ({tie_miss} not ties); see {}", path.display());
        }
        // Texels: mismatches only at cell edges, far below 0.1%.
        assert!(texel_miss * 1000 <= n as usize, "{label}: {texel_miss} texel mismatches");
        // Same map and texel: the same stored value, bit for bit.
        assert_eq!(sample_miss, 0, "{label}");
    }
}
