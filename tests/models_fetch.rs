//! `experiment models fetch` end to end against an HTTP server on 127.0.0.1 that each test
//! runs itself (std `TcpListener`, a bounded number of connections, a deadline): a whole
//! download, a corrupted copy, a truncated transfer, a 404 and a stalled server. Checksums are
//! refused, nothing is half written, and a resumed download equals a whole one. No address
//! other than loopback is ever contacted.

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use visfield::experiment::models_fetch::{fetch_model, FetchOptions, Fetched};
use visfield::geometry::models::{ModelEntry, ModelRegistry};

/// A small OBJ mesh (a strip of 2 × 2000 triangles), about 150 kB: several reads of 64 KiB.
fn mesh_bytes() -> Vec<u8> {
    let mut s = String::from("# test strip\n");
    for i in 0..2001 {
        s.push_str(&format!("v {i} 0 0\nv {i} 1 0\n"));
    }
    for i in 0..2000 {
        let a = 2 * i + 1;
        s.push_str(&format!(
            "f {a} {} {}\nf {} {} {}\n",
            a + 2,
            a + 1,
            a + 1,
            a + 2,
            a + 3
        ));
    }
    s.into_bytes()
}

/// The requests a server saw: (path, Range header).
type Log = Arc<Mutex<Vec<(String, Option<String>)>>>;

/// Serves `body` on 127.0.0.1 at a free port until `max` connections or 30 s:
/// `/mesh.obj` whole or from a `Range`, `/corrupt.obj` with one byte flipped, `/truncated.obj`
/// half of it under the whole length, `/slow.obj` half, then a 3 s stall, `/lingering.obj`
/// all of it under a length one byte longer, then a 3 s stall, and 404 elsewhere. A mirror's
/// layout is served below `/mirror/`: `/mirror/models.example.org/files/NAME` is `/NAME`.
fn serve(body: Vec<u8>, max: usize) -> (String, Log) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let base = format!("http://{}", listener.local_addr().unwrap());
    assert!(base.starts_with("http://127.0.0.1:"));
    listener.set_nonblocking(true).unwrap();
    let log: Log = Arc::default();
    let seen = log.clone();
    std::thread::spawn(move || {
        let deadline = Instant::now() + Duration::from_secs(30);
        let mut served = 0;
        while served < max && Instant::now() < deadline {
            match listener.accept() {
                Ok((stream, _)) => {
                    served += 1;
                    let (body, seen) = (body.clone(), seen.clone());
                    std::thread::spawn(move || answer(stream, &body, &seen));
                }
                Err(_) => std::thread::sleep(Duration::from_millis(5)),
            }
        }
    });
    (base, log)
}

