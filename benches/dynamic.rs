//! Frame time of a moving crowd against its caster count, for every method of
//! `experiment dynamic`: our ray caster with its world BVH rebuilt per frame, in two levels
//! (top level rebuilt), Embree rebuilt and with instance geometries (with `--features embree`),
//! and the fields (transforms placed; every sphere per ray, or the sphere BVH). One iteration
//! is one frame: the method's update to the frame's transforms and the vertex AO of the receiver
//! plane (`Crowd::step`), frames taken in turn.
//!
//! `cargo bench --bench dynamic` (add `--features embree` for Embree). The crowds are the quick
//! profile's (supershapes of 2,000 and 4,000 triangles, 16 rays per point, fields of
//! 290 × 16² u8 maps) with 1, 4, 16 and 64 casters, so that no model files are needed; the full
//! sweep over real models is `experiment dynamic` (results/dynamic/).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::time::Duration;
use visfield::experiment::dynamic::crowd::{Crowd, Profile};
use visfield::experiment::fields::FieldSupply;

fn frame_time(c: &mut Criterion) {
    let mut p = Profile::new(true);
    p.counts = vec![1, 4, 16, 64];
    let supply = FieldSupply {
        cache: None,
        cache_limit: 0,
        memory_limit: 1 << 30,
    };
    let mut g = c.benchmark_group("dynamic_frame");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    for &n in &p.counts {
        let crowd = Crowd::new(&p, n, &supply).expect("crowd");
        g.throughput(Throughput::Elements(n as u64));
        for mut mover in crowd.movers().expect("movers") {
            let name = mover.name();
            let mut f = 0;
            g.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                b.iter(|| {
                    f += 1;
                    crowd.step(&p, mover.as_mut(), f).expect("frame")
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, frame_time);
criterion_main!(benches);
