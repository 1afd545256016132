//! The `experiment` binary: help for every subcommand, errors naming the spec file, and `check`
//! exit codes on a tiny spec.

use std::path::Path;
use std::process::{Command, Output};

fn experiment(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_experiment"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("VISFIELD_EXPERIMENTS")
        .output()
        .expect("the experiment binary runs")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn help_works_for_every_subcommand() {
    for sub in [
        "quickstart",
        "stability",
        "list",
        "run",
        "check",
        "all",
        "plots",
        "figure6",
    ] {
        let o = experiment(&[sub, "--help"]);
        assert!(o.status.success(), "{sub} --help: {}", text(&o));
        assert!(text(&o).contains("Usage"), "{sub} --help: {}", text(&o));
    }
    let o = experiment(&["figure6", "--help"]);
    assert!(text(&o).contains("--quick") && text(&o).contains("--dry-run"));
}

#[test]
fn list_names_the_specs_and_their_figures() {
    let o = experiment(&["list"]);
    assert!(o.status.success(), "{}", text(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let line = out.lines().find(|l| l.starts_with("figure6 ")).expect(&out);
    assert!(line.contains("Figure 6"), "{line}");
    // The 2010 figures, told apart from the 2008 ones by name and paper.
    for (name, figure) in [
        ("ao2010_figure3 ", "Figure 3"),
        ("ao2010_sponza ", "Figure 6"),
        ("shadows2010_figure7 ", "Figure 7"),
    ] {
        let line = out.lines().find(|l| l.starts_with(name)).expect(&out);
        assert!(
            line.contains("WSCG 2010") && line.contains(figure),
            "{line}"
        );
    }
    // One column for the descriptions, whatever the name's length.
    let column = |l: &str| {
        l.find("  ")
            .map(|i| i + l[i..].len() - l[i..].trim_start().len())
    };
    let specs: Vec<&str> = out.lines().take_while(|l| !l.is_empty()).collect();
    let first = column(specs[0]);
    assert!(specs.iter().all(|l| column(l) == first), "{out}");
    // Then the registries: the kinds a spec's `render.what` may name, and the methods.
    let kinds = out
        .lines()
        .find(|l| l.starts_with("render kinds"))
        .expect(&out);
    for k in ["vertex_ao", "image_ao", "shadows", "reflections"] {
        assert!(kinds.contains(k), "{kinds}");
    }
    for m in ["raycast", "embree"] {
        assert!(
            out.lines()
                .any(|l| l.trim_start().starts_with(&format!("{m} "))),
            "{out}"
        );
    }
}

#[test]
fn a_malformed_or_missing_spec_fails_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken.json");
    std::fs::write(&bad, "{ \"reproduces\": \"x\", \"scenes\": [ }").unwrap();
    let o = experiment(&["run", bad.to_str().unwrap(), "--dry-run"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("broken.json"), "{}", text(&o));

    let missing = dir.path().join("missing.json");
    let o = experiment(&["run", missing.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(text(&o).contains("missing.json"), "{}", text(&o));

    let o = experiment(&["no-such-figure"]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("unknown experiment `no-such-figure`") && text(&o).contains("figure6")
    );
}

fn tiny_spec(dir: &Path, rms_image_max: f64) -> String {
    let text = format!(
        r#"{{
  "reproduces": "test",
  "scenes": [{{ "name": "tiny", "instances": [
    {{ "mesh": {{ "corner": {{ "n": 9 }} }}, "receiver": true }},
    {{ "mesh": {{ "sphere": {{ "radius": 0.3, "stacks": 8, "slices": 12 }} }}, "caster": true,
       "transform": {{ "translate": [0.5, 0.45, 0.5] }} }} ] }}],
  "fields": [{{ "counts": [50], "resolutions": [8] }}],
  "render": {{ "rays_per_point": 16, "image": {{ "width": 24, "height": 24 }} }},
  "reference": {{ "rays_per_point": 16, "raycast_sweep": [4] }},
  "quick": {{ "thresholds": [{{ "rms_image_max": {rms_image_max} }}] }}
}}"#
    );
    let p = dir.join(format!("tiny{}.json", (rms_image_max * 1000.0) as u64));
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

#[test]
fn check_exits_non_zero_naming_the_cell_only_when_a_threshold_is_passed() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    // 50 maps of 8² texels are far from exact (measured: RMS ≈ 4.9 per pixel), so a zero
    // threshold fails; a threshold of 255 (the whole scale) cannot fail.
    let strict = tiny_spec(dir.path(), 0.0);
    let o = experiment(&["check", &strict, "--quick", "--no-cache", "--out", out]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("FAIL") && t.contains("tiny-slater-50-concentric-8-u8-nearest-cpu"),
        "{t}"
    );
    let lax = tiny_spec(dir.path(), 255.0);
    let o = experiment(&["check", &lax, "--quick", "--no-cache", "--out", out]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains(
            "1 threshold(s) (not a shipped spec: no committed run compared), 0 failure(s)"
        ),
        "{}",
        text(&o)
    );
}

/// `check` against a committed run fails on a doubled error and on an error of 0, naming the
/// cell and the committed value; the same run passes.
#[test]
fn check_against_the_committed_run_fails_on_a_doubled_error_and_on_zero() {
    let dir = tempfile::tempdir().unwrap();
    let spec = tiny_spec(dir.path(), 255.0);
    let name = Path::new(&spec)
        .file_stem()
        .unwrap()
        .to_str()
        .unwrap()
        .to_string();
    let committed = dir.path().join("committed");
    let o = experiment(&[
        "run",
        &spec,
        "--quick",
        "--no-cache",
        "--out",
        committed.join(&name).to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let table = committed.join(&name).join("table.csv");
    let original = std::fs::read_to_string(&table).unwrap();
    let check = || {
        let out = dir.path().join("out");
        experiment(&[
            "check",
            &spec,
            "--quick",
            "--no-cache",
            "--against",
            committed.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let o = check();
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("0 failure(s)"), "{}", text(&o));
    // The committed run with its rms_image scaled: ×0.5 (so ours reads as doubled) and ×0 (a
    // committed 0 admits only 0, and ours is not 0; the same rule fails an error that drops to 0).
    let header: Vec<&str> = original.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|c| *c == "rms_image").unwrap();
    for factor in [0.5, 0.0] {
        let doctored: Vec<String> = original
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i == 0 {
                    return l.to_string();
                }
                let mut cells: Vec<String> = l.split(',').map(str::to_string).collect();
                let v: f64 = cells[col].parse().unwrap();
                assert!(v > 0.0, "the tiny spec's field is not exact: {v}");
                cells[col] = (v * factor).to_string();
                cells.join(",")
            })
            .collect();
        std::fs::write(&table, doctored.join("\n") + "\n").unwrap();
        let o = check();
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{factor}: {t}");
        assert!(
            t.contains("FAIL") && t.contains("rms_image") && t.contains("committed"),
            "{factor}: {t}"
        );
    }
    // No committed run at all: a failure, not a pass.
    std::fs::remove_file(&table).unwrap();
    let o = check();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("no committed run"), "{}", text(&o));
}

/// Sizes over `--max-memory-mib` are refused with their size before anything is baked (at a
/// limit of 0 the scene's evaluation state is the first: BVHs, points and values, 183.87 KiB;
/// the field alone, 50 maps × 8² texels × 1 byte = 3.12 KiB, would be next), and an output
/// folder that cannot be written fails before any work: both through the command line.
#[test]
fn resource_errors_come_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let spec = tiny_spec(dir.path(), 255.0);
    let out = dir.path().join("out");
    let o = experiment(&[
        "run",
        &spec,
        "--no-cache",
        "--max-memory-mib",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("183.87 KiB") && t.contains("memory limit") && t.contains("--max-memory-mib"),
        "{t}"
    );
    assert!(!t.contains("bake "), "nothing may be baked: {t}");

    let file = dir.path().join("a-file");
    std::fs::write(&file, b"").unwrap();
    let o = experiment(&[
        "run",
        &spec,
        "--no-cache",
        "--out",
        file.join("out").to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("not writable") && t.contains("a-file"), "{t}");
    assert!(!t.contains("load scenes"), "no work may start: {t}");

    let o = experiment(&["stability", "--out", file.join("out").to_str().unwrap()]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("not writable") && t.contains("a-file"), "{t}");
}

/// A size flag whose bytes overflow 64 bits is refused naming the flag (it once wrapped to
/// "memory limit is 0 B"), before the spec's models are looked for. `all --dry-run`, which
/// reads every model, is in `tests/real_models.rs`.
#[test]
fn size_flags_do_not_wrap() {
    for flag in ["--max-memory-mib", "--cache-limit-mib"] {
        let o = experiment(&["figure6", "--dry-run", flag, "17592186044416"]);
        let t = text(&o);
        assert!(!o.status.success(), "{t}");
        assert!(t.contains(flag) && t.contains("17592186044416"), "{t}");
    }
}

/// An adapter asked for by kind that cannot be had fails `relief` as it fails a spec's "gpu"
/// rows (it once exited 0 with empty GPU columns); only `auto` falls back to the CPU columns.
#[test]
fn relief_fails_when_the_adapter_it_was_asked_for_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("relief");
    // No Vulkan driver at all, whatever this machine has.
    let o = Command::new(env!("CARGO_BIN_EXE_experiment"))
        .args(["relief", "--quick", "--adapter", "hardware", "--out"])
        .arg(&out)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("VK_ICD_FILENAMES", "/nonexistent.json")
        .env("VK_DRIVER_FILES", "/nonexistent.json")
        .output()
        .unwrap();
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("no Vulkan adapter"), "{t}");
}

/// `plots` on a folder whose table is not a run's fails naming the table (it once printed
/// "redrew" and changed nothing).
#[test]
fn plots_refuse_a_table_that_is_not_a_runs() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("table.csv"), "garbage\n").unwrap();
    let o = experiment(&["plots", "--dir", dir.path().to_str().unwrap()]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("table.csv") && !t.contains("redrew"), "{t}");
}

