//! Field-lookup AO against CWBVH ray casting on the same rays, on the GPU (whatever adapter
//! `VISFIELD_ADAPTER` picks) and on the CPU: figure6's scene (stanford-bunny_39k over the
//! corner's 3 × 33 × 33 vertices, 256 stratified cosine rays each), a Slater × concentric u8
//! field, nearest selection. The backends (and the GPU field kernel without the queue and
//! without the lookup tables) run interleaved ROUNDS times; the medians and
//! the two field / ray-casting speed-ups are printed, with the GPU answers' largest difference
//! from the CPU field's.
//!
//! `cargo run --release --example gpu_field_speed -- [MAPS] [RES] [ROUNDS]` (default 290 32 5).

use glam::Quat;
use std::sync::Arc;
use std::time::{Duration, Instant};
use visfield::field::bake::BakeOptions;
use visfield::field::cache::load_or_bake;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision};
use visfield::geometry::models;
use visfield::geometry::procedural::over_corner;
use visfield::gpu::{AdapterPreference, FieldAoKernel, FieldGpuOptions, GpuContext, GpuTracer};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::render::receivers::Receivers;
use visfield::sampling::rays::RaySet;
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::trace::Tracer;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn max_diff(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

fn main() {
    let arg = |i: usize, d: usize| -> usize {
        std::env::args()
            .nth(i)
            .map(|s| s.parse().expect("a number"))
            .unwrap_or(d)
    };
    let (maps, res, rounds) = (arg(1, 290), arg(2, 32) as u32, arg(3, 5));
    let mesh = models::load_model("stanford-bunny_39k").expect("bunny");
    let scene = over_corner(mesh, Quat::IDENTITY);
    let recv = Receivers::of(&scene);
    let (p, n) = (&recv.points, &recv.normals);
    let caster = &scene.instances[1];
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: maps,
        layout: LayoutKind::Concentric,
        res,
        precision: Precision::U8,
    };
    let dir = std::env::temp_dir().join("visfield-ao-cost");
    std::fs::create_dir_all(&dir).expect("cache folder");
    let (field, _) = load_or_bake(
        &dir,
        &caster.mesh,
        "stanford-bunny_39k",
        params,
        &BakeOptions::default(),
    )
    .expect("field");
    let inst = FieldInstance::new(Arc::new(field), caster.transform);
    let fs = FieldScene {
        instances: vec![inst.clone()],
        options: Default::default(),
    };
    let tris = scene.caster_triangles();
    let tracer = Tracer::new(&tris);
    let rays = RaySet::new(16, 1);
    let opts = AoOptions::for_scene_radius(1.0);
    let ctx = GpuContext::new(AdapterPreference::from_env()).expect("adapter");
    let kernel = FieldAoKernel::new(
        &ctx,
        std::slice::from_ref(&inst),
        &FieldGpuOptions::default(),
    )
    .expect("kernel");
    let direct = FieldAoKernel::new(
        &ctx,
        std::slice::from_ref(&inst),
        &FieldGpuOptions {
            queue_rays: false,
            ..Default::default()
        },
    )
    .expect("kernel");
    let untabled = FieldAoKernel::new(
        &ctx,
        std::slice::from_ref(&inst),
        &FieldGpuOptions {
            lookup_tables: false,
            ..Default::default()
        },
    )
    .expect("kernel");
    let gtracer = GpuTracer::new(&ctx, &tris).expect("gpu tracer");
    println!(
        "{} on {}: {} points x {} rays",
        params_label(maps, res),
        ctx.adapter_label(),
        p.len(),
        rays.len()
    );
    let cpu_field = ao_at_points(&fs, p, n, &rays, &opts);
    let (gf, _) = kernel.ao(p, n, &rays, &opts).expect("field kernel");
    let (gd, _) = direct.ao(p, n, &rays, &opts).expect("direct kernel");
    let (gu, _) = untabled.ao(p, n, &rays, &opts).expect("untabled kernel");
    println!(
        "max |queued - direct| {:e}; max |tables - no tables| {:e}",
        max_diff(&gf, &gd),
        max_diff(&gf, &gu)
    );
    let (gt, _) = visfield::gpu::ao(&gtracer, p, n, &rays, &opts).expect("gpu tracer");
    println!(
        "max |gpu field - cpu field| {:e}; max |gpu cwbvh - gpu field| {:e}",
        max_diff(&gf, &cpu_field),
        max_diff(&gt, &gf)
    );
    let kern = |t: &visfield::gpu::GpuTiming| t.kernel.unwrap_or(t.wall).as_secs_f64();
    let wall = |f: &dyn Fn()| {
        let t = Instant::now();
        f();
        t.elapsed().as_secs_f64()
    };
    let mut s: [Vec<f64>; 6] = Default::default();
    for _ in 0..rounds {
        s[0].push(kern(&kernel.ao(p, n, &rays, &opts).unwrap().1));
        s[1].push(kern(
            &visfield::gpu::ao(&gtracer, p, n, &rays, &opts).unwrap().1,
        ));
        s[2].push(wall(&|| drop(ao_at_points(&fs, p, n, &rays, &opts))));
        s[3].push(wall(&|| drop(ao_at_points(&tracer, p, n, &rays, &opts))));
        s[4].push(kern(&direct.ao(p, n, &rays, &opts).unwrap().1));
        s[5].push(kern(&untabled.ao(p, n, &rays, &opts).unwrap().1));
        std::thread::sleep(Duration::from_millis(50));
    }
    let m: Vec<f64> = s.iter().map(|v| median(v.clone())).collect();
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("rounds {rounds}, load {}", load.trim());
    println!(
        "gpu field kernel {:.4} s  gpu cwbvh kernel {:.4} s  ratio {:.2}",
        m[0],
        m[1],
        m[1] / m[0]
    );
    println!(
        "gpu direct (before) {:.4} s  ratio to cwbvh {:.2}  queued speed-up {:.2}",
        m[4],
        m[1] / m[4],
        m[4] / m[0]
    );
    println!(
        "gpu no tables    {:.4} s  ratio to cwbvh {:.2}  tables speed-up {:.2}",
        m[5],
        m[1] / m[5],
        m[5] / m[0]
    );
    println!(
        "cpu field        {:.4} s  cpu raycast      {:.4} s  ratio {:.2}",
        m[2],
        m[3],
        m[3] / m[2]
    );
    // Per-round ratios: both sides of a round ran under about the same load.
    let paired = |a: usize, b: usize| median(s[a].iter().zip(&s[b]).map(|(x, y)| x / y).collect());
    println!(
        "median per-round ratios: gpu cwbvh / field {:.2}, cwbvh / direct {:.2}, cwbvh / no tables {:.2}, cpu raycast / field {:.2}",
        paired(1, 0),
        paired(1, 4),
        paired(1, 5),
        paired(3, 2)
    );
    println!("samples: {s:?}");
}

fn params_label(maps: usize, res: u32) -> String {
    format!("slater {maps} x concentric {res}² u8 nearest")
}