fn answer(mut stream: TcpStream, body: &[u8], log: &Log) {
    stream.set_nonblocking(false).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(5)))
        .unwrap();
    let mut reader = BufReader::new(stream.try_clone().unwrap());
    let mut line = String::new();
    if reader.read_line(&mut line).is_err() {
        return;
    }
    let path = line.split_whitespace().nth(1).unwrap_or("").to_string();
    let served = path
        .strip_prefix("/mirror/models.example.org/files")
        .unwrap_or(&path)
        .to_string();
    let mut range = None;
    loop {
        let mut h = String::new();
        if reader.read_line(&mut h).unwrap_or(0) == 0 || h.trim().is_empty() {
            break;
        }
        if let Some(v) = h.to_ascii_lowercase().strip_prefix("range: bytes=") {
            range = Some(v.trim().trim_end_matches('-').to_string());
        }
    }
    log.lock().unwrap().push((path.clone(), range.clone()));
    let head = |status: &str, len: usize, extra: &str| {
        format!("HTTP/1.1 {status}\r\nContent-Length: {len}\r\n{extra}Connection: close\r\n\r\n")
    };
    let half = body.len() / 2;
    let _ = match served.as_str() {
        "/mesh.obj" => match range.as_deref().and_then(|r| r.parse::<usize>().ok()) {
            Some(from) if from < body.len() => {
                let extra = format!(
                    "Content-Range: bytes {from}-{}/{}\r\n",
                    body.len() - 1,
                    body.len()
                );
                stream
                    .write_all(head("206 Partial Content", body.len() - from, &extra).as_bytes())
                    .and_then(|_| stream.write_all(&body[from..]))
            }
            _ => stream
                .write_all(head("200 OK", body.len(), "").as_bytes())
                .and_then(|_| stream.write_all(body)),
        },
        "/corrupt.obj" => {
            let mut bad = body.to_vec();
            bad[half] ^= 1;
            stream
                .write_all(head("200 OK", bad.len(), "").as_bytes())
                .and_then(|_| stream.write_all(&bad))
        }
        "/truncated.obj" => stream
            .write_all(head("200 OK", body.len(), "").as_bytes())
            .and_then(|_| stream.write_all(&body[..half])),
        "/slow.obj" => stream
            .write_all(head("200 OK", body.len(), "").as_bytes())
            .and_then(|_| stream.write_all(&body[..half]))
            .and_then(|_| stream.flush())
            .map(|_| std::thread::sleep(Duration::from_secs(3))),
        "/lingering.obj" => stream
            .write_all(head("200 OK", body.len() + 1, "").as_bytes())
            .and_then(|_| stream.write_all(body))
            .and_then(|_| stream.flush())
            .map(|_| std::thread::sleep(Duration::from_secs(3))),
        _ => stream.write_all(head("404 Not Found", 0, "").as_bytes()),
    };
}

/// A registry entry for the test mesh at `url`.
fn entry(url: &str, body: &[u8]) -> ModelEntry {
    let json = format!(
        r#"{{"comment":"","models":[{{"name":"strip","file":"strip.obj","sha256":"{}","bytes":{},
        "vertices":4002,"triangles":4000,"licence":"test","source":"test","url":"{url}","loadable":true}}]}}"#,
        visfield::io::sha256_hex(body),
        body.len()
    );
    ModelRegistry::from_json(&json, "test.json")
        .unwrap()
        .entries
        .remove(0)
}

