//! `experiment models fetch`: one registered model downloaded from the `url` recorded in
//! `data/models.json` (the source commit's raw file, or a member of a zip archive there),
//! checked against its sha256 and moved into the models folder only when it matches.
//!
//! The rules (each tested in `tests/models_fetch.rs` against a server on 127.0.0.1):
//! - **Nothing half written.** Bytes arrive in `DIR/.FILE.part` (the archive's name for a
//!   zipped model); the model's own file appears, by a rename or an atomic write, only once its
//!   sha256 is the registry's. A file already in place is never touched unless a verified copy
//!   replaces it, so a good file is never overwritten by a bad one.
//! - **Resumable.** A transfer that ends early (a dropped connection, a stalled server past the
//!   timeout) keeps its `.part`; the next fetch asks for the rest (`Range: bytes=N-`) and
//!   appends it when the server answers 206, or starts again when it answers 200. A resumed
//!   download is checked against the same sha256 as a whole one.
//! - **Checksums refused.** Complete bytes whose sha256 differs from the registry's are deleted
//!   (resuming from them could only repeat the error) and the fetch fails naming both hashes.
//! - **Bounded.** The server may not send more than the registry's size; a stalled or slow
//!   transfer ends at the body deadline ([`FetchOptions`]).

use super::{Error, Result};
use crate::geometry::models::ModelEntry;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How a fetch talks to the server.
#[derive(Clone, Debug)]
pub struct FetchOptions {
    /// Connecting and waiting for the response's head.
    pub timeout: Duration,
    /// The lowest transfer rate a body is given time for: the body's deadline is
    /// `timeout + bytes / min_rate` (so a stalled server ends, a large file on a slow line does
    /// not).
    pub min_bytes_per_s: u64,
    /// Draw a progress bar (only shown where stderr is a terminal).
    pub progress: bool,
}

impl Default for FetchOptions {
    fn default() -> FetchOptions {
        FetchOptions {
            timeout: Duration::from_secs(30),
            min_bytes_per_s: 20 * 1024,
            progress: true,
        }
    }
}

/// What a fetch did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Fetched {
    /// The models folder already held the file with the registry's sha256.
    Present(PathBuf),
    /// Downloaded (and extracted) into the folder; `resumed_from` bytes came from an earlier
    /// `.part`.
    Downloaded { path: PathBuf, resumed_from: u64 },
}

/// Fetches `entry` into `dir` (see the module docs); `dir` is made if missing.
pub fn fetch_model(entry: &ModelEntry, dir: &Path, opts: &FetchOptions) -> Result<Fetched> {
    let what = format!("model `{}`", entry.name);
    let target = dir.join(&entry.file);
    if target.is_file() {
        let bytes = std::fs::read(&target).map_err(Error::io(&target))?;
        if crate::io::sha256_hex(&bytes) == entry.sha256 {
            return Ok(Fetched::Present(target));
        }
        eprintln!(
            "{}: sha256 is not the registry's; it is replaced only by a verified copy",
            target.display()
        );
    }
    let Some(url) = &entry.url else {
        let how = entry
            .derived
            .as_deref()
            .unwrap_or("no source URL is recorded");
        return Err(Error::invalid(
            what,
            format!(
                "no public source holds {} (derived by us: {how}); copy it from a machine that \
                 has it into {} or a folder named by $VISFIELD_MODELS",
                entry.file,
                dir.display()
            ),
        ));
    };
    std::fs::create_dir_all(dir).map_err(Error::io(dir))?;
    match &entry.member {
        None => {
            let part = dir.join(format!(".{}.part", entry.file));
            let resumed_from = download(url, &part, entry.bytes, &entry.sha256, &what, opts)?;
            std::fs::rename(&part, &target).map_err(Error::io(&target))?;
            Ok(Fetched::Downloaded {
                path: target,
                resumed_from,
            })
        }
        Some(member) => {
            let (Some(archive_sha), Some(archive_bytes)) =
                (&entry.archive_sha256, entry.archive_bytes)
            else {
                return Err(Error::invalid(
                    what,
                    "`member` needs `archive_sha256` and `archive_bytes` in data/models.json",
                ));
            };
            let archive = url.rsplit('/').next().unwrap_or("archive");
            let part = dir.join(format!(".{archive}.part"));
            let resumed_from = download(url, &part, archive_bytes, archive_sha, &what, opts)?;
            let zip = std::fs::read(&part).map_err(Error::io(&part))?;
            let bytes = zip_member(&zip, member)
                .map_err(|m| Error::invalid(format!("{what}: {url}"), m))?;
            let actual = crate::io::sha256_hex(&bytes);
            if actual != entry.sha256 {
                return Err(Error::invalid(
                    format!("{what}: {url} member {member}"),
                    format!(
                        "sha256 {actual}, the registry's is {}: refused, nothing written",
                        entry.sha256
                    ),
                ));
            }
            crate::io::write_atomic(&target, &bytes).map_err(Error::io(&target))?;
            std::fs::remove_file(&part).map_err(Error::io(&part))?;
            Ok(Fetched::Downloaded {
                path: target,
                resumed_from,
            })
        }
    }
}

