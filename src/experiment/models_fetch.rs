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
//! - **The real cause.** A `.part` left by an earlier fetch whose bytes, completed, fail the
//!   sha256 is named as the corrupt one, deleted, and the download restarts from the start
//!   (once); a transfer that fails after its last byte is not reported as ended short: its
//!   bytes are checked, and kept where their sha256 is the registry's (the failure noted); a
//!   local write that fails is named as such, not as the server's.
//! - **Mirrors.** `--mirror URL` (or `$VISFIELD_MODELS_MIRROR`) asks every model of a mirror
//!   holding the sources' files at `URL/HOST/PATH` ([`mirrored`]).

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
    /// A mirror's base URL ([`mirrored`]): every model is asked of it instead of its source.
    pub mirror: Option<String>,
}

impl Default for FetchOptions {
    fn default() -> FetchOptions {
        FetchOptions {
            timeout: Duration::from_secs(30),
            min_bytes_per_s: 20 * 1024,
            progress: true,
            mirror: None,
        }
    }
}

/// What a fetch did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Fetched {
    /// The models folder already held the file with the registry's sha256.
    Present(PathBuf),
    /// Downloaded (and extracted) into the folder; `resumed_from` bytes came from an earlier
    /// `.part`; `notes`, what the user should know (a corrupt partial file deleted and the
    /// download restarted, a transfer that failed after its last byte).
    Downloaded {
        path: PathBuf,
        resumed_from: u64,
        notes: Vec<String>,
    },
}

/// The environment variable naming a mirror (as `--mirror`).
pub const MIRROR_ENV: &str = "VISFIELD_MODELS_MIRROR";

/// `url` (`https://HOST/PATH`, as `data/models.json` records it) asked of the mirror at `base`:
/// `BASE/HOST/PATH`. A mirror holds each file at its source's host and path below its base
/// (the layout `wget --force-directories` writes), so one base serves every source: e.g.
/// `https://raw.githubusercontent.com/OWNER/REPO/COMMIT/FILE` is asked as
/// `BASE/raw.githubusercontent.com/OWNER/REPO/COMMIT/FILE`. The base must be an `http://` or
/// `https://` URL (else the error says why); a trailing `/` is ignored.
pub fn mirrored(url: &str, base: &str) -> std::result::Result<String, String> {
    fn scheme(u: &str) -> Option<&str> {
        ["https://", "http://"]
            .iter()
            .find_map(|s| u.strip_prefix(s))
            .filter(|rest| !rest.is_empty())
    }
    if scheme(base).is_none() {
        return Err(format!("mirror `{base}` is not an http:// or https:// URL"));
    }
    let rest = scheme(url).ok_or_else(|| format!("`{url}` is not an http:// or https:// URL"))?;
    Ok(format!("{}/{rest}", base.trim_end_matches('/')))
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
    let Some(source) = &entry.url else {
        let how = entry
            .derived
            .as_deref()
            .unwrap_or("no source URL is recorded");
        return Err(Error::invalid(
            what,
            format!(
                "no public source holds {}: derived by us, {how}; it goes into {} (or a folder \
                 named by $VISFIELD_MODELS)",
                entry.file,
                dir.display()
            ),
        ));
    };
    let url = match &opts.mirror {
        Some(base) => &mirrored(source, base).map_err(|m| Error::invalid(what.clone(), m))?,
        None => source,
    };
    std::fs::create_dir_all(dir).map_err(Error::io(dir))?;
    let got = match (&entry.member, &entry.convert) {
        (None, None) => {
            let part = dir.join(format!(".{}.part", entry.file));
            let got = download(url, &part, entry.bytes, &entry.sha256, &what, opts)?;
            std::fs::rename(&part, &target).map_err(Error::io(&target))?;
            got
        }
        (member, _) => {
            let (Some(archive_sha), Some(archive_bytes)) =
                (&entry.archive_sha256, entry.archive_bytes)
            else {
                return Err(Error::invalid(
                    what,
                    "`member` and `convert` need `archive_sha256` and `archive_bytes` in \
                     data/models.json",
                ));
            };
            let archive = url.rsplit('/').next().unwrap_or("archive");
            let part = dir.join(format!(".{archive}.part"));
            let got = download(url, &part, archive_bytes, archive_sha, &what, opts)?;
            let archive_bytes = std::fs::read(&part).map_err(Error::io(&part))?;
            let member = member.as_deref().unwrap_or("");
            let extracted = if member.is_empty() {
                Ok(archive_bytes)
            } else if url.ends_with(".zip") {
                zip_member(&archive_bytes, member)
            } else {
                tgz_member(&archive_bytes, member)
            };
            let mut bytes = extracted.map_err(|m| Error::invalid(format!("{what}: {url}"), m))?;
            if let Some(recipe) = &entry.convert {
                bytes = convert(recipe, &bytes)
                    .map_err(|m| Error::invalid(format!("{what}: {url} {member}"), m))?;
            }
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
            got
        }
    };
    Ok(Fetched::Downloaded {
        path: target,
        resumed_from: got.resumed_from,
        notes: got.notes,
    })
}

