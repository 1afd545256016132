//! Run metadata written beside every result: commit, machine, CPU, threads, GPU adapter, date.

use serde::{Deserialize, Serialize};

/// What made a result.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunMeta {
    /// `git rev-parse HEAD`, with "-dirty" when the tree has uncommitted changes to tracked files
    /// outside `results/` (the outputs of earlier runs do not change what the code computes);
    /// without git, `$VISFIELD_COMMIT`, else "unknown".
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
    /// The command line.
    pub command: String,
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
            command: std::env::args().collect::<Vec<_>>().join(" "),
            load_average: std::fs::read_to_string("/proc/loadavg")
                .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
                .unwrap_or_else(|_| "unknown".into()),
        }
    }

    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("metadata serialises")
    }
}

fn git_commit() -> String {
    let run = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match run(&["rev-parse", "HEAD"]) {
        Some(c) => {
            let dirty = run(&[
                "status",
                "--porcelain",
                "--untracked-files=no",
                "--",
                ".",
                ":(exclude)results",
            ])
            .is_some_and(|s| !s.is_empty());
            if dirty {
                format!("{c}-dirty")
            } else {
                c
            }
        }
        // A copy of the tree without its git history (another machine's run of a packed build,
        // `scripts/device_pack.sh`) names its commit through the environment.
        None => std::env::var("VISFIELD_COMMIT").unwrap_or_else(|_| "unknown".into()),
    }
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
    fn utc_formatting_matches_known_instants() {
        assert_eq!(format_utc(0), "1970-01-01T00:00:00Z");
        // 2000-02-29 (a leap day) 12:34:56 UTC.
        assert_eq!(format_utc(951_827_696), "2000-02-29T12:34:56Z");
        // 2026-11-23 00:00:00 UTC = 20,780 days after the epoch.
        assert_eq!(format_utc(20_780 * 86_400), "2026-11-23T00:00:00Z");
    }
}
