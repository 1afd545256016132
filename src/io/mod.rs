//! Small I/O helpers shared by every module: atomic writes, a lock between processes, hashing
//! and the caches' container.

mod cache;
mod lock;
pub mod places;

pub use cache::{read_cache, write_cache, CacheError, CacheFile};
pub use lock::FileLock;

use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically: the data goes to a temporary file in the same folder,
/// is flushed and synced, then renamed over `path`. A reader never sees a half-written file, and
/// an interrupted write leaves the previous content intact.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir)?;
    let file_name = path
        .file_name()
        .ok_or_else(|| std::io::Error::other(format!("{} has no file name", path.display())))?;
    // Unique to this write: the host, a per-process counter (threads writing the same path)
    // and the process id (processes, the owner test of `remove_stale_temporaries`).
    static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = dir.join(format!(
        ".{}.{}-{n}.tmp-{}",
        file_name.to_string_lossy(),
        host_tag(),
        std::process::id()
    ));
    let written = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    // A failed write (a full disk, a failed rename) leaves no temporary behind.
    written.inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// Whether process `pid` runs (this one, or one with an entry in `/proc`): the owner test of the
/// PID-named leftovers of writes and runs.
pub fn process_alive(pid: u32) -> bool {
    pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists()
}

/// Removes the temporaries of [`write_atomic`] in `dir` (`.NAME.tmp-PID`) whose process no
/// longer runs (a write killed mid-way); returns how many. Temporaries of live processes are
/// kept: they may be writing now.
pub fn remove_stale_temporaries(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = name
            .strip_prefix('.')
            .and_then(|n| n.rsplit_once(".tmp-"))
            .and_then(|(_, pid)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        // A temporary of another host sharing this folder: its process id means nothing here.
        let before = &name[..name.rfind(".tmp-").unwrap_or(0)];
        let other_host = (before.rsplit_once('.'))
            .and_then(|(_, t)| t.rsplit_once('-'))
            .is_some_and(|(h, n)| n.parse::<u64>().is_ok() && h != host_tag());
        if !other_host && !process_alive(pid) && std::fs::remove_file(e.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// This machine's host name as a file-name part (`[A-Za-z0-9_]` only; `host` if unknown).
fn host_tag() -> String {
    let name = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
    let tag: String = (name.trim().chars())
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if tag.is_empty() {
        "host".into()
    } else {
        tag
    }
}

/// Hex-encoded SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::Digest;
    hex(&sha2::Sha256::digest(bytes))
}

/// Hex-encoded SHA-256 and length of a file's bytes, streamed.
pub fn sha256_file(path: &Path) -> std::io::Result<(String, u64)> {
    use sha2::Digest;
    let mut hasher = sha2::Sha256::new();
    let bytes = std::io::copy(&mut std::fs::File::open(path)?, &mut hasher)?;
    Ok((hex(&hasher.finalize()), bytes))
}

/// `bytes` as lower-case hex, two digits a byte.
pub(crate) fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_of_abc_matches_fips_180_2() {
        // FIPS 180-2, appendix B.1.
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn stale_temporaries_of_dead_writers_are_removed_and_live_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        // PID 0 is never a user process (no /proc/0); this process is alive.
        let dead = dir.path().join(".field.vfield.tmp-0");
        let live = dir
            .path()
            .join(format!(".other.vfield.tmp-{}", std::process::id()));
        let kept = dir.path().join("field.vfield");
        // A dead writer's temporary as written now (host-tagged), and one of another host,
        // whose process id cannot be judged here.
        let dead_tagged = dir.path().join(format!(".f.vfield.{}-3.tmp-0", host_tag()));
        let other = dir.path().join(".f.vfield.elsewhere_x-3.tmp-0");
        for p in [&dead, &live, &kept, &dead_tagged, &other] {
            std::fs::write(p, b"x").unwrap();
        }
        assert_eq!(remove_stale_temporaries(dir.path()), 2);
        assert!(!dead.exists() && live.exists() && kept.exists());
        assert!(!dead_tagged.exists() && other.exists());
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "a temporary file was left behind");
    }
}
