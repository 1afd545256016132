//! Field lookup against obvhs ray casting on the same AO rays (2008 paper's setting: 256
//! stratified cosine rays at each of the corner's 3 × 33 × 33 vertices), for casters of growing
//! triangle count, every precision and both map selections; and bake throughput against the
//! tracer's raw closest-hit throughput on the same rays. Field rows go through
//! `ao_at_points`, which batches each vertex's rays (`Visibility::occluded_many`); the
//! `*_per_ray` rows run the same lookups one ray at a time (`PerRay`). The `floor_*` rows time
//! the cost-floor backends of `visfield::experiment::performance::floor` on the same rays: the AO pass with a
//! free query, and with only the bounding-sphere cull and crossing that every lookup starts
//! with; ray casting's time over theirs bounds the speed-up any field lookup can reach here.
//! The `entering_*` rows take the same AO rays but only those that enter the caster's bounding
//! sphere (the rays whose answer comes from the field), so that their ratio is the lookup's
//! against ray casting where the field is actually read.
//!
//! `cargo bench --bench field`. Casters: stanford-bunny_39k (38,889 triangles), dragon
//! (100,000) and a 261,120-triangle supershape (the 2010 paper's count). Real models are found
//! as everywhere else (`$VISFIELD_MODELS`, `data/models/`, `../shared/models/`); a missing model
//! is skipped with a note. Tracers and bakes are built on first use, so a filter
//! (`cargo bench --bench field -- bunny`) skips the setup of the groups it leaves out.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Quat, Vec3};
use rayon::prelude::*;
use std::cell::OnceCell;
use std::sync::Arc;
use std::time::Duration;
use visfield::field::bake::{bake, bake_with, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision, Selection};
use visfield::geometry::procedural::{over_corner, supershape, Supershape};
use visfield::geometry::{models, Mesh};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::render::receivers::Receivers;
use visfield::sampling::rays::RaySet;
use visfield::sampling::{Frame, HemisphereLayout, LayoutKind, SphereKind, SpherePoints};
use visfield::trace::Tracer;
use visfield::visibility::{PerRay, Visibility};

use visfield::experiment::performance::floor::{NoQuery, SphereCull};

fn casters() -> Vec<(String, Mesh)> {
    let mut v = Vec::new();
    for name in ["stanford-bunny_39k", "dragon"] {
        match models::load_model(name) {
            Ok(m) => v.push((name.to_string(), m)),
            Err(e) => eprintln!("skipping {name}: {e}"),
        }
    }
    let ss = supershape(&Supershape::default(), 261_120).expect("supershape");
    v.push((format!("supershape_{}", ss.triangles.len()), ss));
    v
}

fn ao_lookup_vs_raycast(c: &mut Criterion) {
    let rays = RaySet::new(16, 1);
    for (name, mesh) in casters() {
        let scene = over_corner(mesh, Quat::IDENTITY);
        let recv = Receivers::of(&scene);
        let caster = &scene.instances[1];
        // The tracer and the bakes are built on first use, so that a filtered-out benchmark
        // costs nothing (criterion only runs the closures of the benchmarks it selects).
        let tracer = OnceCell::new();
        let opts = AoOptions::for_scene_radius(0.9);
        let mut group = c.benchmark_group(format!("ao_256_rays/{name}"));
        group.sample_size(10);
        group.warm_up_time(Duration::from_millis(500));
        group.measurement_time(Duration::from_secs(3));
        group.throughput(Throughput::Elements(
            (recv.points.len() * rays.len()) as u64,
        ));
        let scene_tris = || scene.caster_triangles();
        group.bench_function("raycast_anyhit", |b| {
            let tracer = tracer.get_or_init(|| Tracer::new(&scene_tris()));
            b.iter(|| ao_at_points(tracer, &recv.points, &recv.normals, &rays, &opts))
        });
        // Cost floor: the AO pass with a query that costs nothing (experiment::performance::floor).
        group.bench_function("floor_no_query", |b| {
            b.iter(|| ao_at_points(&NoQuery, &recv.points, &recv.normals, &rays, &opts))
        });
        for precision in [
            Precision::U8,
            Precision::U16,
            Precision::F32,
            Precision::Bit1,
        ] {
            let params = FieldParams {
                sphere: SphereKind::Slater,
                count: 4226,
                layout: LayoutKind::Concentric,
                res: 32,
                precision,
            };
            let field = OnceCell::new();
            // The field is baked on first use, so a filter that skips these rows skips the bake.
            let scene = |selection| {
                let field = field.get_or_init(|| {
                    let (f, _) = bake(&caster.mesh, params, &BakeOptions::default()).expect("bake");
                    Arc::new(f)
                });
                FieldScene {
                    instances: vec![FieldInstance::new(field.clone(), caster.transform)],
                    options: LookupOptions {
                        selection,
                        ..LookupOptions::default()
                    },
                }
            };
            for selection in [Selection::Nearest, Selection::Interpolated] {
                let id = BenchmarkId::new(
                    format!("field_{selection:?}").to_lowercase(),
                    precision.name(),
                );
                group.bench_function(id, |b| {
                    let fs = scene(selection);
                    b.iter(|| ao_at_points(&fs, &recv.points, &recv.normals, &rays, &opts))
                });
                if precision != Precision::U8 {
                    continue;
                }
                if selection == Selection::Nearest {
                    // Cost floor: the sphere cull and crossing every lookup starts with.
                    group.bench_function("floor_sphere_cull", |b| {
                        let fs = scene(selection);
                        let cull = SphereCull(&fs);
                        b.iter(|| ao_at_points(&cull, &recv.points, &recv.normals, &rays, &opts))
                    });
                    // The same AO rays kept only where they enter the caster's bounding
                    // sphere: the rays a lookup must answer from the field.
                    let entering = OnceCell::new();
                    let entering = || {
                        entering.get_or_init(|| {
                            entering_rays(&SphereCull(&scene(selection)), &recv, &rays, &opts)
                        })
                    };
                    let run = |vis: &dyn Visibility, batches: &[(Vec3, Vec<Vec3>)]| {
                        batches
                            .par_iter()
                            .map(|(o, dirs)| {
                                let mut out = vec![false; dirs.len()];
                                vis.occluded_many(*o, dirs, 0.0, f32::INFINITY, &mut out);
                                out.iter().filter(|&&b| b).count()
                            })
                            .sum::<usize>()
                    };
                    let count = |batches: &[(Vec3, Vec<Vec3>)]| {
                        batches.iter().map(|b| b.1.len()).sum::<usize>() as u64
                    };
                    group.throughput(Throughput::Elements(count(entering())));
                    group.bench_function("entering_raycast_anyhit", |b| {
                        let tracer = tracer.get_or_init(|| Tracer::new(&scene_tris()));
                        b.iter(|| run(tracer, entering()))
                    });
                    group.bench_function("entering_field_nearest/u8", |b| {
                        let fs = scene(selection);
                        b.iter(|| run(&fs, entering()))
                    });
                    group.bench_function("entering_floor_sphere_cull", |b| {
                        let fs = scene(selection);
                        b.iter(|| run(&SphereCull(&fs), entering()))
                    });
                    group.throughput(Throughput::Elements(
                        (recv.points.len() * rays.len()) as u64,
                    ));
                }
                // The same lookups one ray at a time (no shared origin work, no prefetch).
                let id = BenchmarkId::new(
                    format!("field_{selection:?}_per_ray").to_lowercase(),
                    precision.name(),
                );
                group.bench_function(id, |b| {
                    let fs = scene(selection);
                    let per_ray = PerRay(&fs);
                    b.iter(|| ao_at_points(&per_ray, &recv.points, &recv.normals, &rays, &opts))
                });
            }
        }
        group.finish();
    }
}

