//! The field kernel's own top level against testing every sphere, and two-level GPU ray
//! casting, per frame in a moving crowd on the GPU (whatever adapter `VISFIELD_ADAPTER` picks):
//! N supershape casters (2,000 and 4,000 triangles in turn, one 290 × 16² u8 Slater field per
//! mesh) orbiting their cells of a √N × √N grid over a plane, vertex AO at the plane's points
//! (16 per cell, 64 cosine rays each). Per frame each method is moved (`place`: the instance
//! records, and the BVH over the spheres rebuilt and uploaded; `update`: the two levels' top
//! level rebuilt and uploaded; both wait for the upload) and queried; the medians over the
//! frames are printed, with the top level's answers checked bit for bit against every
//! sphere's and the two levels' largest difference from the field's.
//!
//! `cargo run --release --example gpu_crowd_top_level -- [N] [FRAMES]` (default 64 5; N a
//! perfect square). On lavapipe the times are indicative only.

use glam::{Quat, Vec3};
use std::sync::Arc;
use std::time::Instant;
use visfield::field::bake::{bake, BakeOptions};
use visfield::field::scene::FieldInstance;
use visfield::field::{FieldParams, Precision};
use visfield::geometry::procedural::{supershape, Supershape};
use visfield::geometry::Similarity;
use visfield::gpu::{AdapterPreference, FieldAoKernel, FieldGpuOptions, GpuContext, GpuTwoLevel};
use visfield::render::ao::AoOptions;
use visfield::sampling::rays::RaySet;
use visfield::sampling::{LayoutKind, SphereKind};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let arg = |i: usize, d: usize| -> usize {
        std::env::args()
            .nth(i)
            .map(|s| s.parse().expect("a number"))
            .unwrap_or(d)
    };
    let (n, frames) = (arg(1, 64), arg(2, 5));
    let side = (n as f64).sqrt() as usize;
    assert_eq!(side * side, n, "N must be a perfect square");
    let ctx = GpuContext::new(AdapterPreference::from_env()).expect("a GPU adapter");
    println!("adapter: {}", ctx.adapter_label());
    let meshes = [
        supershape(&Supershape::default(), 2000).unwrap(),
        supershape(&Supershape::default(), 4000).unwrap(),
    ];
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 290,
        layout: LayoutKind::Concentric,
        res: 16,
        precision: Precision::U8,
    };
    let fields: Vec<_> = (meshes.iter())
        .map(|m| Arc::new(bake(m, params, &BakeOptions::default()).expect("bake").0))
        .collect();
    let model: Vec<Vec<[Vec3; 3]>> = (meshes.iter())
        .map(|m| {
            (m.triangles.iter())
                .map(|t| t.map(|i| m.positions[i as usize]))
                .collect()
        })
        .collect();
    // Each caster fitted to a sphere of radius 0.3 in its unit cell, 0.02 over the plane y = 0,
    // orbiting the cell's centre at 0.12 and turning.
    let placement = |frame: usize| -> Vec<(usize, Similarity)> {
        (0..n)
            .map(|i| {
                let m = i % 2;
                let b = fields[m].bounds;
                let a = 0.7 * frame as f32 + 0.37 * i as f32;
                let half = (side as f32 - 1.0) / 2.0;
                let centre = Vec3::new(
                    (i % side) as f32 - half + 0.12 * a.cos(),
                    0.32,
                    (i / side) as f32 - half + 0.12 * a.sin(),
                );
                let axis = Vec3::new((i as f32 * 1.3).sin(), 1.0, (i as f32 * 0.7).cos());
                let rotation = Quat::from_axis_angle(axis.normalize(), a);
                let scale = 0.3 / b.radius;
                (
                    m,
                    Similarity::new(rotation, centre - scale * (rotation * b.center), scale),
                )
            })
            .collect()
    };
    let instances = |frame: usize| -> Vec<FieldInstance> {
        (placement(frame).into_iter())
            .map(|(m, t)| FieldInstance::new(fields[m].clone(), t))
            .collect()
    };
    let half = side as f32 / 2.0;
    let points: Vec<Vec3> = (0..side * 4 * side * 4)
        .map(|i| {
            let (x, z) = (i % (side * 4), i / (side * 4));
            Vec3::new(
                (x as f32 + 0.5) / 4.0 - half,
                0.0,
                (z as f32 + 0.5) / 4.0 - half,
            )
        })
        .collect();
    let normals = vec![Vec3::Y; points.len()];
    let rays = RaySet::new(8, 1);
    let opts = AoOptions {
        max_distance: Some(1.0),
        ..AoOptions::for_scene_radius(side as f32)
    };
    let first = instances(0);
    let every = FieldAoKernel::new(&ctx, &first, &FieldGpuOptions::default()).unwrap();
    let plain_opts = FieldGpuOptions {
        queue_rays: false,
        ..Default::default()
    };
    let plain = FieldAoKernel::new(&ctx, &first, &plain_opts).unwrap();
    let top_opts = FieldGpuOptions {
        top_level: true,
        ..Default::default()
    };
    let top = FieldAoKernel::new(&ctx, &first, &top_opts).unwrap();
    let mut two = GpuTwoLevel::new(&ctx, &model).unwrap();
    let labels = [
        "field_every_sphere@gpu (queue)",
        "field_every_sphere@gpu (ao_main)",
        "field@gpu (top level)",
        "two_level@gpu",
    ];
    let mut update = vec![Vec::new(); 4];
    let mut query = vec![Vec::new(); 4];
    let mut two_diff = 0.0f32;
    // Frame 0 once untimed: lavapipe compiles a pipeline on its first dispatch.
    for frame in 0..=frames {
        let insts = instances(frame);
        let mut values = Vec::new();
        for (k, kernel) in [&every, &plain, &top].into_iter().enumerate() {
            let t = Instant::now();
            kernel.place(&insts).unwrap();
            let u = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let (v, _) = kernel.ao(&points, &normals, &rays, &opts).unwrap();
            if frame > 0 {
                update[k].push(u);
                query[k].push(t.elapsed().as_secs_f64());
            }
            values.push(v);
        }
        let t = Instant::now();
        two.update(&placement(frame)).unwrap();
        let u = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (v, _) = visfield::gpu::ao(&two, &points, &normals, &rays, &opts).unwrap();
        if frame > 0 {
            update[3].push(u);
            query[3].push(t.elapsed().as_secs_f64());
        }
        assert!(
            values[2] == values[0] && values[1] == values[0],
            "frame {frame}: the top level's answers differ from every sphere's"
        );
        two_diff = (v.iter().zip(&values[0]))
            .map(|(a, b)| (a - b).abs())
            .fold(two_diff, f32::max);
    }
    println!(
        "{n} casters, {} points x {} rays, {frames} frames (medians); the top level's answers equal every sphere's bit for bit",
        points.len(),
        rays.len()
    );
    for (k, label) in labels.iter().enumerate() {
        println!(
            "  {label:<34} update {:>9.5} s  query {:>9.5} s",
            median(update[k].clone()),
            median(query[k].clone())
        );
    }
    println!(
        "  query, every sphere (queue) / top level: {:.2}x; two levels' largest AO difference from the field's {two_diff:.3}",
        median(query[0].clone()) / median(query[2].clone())
    );
}
