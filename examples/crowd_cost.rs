//! One frame of the moving crowd (`experiment dynamic`'s quick casters: supershapes of 2,000 and
//! 4,000 triangles over the receiver plane, 64 AO rays per point, u8 fields of 290 × 16² maps)
//! by each moving-scene method, at a chosen caster count: its time per ray on this machine's
//! threads, and, under valgrind, its instructions per ray.
//!
//! `cargo run --release --example crowd_cost [--features embree] -- N [METHOD] [FRAMES]`
//!
//! - N: the caster count, a perfect square (1, 4, 16, 64, 256, …).
//! - METHOD: one of `experiment dynamic`'s methods (`field`, `field_every_sphere`, `two_level`,
//!   `embree_instances`, …); all but the world rebuilds, the SDF and the AO fields when absent.
//! - FRAMES: frames timed per method (default 8); each frame's query is timed alone and the
//!   median is printed, with the rays per second it makes.
//!
//! For instruction counts, one method and one frame on one thread:
//! `RAYON_NUM_THREADS=1 valgrind --tool=callgrind --collect-atstart=no
//! --toggle-collect='*Crowd*step*' target/release/examples/crowd_cost 64 field 1`.

use std::time::Instant;
use visfield::experiment::dynamic::crowd::{Crowd, Profile};
use visfield::experiment::fields::FieldSupply;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(64);
    let only = args.get(1).cloned();
    let frames: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(8);
    let mut p = Profile::new(true);
    p.counts = vec![n];
    p.k = 8;
    let supply = FieldSupply {
        cache: Some(std::env::temp_dir().join("visfield-crowd-cost")),
        cache_limit: 1 << 30,
        memory_limit: 1 << 33,
    };
    let crowd = Crowd::new(&p, n, &supply).expect("crowd");
    let rays = crowd.ray_count();
    let skipped = ["world_rebuild", "embree_rebuild", "sdf", "aofield"];
    for mut mover in crowd.movers().expect("movers") {
        let name = mover.name();
        let chosen = match &only {
            Some(m) => m == name,
            None => !skipped.contains(&name),
        };
        if !chosen {
            continue;
        }
        let mut times = Vec::new();
        let mut sum = 0.0f64;
        for f in 0..frames {
            let t = Instant::now();
            let v = crowd.step(&p, mover.as_mut(), f).expect("frame");
            times.push(t.elapsed().as_secs_f64());
            sum += v.iter().map(|&x| x as f64).sum::<f64>();
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        println!(
            "{n:>4} casters {name:<20} {:>9.3} ms/frame {:>7.2} ns/ray {:>7.2} Mrays/s  (mean AO {:.6})",
            median * 1e3,
            median * 1e9 / rays as f64,
            rays as f64 / median / 1e6,
            sum / (frames * crowd.point_count()) as f64
        );
    }
}
