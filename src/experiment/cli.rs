//! The `experiment` command line.

use super::check::{self, check_committed};
use super::columns::{of_serialized, read_csv};
use super::discover;
use super::fields::FieldSupply;
use super::outputs;
use super::run::{staging, LoadedSpec, RunOptions};
use super::spec::Backend;
use super::{Error, Result};
use clap::{Args, Parser, Subcommand};
use std::path::{Path, PathBuf};

/// visfield experiments: reproduce and extend the presampled-visibility papers.
#[derive(Parser, Debug)]
#[command(
    name = "experiment",
    version,
    about,
    long_about = None,
    after_help = "Run a spec by name: `experiment NAME [--quick] [--out DIR] [--dry-run]` runs \
                  experiments/NAME.json (see `experiment list`; `experiment NAME --help`).\n\
                  Your own mesh: `experiment try MESH.obj|MESH.ply [--kind ao|shadows|reflections] \
                  [--quick]` (or {\"mesh\": {\"file\": \"PATH\"}} in a spec)."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Small tour on the embedded procedural scene (no files needed).
    Quickstart {
        /// Output folder.
        #[arg(long, default_value = "results/quickstart")]
        out: std::path::PathBuf,
    },
    /// Sphere point sets and hemisphere layouts: exactness, spacing, timings and plots.
    Sampling {
        /// Output folder.
        #[arg(long, default_value = "results/sampling")]
        out: std::path::PathBuf,
        /// Run into an output folder that holds files no earlier run wrote (no run.json); its
        /// files are kept, never deleted.
        #[arg(long)]
        allow_nonempty_out: bool,
    },
    /// Stiff and extreme cases against f64 or closed-form answers (exit 1 naming any failure).
    Stability {
        /// Output folder.
        #[arg(long, default_value = "results/stability")]
        out: std::path::PathBuf,
        /// Run into an output folder that holds files no earlier run wrote (no run.json); its
        /// files are kept, never deleted.
        #[arg(long)]
        allow_nonempty_out: bool,
    },
    /// The 2005 relief caster: Tables 1–3 (skips × viewing angle, sample rate, bisections).
    Relief {
        /// Output folder (default: results/relief, results/quick/relief with --quick).
        #[arg(long)]
        out: Option<std::path::PathBuf>,
        /// Run into an output folder that holds files no earlier run wrote (no run.json); its
        /// files are kept, never deleted.
        #[arg(long)]
        allow_nonempty_out: bool,
        /// 64² images and one timing per setting (for tests and CI).
        #[arg(long)]
        quick: bool,
        /// The adapter of the GPU columns: auto, lavapipe, hardware, or part of its name
        /// (default: $VISFIELD_ADAPTER, else auto).
        #[arg(long)]
        adapter: Option<String>,
        /// CPU only: leave the GPU columns empty.
        #[arg(long, conflicts_with = "adapter")]
        no_gpu: bool,
    },
    /// Field lookup against ray casting on the same rays, and each one's cost against caster
    /// triangles, field size and the share of rays entering the caster's sphere.
    Performance {
        #[command(flatten)]
        opts: RunArgs,
    },
    /// Rigid casters moving every frame: each method's frame time (the motion's update and the
    /// query) and same-ray error against the caster count (`results/dynamic/`).
    Dynamic {
        #[command(flatten)]
        opts: RunArgs,
    },
    /// List the experiment specs and the figure or table each reproduces.
    List,
    /// Run a spec file from any path.
    Run {
        /// The spec (JSON).
        spec: PathBuf,
        #[command(flatten)]
        opts: RunArgs,
    },
    /// Does a field suit your own mesh (OBJ or PLY)? A verdict per field size.
    ///
    /// Fits MESH to a unit sphere on a floor, bakes fields at a few sizes and runs them against
    /// ray casting (and Embree where built): table, images, plots, a verdict per size, and
    /// OUT/spec.json to edit and rerun with `run`.
    Try {
        /// The mesh file (.obj or .ply).
        mesh: PathBuf,
        /// What is rendered on the floor.
        #[arg(long, value_enum, default_value = "ao")]
        kind: super::try_mesh::TryKind,
        #[command(flatten)]
        opts: RunArgs,
    },
    /// Run specs and fail, naming the cells, where an RMS passes its threshold or moves more
    /// than a factor 1.25 either way from the committed run (results/quick/NAME with --quick,
    /// else results/NAME); with them `experiment dynamic`, each row's errors and mean AO against
    /// the committed results/…/dynamic.
    Check {
        /// Specs by name or path, or `dynamic` (default: every spec of experiments/, the
        /// embedded quickstart and dynamic).
        names: Vec<String>,
        /// Fail when a spec's "gpu" rows cannot run for want of a Vulkan adapter (without it,
        /// check runs their CPU rows and names the GPU rows it skipped).
        #[arg(long)]
        require_gpu: bool,
        /// The folder of the committed runs to compare with, one subfolder per spec (default
        /// results/quick with --quick, else results). Without it, a spec given by path outside
        /// experiments/ is checked against its thresholds only.
        #[arg(long)]
        against: Option<PathBuf>,
        #[command(flatten)]
        opts: RunArgs,
    },
    /// Regenerate every result (results/NAME, or results/quick/NAME with --quick): every spec,
    /// then quickstart, sampling, relief, stability, performance and dynamic.
    All {
        #[command(flatten)]
        opts: RunArgs,
    },
    /// Redraw the plots of finished runs from their CSV files and images, and rewrite their
    /// paper_vs_ours.csv from table.csv, raycast_sweep.csv, pairs.csv and the spec's paper
    /// section.
    Plots {
        /// Specs by name (default: every spec with results).
        names: Vec<String>,
        /// The quick runs' results (results/quick/NAME).
        #[arg(long)]
        quick: bool,
        /// A run's output folder (instead of names and --quick).
        #[arg(long, conflicts_with_all = ["names", "quick"])]
        dir: Option<PathBuf>,
    },
    /// Joins the folders of `--shard I/N` runs of one spec into the folder a single run
    /// writes (refused when a shard is missing or doubled, or commits or specs differ).
    Merge {
        /// The merged results folder.
        out: PathBuf,
        /// The shards' results folders, all N of them, in any order.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
    },
    /// The real meshes of data/models.json: list, verify, fetch from their sources.
    Models {
        #[command(subcommand)]
        command: super::models_cmd::ModelsCommand,
    },
    /// `experiment NAME ...`: runs experiments/NAME.json.
    #[command(external_subcommand)]
    Named(Vec<String>),
}

