//! One vertex-AO pass over the field bench's scene (a caster over the corner, 256 rays at the
//! corner's vertices), by field lookup or by ray casting, for instruction and cache-miss counts
//! under valgrind (`benches/field.rs` times the same work with criterion).
//!
//! `cargo run --release --example ao_cost -- CASTER BACKEND [PRECISION] [STRIDE]`
//!
//! - CASTER: `bunny` (stanford-bunny_39k), `dragon` or `supershape` (261,120 triangles).
//! - BACKEND: `anyhit` (our ray caster: obvhs CWBVH with padded boxes at a working scale and
//!   watertight triangles), `anyhit-plain` (plain obvhs on the same triangles: unpadded boxes,
//!   no scaling, obvhs's Möller–Trumbore test; not watertight, a cost baseline only), `nearest`, `interpolated` (field lookup, per-ray
//!   queries) or `nearest-batch`, `interpolated-batch` (the batched per-point entry point);
//!   and the two cost floors of `visfield::experiment::performance::floor`, below any field lookup: `none`
//!   (every ray free: building the rays and the AO loop alone) and `sphere` (occluded where the
//!   ray meets the caster's bounding sphere: the cull and exact crossing every lookup starts
//!   with, without a map, texel or storage read).
//! - PRECISION: `u8` (default), `u16`, `f32`, `bit1`.
//! - STRIDE: use every STRIDE-th receiver vertex (default 1).
//!
//! Fields are baked once into `$TMPDIR/visfield-ao-cost/` and loaded from there afterwards, so
//! that a valgrind run measures the lookups, not the bake. The pass runs on one thread. Count
//! only the AO pass with
//! `valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*ao_pass*'`.

use glam::{Quat, Vec3};
use std::sync::Arc;
use std::time::Instant;
use visfield::field::bake::BakeOptions;
use visfield::field::cache::load_or_bake;
use visfield::field::lookup::LookupOptions;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision, Selection};
use visfield::geometry::procedural::{over_corner, supershape, Supershape};
use visfield::geometry::{models, Mesh};
use visfield::render::ao::{ao_at_point, AoOptions};
use visfield::render::receivers::Receivers;
use visfield::sampling::rays::RaySet;
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::trace::Tracer;
use visfield::visibility::{PerRay, Visibility};

use visfield::experiment::performance::floor::{NoQuery, SphereCull};

fn usage() -> ! {
    eprintln!(
        "usage: ao_cost CASTER(bunny|dragon|supershape) \
         BACKEND(anyhit|anyhit-plain|nearest|interpolated|nearest-batch|interpolated-batch|none|sphere) \
         [PRECISION(u8|u16|f32|bit1)] [STRIDE]"
    );
    std::process::exit(2)
}

