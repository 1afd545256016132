//! GPU vertex AO on the 2008 paper's setting (the default scene: a 10,000-triangle supershape
//! over the corner's 3 × 33 × 33 vertices, 256 stratified cosine rays each): field lookup with
//! both field layouts (storage-buffer windows, 3D texture) and both selections, against GPU ray
//! casting (CWBVH) on the same rays and device. Field: 1090 Slater maps × 32² concentric, u8.
//!
//! Reported time is the kernel's GPU time (timestamp queries) where the adapter has them, else
//! the wall time of the call; every run names the adapter. On lavapipe these numbers measure
//! the CPU emulation, not a GPU. `cargo bench --bench gpu` (`VISFIELD_ADAPTER` selects the
//! adapter); without a Vulkan adapter the bench prints a note and does nothing.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::sync::Arc;
use std::time::Duration;
use visfield::field::bake::{bake, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::scene::FieldInstance;
use visfield::field::{FieldParams, Precision, Selection};
use visfield::geometry::procedural::default_scene;
use visfield::gpu::{
    AdapterPreference, FieldAoKernel, FieldGpuOptions, FieldLayout, GpuContext, GpuError,
    GpuTiming, GpuTracer,
};
use visfield::render::ao::AoOptions;
use visfield::render::receivers::Receivers;
use visfield::sampling::rays::RaySet;
use visfield::sampling::{LayoutKind, SphereKind};

/// The kernel's GPU time where there is one, else the call's wall time.
fn kernel_or_wall(t: &GpuTiming) -> Duration {
    t.kernel.unwrap_or(t.wall)
}

fn gpu_ao(c: &mut Criterion) {
    let ctx = match GpuContext::new(AdapterPreference::from_env()) {
        Ok(ctx) => ctx,
        Err(GpuError::NoAdapter) => {
            eprintln!("gpu bench: no Vulkan adapter (install mesa-vulkan-drivers); skipped");
            return;
        }
        Err(e) => panic!("gpu bench: {e}"),
    };
    eprintln!("gpu bench on {}", ctx.adapter_label());
    let scene = default_scene();
    let recv = Receivers::of(&scene);
    let (_, caster) = scene
        .casters()
        .next()
        .expect("the default scene has a caster");
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 1090,
        layout: LayoutKind::Concentric,
        res: 32,
        precision: Precision::U8,
    };
    let field = Arc::new(
        bake(&caster.mesh, params, &BakeOptions::default())
            .expect("bake")
            .0,
    );
    let inst = FieldInstance::new(field, caster.transform);
    let rays = RaySet::new(16, 1);
    let opts = AoOptions::for_scene_radius(1.0);
    let (p, n) = (&recv.points, &recv.normals);

    let mut group = c.benchmark_group(format!("gpu_vertex_ao/{}", ctx.info_short()));
    group.sample_size(10);
    group.throughput(Throughput::Elements((p.len() * rays.len()) as u64));
    for layout in [FieldLayout::StorageBuffers, FieldLayout::Texture3d] {
        for selection in [Selection::Nearest, Selection::Interpolated] {
            let gpu_opts = FieldGpuOptions {
                layout,
                lookup: LookupOptions {
                    selection,
                    ..Default::default()
                },
                ..Default::default()
            };
            let kernel = FieldAoKernel::new(&ctx, std::slice::from_ref(&inst), &gpu_opts)
                .expect("field kernel");
            let id = BenchmarkId::new(format!("field_{layout:?}"), format!("{selection:?}"));
            group.bench_function(id, |b| {
                b.iter_custom(|iters| {
                    (0..iters)
                        .map(|_| kernel_or_wall(&kernel.ao(p, n, &rays, &opts).unwrap().1))
                        .sum()
                })
            });
        }
    }
    let tris: Vec<_> = scene
        .casters()
        .flat_map(|(_, i)| i.world_triangles().collect::<Vec<_>>())
        .collect();
    let tracer = GpuTracer::new(&ctx, &tris).expect("gpu tracer");
    group.bench_function(BenchmarkId::new("raycast_cwbvh", "any_hit"), |b| {
        b.iter_custom(|iters| {
            (0..iters)
                .map(|_| kernel_or_wall(&visfield::gpu::ao(&tracer, p, n, &rays, &opts).unwrap().1))
                .sum()
        })
    });
    group.finish();
}

criterion_group!(benches, gpu_ao);
criterion_main!(benches);
