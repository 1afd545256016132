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