/// What [`download`] did: the bytes resumed from, and what the user should be told.
struct Downloaded {
    resumed_from: u64,
    notes: Vec<String>,
}

/// Downloads `url` into `part` until it holds `bytes` bytes whose sha256 is `sha256`, resuming
/// from what `part` already holds. Where the whole differs and some of it came from an earlier
/// `.part`, that partial file is what is wrong (the server's bytes cannot be told apart from
/// it): it is deleted, the user told so, and the download starts again from the start, once.
fn download(
    url: &str,
    part: &Path,
    bytes: u64,
    sha256: &str,
    what: &str,
    opts: &FetchOptions,
) -> Result<Downloaded> {
    let at = |m: String| Error::invalid(format!("{what}: {url}"), m);
    let mut notes = Vec::new();
    loop {
        let mut have = std::fs::metadata(part).map(|m| m.len()).unwrap_or(0);
        if have > bytes {
            notes.push(format!(
                "{}: the partial file of an earlier fetch holds {have} bytes, more than the \
                 registry's {bytes}: deleted, the download starts from the start",
                part.display()
            ));
            std::fs::remove_file(part).map_err(Error::io(part))?;
            have = 0;
        }
        let (resumed_from, late) = if have < bytes {
            // A partial file discarded before: the error says so.
            transfer(url, part, have, bytes, what, opts).map_err(|e| match notes.last() {
                Some(n) => e.context(n.clone()),
                None => e,
            })?
        } else {
            (have, None)
        };
        let got = std::fs::read(part).map_err(Error::io(part))?;
        let actual = crate::io::sha256_hex(&got);
        if actual == sha256 {
            notes.extend(late.map(|m| {
                format!(
                    "the transfer failed after the last of the registry's {bytes} bytes ({m}); \
                     their sha256 is the registry's"
                )
            }));
            return Ok(Downloaded {
                resumed_from,
                notes,
            });
        }
        std::fs::remove_file(part).map_err(Error::io(part))?;
        if resumed_from > 0 {
            let sent = match bytes - resumed_from {
                0 => "(the whole length: nothing was asked of the server)".to_string(),
                n => format!("and the {n} the server sent after them"),
            };
            notes.push(format!(
                "{}: the partial file of an earlier fetch is corrupt: its {resumed_from} bytes \
                 {sent} have sha256 {actual}, the registry's is {sha256}; deleted, the \
                 download starts from the start",
                part.display()
            ));
            continue;
        }
        let late = late.map_or(String::new(), |m| {
            format!(" (the transfer also failed after the last byte: {m})")
        });
        let e = at(format!(
            "the server's {bytes} bytes have sha256 {actual}, the registry's is {sha256}: \
             refused, nothing written{late}"
        ));
        return Err(match notes.last() {
            Some(n) => e.context(n.clone()),
            None => e,
        });
    }
}

