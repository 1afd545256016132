//! `experiment dynamic --quick`: every method on every frame of every crowd, with exact row
//! counts, the reference's own error exactly 0, the field's error two-sided, and the overlap
//! counts the choreography guarantees (orbits that keep neighbours' spheres apart, spheres
//! clear of the plane). The run is staged and published as a spec's is: into a folder of the
//! user's (allowed), it keeps their files and empty folders.

use visfield::experiment::dynamic::{self, crowd::Profile, FrameRow};
use visfield::experiment::fields::FieldSupply;

#[test]
fn the_quick_crowd_gives_every_method_every_frame_with_bounded_errors() {
    let out = tempfile::tempdir().unwrap();
    let supply = FieldSupply {
        cache: None,
        cache_limit: 0,
        memory_limit: 1 << 30,
    };
    // A folder of the user's: their sweep_frames.csv (once replaced), notes and an empty folder.
    let dyn_out = out.path().join("dyn");
    std::fs::create_dir_all(dyn_out.join("drafts")).unwrap();
    std::fs::write(dyn_out.join("sweep_frames.csv"), "my table").unwrap();
    std::fs::write(dyn_out.join("notes.txt"), "my notes").unwrap();
    let refused = dynamic::run(&dyn_out, true, &supply, false).unwrap_err();
    assert!(refused.to_string().contains("no run.json"), "{refused}");
    let rows: Vec<FrameRow> = dynamic::run(&dyn_out, true, &supply, true).unwrap();
    for f in ["sweep_frames.csv", "run.json", "frame_time.png"] {
        assert!(dyn_out.join(f).is_file(), "{f}");
    }
    let read = |f: &str| std::fs::read_to_string(dyn_out.join(f)).unwrap();
    assert_eq!(read("sweep_frames.csv.kept"), "my table");
    assert_eq!(read("notes.txt"), "my notes");
    assert!(dyn_out.join("drafts").is_dir());
    assert!(read("sweep_frames.csv").starts_with("sweep,"));
    let p = Profile::new(true);
    // World rebuild, two levels, the field with and without its sphere BVH, the mesh distance
    // fields and the AO fields; Embree rebuilt and instanced.
    let methods = if cfg!(feature = "embree") { 8 } else { 6 };
    assert_eq!(
        rows.len(),
        (p.counts.len() * p.frames + p.gaps.len()) * methods
    );
    let (crowd, approach): (Vec<&FrameRow>, Vec<&FrameRow>) =
        rows.iter().partition(|r| r.scene == "crowd");
    // The approach: no receiver point inside the sphere while it clears the plane, some once
    // it cuts it, more the deeper it goes; the plane's vertices are the same every frame.
    let mut last = 0;
    for r in approach.iter().filter(|r| r.method == "world_rebuild") {
        let g = r.gap_radii.unwrap();
        assert!(r.mesh_clearance.unwrap() >= g - 1e-6, "{r:?}");
        if g >= 0.0 {
            assert_eq!(r.points_in_spheres, 0, "{r:?}");
        } else {
            assert!(r.points_in_spheres > last, "{r:?}");
        }
        last = r.points_in_spheres;
    }
    for r in &approach {
        match r.method.as_str() {
            "world_rebuild" | "two_level" => assert_eq!(r.rms_vs_raycast, 0.0, "{r:?}"),
            // Where the mesh goes through the plane, origins sit inside it or on its surface:
            // the two casters may differ on a few contact rays, never by much.
            "embree_rebuild" | "embree_instances" => assert!(r.rms_vs_raycast < 0.5, "{r:?}"),
            _ => assert!(r.rms_vs_raycast > 0.5, "{r:?}"),
        }
    }
    for r in crowd {
        assert!(r.update_s >= 0.0 && r.query_s > 0.0, "{r:?}");
        assert_eq!(r.frame_s, r.update_s + r.query_s);
        assert_eq!(r.sphere_overlaps, 0, "{r:?}");
        assert_eq!(r.points_in_spheres, 0, "{r:?}");
        // Against the frame's converged reference: 16 rays per point leave a noise of the
        // order of 255·sqrt(p(1 − p)/16) at partly occluded points, far above the truth's own;
        // the AO field casts no ray, so its error has no such floor, but is not 0.
        assert!(r.truth_stderr > 0.0 && r.truth_stderr < 2.0, "{r:?}");
        let floor = if r.method == "aofield" { 0.1 } else { 2.0 };
        assert!(r.rms_vs_truth > floor && r.rms_vs_truth < 60.0, "{r:?}");
        match r.method.as_str() {
            "world_rebuild" | "two_level" => assert_eq!(r.rms_vs_raycast, 0.0, "{r:?}"),
            // Embree against our tracer: the same scene, no contact origins (the spheres float
            // clear of the plane), so the same answer on every ray.
            "embree_rebuild" | "embree_instances" => assert_eq!(r.rms_vs_raycast, 0.0, "{r:?}"),
            // 290 × 16² u8 maps: a real error, neither 0 nor the whole occlusion.
            "field" | "field_every_sphere" => {
                assert!(r.rms_vs_raycast > 1.0 && r.rms_vs_raycast < 30.0, "{r:?}")
            }
            // Sphere tracing 32-sample volumes on the same rays: near ray casting, not equal.
            "sdf" => assert!(r.rms_vs_raycast > 0.1 && r.rms_vs_raycast < 30.0, "{r:?}"),
            // The caps of 8² AO fields, no rays: a real error, neither 0 nor the whole
            // occlusion; nothing is rebuilt, so its update is the instance list.
            "aofield" => {
                assert!(r.rms_vs_raycast > 1.0 && r.rms_vs_raycast < 60.0, "{r:?}");
                assert!(r.bytes.unwrap() > 0, "{r:?}");
            }
            other => panic!("unexpected method {other}"),
        }
    }
    // The sphere BVH changes which spheres a ray is tested against, never an answer.
    let field = |m: &str| -> Vec<(Option<usize>, usize, u64, u64)> {
        rows.iter()
            .filter(|r| r.method == m)
            .map(|r| {
                (
                    r.casters,
                    r.frame,
                    r.mean_value.to_bits(),
                    r.rms_vs_raycast.to_bits(),
                )
            })
            .collect()
    };
    assert_eq!(field("field"), field("field_every_sphere"));
    // The frames move the casters: the answers differ between frames.
    let ao: Vec<f64> = rows
        .iter()
        .filter(|r| r.method == "world_rebuild" && r.casters == Some(16))
        .map(|r| r.mean_value)
        .collect();
    assert!(ao.windows(2).any(|w| w[0] != w[1]), "{ao:?}");
    // More casters occlude more of the plane.
    let mean = |n: usize| {
        rows.iter()
            .find(|r| r.method == "world_rebuild" && r.casters == Some(n))
            .unwrap()
            .mean_value
    };
    assert!(mean(16) < mean(1), "{} vs {}", mean(16), mean(1));
}
