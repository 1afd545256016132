//! The 2010 paper's other rays on `ao_cost`'s scene and field (the bunny over the corner, the
//! bunny's Slater 4226 × concentric 32² u8 field), for instruction counts under valgrind: shadow
//! rays to spherical lights (`render::shadow::light_fraction`, one `occluded_many_to` call per
//! receiver with a far end per ray), intra-object rays (vertex AO at the bunny's own vertices,
//! every ray starting inside the caster's sphere) and reflection rays
//! (`render::reflect::reflected`, one `surface_hit_many` call per receiver).
//!
//! `cargo run --release --example ray_cost -- KIND BACKEND [STRIDE]`
//!
//! - KIND: `shadow` (the corner's vertices, three lights of radius 0.3 over the open side of the
//!   corner, 4 × 4 rays per light), `intra` (the bunny's vertices, 16 × 16 AO rays),
//!   `reflect` (the corner's vertices seen from an eye, a Phong lobe of exponent 50, 4 × 4
//!   rays) or `reflect4` (the same with 2 × 2 rays and a second bunny beside the first, the
//!   shape of the 2010 Figure 9: four rays per point, two casters).
//! - BACKEND: `field` (the batched field lookup, nearest), `per-ray` (the field one ray at a
//!   time, `visibility::PerRay`), `raycast` (our ray caster), `embree` (Embree 3 as the
//!   `embree` method runs it: 8-wide `rtcOccluded8` packets for shadow and AO rays,
//!   `rtcIntersect1` and the hit triangle's normal for reflection rays; `--features embree`),
//!   or the cost floors of
//!   `visfield::experiment::performance::floor`: `none` (every ray free: building the rays and
//!   the caller's loop) and `sphere` (the bounding-sphere cull and exact crossing alone).
//! - STRIDE: use every STRIDE-th receiver vertex (default 1).
//!
//! The field is `ao_cost`'s (baked into `$TMPDIR/visfield-ao-cost/`); `reflect` also bakes the
//! field's normal field once and keeps it there. The pass runs on one thread. Count only the
//! pass with `valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*ray_pass*'`.

use glam::{Quat, Vec3};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
use visfield::field::bake::{bake_mesh_with_normals, BakeOptions};
use visfield::field::cache::load_or_bake;
use visfield::field::normals::NormalField;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision};
use visfield::geometry::procedural::over_corner;
use visfield::geometry::{models, Scene};
use visfield::render::ao::{ao_at_point, AoOptions};
use visfield::render::receivers::Receivers;
use visfield::render::reflect::{reflected, ReflectScratch};
use visfield::render::shadow::{light_fraction, ShadowScratch};
use visfield::sampling::rays::RaySet;
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::trace::Tracer;
use visfield::visibility::{PerRay, Visibility};

use visfield::experiment::performance::floor::{NoQuery, SphereCull};
use visfield::experiment::performance::secondary::{Counted, Secondary};

const MODEL: &str = "stanford-bunny_39k";

fn usage() -> ! {
    eprintln!(
        "usage: ray_cost KIND(shadow|intra|reflect) \
         BACKEND(field|per-ray|raycast|embree|none|sphere) [STRIDE]"
    );
    std::process::exit(2)
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Shadow,
    Intra,
    Reflect,
    /// Reflection rays, 2 × 2 per point, two casters.
    Reflect4,
}

/// One pass of `kind`'s rays at every point, on this thread (what callgrind's
/// `--toggle-collect` names); returns the per-point values and the rays cast.
#[inline(never)]
fn ray_pass<V: Visibility + ?Sized>(
    vis: &V,
    kind: Kind,
    p: &[Vec3],
    n: &[Vec3],
    rays: &RaySet,
) -> (Vec<f32>, usize) {
    let mut cast = 0;
    let values = match kind {
        Kind::Shadow => {
            // `experiment performance`'s shadow rays.
            let opts = Secondary::new(&AoOptions::for_scene_radius(0.9)).shadow;
            let mut sc = ShadowScratch::default();
            (0..p.len())
                .map(|i| {
                    let counted = Counted::new(vis);
                    let f = light_fraction(&counted, i as u32, p[i], n[i], rays, &opts, &mut sc);
                    cast += counted.rays() as usize;
                    f
                })
                .collect()
        }
        Kind::Intra => {
            let opts = AoOptions::for_scene_radius(0.9);
            let prepared = rays.prepare();
            let mut scratch = Vec::with_capacity(rays.len());
            cast = p.len() * rays.len();
            (0..p.len())
                .map(|i| ao_at_point(vis, i as u32, p[i], n[i], &prepared, &opts, &mut scratch))
                .collect()
        }
        Kind::Reflect | Kind::Reflect4 => {
            // `experiment performance`'s reflection rays.
            let opts = Secondary::new(&AoOptions::for_scene_radius(0.9)).reflect;
            let mut sc = ReflectScratch::default();
            (0..p.len())
                .map(|i| {
                    let counted = Counted::new(vis);
                    let v = reflected(&counted, i as u32, p[i], n[i], rays, &opts, &mut sc);
                    cast += counted.rays() as usize;
                    v
                })
                .collect()
        }
    };
    (values, cast)
}

