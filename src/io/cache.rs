//! The container of the on-disk caches (fields, distance volumes, AO fields, truths): `magic`
//! (8 bytes), `version` (u32 LE), the header's length (u32 LE), the header as JSON, the payload.
//! Every reader checks the magic, the version, the header and, through the header's record of
//! them, the payload's length and SHA-256; each failure names the file.

use std::path::{Path, PathBuf};

/// Why a cache file was not used.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Not such a file, cut short, or its bytes are not what its header says.
    #[error("{path}: {reason}")]
    Corrupt { path: PathBuf, reason: String },
    /// A sound file of another format version or another key.
    #[error("{path}: stale cache ({reason})")]
    Stale { path: PathBuf, reason: String },
}

impl CacheError {
    /// `path` could not be read or written.
    pub fn io(path: &Path) -> impl FnOnce(std::io::Error) -> CacheError + '_ {
        move |source| CacheError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// `path` is damaged: `reason` says how.
    pub fn corrupt(path: &Path, reason: impl Into<String>) -> CacheError {
        CacheError::Corrupt {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }

    /// `path` is sound but was written for something else: `reason` says what differs.
    pub fn stale(path: &Path, reason: impl Into<String>) -> CacheError {
        CacheError::Stale {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }
}

/// A cache file read whole: its header, and its payload once [`CacheFile::payload`] has checked
/// it against the header's record.
#[derive(Debug)]
pub struct CacheFile<H> {
    /// The header, as written.
    pub header: H,
    path: PathBuf,
    bytes: Vec<u8>,
    payload_at: usize,
}

impl<H> CacheFile<H> {
    /// The payload, when it has the `len` bytes and the SHA-256 `sha256` the header records.
    pub fn payload(&self, len: u64, sha256: &str) -> Result<&[u8], CacheError> {
        let payload = &self.bytes[self.payload_at..];
        if payload.len() as u64 != len {
            return Err(self.corrupt(format!(
                "truncated payload: {} of {len} bytes",
                payload.len()
            )));
        }
        if super::sha256_hex(payload) != sha256 {
            return Err(self.corrupt("payload checksum mismatch"));
        }
        Ok(payload)
    }

    /// The file is damaged: `reason` says how.
    pub fn corrupt(&self, reason: impl Into<String>) -> CacheError {
        CacheError::corrupt(&self.path, reason)
    }

    /// The file is sound but was written for something else.
    pub fn stale(&self, reason: impl Into<String>) -> CacheError {
        CacheError::stale(&self.path, reason)
    }
}

/// Writes `header` (as JSON) and `payload` to `path` in the container, atomically.
pub fn write_cache(
    path: &Path,
    magic: &[u8; 8],
    version: u32,
    header: &impl serde::Serialize,
    payload: &[u8],
) -> Result<(), CacheError> {
    let h = serde_json::to_vec(header).expect("a cache header serialises");
    let mut out = Vec::with_capacity(16 + h.len() + payload.len());
    out.extend_from_slice(magic);
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&(h.len() as u32).to_le_bytes());
    out.extend_from_slice(&h);
    out.extend_from_slice(payload);
    super::write_atomic(path, &out).map_err(CacheError::io(path))
}

/// Reads the container at `path`: checks the magic (`what` names the file kind in the
/// message), the version and the header. The payload is checked by [`CacheFile::payload`].
pub fn read_cache<H: serde::de::DeserializeOwned>(
    path: &Path,
    magic: &[u8; 8],
    version: u32,
    what: &str,
) -> Result<CacheFile<H>, CacheError> {
    let bytes = std::fs::read(path).map_err(CacheError::io(path))?;
    if bytes.len() < 16 || &bytes[..8] != magic {
        return Err(CacheError::corrupt(
            path,
            format!("not a {what} file (bad magic or truncated)"),
        ));
    }
    let found = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if found != version {
        return Err(CacheError::stale(
            path,
            format!("format version {found}, this build reads {version}"),
        ));
    }
    let hlen = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes")) as usize;
    let end = 16usize
        .checked_add(hlen)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| {
            CacheError::corrupt(
                path,
                format!("truncated header ({} bytes in file)", bytes.len()),
            )
        })?;
    let header = serde_json::from_slice(&bytes[16..end])
        .map_err(|e| CacheError::corrupt(path, format!("unreadable header: {e}")))?;
    Ok(CacheFile {
        header,
        path: path.to_path_buf(),
        bytes,
        payload_at: end,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cache_files_round_trip_and_damage_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.test");
        let payload = b"payload";
        let sha = crate::io::sha256_hex(payload);
        write_cache(&path, b"VFTEST01", 2, &serde_json::json!({"n": 3}), payload).unwrap();
        let read = |v| read_cache::<serde_json::Value>(&path, b"VFTEST01", v, "test");
        let file = read(2).unwrap();
        assert_eq!(file.header["n"].as_u64(), Some(3));
        assert_eq!(file.payload(7, &sha).unwrap(), &payload[..]);
        assert!(matches!(
            file.payload(8, &sha),
            Err(CacheError::Corrupt { .. })
        ));
        let other = crate::io::sha256_hex(b"paylxad");
        assert!(matches!(
            file.payload(7, &other),
            Err(CacheError::Corrupt { .. })
        ));
        assert!(matches!(read(3), Err(CacheError::Stale { .. })));

        let bytes = std::fs::read(&path).unwrap();
        for cut in [5, 20] {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            assert!(matches!(read(2), Err(CacheError::Corrupt { .. })), "{cut}");
        }
        let mut bad = bytes.clone();
        bad[0] = b'X';
        std::fs::write(&path, &bad).unwrap();
        let err = read(2).unwrap_err().to_string();
        assert_eq!(
            err,
            format!(
                "{}: not a test file (bad magic or truncated)",
                path.display()
            )
        );
        std::fs::remove_file(&path).unwrap();
        assert!(matches!(read(2), Err(CacheError::Io { .. })));
    }
}