/// Per receiver point, the origin and the world directions of its AO rays (as `ao_at_point`
/// builds them) that `cull` reports as meeting the caster's bounding sphere.
fn entering_rays(
    cull: &SphereCull,
    recv: &Receivers,
    rays: &RaySet,
    opts: &AoOptions,
) -> Vec<(Vec3, Vec<Vec3>)> {
    (0..recv.points.len())
        .map(|i| {
            let (p, n) = (recv.points[i], recv.normals[i]);
            let frame = Frame::from_normal(n);
            let origin = p + opts.offset * n;
            let dirs = rays
                .directions(i as u32)
                .into_iter()
                .map(|d| frame.to_world(d))
                .filter(|&d| cull.occluded(origin, d, 0.0, f32::INFINITY))
                .collect();
            (origin, dirs)
        })
        .collect()
}

/// Bake throughput against the tracer's raw closest-hit throughput on exactly the bake's rays.
fn bake_vs_closest_hit(c: &mut Criterion) {
    let Ok(mesh) = models::load_model("stanford-bunny_39k") else {
        eprintln!("skipping bake_290x64: stanford-bunny_39k not found");
        return;
    };
    let tris: Vec<_> = (0..mesh.triangles.len())
        .map(|i| mesh.triangle(i))
        .collect();
    let tracer = Tracer::new(&tris);
    let bounds = mesh.bounding_sphere();
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 290,
        layout: LayoutKind::Concentric,
        res: 64,
        precision: Precision::U8,
    };
    let points = SpherePoints::new(params.sphere, params.count).expect("points");
    let layout = HemisphereLayout::new(params.layout, params.res);
    let rays: Vec<(glam::Vec3, glam::Vec3)> = (0..points.len())
        .flat_map(|m| {
            let frame = Frame::from_normal(-points.point(m));
            let origin = bounds.center + bounds.radius * points.point(m);
            (0..layout.texel_count() as u32)
                .filter_map(|t| layout.to_direction(t))
                .map(move |d| (origin, frame.to_world(d)))
                .collect::<Vec<_>>()
        })
        .collect();
    let mut group = c.benchmark_group("bake_290x64");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.bench_function("raw_closest_hit", |b| {
        b.iter(|| {
            rays.par_chunks(layout.texel_count())
                .map(|chunk| {
                    chunk
                        .iter()
                        .filter(|(o, d)| {
                            tracer
                                .closest_hit(*o, *d, 0.0, 2.0 * bounds.radius)
                                .is_some()
                        })
                        .count()
                })
                .sum::<usize>()
        })
    });
    group.bench_function("bake", |b| {
        b.iter(|| bake_with(&tracer, bounds, params, &BakeOptions::default()).expect("bake"))
    });
    group.finish();
}

criterion_group!(benches, ao_lookup_vs_raycast, bake_vs_closest_hit);
criterion_main!(benches);
