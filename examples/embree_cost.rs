//! Our tracer against Embree on the same rays (needs `--features embree` and libembree-dev).
//!
//! `cargo run --release --features embree --example embree_cost -- [ao|bake|all] [REPEATS]`
//!
//! - `ao`: vertex AO on the 2008 paper's Figure 6 rays (stanford-bunny_39k fitted to radius
//!   0.35 at (0.5, 0.45, 0.5) over the corner's 3 × 33 × 33 vertices, 256 stratified cosine
//!   rays each, `RaySet::new(16, 1)`), through `ao_at_points` as the harness runs it, on a pool
//!   of 2 threads: our tracer (obvhs CWBVH + watertight, any hit), Embree one ray at a time
//!   (`rtcOccluded1`), Embree 8-wide packets (`rtcOccluded8`) and the field lookup
//!   (1090 × 64² concentric u8, nearest; baked once into `$TMPDIR/visfield-embree-cost/`).
//!   Mrays/s, best of REPEATS (default 5) with the backends interleaved, and the AO of each
//!   against ours (max difference and the number of vertices that differ).
//! - `bake`: the field bake (290 × 64² concentric, the bunny) through our tracer and through
//!   Embree, each against its caster's raw closest-hit throughput on exactly the bake's rays.
//!
//! Times are wall clock on a shared machine: compare the ratios of one run, not the Mrays/s
//! across runs.

use glam::{Quat, Vec3};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;
use visfield::field::bake::{bake_with, BakeOptions};
use visfield::field::cache::load_or_bake;
use visfield::field::lookup::LookupOptions;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision, Selection};
use visfield::geometry::procedural::over_corner;
use visfield::geometry::{models, Mesh};
use visfield::render::ao::{ao_at_points, instance_epsilon, AoOptions};
use visfield::render::receivers::Receivers;
use visfield::sampling::rays::RaySet;
use visfield::sampling::{Frame, HemisphereLayout, LayoutKind, SphereKind, SpherePoints};
use visfield::trace::embree::{EmbreeRays, EmbreeTracer};
use visfield::trace::{ClosestHit, Tracer};
use visfield::visibility::Visibility;

const MODEL: &str = "stanford-bunny_39k";

fn best_of(repeats: usize, mut f: impl FnMut() -> f64) -> f64 {
    (0..repeats).map(|_| f()).fold(f64::INFINITY, f64::min)
}

fn ao(bunny: Mesh, repeats: usize) {
    let scene = over_corner(bunny, Quat::IDENTITY);
    let recv = Receivers::of(&scene);
    let opts = AoOptions {
        offset: 0.0,
        ..AoOptions::for_scene(scene.bounding_sphere())
    };
    let eps = instance_epsilon(&scene.instances[0]);
    let origins: Vec<Vec3> = recv
        .points
        .iter()
        .zip(&recv.normals)
        .map(|(&p, &n)| p + eps * n)
        .collect();
    let rays = RaySet::new(16, 1);
    let n_rays = (origins.len() * rays.len()) as f64;
    let tris = scene.caster_triangles();
    let t = Instant::now();
    let ours = Tracer::new(&tris);
    let ours_build = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let single = EmbreeTracer::new(&tris)
        .expect("Embree")
        .with_rays(EmbreeRays::Single);
    let embree_build = t.elapsed().as_secs_f64();
    let packets = EmbreeTracer::new(&tris)
        .expect("Embree")
        .with_rays(EmbreeRays::Packet8);
    let caster = &scene.instances[1];
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 1090,
        layout: LayoutKind::Concentric,
        res: 64,
        precision: Precision::U8,
    };
    let dir = std::env::temp_dir().join("visfield-embree-cost");
    std::fs::create_dir_all(&dir).expect("cache folder");
    let (field, _) =
        load_or_bake(&dir, &caster.mesh, MODEL, params, &BakeOptions::default()).expect("field");
    let fs = FieldScene {
        instances: vec![FieldInstance::new(Arc::new(field), caster.transform)],
        options: LookupOptions {
            selection: Selection::Nearest,
            ..LookupOptions::default()
        },
    };
    println!(
        "{} vertices x {} rays = {n_rays} rays; {} caster triangles; BVH build ours {ours_build:.2} s, \
         Embree {} {embree_build:.2} s",
        origins.len(),
        rays.len(),
        tris.len(),
        single.version()
    );
    let backends: [(&str, &dyn Visibility); 4] = [
        ("ours (obvhs + watertight)", &ours),
        ("Embree single rays", &single),
        ("Embree 8-wide packets", &packets),
        ("field 1090x64 u8 nearest", &fs),
    ];
    let run = |v: &dyn Visibility| ao_at_points(v, &origins, &recv.normals, &rays, &opts);
    let reference = run(&ours);
    let mut best = [f64::INFINITY; 4];
    for _ in 0..repeats {
        for (i, (_, v)) in backends.iter().enumerate() {
            let t = Instant::now();
            std::hint::black_box(run(*v));
            best[i] = best[i].min(t.elapsed().as_secs_f64());
        }
    }
    for (i, (name, v)) in backends.iter().enumerate() {
        let ao = run(*v);
        let diff = ao
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        let n_diff = ao.iter().zip(&reference).filter(|(a, b)| a != b).count();
        println!(
            "{name:28} {:7.2} Mrays/s  {:5.2}x ours  AO vs ours: max |diff| {diff:.4}, {n_diff} \
             vertices differ",
            n_rays / best[i] / 1e6,
            best[0] / best[i]
        );
    }
}

