//! Motion in specs: bad motion refused naming the field before any work; one still frame equal
//! to the static run of the same cell; a scene translated as a whole (camera and motion with it)
//! giving every frame's values bit for bit; the overlap counts of a constructed approach exact.

use std::path::Path;
use visfield::experiment::run::frames::FrameRow;
use visfield::experiment::run::run;
use visfield::experiment::scenes::Scenes;
use visfield::experiment::spec::Spec;
use visfield::experiment::table::Row;

mod common;
use common::{animated, frames_of, loaded, options, tiny, ONE_FIELD, ORBIT, TWO_FRAMES};

fn error_of(text: &str) -> String {
    let e = Spec::parse(text, Path::new("specs/bad.json"))
        .err()
        .unwrap_or_else(|| panic!("accepted: {text}"))
        .to_string();
    assert!(e.starts_with("specs/bad.json: "), "{e}");
    e
}

/// Every bad value of a motion or an animation is refused when the spec is read, naming the
/// field and the value.
#[test]
fn bad_motion_is_refused_naming_the_field_and_the_value() {
    let at = "scenes[0].instances[1].motion";
    let keys = |k: &str| format!(r#"{{ "keyframes": {k} }}"#);
    let cases: Vec<(String, String, String, String)> = vec![
        // (caster motion, corner motion, animation, expected in the error)
        (ORBIT.into(), "".into(), r#"{ "frames": 0, "time_step": 0.5 }"#.into(), "`animation.frames`: 0 frames: needs 1 to 10000".into()),
        (ORBIT.into(), "".into(), r#"{ "frames": 1000000000, "time_step": 0.5 }"#.into(), "`animation.frames`: 1000000000 frames".into()),
        (ORBIT.into(), "".into(), r#"{ "frames": 3, "time_step": 0 }"#.into(), "`animation.time_step`: 0 must be positive".into()),
        (ORBIT.into(), "".into(), r#"{ "frames": 3, "time_step": -1.5 }"#.into(), "`animation.time_step`: -1.5".into()),
        (ORBIT.into(), "".into(), r#"{ "frames": 3, "time_step": 1e400 }"#.into(), "animation.time_step`: number out of range".into()),
        (ORBIT.into(), "".into(), r#"{ "frames": 3, "time_step": 0.1, "methods": ["field", "bvh"] }"#.into(), "`animation.methods[1]`: unknown per-frame method \"bvh\"".into()),
        (ORBIT.into(), "".into(), r#"{ "frames": 3, "time_step": 0.1, "methods": ["field", "field"] }"#.into(), "`animation.methods[1]`: \"field\" twice".into()),
        (ORBIT.into(), "".into(), "".into(), format!("`{at}`: moves only in a spec with `animation`")),
        ("{}".into(), "".into(), TWO_FRAMES.into(), format!("`{at}`: names no path")),
        (keys(r#"[{ "time": 1 }, { "time": 0.5 }]"#), "".into(), TWO_FRAMES.into(), format!("`{at}.keyframes[1].time`: 0.5 is not after keyframes[0].time 1")),
        (keys(r#"[{ "time": 1 }, { "time": 1 }]"#), "".into(), TWO_FRAMES.into(), format!("`{at}.keyframes[1].time`: 1 is not after")),
        (keys(r#"[{ "time": 0, "translate": [2e18, 0, 0] }]"#), "".into(), TWO_FRAMES.into(), format!("`{at}.keyframes[0].translate`: [2e18, 0.0, 0.0] must be finite, within ±1.152921504606847e18")),
        (keys(r#"[{ "time": 1e999 }]"#), "".into(), TWO_FRAMES.into(), format!("{at}.keyframes[0].time`: number out of range")),
        (r#"{ "keyframes": [{ "time": 0 }], "pivot": [0, 1e300, 0] }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.pivot`: [0.0, 1e300, 0.0] must be finite, within ±1.152921504606847e18")),
        (r#"{ "pivot": [0, 0, 0], "walk": { "speed": 1 } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.pivot`: turns the keyframes' rotations")),
        (r#"{ "orbit": { "axis": [0, 0, 0], "radius": 0.1, "period": 1 } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.orbit.axis`: [0.0, 0.0, 0.0] must be finite and of non-zero length")),
        (r#"{ "orbit": { "axis": [0, 1, 0], "radius": 0.1, "period": 0 } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.orbit.period`: 0 must be finite and not 0")),
        // A period so short that the turns t / period overflow (once NaN scene bounds).
        (r#"{ "orbit": { "axis": [0, 1, 0], "radius": 0.1, "period": 5e-324 } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.orbit.period`: 5e-324 s makes inf turns over the animation's 0.5 s: the turns must be finite")),
        (r#"{ "orbit": { "axis": [0, 1, 0], "radius": 0.1, "period": -5e-324 } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.orbit.period`: -5e-324 s makes -inf turns")),
        (r#"{ "orbit": { "axis": [0, 1, 0], "radius": -0.1, "period": 1 } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.orbit.radius`: -0.1 must be at least 0")),
        (r#"{ "orbit": { "axis": [0, 1, 0], "period": 1 } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.orbit`: an orbit about the instance's own centre needs a `radius`")),
        (r#"{ "tumble": { "rate_deg": 10, "axis": [0, 0, 0] } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.tumble.axis`: [0.0, 0.0, 0.0] must be finite and of non-zero length")),
        (r#"{ "tumble": { "rate_deg": 1e308 } }"#.into(), "".into(), r#"{ "frames": 3, "time_step": 1e10 }"#.into(), format!("`{at}.tumble.rate_deg`: 100000000000000000000000000000000")),
        (r#"{ "walk": { "speed": -1 } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.walk.speed`: -1 must be at least 0")),
        (r#"{ "walk": { "speed": 1, "plane_normal": [0, 0, 0] } }"#.into(), "".into(), TWO_FRAMES.into(), format!("`{at}.walk.plane_normal`: [0.0, 0.0, 0.0]")),
        (r#"{ "walk": { "speed": 1e300 } }"#.into(), "".into(), r#"{ "frames": 2, "time_step": 1e10 }"#.into(), format!("`{at}.walk.speed`: 1e300 makes a step of inf over a time step of 1e10 s")),
        (r#"{ "walk": { "speed": 1e17 } }"#.into(), "".into(), r#"{ "frames": 100, "time_step": 1 }"#.into(), format!("`{at}`: moves the instance up to 9.9e18 over 100 frames: past ±1.152921504606847e18")),
        ("".into(), r#"{ "orbit": { "axis": [1, 0, 0], "period": 1, "radius": 1e19 } }"#.into(), TWO_FRAMES.into(), "`scenes[0].instances[0].motion.orbit.radius`: 10000000000000000000 must be at least 0, at most".into()),
        ("".into(), r#"{ "bounce": 1 }"#.into(), TWO_FRAMES.into(), "at `scenes[0].instances[0].motion.bounce`: unknown field `bounce`".into()),
    ];
    for (motion, corner, animation, expected) in &cases {
        let e = error_of(&animated(motion, corner, animation));
        assert!(
            e.contains(expected.as_str()),
            "expected {expected:?} in\n{e}"
        );
    }
    // Frames in the quick profile, and the keys of the static table in an animated spec.
    let spec = animated(ORBIT, "", TWO_FRAMES);
    for (from, to, expected) in [
        (
            r#""quick": {}"#,
            r#""quick": { "frames": 0 }"#,
            "`quick.frames`: 0 frames",
        ),
        (
            r#""reference": {"#,
            r#""methods": [{"method": "raycast"}], "reference": {"#,
            "`methods`: an animated spec measures its per-frame methods",
        ),
        (
            r#""thresholds": []"#,
            r#""thresholds": [{"rms_vertex_max": 1}]"#,
            "`thresholds`: an animated spec has no thresholds",
        ),
        (
            r#""raycast_sweep": [4, 16]"#,
            r#""raycast_sweep": [4, 16], "field_rays_sweep": [16]"#,
            "`reference.field_rays_sweep`: an animated spec has no field sweep",
        ),
    ] {
        assert!(spec.contains(from), "{from}");
        let e = error_of(&spec.replace(from, to));
        assert!(e.contains(expected), "expected {expected:?} in\n{e}");
    }
    let e = error_of(&tiny(ONE_FIELD, "").replace(r#""quick": {}"#, r#""quick": { "frames": 2 }"#));
    assert!(
        e.contains("`quick.frames`: 2 frames: the spec has no `animation`"),
        "{e}"
    );
}

/// A path whose values are each in range can still carry an instance out of range, or make it
/// too small beside the frame's extent: refused when the scenes are built, before any BVH or
/// field, naming the instance's motion and the frame.
#[test]
fn a_path_leaving_the_range_is_refused_when_the_scene_is_built() {
    // A half turn about a pivot 1e18 away carries the caster 2e18 off.
    let far = r#"{ "keyframes": [{ "time": 0 }, { "time": 1, "rotate_deg": [0, 180, 0] }], "pivot": [1e18, 0, 0] }"#;
    // A walk that spreads the frame 1e13 wide: the corner is below 2⁻²¹ of it.
    let wide = r#"{ "walk": { "speed": 1e13 } }"#;
    // The caster (instances[1]) moves; the still corner (instances[0]) is what falls below
    // the frame's resolution, and the error names the caster's motion that spread it.
    for (motion, expected) in [
        (
            far,
            "`scenes[0].instances[1].motion`: at frame 1 puts its bounding sphere",
        ),
        (
            wide,
            "`scenes[0].instances[1].motion`: at frame 1 moves it 1e13 from its placement, \
             spreading the frame to a half-extent of",
        ),
    ] {
        let text = animated(motion, "", r#"{ "frames": 2, "time_step": 1 }"#);
        let spec = Spec::parse(&text, Path::new("specs/bad.json")).expect("valid values");
        let e = Scenes::build(&spec, Path::new("specs/bad.json"), "scenes")
            .err()
            .unwrap_or_else(|| panic!("{motion} was accepted"))
            .to_string();
        assert!(e.contains(expected), "expected {expected:?} in\n{e}");
        if motion == wide {
            assert!(e.contains("instances[0], of radius"), "{e}");
        }
    }
}

/// An animation of one frame with no motion is the static scene: the field methods' values
/// against the same-ray ray cast and against the converged reference equal the static cell's
/// bit for bit (one seed), and the world rebuild's error against the truth equals the static
/// ray cast's.
#[test]
fn one_still_frame_equals_the_static_run_of_the_same_cell() {
    let dir = tempfile::tempdir().unwrap();
    let one_seed = |t: String| {
        t.replace(
            r#""rays_per_point": 16, "raycast_sweep""#,
            r#""rays_per_point": 16, "seeds": 1, "raycast_sweep""#,
        )
    };
    let still = one_seed(animated("", "", r#"{ "frames": 1, "time_step": 1 }"#));
    let stat = one_seed(animated("", "", ""));
    assert!(still.contains(r#""seeds": 1"#));
    let frames = frames_of(dir.path(), &still, "still");
    let ls = loaded(dir.path(), &stat);
    let table = run(&ls, &options(dir.path().join("static"))).unwrap().rows;
    let cell: &Row = &table[0];
    let methods = if cfg!(feature = "embree") { 6 } else { 4 };
    assert_eq!(frames.len(), methods);
    for r in &frames {
        assert_eq!((r.frame, r.points), (0, cell.receiver_points), "{r:?}");
        assert_eq!(r.crease_points, Some(cell.crease_points));
        match r.method.as_str() {
            "field" | "field_every_sphere" => {
                assert_eq!(r.cell, cell.cell);
                assert_eq!(Some(r.rms_vs_raycast), cell.rms_vertex, "{r:?}");
                assert_eq!(Some(r.rms_vs_truth), cell.rms_vs_truth, "{r:?}");
                assert!(r.rms_vs_raycast > 0.0);
            }
            _ => {
                assert_eq!(r.rms_vs_raycast, 0.0, "{r:?}");
                assert_eq!(Some(r.rms_vs_truth), cell.raycast_rms_vs_truth, "{r:?}");
            }
        }
        assert_eq!(Some(r.truth_stderr), cell.truth_stderr);
        assert_eq!((r.sphere_overlaps, r.points_in_spheres), (0, 0));
    }
}

/// Every frame of a moving scene (the caster orbiting and tumbling, the corner walking) equals
/// the frame of the same scene translated as a whole by a multiple of the rebasing step (its
/// placements, its motions' points and its camera with it), bit for bit: per vertex and per
/// pixel (the G-buffer recomputed each frame from the translated camera).
#[test]
fn a_scene_translated_as_a_whole_gives_the_same_frames() {
    let dir = tempfile::tempdir().unwrap();
    let caster = r#"{ "orbit": { "center": [0.5, 0, 0.5], "axis": [0, 1, 0], "period": 3, "turn": true }, "tumble": { "rate_deg": 40, "seed": 5 }, "keyframes": [{ "time": 0 }, { "time": 2, "rotate_deg": [0, 30, 0], "translate": [0, 0.05, 0] }], "pivot": [0.5, 0.5, 0.5] }"#;
    let corner = r#"{ "walk": { "speed": 0.02, "seed": 3, "plane_normal": [0, 1, 0] } }"#;
    let frames = r#"{ "frames": 3, "time_step": 0.5 }"#;
    let camera = r#""image": { "width": 32, "height": 32, "camera": { "eye": [2.5, 1.75, 3], "target": [0.5, 0.25, 0.5], "fov_y_deg": 40 } }"#;
    let near = animated(caster, corner, frames)
        .replace(r#""image": { "width": 32, "height": 32 }"#, camera);
    assert!(near.contains("eye"));
    // (256, −512, 128): a multiple of the step (a power of two above four times the scene's
    // half-extent, 8 or 16 here), exact in f32 beside the camera's coordinates.
    let shift = |v: [f64; 3]| [v[0] + 256.0, v[1] - 512.0, v[2] + 128.0];
    let at = |v: [f64; 3]| format!("[{}, {}, {}]", v[0], v[1], v[2]);
    let mut far = near.clone();
    for (from, v) in [
        ("[0.5, 0, 0.5]", [0.5, 0.0, 0.5]),
        ("[0.5, 0.5, 0.5]", [0.5, 0.5, 0.5]),
        ("[2.5, 1.75, 3]", [2.5, 1.75, 3.0]),
        ("[0.5, 0.25, 0.5]", [0.5, 0.25, 0.5]),
    ] {
        assert!(far.contains(from), "{from}");
        far = far.replace(from, &at(shift(v)));
    }
    // The placements: a translation (f64) outside each, the caster's fit kept.
    let d = at(shift([0.0; 3]));
    far = far
        .replace(
            r#""receiver": true, "motion""#,
            &format!(r#""receiver": true, "transform": {{ "translate": {d} }}, "motion""#),
        )
        .replace(
            r#""radius": 0.35 } }"#,
            &format!(r#""radius": 0.35 }}, "translate": {d} }}"#),
        );
    assert_eq!(far.matches("[256, -512, 128]").count(), 2);
    for what in ["vertex_ao", "image_ao"] {
        let kind = |t: &str| {
            t.replace(
                r#""render": { "#,
                &format!(r#""render": {{ "what": "{what}", "#),
            )
        };
        let a = frames_of(dir.path(), &kind(&near), &format!("near-{what}"));
        let b = frames_of(dir.path(), &kind(&far), &format!("far-{what}"));
        assert_eq!(a.len(), b.len());
        let moved = a
            .iter()
            .filter(|r| r.method == "world_rebuild")
            .map(|r| r.mean_value);
        let moved: Vec<f64> = moved.collect();
        assert!(
            moved.windows(2).all(|w| w[0] != w[1]),
            "the frames differ: {moved:?}"
        );
        for (x, y) in a.iter().zip(&b) {
            let key = |r: &FrameRow| {
                (
                    (r.frame, r.method.clone(), r.points, r.crease_points),
                    (
                        r.rms_vs_raycast.to_bits(),
                        r.rms_vs_truth.to_bits(),
                        r.mean_value.to_bits(),
                    ),
                    (r.sphere_overlaps, r.points_in_spheres),
                )
            };
            assert_eq!(key(x), key(y), "{what}");
        }
    }
}

/// Two spheres over a plane of vertices 0.1 apart: one fixed, one led by keyframes down and
/// towards it. A sphere of radius 0.3 whose centre stands h over a vertex covers the vertices
/// at (0.1·i, 0.1·j) from it with i² + j² < 9 − 100·h² (2.75, 4.59, 6.75 and 8.75 at h = 0.25,
/// 0.21, 0.15 and 0.05, each a quarter or more from a sum of two squares): none at h = 0.4,
/// 9, 13, 21 and 25; the spheres overlap once their centres are nearer than 0.6 (0.906, 0.743,
/// 0.578, 0.461 and 0.492 apart).
#[test]
fn overlap_counts_on_a_constructed_approach_are_exact() {
    let text = r#"{
  "reproduces": "test",
  "scenes": [{ "name": "approach", "instances": [
    { "mesh": { "plane": { "size": 2, "n": 21 } }, "receiver": true },
    { "mesh": { "sphere": { "radius": 0.3, "stacks": 8, "slices": 12 } }, "caster": true,
      "transform": { "translate": [-0.3, 0.5, 0] } },
    { "mesh": { "sphere": { "radius": 0.3, "stacks": 8, "slices": 12 } }, "caster": true,
      "transform": { "translate": [0.6, 0.4, 0] },
      "motion": { "keyframes": [
        { "time": 0 },
        { "time": 1, "translate": [-0.2, -0.15, 0] },
        { "time": 2, "translate": [-0.4, -0.19, 0] },
        { "time": 3, "translate": [-0.6, -0.25, 0] },
        { "time": 4, "translate": [-0.7, -0.35, 0] } ] } }
  ] }],
  "animation": { "frames": 5, "time_step": 1, "methods": ["field"] },
  "fields": [{ "counts": [290], "resolutions": [16] }],
  "render": { "rays_per_point": 4 },
  "reference": { "rays_per_point": 4, "truth": { "max_rays": 256, "batches": 2 } },
  "quick": {}
}"#;
    let dir = tempfile::tempdir().unwrap();
    let rows = frames_of(dir.path(), text, "approach");
    let world: Vec<&FrameRow> = rows
        .iter()
        .filter(|r| r.method == "world_rebuild")
        .collect();
    let counts: Vec<(usize, usize)> = world
        .iter()
        .map(|r| (r.sphere_overlaps, r.points_in_spheres))
        .collect();
    assert_eq!(counts, [(0, 0), (0, 9), (1, 13), (1, 21), (1, 25)]);
    // Only the world rebuild and the field with its sphere BVH ran; each frame's counts are
    // the frame's, whichever method's row.
    assert_eq!(rows.len(), 10);
    for r in &rows {
        assert!(
            ["world_rebuild", "field"].contains(&r.method.as_str()),
            "{r:?}"
        );
        assert_eq!(r.points, 21 * 21);
        assert_eq!((r.sphere_overlaps, r.points_in_spheres), counts[r.frame]);
    }
}

/// Soft shadows and glossy reflections per frame, through their kinds: the ray casters agree
/// on every shadow ray, and on every reflection ray to the f32 rounding of a hit's normal in
/// another frame (a few units of 1e-7 of the radiance: under 255·10⁻⁶ on the 0–255 scale);
/// the fields (with their normal fields for reflections) err by more than 1 and less than 60.
#[test]
fn shadows_and_reflections_are_measured_per_frame() {
    let lights = r#""lights": [{ "center": [2, 3, 2.5], "radius": 0.2, "intensity": 1 }]"#;
    let dir = tempfile::tempdir().unwrap();
    for (what, own, exact) in [
        ("shadows", String::new(), true),
        (
            "reflections",
            r#", "gloss": { "phong": { "exponent": 50 } }, "normal_bits": [8]"#.to_string(),
            false,
        ),
    ] {
        let text = animated(ORBIT, "", r#"{ "frames": 2, "time_step": 1 }"#).replace(
            r#""render": { "#,
            &format!(r#""render": {{ "what": "{what}", {lights}{own}, "#),
        );
        let rows = frames_of(dir.path(), &text, what);
        let methods = if cfg!(feature = "embree") { 6 } else { 4 };
        assert_eq!(rows.len(), 2 * methods, "{what}");
        for r in &rows {
            assert!(r.points > 0 && r.truth_stderr > 0.0, "{r:?}");
            match r.method.as_str() {
                "field" | "field_every_sphere" => {
                    assert!(r.rms_vs_raycast > 1.0 && r.rms_vs_raycast < 60.0, "{r:?}")
                }
                "world_rebuild" => assert_eq!(r.rms_vs_raycast, 0.0),
                _ if exact => assert_eq!(r.rms_vs_raycast, 0.0, "{r:?}"),
                _ => assert!(r.rms_vs_raycast < 255e-6, "{r:?}"),
            }
        }
        assert_ne!(
            rows[0].mean_value, rows[methods].mean_value,
            "{what}: the frames differ"
        );
    }
}

/// A scene moved rigidly as a whole, every instance (receiver and caster) by the same
/// keyframes, by multiples of the rebasing step: each frame, rebased on itself, has the static
/// scene's coordinates bit for bit, so every method's values on every frame equal the static
/// scene's.
#[test]
fn a_scene_moved_as_a_whole_gives_the_static_values_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    let frames = r#"{ "frames": 3, "time_step": 1 }"#;
    let whole = r#"{ "keyframes": [{ "time": 0 }, { "time": 2, "translate": [256, -512, 128] }] }"#;
    let still = frames_of(dir.path(), &animated("", "", frames), "still");
    let moved = frames_of(dir.path(), &animated(whole, whole, frames), "moved");
    assert_eq!(still.len(), moved.len());
    let key = |r: &FrameRow| {
        (
            (r.method.clone(), r.points, r.crease_points),
            (
                r.rms_vs_raycast.to_bits(),
                r.rms_vs_truth.to_bits(),
                r.mean_value.to_bits(),
            ),
            (r.sphere_overlaps, r.points_in_spheres),
        )
    };
    let frame0: Vec<_> = still.iter().filter(|r| r.frame == 0).map(key).collect();
    for f in 0..3 {
        let at = |rows: &[FrameRow]| -> Vec<_> {
            rows.iter().filter(|r| r.frame == f).map(key).collect()
        };
        assert_eq!(at(&still), frame0, "the still scene, frame {f}");
        assert_eq!(at(&moved), frame0, "the moved scene, frame {f}");
    }
}

/// A kind's check of a built scene runs on every frame: a caster orbiting into a light's
/// sphere at frame 2 is refused before any work, naming the light and the frame.
#[test]
fn a_caster_moving_onto_a_light_is_refused_naming_the_frame() {
    // The caster's sphere (centre (0.5, 0.45, 0.5), radius 0.35) turned a half turn about the
    // vertical through (0, 0, 0.5) by frame 2: centre (−0.5, 0.45, 0.5), onto the light.
    let motion = r#"{ "orbit": { "center": [0, 0, 0.5], "axis": [0, 1, 0], "period": 4 } }"#;
    let lights = r#""lights": [{ "center": [-0.5, 0.45, 0.5], "radius": 0.05, "intensity": 1 }]"#;
    let text = animated(motion, "", r#"{ "frames": 3, "time_step": 1 }"#).replace(
        r#""render": { "#,
        &format!(r#""render": {{ "what": "shadows", {lights}, "#),
    );
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &text);
    let out = dir.path().join("out");
    let e = run(&ls, &options(out.clone())).unwrap_err().to_string();
    assert!(
        e.contains("render.lights[0]") && e.contains("at frame 2: overlaps the bounding sphere"),
        "{e}"
    );
    assert!(!out.exists(), "nothing written");
}

/// A run's poses cost O(frames): 32 random walkers over 10,000 frames are placed in well under
/// a second (a walk summed from frame 1 at every frame took about 16·10⁸ steps, tens of
/// seconds, before the scene was even built).
#[test]
fn walkers_over_the_most_frames_are_placed_in_linear_time() {
    let walker = |i: usize| {
        format!(
            r#"{{ "mesh": {{ "sphere": {{ "radius": 0.05, "stacks": 4, "slices": 6 }} }}, "caster": true,
      "transform": {{ "translate": [{}, 0.5, 0] }},
      "motion": {{ "walk": {{ "speed": 0.001, "seed": {i}, "plane_normal": [0, 1, 0] }} }} }}"#,
            0.1 * i as f64 - 1.6
        )
    };
    let walkers: Vec<String> = (0..32).map(walker).collect();
    let text = format!(
        r#"{{
  "reproduces": "test",
  "scenes": [{{ "name": "walkers", "instances": [
    {{ "mesh": {{ "plane": {{ "size": 4, "n": 3 }} }}, "receiver": true }},
    {} ] }}],
  "animation": {{ "frames": 10000, "time_step": 0.01, "methods": ["field"] }},
  "fields": [{{ "counts": [290], "resolutions": [16] }}],
  "render": {{ "rays_per_point": 4 }},
  "reference": {{ "rays_per_point": 4, "truth": {{ "max_rays": 256, "batches": 2 }} }},
  "quick": {{}}
}}"#,
        walkers.join(",\n    ")
    );
    let spec = Spec::parse(&text, Path::new("specs/walkers.json")).expect("valid");
    let t = std::time::Instant::now();
    let scenes = Scenes::build(&spec, Path::new("specs/walkers.json"), "scenes").unwrap();
    let s = t.elapsed().as_secs_f64();
    assert_eq!(scenes.scenes[0].frame_count(), 10_000);
    assert!(s < 5.0, "{s} s to place 32 walkers over 10,000 frames");
}
