//! The runner: executes a [`Plan`] step by step, streaming fields (bake, evaluate the cells that
//! read them, release), and writes the outputs of [`super::outputs`], the images, `run.json` and
//! the plots of [`super::figures`].
//!
//! Everything runs through the spec's render kind ([`super::kinds::Kind`]): its points, its
//! estimator, its metric columns. Every lookup uses the reference's rays: the same seeded k²
//! set, the same points, the same offset; the lookup and the ray cast differ only in the
//! [`crate::visibility::Visibility`] behind the same estimator. Stages shorter than
//! `short_stage_s` are timed as the best of `repeats` runs.

pub mod frames;
mod frames_write;

pub use frames_write::redraw as redraw_frames;
mod methods;
mod references;
pub(crate) use super::staging;
mod state;
mod steps;
mod write;

use super::fields::FieldSupply;
use super::plan::{Plan, PlanLimits};
use super::progress::stage;
use super::scenes::Scenes;
use super::spec::{Spec, SpecError, Threshold};
use super::table::Row;
use super::{Error, Result, ResultExt};
use crate::gpu::AdapterPreference;
use std::path::{Path, PathBuf};
use steps::Runner;

/// A spec read from disk.
#[derive(Clone, Debug)]
pub struct LoadedSpec {
    /// The file stem.
    pub name: String,
    pub path: PathBuf,
    pub text: String,
    pub spec: Spec,
}

impl LoadedSpec {
    /// Reads, parses and validates `path`.
    pub fn load(path: &Path) -> Result<LoadedSpec, SpecError> {
        let text = std::fs::read_to_string(path).map_err(|source| SpecError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        let spec = Spec::parse(&text, path)?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "spec".into());
        Ok(LoadedSpec {
            name,
            path: path.to_path_buf(),
            text,
            spec,
        })
    }
}

/// How to run a spec.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Use the quick profile.
    pub quick: bool,
    /// Output folder.
    pub out: PathBuf,
    /// Fields served from and saved to the cache (see [`super::fields`]).
    pub supply: FieldSupply,
    /// Print the plan and stop.
    pub dry_run: bool,
    /// Stages faster than this (seconds) are repeated, the best run reported.
    pub short_stage_s: f64,
    /// Runs of a short stage.
    pub repeats: usize,
    /// The adapter of the "gpu" backend (default: `VISFIELD_ADAPTER`, else hardware where
    /// there is one, else lavapipe); unused unless a spec asks for "gpu".
    pub adapter: AdapterPreference,
    /// Run into an output folder that holds files no run wrote (they are kept).
    pub allow_nonempty_out: bool,
    /// Fail, rather than skip its rows, where a spec lists a method this build cannot run
    /// (Embree without the `embree` feature).
    pub require_embree: bool,
    /// Run only this shard's cells (`--shard I/N`, [`super::shard`]).
    pub shard: Option<crate::experiment::shard::Shard>,
}

impl RunOptions {
    /// Defaults: full profile, the default cache (256 MiB per field at most), half the memory.
    pub fn new(out: PathBuf) -> RunOptions {
        RunOptions {
            quick: false,
            out,
            supply: FieldSupply {
                cache: Some(super::fields::default_cache_dir()),
                cache_limit: 256 << 20,
                memory_limit: crate::field::default_memory_limit(),
            },
            dry_run: false,
            short_stage_s: 2.0,
            repeats: 3,
            adapter: AdapterPreference::from_env(),
            allow_nonempty_out: false,
            require_embree: false,
            shard: None,
        }
    }
}

/// What a run produced.
#[derive(Clone, Debug)]
pub struct RunReport {
    pub name: String,
    pub out: PathBuf,
    pub rows: Vec<Row>,
    /// An animated spec's rows of `frames.csv` (empty for a static spec, whose `rows` are its
    /// cells).
    pub frames: Vec<frames::FrameRow>,
    /// The thresholds of the profile that ran.
    pub thresholds: Vec<Threshold>,
    /// The plan as printed by `--dry-run`.
    pub plan_text: String,
    pub seconds: f64,
}

