//! `experiment stability`: every stiff and extreme case passes (one test per case), and the
//! command writes its table.

use visfield::experiment::stability::{self, StabilityRow, CASES};

fn run_case(name: &str) {
    let (_, case) = CASES
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("no case {name}"));
    let rows: Vec<StabilityRow> = case();
    assert!(!rows.is_empty(), "{name}: no rows");
    let failing: Vec<_> = rows.iter().filter(|r| !r.pass).collect();
    assert!(failing.is_empty(), "{name}: failing rows {failing:#?}");
    for r in &rows {
        assert!(r.max_error.is_finite() && r.max_error >= 0.0, "{r:?}");
    }
}

macro_rules! case_tests {
    ($($name:ident),* $(,)?) => {
        $(#[test] fn $name() { run_case(stringify!($name)); })*

        /// Every case in `CASES` has a test.
        #[test]
        fn every_case_has_a_test() {
            let tested = [$(stringify!($name)),*, "position"];
            for (name, _) in CASES {
                assert!(tested.contains(name), "case {name} has no test");
            }
        }
    };
}

case_tests!(
    ray_sphere_far_and_near,
    ray_sphere_grazing,
    ray_sphere_on_and_inside,
    frames_at_poles_and_axes,
    layout_singular_directions,
    quantisation_edges,
    scale,
    bystanders,
    receiver_touching_caster,
    thin_sheet,
    caster_1000x_larger_and_smaller,
    concave_caster,
    overlapping_spheres,
    receiver_inside_caster_sphere,
    thread_determinism,
    sphere_light_unoccluded,
    sphere_light_behind_sphere_occluder,
    light_grazing_caster_sphere,
    light_below_receiver,
    phong_lobe_by_exponent,
    mirror_grazing,
);

/// Translated by 1e4 and 1e6, and a mesh with its coordinates at 1e4: equal AO within 1/255
/// once the scene is rebased.
#[test]
fn position() {
    run_case("position");
}

/// Without rebasing, the f32 world coordinates at 1e4 (spacing 1e-3 ≈ 1e-3 R) move the
/// ray-cast AO by more than 1/255: the case above fails for the reason rebasing removes.
#[test]
fn unrebased_translation_fails_the_tolerance() {
    use visfield::experiment::stability::scale::{unit_scene, unrebased, AO_TOLERANCE};
    use visfield::experiment::stability::scene_ao::{max_diff, raycast_ao, scene};
    let unit = scene(&unit_scene(), visfield::geometry::Similarity::default());
    let d = max_diff(&raycast_ao(&unrebased(1e4), 16), &raycast_ao(&unit, 16));
    println!("unrebased translation 1e4: max AO difference {d}");
    assert!(d > AO_TOLERANCE, "{d}");
}

/// The position-aware offset fixes self-intersection far from the origin: at translation 1e4
/// the former offset 1e-4 R (below the f32 spacing of the coordinates) lets receivers hit the
/// surface they start on, the new one (`scene_epsilon_for`) does not.
#[test]
fn position_aware_offset_removes_self_intersection() {
    use visfield::experiment::stability::scale::translated_raycast_difference;
    use visfield::render::ao::{scene_epsilon, scene_epsilon_for};
    let sc = visfield::experiment::stability::scale::unrebased(1e4);
    let b = sc.bounding_sphere();
    let old = translated_raycast_difference(scene_epsilon(b.radius));
    let new = translated_raycast_difference(scene_epsilon_for(b));
    println!("translation 1e4: max AO difference {old} with 1e-4 R, {new} position-aware");
    assert!(new < old, "old {old}, new {new}");
    assert!(new <= 4.0 / 256.0, "new {new}");
}

/// A failing row is a failure: NaN errors and errors above the tolerance do not pass.
#[test]
fn rows_fail_above_tolerance_and_on_nan() {
    assert!(StabilityRow::new("c", "q", 1.0, 1.0).pass);
    assert!(!StabilityRow::new("c", "q", 1.0 + 1e-12, 1.0).pass);
    assert!(!StabilityRow::new("c", "q", f64::NAN, 1.0).pass);
    assert!(stability::max_of([0.5, f64::NAN]).is_nan());
}
