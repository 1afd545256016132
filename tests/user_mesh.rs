//! A user's own mesh in a spec (`{"mesh": {"file": PATH, "sha256": …}}`): OBJ and PLY files
//! named by a path relative to the spec's folder, recorded in `run.json`, keyed in the field
//! cache by their content, and the same numbers as the registry's copy of the same model.

use std::path::{Path, PathBuf};
use visfield::experiment::run::{run, LoadedSpec};
use visfield::experiment::user_mesh::sha256_file;
use visfield::geometry::{procedural, Mesh};

mod common;
use common::options;

/// A 2,000-triangle supershape as OBJ text (positions printed exactly: Rust's shortest
/// round-trip form).
fn obj_text(m: &Mesh) -> String {
    let mut s = String::from("# test mesh\n");
    for p in &m.positions {
        s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    for t in &m.triangles {
        s.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    s
}

/// `m` as a binary PLY (float positions, uchar-counted int indices), little- or big-endian.
fn ply_bytes(m: &Mesh, big: bool) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_{}_endian 1.0\ncomment test\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        if big { "big" } else { "little" },
        m.vertex_count(),
        m.triangle_count()
    )
    .into_bytes();
    let f = |x: f32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let i = |x: u32| {
        if big {
            (x as i32).to_be_bytes()
        } else {
            (x as i32).to_le_bytes()
        }
    };
    for p in &m.positions {
        for c in p.to_array() {
            b.extend_from_slice(&f(c));
        }
    }
    for t in &m.triangles {
        b.push(3);
        for &v in t {
            b.extend_from_slice(&i(v));
        }
    }
    b
}

/// The supershape as the OBJ loader reads it back (welded), so that every format below holds
/// exactly this mesh.
fn test_mesh(dir: &Path) -> Mesh {
    let m = procedural::supershape(&Default::default(), 2000).unwrap();
    let p = dir.join("welded.obj");
    std::fs::write(&p, obj_text(&m)).unwrap();
    Mesh::load_obj(&p).unwrap()
}

/// A small vertex-AO spec: a 9 × 9 corner receiving from `caster` (JSON of a mesh) fitted
/// over it, one field of 290 × 16².
fn spec_with(caster: &str) -> String {
    format!(
        r#"{{
  "reproduces": "test",
  "scenes": [{{
    "name": "user",
    "instances": [
      {{ "mesh": {{ "corner": {{ "n": 9 }} }}, "receiver": true }},
      {{ "mesh": {caster}, "caster": true,
         "transform": {{ "fit": {{ "center": [0.5, 0.45, 0.5], "radius": 0.35 }} }} }}
    ]
  }}],
  "fields": [{{ "counts": [290], "resolutions": [16] }}],
  "render": {{ "rays_per_point": 16, "image": {{ "width": 32, "height": 32 }} }},
  "reference": {{ "rays_per_point": 16, "raycast_sweep": [16], "field_rays_sweep": [16],
                 "truth": {{ "max_rays": 1024 }} }},
  "quick": {{}}
}}"#
    )
}

/// `text` written to `dir/NAME.json`, loaded, and run into `dir/out-NAME`; returns the output
/// folder.
fn run_spec(dir: &Path, name: &str, text: &str, cache: Option<&Path>) -> PathBuf {
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, text).unwrap();
    let ls = LoadedSpec::load(&path).unwrap();
    let out = dir.join(format!("out-{name}"));
    let mut o = options(out.clone());
    o.supply.cache = cache.map(Path::to_path_buf);
    o.supply.cache_limit = 64 << 20;
    run(&ls, &o).unwrap();
    out
}

fn run_json(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap()
}

