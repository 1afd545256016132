//! Reflection rays through the batched field lookup: `FieldScene::surface_hit_many` (one origin,
//! the nearest hit and its normal-field normal per ray, as `render::reflect` casts them) against
//! the per-ray `surface_hit` it replaces, bit for bit (distance and normal), on every
//! instruction set the CPU runs (`FieldScene::surface_hit_many_on`: the eight-lane AVX2 steps
//! and the one-lane twin), for blocks of 0 to 3,000 rays, one instance and four (two overlapping
//! spheres, one apart, and one placed exactly on the first: equal entries and equal hits, where
//! the instances' order decides), both selections.
//!
//! The rays are random and adversarial, as in `tests/shadow_batch.rs`: aimed at the caster's
//! sphere and around its outline, from outside every sphere, far away, inside a sphere
//! (intra-object) and from the caster's surface; far ends at infinity and about the middle of
//! the hits.

mod common;
use common::batch_rays::{directions, origins};
use glam::{Quat, Vec3};
use std::sync::Arc;
use visfield::field::bake::{bake_mesh_with_normals, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::normals::NormalField;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision, Selection, VisibilityField};
use visfield::geometry::procedural::{supershape, Supershape};
use visfield::geometry::{Mesh, Similarity};
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::simd::Isa;
use visfield::visibility::{SurfaceHit, Visibility};

/// Rays per origin; blocks of every length below are prefixes of them.
const RAYS: usize = 3000;
const BLOCKS: [usize; 13] = [0, 1, 7, 8, 9, 15, 16, 17, 63, 64, 65, 1000, RAYS];

fn caster() -> Mesh {
    supershape(&Supershape::default(), 2000).expect("supershape")
}

fn field(layout: LayoutKind, res: u32, precision: Precision) -> Baked {
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 290,
        layout,
        res,
        precision,
    };
    let (f, n, _) =
        bake_mesh_with_normals(&caster(), params, 8, &BakeOptions::default()).expect("bake");
    (Arc::new(f), Arc::new(n))
}

type Baked = (Arc<VisibilityField>, Arc<NormalField>);

/// One instance of `field` rotated and scaled, or four: two overlapping spheres and one apart,
/// and the first again with its normals at 6 bits: every ray meets the two at the same distance
/// with other normals, and the instances' order decides which it reports.
fn scene((field, normals): &Baked, several: bool, selection: Selection) -> FieldScene {
    let other = Arc::new(normals.requantized(6));
    let first = Similarity::new(
        Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.3, 1.1),
        Vec3::new(0.9, 0.2, -0.3),
        0.8,
    );
    let transforms = [
        first,
        Similarity::default(),
        Similarity::new(Quat::from_rotation_z(2.0), Vec3::new(-3.0, 1.0, 2.0), 1.5),
        first,
    ];
    FieldScene {
        instances: transforms
            .iter()
            .take(if several { 4 } else { 1 })
            .enumerate()
            .map(|(j, &t)| {
                let n = if j == 3 { &other } else { normals };
                FieldInstance::new(field.clone(), t).with_normals(n.clone())
            })
            .collect(),
        options: LookupOptions {
            selection,
            ..LookupOptions::default()
        },
    }
}

fn bits(h: Option<SurfaceHit>) -> Option<(u32, [u32; 3])> {
    h.map(|h| (h.t.to_bits(), h.normal.to_array().map(f32::to_bits)))
}

#[derive(Default)]
struct Tally {
    rays: usize,
    hits: usize,
    /// Rays of several instances whose nearest hit is not the first instance's.
    not_first: usize,
}

/// Asserts `surface_hit_many_on` == per-ray `surface_hit` for every instruction set and block.
fn compare(scene: &FieldScene, origins: &[Vec3], tally: &mut Tally) {
    for (k, &origin) in origins.iter().enumerate() {
        let dirs = directions(scene, origin, 10 * k as u64, RAYS);
        // A far end about the middle of this origin's hits, and none.
        let mut ts: Vec<f32> = dirs
            .iter()
            .filter_map(|&d| scene.hit_distance(origin, d, 0.0, f32::INFINITY))
            .collect();
        ts.sort_by(f32::total_cmp);
        let middle = ts.get(ts.len() / 2).copied().unwrap_or(1.0);
        for (tmin, tmax) in [(0.0, f32::INFINITY), (0.01, f32::INFINITY), (0.0, middle)] {
            let want: Vec<Option<SurfaceHit>> = dirs
                .iter()
                .map(|&d| scene.surface_hit(origin, d, tmin, tmax))
                .collect();
            for (&d, w) in dirs.iter().zip(&want) {
                tally.rays += 1;
                tally.hits += w.is_some() as usize;
                if let (Some(w), [first, ..]) = (w, scene.instances.as_slice()) {
                    if scene.instances.len() > 1 {
                        let own = first.surface_hit(origin, d, tmin, tmax, &scene.options);
                        tally.not_first += own.is_none_or(|h| h.t != w.t) as usize;
                    }
                }
            }
            for isa in Isa::all_available() {
                for n in BLOCKS {
                    let mut got = vec![
                        Some(SurfaceHit {
                            t: -1.0,
                            normal: Vec3::X
                        });
                        n
                    ];
                    scene.surface_hit_many_on(isa, origin, &dirs[..n], tmin, tmax, &mut got);
                    if let Some(i) = (0..n).find(|&i| bits(got[i]) != bits(want[i])) {
                        panic!(
                            "{isa:?}, {n} rays, {:?}, {} instances: origin {origin}, dir {}, \
                             [{tmin}, {tmax}]: batched {:?}, per ray {:?}",
                            scene.options.selection,
                            scene.instances.len(),
                            dirs[i],
                            got[i],
                            want[i]
                        );
                    }
                }
            }
            // The trait's entry is the batched one.
            let mut got = vec![None; RAYS];
            scene.surface_hit_many(origin, &dirs, tmin, tmax, &mut got);
            assert!(got.iter().zip(&want).all(|(&g, &w)| bits(g) == bits(w)));
        }
    }
}

#[test]
fn batched_reflection_rays_are_bit_identical_to_per_ray() {
    let mesh = caster();
    let mut tally = Tally::default();
    for (layout, res, precision) in [
        (LayoutKind::Concentric, 32, Precision::U8),
        (LayoutKind::Polar, 16, Precision::U16),
    ] {
        let field = field(layout, res, precision);
        for several in [false, true] {
            for selection in [Selection::Nearest, Selection::Interpolated] {
                let scene = scene(&field, several, selection);
                compare(&scene, &origins(&scene, &mesh), &mut tally);
            }
        }
    }
    // Both answers occur, and with several instances the nearest hit is often another
    // instance's than the first one's.
    let t = &tally;
    assert!(
        t.hits > t.rays / 10 && t.hits < t.rays * 9 / 10,
        "{} hits of {}",
        t.hits,
        t.rays
    );
    assert!(
        t.not_first > 1000,
        "{} rays hit nearer than the first instance",
        t.not_first
    );
}

#[test]
#[should_panic(expected = "needs the instance's normal field")]
fn a_batch_reaching_an_instance_without_normals_panics_as_one_ray_does() {
    let (field, _) = field(LayoutKind::Concentric, 8, Precision::U8);
    let scene = FieldScene {
        instances: vec![FieldInstance::new(field, Similarity::default())],
        options: LookupOptions::default(),
    };
    let c = scene.instances[0].world_center;
    let origin = c + Vec3::new(0.0, 0.0, 5.0);
    let mut out = vec![None; 1];
    scene.surface_hit_many(origin, &[Vec3::NEG_Z], 0.0, f32::INFINITY, &mut out);
}