/// Options of a run.
#[derive(Args, Debug, Clone)]
pub struct RunArgs {
    /// The quick profile (smaller axes; under a minute on 2 cores).
    #[arg(long)]
    pub quick: bool,
    /// Output folder (default results/NAME, or results/quick/NAME with --quick). For `all` and
    /// `check`: the parent folder, one subfolder per spec.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the plan (steps with their rays and bytes) and stop.
    #[arg(long)]
    pub dry_run: bool,
    /// Field cache folder (default $VISFIELD_CACHE, else cache/ of the project run in, the
    /// nearest folder holding experiments/, else of ~/.local/share/visfield).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Do not read or write the field cache.
    #[arg(long, conflicts_with_all = ["cache", "cache_limit_mib"])]
    pub no_cache: bool,
    /// Cache only fields up to this many MiB.
    #[arg(long, default_value_t = 256)]
    pub cache_limit_mib: u64,
    /// Refuse fields larger than this many MiB (default: half the machine's memory).
    #[arg(long)]
    pub max_memory_mib: Option<u64>,
    /// The adapter of the "gpu" backend: auto, lavapipe, hardware, or part of its name
    /// (default: $VISFIELD_ADAPTER, else auto = hardware where there is one, else lavapipe).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Run into an output folder that holds files no earlier run wrote (no run.json); its
    /// files are kept, never deleted.
    #[arg(long)]
    pub allow_nonempty_out: bool,
    /// Fail where a spec lists a method this build cannot run (`{"method": "embree"}` without
    /// the `embree` feature); without it, such a run leaves out that method's rows and says why.
    #[arg(long)]
    pub require_embree: bool,
    /// Run shard I of N of the spec's cells (contiguous blocks in plan order; see
    /// `experiment merge` to join the shards' folders).
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
}

/// Runs the spec experiments/NAME.json (see `experiment list`).
#[derive(Parser, Debug)]
struct NamedRun {
    #[command(flatten)]
    opts: RunArgs,
}

impl RunArgs {
    /// Options for the spec called `name`; `parent` replaces `results` (for `all`/`check`).
    /// A size flag whose bytes overflow is an error naming the flag.
    fn options(&self, name: &str, parent: Option<&Path>) -> Result<RunOptions> {
        let mut o = RunOptions::new(self.out(name, parent));
        o.quick = self.quick;
        o.dry_run = self.dry_run;
        o.adapter = adapter_preference(self.adapter.as_deref());
        o.allow_nonempty_out = self.allow_nonempty_out;
        o.require_embree = self.require_embree;
        o.shard = self
            .shard
            .as_deref()
            .map(|v| super::shard::Shard::parse(v, "--shard"))
            .transpose()?;
        o.supply = FieldSupply {
            cache: (!self.no_cache)
                .then(|| (self.cache.clone()).unwrap_or_else(super::fields::default_cache_dir)),
            cache_limit: mib_to_bytes(self.cache_limit_mib, "--cache-limit-mib")?,
            memory_limit: match self.max_memory_mib {
                Some(m) => mib_to_bytes(m, "--max-memory-mib")?,
                None => crate::field::default_memory_limit(),
            },
        };
        Ok(o)
    }