/// One request for the bytes of `url` from `have` on, written to `part` (appended where the
/// server answers 206 to the `Range`, from the start where it answers 200) until `part` holds
/// `bytes`; returns how many of its bytes were kept from before (0 where the server sent the
/// whole file), and the transfer's failure after the last byte, if any (the caller checks the
/// bytes' sha256 and tells it), which is not an error. An error where it ends short (the bytes
/// kept for a resume) or a local write fails.
fn transfer(
    url: &str,
    part: &Path,
    mut have: u64,
    bytes: u64,
    what: &str,
    opts: &FetchOptions,
) -> Result<(u64, Option<String>)> {
    let at = |m: String| Error::invalid(format!("{what}: {url}"), m);
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
    let kept = have;
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
    /// Why the body's reading stopped early.
    enum Stop {
        TooMuch,
        Write(std::io::Error),
        Read(String),
    }
    let mut reader = response.into_body().into_reader();
    let mut buf = vec![0u8; 1 << 16];
    let outcome = loop {
        match reader.read(&mut buf) {
            Ok(0) => break Ok(()),
            Ok(n) => {
                if have + n as u64 > bytes {
                    break Err(Stop::TooMuch);
                }
                if let Err(e) = file.write_all(&buf[..n]) {
                    break Err(Stop::Write(e));
                }
                have += n as u64;
                if let Some(b) = &bar {
                    b.set_position(have);
                }
            }
            Err(e) => break Err(Stop::Read(e.to_string())),
        }
    };
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    file.sync_all().map_err(Error::io(part))?;
    drop(file);
    let resume = |have: u64| {
        format!(
            "`experiment models fetch` again resumes from the {have} bytes of {}",
            part.display()
        )
    };
    match outcome {
        Err(Stop::TooMuch) => {
            std::fs::remove_file(part).map_err(Error::io(part))?;
            Err(at(format!(
                "the server sent more than the registry's {bytes} bytes: refused, nothing \
                 written"
            )))
        }
        Err(Stop::Write(e)) => Err(Error::invalid(
            format!("{what}: writing {}", part.display()),
            format!(
                "{e}, after {have} of {bytes} bytes had arrived from {url}; {}",
                resume(have)
            ),
        )),
        Err(Stop::Read(m)) if have == bytes => Ok((kept, Some(m))),
        Err(Stop::Read(m)) => Err(at(format!(
            "transfer ended after {have} of {bytes} bytes ({m}); {}",
            resume(have)
        ))),
        Ok(()) if have < bytes => Err(at(format!(
            "transfer ended after {have} of {bytes} bytes: the server closed it; {}",
            resume(have)
        ))),
        Ok(()) => Ok((kept, None)),
    }
}

/// The bytes of `name` in the gzipped tar archive `tgz` (an npm package).
fn tgz_member(tgz: &[u8], name: &str) -> std::result::Result<Vec<u8>, String> {
    let bad = || "not a gzip archive this reader understands".to_string();
    // RFC 1952: a 10-byte header, then optional fields by the flag bits.
    if tgz.len() < 18 || tgz[0..3] != [0x1f, 0x8b, 8] {
        return Err(bad());
    }
    let flags = tgz[3];
    let mut at = 10;
    if flags & 4 != 0 {
        let n = tgz.get(at..at + 2).ok_or_else(bad)?;
        at += 2 + u16::from_le_bytes([n[0], n[1]]) as usize;
    }
    for bit in [8u8, 16] {
        if flags & bit != 0 {
            at += tgz
                .get(at..)
                .ok_or_else(bad)?
                .iter()
                .position(|&b| b == 0)
                .ok_or_else(bad)?
                + 1;
        }
    }
    if flags & 2 != 0 {
        at += 2;
    }
    let tar =
        miniz_oxide::inflate::decompress_to_vec_with_limit(tgz.get(at..).ok_or_else(bad)?, 1 << 30)
            .map_err(|e| format!("cannot inflate: {e:?}"))?;
    let mut at = 0;
    while at + 512 <= tar.len() && tar[at] != 0 {
        let header = &tar[at..at + 512];
        let end = header[..100].iter().position(|&b| b == 0).unwrap_or(100);
        let size_text = String::from_utf8_lossy(&header[124..136]);
        let size =
            usize::from_str_radix(size_text.trim_matches(|c: char| c == '\0' || c == ' '), 8)
                .map_err(|_| format!("tar header size `{size_text}`"))?;
        if &header[..end] == name.as_bytes() {
            return tar
                .get(at + 512..at + 512 + size)
                .map(<[u8]>::to_vec)
                .ok_or_else(|| format!("{name}: truncated in the archive"));
        }
        at += 512 + size.div_ceil(512) * 512;
    }
    Err(format!("no member `{name}`"))
}

