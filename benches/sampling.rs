//! Criterion benches of the sampling inverses: `SpherePoints::nearest` (cube-map grid) and
//! `SpherePoints::nearest_analytic` per set and count,
//! `SpherePoints::surrounding`, and `HemisphereLayout::to_texel` per layout. Inputs are seeded
//! directions, so runs are comparable.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use std::hint::black_box;
use visfield::sampling::rays::seeded_sphere_direction;
use visfield::sampling::{HemisphereLayout, LayoutKind, SphereKind, SpherePoints};

const QUERIES: usize = 4096;

fn directions(seed: u64) -> Vec<Vec3> {
    (0..QUERIES as u64)
        .map(|i| seeded_sphere_direction(i, seed))
        .collect()
}

fn nearest(c: &mut Criterion) {
    let dirs = directions(1);
    let mut group = c.benchmark_group("nearest");
    group.throughput(Throughput::Elements(QUERIES as u64));
    for (kind, count) in [
        (SphereKind::Slater, 290),
        (SphereKind::Slater, 1090),
        (SphereKind::Slater, 4226),
        (SphereKind::Slater, 16642),
        (SphereKind::LatLong, 1122),
        (SphereKind::Fibonacci, 1090),
        (SphereKind::Fibonacci, 16642),
    ] {
        let set = SpherePoints::new(kind, count).expect("valid count");
        group.bench_function(BenchmarkId::new(kind.name(), count), |b| {
            b.iter(|| {
                dirs.iter()
                    .map(|&d| set.nearest(black_box(d)))
                    .sum::<usize>()
            })
        });
        // The analytic query without the cube-map grid (ring bracketing, Keinert et al. plus
        // certificate): the grid's construction oracle.
        group.bench_function(
            BenchmarkId::new(format!("{}_analytic", kind.name()), count),
            |b| {
                b.iter(|| {
                    dirs.iter()
                        .map(|&d| set.nearest_analytic(black_box(d)))
                        .sum::<usize>()
                })
            },
        );
        if kind == SphereKind::Fibonacci {
            group.bench_function(BenchmarkId::new("fibonacci_keinert", count), |b| {
                b.iter(|| {
                    dirs.iter()
                        .map(|&d| set.nearest_keinert(black_box(d)).unwrap_or(0))
                        .sum::<usize>()
                })
            });
        }
    }
    group.finish();
}

fn surrounding(c: &mut Criterion) {
    let dirs = directions(2);
    let mut group = c.benchmark_group("surrounding");
    group.throughput(Throughput::Elements(QUERIES as u64));
    for (kind, count) in [
        (SphereKind::Slater, 1090),
        (SphereKind::LatLong, 1122),
        (SphereKind::Fibonacci, 1090),
    ] {
        let set = SpherePoints::new(kind, count).expect("valid count");
        group.bench_function(BenchmarkId::new(kind.name(), count), |b| {
            b.iter(|| {
                dirs.iter()
                    .map(|&d| set.surrounding(black_box(d)).0[0])
                    .sum::<usize>()
            })
        });
    }
    group.finish();
}

fn to_texel(c: &mut Criterion) {
    let dirs: Vec<Vec3> = directions(3)
        .into_iter()
        .map(|d| Vec3::new(d.x, d.y, d.z.abs()))
        .collect();
    let mut group = c.benchmark_group("to_texel");
    group.throughput(Throughput::Elements(QUERIES as u64));
    for kind in LayoutKind::ALL {
        for res in [32, 256] {
            let layout = HemisphereLayout::new(kind, res);
            group.bench_function(BenchmarkId::new(kind.name(), res), |b| {
                b.iter(|| {
                    dirs.iter()
                        .map(|&d| layout.to_texel(black_box(d)))
                        .sum::<u32>()
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, nearest, surrounding, to_texel);
criterion_main!(benches);
