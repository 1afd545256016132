//! Ray-cast throughput for ambient-occlusion rays: origins at the mesh vertices, offset along the
//! area-weighted vertex normal by `scene_epsilon(R)`, 16 stratified cosine directions each
//! (`RaySet::new(4, seed)`), unbounded. Closest hit and any hit, on one thread and on all.
//!
//! Mesh: `../shared/models/dragon.obj` (100,000 triangles) if present, else a generated
//! UV sphere of about 100,000 triangles. `cargo bench --bench trace`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{DVec3, Vec3};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;
use visfield::render::ao::scene_epsilon;
use visfield::sampling::{rays::RaySet, Frame};
use visfield::trace::{RayQuery, Tracer};

/// Indexed triangles.
struct Mesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

/// Minimal OBJ loader (positions and faces, triangulated).
fn load_obj(path: &Path) -> Option<Mesh> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(path, &opts).ok()?;
    let mut mesh = Mesh {
        positions: Vec::new(),
        triangles: Vec::new(),
    };
    for m in models {
        let base = mesh.positions.len() as u32;
        let p = &m.mesh.positions;
        mesh.positions.extend(
            p.chunks_exact(3)
                .map(|c| DVec3::new(c[0], c[1], c[2]).as_vec3()),
        );
        mesh.triangles.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|c| [base + c[0], base + c[1], base + c[2]]),
        );
    }
    Some(mesh)
}

/// A UV sphere with `rings × segments` quads (2 triangles each, minus the pole fans).
fn uv_sphere(rings: u32, segments: u32) -> Mesh {
    let mut positions = vec![Vec3::Z, -Vec3::Z];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            positions.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ));
        }
    }
    let v = |r: u32, s: u32| match r {
        0 => 0,
        r if r == rings => 1,
        r => 2 + (r - 1) * segments + s % segments,
    };
    let mut triangles = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (v(r, s), v(r + 1, s), v(r + 1, s + 1), v(r, s + 1));
            if r != 0 {
                triangles.push([a, b, d]);
            }
            if r + 1 != rings {
                triangles.push([b, c, d]);
            }
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

fn load_scene() -> (String, Mesh) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models/dragon.obj");
    match load_obj(&path) {
        Some(m) => ("dragon".into(), m),
        None => ("uv-sphere".into(), uv_sphere(224, 224)),
    }
}

/// AO rays: every `stride`-th vertex, 16 cosine directions around the vertex normal.
fn ao_rays(mesh: &Mesh, radius: f32, stride: usize) -> Vec<RayQuery> {
    let mut normals = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a); // area weighted
        for &i in t {
            normals[i as usize] += n;
        }
    }
    let set = RaySet::new(4, 1);
    let eps = scene_epsilon(radius);
    let mut dirs = Vec::new();
    let mut rays = Vec::new();
    for (i, (&p, n)) in mesh
        .positions
        .iter()
        .zip(&normals)
        .enumerate()
        .step_by(stride)
    {
        let Some(n) = n.try_normalize() else { continue };
        let frame = Frame::from_normal(n);
        set.fill(i as u32, &mut dirs);
        rays.extend(dirs.iter().map(|&d| RayQuery {
            origin: p + eps * n,
            dir: frame.to_world(d),
            tmin: 0.0,
            tmax: f32::INFINITY,
        }));
    }
    rays
}

fn bench_trace(c: &mut Criterion) {
    let (name, mesh) = load_scene();
    let tris: Vec<[Vec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    let (lo, hi) = mesh.positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let radius = 0.5 * (hi - lo).length();
    let start = Instant::now();
    let tracer = Tracer::new(&tris);
    println!(
        "{name}: {} triangles, BVH build {:.3} s, {} threads",
        tris.len(),
        start.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    let rays = ao_rays(&mesh, radius, (mesh.positions.len() / 4096).max(1));
    let hits = tracer.any_hits(&rays).iter().filter(|&&h| h).count();
    println!(
        "{} AO rays, {:.1} % occluded",
        rays.len(),
        100.0 * hits as f64 / rays.len() as f64
    );

    let mut group = c.benchmark_group(format!("ao_rays_{name}"));
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.bench_function(BenchmarkId::new("closest_hit", "1_thread"), |b| {
        b.iter(|| {
            rays.iter()
                .map(|r| tracer.closest_hit(r.origin, r.dir, r.tmin, r.tmax))
                .filter(Option::is_some)
                .count()
        })
    });
    group.bench_function(BenchmarkId::new("any_hit", "1_thread"), |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| tracer.any_hit(r.origin, r.dir, r.tmin, r.tmax))
                .count()
        })
    });
    group.bench_function(BenchmarkId::new("closest_hit", "all_threads"), |b| {
        b.iter(|| black_box(tracer.closest_hits(&rays)))
    });
    group.bench_function(BenchmarkId::new("any_hit", "all_threads"), |b| {
        b.iter(|| black_box(tracer.any_hits(&rays)))
    });
    group.finish();
}

criterion_group!(benches, bench_trace);
criterion_main!(benches);
