//! The AO field's cost against its paper's claims (Kontkanen & Laine 2005): one occluder (the
//! 39k bunny, `stanford-bunny_39k`) baked at cube-map sides 8, 16 and 32, its exact bytes at each
//! precision, and the time to evaluate AO at one frame's worth of receiver points (1024 × 768,
//! the paper's Figure 1 resolution) on a plane below it, on one thread and on all.
//!
//! `cargo run --release --example aofield_speed` (fits cached in `cache/`, as the harness's).

use glam::Vec3;
use std::sync::Arc;
use std::time::Instant;
use visfield::aofield::cache::load_or_bake;
use visfield::aofield::{AoField, AoFieldInstance, AoFieldScene, BakeParams, Inside, Precision};
use visfield::geometry::Similarity;

fn main() {
    let mesh = visfield::geometry::models::load_model("stanford-bunny_39k")
        .expect("stanford-bunny_39k: `experiment models fetch stanford-bunny_39k`");
    let sha = visfield::experiment::scenes::mesh_sha256(&mesh);
    let tris: Vec<[Vec3; 3]> = (0..mesh.triangle_count())
        .map(|t| mesh.triangle(t))
        .collect();
    let bounds = mesh.bounding_sphere();
    // One frame's receiver points: a 1024 × 768 grid on the plane one bounding radius below the
    // bunny, spanning ±4 radii, normals up.
    let (w, h) = (1024, 768);
    let r = bounds.radius;
    let mut points = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            let x = (i as f32 / (w - 1) as f32 - 0.5) * 8.0 * r;
            let z = (j as f32 / (h - 1) as f32 - 0.5) * 6.0 * r;
            points.push(bounds.center + Vec3::new(x, -2.0 * r, z));
        }
    }
    let normals = vec![Vec3::Y; points.len()];
    let threads = rayon::current_num_threads();
    println!(
        "bunny: {} triangles; {} points; {threads} threads",
        tris.len(),
        points.len()
    );
    println!("res  precision  bytes  bake_s  1-thread Mpoints/s  {threads}-thread Mpoints/s");
    for res in [8, 16, 32] {
        let params = BakeParams {
            res,
            ..BakeParams::default()
        };
        let t0 = Instant::now();
        let (fitted, _) =
            load_or_bake(Some(std::path::Path::new("cache")), &sha, &tris, &params).expect("bake");
        let bake_s = t0.elapsed().as_secs_f64();
        for precision in [Precision::F32, Precision::F16, Precision::U8] {
            let field = Arc::new(AoField::new(&fitted, precision));
            let scene = AoFieldScene {
                instances: vec![AoFieldInstance {
                    field: field.clone(),
                    transform: Similarity::default(),
                }],
                inside: Inside::default(),
            };
            let best = |f: &dyn Fn() -> f32| {
                (0..3)
                    .map(|_| {
                        let t = Instant::now();
                        std::hint::black_box(f());
                        t.elapsed().as_secs_f64()
                    })
                    .fold(f64::INFINITY, f64::min)
            };
            let one = best(&|| points.iter().map(|&p| scene.ao(p, Vec3::Y)).sum());
            let all = best(&|| scene.ao_at_points(&points, &normals).iter().sum());
            let n = points.len() as f64 / 1e6;
            println!(
                "{res:3}  {:9}  {:6}  {bake_s:6.2}  {:18.2}  {:18.2}",
                precision.name(),
                field.bytes(),
                n / one,
                n / all
            );
        }
    }
}
