//! The field visibility's own top level on the GPU (`FieldGpuOptions::top_level`: a BVH over
//! the instances' bounding spheres, the CPU's `field::sphere_bvh`, rebuilt on the host and
//! walked in WGSL) against testing every instance's sphere on the GPU, bit for bit, on a small
//! moving crowd, for AO, soft shadows and reflections; and against the CPU's field values with
//! the GPU parity tests' bounds (tests/gpu.rs, tests/gpu_shadow.rs, tests/gpu_reflect.rs).
//!
//! Only a missing Vulkan driver skips these tests (reported as ignored, with the reason
//! printed; the harness is `main`, through libtest-mimic); every other GPU failure fails them.

use glam::{Quat, Vec3};
use std::sync::{Arc, OnceLock};
use visfield::field::bake::{bake_mesh_with_normals, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::normals::NormalField;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{Precision, Selection, VisibilityField};
use visfield::geometry::Similarity;
use visfield::gpu::{
    FieldAoKernel, FieldGpuOptions, FieldLayout, FieldReflectKernel, FieldShadowKernel,
};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::render::reflect::{reflect_at_points, Gloss, ReflectOptions};
use visfield::render::shadow::{shadow_at_points, ShadowOptions, SphereLight};
use visfield::sampling::rays::RaySet;

mod common;
use common::unit;
use common::{gpu_context as context, slater_params, supershape_2000 as caster};

/// The caster's field (290 Slater maps × 16² concentric texels, 8-bit) and its 16-bit normal
/// field.
fn field() -> &'static (Arc<VisibilityField>, Arc<NormalField>) {
    static FIELD: OnceLock<(Arc<VisibilityField>, Arc<NormalField>)> = OnceLock::new();
    FIELD.get_or_init(|| {
        let p = slater_params(290, 16, Precision::U8);
        let (f, n, _) =
            bake_mesh_with_normals(caster(), p, 16, &BakeOptions::default()).expect("bake");
        (Arc::new(f), Arc::new(n))
    })
}

/// A 4 × 4 crowd of the caster over the floor y = 0 at frame `frame`: each in its unit cell,
/// radius 0.3 to 0.4 (neighbours' spheres may overlap), orbiting its cell's centre and
/// turning; with the normal field.
fn crowd(frame: u32) -> Vec<FieldInstance> {
    let (f, n) = field();
    let s = f.bounds;
    (0..16u64)
        .map(|i| {
            let a = 0.8 * frame as f32 + 6.0 * unit(i);
            let centre = Vec3::new(
                (i % 4) as f32 - 1.5 + 0.1 * a.cos(),
                0.45,
                (i / 4) as f32 - 1.5 + 0.1 * a.sin(),
            );
            let radius = 0.3 + 0.1 * unit(i + 40);
            let axis = Vec3::new(unit(i + 1), 1.0, unit(i + 2)).normalize();
            let rotation = Quat::from_axis_angle(axis, a);
            let scale = radius / s.radius;
            let translation = centre - scale * (rotation * s.center);
            FieldInstance::new(f.clone(), Similarity::new(rotation, translation, scale))
                .with_normals(n.clone())
        })
        .collect()
}

/// Floor points under and between the casters (inter-object lookups) and some of the first
/// caster's own vertices (intra-object lookups), with unit normals.
fn receivers(insts: &[FieldInstance]) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut p: Vec<Vec3> = (0..24 * 24)
        .map(|i| {
            Vec3::new(
                (i % 24) as f32 / 6.0 - 2.0,
                0.0,
                (i / 24) as f32 / 6.0 - 2.0,
            )
        })
        .collect();
    let mut n = vec![Vec3::Y; p.len()];
    let c = caster();
    for (q, m) in c.positions.iter().zip(&c.normals).step_by(7) {
        p.push(insts[5].transform.to_world_point(*q));
        n.push(insts[5].transform.to_world_dir(*m).normalize());
    }
    (p, n)
}

fn with_top_level(top_level: bool) -> FieldGpuOptions {
    FieldGpuOptions {
        top_level,
        ..Default::default()
    }
}

/// How many values differ at all, and the largest difference.
fn differences(a: &[f32], b: &[f32]) -> (usize, f32) {
    assert_eq!(a.len(), b.len());
    let n = a
        .iter()
        .zip(b)
        .filter(|(x, y)| x.to_bits() != y.to_bits())
        .count();
    let max = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max);
    (n, max)
}