fn quick() -> FetchOptions {
    FetchOptions {
        timeout: Duration::from_secs(1),
        min_bytes_per_s: u64::MAX,
        progress: false,
        mirror: None,
    }
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn a_whole_download_is_verified_moved_in_and_then_present() {
    let body = mesh_bytes();
    let (base, log) = serve(body.clone(), 4);
    let dir = tempfile::tempdir().unwrap();
    let e = entry(&format!("{base}/mesh.obj"), &body);
    let got = fetch_model(&e, dir.path(), &quick()).unwrap();
    let path = dir.path().join("strip.obj");
    assert_eq!(
        got,
        Fetched::Downloaded {
            path: path.clone(),
            resumed_from: 0,
            notes: Vec::new(),
        }
    );
    assert_eq!(std::fs::read(&path).unwrap(), body);
    assert_eq!(names(dir.path()), ["strip.obj"]);
    // Present and verified: the server is not asked again.
    assert_eq!(
        fetch_model(&e, dir.path(), &quick()).unwrap(),
        Fetched::Present(path)
    );
    assert_eq!(log.lock().unwrap().len(), 1);
    // And the loader reads what was fetched.
    let mesh = visfield::geometry::Mesh::load_obj(&dir.path().join("strip.obj")).unwrap();
    assert_eq!(mesh.triangle_count(), 4000);
}

#[test]
fn a_corrupted_copy_is_refused_and_never_replaces_a_file() {
    let body = mesh_bytes();
    let (base, _) = serve(body.clone(), 4);
    let dir = tempfile::tempdir().unwrap();
    let bad = entry(&format!("{base}/corrupt.obj"), &body);
    let e = fetch_model(&bad, dir.path(), &quick())
        .unwrap_err()
        .to_string();
    let mut flipped = body.clone();
    flipped[body.len() / 2] ^= 1;
    assert!(
        e.contains(&visfield::io::sha256_hex(&flipped))
            && e.contains(&bad.sha256)
            && e.contains("refused"),
        "{e}"
    );
    assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
    // A user's file in place (here a wrong one) is kept through a refused download, and
    // replaced by a verified one.
    let target = dir.path().join("strip.obj");
    std::fs::write(&target, b"a user's file").unwrap();
    assert!(fetch_model(&bad, dir.path(), &quick()).is_err());
    assert_eq!(std::fs::read(&target).unwrap(), b"a user's file");
    let good = entry(&format!("{base}/mesh.obj"), &body);
    fetch_model(&good, dir.path(), &quick()).unwrap();
    assert_eq!(std::fs::read(&target).unwrap(), body);
    assert_eq!(names(dir.path()), ["strip.obj"]);
}

#[test]
fn a_truncated_transfer_keeps_its_part_and_resumes_to_the_whole_file() {
    let body = mesh_bytes();
    let (base, log) = serve(body.clone(), 4);
    let dir = tempfile::tempdir().unwrap();
    let e = fetch_model(
        &entry(&format!("{base}/truncated.obj"), &body),
        dir.path(),
        &quick(),
    )
    .unwrap_err()
    .to_string();
    let half = body.len() / 2;
    assert!(
        e.contains(&format!("after {half} of {} bytes", body.len())),
        "{e}"
    );
    // Nothing half written under the model's name; the bytes so far kept for a resume.
    assert_eq!(names(dir.path()), [".strip.obj.part"]);
    let part = std::fs::read(dir.path().join(".strip.obj.part")).unwrap();
    assert_eq!(part, body[..half]);
    let got = fetch_model(
        &entry(&format!("{base}/mesh.obj"), &body),
        dir.path(),
        &quick(),
    )
    .unwrap();
    assert_eq!(
        got,
        Fetched::Downloaded {
            path: dir.path().join("strip.obj"),
            resumed_from: half as u64,
            notes: Vec::new(),
        }
    );
    assert_eq!(std::fs::read(dir.path().join("strip.obj")).unwrap(), body);
    assert_eq!(names(dir.path()), ["strip.obj"]);
    // The resume asked for the rest only.
    assert_eq!(
        log.lock().unwrap().last().unwrap(),
        &("/mesh.obj".to_string(), Some(half.to_string()))
    );
}

#[test]
fn a_stalled_server_times_out_and_the_resume_equals_a_whole_download() {
    let body = mesh_bytes();
    let (base, _) = serve(body.clone(), 4);
    let dir = tempfile::tempdir().unwrap();
    let started = Instant::now();
    let e = fetch_model(
        &entry(&format!("{base}/slow.obj"), &body),
        dir.path(),
        &quick(),
    )
    .unwrap_err()
    .to_string();
    // The body's deadline (1 s here) ends the stall (3 s), not the server.
    assert!(started.elapsed() < Duration::from_millis(2900), "{e}");
    assert!(e.contains("transfer ended after"), "{e}");
    assert_eq!(names(dir.path()), [".strip.obj.part"]);
    fetch_model(
        &entry(&format!("{base}/mesh.obj"), &body),
        dir.path(),
        &quick(),
    )
    .unwrap();
    let whole = tempfile::tempdir().unwrap();
    fetch_model(
        &entry(&format!("{base}/mesh.obj"), &body),
        whole.path(),
        &quick(),
    )
    .unwrap();
    assert_eq!(
        std::fs::read(dir.path().join("strip.obj")).unwrap(),
        std::fs::read(whole.path().join("strip.obj")).unwrap()
    );
}

#[test]
fn a_404_writes_nothing_and_names_the_status_and_url() {
    let body = mesh_bytes();
    let (base, _) = serve(body.clone(), 2);
    let dir = tempfile::tempdir().unwrap();
    let url = format!("{base}/gone.obj");
    let e = fetch_model(&entry(&url, &body), &dir.path().join("models"), &quick())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("HTTP 404") && e.contains(&url) && e.contains("strip"),
        "{e}"
    );
    assert!(names(&dir.path().join("models")).is_empty());
}