/// Downloads `url` into `part` until it holds `bytes` bytes whose sha256 is `sha256`, resuming
/// from what `part` already holds; returns how many bytes were resumed from.
fn download(
    url: &str,
    part: &Path,
    bytes: u64,
    sha256: &str,
    what: &str,
    opts: &FetchOptions,
) -> Result<u64> {
    let at = |m: String| Error::invalid(format!("{what}: {url}"), m);
    let mut have = std::fs::metadata(part).map(|m| m.len()).unwrap_or(0);
    if have > bytes {
        std::fs::remove_file(part).map_err(Error::io(part))?;
        have = 0;
    }
    let resumed_from = have;
    if have < bytes {
        let body_deadline =
            opts.timeout + Duration::from_secs_f64(bytes as f64 / opts.min_bytes_per_s as f64);
        let loopback = url.starts_with("http://127.0.0.1:") || url.starts_with("http://[::1]:");
        let mut config = ureq::Agent::config_builder()
            .timeout_connect(Some(opts.timeout))
            .timeout_recv_response(Some(opts.timeout))
            .timeout_recv_body(Some(body_deadline))
            .http_status_as_error(false);
        if loopback {
            config = config.proxy(None);
        }
        let agent: ureq::Agent = config.build().into();
        let mut request = agent.get(url);
        if have > 0 {
            request = request.header("Range", format!("bytes={have}-"));
        }
        let response = request.call().map_err(|e| at(e.to_string()))?;
        let status = response.status().as_u16();
        let append = match status {
            206 if have > 0 => true,
            200 => false,
            _ => {
                return Err(at(format!(
                    "HTTP {status}{}",
                    if have > 0 {
                        format!(" (the {have} bytes of {} are kept)", part.display())
                    } else {
                        String::new()
                    }
                )))
            }
        };
        if !append {
            have = 0;
        }
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .write(true)
            .append(append)
            .truncate(!append)
            .open(part)
            .map_err(Error::io(part))?;
        let bar = opts.progress.then(|| {
            let b = super::progress::bar(bytes, what);
            b.set_position(have);
            b
        });
        let mut reader = response.into_body().into_reader();
        let mut buf = vec![0u8; 1 << 16];
        let outcome = loop {
            match reader.read(&mut buf) {
                Ok(0) => break Ok(()),
                Ok(n) => {
                    if have + n as u64 > bytes {
                        break Err(format!(
                            "the server sent more than the registry's {bytes} bytes"
                        ));
                    }
                    if let Err(e) = file.write_all(&buf[..n]) {
                        break Err(format!("{}: {e}", part.display()));
                    }
                    have += n as u64;
                    if let Some(b) = &bar {
                        b.set_position(have);
                    }
                }
                Err(e) => break Err(e.to_string()),
            }
        };
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        file.sync_all().map_err(Error::io(part))?;
        drop(file);
        if let Err(m) = outcome {
            if m.contains("more than") {
                std::fs::remove_file(part).map_err(Error::io(part))?;
                return Err(at(format!("{m}: refused, nothing written")));
            }
            return Err(at(format!(
                "transfer ended after {have} of {bytes} bytes ({m}); `experiment models fetch` \
                 again resumes from {}",
                part.display()
            )));
        }
        if have < bytes {
            return Err(at(format!(
                "transfer ended after {have} of {bytes} bytes; `experiment models fetch` again \
                 resumes from {}",
                part.display()
            )));
        }
    }
    let got = std::fs::read(part).map_err(Error::io(part))?;
    let actual = crate::io::sha256_hex(&got);
    if actual != sha256 {
        std::fs::remove_file(part).map_err(Error::io(part))?;
        return Err(at(format!(
            "sha256 {actual}, the registry's is {sha256}: refused, nothing written"
        )));
    }
    Ok(resumed_from)
}