    /// The output folder of the spec called `name` (see [`Self::options`]).
    fn out(&self, name: &str, parent: Option<&Path>) -> PathBuf {
        match (parent, &self.out) {
            (Some(p), _) => p.join(name),
            (None, Some(o)) => o.clone(),
            (None, None) => Path::new(results_root(self.quick)).join(name),
        }
    }
}

/// The checks of the flags that a command without a spec's cells or a GPU has no use for: no
/// flag is accepted and ignored.
impl RunArgs {
    /// Refuses `--shard` and `--adapter` for `command` (a command-made result that runs whole,
    /// on the CPU), and `--require-embree` in a build without Embree ([`Self::embree_built`]).
    fn whole_cpu_run(&self, command: &str) -> Result<()> {
        if let Some(v) = &self.shard {
            return Err(Error::invalid(
                "--shard",
                format!(
                    "`{v}`: experiment {command} runs whole (its rows are not a spec's cells); \
                     --shard splits a spec's cells (`experiment NAME --shard I/N`)"
                ),
            ));
        }
        if let Some(a) = &self.adapter {
            return Err(Error::invalid(
                "--adapter",
                format!("`{a}`: experiment {command} runs on the CPU only and opens no GPU"),
            ));
        }
        self.embree_built(command)
    }

    /// Refuses `--require-embree` where this build has no Embree: `command` would run without
    /// its rows.
    fn embree_built(&self, command: &str) -> Result<()> {
        if self.require_embree && !cfg!(feature = "embree") {
            return Err(Error::invalid(
                "--require-embree",
                format!(
                    "experiment {command}: this build has no Embree (build with --features \
                     embree)"
                ),
            ));
        }
        Ok(())
    }
}

/// `experiment performance` into `o.out`, staged and published as a spec's run is
/// ([`staging`]): a file or a folder no run wrote refused before any work unless
/// `--allow-nonempty-out`.
fn performance(o: &RunOptions) -> Result<()> {
    staging::check_ownership(&o.out, o.allow_nonempty_out)?;
    let rows = staging::staged(&o.out, |dir| {
        super::performance::run(dir, o.quick, &o.supply)
    })?;
    println!("performance: {} row(s) -> {}", rows.len(), o.out.display());
    Ok(())
}

/// The folder of the committed results: `results/quick` for the quick profile, else `results`.
fn results_root(quick: bool) -> &'static str {
    if quick {
        "results/quick"
    } else {
        "results"
    }
}

/// `mib` MiB in bytes, or the error naming `flag` when that overflows.
fn mib_to_bytes(mib: u64, flag: &str) -> Result<u64> {
    mib.checked_mul(1 << 20).ok_or_else(|| {
        super::Error::invalid(
            flag,
            format!("{mib} MiB is more bytes than 64 bits can count"),
        )
    })
}

/// Runs one spec file; prints the plan on a dry run.
fn run_one(path: &Path, args: &RunArgs, parent: Option<&Path>) -> Result<super::run::RunReport> {
    run_loaded(&LoadedSpec::load(path)?, args, parent)
}

/// Runs one loaded spec; prints the plan on a dry run.
fn run_loaded(
    ls: &LoadedSpec,
    args: &RunArgs,
    parent: Option<&Path>,
) -> Result<super::run::RunReport> {
    let report = super::run::run(ls, &args.options(&ls.name, parent)?)?;
    if args.dry_run {
        print!("{}", report.plan_text);
    }
    Ok(report)
}

/// Lists the specs; exit code 1 when one is invalid.
fn list() -> Result<i32> {
    let paths = discover::spec_paths()?;
    let width = paths
        .iter()
        .map(|p| discover::name_of(p).chars().count())
        .max()
        .unwrap_or(0);
    let mut code = 0;
    for p in paths {
        match LoadedSpec::load(&p) {
            Ok(ls) => println!("{:<width$}  {}", ls.name, ls.spec.reproduces),
            Err(e) => {
                println!("{:<width$}  INVALID: {e}", discover::name_of(&p));
                code = 1;
            }
        }
    }
    println!();
    println!(
        "render kinds (render.what): {}",
        super::kinds::names().join(", ")
    );
    println!("methods (methods[].method):");
    for name in super::methods::names() {
        if let Some(e) = super::methods::lookup(name) {
            println!("  {name:<12} {}", e.about);
        }
    }
    Ok(code)
}