/// The normal field of `field_params` for the bunny, baked once and kept beside `ao_cost`'s
/// fields (raw: texel count, bits, then the packed pairs, little-endian).
fn normals(dir: &Path, mesh: &visfield::geometry::Mesh, params: FieldParams) -> NormalField {
    let path = dir.join(format!(
        "{MODEL}-normals-{}x{}.bin",
        params.count, params.res
    ));
    if let Ok(bytes) = std::fs::read(&path) {
        let word = |k: usize| u64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().unwrap());
        let (texels, bits) = (word(0) as usize, word(1) as u32);
        let data = bytes[16..]
            .chunks_exact(4)
            .map(|c| {
                [
                    u16::from_le_bytes([c[0], c[1]]),
                    u16::from_le_bytes([c[2], c[3]]),
                ]
            })
            .collect();
        return NormalField { texels, bits, data };
    }
    let (_, normals, _) =
        bake_mesh_with_normals(mesh, params, 16, &BakeOptions::default()).expect("bake");
    let mut bytes = Vec::with_capacity(16 + 4 * normals.data.len());
    bytes.extend((normals.texels as u64).to_le_bytes());
    bytes.extend((normals.bits as u64).to_le_bytes());
    for [a, b] in &normals.data {
        bytes.extend(a.to_le_bytes());
        bytes.extend(b.to_le_bytes());
    }
    std::fs::write(&path, bytes).expect("write the normal field");
    normals
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        usage();
    }
    let kind = match args[0].as_str() {
        "shadow" => Kind::Shadow,
        "intra" => Kind::Intra,
        "reflect" => Kind::Reflect,
        "reflect4" => Kind::Reflect4,
        _ => usage(),
    };
    let stride: usize = match args.get(2) {
        Some(s) => s.parse().unwrap_or_else(|_| usage()),
        None => 1,
    };
    let mesh = models::load_model(MODEL).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1)
    });
    let mut scene = over_corner(mesh, Quat::IDENTITY);
    if kind == Kind::Reflect4 {
        let mut second = scene.instances[1].clone();
        second.transform.translation += Vec3::new(0.25, 0.1, -0.3);
        scene.instances.push(second);
    }
    let caster = &scene.instances[1];
    // Shadow and reflection rays leave the corner; intra-object rays the bunny's surface.
    let recv = if kind == Kind::Intra {
        let mut own = caster.clone();
        own.receiver = true;
        Receivers::of(&Scene {
            instances: vec![own],
        })
    } else {
        Receivers::of(&scene)
    };
    let pick = |v: &[Vec3]| v.iter().copied().step_by(stride.max(1)).collect::<Vec<_>>();
    let (points, normals_at) = (pick(&recv.points), pick(&recv.normals));
    let rays = RaySet::new(
        match kind {
            Kind::Intra => 16,
            Kind::Reflect4 => 2,
            _ => 4,
        },
        1,
    );

    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 4226,
        layout: LayoutKind::Concentric,
        res: 32,
        precision: Precision::U8,
    };
    let dir = std::env::temp_dir().join("visfield-ao-cost");
    std::fs::create_dir_all(&dir).expect("cache folder");
    let backend = args[1].as_str();
    let fs = if matches!(backend, "field" | "per-ray" | "sphere") {
        let (field, _) = load_or_bake(&dir, &caster.mesh, MODEL, params, &BakeOptions::default())
            .expect("field");
        let (field, reflect) = (
            Arc::new(field),
            matches!(kind, Kind::Reflect | Kind::Reflect4),
        );
        let normals = reflect.then(|| Arc::new(normals(&dir, &caster.mesh, params)));
        let instances = scene.instances[1..]
            .iter()
            .map(|c| {
                let inst = FieldInstance::new(field.clone(), c.transform);
                match &normals {
                    Some(n) => inst.with_normals(n.clone()),
                    None => inst,
                }
            })
            .collect();
        Some(FieldScene {
            instances,
            options: Default::default(),
        })
    } else {
        None
    };
    let tracer = (backend == "raycast").then(|| Tracer::new(&scene.caster_triangles()));
    #[cfg(feature = "embree")]
    let embree = (backend == "embree").then(|| {
        visfield::trace::embree::EmbreeTracer::new(&scene.caster_triangles()).expect("Embree")
    });
    let t = Instant::now();
    let (values, cast) = match (backend, &fs, &tracer) {
        #[cfg(feature = "embree")]
        ("embree", ..) => match &embree {
            Some(e) => ray_pass(e, kind, &points, &normals_at, &rays),
            None => usage(),
        },
        ("none", ..) => ray_pass(&NoQuery, kind, &points, &normals_at, &rays),
        ("raycast", _, Some(tr)) => ray_pass(tr, kind, &points, &normals_at, &rays),
        ("field", Some(fs), _) => ray_pass(fs, kind, &points, &normals_at, &rays),
        ("per-ray", Some(fs), _) => ray_pass(&PerRay(fs), kind, &points, &normals_at, &rays),
        ("sphere", Some(fs), _) => ray_pass(&SphereCull(fs), kind, &points, &normals_at, &rays),
        _ => usage(),
    };
    let secs = t.elapsed().as_secs_f64();
    let mean = values.iter().map(|&v| v as f64).sum::<f64>() / values.len().max(1) as f64;
    println!(
        "{} points, {cast} rays, mean {mean:.6}, {secs:.3} s, {:.2} Mrays/s",
        points.len(),
        cast as f64 / secs / 1e6
    );
}
