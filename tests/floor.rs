//! The cost-floor backends of `visfield::experiment::performance::floor` (shared with `benches/field.rs` and
//! `examples/ao_cost.rs`): the sphere cull answers exactly whether a segment meets a caster's
//! bounding sphere, and the free query answers nothing.

use glam::Vec3;
use std::sync::Arc;
use visfield::experiment::performance::floor::{NoQuery, SphereCull};
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision, Storage, VisibilityField};
use visfield::geometry::{Similarity, Sphere};
use visfield::sampling::{LayoutKind, SphereKind};
use visfield::visibility::Visibility;

/// A field of one sphere of radius 1 at (0, 0, 5) (its texels do not matter here).
fn scene() -> FieldScene {
    let bounds = Sphere {
        center: Vec3::new(0.0, 0.0, 5.0),
        radius: 1.0,
    };
    // 290 Slater maps of 8² concentric texels, every one a miss.
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 290,
        layout: LayoutKind::Concentric,
        res: 8,
        precision: Precision::F32,
    };
    let storage = Storage::F32 {
        texels: 64,
        data: vec![1.0; 290 * 64],
    };
    let field = VisibilityField::from_storage(params, bounds, storage).unwrap();
    FieldScene {
        instances: vec![FieldInstance::new(Arc::new(field), Similarity::default())],
        options: Default::default(),
    }
}

#[test]
fn sphere_cull_answers_whether_the_segment_meets_the_sphere() {
    let fs = scene();
    let cull = SphereCull(&fs);
    let o = Vec3::ZERO;
    let toward = Vec3::Z;
    let past = Vec3::new(0.3, 0.0, 1.0).normalize(); // 5·0.3/1.04 ≈ 1.44 > 1 from the centre
    let grazing_in = Vec3::new(0.19, 0.0, 1.0).normalize(); // ≈ 0.93 from the centre
    assert_eq!(cull.hit_distance(o, toward, 0.0, 10.0), Some(4.0));
    assert!(!cull.occluded(o, past, 0.0, 10.0));
    assert!(cull.occluded(o, grazing_in, 0.0, 10.0));
    assert!(
        !cull.occluded(o, toward, 0.0, 3.9),
        "segment ends before the sphere"
    );
    assert!(
        !cull.occluded(o, -toward, 0.0, 10.0),
        "sphere behind the ray"
    );
    assert_eq!(
        cull.hit_distance(Vec3::new(0.0, 0.0, 5.0), Vec3::X, 0.0, 1.0),
        Some(0.0)
    );
    let dirs = [toward, past, grazing_in, -toward];
    let mut out = [true; 4];
    cull.occluded_many(o, &dirs, 0.0, 10.0, &mut out);
    assert_eq!(out, [true, false, true, false]);
    // Each ray its own far end: before, at and past the entry at 4 of the ray toward the centre.
    for (far, want) in [(3.9, false), (4.0, true), (4.1, true)] {
        cull.occluded_many_to(o, &dirs, 0.0, &[far, 10.0, 10.0, 10.0], &mut out);
        assert_eq!(out, [want, false, true, false], "far end {far}");
    }
    NoQuery.occluded_many(o, &dirs, 0.0, 10.0, &mut out);
    assert_eq!(out, [false; 4]);
}
