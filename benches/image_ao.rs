//! Per-pixel AO on the 2010 paper's Figure 3 setting (Gaitatzes, Andreadis, Papaioannou,
//! Chrysanthou, WSCG 2010): stanford-bunny_39k (38,889 triangles) fitted to a bounding sphere
//! of radius 0.35 centred at (0, 0.266, 0), a caster over a 4 × 4 plane receiver, seen from
//! (0, 0.75, 1.25) towards (0, 0.25, 0) with a 45° field of view at 256 × 256 pixels; 64
//! stratified cosine rays at each receiver pixel (`RaySet::new(8, 1)`). Field lookup (Slater
//! maps × 64² concentric texels, u8, nearest selection; 1090 and 4226 maps) against ray casting
//! (`Tracer`, any hit) on the same rays, through `ao_at_points` as the harness runs image AO.
//! Throughput is in rays (receiver pixels × 64).
//!
//! The G-buffer is cast once with the reference tracer, as in the harness; bakes are built on
//! first use (a filter that skips a field row skips its bake), and each field's image RMS
//! against the ray cast is printed once, for context. `cargo bench --bench image_ao`. The
//! bunny is found as everywhere else (`$VISFIELD_MODELS`, `data/models/`, `../shared/models/`);
//! without it the bench prints a note and does nothing.
//!
//! A second group times shadow rays on the same pixels (2010 §4.2): three spherical lights of
//! radius 0.35 (the `shadows2010_figure7` spec's), 16 stratified shadow rays per light and pixel
//! (`render::shadow`), through the 1090 × 64² field and by ray casting; throughput in shadow
//! rays. A third times reflection rays (2010 §4.2, Figure 9): the plane as a glossy floor
//! (Phong exponent 100, 4 rays per pixel, `render::reflect`), each ray's closest hit and normal
//! by ray casting or through the 1090 × 64² u16 field and its 16-bit normal field; throughput in
//! reflection rays.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Quat, Vec3};
use std::cell::OnceCell;
use std::sync::Arc;
use std::time::{Duration, Instant};
use visfield::experiment::metrics::rms_u8;
use visfield::field::bake::{bake, bake_mesh_with_normals, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision, Selection};
use visfield::geometry::{models, procedural, Instance, Scene, Similarity};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::render::camera::Camera;
use visfield::render::points::{EvalPoints, GBuffer};
use visfield::render::primary::{gbuffer, PrimaryScene};
use visfield::render::reflect::{reflect_at_points, Gloss, ReflectOptions};
use visfield::render::shadow::{shadow_at_points, ShadowOptions, SphereLight};
use visfield::sampling::rays::RaySet;
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::trace::Tracer;

const MODEL: &str = "stanford-bunny_39k";

/// The Figure 3 scene: the plane receiver and the fitted bunny caster.
fn figure3_scene() -> Option<Scene> {
    let bunny = match models::load_model(MODEL) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("image_ao bench: skipping {MODEL}: {e}");
            return None;
        }
    };
    let s = bunny.bounding_sphere();
    let k = 0.35 / s.radius;
    let fit = Similarity::new(Quat::IDENTITY, Vec3::new(0.0, 0.266, 0.0) - k * s.center, k);
    let plane = procedural::plane(4.0, 2).expect("plane");
    Some(Scene {
        instances: vec![
            Instance {
                mesh: Arc::new(plane),
                transform: Similarity::default(),
                caster: false,
                receiver: true,
            },
            Instance {
                mesh: Arc::new(bunny),
                transform: fit,
                caster: true,
                receiver: false,
            },
        ],
    })
}