/// Without any Vulkan driver, `check` runs a spec's CPU rows and names the GPU rows it left out
/// (where they once failed the whole spec); `--require-gpu` makes that a failure.
#[test]
fn check_without_vulkan_skips_gpu_rows_loudly_unless_required() {
    let dir = tempfile::tempdir().unwrap();
    let spec = tiny_spec(dir.path(), 255.0);
    let both = std::fs::read_to_string(&spec).unwrap().replace(
        r#""reference": {"#,
        r#""backends": ["cpu", "gpu"], "reference": {"#,
    );
    std::fs::write(&spec, both).unwrap();
    let check = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_experiment"))
            .args(["check", &spec, "--no-cache", "--out"])
            .arg(dir.path().join("out"))
            .args(extra)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env("VK_ICD_FILENAMES", "/nonexistent.json")
            .env("VK_DRIVER_FILES", "/nonexistent.json")
            .env_remove("VISFIELD_ADAPTER")
            .output()
            .unwrap()
    };
    let o = check(&[]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("SKIPPED the \"gpu\" rows") && t.contains("no Vulkan adapter"),
        "{t}"
    );
    assert!(t.contains("1 cell(s)"), "the CPU row ran: {t}");
    let o = check(&["--require-gpu"]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("FAIL") && t.contains("cannot run"), "{t}");
}