/// The AO pass alone, on this thread (what callgrind's `--toggle-collect` names): the loop of
/// `ao_at_points` without its thread pool.
#[inline(never)]
fn ao_pass<V: Visibility + ?Sized>(vis: &V, p: &[Vec3], n: &[Vec3], rays: &RaySet) -> Vec<f32> {
    let opts = AoOptions::for_scene_radius(0.9);
    let prepared = rays.prepare();
    let mut scratch = Vec::with_capacity(rays.len());
    (0..p.len())
        .map(|i| ao_at_point(vis, i as u32, p[i], n[i], &prepared, &opts, &mut scratch))
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        usage();
    }
    let (mesh, key): (Mesh, String) = match args[0].as_str() {
        "bunny" | "dragon" => {
            let name = if args[0] == "bunny" {
                "stanford-bunny_39k"
            } else {
                "dragon"
            };
            let mesh = models::load_model(name).unwrap_or_else(|e| {
                eprintln!("{e}");
                std::process::exit(1)
            });
            (mesh, name.to_string())
        }
        "supershape" => (
            supershape(&Supershape::default(), 261_120).expect("supershape"),
            "supershape-default-261120".to_string(),
        ),
        _ => usage(),
    };
    let precision = match args.get(2).map(String::as_str).unwrap_or("u8") {
        "u8" => Precision::U8,
        "u16" => Precision::U16,
        "f32" => Precision::F32,
        "bit1" => Precision::Bit1,
        _ => usage(),
    };
    let stride: usize = match args.get(3) {
        Some(s) => s.parse().unwrap_or_else(|_| usage()),
        None => 1,
    };
    let scene = over_corner(mesh, Quat::IDENTITY);
    let recv = Receivers::of(&scene);
    let points: Vec<Vec3> = recv.points.iter().copied().step_by(stride.max(1)).collect();
    let normals: Vec<Vec3> = recv
        .normals
        .iter()
        .copied()
        .step_by(stride.max(1))
        .collect();
    let rays = RaySet::new(16, 1);
    let caster = &scene.instances[1];
    let n_rays = points.len() * rays.len();
    let (ao, secs) = if args[1] == "none" {
        let t = Instant::now();
        let ao = ao_pass(&NoQuery, &points, &normals, &rays);
        (ao, t.elapsed().as_secs_f64())
    } else if args[1] == "anyhit-plain" {
        let plain = PlainObvhs::new(&scene.caster_triangles());
        let t = Instant::now();
        let ao = ao_pass(&plain, &points, &normals, &rays);
        (ao, t.elapsed().as_secs_f64())
    } else if args[1] == "anyhit" {
        let tracer = Tracer::new(&scene.caster_triangles());
        let t = Instant::now();
        let ao = ao_pass(&tracer, &points, &normals, &rays);
        (ao, t.elapsed().as_secs_f64())
    } else {
        let (selection, batch) = match args[1].as_str() {
            "nearest" => (Selection::Nearest, false),
            "interpolated" => (Selection::Interpolated, false),
            "nearest-batch" => (Selection::Nearest, true),
            "interpolated-batch" | "sphere" => (Selection::Interpolated, true),
            _ => usage(),
        };
        let params = FieldParams {
            sphere: SphereKind::Slater,
            count: 4226,
            layout: LayoutKind::Concentric,
            res: 32,
            precision,
        };
        let dir = std::env::temp_dir().join("visfield-ao-cost");
        std::fs::create_dir_all(&dir).expect("cache folder");
        let (field, _) =
            load_or_bake(&dir, &caster.mesh, &key, params, &BakeOptions::default()).expect("field");
        println!(
            "field {} bytes; lookup tables: owner {} bytes, texel {} bytes",
            field.bytes(),
            field.points.owner_table_bytes(),
            field.texels.bytes()
        );
        let fs = FieldScene {
            instances: vec![FieldInstance::new(Arc::new(field), caster.transform)],
            options: LookupOptions {
                selection,
                ..LookupOptions::default()
            },
        };
        let t = Instant::now();
        let ao = if args[1] == "sphere" {
            ao_pass(&SphereCull(&fs), &points, &normals, &rays)
        } else if batch {
            ao_pass(&fs, &points, &normals, &rays)
        } else {
            ao_pass(&PerRay(&fs), &points, &normals, &rays)
        };
        (ao, t.elapsed().as_secs_f64())
    };
    let mean = ao.iter().sum::<f32>() / ao.len().max(1) as f32;
    println!(
        "{} points x {} rays = {n_rays} rays, mean AO {mean:.6}, {:.3} s, {:.2} Mrays/s",
        points.len(),
        rays.len(),
        secs,
        n_rays as f64 / secs / 1e6
    );
}

/// Plain obvhs any hit (the `medium_build` CWBVH over the triangles' own boxes, obvhs's
/// Möller–Trumbore test): what our ray caster costs over obvhs itself on the same rays.
struct PlainObvhs {
    bvh: obvhs::cwbvh::CwBvh,
    triangles: Vec<obvhs::triangle::Triangle>,
}

impl PlainObvhs {
    fn new(tris: &[[Vec3; 3]]) -> PlainObvhs {
        use obvhs::triangle::Triangle;
        let tris: Vec<Triangle> = tris
            .iter()
            .map(|t| Triangle {
                v0: t[0].into(),
                v1: t[1].into(),
                v2: t[2].into(),
            })
            .collect();
        let boxes: Vec<obvhs::aabb::Aabb> = tris.iter().map(|t| t.aabb()).collect();
        let bvh = obvhs::cwbvh::builder::build_cwbvh(
            &boxes,
            obvhs::BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        let triangles = bvh
            .primitive_indices
            .iter()
            .map(|&i| tris[i as usize])
            .collect();
        PlainObvhs { bvh, triangles }
    }
}

impl Visibility for PlainObvhs {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let ray = obvhs::ray::Ray::new(origin.into(), dir.into(), tmin, tmax);
        !self.bvh.ray_traverse_miss(ray, |r, id| {
            let t = self.triangles[id].intersect(r);
            if t >= tmin && t <= tmax {
                f32::NEG_INFINITY
            } else {
                f32::INFINITY
            }
        })
    }

    fn hit_distance(&self, _: Vec3, _: Vec3, _: f32, _: f32) -> Option<f32> {
        unimplemented!("ao_cost times any-hit queries only")
    }

    fn surface_hit(
        &self,
        _: Vec3,
        _: Vec3,
        _: f32,
        _: f32,
    ) -> Option<visfield::visibility::SurfaceHit> {
        unimplemented!("ao_cost times any-hit queries only")
    }
}