/// Fails unless `dir` can be created and written to.
pub fn ensure_writable(dir: &Path) -> Result<()> {
    let fail = |source: std::io::Error| {
        Error::Io {
            path: dir.to_path_buf(),
            source,
        }
        .context("output folder is not writable")
    };
    std::fs::create_dir_all(dir).map_err(fail)?;
    let probe = dir.join(format!(".write-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(fail)?;
    std::fs::remove_file(&probe).map_err(fail)
}

/// Runs `ls` (or prints its plan with `dry_run`).
pub fn run(ls: &LoadedSpec, opts: &RunOptions) -> Result<RunReport> {
    let started = std::time::Instant::now();
    crate::experiment::progress::begin_run();
    let spec = ls.spec.profile(opts.quick);
    let profile = if opts.quick { "quick" } else { "full" };
    let out_existed = opts.out.exists();
    let result = (|| {
        if !opts.dry_run {
            staging::check_ownership(&opts.out, opts.allow_nonempty_out)?;
            ensure_writable(&opts.out)?;
            if let Some(cache) = &opts.supply.cache {
                ensure_writable(cache)
                    .map_err(|e| e.context(format!("field cache {}", cache.display())))?;
                // Writes of fields or references killed mid-way.
                crate::io::remove_stale_temporaries(cache);
            }
        }
        run_checked(ls, opts, &spec, profile, started)
    })();
    if result.is_err() && !out_existed {
        // A failed run leaves no empty output folder behind (only an empty one is removed).
        let _ = std::fs::remove_dir(&opts.out);
    }
    result
}

/// [`run`] once the output folder (and the cache) are known to be writable.
fn run_checked(
    ls: &LoadedSpec,
    opts: &RunOptions,
    spec: &Spec,
    profile: &str,
    started: std::time::Instant,
) -> Result<RunReport> {
    let scenes_path = if opts.quick && ls.spec.quick.scenes.is_some() {
        "quick.scenes"
    } else {
        "scenes"
    };
    eprintln!("{} ({profile}): {}", ls.name, spec.reproduces);
    crate::experiment::models_cmd::require(
        &ls.name,
        crate::experiment::models_cmd::spec_models(spec),
    )?;
    let (scenes, _) = stage("load scenes", || {
        Scenes::build_within(spec, &ls.path, scenes_path, opts.supply.memory_limit)
    });
    let scenes = scenes?;
    let kind = crate::experiment::kinds::of(&spec.render);
    // Every frame of an animated scene (a caster may move onto a light).
    let problem = |bs: &crate::experiment::scenes::BuiltScene| {
        if bs.frames.is_empty() {
            return kind.scene_problem(bs);
        }
        (0..bs.frame_count()).find_map(|f| {
            let (field, message) = kind.scene_problem(&bs.at_frame(f))?;
            Some((field, format!("at frame {f}: {message}")))
        })
    };
    if let Some((field, message)) = scenes.scenes.iter().find_map(problem) {
        return Err(crate::experiment::spec::SpecError::Invalid {
            file: ls.path.clone(),
            field,
            message,
        }
        .into());
    }
    let limits = PlanLimits {
        memory_limit: opts.supply.memory_limit,
    };
    crate::experiment::plan::check_scene_memory(spec, &scenes, limits)
        .context(|| ls.path.display().to_string())?;
    if spec.animation.is_some() {
        crate::experiment::plan::check_animated_fields(spec, &scenes, limits)
            .context(|| ls.path.display().to_string())?;
        return run_animated(ls, opts, spec, &scenes, started);
    }
    let plan = Plan::new_shard(spec, &scenes, limits, opts.shard)
        .context(|| ls.path.display().to_string())?;
    let supply = &opts.supply;
    let plan_text = plan.describe(&ls.name, &scenes, &|m, p| {
        supply.state(&scenes.meshes[m], p)
    });
    let report = |rows: Vec<Row>| RunReport {
        name: ls.name.clone(),
        out: opts.out.clone(),
        rows,
        frames: Vec::new(),
        thresholds: spec.thresholds.clone(),
        plan_text: plan_text.clone(),
        seconds: started.elapsed().as_secs_f64(),
    };
    if opts.dry_run {
        return Ok(report(Vec::new()));
    }
    eprint!("{plan_text}");
    if let (Some(shard), true) = (opts.shard, plan.cells.is_empty()) {
        eprintln!(
            "shard {}: no cells (every field group lies in another shard); writing an empty \
             shard for `experiment merge`",
            shard.label()
        );
    }
    let method_runs = methods::runnable(ls, spec, opts)?;
    let rows = staged_run(opts, |staged| {
        let mut runner = Runner::new(spec, &plan, &scenes, staged)?;
        runner.method_runs = method_runs;
        for step in &plan.steps {
            runner.step(step)?;
        }
        runner.finish(ls)
    })?;
    let r = report(rows);
    eprintln!(
        "{}: {} cells in {:.1} s -> {}",
        ls.name,
        r.rows.len(),
        r.seconds,
        opts.out.display()
    );
    Ok(r)
}

/// Runs `work` with its outputs going to a staging folder beside `opts.out` (the options it is
/// given), published only once it has finished; the staging folder removed on any failure
/// ([`staging::staged`]).
fn staged_run<T>(opts: &RunOptions, work: impl FnOnce(&RunOptions) -> Result<T>) -> Result<T> {
    staging::staged(&opts.out, |dir| {
        work(&RunOptions {
            out: dir.to_path_buf(),
            ..opts.clone()
        })
    })
}

/// [`run_checked`] for an animated spec: every scene frame by frame ([`frames`]), written by
/// [`frames_write`] through the same staging.
fn run_animated(
    ls: &LoadedSpec,
    opts: &RunOptions,
    spec: &Spec,
    scenes: &Scenes,
    started: std::time::Instant,
) -> Result<RunReport> {
    if opts.shard.is_some() {
        return Err(Error::invalid(
            "--shard",
            format!(
                "{}: an animated spec runs whole (its rows are frames, not cells)",
                ls.name
            ),
        ));
    }
    let frames = spec.animation.as_ref().map_or(1, |a| a.frames);
    let cells = crate::experiment::plan::cells_of(spec).len();
    let kept: Vec<String> = (0..scenes.scenes.len())
        .map(|s| {
            let bytes = crate::experiment::plan::animated_field_bytes(spec, scenes, s);
            format!(
                "{} {}",
                scenes.scenes[s].name,
                crate::field::ByteSize(bytes)
            )
        })
        .collect();
    let plan_text = format!(
        "{}: {} scene(s) x {frames} frame(s): the ray casters once a frame, the field methods \
         once a frame per field cell ({cells} cell(s) over all scenes), {} rays per point, each \
         frame's converged reference; fields kept for every frame: {}\n",
        ls.name,
        scenes.scenes.len(),
        spec.render.rays_per_point,
        kept.join(", ")
    );
    let report = |frames: Vec<frames::FrameRow>| RunReport {
        name: ls.name.clone(),
        out: opts.out.clone(),
        rows: Vec::new(),
        frames,
        thresholds: Vec::new(),
        plan_text: plan_text.clone(),
        seconds: started.elapsed().as_secs_f64(),
    };
    if opts.dry_run {
        return Ok(report(Vec::new()));
    }
    eprint!("{plan_text}");
    let rows = staged_run(opts, |staged| {
        let run = frames::run(ls, spec, scenes, staged)?;
        frames_write::write(ls, spec, scenes, staged, &run)?;
        Ok(run.rows)
    })?;
    let r = report(rows);
    eprintln!(
        "{}: {} frame rows in {:.1} s -> {}",
        ls.name,
        r.frames.len(),
        r.seconds,
        opts.out.display()
    );
    Ok(r)
}
