//! Run metadata written beside every result: commit, machine, CPU, threads, GPU adapter, date,
//! the command line and the wall times. Paths are recorded relative to the crate (or `~`), never
//! as one machine's absolute folders ([`portable_path`]).

use super::progress::StageTime;
use serde::{Deserialize, Serialize};
use std::path::{Component, Path, PathBuf};

/// What made a result.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunMeta {
    /// The commit the binary was built from ([`BUILD_COMMIT`], captured at build time): `git
    /// rev-parse HEAD`, with "-dirty" when a tracked file the binary is built from (`src/`,
    /// `shaders/`, `assets/`, `data/`, `Cargo.toml`, `Cargo.lock`, `build.rs`) had uncommitted
    /// changes (docs, tests and the outputs of earlier runs do not change what the code
    /// computes; a spec is recorded by its sha256); without git, `$VISFIELD_COMMIT`, else
    /// "unknown".
    pub commit: String,
    /// Host name.
    pub machine: String,
    /// CPU model name (from /proc/cpuinfo).
    pub cpu: String,
    /// Logical CPUs of the machine.
    pub cpus: usize,
    /// Worker threads used (rayon).
    pub threads: usize,
    /// GPU adapter and driver, when a GPU backend ran.
    pub gpu_adapter: Option<String>,
    /// UTC date and time, ISO 8601.
    pub date: String,
    /// Crate version.
    pub version: String,
    /// sha256 of the spec text (when a spec made the result).
    pub spec_sha256: Option<String>,
    /// The command line: the binary by its file name, absolute paths as [`portable_path`]
    /// writes them.
    pub command: String,
    /// Seconds from the run's start to this record ([`RunMeta::timed`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_s: Option<f64>,
    /// Each timed stage of the run, in order, with its wall time (repeats included).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stages: Vec<StageTime>,
    /// 1, 5 and 15 minute load averages when the run started (from /proc/loadavg): timings
    /// taken on a loaded machine are slower and noisier.
    #[serde(default)]
    pub load_average: String,
}

impl RunMeta {
    /// Collects the metadata of this process.
    pub fn collect(spec_text: Option<&str>) -> RunMeta {
        RunMeta {
            commit: git_commit(),
            machine: std::fs::read_to_string("/etc/hostname")
                .map(|s| s.trim().to_string())
                .unwrap_or_else(|_| "unknown".into()),
            cpu: cpu_model(),
            cpus: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            threads: rayon::current_num_threads(),
            gpu_adapter: None,
            date: utc_now_iso8601(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            spec_sha256: spec_text.map(|t| crate::io::sha256_hex(t.as_bytes())),
            command: portable_command(std::env::args()),
            wall_s: None,
            stages: Vec::new(),
            load_average: std::fs::read_to_string("/proc/loadavg")
                .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
                .unwrap_or_else(|_| "unknown".into()),
        }
    }

    /// With the wall time of the run begun on this thread (`progress::begin_run`) and its stages
    /// so far.
    pub fn timed(mut self) -> RunMeta {
        if let Some((wall_s, stages)) = super::progress::run_times() {
            self.wall_s = Some(wall_s);
            self.stages = stages;
        }
        self
    }

    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("metadata serialises")
    }
}

/// `path` as a result records it: relative to the project the program runs in (the nearest
/// folder holding `experiments/`, else the current directory) when inside it (`cache`,
/// `experiments/figure6.json`), `~/...` when under the home folder, else relative to the
/// project through `..`; never absolute, so committed outputs name no machine's folders.
pub fn portable_path(path: &Path) -> String {
    let root = crate::io::places::project_dir()
        .or_else(|| std::env::current_dir().ok())
        .unwrap_or_default();
    portable_path_from(path, &root, home().as_deref())
}

fn home() -> Option<PathBuf> {
    std::env::var_os("HOME")
        .map(PathBuf::from)
        .filter(|h| h.is_absolute())
}

