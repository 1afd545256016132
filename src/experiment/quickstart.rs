//! `experiment quickstart`: the small tour on the embedded default scene (a supershape floating
//! over the 2008 paper's corner receiver). It computes ray-cast vertex AO at the corner's
//! vertices, bakes a small visibility field of the supershape, computes AO through the field on
//! the same rays, and writes per-vertex AO, images, an error-against-time plot and the run
//! metadata.

use super::meta::RunMeta;
use super::plot::{self, Axes, Series};
use super::progress::{stage, stage_best_of};
use crate::experiment::metrics::{rms_u8 as rms_255, rms_unquantised as rms_vertex};
use crate::field::bake::{bake, BakeOptions};
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::{FieldParams, Precision};
use crate::geometry::procedural;
use crate::render::ao::{ao_at_points, AoOptions};
use crate::render::camera::Camera;
use crate::render::primary::{gbuffer, shade_vertex_ao, PrimaryScene};
use crate::render::receivers::Receivers;
use crate::sampling::rays::RaySet;
use crate::sampling::{LayoutKind, SphereKind};
use crate::trace::Tracer;
use glam::Vec3;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

/// The default camera of the corner scenes: looking into the corner from the open octant.
pub fn corner_camera() -> Camera {
    Camera::corner()
}

/// Runs the tour and writes its outputs to `out`.
pub fn run(out: &Path) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let meta = RunMeta::collect(None);
    eprintln!(
        "quickstart: supershape over the corner receiver -> {}",
        out.display()
    );

    let scene = procedural::default_scene();
    let recv = Receivers::of(&scene);
    let casters = scene.caster_triangles();
    let scene_bounds = crate::geometry::minimal_bounding_sphere(
        &scene
            .instances
            .iter()
            .flat_map(|i| i.world_triangles().flatten())
            .collect::<Vec<_>>(),
    );
    let opts = AoOptions::for_scene(scene_bounds);
    let seed = 1;
    let rays = RaySet::new(16, seed); // 256 rays per vertex, as in the papers

    let (tracer, bvh_s) = stage("build BVH (reference)", || Tracer::new(&casters));
    let (ao_ref, ref_s) = stage_best_of("ray-cast AO, 256 rays/vertex", 3, || {
        ao_at_points(&tracer, &recv.points, &recv.normals, &rays, &opts)
    });

    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 1090,
        layout: LayoutKind::Concentric,
        res: 32,
        precision: Precision::U8,
    };
    let (caster_idx, caster) = scene.casters().next().ok_or("the scene has no caster")?;
    let pb = super::progress::bar(params.count as u64, "bake 1090 × 32² u8");
    let bake_opts = BakeOptions {
        progress: Some(&pb),
        ..BakeOptions::default()
    };
    let (field, stats) = bake(&caster.mesh, params, &bake_opts).map_err(|e| e.to_string())?;
    pb.finish_and_clear();
    eprintln!(
        "  {:<40} {:>9.3} s  ({:.1} Mrays/s)",
        "bake field",
        stats.seconds,
        stats.mrays_per_second()
    );
    let fscene = FieldScene {
        instances: vec![FieldInstance::new(Arc::new(field), caster.transform)],
        options: Default::default(),
    };
    let (ao_field, field_s) = stage_best_of("field-lookup AO, 256 rays/vertex", 3, || {
        ao_at_points(&fscene, &recv.points, &recv.normals, &rays, &opts)
    });
    let rms_v = rms_vertex(&ao_field, &ao_ref);

    // Error against time: ray casting with fewer rays, the field with more.
    let mut rc_pts = Vec::new();
    for k in [4u32, 8] {
        let r = RaySet::new(k, seed);
        let (ao, s) = stage_best_of(&format!("ray-cast AO, {} rays/vertex", k * k), 3, || {
            ao_at_points(&tracer, &recv.points, &recv.normals, &r, &opts)
        });
        rc_pts.push((s, rms_vertex(&ao, &ao_ref), k * k));
    }
    rc_pts.push((ref_s, 0.0, 256));
    let mut f_pts = vec![(field_s, rms_v, 256)];
    for k in [8u32, 32] {
        let r = RaySet::new(k, seed);
        let (ao, s) = stage_best_of(
            &format!("field-lookup AO, {} rays/vertex", k * k),
            3,
            || ao_at_points(&fscene, &recv.points, &recv.normals, &r, &opts),
        );
        f_pts.push((s, rms_vertex(&ao, &ao_ref), k * k));
    }

    // Images.
    let (w, h) = (384, 384);
    let cam = corner_camera();
    let ps = PrimaryScene::new(&scene);
    let gb = gbuffer(&ps, &cam, w, h);
    let (img_ref, mask) = shade_vertex_ao(&scene, &gb, w, h, &recv.split(&scene, &ao_ref));
    let (img_field, _) = shade_vertex_ao(&scene, &gb, w, h, &recv.split(&scene, &ao_field));
    let rms_i = rms_255(&img_field.data, &img_ref.data, Some(&mask));
    let diff = img_field.difference(&img_ref, 5.0);
    let io =
        |r: std::io::Result<()>, p: &str| r.map_err(|e| format!("{}: {e}", out.join(p).display()));
    io(
        img_ref.save_png(&out.join("ao_reference.png")),
        "ao_reference.png",
    )?;
    io(
        img_field.save_png(&out.join("ao_field.png")),
        "ao_field.png",
    )?;
    io(
        diff.save_png(&out.join("difference_x5.png")),
        "difference_x5.png",
    )?;
    io(
        img_ref.save_exr(&out.join("ao_reference.exr")),
        "ao_reference.exr",
    )?;
    io(
        img_field.save_exr(&out.join("ao_field.exr")),
        "ao_field.exr",
    )?;
    plot::image_grid(
        &out.join("images.png"),
        "quickstart: reference | field 1090 × 32² u8 | difference ×5",
        &[
            (
                &img_ref,
                vec!["ray cast, 256 rays".into(), format!("{ref_s:.3} s")],
            ),
            (
                &img_field,
                vec![
                    "field lookup, 256 rays".into(),
                    format!(
                        "bake {:.2} s, AO {field_s:.3} s, RMS {rms_i:.3}",
                        stats.seconds
                    ),
                ],
            ),
            (&diff, vec!["|field − reference| × 5".into()]),
        ],
        3,
    )?;
    plot::xy_plot(
        &out.join("pareto.png"),
        &Axes {
            title: "quickstart: vertex AO error against AO time".into(),
            x_label: "AO time (s, 2 threads)".into(),
            y_label: "RMS vs 256-ray reference (0–255)".into(),
            log_x: true,
            log_y: false,
        },
        &[
            Series {
                label: "ray cast (16, 64, 256 rays)".into(),
                points: rc_pts.iter().map(|p| (p.0, p.1)).collect(),
                line: true,
            },
            Series {
                label: "field 1090 × 32² u8 (256, 64, 1024 rays)".into(),
                points: f_pts.iter().map(|p| (p.0, p.1)).collect(),
                line: true,
            },
        ],
        &[],
    )?;

    // Per-vertex CSV.
    let mut csv = String::from("vertex,x,y,z,ao_reference,ao_field\n");
    for (i, p) in recv.points.iter().enumerate() {
        let _ = writeln!(
            csv,
            "{i},{},{},{},{},{}",
            p.x, p.y, p.z, ao_ref[i], ao_field[i]
        );
    }
    io(
        crate::io::write_atomic(&out.join("vertex_ao.csv"), csv.as_bytes()),
        "vertex_ao.csv",
    )?;

    let speedup = ref_s / field_s.max(1e-12);
    let summary = serde_json::json!({
        "meta": meta,
        "scene": {
            "receiver": "corner 3×33×33",
            "receiver_vertices": recv.points.len(),
            "caster": "supershape",
            "caster_triangles": caster.mesh.triangles.len(),
            "caster_instance": caster_idx,
        },
        "rays_per_vertex": 256,
        "seed": seed,
        "field": params,
        "field_bytes": fscene.instances[0].field.bytes(),
        "timings_s": {
            "bvh_build": bvh_s,
            "raycast_ao": ref_s,
            "bake": stats.seconds,
            "bake_mrays_per_s": stats.mrays_per_second(),
            "field_ao": field_s,
        },
        "rms_vertex": rms_v,
        "rms_image": rms_i,
        "speedup_field_vs_raycast": speedup,
        "raycast_sweep": rc_pts.iter().map(|p| serde_json::json!({"rays": p.2, "ao_s": p.0, "rms_vertex": p.1})).collect::<Vec<_>>(),
        "field_sweep": f_pts.iter().map(|p| serde_json::json!({"rays": p.2, "ao_s": p.0, "rms_vertex": p.1})).collect::<Vec<_>>(),
    });
    io(
        crate::io::write_atomic(
            &out.join("run.json"),
            serde_json::to_string_pretty(&summary)
                .expect("json")
                .as_bytes(),
        ),
        "run.json",
    )?;

    println!();
    println!(
        "visfield quickstart ({} threads, {})",
        meta.threads, meta.cpu
    );
    println!(
        "  receiver: corner, {} vertices; caster: supershape, {} triangles",
        recv.points.len(),
        caster.mesh.triangles.len()
    );
    println!("  ray-cast AO (256 rays/vertex):   {ref_s:>8.3} s");
    println!(
        "  field bake (1090 × 32² u8):      {:>8.3} s  ({:.1} Mrays/s, {} KiB)",
        stats.seconds,
        stats.mrays_per_second(),
        fscene.instances[0].field.bytes() / 1024
    );
    println!("  field-lookup AO (same rays):     {field_s:>8.3} s  ({speedup:.1}× faster)");
    println!("  RMS vs reference (0–255): per vertex {rms_v:.3}, per image pixel {rms_i:.3}");
    println!("  outputs: {}", out.display());
    Ok(())
}