#[test]
fn a_derived_model_without_a_source_says_how_it_was_made() {
    let reg = ModelRegistry::embedded();
    let dir = tempfile::tempdir().unwrap();
    let e = fetch_model(reg.get("stanford-bunny_39k").unwrap(), dir.path(), &quick())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("fast-simplification")
            && e.contains("scripts/derive_decimated.py stanford-bunny_39k")
            && e.contains(&dir.path().display().to_string()),
        "{e}"
    );
    assert!(names(dir.path()).is_empty());
}

#[test]
fn verify_names_a_wrong_copy_and_fetch_refuses_an_unknown_name() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bunny_npm.obj"), b"not the bunny").unwrap();
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_experiment"))
            .args(args)
            .env("VISFIELD_MODELS", dir.path())
            .output()
            .unwrap()
    };
    let o = run(&["models", "verify", "bunny_npm"]);
    let t = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("WRONG") && t.contains(&visfield::io::sha256_hex(b"not the bunny")),
        "{t}"
    );
    let o = run(&["models", "fetch", "teapot"]);
    let t = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        t.contains("unknown model `teapot`") && t.contains("bunny_npm"),
        "{t}"
    );
    assert_eq!(names(dir.path()), ["bunny_npm.obj"]);
}

/// A `.part` of garbage left by an earlier fetch (half the file, or all of its length) is named
/// as the corrupt one, deleted, and the download restarts from the start: the fetch succeeds
/// with the server's bytes (before, its sha256 was blamed on the server and the fetch failed).
#[test]
fn a_corrupt_partial_file_is_named_deleted_and_the_download_restarted() {
    let body = mesh_bytes();
    let (base, log) = serve(body.clone(), 4);
    let e = entry(&format!("{base}/mesh.obj"), &body);
    for stale in [body.len() / 2, body.len()] {
        let dir = tempfile::tempdir().unwrap();
        let part = dir.path().join(".strip.obj.part");
        std::fs::write(&part, vec![b'#'; stale]).unwrap();
        let before = log.lock().unwrap().len();
        let got = fetch_model(&e, dir.path(), &quick()).unwrap();
        let Fetched::Downloaded {
            path,
            resumed_from: 0,
            notes,
        } = got
        else {
            panic!("{got:?}")
        };
        assert_eq!(std::fs::read(&path).unwrap(), body);
        assert_eq!(names(dir.path()), ["strip.obj"]);
        assert_eq!(notes.len(), 1, "{notes:?}");
        let n = &notes[0];
        assert!(
            n.contains(&part.display().to_string())
                && n.contains("partial file of an earlier fetch is corrupt")
                && n.contains(&format!("its {stale} bytes"))
                && n.contains("starts from the start"),
            "{n}"
        );
        // A resume of the rest (none where the part had the whole length), then the whole.
        let asked: Vec<_> = log.lock().unwrap()[before..].to_vec();
        let whole = ("/mesh.obj".to_string(), None);
        if stale < body.len() {
            assert_eq!(
                asked,
                [("/mesh.obj".to_string(), Some(stale.to_string())), whole]
            );
        } else {
            assert_eq!(asked, [whole]);
        }
    }
}

/// A transfer that fails after its last byte (the server announced one byte more, then
/// stalled) is not reported as ended short ("after N of N bytes"): the bytes are checked and
/// kept where their sha256 is the registry's, with a note; where it is not, the refusal names
/// both hashes and the late failure.
#[test]
fn a_transfer_failing_after_its_last_byte_gives_the_real_cause() {
    let body = mesh_bytes();
    let (base, _) = serve(body.clone(), 4);
    let url = format!("{base}/lingering.obj");
    let dir = tempfile::tempdir().unwrap();
    let got = fetch_model(&entry(&url, &body), dir.path(), &quick()).unwrap();
    let Fetched::Downloaded { path, notes, .. } = got else {
        panic!("{got:?}")
    };
    assert_eq!(std::fs::read(&path).unwrap(), body);
    assert!(
        notes.len() == 1
            && notes[0].contains(&format!(
                "after the last of the registry's {} bytes",
                body.len()
            ))
            && notes[0].contains("sha256 is the registry's"),
        "{notes:?}"
    );
    // The same bytes against another file's sha256 (one byte flipped, the same length).
    let mut other = body.clone();
    other[7] ^= 1;
    let dir = tempfile::tempdir().unwrap();
    let e = fetch_model(&entry(&url, &other), dir.path(), &quick())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&visfield::io::sha256_hex(&body))
            && e.contains(&visfield::io::sha256_hex(&other))
            && e.contains("failed after the last byte")
            && !e.contains("transfer ended after"),
        "{e}"
    );
    assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
}

