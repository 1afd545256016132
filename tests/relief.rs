//! The 2005 relief caster in the harness: `experiment relief --quick` writes its tables, and
//! the properties the paper's Tables 1–3 rest on hold in them; where a Vulkan adapter exists
//! (lavapipe in CI) its GPU columns are filled and its frames match the CPU's. Beside it, the
//! caster's own guarantees on the views and maps the experiment uses: the views enter through
//! the lid, floors at height 0 are found, and skipping never loses a hit the search without
//! skips finds.

use visfield::experiment::relief::{
    run, Population, Reference, ANGLES, PEERS, QUALITY_DATASETS, QUALITY_RATES, RATE_SETTINGS,
};
use visfield::gpu::AdapterPreference;
use visfield::relief::cast::skip;
use visfield::relief::view::View;
use visfield::relief::{
    exact, intersect, CastParams, Dataset, HeightMap, SafetyZones, PAPER_BOXES,
};

/// At every angle of the table, whole lid and close-up, every pixel's ray enters the prism
/// through the lid (z = 1, inside the square) and goes down: none through a side wall, none
/// upward, so no pixel is culled at the entry.
#[test]
fn every_view_enters_through_the_lid_going_down() {
    let map = Dataset::Relief.map(64);
    for angle in ANGLES {
        for view in [View::lid(angle, 32), View::close_up(angle, 32)] {
            for k in 0..32 * 32 {
                let (e, x) = view.segment(k).expect("every pixel meets the prism");
                assert_eq!(e.z, 1.0, "{angle}° pixel {k}: enters at {e}");
                assert!(
                    (0.0..=1.0).contains(&e.x) && (0.0..=1.0).contains(&e.y),
                    "{e}"
                );
                assert!(x.z < e.z, "{angle}° pixel {k}: {e} -> {x} does not go down");
            }
            let reference = Reference::new(&map, &view);
            assert!(!reference.populations.contains(&Population::Culled));
        }
    }
}

/// On an all-zero map every ray that leaves through the floor meets the surface at its end,
/// and one that leaves through a side wall does not; the search (with and without skips and
/// bisection) and the exact reference agree on every pixel.
#[test]
fn all_zero_map_every_floor_ray_is_a_hit() {
    let map = HeightMap::new(16, 16, vec![0.0; 256]);
    let zones = SafetyZones::new(&map, &PAPER_BOXES);
    for angle in ANGLES {
        let view = View::lid(angle, 48);
        let mut floor = 0;
        for k in 0..48 * 48 {
            let (e, x) = view.segment(k).unwrap();
            let len = (x - e).length();
            let want = (x.z == 0.0).then_some(len);
            floor += want.is_some() as usize;
            assert_eq!(exact(&map, e, x), want, "{angle}° pixel {k}: {e} -> {x}");
            for (rate, bisections, skips) in [(75.0, 2, 0), (75.0, 2, 2), (10.0, 0, 1)] {
                let p = CastParams {
                    samples_per_unit: rate,
                    bisections,
                    skips,
                };
                let got = intersect(&map, Some(&zones), e, x, &p).hit;
                match (want, got) {
                    (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-6, "{p:?}: {a} vs {b}"),
                    (None, None) => {}
                    _ => panic!("{angle}° pixel {k} {p:?}: {got:?}, want {want:?}"),
                }
            }
        }
        // Straight down every ray reaches the floor; at 75° only those from the near part of
        // the lid do, the rest leave through the walls first. At least a row of them.
        assert!(floor >= 48, "{angle}°: {floor}");
    }
}

/// On `spikes` (28.5% of its texels 0), every pixel whose exact first hit is the floor under a
/// zero texel is found there by the search at Table 2's settings, with and without skips.
#[test]
fn spikes_floor_pixels_are_all_found() {
    let map = Dataset::Spikes.map(256);
    let zones = SafetyZones::new(&map, &PAPER_BOXES);
    for angle in [0.0, 30.0, 45.0] {
        let view = View::lid(angle, 128);
        let mut floor = 0;
        for k in 0..128 * 128 {
            let (e, x) = view.segment(k).unwrap();
            let len = (x - e).length();
            let Some(h) = exact(&map, e, x) else { continue };
            if x.z != 0.0 || (h - len).abs() > 1e-6 {
                continue;
            }
            floor += 1;
            for skips in 0..=2 {
                let p = CastParams {
                    samples_per_unit: 75.0,
                    bisections: 2,
                    skips,
                };
                let got = intersect(&map, Some(&zones), e, x, &p).hit;
                assert!(
                    got.is_some_and(|g| (g - h).abs() <= 1e-5),
                    "{angle}° pixel {k} skips {skips}: {got:?} vs the floor at {h}"
                );
            }
        }
        assert!(
            floor >= 128,
            "{angle}°: {floor} floor pixels (at least a row)"
        );
    }
}

