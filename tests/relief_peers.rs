//! The modern peers of the 2005 relief search (cell walk, maximum mipmaps, cone and relaxed
//! cone stepping) against the exact reference on every pixel of several views and on seeded
//! grazing rays, over the five datasets, an all-zero map and a map of one-texel needles; and,
//! where a Vulkan adapter exists (lavapipe in CI), their WGSL twins against the CPU.
//!
//! The peers run in f32, the reference in f64. A peer's f32 arithmetic perturbs the surface it
//! sees by at most `EPS` in height (grid coordinates up to `W` carry a unit roundoff of
//! `2⁻²⁴`, a dozen roundings, and a bilinear patch rises at most 1 per cell), so its first hit
//! lies between the exact first hits on the surface raised by `EPS` and lowered by `EPS`
//! (raising a surface only brings its first hit closer); a ray that passes within `EPS` of the
//! surface may go either way, and does not count as a disagreement.

use glam::{Vec2, Vec3};
use visfield::relief::height::Lcg;
use visfield::relief::peers::{cone, render_peer, Peer, PeerData, CONE_CAP};
use visfield::relief::view::{clip_to_prism, View};
use visfield::relief::{exact, Cast, Dataset, HeightMap};

mod common;

const N: usize = 64;
/// Height tolerance of the f32 peers (see the file doc): 32·N·2⁻²⁴ ≈ 1.2·10⁻⁴ at N = 64.
const EPS: f32 = 32.0 * N as f32 / (1u32 << 24) as f32;
/// λ tolerance: a few ulps of λ ≤ √3.
const TOL: f32 = 1e-5;

