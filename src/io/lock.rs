//! An exclusive lock between processes (and between threads of one process): `flock(2)` on a
//! lock file, the file removed by its holder when it lets go.
//!
//! Removing a lock file is safe only with a check after locking: a waiter that opened the file
//! before its holder removed it would otherwise lock the removed file while a third process
//! locks a new one. So a lock, once taken, is kept only while the path still names the locked
//! file (same device and inode); else the waiter opens the path again. A holder killed mid-way
//! leaves its file behind but no lock (the kernel drops a dead process's locks): the next taker
//! locks the file, uses it and removes it.

use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::os::unix::fs::MetadataExt;
use std::os::unix::io::AsRawFd;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// An exclusive lock on the file at `path`, held until dropped (the file is then removed).
#[derive(Debug)]
pub struct FileLock {
    path: PathBuf,
    // Closed after `drop` removed the path: the lock goes with the descriptor.
    _file: File,
}

impl FileLock {
    /// Takes the lock at `path` (creating the file), waiting up to `wait` while another holds it.
    /// On timeout: an error of kind `WouldBlock` naming the path and the holder's process id
    /// (which the holder writes into the file).
    pub fn acquire(path: &Path, wait: Duration) -> std::io::Result<FileLock> {
        let deadline = Instant::now() + wait;
        loop {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(path)?;
            if try_lock(&file)? {
                let held = file.metadata()?;
                let named = std::fs::metadata(path).ok();
                if named.is_some_and(|m| m.dev() == held.dev() && m.ino() == held.ino()) {
                    file.set_len(0)?;
                    file.write_all(std::process::id().to_string().as_bytes())?;
                    return Ok(FileLock {
                        path: path.to_path_buf(),
                        _file: file,
                    });
                }
                // The holder removed the file between our open and our lock: open it anew.
                continue;
            }
            if Instant::now() >= deadline {
                let mut holder = String::new();
                let _ = file.read_to_string(&mut holder);
                let holder = match holder.trim() {
                    "" => "another process".to_string(),
                    pid => format!("process {pid}"),
                };
                return Err(std::io::Error::new(
                    std::io::ErrorKind::WouldBlock,
                    format!(
                        "{} is held by {holder} (waited {:.0} s)",
                        path.display(),
                        wait.as_secs_f64()
                    ),
                ));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for FileLock {
    fn drop(&mut self) {
        // Removed while still locked; the descriptor (and the lock) goes after this.
        let _ = std::fs::remove_file(&self.path);
    }
}

/// `flock(LOCK_EX | LOCK_NB)`: whether `file` is now locked by this descriptor.
fn try_lock(file: &File) -> std::io::Result<bool> {
    loop {
        // SAFETY: flock on a descriptor `file` owns and keeps open for the call.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } == 0 {
            return Ok(true);
        }
        let e = std::io::Error::last_os_error();
        match e.raw_os_error() {
            Some(libc::EWOULDBLOCK) => return Ok(false),
            Some(libc::EINTR) => continue,
            _ => return Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_taker_waits_for_the_first_and_times_out_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(".out.lock");
        let first = FileLock::acquire(&path, Duration::ZERO).unwrap();
        // Another descriptor (another thread or process) cannot take it meanwhile.
        let e = FileLock::acquire(&path, Duration::from_millis(100)).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::WouldBlock);
        let msg = e.to_string();
        assert!(
            msg.contains(&format!("process {}", std::process::id())),
            "{msg}"
        );
        // A waiter gets it once the holder lets go, though the holder removed the file.
        let (tx, rx) = std::sync::mpsc::channel();
        let p = path.clone();
        let waiter = std::thread::spawn(move || {
            let l = FileLock::acquire(&p, Duration::from_secs(20)).unwrap();
            tx.send(()).unwrap();
            drop(l);
        });
        assert!(
            rx.recv_timeout(Duration::from_millis(200)).is_err(),
            "taken while held"
        );
        drop(first);
        rx.recv_timeout(Duration::from_secs(20))
            .expect("the waiter took the lock");
        waiter.join().unwrap();
        assert!(
            !path.exists(),
            "the lock file is removed by its last holder"
        );
    }

    #[test]
    fn a_lock_file_left_by_a_dead_holder_is_free() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(".out.lock");
        std::fs::write(&path, "0").unwrap();
        drop(FileLock::acquire(&path, Duration::ZERO).unwrap());
        assert!(!path.exists());
    }
}