/// A command's results folder as a spec's run has it: `out` refused before any work when it is
/// a file or holds files no run wrote (unless `allow_nonempty_out`), or when it cannot be
/// written; `work` run in a staging folder beside it and published whole
/// ([`staging::staged`]); a folder this call created is removed again when nothing was
/// published.
fn staged_command<T>(
    out: &Path,
    allow_nonempty_out: bool,
    work: impl FnOnce(&Path) -> Result<T>,
) -> Result<T> {
    staging::check_ownership(out, allow_nonempty_out)?;
    let existed = out.exists();
    super::run::ensure_writable(out)?;
    let done = staging::staged(out, work);
    if done.is_err() && !existed {
        // Only when empty: nothing of anyone's is removed.
        let _ = std::fs::remove_dir(out);
    }
    done
}

/// `experiment stability` into `out`, written as a spec's run is (`run/staging.rs`): `out`
/// checked before any work, the cases run in a staging folder beside it and published whole. A
/// failing case is a result too: its rows are written before the error names it, so they are
/// published; an error before any row is written publishes nothing.
fn stability(out: &Path, allow_nonempty_out: bool) -> Result<()> {
    let cases = staged_command(out, allow_nonempty_out, |dir| {
        let r = super::stability::run(dir);
        if r.is_err() && dir.join("run.json").is_file() {
            Ok(r)
        } else {
            r.map(Ok)
        }
    })?;
    cases?;
    println!("stability: written to {}", out.display());
    Ok(())
}

/// `experiment relief` into `out`, staged and published as [`stability`] is.
fn relief(
    out: &Path,
    allow_nonempty_out: bool,
    quick: bool,
    gpu: Option<crate::gpu::AdapterPreference>,
) -> Result<()> {
    let rows = staged_command(out, allow_nonempty_out, |dir| {
        super::relief::run(dir, quick, gpu)
    })?;
    println!("relief: {} row(s) -> {}", rows.len(), out.display());
    Ok(())
}

/// `experiment sampling` into `out`, staged and published as [`stability`] is.
fn sampling(out: &Path, allow_nonempty_out: bool) -> Result<()> {
    staged_command(out, allow_nonempty_out, super::sampling_report::run)
        .map_err(|e| e.context("sampling"))?;
    eprintln!("sampling: report written to {}", out.display());
    Ok(())
}