/// The maps: the five datasets, all zero, and one-texel needles of height 1 every 7 texels.
fn maps() -> Vec<(&'static str, HeightMap)> {
    let mut v: Vec<_> = Dataset::ALL.iter().map(|d| (d.name(), d.map(N))).collect();
    v.push(("zero", HeightMap::new(N, N, vec![0.0; N * N])));
    let needles = (0..N * N)
        .map(|k| {
            if (k % N) % 7 == 3 && (k / N) % 7 == 3 {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    v.push(("needles", HeightMap::new(N, N, needles)));
    v
}

/// The whole lid of a prism as high as wide, seen from `angle_deg` (so that the angle is the
/// rays' own in prism coordinates, up to grazing).
fn view(angle_deg: f32) -> View {
    View {
        depth: 1.0,
        ..View::lid(angle_deg, 40)
    }
}

/// The views: perpendicular to grazing.
const ANGLES: [f32; 4] = [0.0, 45.0, 75.0, 88.0];

/// Every pixel's segment of every view, and seeded grazing segments: from a point in the
/// prism along a direction at most 8° off the base plane (half of them slightly upward).
fn segments() -> Vec<(Vec3, Vec3)> {
    let mut v: Vec<(Vec3, Vec3)> = ANGLES
        .iter()
        .flat_map(|&a| {
            let w = view(a);
            (0..w.width * w.height).filter_map(move |k| w.segment(k))
        })
        .collect();
    let mut rng = Lcg(2008);
    let mut rnd = || rng.next_f32();
    for k in 0..4000 {
        let p = Vec3::new(rnd(), rnd(), 0.2 + 0.8 * rnd());
        let phi = std::f32::consts::TAU * rnd();
        let slope = (8.0f32 * rnd()).to_radians().tan() * if k % 2 == 0 { -1.0 } else { 0.3 };
        let d = Vec3::new(phi.cos(), phi.sin(), slope).normalize();
        if let Some(s) = clip_to_prism(p - 4.0 * d, d) {
            v.push(s);
        }
    }
    v
}

fn key(h: Option<f32>) -> f32 {
    h.unwrap_or(f32::INFINITY)
}

/// The exact first hits on the surface raised and lowered by `EPS` (`None` when the entry is
/// within `EPS` of the surface: either answer stands).
fn bracket(map: &HeightMap, e: Vec3, x: Vec3) -> Option<(f32, f32)> {
    let de = e.z - map.sample(Vec2::new(e.x, e.y));
    if de.abs() <= EPS {
        return None;
    }
    let dz = Vec3::Z * EPS;
    Some((
        key(exact(map, e - dz, x - dz)),
        key(exact(map, e + dz, x + dz)),
    ))
}

/// Checks `peer` on every segment of every map with `check(answer, lo, hi, exact)`, returning
/// per map the mean fetches and, over the rays whose bracket is tight (`hi − lo ≤ 10⁻⁴`: the
/// exact answer does not depend on rounding), the share of answers equal to the exact hit
/// (to 10⁻⁴).
fn sweep(peer: Peer, check: impl Fn(&str, Cast, f32, f32, Option<f32>)) -> Vec<(String, f64, f64)> {
    let segs = segments();
    maps()
        .into_iter()
        .map(|(name, map)| {
            let data = PeerData::new(&map);
            let (mut fetches, mut same, mut tight) = (0u64, 0usize, 0usize);
            for &(e, x) in &segs {
                let c = data.cast(&map, &peer, e, x);
                fetches += c.fetches as u64;
                let want = exact(&map, e, x);
                let Some((lo, hi)) = bracket(&map, e, x) else { continue };
                check(name, c, lo, hi, want);
                if lo == hi || hi - lo <= 1e-4 {
                    tight += 1;
                    same += match (c.hit, want) {
                        (None, None) => 1,
                        (Some(a), Some(b)) => ((a - b).abs() <= 1e-4) as usize,
                        _ => 0,
                    };
                }
            }
            let row = (name.to_string(), fetches as f64 / segs.len() as f64, same as f64 / tight as f64);
            eprintln!(
                "{} {name}: {:.2} fetches/ray, {:.4} of {tight} tight rays equal to exact ({} rays)",
                peer.label(),
                row.1,
                row.2,
                segs.len()
            );
            row
        })
        .collect()
}

/// The cell walk and the max mip find the exact first hit (up to the f32 bracket) on every
/// segment; the max mip reads fewer texels than the walk wherever rays run long over the map.
fn exact_peers_find_the_exact_first_hit() {
    let exactly = |peer: Peer| {
        move |name: &str, c: Cast, lo: f32, hi: f32, want: Option<f32>| {
            let h = key(c.hit);
            assert!(
                lo - TOL <= h && h <= hi + TOL,
                "{} on {name}: {:?} outside [{lo}, {hi}] (exact {want:?})",
                peer.label(),
                c.hit
            );
        }
    };
    let walk = sweep(Peer::CellWalk, exactly(Peer::CellWalk));
    let mip = sweep(Peer::MaxMip, exactly(Peer::MaxMip));
    for (w, m) in walk.iter().zip(&mip) {
        // Where rounding cannot matter, the answer is the exact one.
        assert!(w.2 == 1.0 && m.2 == 1.0, "{w:?} {m:?}");
        // Most rays of these views and the grazing set cross many empty cells, which the
        // max mip skips; not on the needle maps, where every node of 8 × 8 cells or more holds
        // a needle of height 1 and nothing above the floor is skipped, nor on white noise,
        // where every node of a few cells holds a peak near 1 (the descents cost more than the
        // walk).
        if !matches!(w.0.as_str(), "needles" | "noise") {
            assert!(m.1 < w.1, "max mip {m:?} vs walk {w:?}");
        }
    }
}

/// The max mip answers as the cell walk does, ray for ray (both solve the same cells in the
/// same f32 operations), on the views and the grazing set.
fn max_mip_answers_as_the_cell_walk() {
    let segs = segments();
    for (name, map) in maps() {
        let data = PeerData::new(&map);
        let mut differ = 0;
        for &(e, x) in &segs {
            let a = data.cast(&map, &Peer::CellWalk, e, x);
            let b = data.cast(&map, &Peer::MaxMip, e, x);
            let same = match (a.hit, b.hit) {
                (None, None) => true,
                (Some(p), Some(q)) => (p - q).abs() <= TOL,
                _ => false,
            };
            differ += !same as usize;
        }
        // The two agree but where a ray passes within a rounding of a cell corner (the walk
        // steps through it by comparing exits, the max mip by flooring the position).
        assert!(
            differ * 1000 <= segs.len(),
            "{name}: {differ} of {}",
            segs.len()
        );
        eprintln!(
            "{name}: max mip ≠ cell walk on {differ} of {} rays",
            segs.len()
        );
    }
}

/// Conservative cones never step past the first hit (on the surface lowered by EPS), and a
/// walk only advances: with 256 steps each ray ends at or after where 16 steps end (the first
/// 16 steps are the same), or both leave the segment.
fn conservative_cones_never_pass_the_first_hit() {
    let rows = sweep(Peer::Cone { steps: 256 }, |name, c, _lo, hi, want| {
        assert!(
            key(c.hit) <= hi + TOL,
            "cone on {name}: {:?} past the first hit {hi} (exact {want:?})",
            c.hit
        );
    });
    let segs = segments();
    for (name, map) in maps() {
        let data = PeerData::new(&map);
        for &(e, x) in &segs {
            let a = data.cast(&map, &Peer::Cone { steps: 16 }, e, x);
            let b = data.cast(&map, &Peer::Cone { steps: 256 }, e, x);
            assert!(
                key(b.hit) >= key(a.hit),
                "{name}: 256 steps {b:?} before 16 {a:?}"
            );
            assert!(b.fetches >= a.fetches, "{name}: {b:?} {a:?}");
        }
    }
    // On the flat map the widest cones reach the floor in one step.
    let zero = rows.iter().find(|r| r.0 == "zero").unwrap();
    assert!(zero.2 == 1.0 && zero.1 < 5.0, "{zero:?}");
}

/// Relaxed cones: a step that lands below the surface crossed it; after B bisections the
/// answer lies within step / 2^B after a crossing (the sub-segment has an exact hit), so it is
/// never before the first hit. (It may be after it: a sampled relaxed cone can step over a
/// thin feature; the share at the first hit is printed.)
fn relaxed_cones_bisect_to_a_crossing() {
    let (steps, b) = (32, 10);
    let segs = segments();
    for (name, map) in maps() {
        let data = PeerData::new(&map);
        let (mut bisected, mut first) = (0usize, 0usize);
        for &(e, x) in &segs {
            let t = cone::cast(&map, &data.cones.relaxed, e, x, steps, Some(b));
            let Some((la, lb)) = t.bracket else { continue };
            bisected += 1;
            let l = t.cast.hit.unwrap();
            let r = (x - e).normalize();
            let width = (lb - la) / (1u32 << b) as f32;
            assert!(la < l && l <= lb, "{name}: {l} outside ({la}, {lb}]");
            // A crossing of the exact surface within [l − width, l], up to EPS in height.
            let (p, q) = (
                e + (l - width - TOL) * r + Vec3::Z * EPS,
                e + l * r - Vec3::Z * EPS,
            );
            assert!(
                exact(&map, p, q).is_some(),
                "{name}: no crossing in [{}, {l}]",
                l - width
            );
            if let Some((lo, hi)) = bracket(&map, e, x) {
                assert!(l >= lo - TOL, "{name}: {l} before the first hit {lo}");
                first += (l <= hi + 1e-3) as usize;
            }
        }
        eprintln!("relaxed {name}: {bisected} bisected, {first} at the first hit");
        assert!(
            bisected > 1000,
            "{name}: {bisected} rays bisected, too few to test"
        );
    }
}

/// Conservative ratios are valid: for seeded points p in a footprint and q anywhere,
/// |q − p| ≥ c·(M(q) − M(p)) (up to rounding); relaxed ratios are never below them; on a flat
/// map every ratio is the cap (nothing is higher than anything).
fn cone_ratios_are_valid() {
    for (name, map) in maps() {
        let data = PeerData::new(&map);
        let c = &data.cones;
        assert!(
            c.relaxed.iter().zip(&c.conservative).all(|(r, k)| r >= k),
            "{name}"
        );
        if name == "zero" {
            // The cap, less the rounding margin of 10⁻⁶.
            let cap = (CONE_CAP as f64 * (1.0 - 1e-6)) as f32;
            assert!(c.conservative.iter().all(|&v| v == cap), "{name}");
            assert!(c.relaxed.iter().all(|&v| v == CONE_CAP), "{name}");
            continue;
        }
        let mut rng = Lcg(18);
        let mut rnd = || rng.next_f32();
        for _ in 0..20_000 {
            let (ti, tj) = ((rnd() * N as f32) as usize, (rnd() * N as f32) as usize);
            let p = Vec2::new(
                (ti as f32 + rnd()) / N as f32,
                (tj as f32 + rnd()) / N as f32,
            );
            let q = if rnd() < 0.5 {
                p + (Vec2::new(rnd(), rnd()) - 0.5) * (6.0 / N as f32)
            } else {
                Vec2::new(rnd(), rnd())
            };
            let q = q.clamp(Vec2::ZERO, Vec2::ONE);
            let rise = map.sample(q) - map.sample(p);
            let k = c.conservative[tj * N + ti];
            assert!(
                (q - p).length() >= k * rise - 1e-5,
                "{name}: texel ({ti}, {tj}) ratio {k}: |q − p| = {} < {k}·{rise}",
                (q - p).length()
            );
        }
    }
}

/// Bad settings are refused with the field named; rendering with a valid peer gives a frame.
fn settings_are_checked() {
    let map = Dataset::Simple.map(16);
    let data = PeerData::new(&map);
    let err = render_peer(&map, &data, &view(30.0), &Peer::Cone { steps: 0 })
        .err()
        .unwrap();
    assert!(err.contains("steps") && err.contains('0'), "{err}");
    let err = render_peer(
        &map,
        &data,
        &view(30.0),
        &Peer::RelaxedCone {
            steps: 8,
            bisections: 1 << 20,
        },
    )
    .err()
    .unwrap();
    assert!(err.contains("bisections"), "{err}");
    let other = Dataset::Simple.map(8);
    assert!(render_peer(&other, &data, &view(30.0), &Peer::MaxMip).is_err());
    let f = render_peer(&map, &data, &view(30.0), &Peer::MaxMip).unwrap();
    assert!(f.hit.iter().filter(|h| **h).count() > 100);
}

/// The WGSL peers answer as the CPU peers, ray for ray: the same hit or miss, λ to 10⁻⁵ and the
/// same fetch count on at least 99 % of the segments (the two run the same f32 operations;
/// a driver may fuse a multiply and an add, which moves a ray within a rounding of the surface
/// or of a cell corner to the other side), and every GPU answer meets the CPU's own check
/// against the exact reference (the f32 bracket; for cones, never past the first hit).
fn gpu_peers_match_the_cpu() {
    use visfield::gpu::ReliefPeersKernel;
    let Some(ctx) = common::gpu_context() else {
        return;
    };
    let segs = segments();
    let peers = [
        Peer::CellWalk,
        Peer::MaxMip,
        Peer::Cone { steps: 64 },
        Peer::RelaxedCone {
            steps: 32,
            bisections: 10,
        },
    ];
    for (name, map) in maps() {
        let data = PeerData::new(&map);
        let kernel = ReliefPeersKernel::new(ctx, &map, &data).unwrap();
        for peer in &peers {
            let (gpu, _) = kernel.cast(&segs, peer).unwrap();
            assert_eq!(gpu.len(), segs.len());
            let (mut same, mut same_fetches) = (0usize, 0usize);
            for (&(e, x), g) in segs.iter().zip(&gpu) {
                let c = data.cast(&map, peer, e, x);
                same += match (g.hit, c.hit) {
                    (None, None) => true,
                    (Some(a), Some(b)) => (a - b).abs() <= TOL,
                    _ => false,
                } as usize;
                same_fetches += (g.fetches == c.fetches) as usize;
                let Some((lo, hi)) = bracket(&map, e, x) else {
                    continue;
                };
                let h = key(g.hit);
                match peer {
                    Peer::CellWalk | Peer::MaxMip => assert!(
                        lo - TOL <= h && h <= hi + TOL,
                        "GPU {} on {name}: {:?} outside [{lo}, {hi}] (CPU {:?})",
                        peer.label(),
                        g.hit,
                        c.hit
                    ),
                    Peer::Cone { .. } => assert!(
                        h <= hi + TOL || hi.is_infinite(),
                        "GPU cone on {name}: {:?} past {hi}",
                        g.hit
                    ),
                    Peer::RelaxedCone { .. } => {}
                }
            }
            let n = segs.len();
            eprintln!(
                "GPU {} {name}: {same}/{n} same answer, {same_fetches}/{n} same fetches",
                peer.label()
            );
            assert!(
                same * 100 >= 99 * n && same_fetches * 100 >= 99 * n,
                "{} {name}",
                peer.label()
            );
        }
    }
}

/// Bad settings, segments and a mismatched map are refused before any dispatch, naming the
/// field; a frame rendered on the GPU is the CPU's frame.
fn gpu_peers_refuse_bad_settings() {
    use visfield::gpu::{GpuError, ReliefPeersKernel};
    let Some(ctx) = common::gpu_context() else {
        return;
    };
    let map = Dataset::Simple.map(16);
    let data = PeerData::new(&map);
    let kernel = ReliefPeersKernel::new(ctx, &map, &data).unwrap();
    let segs = [(Vec3::new(0.5, 0.5, 1.0), Vec3::new(0.6, 0.5, 0.0))];
    let err = kernel.cast(&segs, &Peer::Cone { steps: 0 }).err().unwrap();
    assert!(
        matches!(err, GpuError::Invalid(_)) && err.to_string().contains("steps"),
        "{err}"
    );
    for bad in [
        [(Vec3::new(f32::NAN, 0.5, 1.0), Vec3::ONE)],
        [(Vec3::new(0.5, 0.5, 1.0), Vec3::new(2.0, 0.5, 0.0))],
    ] {
        let err = kernel.cast(&bad, &Peer::MaxMip).err().unwrap();
        assert!(err.to_string().contains("segment 0"), "{err}");
    }
    let other = Dataset::Simple.map(8);
    assert!(ReliefPeersKernel::new(ctx, &other, &data).is_err());
    // Hits come back as the CPU's (one segment, straight down onto the smooth map).
    let (got, _) = kernel.cast(&segs, &Peer::MaxMip).unwrap();
    assert_eq!(got[0], data.cast(&map, &Peer::MaxMip, segs[0].0, segs[0].1));
    // A GPU frame is the CPU frame (every pixel's answer and fetches agreed above).
    let v = view(45.0);
    let (gpu, _) = visfield::relief::view::render_gpu(&kernel, &map, &v, &Peer::MaxMip).unwrap();
    let cpu = render_peer(&map, &data, &v, &Peer::MaxMip).unwrap();
    assert_eq!(gpu.hit, cpu.hit);
    assert_eq!(gpu.fetches, cpu.fetches);
    assert_eq!(gpu.image.data, cpu.image.data);
}

fn main() {
    common::run_gpu_trials(
        "relief_peers",
        &[
            ("gpu_peers_match_the_cpu", gpu_peers_match_the_cpu),
            (
                "gpu_peers_refuse_bad_settings",
                gpu_peers_refuse_bad_settings,
            ),
        ],
        &[
            (
                "exact_peers_find_the_exact_first_hit",
                exact_peers_find_the_exact_first_hit,
            ),
            (
                "max_mip_answers_as_the_cell_walk",
                max_mip_answers_as_the_cell_walk,
            ),
            (
                "conservative_cones_never_pass_the_first_hit",
                conservative_cones_never_pass_the_first_hit,
            ),
            (
                "relaxed_cones_bisect_to_a_crossing",
                relaxed_cones_bisect_to_a_crossing,
            ),
            ("cone_ratios_are_valid", cone_ratios_are_valid),
            ("settings_are_checked", settings_are_checked),
        ],
    );
}