fn bake(bunny: Mesh, repeats: usize) {
    let tris: Vec<_> = (0..bunny.triangles.len())
        .map(|i| bunny.triangle(i))
        .collect();
    let ours = Tracer::new(&tris);
    let embree = EmbreeTracer::new(&tris).expect("Embree");
    let bounds = bunny.bounding_sphere();
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 290,
        layout: LayoutKind::Concentric,
        res: 64,
        precision: Precision::U8,
    };
    let points = SpherePoints::new(params.sphere, params.count).expect("points");
    let layout = HemisphereLayout::new(params.layout, params.res);
    // The bake's rays: each map's used texels from its point on the sphere, inwards.
    let rays: Vec<(Vec3, Vec3)> = (0..points.len())
        .flat_map(|m| {
            let frame = Frame::from_normal(-points.point(m));
            let origin = bounds.center + bounds.radius * points.point(m);
            (0..layout.texel_count() as u32)
                .filter_map(|t| layout.to_direction(t))
                .map(move |d| (origin, frame.to_world(d)))
                .collect::<Vec<_>>()
        })
        .collect();
    let n = rays.len() as f64;
    fn raw<T: ClosestHit>(c: &T, rays: &[(Vec3, Vec3)], chunk: usize, tmax: f32) -> usize {
        rays.par_chunks(chunk)
            .map(|ch| {
                ch.iter()
                    .filter(|(o, d)| c.closest_hit(*o, *d, 0.0, tmax).is_some())
                    .count()
            })
            .sum()
    }
    let tmax = 2.0 * bounds.radius;
    let chunk = layout.texel_count();
    let opts = BakeOptions::default();
    let time = |f: &mut dyn FnMut()| {
        best_of(repeats, || {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
    };
    let raw_ours = time(&mut || {
        std::hint::black_box(raw(&ours, &rays, chunk, tmax));
    });
    // The bake's own time (`BakeStats::seconds`: tracing and storing, as `bake` reports its
    // throughput); the set-up around it (sphere points, frames, texel table, intra tolerance)
    // is the same for both casters and outside it.
    let bake_time = |c: &dyn Fn() -> f64| (0..repeats).map(|_| c()).fold(f64::INFINITY, f64::min);
    let bake_ours = bake_time(&|| {
        bake_with(&ours, bounds, params, &opts)
            .expect("bake")
            .1
            .seconds
    });
    let raw_embree = time(&mut || {
        std::hint::black_box(raw(&embree, &rays, chunk, tmax));
    });
    let bake_embree = bake_time(&|| {
        bake_with(&embree, bounds, params, &opts)
            .expect("bake")
            .1
            .seconds
    });
    let (fo, _) = bake_with(&ours, bounds, params, &opts).expect("bake");
    let (fe, _) = bake_with(&embree, bounds, params, &opts).expect("bake");
    let texels = params.texels();
    let texels_differ = (0..params.count)
        .flat_map(|m| (0..texels).map(move |t| (m, t)))
        .filter(|&(m, t)| fo.storage.get(m, t) != fe.storage.get(m, t))
        .count();
    println!("bake 290x64 u8 of {MODEL}: {n} rays");
    for (name, raw_s, bake_s) in [
        ("ours", raw_ours, bake_ours),
        ("Embree", raw_embree, bake_embree),
    ] {
        println!(
            "{name:7} raw closest hit {:6.2} Mrays/s, bake {:6.2} Mrays/s: bake at {:.0}% of raw",
            n / raw_s / 1e6,
            n / bake_s / 1e6,
            100.0 * raw_s / bake_s
        );
    }
    println!(
        "Embree bake {:.2}x ours; u8 texels that differ between the two bakes: {texels_differ}",
        bake_ours / bake_embree
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let what = args.first().map_or("all", String::as_str);
    let repeats: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(5);
    let bunny = models::load_model(MODEL).unwrap_or_else(|e| {
        eprintln!("embree_cost: {e}");
        std::process::exit(1)
    });
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build_global()
        .expect("a pool of 2 threads");
    match what {
        "ao" => ao(bunny, repeats),
        "bake" => bake(bunny, repeats),
        "all" => {
            ao(bunny.clone(), repeats);
            bake(bunny, repeats);
        }
        _ => {
            eprintln!("usage: embree_cost [ao|bake|all] [REPEATS]");
            std::process::exit(2)
        }
    }
}