/// A mirror serves each source's file at `MIRROR/HOST/PATH`: the fetch asks it there, and the
/// result is the source's file, verified.
#[test]
fn a_mirror_is_asked_at_the_sources_host_and_path() {
    use visfield::experiment::models_fetch::mirrored;
    let body = mesh_bytes();
    let (base, log) = serve(body.clone(), 2);
    let dir = tempfile::tempdir().unwrap();
    let e = entry("https://models.example.org/files/mesh.obj", &body);
    let opts = FetchOptions {
        mirror: Some(format!("{base}/mirror/")),
        ..quick()
    };
    let got = fetch_model(&e, dir.path(), &opts).unwrap();
    assert!(matches!(got, Fetched::Downloaded { .. }), "{got:?}");
    assert_eq!(std::fs::read(dir.path().join("strip.obj")).unwrap(), body);
    assert_eq!(
        log.lock().unwrap().as_slice(),
        [(
            "/mirror/models.example.org/files/mesh.obj".to_string(),
            None
        )]
    );
    assert_eq!(
        mirrored("https://raw.example.com/o/r/c/f.obj", "http://m.local/base").unwrap(),
        "http://m.local/base/raw.example.com/o/r/c/f.obj"
    );
    for bad in ["ftp://m.local", "m.local/base", "https://"] {
        let why = mirrored("https://raw.example.com/f.obj", bad).unwrap_err();
        assert!(why.contains(bad), "{why}");
    }
}

/// `experiment models fetch --mirror URL` and `$VISFIELD_MODELS_MIRROR` ask the mirror for the
/// registry's file (bunny_npm's npm archive here, which the test server does not hold: the
/// 404 names the mirrored URL); a mirror that is not an http(s) URL fails naming its source.
#[test]
fn the_fetch_command_takes_a_mirror_by_flag_and_by_variable() {
    let (base, log) = serve(Vec::new(), 2);
    let dir = tempfile::tempdir().unwrap();
    let fetch = |flag: Option<&str>, var: Option<&str>| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_experiment"));
        c.args(["models", "fetch", "bunny_npm", "--dir"])
            .arg(dir.path())
            .env_remove("VISFIELD_MODELS_MIRROR");
        if let Some(m) = flag {
            c.args(["--mirror", m]);
        }
        if let Some(m) = var {
            c.env("VISFIELD_MODELS_MIRROR", m);
        }
        c.output().unwrap()
    };
    let want = "/registry.npmjs.org/bunny/-/bunny-1.0.1.tgz";
    for (flag, var, prefix) in [
        (Some(format!("{base}/flag")), None, "/flag"),
        (None, Some(format!("{base}/var")), "/var"),
    ] {
        let o = fetch(flag.as_deref(), var.as_deref());
        let out = String::from_utf8_lossy(&o.stdout);
        assert_eq!(o.status.code(), Some(1), "{out}");
        let url = format!("{base}{prefix}{want}");
        assert!(out.contains("HTTP 404") && out.contains(&url), "{out}");
        assert_eq!(
            log.lock().unwrap().last().unwrap().0,
            format!("{prefix}{want}")
        );
    }
    let o = fetch(Some("ftp://mirror.local"), None);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("--mirror") && err.contains("ftp://mirror.local"),
        "{err}"
    );
    let o = fetch(None, Some("mirror.local"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("$VISFIELD_MODELS_MIRROR")
            && err.contains("mirror.local"),
        "{err}"
    );
    assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
}