/// Runs the specs and checks their thresholds and the committed runs
/// ([`check_committed`]); exit code 1 naming each failure (a cell past its
/// threshold, a cell away from its committed value, a spec without a committed run, or a spec
/// that failed to run).
/// Every spec by default (the embedded quickstart too), or the ones named. Where no Vulkan
/// driver is installed and no adapter was named, the specs' "gpu" rows are left out, loudly,
/// unless `require_gpu` makes that a failure.
fn check(
    names: &[String],
    args: &RunArgs,
    require_gpu: bool,
    against: Option<&Path>,
) -> Result<i32> {
    // Each spec, and whether it is shipped (in experiments/, or the quickstart): a shipped spec
    // must have a committed run to compare with.
    let mut specs: Vec<(Result<LoadedSpec>, bool)> = Vec::new();
    let shipped = discover::spec_paths()?;
    if names.is_empty() {
        specs.extend(
            shipped
                .iter()
                .map(|p| (LoadedSpec::load(p).map_err(Into::into), true)),
        );
        specs.push((super::quickstart::spec(), true));
    } else {
        for n in names.iter().filter(|n| n.as_str() != "dynamic") {
            specs.push(match n.as_str() {
                "quickstart" => (super::quickstart::spec(), true),
                _ => match discover::find(n) {
                    Ok(p) => {
                        let ours = shipped.iter().any(|s| same_file(s, &p));
                        (LoadedSpec::load(&p).map_err(Into::into), ours)
                    }
                    Err(e) => (Err(e), true),
                },
            });
        }
    }
    let committed_root = against.map_or_else(|| results_root(args.quick).into(), Path::to_path_buf);
    let parent = args.out.clone().unwrap_or_else(|| {
        std::env::temp_dir().join(if args.quick {
            "visfield-check-quick"
        } else {
            "visfield-check"
        })
    });
    let mut failed = Vec::new();
    // Opening a device takes a while: probed once, for the first spec with GPU rows.
    let missing_vulkan = std::cell::OnceCell::new();
    for (ls, shipped) in specs {
        let mut ls = match ls {
            Ok(ls) => ls,
            Err(e) => {
                failed.push(format!("error: {e}"));
                continue;
            }
        };
        let name = ls.name.clone();
        let gpu = ls.spec.profile(args.quick).backends.contains(&Backend::Gpu)
            || ls
                .spec
                .methods
                .iter()
                .any(|m| m.backends.contains(&Backend::Gpu));
        if gpu && *missing_vulkan.get_or_init(|| no_vulkan(args)) {
            let why = "no Vulkan adapter (install mesa-vulkan-drivers for lavapipe)";
            if require_gpu {
                failed.push(format!("{name}: its \"gpu\" rows cannot run: {why}"));
                continue;
            }
            println!("SKIPPED the \"gpu\" rows of {name}: {why}; --require-gpu fails instead");
            ls.spec.backends.retain(|&b| b != Backend::Gpu);
            if let Some(b) = &mut ls.spec.quick.backends {
                b.retain(|&b| b != Backend::Gpu);
            }
            for m in &mut ls.spec.methods {
                m.backends.retain(|&b| b != Backend::Gpu);
            }
            if ls.spec.profile(args.quick).backends.is_empty() {
                continue;
            }
        }
        match run_loaded(&ls, args, Some(&parent)) {
            Ok(report) => {
                let mut f = check::check_rows(&report.thresholds, &report.rows);
                let animated = ls.spec.animation.is_some();
                let table = if animated { "frames.csv" } else { "table.csv" };
                let committed = committed_root.join(&name).join(table);
                let compared = if shipped || against.is_some() {
                    let read = if animated {
                        committed_frames(&report.out, &committed)
                    } else {
                        read_csv(&committed).and_then(|theirs| {
                            let ours: Vec<_> = report.rows.iter().map(of_serialized).collect();
                            let (mut f, _) = check_committed(&check::TABLE, &ours, &theirs);
                            f.extend(committed_methods(&report.out, &committed)?);
                            Ok(f)
                        })
                    };
                    match read {
                        Ok(failures) => {
                            f.extend(failures);
                            format!(" and the committed {}", committed.display())
                        }
                        Err(e) => {
                            failed.push(no_committed_run(&name, args.quick, e));
                            String::new()
                        }
                    }
                } else {
                    " (not a shipped spec: no committed run compared)".into()
                };
                println!(
                    "{name}: {} {}, {} threshold(s){compared}, {} failure(s) ({:.1} s)",
                    report.rows.len() + report.frames.len(),
                    if animated { "frame row(s)" } else { "cell(s)" },
                    report.thresholds.len(),
                    f.len(),
                    report.seconds
                );
                failed.extend(f.into_iter().map(|f| format!("{name}: {f}")));
            }
            Err(e) => failed.push(format!("{name}: error: {e}")),
        }
    }
    if names.is_empty() || names.iter().any(|n| n == "dynamic") {
        match check_dynamic(args, &parent, &committed_root) {
            Ok(f) => failed.extend(f),
            Err(e) => failed.push(format!("dynamic: error: {e}")),
        }
    }
    for f in &failed {
        println!("FAIL {f}");
    }
    Ok(i32::from(!failed.is_empty()))
}

/// Refuses the flags `check` would accept and ignore: `--dry-run` (it runs the specs to compare
/// them), and with `dynamic` among the checked names (as by default) `--shard`, and
/// `--adapter` where `dynamic` is all it checks.
fn check_flags(names: &[String], args: &RunArgs) -> Result<()> {
    if args.dry_run {
        return Err(Error::invalid(
            "--dry-run",
            "experiment check runs the specs to compare them; `experiment NAME --dry-run` \
             prints a spec's plan",
        ));
    }
    let dynamic = names.is_empty() || names.iter().any(|n| n == "dynamic");
    if let (true, Some(v)) = (dynamic, &args.shard) {
        return Err(Error::invalid(
            "--shard",
            format!(
                "`{v}`: experiment dynamic, which check runs {}, runs whole; name the specs to \
                 check a shard of them",
                if names.is_empty() {
                    "by default"
                } else {
                    "here"
                }
            ),
        ));
    }
    if names.iter().all(|n| n == "dynamic") && !names.is_empty() {
        return args.whole_cpu_run("dynamic");
    }
    Ok(())
}