fn bit_identical(what: &str, top: &[f32], every: &[f32]) {
    let (n, max) = differences(top, every);
    assert_eq!(
        n, 0,
        "{what}: {n} values differ from every sphere's, by up to {max}"
    );
}

/// AO on three frames of the moving crowd, both selections: the top level's values are those
/// of every sphere (the workgroup queue's and the plain integrand's) bit for bit, and the
/// CPU's within the AO parity test's bound (no point off by more than 1/255, RMS at most 0.5
/// on the 0–255 scale); the motion reaches the device (the frames' values differ).
fn top_level_ao_is_every_spheres_bit_for_bit() {
    let ctx = context().expect("a Vulkan adapter (the harness checked)");
    let rays = RaySet::new(6, 3);
    let opts = AoOptions {
        max_distance: Some(1.5),
        ..AoOptions::for_scene_radius(3.0)
    };
    let first = crowd(0);
    let mut top = FieldAoKernel::new(ctx, &first, &with_top_level(true)).unwrap();
    let mut queue = FieldAoKernel::new(ctx, &first, &with_top_level(false)).unwrap();
    let plain_opts = FieldGpuOptions {
        queue_rays: false,
        ..with_top_level(false)
    };
    let mut plain = FieldAoKernel::new(ctx, &first, &plain_opts).unwrap();
    let mut previous: Option<Vec<f32>> = None;
    for frame in 0..3 {
        let insts = crowd(frame);
        let (p, n) = receivers(&insts);
        for k in [&top, &queue, &plain] {
            k.place(&insts).unwrap();
        }
        for selection in [Selection::Nearest, Selection::Interpolated] {
            let lookup = LookupOptions {
                selection,
                ..Default::default()
            };
            for k in [&mut top, &mut queue, &mut plain] {
                k.lookup = lookup;
            }
            let (t, _) = top.ao(&p, &n, &rays, &opts).unwrap();
            let (q, _) = queue.ao(&p, &n, &rays, &opts).unwrap();
            let (e, _) = plain.ao(&p, &n, &rays, &opts).unwrap();
            let what = format!("AO frame {frame} {selection:?}");
            bit_identical(&format!("{what} (queue)"), &t, &q);
            bit_identical(&format!("{what} (plain)"), &t, &e);
            let scene = FieldScene {
                instances: insts.clone(),
                options: lookup,
            };
            let cpu = ao_at_points(&scene, &p, &n, &rays, &opts);
            assert!(
                cpu.iter().filter(|&&v| v < 0.9).count() * 10 > cpu.len(),
                "{what}: little occlusion"
            );
            let over = t
                .iter()
                .zip(&cpu)
                .filter(|(a, b)| (*a - *b).abs() > 1.0 / 255.0 + 1e-6)
                .count();
            let rms = visfield::experiment::metrics::rms_unquantised(&t, &cpu);
            eprintln!("{what}: {over} over 1/255 from the CPU, RMS {rms:.4}/255");
            assert!(
                over == 0 && rms <= 0.5,
                "{what}: {over} over 1/255, RMS {rms}"
            );
            if selection == Selection::Nearest {
                if let Some(prev) = &previous {
                    assert_ne!(prev, &t, "{what}: answers as the frame before");
                }
                previous = Some(t);
            }
        }
    }
}

/// The top level bound after the 3D texture of the 2010 paper's layout instead of the storage
/// windows: AO every sphere's bit for bit there too.
fn top_level_binds_after_the_texture_layout() {
    let ctx = context().expect("a Vulkan adapter (the harness checked)");
    let rays = RaySet::new(4, 5);
    let opts = AoOptions {
        max_distance: Some(1.5),
        ..AoOptions::for_scene_radius(3.0)
    };
    let insts = crowd(1);
    let (p, n) = receivers(&insts);
    let texture = |top_level| FieldGpuOptions {
        layout: FieldLayout::Texture3d,
        ..with_top_level(top_level)
    };
    let top = FieldAoKernel::new(ctx, &insts, &texture(true)).unwrap();
    let every = FieldAoKernel::new(ctx, &insts, &texture(false)).unwrap();
    assert!(top.texture_depth().is_some());
    let (t, _) = top.ao(&p, &n, &rays, &opts).unwrap();
    let (e, _) = every.ao(&p, &n, &rays, &opts).unwrap();
    bit_identical("AO, texture layout", &t, &e);
    assert!(t.iter().any(|&v| v < 0.9), "no occlusion");
}