/// Thin needles and noise at grazing angles: the search with 1–2 rounds of skips finds a hit
/// exactly where the search without skips at the same samples per unit does. Its samples are
/// the same lattice points (`intersect`), the skipped ones lie in empty space, so the hit is
/// the same bit for bit, except where the backward skip cut the segment inside the solid
/// below the surface before the zero-skip search's bracketing sample: there both bracket the
/// same crossing and differ by less than one sample step. (Neither is bounded below by the
/// exact first hit: the interpolating bisection can land before it on a curved surface.)
#[test]
fn skips_never_lose_a_hit_the_search_without_skips_finds() {
    for dset in [Dataset::Needles, Dataset::Noise, Dataset::Spikes] {
        let map = dset.map(128);
        let zones = SafetyZones::new(&map, &PAPER_BOXES);
        let (mut same, mut cut, mut hits) = (0usize, 0usize, 0usize);
        for angle in [60.0, 75.0, 85.0] {
            let view = View::lid(angle, 64);
            for (rate, bisections) in [(10.0, 0), (10.0, 2), (40.0, 2), (75.0, 2)] {
                let step = 1.0 / rate;
                for k in 0..64 * 64 {
                    let (e, x) = view.segment(k).unwrap();
                    let p = |skips| CastParams {
                        samples_per_unit: rate,
                        bisections,
                        skips,
                    };
                    let h0 = intersect(&map, Some(&zones), e, x, &p(0)).hit;
                    let truth = exact(&map, e, x);
                    hits += h0.is_some() as usize;
                    for skips in 1..=2 {
                        let hs = intersect(&map, Some(&zones), e, x, &p(skips)).hit;
                        let ctx = || format!("{dset:?} {angle}° {:?} pixel {k}", p(skips));
                        assert_eq!(hs.is_some(), h0.is_some(), "{}: {hs:?} vs {h0:?}", ctx());
                        let (Some(a), Some(b)) = (h0, hs) else {
                            continue;
                        };
                        assert!(truth.is_some(), "{}: no exact hit", ctx());
                        if a == b {
                            same += 1;
                            continue;
                        }
                        let len = (x - e).length();
                        let (_, l2) = skip(&zones, e, (x - e) / len, len, skips, &mut 0)
                            .expect("segment not empty");
                        assert!(
                            l2 < a + step && (a - b).abs() < step,
                            "{}: {b} with skips, {a} without, segment end {l2}",
                            ctx()
                        );
                        cut += 1;
                    }
                }
            }
        }
        eprintln!("{dset:?}: {same} hits identical, {cut} within a step (tail cut), {hits} hits");
        assert!(hits > 10_000 && same > cut, "{dset:?}");
    }
}