/// `experiment dynamic` run under `parent` and its rows checked against the committed run
/// ([`check::DYNAMIC`]); the failures, named.
fn check_dynamic(args: &RunArgs, parent: &Path, committed_root: &Path) -> Result<Vec<String>> {
    args.embree_built("dynamic")?;
    let o = args.options("dynamic", Some(parent))?;
    let t = std::time::Instant::now();
    super::dynamic::run(&o.out, o.quick, &o.supply, o.allow_nonempty_out)?;
    let committed = outputs::table_path(&committed_root.join("dynamic"), outputs::SWEEP_FRAMES_CSV);
    let theirs = match read_csv(&committed) {
        Ok(rows) => rows,
        Err(e) => return Ok(vec![no_committed_run("dynamic", args.quick, e)]),
    };
    let ours = read_csv(&o.out.join(outputs::SWEEP_FRAMES_CSV))?;
    let (f, left) = check_committed(&check::DYNAMIC, &ours, &theirs);
    if left > 0 {
        println!(
            "dynamic: {left} row(s) of methods the committed run lacks (Embree's, in a build \
             with the `embree` feature) not compared"
        );
    }
    println!(
        "dynamic: {} row(s) and the committed {}, {} failure(s) ({:.1} s)",
        ours.len(),
        committed.display(),
        f.len(),
        t.elapsed().as_secs_f64()
    );
    Ok(f.into_iter().map(|f| format!("dynamic: {f}")).collect())
}

/// The failure of `name`, a command or a spec whose committed run could not be read (`e`).
fn no_committed_run(name: &str, quick: bool, e: Error) -> String {
    format!(
        "{name}: no committed run to compare with ({e}); regenerate it with `experiment \
         {name}{}` and commit it",
        if quick { " --quick" } else { "" }
    )
}

/// An animated run's `frames.csv` (in `out`) against the committed one
/// ([`check::FRAMES`]); an error where the committed file is missing.
fn committed_frames(out: &Path, committed: &Path) -> Result<Vec<check::Failure>> {
    let mut theirs = read_csv(committed)?;
    let ours = read_csv(&out.join("frames.csv"))?;
    // The committed rows of a method this run skipped on its device (ray queries on an
    // adapter without them; run.json's `skipped_methods`) are not compared.
    let skipped: Vec<String> = read_run_json(out)["skipped_methods"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|m| m["method"].as_str().map(String::from))
        .collect();
    let before = theirs.len();
    theirs.retain(|r| !skipped.iter().any(|m| r.get("method") == Some(m.as_str())));
    if theirs.len() < before {
        println!(
            "{}: {} committed frame row(s) of methods this run skipped ({}) not compared",
            out.display(),
            before - theirs.len(),
            skipped.join(", ")
        );
    }
    let (f, left) = check_committed(&check::FRAMES, &ours, &theirs);
    if left > 0 {
        println!(
            "{}: {left} frame row(s) of methods the committed run lacks (Embree's, in a build \
             with the `embree` feature; ray queries, on an adapter with them; or methods newer
             than that run) not compared",
            out.display()
        );
    }
    Ok(f)
}

/// The run's `methods.csv` rows against the committed ones beside `committed_table` (the
/// committed `table.csv`); a run without method rows compares nothing, and a run with them
/// against a committed run without `methods.csv` fails each row as not committed.
fn committed_methods(out: &Path, committed_table: &Path) -> Result<Vec<check::Failure>> {
    let ours = out.join("methods.csv");
    if !ours.is_file() {
        return Ok(Vec::new());
    }
    let theirs = committed_table.with_file_name("methods.csv");
    let committed = if theirs.is_file() {
        read_csv(&theirs)?
    } else {
        Vec::new()
    };
    Ok(check_committed(&check::METHODS, &read_csv(&ours)?, &committed).0)
}

/// Whether two paths name the same file.
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

