//! `experiment models`: the real meshes of `data/models.json` (`geometry::models`), which
//! ones this machine has (`list`, `verify`) and how a run that needs a missing one is refused
//! before any work, with the command that fetches it ([`require`]).

use super::spec::{MeshSource, Spec};
use super::{Error, Result};
use crate::geometry::models::{fetch_hint, missing_models};

/// The registered models a spec's scenes name, in order of first use.
pub fn spec_models(spec: &Spec) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for sc in &spec.scenes {
        for inst in &sc.instances {
            if let MeshSource::Model(m) = &inst.mesh {
                if !names.contains(&m.as_str()) {
                    names.push(m);
                }
            }
        }
    }
    names
}

/// Fails, naming `what`, the missing models and the command that fetches them ("figure6:
/// needs stanford-bunny_39k: `experiment models fetch stanford-bunny_39k`"), where a model
/// folder lacks one of `names`; checks file names only, before any work.
pub fn require<'a>(what: &str, names: impl IntoIterator<Item = &'a str>) -> Result<()> {
    let missing = missing_models(names);
    if missing.is_empty() {
        Ok(())
    } else {
        Err(Error::invalid(what, fetch_hint(&missing)))
    }
}

/// `experiment models ...`.
#[derive(clap::Subcommand, Debug)]
pub enum ModelsCommand {
    /// Every registered model: triangles, present / missing / wrong checksum, where, licence.
    List,
    /// Check the sha256 of the models found (all, or the ones named); exit 1 naming each
    /// wrong or missing one.
    Verify {
        /// Models by name (default: every registered model; missing ones are listed, not
        /// failed).
        names: Vec<String>,
    },
    /// Download models from their recorded sources, checked against their sha256, into
    /// $VISFIELD_MODELS, else the per-user data folder, else data/models/.
    Fetch {
        /// Models by name.
        #[arg(required_unless_present = "all")]
        names: Vec<String>,
        /// Every registered model.
        #[arg(long, conflicts_with = "names")]
        all: bool,
        /// The folder to write into (default as above).
        #[arg(long)]
        dir: Option<std::path::PathBuf>,
        /// Ask a mirror instead of the recorded sources: each source URL `https://HOST/PATH`
        /// is asked as `MIRROR/HOST/PATH` (default $VISFIELD_MODELS_MIRROR).
        #[arg(long, value_name = "URL")]
        mirror: Option<String>,
    },
}

/// Where a model stands on this machine.
enum State {
    Present(std::path::PathBuf),
    Missing,
    Wrong {
        path: std::path::PathBuf,
        actual: String,
    },
}

fn state(entry: &crate::geometry::models::ModelEntry) -> Result<State> {
    use crate::geometry::models::{search_dirs, sha256_file_cached};
    for d in search_dirs() {
        let path = d.join(&entry.file);
        if path.is_file() {
            let actual = sha256_file_cached(&path)?;
            return Ok(if actual == entry.sha256 {
                State::Present(path)
            } else {
                State::Wrong { path, actual }
            });
        }
    }
    Ok(State::Missing)
}

fn entries<'a>(names: &[String]) -> Result<Vec<&'a crate::geometry::models::ModelEntry>> {
    let registry = crate::geometry::models::ModelRegistry::embedded();
    if names.is_empty() {
        return Ok(registry.entries.iter().collect());
    }
    names
        .iter()
        .map(|n| Ok(registry.get(n)?))
        .collect::<Result<Vec<_>>>()
}

/// Runs `experiment models ...`; the exit code.
pub fn run(cmd: ModelsCommand) -> Result<i32> {
    match cmd {
        ModelsCommand::List => {
            let all = entries(&[])?;
            let width = all.iter().map(|e| e.name.len()).max().unwrap_or(0);
            for e in all {
                let where_ = match state(e)? {
                    State::Present(p) => format!("present  {}", p.display()),
                    State::Missing => "missing".to_string(),
                    State::Wrong { path, .. } => {
                        format!("WRONG CHECKSUM  {}", path.display())
                    }
                };
                println!("{:<width$}  {:>7} triangles  {where_}", e.name, e.triangles);
                println!("{:<width$}  licence: {}", "", e.licence);
            }
            println!(
                "search order: {}",
                crate::geometry::models::search_dirs()
                    .iter()
                    .map(|d| d.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            Ok(0)
        }
        ModelsCommand::Verify { names } => {
            let named = !names.is_empty();
            let mut bad = 0;
            for e in entries(&names)? {
                match state(e)? {
                    State::Present(p) => println!("ok       {}  {}", e.name, p.display()),
                    State::Missing => {
                        println!(
                            "missing  {}  (`experiment models fetch {}`)",
                            e.name, e.name
                        );
                        bad += usize::from(named);
                    }
                    State::Wrong { path, actual } => {
                        println!(
                            "WRONG    {}  {}: sha256 {actual}, the registry's is {}",
                            e.name,
                            path.display(),
                            e.sha256
                        );
                        bad += 1;
                    }
                }
            }
            Ok(i32::from(bad > 0))
        }
        ModelsCommand::Fetch {
            names,
            all,
            dir,
            mirror,
        } => {
            use super::models_fetch::{mirrored, FetchOptions, MIRROR_ENV};
            let chosen = entries(if all { &[] } else { &names })?;
            let explicit_dir = dir;
            let dir = explicit_dir
                .clone()
                .unwrap_or_else(crate::geometry::models::fetch_dir);
            let (mirror, from) = match mirror {
                Some(m) => (Some(m), "--mirror".to_string()),
                None => (
                    std::env::var(MIRROR_ENV).ok().filter(|m| !m.is_empty()),
                    format!("${MIRROR_ENV}"),
                ),
            };
            // A bad mirror fails before any model, naming where it came from.
            if let Some(m) = &mirror {
                mirrored("https://host/path", m).map_err(|why| Error::invalid(from, why))?;
            }
            let opts = FetchOptions {
                mirror,
                ..FetchOptions::default()
            };
            let mut failed = Vec::new();
            for e in chosen {
                if explicit_dir.is_none() {
                    if let State::Present(p) = state(e)? {
                        println!("present     {}  {}", e.name, p.display());
                        continue;
                    }
                }
                if e.restricted && e.url.is_some() {
                    println!("{}: licence restricts use: {}", e.name, e.licence);
                }
                match super::models_fetch::fetch_model(e, &dir, &opts) {
                    Ok(super::models_fetch::Fetched::Present(p)) => {
                        println!("present     {}  {}", e.name, p.display())
                    }
                    Ok(super::models_fetch::Fetched::Downloaded {
                        path,
                        resumed_from,
                        notes,
                    }) => {
                        for n in notes {
                            println!("note        {}: {n}", e.name);
                        }
                        println!(
                            "downloaded  {}  {}{}",
                            e.name,
                            path.display(),
                            if resumed_from > 0 {
                                format!(" (resumed after {resumed_from} bytes)")
                            } else {
                                String::new()
                            }
                        )
                    }
                    Err(err) => {
                        println!("FAILED      {}: {}", e.name, err.chain());
                        failed.push(e.name.clone());
                    }
                }
            }
            if !failed.is_empty() {
                println!("not fetched: {}", failed.join(", "));
            }
            Ok(i32::from(!failed.is_empty()))
        }
    }
}