#[test]
fn relief_quick_writes_tables_where_skipping_removes_fetches() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("relief");
    let rows = run(&out, true, Some(AdapterPreference::from_env())).unwrap();
    for f in [
        "renderings.csv",
        "paper_vs_ours.csv",
        "fetches_vs_angle.png",
        "fetch_gain_vs_angle.png",
        "time_vs_angle.png",
        "missed_vs_angle.png",
        "missed_vs_rate.png",
        "pareto.png",
        "images.png",
        "quality_needles.png",
        "quality_relief.png",
        "run.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // Five maps × six angles × (0–2 skips with the paper's δ, 1–2 with half of it), the
    // sample-rate table and the quality table.
    // The quick profile runs the peers on `simple` only.
    let n = Dataset::ALL.len();
    let count = |t: &str| rows.iter().filter(|r| r.table == t).count();
    assert_eq!(
        count("angles"),
        n * ANGLES.len() * 5 + PEERS.len() * ANGLES.len()
    );
    assert!(out.join("methods_error_vs_fetches.png").is_file());
    assert!(out.join("methods_error_vs_time.png").is_file());
    assert_eq!(count("rates"), RATE_SETTINGS.len() * 3);
    assert_eq!(
        count("quality"),
        QUALITY_DATASETS.len() * QUALITY_RATES.len() * 3
    );
    for r in &rows {
        if r.method != "paper-skips" {
            assert!(PEERS.iter().any(|p| p.1 == r.method), "{r:?}");
            assert_eq!(
                (r.table, r.dataset, r.skips),
                ("angles", "simple", 0),
                "{r:?}"
            );
            assert!(r.setup_s.is_some(), "{r:?}");
            // The exact peers find every surface pixel's first hit.
            if matches!(r.method, "cell-walk" | "max-mip") {
                assert_eq!(r.missed_share, 0.0, "{r:?}");
            }
            if let Some(d) = r.gpu_hit_mismatches_vs_cpu {
                assert_eq!(d, 0, "{r:?}");
            }
        }
        assert_eq!(
            r.surface_pixels + r.no_hit_pixels + r.culled_pixels,
            r.pixels
        );
        assert_eq!(r.culled_pixels, 0, "{r:?}");
        assert!(r.surface_pixels > 0 && r.surface_fetches >= 1.0, "{r:?}");
        // Every pixel's fetches: the mean over all is the population means' weighted sum.
        let parts = r.surface_fetches * r.surface_pixels as f64
            + if r.no_hit_pixels > 0 {
                r.no_hit_fetches * r.no_hit_pixels as f64
            } else {
                0.0
            };
        assert!((parts - r.fetches_per_pixel * r.pixels as f64).abs() < 1e-6 * parts);
        assert!(r.rms_vs_exact.is_finite() && r.rms_vs_exact >= 0.0, "{r:?}");
        assert!((0.0..=1.0).contains(&r.missed_share), "{r:?}");
        if r.skips == 0 && r.method == "paper-skips" {
            assert_eq!(r.surface_fetch_reduction, 1.0);
            assert_eq!(r.delta_rule, "paper");
        }
    }
    let find = |d: &str, angle: f32, skips: u32, rule: &str| {
        rows.iter()
            .find(|r| {
                r.table == "angles"
                    && r.method == "paper-skips"
                    && r.dataset == d
                    && r.view_deg == angle
                    && r.skips == skips
                    && r.delta_rule == rule
            })
            .unwrap()
    };
    // Looking straight down on the smooth maps, skipping removes most of the empty space
    // above them (the paper's largest gains are at perpendicular views).
    for d in ["simple", "relief"] {
        let r = find(d, 0.0, 2, "paper");
        assert!(r.surface_fetch_reduction > 1.5, "{d}: {r:?}");
    }
    // The lattice-aligned search loses no hit to skipping: with skips a ray's hit is the same
    // as without, or (where the backward skip ends the segment inside the solid, before the
    // search's bracketing sample) taken from a shorter bracket around the same crossing, which
    // without bisection is always closer and with it nearly always. So the missed share does
    // not grow, up to a percent of bisection outliers.
    for r in rows.iter().filter(|r| r.skips > 0) {
        let base = rows
            .iter()
            .find(|b| {
                b.skips == 0
                    && (
                        b.table,
                        b.dataset,
                        b.view_deg,
                        b.samples_per_unit,
                        b.bisections,
                    ) == (
                        r.table,
                        r.dataset,
                        r.view_deg,
                        r.samples_per_unit,
                        r.bisections,
                    )
            })
            .unwrap();
        let slack = if r.bisections == 0 { 0.0 } else { 0.01 };
        assert!(
            r.missed_share <= base.missed_share + slack,
            "{r:?} vs {base:?}"
        );
    }
    // More samples per unit cost more fetches and do not lose accuracy against the exact
    // intersection (Table 3's trade-off).
    let rate = |s: f32| {
        rows.iter()
            .find(|r| {
                r.table == "rates" && r.samples_per_unit == s && r.bisections == 2 && r.skips == 0
            })
            .unwrap()
    };
    assert!(rate(75.0).surface_fetches > rate(10.0).surface_fetches);
    assert!(rate(75.0).rms_vs_exact <= rate(10.0).rms_vs_exact);
    // On thin needles at 75°, 10 samples per unit miss more surface than 150 do.
    let quality = |s: f32| {
        rows.iter()
            .find(|r| {
                r.table == "quality"
                    && r.dataset == "needles"
                    && r.samples_per_unit == s
                    && r.skips == 0
            })
            .unwrap()
    };
    assert!(quality(10.0).missed_share > quality(150.0).missed_share);
    let csv = std::fs::read_to_string(out.join("paper_vs_ours.csv")).unwrap();
    assert!(csv.lines().count() > 20, "{csv}");
    // The GPU columns: all rows or none (no Vulkan driver); the GPU frames are the CPU's but
    // for rays whose samples fall within a rounding of the surface.
    let gpu = rows.iter().filter(|r| r.gpu_adapter.is_some()).count();
    assert!(
        gpu == 0 || gpu == rows.len(),
        "{gpu} of {} rows",
        rows.len()
    );
    if gpu == 0 {
        eprintln!("no Vulkan adapter: GPU columns not checked");
        return;
    }
    assert!(out.join("gpu_time_vs_angle.png").is_file() || rows[0].gpu_kernel_s.is_none());
    for r in &rows {
        let differ = r.gpu_hit_mismatches_vs_cpu.unwrap();
        assert!(
            differ * 200 <= r.pixels,
            "{differ} of {} pixels: {r:?}",
            r.pixels
        );
        let fetches = r.gpu_fetches_per_pixel.unwrap();
        assert!(
            (fetches - r.fetches_per_pixel).abs() <= 0.01 * r.fetches_per_pixel,
            "{r:?}"
        );
        assert!(r.gpu_rms_vs_cpu.unwrap() <= 0.5, "{r:?}");
        assert!(r.gpu_wall_s.unwrap() > 0.0);
    }
}