fn plots(names: &[String], quick: bool, dir: Option<&Path>) -> Result<()> {
    let root = PathBuf::from(results_root(quick));
    let dirs: Vec<PathBuf> = match (dir, names.is_empty()) {
        (Some(d), _) => vec![d.to_path_buf()],
        (None, false) => names.iter().map(|n| root.join(n)).collect(),
        (None, true) => discover::spec_paths()?
            .iter()
            .map(|p| root.join(discover::name_of(p)))
            .filter(|d| d.join("table.csv").exists() || d.join("frames.csv").exists())
            .collect(),
    };
    // Each folder by the table it holds: `experiment performance`'s (under its name before
    // too, [`outputs::table_path`]), an animated spec's `frames.csv`, else a spec's `table.csv`.
    for d in dirs {
        if outputs::table_path(&d, outputs::BACKEND_TIMES_CSV).exists() {
            super::performance::plots::redraw(&d)?;
            println!("redrew the plots in {}", d.display());
            continue;
        }
        if let Some(t) = [outputs::SWEEP_FRAMES_CSV, outputs::RENDERINGS_CSV]
            .into_iter()
            .find(|t| d.join(t).exists())
        {
            return Err(Error::invalid(
                d.join(t).display().to_string(),
                "its plots are drawn by the command that wrote it (experiment dynamic or \
                 relief); rerun that",
            ));
        }
        // An animated run: its plots from frames.csv.
        if d.join("frames.csv").exists() && !d.join("table.csv").exists() {
            let run = read_run_json(&d);
            super::run::redraw_frames(&d, run["render"].as_str().unwrap_or("the kind"))?;
            own_plots(&d, run)?;
            println!("redrew the plots in {}", d.display());
            continue;
        }
        let run = read_run_json(&d);
        let title = format!(
            "{}{}",
            run["spec"].as_str().unwrap_or(&discover::name_of(&d)),
            if run["profile"] == "quick" {
                " (quick)"
            } else {
                ""
            }
        );
        let name = run["spec"]
            .as_str()
            .map_or_else(|| discover::name_of(&d), String::from);
        if rewrite_paper_vs_ours(&d, &name)? {
            println!("rewrote {}", d.join("paper_vs_ours.csv").display());
        }
        super::figures::draw_all(&d, &title)?;
        own_plots(&d, run)?;
        println!("redrew the plots in {}", d.display());
    }
    Ok(())
}

/// A run's `run.json` (null where it has none or cannot be read).
fn read_run_json(dir: &Path) -> serde_json::Value {
    std::fs::read(dir.join("run.json"))
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok())
        .unwrap_or_default()
}

/// Rewrites `dir/paper_vs_ours.csv` from the run's CSV files and the paper section of
/// `experiments/NAME.json` as it is now (validated first), so that a corrected pairing needs no
/// rerun. Folders of no spec, or of a spec without a paper section, are left alone.
fn rewrite_paper_vs_ours(dir: &Path, name: &str) -> Result<bool> {
    let Some(path) = discover::spec_paths()?
        .into_iter()
        .find(|p| discover::name_of(p) == name)
    else {
        return Ok(false);
    };
    match LoadedSpec::load(&path)?.spec.paper {
        Some(paper) => super::paper::rewrite(dir, &paper),
        None => Ok(false),
    }
}

/// Adds the plots now in `dir` (its top-level PNGs) to the `files` its `run.json` lists, so that
/// a plot this command drew that the run had not (a newer plot kind) stays the program's file,
/// replaced or removed by the next run rather than kept as a user's. `run.json` is rewritten,
/// atomically, only when the list grows.
fn own_plots(dir: &Path, mut run: serde_json::Value) -> Result<()> {
    let Some(files) = run.get("files").and_then(|f| f.as_array()) else {
        return Ok(());
    };
    let mut listed: Vec<String> = files
        .iter()
        .filter_map(|f| f.as_str().map(String::from))
        .collect();
    let before = listed.len();
    for e in std::fs::read_dir(dir).map_err(Error::io(dir))? {
        let name = e.map_err(Error::io(dir))?.file_name();
        let name = name.to_string_lossy();
        if name.ends_with(".png") && !listed.iter().any(|f| f == name.as_ref()) {
            listed.push(name.into_owned());
        }
    }
    if listed.len() == before {
        return Ok(());
    }
    listed.sort();
    run["files"] = serde_json::json!(listed);
    let path = dir.join("run.json");
    let text = serde_json::to_string_pretty(&run).expect("run.json serialises");
    crate::io::write_atomic(&path, text.as_bytes()).map_err(Error::io(&path))
}

/// The adapter a `--adapter` flag names, else `$VISFIELD_ADAPTER`'s, else auto.
/// Whether no Vulkan driver is installed while the adapter is left to choose (`auto`): the one
/// case in which `check` may leave GPU rows out. A named adapter that is missing is an error of
/// the run, as everywhere.
fn no_vulkan(args: &RunArgs) -> bool {
    use crate::gpu::{AdapterPreference, GpuContext, GpuError};
    let pref = adapter_preference(args.adapter.as_deref());
    matches!(pref, AdapterPreference::Auto)
        && matches!(GpuContext::new(pref), Err(GpuError::NoAdapter))
}

fn adapter_preference(flag: Option<&str>) -> crate::gpu::AdapterPreference {
    flag.map_or_else(
        crate::gpu::AdapterPreference::from_env,
        crate::gpu::AdapterPreference::parse,
    )
}

/// Parses the command line and runs it: the exit code of a command that reports its own
/// failures (`list`, `check`, 0 elsewhere), or the error for the caller to print
/// (`src/bin/experiment.rs`, with [`super::Error::chain`]).
pub fn main() -> Result<i32> {
    run(Cli::parse())
}