/// [`portable_path`] against a given project folder and home folder.
pub fn portable_path_from(path: &Path, root: &Path, home: Option<&Path>) -> String {
    let norm = |p: &Path| -> PathBuf {
        let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let mut out = PathBuf::new();
        for c in abs.components() {
            match c {
                Component::CurDir => {}
                Component::ParentDir => {
                    out.pop();
                }
                c => out.push(c),
            }
        }
        out
    };
    let (path, root) = (norm(path), norm(root));
    let text = |p: &Path| p.to_string_lossy().replace('\\', "/");
    if let Ok(rel) = path.strip_prefix(&root) {
        return if rel.as_os_str().is_empty() {
            ".".to_string()
        } else {
            text(rel)
        };
    }
    if let Some(rel) = home
        .map(norm)
        .and_then(|h| path.strip_prefix(&h).ok().map(PathBuf::from))
    {
        return format!("~/{}", text(&rel));
    }
    let (p, r): (Vec<_>, Vec<_>) = (path.components().collect(), root.components().collect());
    let common = p.iter().zip(&r).take_while(|(a, b)| a == b).count();
    let mut rel = PathBuf::new();
    for _ in common..r.len() {
        rel.push("..");
    }
    for c in &p[common..] {
        rel.push(c);
    }
    text(&rel)
}

/// The command line as a result records it: the binary by its file name, each absolute path
/// (also as `--flag=/path`) through [`portable_path`].
pub fn portable_command(args: impl IntoIterator<Item = String>) -> String {
    let one = |a: &str| -> String {
        if Path::new(a).is_absolute() {
            portable_path(Path::new(a))
        } else {
            a.to_string()
        }
    };
    args.into_iter()
        .enumerate()
        .map(|(i, a)| {
            if i == 0 {
                Path::new(&a)
                    .file_name()
                    .map_or(a.clone(), |n| n.to_string_lossy().into_owned())
            } else if let Some((flag, value)) =
                a.split_once('=').filter(|(f, _)| f.starts_with("--"))
            {
                format!("{flag}={}", one(value))
            } else {
                one(&a)
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The commit this binary was built from, with `-dirty` where a tracked file it is built from
/// (its sources, shaders and the files they embed) differed from it, as the build script
/// (`build.rs`) found it; "unknown" where it was built without git and without
/// `$VISFIELD_COMMIT`.
pub const BUILD_COMMIT: &str = env!("VISFIELD_BUILD_COMMIT");

/// [`BUILD_COMMIT`]: the code that runs, wherever it runs (never the state of a checkout at run
/// time). Where the build knew no commit, `$VISFIELD_COMMIT` at run time names it (a copy of
/// the tree without its git history, `scripts/device_pack.sh`), else "unknown".
fn git_commit() -> String {
    if BUILD_COMMIT != "unknown" {
        return BUILD_COMMIT.to_string();
    }
    std::env::var("VISFIELD_COMMIT").unwrap_or_else(|_| "unknown".into())
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

/// The current UTC time as `YYYY-MM-DDTHH:MM:SSZ`.
pub fn utc_now_iso8601() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    format_utc(secs)
}

/// Seconds since the Unix epoch → `YYYY-MM-DDTHH:MM:SSZ` (proleptic Gregorian; Hinnant's
/// days-to-civil algorithm).
pub fn format_utc(secs: i64) -> String {
    let days = secs.div_euclid(86_400);
    let rem = secs.rem_euclid(86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        (rem % 3600) / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_are_recorded_relative_to_the_crate_or_home_never_absolute() {
        let root = Path::new("/srv/x/visfield");
        let home = Some(Path::new("/home/u"));
        let p = |s: &str| portable_path_from(Path::new(s), root, home);
        assert_eq!(p("/srv/x/visfield/cache"), "cache");
        assert_eq!(p("/srv/x/visfield/./results/../cache/f"), "cache/f");
        assert_eq!(p("/srv/x/visfield"), ".");
        assert_eq!(
            p("/home/u/.local/share/visfield/models"),
            "~/.local/share/visfield/models"
        );
        assert_eq!(p("/tmp/out"), "../../../tmp/out");
        assert_eq!(p("/srv/y"), "../../y");
        let c = portable_command(
            [
                "/opt/bin/experiment",
                "figure6",
                "--out",
                "/tmp/o",
                "--cache=/tmp/c",
            ]
            .map(String::from),
        );
        assert!(c.starts_with("experiment figure6 --out "), "{c}");
        assert!(!c.contains(" /") && !c.contains("=/"), "{c}");
    }

    #[test]
    fn utc_formatting_matches_known_instants() {
        assert_eq!(format_utc(0), "1970-01-01T00:00:00Z");
        // 2000-02-29 (a leap day) 12:34:56 UTC.
        assert_eq!(format_utc(951_827_696), "2000-02-29T12:34:56Z");
        // 2026-11-23 00:00:00 UTC = 20,780 days after the epoch.
        assert_eq!(format_utc(20_780 * 86_400), "2026-11-23T00:00:00Z");
    }
}
