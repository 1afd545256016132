//! Where the program keeps its files, found from where it runs, never from where it was built
//! (a binary built in one checkout and run from another, or installed with `cargo install`,
//! works in the folder it is run from):
//!
//! - the **project**: the nearest folder, from the current directory up, that holds an
//!   `experiments/` folder ([`project_dir`]); its `cache/`, `experiments/` and `data/models/`;
//! - the **per-user data folder** ([`user_data_dir`]): `$XDG_DATA_HOME/visfield`, else
//!   `~/.local/share/visfield` (`%APPDATA%\visfield` on Windows), where no project holds it.

use std::path::{Path, PathBuf};

/// The folder a project keeps its specs in; the one that marks a folder as a project.
pub const PROJECT_MARK: &str = "experiments";

/// The nearest folder holding `experiments/`, from the current directory up; none outside a
/// project (or where the current directory cannot be read).
pub fn project_dir() -> Option<PathBuf> {
    let cwd = std::env::current_dir().ok()?;
    project_dir_from(&cwd)
}

/// [`project_dir`] from a given folder.
pub fn project_dir_from(start: &Path) -> Option<PathBuf> {
    start
        .ancestors()
        .find(|d| d.join(PROJECT_MARK).is_dir())
        .map(Path::to_path_buf)
}

/// The per-user data folder: `$XDG_DATA_HOME/visfield`, else `$HOME/.local/share/visfield`
/// (`%APPDATA%\visfield` on Windows); none when none of those variables is set to an absolute
/// path.
pub fn user_data_dir() -> Option<PathBuf> {
    let var = |name: &str| {
        std::env::var_os(name)
            .map(PathBuf::from)
            .filter(|p| p.is_absolute())
    };
    let base = if cfg!(windows) {
        var("APPDATA")
    } else {
        var("XDG_DATA_HOME").or_else(|| var("HOME").map(|h| h.join(".local/share")))
    };
    base.map(|b| b.join("visfield"))
}

/// `sub` of the project, else of the per-user data folder, else `sub` relative to the current
/// directory: where a default folder (the field cache) goes.
pub fn project_or_user(sub: &str) -> PathBuf {
    project_dir()
        .or_else(user_data_dir)
        .map_or_else(|| PathBuf::from(sub), |d| d.join(sub))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The nearest folder holding `experiments/` wins, from any depth below it; a folder
    /// without one above it has none of its own.
    #[test]
    fn the_project_is_the_nearest_folder_holding_experiments() {
        let t = tempfile::tempdir().unwrap();
        let outer = t.path().join("outer");
        let inner = outer.join("a/inner");
        let deep = inner.join("b/c");
        std::fs::create_dir_all(&deep).unwrap();
        // Whatever holds the temporary folder (normally no project).
        let above = project_dir_from(t.path());
        assert_eq!(project_dir_from(&deep), above);
        std::fs::create_dir_all(outer.join(PROJECT_MARK)).unwrap();
        assert_eq!(project_dir_from(&deep), Some(outer.clone()));
        std::fs::create_dir_all(inner.join(PROJECT_MARK)).unwrap();
        assert_eq!(project_dir_from(&deep), Some(inner.clone()));
        assert_eq!(project_dir_from(&inner), Some(inner));
        // A file of that name does not make a project.
        let file = t.path().join("f");
        std::fs::create_dir_all(&file).unwrap();
        std::fs::write(file.join(PROJECT_MARK), b"").unwrap();
        assert_eq!(project_dir_from(&file), above);
    }
}