/// Runs the recipe `recipe` (`data/models.json` `convert`) on a downloaded member.
fn convert(recipe: &str, member: &[u8]) -> std::result::Result<Vec<u8>, String> {
    match recipe {
        "bunny-js-to-obj" => bunny_js_to_obj(member),
        "igea-ply-to-obj" => igea_ply_to_obj(member),
        other => Err(format!("unknown recipe `{other}`")),
    }
}

/// npm bunny@1.0.1's `index.js` (`exports.positions=[[x,y,z],...]` and
/// `exports.cells=[[i,j,k],...]`, 0-based) as the OBJ of `bunny_npm`: one comment line, each
/// coordinate's text as the file has it, faces 1-based.
fn bunny_js_to_obj(js: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let js = std::str::from_utf8(js).map_err(|e| format!("index.js: {e}"))?;
    let array = |key: &str| -> std::result::Result<Vec<Vec<&str>>, String> {
        let start = js
            .find(key)
            .ok_or_else(|| format!("index.js: no `{key}`"))?
            + key.len();
        let body = &js[start..];
        let end = body
            .find("]]")
            .ok_or_else(|| format!("index.js: `{key}` not closed"))?;
        let inner = body[..end]
            .strip_prefix("[[")
            .ok_or_else(|| format!("index.js: `{key}` is not an array of arrays"))?;
        Ok(inner.split("],[").map(|t| t.split(',').collect()).collect())
    };
    let mut out = String::from(
        "# Stanford bunny (low-res), converted from npm package bunny@1.0.1 (index.js \
         positions/cells); faces are 1-based\n",
    );
    for p in array("exports.positions=")? {
        if p.len() != 3 || p.iter().any(|t| t.parse::<f64>().is_err()) {
            return Err(format!("index.js: position {p:?}"));
        }
        out.push_str(&format!("v {}\n", p.join(" ")));
    }
    for c in array("exports.cells=")? {
        let idx: Vec<usize> = c
            .iter()
            .map(|t| t.parse::<usize>().map(|i| i + 1))
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| format!("index.js: cell {c:?}"))?;
        out.push_str(&format!(
            "f {}\n",
            idx.iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(" ")
        ));
    }
    Ok(out.into_bytes())
}

/// igea.ply (binary little-endian PLY: `vertex` x y z floats, then one `tristrips` list of int
/// indices with -1 restarts) as the OBJ of `igea`: one comment line, each coordinate as C's
/// `%g` prints it ([`format_g`]), each strip unrolled with alternating winding (odd triangles
/// swap their first two corners), triangles with a repeated corner dropped, faces 1-based.
fn igea_ply_to_obj(ply: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let marker = b"end_header\n";
    let body = ply
        .windows(marker.len())
        .position(|w| w == marker)
        .ok_or("igea.ply: no end_header")?
        + marker.len();
    let header = String::from_utf8_lossy(&ply[..body]);
    let count = |element: &str| -> std::result::Result<usize, String> {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {element} ")))
            .and_then(|n| n.trim().parse().ok())
            .ok_or_else(|| format!("igea.ply: no `element {element}` count"))
    };
    let (vertices, strips) = (count("vertex")?, count("tristrips")?);
    if !header.contains("binary_little_endian") || strips != 1 {
        return Err("igea.ply: expected binary little-endian with one tristrips list".into());
    }
    let word = |at: usize| -> std::result::Result<[u8; 4], String> {
        ply.get(at..at + 4)
            .map(|b| [b[0], b[1], b[2], b[3]])
            .ok_or_else(|| "igea.ply: truncated".to_string())
    };
    let mut out = String::from(
        "# Igea (Cyberware), converted by us from igea.ply (binary tristrips) of \
         alecjacobson/common-3d-test-models: strips unrolled with alternating winding, \
         degenerate triangles dropped; faces 1-based\n",
    );
    for i in 0..vertices {
        let c: Vec<String> = (0..3)
            .map(|k| word(body + 12 * i + 4 * k).map(|w| format_g(f32::from_le_bytes(w) as f64)))
            .collect::<std::result::Result<_, _>>()?;
        out.push_str(&format!("v {}\n", c.join(" ")));
    }
    let list = body + 12 * vertices;
    let n = i32::from_le_bytes(word(list)?);
    let n = usize::try_from(n).map_err(|_| format!("igea.ply: strip length {n}"))?;
    let mut strip: Vec<i64> = Vec::new();
    let flush = |strip: &mut Vec<i64>, out: &mut String| {
        for k in 0..strip.len().saturating_sub(2) {
            let (mut a, mut b, c) = (strip[k], strip[k + 1], strip[k + 2]);
            if k % 2 == 1 {
                std::mem::swap(&mut a, &mut b);
            }
            if a != b && b != c && a != c {
                out.push_str(&format!("f {} {} {}\n", a + 1, b + 1, c + 1));
            }
        }
        strip.clear();
    };
    for j in 0..n {
        match i32::from_le_bytes(word(list + 4 + 4 * j)?) {
            -1 => flush(&mut strip, &mut out),
            i if i >= 0 && (i as usize) < vertices => strip.push(i64::from(i)),
            i => return Err(format!("igea.ply: index {i} of {vertices} vertices")),
        }
    }
    flush(&mut strip, &mut out);
    Ok(out.into_bytes())
}