/// Runs a parsed command line (see [`main`]).
pub fn run(cli: Cli) -> Result<i32> {
    match cli.command {
        Command::Quickstart { out } => super::quickstart::run(&out, false)?,
        Command::List => return list(),
        Command::Stability {
            out,
            allow_nonempty_out,
        } => stability(&out, allow_nonempty_out)?,
        Command::Relief {
            out,
            allow_nonempty_out,
            quick,
            adapter,
            no_gpu,
        } => {
            let gpu = (!no_gpu).then(|| adapter_preference(adapter.as_deref()));
            let out = out.unwrap_or_else(|| Path::new(results_root(quick)).join("relief"));
            relief(&out, allow_nonempty_out, quick, gpu)?;
        }
        Command::Run { spec, opts } => {
            run_one(&spec, &opts, None)?;
        }
        Command::Try { mesh, kind, opts } => {
            let name = super::try_mesh::run_name(&mesh);
            let o = opts.options(&name, None)?;
            let (report, verdicts) = super::try_mesh::run(&mesh, kind, &o)?;
            if o.dry_run {
                print!("{}", report.plan_text);
                return Ok(0);
            }
            println!(
                "\n{}: field lookup against ray casting on the same rays",
                mesh.display()
            );
            for v in verdicts {
                println!("  {v}");
            }
            println!(
                "  outputs: {}; edit and rerun: experiment run {} --out {}",
                o.out.display(),
                o.out.join("spec.json").display(),
                o.out.display()
            );
        }
        Command::Performance { opts } => {
            opts.whole_cpu_run("performance")?;
            let o = opts.options("performance", None)?;
            if o.dry_run {
                println!("{}", super::performance::plan(o.quick));
                return Ok(0);
            }
            performance(&o)?;
        }
        Command::Dynamic { opts } => {
            opts.whole_cpu_run("dynamic")?;
            let o = opts.options("dynamic", None)?;
            if o.dry_run {
                println!(
                    "dynamic: {}",
                    super::dynamic::crowd::Profile::new(o.quick).describe()
                );
                return Ok(0);
            }
            super::dynamic::run(&o.out, o.quick, &o.supply, o.allow_nonempty_out)?;
        }
        Command::Check {
            names,
            require_gpu,
            against,
            opts,
        } => {
            check_flags(&names, &opts)?;
            return check(&names, &opts, require_gpu, against.as_deref());
        }
        Command::All { opts } => {
            if let Some(v) = &opts.shard {
                return Err(Error::invalid(
                    "--shard",
                    format!(
                        "`{v}`: experiment all runs every result whole; run a spec's shards \
                         with `experiment NAME --shard I/N`"
                    ),
                ));
            }
            opts.embree_built("all")?;
            for p in discover::spec_paths()? {
                let parent = opts.out.clone();
                run_one(&p, &opts, parent.as_deref())?;
            }
            if opts.dry_run {
                // The command-made results have no plan to print: a dry run stops here.
                println!(
                    "dry run: quickstart, sampling, relief, stability, performance and dynamic not run"
                );
                return Ok(0);
            }
            // The command-made results beside the specs' (same root).
            let root = |name: &str| opts.out(name, opts.out.as_deref());
            // The quickstart in the run's profile: with --quick, what `check --quick` compares.
            super::quickstart::run(&root("quickstart"), opts.quick)?;
            sampling(&root("sampling"), false)?;
            let adapter = adapter_preference(opts.adapter.as_deref());
            relief(&root("relief"), false, opts.quick, Some(adapter))?;
            stability(&root("stability"), false)?;
            performance(&opts.options("performance", opts.out.as_deref())?)?;
            let d = opts.options("dynamic", opts.out.as_deref())?;
            super::dynamic::run(&d.out, d.quick, &d.supply, d.allow_nonempty_out)?;
        }
        Command::Plots { names, quick, dir } => plots(&names, quick, dir.as_deref())?,
        Command::Merge { out, shards } => super::merge::merge(&out, &shards)?,
        Command::Named(args) => {
            let name = args.first().cloned().unwrap_or_default();
            let parsed = NamedRun::try_parse_from(
                std::iter::once(format!("experiment {name}")).chain(args.into_iter().skip(1)),
            )
            .unwrap_or_else(|e| e.exit());
            run_one(&discover::find(&name)?, &parsed.opts, None)?;
        }
        Command::Models { command } => return super::models_cmd::run(command),
        Command::Sampling {
            out,
            allow_nonempty_out,
        } => sampling(&out, allow_nonempty_out)?,
    }
    Ok(0)
}