/// The bytes of `name` in the zip archive `zip` (stored or deflated; through the central
/// directory, so sizes come from it even where the local header defers them).
fn zip_member(zip: &[u8], name: &str) -> std::result::Result<Vec<u8>, String> {
    let u16_at = |i: usize| -> Option<usize> {
        zip.get(i..i + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]) as usize)
    };
    let u32_at = |i: usize| -> Option<usize> {
        zip.get(i..i + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let bad = || "not a zip archive this reader understands".to_string();
    // The end of central directory record: the last "PK\x05\x06".
    let eocd = (0..zip.len().saturating_sub(21))
        .rev()
        .find(|&i| zip[i..].starts_with(b"PK\x05\x06"))
        .ok_or_else(bad)?;
    let entries = u16_at(eocd + 10).ok_or_else(bad)?;
    let mut at = u32_at(eocd + 16).ok_or_else(bad)?;
    for _ in 0..entries {
        if !zip.get(at..).is_some_and(|z| z.starts_with(b"PK\x01\x02")) {
            return Err(bad());
        }
        let method = u16_at(at + 10).ok_or_else(bad)?;
        let packed = u32_at(at + 20).ok_or_else(bad)?;
        let size = u32_at(at + 24).ok_or_else(bad)?;
        let name_len = u16_at(at + 28).ok_or_else(bad)?;
        let extra_len = u16_at(at + 30).ok_or_else(bad)?;
        let comment_len = u16_at(at + 32).ok_or_else(bad)?;
        let local = u32_at(at + 42).ok_or_else(bad)?;
        let this = zip.get(at + 46..at + 46 + name_len).ok_or_else(bad)?;
        if this == name.as_bytes() {
            let data = local
                + 30
                + u16_at(local + 26).ok_or_else(bad)?
                + u16_at(local + 28).ok_or_else(bad)?;
            let raw = zip.get(data..data + packed).ok_or_else(bad)?;
            let out = match method {
                0 => raw.to_vec(),
                8 => miniz_oxide::inflate::decompress_to_vec_with_limit(raw, size)
                    .map_err(|e| format!("{name}: cannot inflate: {e:?}"))?,
                m => return Err(format!("{name}: compression method {m} is not supported")),
            };
            if out.len() != size {
                return Err(format!(
                    "{name}: {} bytes, the archive says {size}",
                    out.len()
                ));
            }
            return Ok(out);
        }
        at += 46 + name_len + extra_len + comment_len;
    }
    Err(format!("no member `{name}`"))
}

#[cfg(test)]
mod tests {
    use super::zip_member;

    /// sponza.zip's layout in miniature: one stored and one deflated member, found through the
    /// central directory and returned byte for byte.
    #[test]
    fn zip_members_stored_and_deflated_come_back_whole() {
        let stored = b"v 0 0 0\n".to_vec();
        let text: Vec<u8> = (0..5000)
            .flat_map(|i| format!("v {i} 1 2\n").into_bytes())
            .collect();
        let deflated = miniz_oxide::deflate::compress_to_vec(&text, 6);
        let mut zip = Vec::new();
        let mut central = Vec::new();
        for (name, method, raw, size) in [
            ("a.obj", 0u16, &stored, stored.len()),
            ("b.obj", 8u16, &deflated, text.len()),
        ] {
            let local = zip.len() as u32;
            zip.extend_from_slice(b"PK\x03\x04");
            zip.extend_from_slice(&[20, 0, 0, 0]);
            zip.extend_from_slice(&method.to_le_bytes());
            zip.extend_from_slice(&[0; 8]); // time, date, crc
            zip.extend_from_slice(&(raw.len() as u32).to_le_bytes());
            zip.extend_from_slice(&(size as u32).to_le_bytes());
            zip.extend_from_slice(&(name.len() as u16).to_le_bytes());
            zip.extend_from_slice(&0u16.to_le_bytes());
            zip.extend_from_slice(name.as_bytes());
            zip.extend_from_slice(raw);
            central.extend_from_slice(b"PK\x01\x02");
            central.extend_from_slice(&[20, 0, 20, 0, 0, 0]);
            central.extend_from_slice(&method.to_le_bytes());
            central.extend_from_slice(&[0; 8]);
            central.extend_from_slice(&(raw.len() as u32).to_le_bytes());
            central.extend_from_slice(&(size as u32).to_le_bytes());
            central.extend_from_slice(&(name.len() as u16).to_le_bytes());
            central.extend_from_slice(&[0; 12]);
            central.extend_from_slice(&local.to_le_bytes());
            central.extend_from_slice(name.as_bytes());
        }
        let cd_at = zip.len() as u32;
        zip.extend_from_slice(&central);
        zip.extend_from_slice(b"PK\x05\x06");
        zip.extend_from_slice(&[0; 4]);
        zip.extend_from_slice(&2u16.to_le_bytes());
        zip.extend_from_slice(&2u16.to_le_bytes());
        zip.extend_from_slice(&(central.len() as u32).to_le_bytes());
        zip.extend_from_slice(&cd_at.to_le_bytes());
        zip.extend_from_slice(&0u16.to_le_bytes());
        assert_eq!(zip_member(&zip, "a.obj").unwrap(), stored);
        assert_eq!(zip_member(&zip, "b.obj").unwrap(), text);
        let e = zip_member(&zip, "c.obj").unwrap_err();
        assert!(e.contains("c.obj"), "{e}");
        assert!(zip_member(&zip[..zip.len() - 30], "a.obj").is_err());
    }
}