/// `x` as C's (and Python's) `%g` prints it: 6 significant digits, fixed notation for decimal
/// exponents from -4 to 5, else `d.ddddde±XX`, trailing zeros (and a bare point) removed.
fn format_g(x: f64) -> String {
    let strip = |t: &str| -> String {
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t.to_string()
        }
    };
    let e = format!("{x:.5e}");
    let (mantissa, exp) = e.split_once('e').expect("exponent");
    let exp: i32 = exp.parse().expect("integer exponent");
    if (-4..6).contains(&exp) {
        strip(&format!("{x:.*}", (5 - exp) as usize))
    } else {
        let sign = if exp < 0 { '-' } else { '+' };
        format!("{}e{sign}{:02}", strip(mantissa), exp.abs())
    }
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
    use super::{bunny_js_to_obj, format_g, tgz_member, zip_member};

    /// C's `%g` (printf("%g") / Python "%g" % x), value by value.
    #[test]
    fn format_g_prints_what_printf_prints() {
        for (x, g) in [
            (0.0, "0"),
            (-0.0, "-0"),
            (1.0, "1"),
            (0.008178, "0.008178"),
            (7.7e-05, "7.7e-05"),
            (0.0001, "0.0001"),
            (123456.0, "123456"),
            (1234567.0, "1.23457e+06"),
            (-0.049669, "-0.049669"),
            (9.9999996, "10"),
            (1e-10, "1e-10"),
            (f32::from_bits(0x3c05fb4d) as f64, "0.00817759"),
        ] {
            assert_eq!(format_g(x), g, "{x:e}");
        }
    }

    /// An npm package in miniature: index.js in a gzipped tar, found and converted to the OBJ
    /// the recipe writes (coordinates verbatim, faces 1-based).
    #[test]
    fn the_bunny_recipe_reads_index_js_from_a_tgz_and_writes_obj() {
        let js = b"exports.positions=[[1.5,-0.25,3],[0,1e-3,2],[4,5,6]]\nexports.cells=[[0,2,1]]\n";
        let mut tar = vec![0u8; 512];
        tar[..16].copy_from_slice(b"package/index.js");
        tar[124..136].copy_from_slice(format!("{:011o}\0", js.len()).as_bytes());
        tar.extend_from_slice(js);
        tar.resize(512 + js.len().div_ceil(512) * 512 + 1024, 0);
        let mut tgz = vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 0xff];
        tgz.extend(miniz_oxide::deflate::compress_to_vec(&tar, 6));
        tgz.extend_from_slice(&[0; 8]);
        let member = tgz_member(&tgz, "package/index.js").unwrap();
        assert_eq!(member, js);
        assert!(tgz_member(&tgz, "package/other.js").is_err());
        let obj = String::from_utf8(bunny_js_to_obj(&member).unwrap()).unwrap();
        let body: Vec<&str> = obj.lines().skip(1).collect();
        assert_eq!(body, ["v 1.5 -0.25 3", "v 0 1e-3 2", "v 4 5 6", "f 1 3 2"]);
        assert!(bunny_js_to_obj(b"exports.positions=[[1,x,3]]").is_err());
    }

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
