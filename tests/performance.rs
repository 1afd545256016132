//! `experiment performance --dry-run`: the plan names every caster and field. The quick run
//! itself reads real models: it is in `tests/real_models.rs`.

use visfield::experiment::performance::plan;

#[test]
fn the_dry_run_names_every_caster_and_field_without_running() {
    let full = plan(false);
    for m in [
        "bunny_npm",
        "dragon",
        "supershape",
        "igea",
        "4226x64² f32",
        "0.25",
    ] {
        assert!(full.contains(m), "{m} missing from {full}");
    }
    assert!(
        plan(true).contains("every 16th corner vertex"),
        "{}",
        plan(true)
    );
}