fn image_ao(c: &mut Criterion) {
    let Some(scene) = figure3_scene() else { return };
    let camera = Camera {
        eye: Vec3::new(0.0, 0.75, 1.25),
        target: Vec3::new(0.0, 0.25, 0.0),
        up: Vec3::Y,
        fov_y_deg: 45.0,
    };
    let (w, h) = (256, 256);
    let gbuf = GBuffer {
        hits: gbuffer(&PrimaryScene::new(&scene), &camera, w, h),
        width: w,
        height: h,
    };
    // The points' origins carry each instance's ray offset: the estimators add none.
    let opts = AoOptions {
        offset: 0.0,
        ..AoOptions::for_scene(scene.bounding_sphere())
    };
    let pts = EvalPoints::pixels(&scene, &gbuf);
    let rays = RaySet::new(8, 1);
    eprintln!(
        "image_ao bench: {} receiver pixels of {w} × {h}, {} rays each",
        pts.len(),
        rays.len()
    );
    let run = |vis: &dyn visfield::visibility::Visibility| {
        ao_at_points(vis, &pts.origins, &pts.normals, &rays, &opts)
    };
    let tracer = OnceCell::new();
    let tracer = || tracer.get_or_init(|| Tracer::new(&scene.caster_triangles()));
    let reference = OnceCell::new();
    let reference = || {
        reference.get_or_init(|| {
            let ao = run(tracer());
            pts.image(&scene, &gbuf, &ao)
        })
    };
    let caster = &scene.instances[1];

    let mut group = c.benchmark_group(format!("image_ao_{w}x{h}_64_rays/{MODEL}"));
    group.sample_size(10);
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(5));
    group.throughput(Throughput::Elements((pts.len() * rays.len()) as u64));
    group.bench_function("raycast_anyhit", |b| {
        let tracer = tracer();
        b.iter(|| run(tracer))
    });
    for count in [1090, 4226] {
        let params = FieldParams {
            sphere: SphereKind::Slater,
            count,
            layout: LayoutKind::Concentric,
            res: 64,
            precision: Precision::U8,
        };
        // Baked on first use: criterion calls the closure once per warm-up and sample batch.
        let field = OnceCell::new();
        let field = || {
            field.get_or_init(|| {
                let t = Instant::now();
                let (f, stats) = bake(&caster.mesh, params, &BakeOptions::default()).expect("bake");
                let fs = FieldScene {
                    instances: vec![FieldInstance::new(Arc::new(f), caster.transform)],
                    options: LookupOptions {
                        selection: Selection::Nearest,
                        ..LookupOptions::default()
                    },
                };
                let (image, _) = pts.image(&scene, &gbuf, &run(&fs));
                let (expected, mask) = reference();
                eprintln!(
                    "image_ao bench: {count} × 64² u8 baked in {:.1} s ({:.1} Mrays/s); image \
                     RMS against the ray cast {:.3}/255",
                    t.elapsed().as_secs_f64(),
                    stats.mrays_per_second(),
                    rms_u8(&image.data, &expected.data, Some(mask))
                );
                fs
            })
        };
        let id = BenchmarkId::new("field_nearest", format!("{count}x64_u8"));
        group.bench_function(id, |b| {
            let fs = field();
            b.iter(|| run(fs))
        });
    }
    group.finish();

    // Shadow rays (2010 §4.2, Figure 7's three lights): 16 per light and pixel to the
    // spherical lights, through the 1090 × 64² field and by ray casting.
    let lights = [
        (Vec3::new(1.2, 2.0, 1.4), 0.35),
        (Vec3::new(-1.6, 1.8, 0.6), 0.35),
        (Vec3::new(0.4, 2.4, -1.4), 0.35),
    ]
    .map(|(center, radius)| SphereLight {
        center,
        radius,
        intensity: 1.0,
    });
    let sopts = ShadowOptions {
        offset: opts.offset,
        lights: lights.to_vec(),
    };
    let srays = RaySet::new(4, 1);
    let shadows = |vis: &dyn visfield::visibility::Visibility| {
        shadow_at_points(vis, &pts.origins, &pts.normals, &srays, &sopts)
    };
    let mut group = c.benchmark_group(format!("shadow_{w}x{h}_3x16_rays/{MODEL}"));
    group.sample_size(10);
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(5));
    group.throughput(Throughput::Elements(
        (pts.len() * srays.len() * lights.len()) as u64,
    ));
    group.bench_function("raycast_anyhit", |b| {
        let tracer = tracer();
        b.iter(|| shadows(tracer))
    });
    let field = OnceCell::new();
    let field = || {
        field.get_or_init(|| {
            let params = FieldParams {
                sphere: SphereKind::Slater,
                count: 1090,
                layout: LayoutKind::Concentric,
                res: 64,
                precision: Precision::U8,
            };
            let (f, _) = bake(&caster.mesh, params, &BakeOptions::default()).expect("bake");
            FieldScene {
                instances: vec![FieldInstance::new(Arc::new(f), caster.transform)],
                options: LookupOptions::default(),
            }
        })
    };
    group.bench_function(BenchmarkId::new("field_nearest", "1090x64_u8"), |b| {
        let fs = field();
        b.iter(|| shadows(fs))
    });
    group.finish();

    // Reflection rays (2010 §4.2, Figure 9): 4 per pixel in a Phong lobe about the mirror
    // direction, closest hit and normal by ray casting or through the field and normal field.
    let ropts = ReflectOptions {
        offset: opts.offset,
        eye: camera.eye,
        gloss: Gloss::Phong { exponent: 100.0 },
        lights: lights.to_vec(),
        albedo: 0.8,
        sky: 0.3,
    };
    let rrays = RaySet::new(2, 1);
    let reflect = |vis: &dyn visfield::visibility::Visibility| {
        reflect_at_points(vis, &pts.origins, &pts.normals, &rrays, &ropts)
    };
    let mut group = c.benchmark_group(format!("reflection_{w}x{h}_4_rays/{MODEL}"));
    group.sample_size(10);
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(5));
    group.throughput(Throughput::Elements((pts.len() * rrays.len()) as u64));
    group.bench_function("raycast_closest", |b| {
        let tracer = tracer();
        b.iter(|| reflect(tracer))
    });
    let with_normals = OnceCell::new();
    let with_normals = || {
        with_normals.get_or_init(|| {
            let params = FieldParams {
                sphere: SphereKind::Slater,
                count: 1090,
                layout: LayoutKind::Concentric,
                res: 64,
                precision: Precision::U16,
            };
            let (f, n, _) =
                bake_mesh_with_normals(&caster.mesh, params, 16, &BakeOptions::default())
                    .expect("bake");
            let inst = FieldInstance::new(Arc::new(f), caster.transform).with_normals(Arc::new(n));
            FieldScene {
                instances: vec![inst],
                options: LookupOptions::default(),
            }
        })
    };
    group.bench_function(
        BenchmarkId::new("field_nearest_normals", "1090x64_u16_n16"),
        |b| {
            let fs = with_normals();
            b.iter(|| reflect(fs))
        },
    );
    group.finish();
}

criterion_group!(benches, image_ao);
criterion_main!(benches);