/// Soft shadows and glossy reflections on two frames: the top level's values are every
/// sphere's bit for bit; the CPU's within the f32 sums' rounding (shadows, at 99% of the
/// points; one ray's share elsewhere) and within 1e-3 at 99% of the points (reflections: the
/// bounds of tests/gpu_shadow.rs and tests/gpu_reflect.rs are finer-grained; this asks what
/// the top level must not change).
fn top_level_shadows_and_reflections_are_every_spheres_bit_for_bit() {
    let ctx = context().expect("a Vulkan adapter (the harness checked)");
    let rays = RaySet::new(4, 9);
    let light = SphereLight {
        center: Vec3::new(0.8, 3.0, 0.4),
        radius: 0.4,
        intensity: 1.0,
    };
    let sh = ShadowOptions {
        offset: 1e-4,
        lights: vec![light],
    };
    let refl = ReflectOptions {
        offset: 1e-4,
        eye: Vec3::new(0.0, 2.5, 4.0),
        gloss: Gloss::Phong { exponent: 20.0 },
        lights: vec![light],
        albedo: 0.8,
        sky: 0.1,
    };
    let first = crowd(0);
    let top_s = FieldShadowKernel::new(ctx, &first, &with_top_level(true)).unwrap();
    let every_s = FieldShadowKernel::new(ctx, &first, &with_top_level(false)).unwrap();
    let top_r = FieldReflectKernel::new(ctx, &first, &with_top_level(true)).unwrap();
    let every_r = FieldReflectKernel::new(ctx, &first, &with_top_level(false)).unwrap();
    for frame in [0, 2] {
        let insts = crowd(frame);
        let (p, n) = receivers(&insts);
        top_s.place(&insts).unwrap();
        every_s.place(&insts).unwrap();
        top_r.place(&insts).unwrap();
        every_r.place(&insts).unwrap();
        let scene = FieldScene {
            instances: insts.clone(),
            options: LookupOptions::default(),
        };
        let (t, _) = visfield::gpu::shadows(&top_s, &p, &n, &rays, &sh).unwrap();
        let (e, _) = visfield::gpu::shadows(&every_s, &p, &n, &rays, &sh).unwrap();
        bit_identical(&format!("shadows frame {frame}"), &t, &e);
        let cpu = shadow_at_points(&scene, &p, &n, &rays, &sh);
        assert!(
            cpu.contains(&0.0) || cpu.iter().any(|&v| v < 0.5),
            "shadows: none"
        );
        let rounding = 2.0 * 19.0 * 2f32.powi(-24);
        let off = t
            .iter()
            .zip(&cpu)
            .filter(|(a, b)| (*a - *b).abs() > rounding)
            .count();
        let (_, max) = differences(&t, &cpu);
        eprintln!(
            "shadows frame {frame}: {off} of {} beyond rounding, max {max}",
            t.len()
        );
        assert!(
            off * 100 <= t.len() && max <= 1.0 / 16.0 + 1e-4,
            "shadows: {off} off, max {max}"
        );

        let (t, _) = visfield::gpu::reflections(&top_r, &p, &n, &rays, &refl).unwrap();
        let (e, _) = visfield::gpu::reflections(&every_r, &p, &n, &rays, &refl).unwrap();
        bit_identical(&format!("reflections frame {frame}"), &t, &e);
        let cpu = reflect_at_points(&scene, &p, &n, &rays, &refl);
        assert!(
            cpu.iter().any(|&v| v != 0.1),
            "reflections: nothing reflected"
        );
        let close = t
            .iter()
            .zip(&cpu)
            .filter(|(a, b)| (*a - *b).abs() <= 1e-3)
            .count();
        eprintln!(
            "reflections frame {frame}: {close} of {} within 1e-3",
            t.len()
        );
        assert!(
            close * 100 >= 99 * t.len(),
            "reflections: {close} of {} close",
            t.len()
        );
    }
}

/// The harness: every test above, run where a Vulkan adapter exists and reported as ignored,
/// with the reason, where none does (a skipped test never shows as passed).
fn main() {
    common::run_gpu_trials(
        "gpu_field_top_level",
        &[
            (
                "top_level_ao_is_every_spheres_bit_for_bit",
                top_level_ao_is_every_spheres_bit_for_bit,
            ),
            (
                "top_level_binds_after_the_texture_layout",
                top_level_binds_after_the_texture_layout,
            ),
            (
                "top_level_shadows_and_reflections_are_every_spheres_bit_for_bit",
                top_level_shadows_and_reflections_are_every_spheres_bit_for_bit,
            ),
        ],
        &[],
    )
}
