//! `experiment stability`: every stiff and extreme case passes (one test per case), and the
//! command writes its table.

use visfield::experiment::stability::{self, Row, CASES};

fn run_case(name: &str) {
    let (_, case) = CASES
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("no case {name}"));
    let rows: Vec<Row> = case();
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

        /// Every case in `CASES` has a test above.
        #[test]
        fn every_case_has_a_test() {
            let tested = [$(stringify!($name)),*];
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
    scale_and_position,
    receiver_touching_caster,
    thin_sheet,
    caster_1000x_larger_and_smaller,
    concave_caster,
    overlapping_spheres,
    receiver_inside_caster_sphere,
    thread_determinism,
);

/// A failing row is a failure: NaN errors and errors above the tolerance do not pass.
#[test]
fn rows_fail_above_tolerance_and_on_nan() {
    assert!(Row::new("c", "q", 1.0, 1.0).pass);
    assert!(!Row::new("c", "q", 1.0 + 1e-12, 1.0).pass);
    assert!(!Row::new("c", "q", f64::NAN, 1.0).pass);
    assert!(stability::max_of_for_tests(&[0.5, f64::NAN]).is_nan());
}
