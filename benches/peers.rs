//! The per-object peers against the visibility field and ray casting, on the same vertex AO
//! (2008 Figure 6's setting: 256 stratified cosine rays at each of the corner's 3 × 33 × 33
//! vertices under a caster fitted to a sphere of radius 0.35): our ray caster (any hit), the
//! field (1090 Slater maps × 32² concentric texels, u8, nearest), a mesh signed distance field
//! sphere traced on the same rays (res 32 and 64, f32 and u8) and cone traced (9 cones, as
//! Unreal's), and an AO field (Kontkanen & Laine 2005; 16² texels a face, f32 and u8), which
//! casts no ray. Each row is the whole AO pass over the vertices (rayon); bakes and BVH builds
//! are done once, outside the timings, on first use (a filter skips the setup of what it leaves
//! out). The errors of the same settings are in `results/figure6/methods.csv`.
//!
//! `cargo bench --bench peers`. The caster: stanford-bunny_39k where the models are found (as
//! everywhere else: `$VISFIELD_MODELS`, `data/models/`, `../shared/models/`), else a
//! 40,000-triangle supershape (named in the group).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{Quat, Vec3};
use std::cell::OnceCell;
use std::sync::Arc;
use std::time::Duration;
use visfield::aofield::{AoField, AoFieldInstance, AoFieldScene, BakeParams, Inside};
use visfield::field::bake::{bake, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision};
use visfield::geometry::procedural::{over_corner, supershape, Supershape};
use visfield::geometry::{models, Mesh};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::render::receivers::Receivers;
use visfield::sampling::rays::RaySet;
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::sdf::{ConeSet, ConeTrace, DistanceVolume, SdfInstance, SdfScene, SdfTrace};
use visfield::trace::Tracer;

fn caster() -> (String, Mesh) {
    match models::load_model("stanford-bunny_39k") {
        Ok(m) => ("stanford-bunny_39k".into(), m),
        Err(e) => {
            eprintln!("stanford-bunny_39k: {e}; a supershape instead");
            let m = supershape(&Supershape::default(), 40_000).expect("supershape");
            (format!("supershape_{}", m.triangles.len()), m)
        }
    }
}

fn peers(c: &mut Criterion) {
    let (name, mesh) = caster();
    let model_triangles: Vec<[Vec3; 3]> = (0..mesh.triangle_count())
        .map(|t| mesh.triangle(t))
        .collect();
    let scene = over_corner(mesh, Quat::IDENTITY);
    let recv = Receivers::of(&scene);
    let caster = &scene.instances[1];
    let rays = RaySet::new(16, 1);
    let opts = AoOptions::for_scene_radius(0.9);
    let mut group = c.benchmark_group(format!("peers_vertex_ao_256_rays/{name}"));
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(3));
    group.throughput(Throughput::Elements(recv.points.len() as u64));
    let ao = |vis: &dyn visfield::visibility::Visibility| {
        ao_at_points(vis, &recv.points, &recv.normals, &rays, &opts)
    };

    let tracer = OnceCell::new();
    group.bench_function("raycast_anyhit", |b| {
        let t = tracer.get_or_init(|| Tracer::new(&scene.caster_triangles()));
        b.iter(|| ao(t))
    });

    let field = OnceCell::new();
    group.bench_function("field_1090_32_u8_nearest", |b| {
        let fs = field.get_or_init(|| {
            let params = FieldParams {
                sphere: SphereKind::Slater,
                count: 1090,
                layout: LayoutKind::Concentric,
                res: 32,
                precision: Precision::U8,
            };
            let (f, _) = bake(&caster.mesh, params, &BakeOptions::default()).expect("bake");
            FieldScene {
                instances: vec![FieldInstance::new(Arc::new(f), caster.transform)],
                options: LookupOptions::default(),
            }
        });
        b.iter(|| ao(fs))
    });

    for res in [32, 64] {
        let f32_volume = OnceCell::new();
        let volume = || -> &DistanceVolume {
            f32_volume.get_or_init(|| DistanceVolume::bake(&model_triangles, res, 2).expect("bake"))
        };
        let sdf = |precision| SdfScene {
            instances: vec![SdfInstance {
                volume: Arc::new(volume().with_precision(precision)),
                transform: caster.transform,
            }],
            trace: SdfTrace::default(),
        };
        for precision in [visfield::sdf::Precision::F32, visfield::sdf::Precision::U8] {
            group.bench_function(format!("sdf_trace_{res}_{}", precision.name()), |b| {
                let s = sdf(precision);
                b.iter(|| ao(&s))
            });
        }
        group.bench_function(format!("sdf_cone_{res}_f32_9_cones"), |b| {
            let s = sdf(visfield::sdf::Precision::F32);
            let cones = ConeSet::hemisphere(9);
            let trace = ConeTrace::default();
            b.iter(|| {
                use rayon::prelude::*;
                (recv.points.par_iter().zip(&recv.normals))
                    .map(|(&p, &n)| {
                        s.cone_ao(p + opts.offset * n, n, &cones, f32::INFINITY, &trace)
                    })
                    .collect::<Vec<f32>>()
            })
        });
    }

    let fit = OnceCell::new();
    for precision in [
        visfield::aofield::Precision::F32,
        visfield::aofield::Precision::U8,
    ] {
        group.bench_function(format!("aofield_16_{}", precision.name()), |b| {
            let fitted = fit.get_or_init(|| {
                let params = BakeParams {
                    res: 16,
                    radial_samples: 12,
                    rays: 256,
                    reach: 8.0,
                };
                visfield::aofield::bake(&model_triangles, &params)
                    .expect("bake")
                    .0
            });
            let s = AoFieldScene {
                instances: vec![AoFieldInstance {
                    field: Arc::new(AoField::new(fitted, precision)),
                    transform: caster.transform,
                }],
                inside: Inside::default(),
            };
            b.iter(|| s.ao_at_points(&recv.points, &recv.normals))
        });
    }
    group.finish();
}

criterion_group!(benches, peers);
criterion_main!(benches);
