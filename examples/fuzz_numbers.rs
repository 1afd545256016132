//! A fuzzing run over specs with extreme finite numbers (not malformed text, which
//! `fuzz/fuzz_targets/spec.rs` covers): a tiny vertex- or image-AO spec whose every numeric slot
//! (mesh sizes, placements, field axes, rays, image and camera, reference and truth settings)
//! takes, at random and several at once, a value from zeros, signs, powers of ten from 1e-45 to
//! 1e300, the f32 and u32 edges. Each case must be refused with an error naming the file, or go
//! through the scenes, the plan and its `--dry-run` text; cases whose plan traces at most
//! `RAY_BUDGET` rays also run in full. A panic is reported with the spec and fails the run; a
//! case over `CASE_LIMIT` seconds is reported as a hang.
//!
//! `cargo run --release --example fuzz_numbers -- [SECONDS] [SEED]` (default 60 s, seed 1).

use std::path::Path;
use std::time::{Duration, Instant};
use visfield::experiment::plan::{Plan, PlanLimits};
use visfield::experiment::run::{run, LoadedSpec, RunOptions};
use visfield::experiment::scenes::Scenes;
use visfield::experiment::spec::Spec;

/// Values a slot may take.
const VALUES: [&str; 30] = [
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "7",
    "16",
    "64",
    "256",
    "290",
    "1090",
    "4226",
    "65536",
    "1e-45",
    "-1e-45",
    "1e-30",
    "1e-7",
    "0.5",
    "1e7",
    "1e9",
    "1e12",
    "1e15",
    "1e20",
    "3e38",
    "-3.4e38",
    "1e300",
    "-1e300",
    "4294967295",
    "4294967296",
];

/// Plans at most this many rays are run in full.
const RAY_BUDGET: u64 = 20_000_000;
/// A case taking longer than this is a hang.
const CASE_LIMIT: Duration = Duration::from_secs(60);

/// The template: `{N}` marks each numeric slot.
const TEMPLATE: &str = r#"{
  "reproduces": "fuzz",
  "scenes": [{
    "name": "fuzz",
    "instances": [
      { "mesh": { "corner": { "n": {N} } }, "receiver": true,
        "transform": { "translate": [{N}, 0, {N}], "scale": {N} } },
      { "mesh": { "supershape": { "triangles": {N} } }, "caster": true,
        "transform": { "rotate_deg": [{N}, 0, 0], "translate": [{N}, {N}, 0],
                       "fit": { "center": [0.5, {N}, 0.5], "radius": {N} } } }
    ]
  }],
  "fields": [{ "counts": [{N}], "resolutions": [{N}] }],
  "render": { "what": "WHAT", "rays_per_point": {N}, "max_distance": {N},
              "image": { "width": {N}, "height": {N},
                         "camera": { "eye": [{N}, 2, 2], "target": [0.4, {N}, 0.4], "fov_y_deg": {N} } } },
  "reference": { "rays_per_point": {N}, "seeds": {N}, "raycast_sweep": [{N}],
                 "field_rays_sweep": [{N}],
                 "truth": { "target_stderr": {N}, "max_rays": {N}, "batches": {N} } },
  "quick": {}
}"#;

/// Sane values per slot, in template order: a case starts from these and replaces a few.
const SANE: [&str; 26] = [
    "9", "0", "0", "1", "2000", "10", "0", "0", "0.45", "0.35", "290", "16", "16", "0.5", "32",
    "32", "2", "0.4", "40", "16", "1", "16", "16", "1", "256", "4",
];

/// A small deterministic generator (splitmix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

enum Outcome {
    Refused,
    Planned,
    Ran,
}

fn case(text: &str, dir: &Path) -> Outcome {
    let file = Path::new("fuzz.json");
    let spec = match Spec::parse(text, file) {
        Ok(s) => s,
        Err(e) => {
            assert!(e.to_string().starts_with("fuzz.json: "), "{e}");
            return Outcome::Refused;
        }
    };
    let scenes = match Scenes::build(&spec, file, "scenes") {
        Ok(s) => s,
        Err(e) => {
            assert!(e.to_string().contains("fuzz.json"), "{e}");
            return Outcome::Refused;
        }
    };
    let limits = PlanLimits {
        memory_limit: 1 << 30,
    };
    let plan = match Plan::new(&spec, &scenes, limits) {
        Ok(p) => p,
        Err(_) => return Outcome::Refused,
    };
    let text_plan = plan.describe("fuzz", &scenes, &|_, _| "bake");
    let total: u64 = text_plan
        .lines()
        .find_map(|l| l.trim().strip_prefix("total: "))
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(u64::MAX);
    if total > RAY_BUDGET {
        return Outcome::Planned;
    }
    let path = dir.join("fuzz.json");
    std::fs::write(&path, text).expect("write the case");
    let Ok(ls) = LoadedSpec::load(&path) else {
        return Outcome::Refused;
    };
    let mut o = RunOptions::new(dir.join("out"));
    o.supply.cache = None;
    o.repeats = 1;
    match run(&ls, &o) {
        Ok(_) => Outcome::Ran,
        Err(_) => Outcome::Refused,
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let secs: u64 = args.next().map_or(60, |s| s.parse().expect("SECONDS"));
    let seed: u64 = args.next().map_or(1, |s| s.parse().expect("SEED"));
    let slots = TEMPLATE.matches("{N}").count();
    assert_eq!(slots, SANE.len(), "one sane value per slot");
    let mut rng = Rng(seed);
    let start = Instant::now();
    let (mut refused, mut planned, mut ran, mut cases) = (0u64, 0u64, 0u64, 0u64);
    let dir = std::env::temp_dir().join(format!("visfield-fuzz-numbers-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    while start.elapsed() < Duration::from_secs(secs) {
        let mut values: Vec<&str> = SANE.to_vec();
        for _ in 0..1 + rng.below(4) {
            values[rng.below(slots)] = VALUES[rng.below(VALUES.len())];
        }
        let what = if rng.below(2) == 0 {
            "vertex_ao"
        } else {
            "image_ao"
        };
        let mut text = String::new();
        for (i, part) in TEMPLATE.replace("WHAT", what).split("{N}").enumerate() {
            text.push_str(part);
            if i < slots {
                text.push_str(values[i]);
            }
        }
        let t = Instant::now();
        let result = std::panic::catch_unwind(|| case(&text, &dir));
        let took = t.elapsed();
        cases += 1;
        match result {
            Ok(Outcome::Refused) => refused += 1,
            Ok(Outcome::Planned) => planned += 1,
            Ok(Outcome::Ran) => ran += 1,
            Err(_) => {
                eprintln!("PANIC on case {cases}:\n{text}");
                std::process::exit(1);
            }
        }
        if took > CASE_LIMIT {
            eprintln!("HANG: case {cases} took {took:?}:\n{text}");
            std::process::exit(1);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    println!(
        "fuzz_numbers: {cases} cases in {:.0} s (seed {seed}): {refused} refused with an error, \
         {planned} planned only (over {RAY_BUDGET} rays), {ran} run in full; no panic, no hang",
        start.elapsed().as_secs_f64()
    );
}