/// table.csv without its timing columns (seconds, rates and speed-ups), as header → value.
fn non_time_columns(out: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(out.join("table.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut cols = Vec::new();
    for line in lines {
        for (h, v) in header.iter().zip(line.split(',')) {
            let timing = h.ends_with("_s")
                || h.contains("_s_")
                || h.contains("mrays")
                || h.contains("speedup")
                || h.contains("per_s");
            if !timing {
                cols.push((h.to_string(), v.to_string()));
            }
        }
    }
    assert!(cols.len() > 20, "{cols:?}");
    cols
}

fn obj_and_ply_by_relative_path_are_recorded_in_run_json_with_their_sums_and_counts() {
    let meshes = tempfile::tempdir().unwrap();
    let specs = tempfile::tempdir().unwrap();
    let m = test_mesh(meshes.path());
    std::fs::write(meshes.path().join("shape.obj"), obj_text(&m)).unwrap();
    std::fs::write(meshes.path().join("shape.ply"), ply_bytes(&m, false)).unwrap();
    std::fs::write(meshes.path().join("shape_be.ply"), ply_bytes(&m, true)).unwrap();
    // The spec's folder → the meshes' folder, relatively.
    let rel = format!(
        "../{}",
        meshes.path().file_name().unwrap().to_string_lossy()
    );
    let mut tables = Vec::new();
    for file in ["shape.obj", "shape.ply", "shape_be.ply"] {
        let given = format!("{rel}/{file}");
        let (sum, bytes) = sha256_file(&meshes.path().join(file)).unwrap();
        let caster = format!(r#"{{ "file": "{given}", "sha256": "{sum}" }}"#);
        let out = run_spec(
            specs.path(),
            &file.replace('.', "_"),
            &spec_with(&caster),
            None,
        );
        let j = run_json(&out);
        let rec = &j["meshes"][1]["file"];
        assert_eq!(rec["file"], given.as_str(), "{j}");
        assert_eq!(rec["sha256"], sum.as_str());
        assert_eq!(rec["bytes"], bytes);
        assert_eq!(rec["vertices"], m.vertex_count());
        assert_eq!(rec["triangles"], m.triangle_count());
        // No absolute path of the mesh anywhere in run.json.
        let text = std::fs::read_to_string(out.join("run.json")).unwrap();
        assert!(
            !text.contains(&meshes.path().display().to_string()),
            "run.json names the mesh's absolute path"
        );
        assert!(j["meshes"][0]["file"].is_null(), "the corner is procedural");
        tables.push(non_time_columns(&out));
    }
    // Three encodings of one mesh: the same numbers.
    assert_eq!(tables[0], tables[1]);
    assert_eq!(tables[0], tables[2]);
}

fn a_pin_that_does_not_match_names_both_sums_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let m = test_mesh(dir.path());
    std::fs::write(dir.path().join("shape.obj"), obj_text(&m)).unwrap();
    let (sum, _) = sha256_file(&dir.path().join("shape.obj")).unwrap();
    let pin = "0".repeat(64);
    let path = dir.path().join("pinned.json");
    let caster = format!(r#"{{ "file": "shape.obj", "sha256": "{pin}" }}"#);
    std::fs::write(&path, spec_with(&caster)).unwrap();
    let ls = LoadedSpec::load(&path).unwrap();
    let out = dir.path().join("out");
    let e = run(&ls, &options(out.clone())).unwrap_err().chain();
    assert!(
        e.contains(&sum) && e.contains(&pin) && e.contains("shape.obj"),
        "{e}"
    );
    assert!(!out.exists(), "a refused run leaves no output folder");
    // A malformed pin is refused by validation, naming the field.
    let caster = r#"{ "file": "shape.obj", "sha256": "xyz" }"#;
    std::fs::write(&path, spec_with(caster)).unwrap();
    let e = LoadedSpec::load(&path).unwrap_err().to_string();
    assert!(
        e.contains("instances[1].mesh.sha256") && e.contains("`xyz`"),
        "{e}"
    );
    // So is an extension no loader reads, naming the extensions read.
    let caster = r#"{ "file": "shape.stl" }"#;
    std::fs::write(&path, spec_with(caster)).unwrap();
    let e = LoadedSpec::load(&path).unwrap_err().to_string();
    assert!(e.contains("mesh.file") && e.contains(".obj, .ply"), "{e}");
}

fn the_cache_keys_on_content_a_renamed_file_reuses_its_field_an_edited_one_bakes() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let m = test_mesh(dir.path());
    std::fs::write(dir.path().join("a.obj"), obj_text(&m)).unwrap();
    let bake_cached = |out: &Path| {
        let rows: Vec<visfield::experiment::table::Row> =
            visfield::experiment::outputs::read_csv(&out.join("table.csv")).unwrap();
        rows[0].bake_cached
    };
    let first = run_spec(
        dir.path(),
        "a",
        &spec_with(r#"{"file": "a.obj"}"#),
        Some(&cache),
    );
    assert!(!bake_cached(&first));
    std::fs::rename(dir.path().join("a.obj"), dir.path().join("b.obj")).unwrap();
    let renamed = run_spec(
        dir.path(),
        "b",
        &spec_with(r#"{"file": "b.obj"}"#),
        Some(&cache),
    );
    assert!(bake_cached(&renamed), "a renamed file must reuse its field");
    // One vertex moved: another mesh, another field.
    let mut text = obj_text(&m);
    let p = m.positions[0];
    text = text.replacen(
        &format!("v {} {} {}\n", p.x, p.y, p.z),
        &format!("v {} {} {}\n", p.x * 1.01, p.y, p.z),
        1,
    );
    std::fs::write(dir.path().join("b.obj"), text).unwrap();
    let edited = run_spec(
        dir.path(),
        "c",
        &spec_with(r#"{"file": "b.obj"}"#),
        Some(&cache),
    );
    assert!(!bake_cached(&edited), "an edited file must bake again");
}

/// The registry's `bunny_npm` and the same file named by path: every non-time column equal.
fn a_registry_model_and_its_file_by_path_give_the_same_numbers() {
    let shared = bunny_npm().expect("bunny_npm.obj (the trial is ignored without it)");
    let dir = tempfile::tempdir().unwrap();
    let by_name = run_spec(
        dir.path(),
        "name",
        &spec_with(r#"{"model": "bunny_npm"}"#),
        None,
    );
    let caster = format!(r#"{{"file": "{}"}}"#, shared.display());
    let by_path = run_spec(dir.path(), "path", &spec_with(&caster), None);
    assert_eq!(non_time_columns(&by_name), non_time_columns(&by_path));
    let (a, b) = (run_json(&by_name), run_json(&by_path));
    assert_eq!(a["meshes"][1]["mesh_sha256"], b["meshes"][1]["mesh_sha256"]);
    assert_eq!(
        b["meshes"][1]["file"]["vertices"],
        a["meshes"][1]["vertices"]
    );
}

/// `experiment try` on an OBJ outside the repository: the table, images, plots and the spec,
/// a verdict per CPU row computed from the table, and the spec reruns to the same numbers; a
/// refused mesh is named as given.
fn try_writes_table_images_plots_and_a_spec_that_reruns() {
    use visfield::experiment::try_mesh::{self, TryKind};
    let dir = tempfile::tempdir().unwrap();
    let m = test_mesh(dir.path());
    let mesh = dir.path().join("my mesh.obj");
    std::fs::write(&mesh, obj_text(&m)).unwrap();
    let out = dir.path().join("results").join("try");
    let mut o = options(out.clone());
    o.quick = true;
    let (report, verdicts) = try_mesh::run(&mesh, TryKind::Ao, &o).unwrap();
    for f in [
        "table.csv",
        "run.json",
        "spec.json",
        "pareto.png",
        "images.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let images: Vec<_> = std::fs::read_dir(out.join("images")).unwrap().collect();
    assert!(images.len() >= 3, "{images:?}");
    // One verdict per field size (the quick profile's 290 and 1090 × 32², u8), its numbers the
    // table's.
    assert_eq!(verdicts.len(), 2, "{verdicts:?}");
    assert_eq!(report.rows.len(), 2);
    for (v, r) in verdicts.iter().zip(&report.rows) {
        let head = format!(
            "{} × 32² u8: RMS {:.1} of 255, ",
            r.positional_samples,
            r.rms_image.unwrap()
        );
        assert!(v.starts_with(&head), "{v} vs {head}");
        assert!(
            v.ends_with(&format!("{:.1} MiB", r.field_bytes as f64 / 1048576.0)),
            "{v}"
        );
        let speed = r.raycast_s.unwrap() / r.estimate_s;
        let word = if speed >= 1.0 { "faster" } else { "slower" };
        assert!(v.contains(&format!("× {word} than ray casting")), "{v}");
    }
    // The spec names the mesh relative to its own folder, and reruns with `run`.
    let spec = std::fs::read_to_string(out.join("spec.json")).unwrap();
    assert!(spec.contains(r#""file": "../../my mesh.obj""#), "{spec}");
    let first = non_time_columns(&out);
    let ls = LoadedSpec::load(&out.join("spec.json")).unwrap();
    run(&ls, &o).unwrap();
    assert_eq!(non_time_columns(&out), first);
    // A format no loader reads is refused before any work, and leaves no folder.
    let stl = dir.path().join("m.stl");
    std::fs::write(&stl, "solid").unwrap();
    let o = options(dir.path().join("stl-out"));
    let e = try_mesh::run(&stl, TryKind::Ao, &o).unwrap_err().chain();
    assert!(e.contains("m.stl") && e.contains(".obj, .ply"), "{e}");
    assert!(!dir.path().join("stl-out").exists());
    // A mesh refused while the run loads it is named as given, not through `OUT/spec.json`,
    // a file that exists only once a run has finished (every refusal once named it).
    let nan = dir.path().join("nan.obj");
    std::fs::write(&nan, "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n").unwrap();
    let o = options(dir.path().join("nan-out"));
    let e = try_mesh::run(&nan, TryKind::Ao, &o).unwrap_err().chain();
    assert!(
        e.starts_with(&format!("{}: ", nan.display())) && e.contains("line 3"),
        "{e}"
    );
    assert!(!e.contains("spec.json") && !e.contains("nan-out"), "{e}");
    assert!(!dir.path().join("nan-out").exists());
}

/// `experiment --help` names `try` and the file form of a spec's mesh; `experiment try --help`
/// its kinds.
fn help_mentions_try_and_the_mesh_file_key() {
    let help = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_experiment"))
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{args:?}");
        String::from_utf8(o.stdout).unwrap()
    };
    let top = help(&["--help"]);
    assert!(
        top.contains("  try ") && top.contains(r#"{"mesh": {"file": "PATH"}}"#),
        "{top}"
    );
    let t = help(&["try", "--help"]);
    assert!(
        t.contains("<MESH>")
            && t.contains("ao")
            && t.contains("shadows")
            && t.contains("reflections"),
        "{t}"
    );
}

/// The registry's `bunny_npm.obj` where the registry finds it, absolute.
fn bunny_npm() -> Option<PathBuf> {
    visfield::geometry::models::ModelRegistry::embedded()
        .resolve("bunny_npm")
        .ok()?
        .canonicalize()
        .ok()
}

/// The trials; the registry one is reported ignored, with the reason, where the registry's
/// `bunny_npm.obj` is not found (never as passed).
fn main() {
    let args = libtest_mimic::Arguments::from_args();
    let trial = |name: &'static str, f: fn()| {
        libtest_mimic::Trial::test(name, move || {
            f();
            Ok(())
        })
    };
    let no_model = bunny_npm().is_none();
    if no_model {
        eprintln!("a_registry_model_and_its_file_by_path_give_the_same_numbers ignored: the registry's bunny_npm.obj is not found ($VISFIELD_MODELS, data/models/, ../shared/models/)");
    }
    let trials = vec![
        trial(
            "obj_and_ply_by_relative_path_are_recorded_in_run_json_with_their_sums_and_counts",
            obj_and_ply_by_relative_path_are_recorded_in_run_json_with_their_sums_and_counts,
        ),
        trial(
            "a_pin_that_does_not_match_names_both_sums_before_any_work",
            a_pin_that_does_not_match_names_both_sums_before_any_work,
        ),
        trial(
            "the_cache_keys_on_content_a_renamed_file_reuses_its_field_an_edited_one_bakes",
            the_cache_keys_on_content_a_renamed_file_reuses_its_field_an_edited_one_bakes,
        ),
        trial(
            "help_mentions_try_and_the_mesh_file_key",
            help_mentions_try_and_the_mesh_file_key,
        ),
        trial(
            "try_writes_table_images_plots_and_a_spec_that_reruns",
            try_writes_table_images_plots_and_a_spec_that_reruns,
        ),
        trial(
            "a_registry_model_and_its_file_by_path_give_the_same_numbers",
            a_registry_model_and_its_file_by_path_give_the_same_numbers,
        )
        .with_ignored_flag(no_model),
    ];
    libtest_mimic::run(&args, trials).exit()
}