/// A plot that `plots` draws and the run had not listed (a run older than the plot kind)
/// becomes one of the run's files in its `run.json`, so that the next run into the folder
/// replaces it rather than keep it as a user's; with nothing new, `run.json` is left as it is.
#[test]
fn plots_list_the_plots_they_draw_as_the_runs_files() {
    let dir = tempfile::tempdir().unwrap();
    let spec = tiny_spec(dir.path(), 255.0);
    let out = dir.path().join("out");
    let o = experiment(&["run", &spec, "--no-cache", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let run_json = out.join("run.json");
    let listed = |bytes: &[u8]| -> Vec<String> {
        let v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
        v["files"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f.as_str().unwrap().to_string())
            .collect()
    };
    let original = std::fs::read(&run_json).unwrap();
    assert!(listed(&original).contains(&"pareto.png".to_string()));
    // An older run's list: without pareto.png.
    let mut v: serde_json::Value = serde_json::from_slice(&original).unwrap();
    let fewer: Vec<String> = listed(&original)
        .into_iter()
        .filter(|f| f != "pareto.png")
        .collect();
    v["files"] = serde_json::json!(fewer);
    std::fs::write(&run_json, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let o = experiment(&["plots", "--dir", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let after = std::fs::read(&run_json).unwrap();
    assert_eq!(listed(&after), listed(&original));
    // Nothing new: the file is not rewritten.
    let o = experiment(&["plots", "--dir", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(std::fs::read(&run_json).unwrap(), after);
}

/// Guards the command-made results against writing into a folder no run wrote: `experiment
/// dynamic --out DIR` once wrote straight into it (replacing the user's `table.csv`), as
/// `performance` did, and `stability`, `sampling` and `relief` likewise; each is now refused
/// before any work, as a spec's run is, the folder untouched; a file given as the output folder
/// is refused and left as it is.
#[test]
fn command_made_results_refuse_a_folder_no_run_wrote() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mine");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("table.csv"), "my table").unwrap();
    let file = dir.path().join("notes.txt");
    std::fs::write(&file, "my notes").unwrap();
    // `stability`, `sampling` and `relief` likewise: staged and published as a spec's run is.
    for sub in [
        vec!["dynamic", "--quick", "--no-cache"],
        vec!["performance", "--quick", "--no-cache"],
        vec!["stability"],
        vec!["sampling"],
        vec!["relief", "--quick", "--no-gpu"],
    ] {
        for (to, why) in [
            (&out, ["no run.json", "--allow-nonempty-out"]),
            (&file, ["notes.txt", "is a file"]),
        ] {
            let mut args = sub.clone();
            args.extend(["--out", to.to_str().unwrap()]);
            let o = experiment(&args);
            let t = text(&o);
            assert!(!o.status.success(), "{sub:?}: {t}");
            assert!(why.iter().all(|w| t.contains(w)), "{sub:?}: {t}");
        }
    }
    assert_eq!(
        std::fs::read_to_string(out.join("table.csv")).unwrap(),
        "my table"
    );
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "my notes");
    // Nothing staged beside them either.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

/// Guards against flags accepted and ignored: `dynamic` and `performance` (which run whole, on
/// the CPU) once took `--shard` and `--adapter` and ran without them, `all` took `--shard` for
/// its specs only, `check --dry-run` ran `dynamic` in full and passed a spec on no rows,
/// `plots --dir` dropped its names and `--quick`, `--no-cache` dropped `--cache`. Each is now
/// refused naming the flag, before anything is written.
#[test]
fn no_flag_is_accepted_and_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let mut cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["dynamic", "--quick", "--out", o, "--shard", "1/2"],
            "--shard",
        ),
        (
            vec!["dynamic", "--quick", "--out", o, "--adapter", "lavapipe"],
            "--adapter",
        ),
        (
            vec!["performance", "--quick", "--out", o, "--shard", "2/2"],
            "--shard",
        ),
        (
            vec!["performance", "--quick", "--out", o, "--adapter", "auto"],
            "--adapter",
        ),
        (
            vec!["all", "--quick", "--out", o, "--shard", "1/2"],
            "--shard",
        ),
        (
            vec!["check", "--quick", "--out", o, "--dry-run"],
            "--dry-run",
        ),
        (
            vec!["check", "--quick", "--out", o, "--shard", "1/2"],
            "--shard",
        ),
        (
            vec!["check", "dynamic", "--out", o, "--adapter", "auto"],
            "--adapter",
        ),
        (vec!["plots", "--dir", o, "--quick"], "--quick"),
        (vec!["plots", "--dir", o, "figure6"], "NAMES"),
        (
            vec!["figure6", "--out", o, "--no-cache", "--cache", o],
            "--cache",
        ),
        (
            vec![
                "figure6",
                "--out",
                o,
                "--no-cache",
                "--cache-limit-mib",
                "9",
            ],
            "--cache-limit-mib",
        ),
    ];
    if !cfg!(feature = "embree") {
        cases.push((
            vec!["dynamic", "--out", o, "--require-embree"],
            "--require-embree",
        ));
        cases.push((
            vec!["performance", "--out", o, "--require-embree"],
            "--require-embree",
        ));
    }
    for (args, flag) in cases {
        let r = experiment(&args);
        let t = text(&r);
        assert!(!r.status.success(), "{args:?} accepted: {t}");
        assert!(t.contains(flag), "{args:?}: {t}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}
