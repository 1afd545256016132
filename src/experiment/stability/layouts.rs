//! Frames, layouts and quantisation at their singular points.
//!
//! - Frames (Duff et al. 2017) at the poles, along ±x/±y/±z, a hair off them and with −0
//!   components, and every field frame of the sphere sets: orthonormal and right-handed.
//! - Layout texels for directions on texel boundaries, the concentric map's centre and
//!   diagonals, the last texel row and column, the horizon and below it: the texel
//!   [`HemisphereLayout::to_texel`] returns is in range, used, and its cell contains the
//!   direction's square point computed in f64 (distance 0 inside the cell).
//! - Quantisation of stored distances 0, just under 1 and exactly 1 at every precision, and the
//!   1-bit threshold.

use super::{max_of, StabilityRow};
use crate::field::storage::{Precision, Storage};
use crate::sampling::{Frame, HemisphereLayout, LayoutKind, SphereKind, SpherePoints};
use glam::{DVec2, DVec3, Vec3};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI, TAU};

/// Orthonormality and handedness error allowed for an f32 frame (a few ulps).
pub const FRAME_TOLERANCE: f64 = 1e-6;

/// Largest distance (in texels) allowed between a direction's f64 square point and the cell of
/// the texel returned: the f32 direction and the f32 inverse are within ~1e-6 of the square,
/// 3e-4 texels at 256², so this leaves a margin of three.
pub const TEXEL_TOLERANCE: f64 = 1e-3;

fn frame_error(n: Vec3) -> f64 {
    let f = Frame::from_normal(n);
    let (x, y, z) = (f.x.as_dvec3(), f.y.as_dvec3(), f.z.as_dvec3());
    let unit_n = n.as_dvec3().normalize();
    max_of([
        (x.length() - 1.0).abs(),
        (y.length() - 1.0).abs(),
        (z - unit_n).length(),
        x.dot(y).abs(),
        y.dot(z).abs(),
        z.dot(x).abs(),
        (x.cross(y) - z).length(),
    ])
}

/// Frames at the poles and axes, near them, with −0 components, and the frames of every map of
/// the sphere sets (Slater 290, lat-long 1122, Fibonacci 1000).
pub fn frames() -> Vec<StabilityRow> {
    let case = "frames_at_poles_and_axes";
    let mut axes = Vec::new();
    for a in 0..3 {
        for s in [1.0f32, -1.0] {
            let mut n = Vec3::ZERO;
            n[a] = s;
            axes.push(n);
            for eps in [1e-7f32, 1e-4] {
                for b in 0..3 {
                    if b != a {
                        let mut m = n;
                        m[b] = eps;
                        axes.push(m.normalize());
                        m[b] = -eps;
                        axes.push(m.normalize());
                    }
                }
            }
        }
    }
    axes.push(Vec3::new(-0.0, -0.0, 1.0));
    axes.push(Vec3::new(-0.0, 0.0, -1.0));
    axes.push(Vec3::new(1.0, -0.0, -0.0));
    let axis_err = max_of(axes.iter().map(|&n| frame_error(n)));
    let mut field_err = 0.0f64;
    let mut frames = 0;
    for (kind, count) in [
        (SphereKind::Slater, 290),
        (SphereKind::LatLong, 1122),
        (SphereKind::Fibonacci, 1000),
    ] {
        let pts = SpherePoints::new(kind, count).expect("valid sphere set");
        for f in crate::field::frames_for(&pts) {
            field_err = max_of([field_err, frame_error(f.z)]);
            frames += 1;
        }
    }
    vec![
        StabilityRow::new(
            case,
            format!(
                "poles and axes ± 1e-7, −0: orthonormality (of {})",
                axes.len()
            ),
            axis_err,
            FRAME_TOLERANCE,
        ),
        StabilityRow::new(
            case,
            format!("every field frame: orthonormality (of {frames})"),
            field_err,
            FRAME_TOLERANCE,
        ),
    ]
}

/// f64 hemisphere → disk, as `warp::hemisphere_to_disk` (below the horizon: onto the rim).
fn disk64(d: DVec3) -> DVec2 {
    let p = DVec2::new(d.x, d.y);
    if d.z < 0.0 {
        p.try_normalize().unwrap_or(DVec2::X)
    } else {
        p
    }
}

/// The layout's square point of `d` in f64 (the inverses of `sampling::warp`).
pub fn square64(kind: LayoutKind, d: DVec3) -> DVec2 {
    match kind {
        LayoutKind::Polar => {
            let theta = d.z.clamp(-1.0, 1.0).acos().min(FRAC_PI_2);
            let mut phi = d.y.atan2(d.x);
            if phi < 0.0 {
                phi += TAU;
            }
            let x = phi / TAU;
            DVec2::new(if x >= 1.0 { 0.0 } else { x }, theta / FRAC_PI_2)
        }
        LayoutKind::Rejection => {
            let p = disk64(d);
            let p = if p.length_squared() > 1.0 {
                p.normalize()
            } else {
                p
            };
            0.5 * (p + DVec2::ONE)
        }
        LayoutKind::Concentric => {
            let p = disk64(d);
            let r = p.length();
            if r == 0.0 {
                return DVec2::splat(0.5);
            }
            let mut phi = p.y.atan2(p.x);
            if phi < -FRAC_PI_4 {
                phi += TAU;
            }
            let (a, b) = if phi < FRAC_PI_4 {
                (r, r * phi / FRAC_PI_4)
            } else if phi < 3.0 * FRAC_PI_4 {
                (r * (FRAC_PI_2 - phi) / FRAC_PI_4, r)
            } else if phi < 5.0 * FRAC_PI_4 {
                (-r, -r * (phi - PI) / FRAC_PI_4)
            } else {
                (-r * (3.0 * FRAC_PI_2 - phi) / FRAC_PI_4, -r)
            };
            DVec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0))
        }
    }
}

/// The layout's forward map in f64: square point → unit direction.
fn direction64(kind: LayoutKind, u: DVec2) -> DVec3 {
    let disk = |p: DVec2| DVec3::new(p.x, p.y, (1.0 - p.length_squared()).max(0.0).sqrt());
    match kind {
        LayoutKind::Polar => {
            let (theta, phi) = (u.y * FRAC_PI_2, u.x * TAU);
            DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            )
        }
        LayoutKind::Rejection => disk((2.0 * u - DVec2::ONE).clamp_length_max(1.0)),
        LayoutKind::Concentric => {
            let (a, b) = (2.0 * u.x - 1.0, 2.0 * u.y - 1.0);
            if a == 0.0 && b == 0.0 {
                return DVec3::Z;
            }
            let (r, phi) = if a.abs() > b.abs() {
                (a, FRAC_PI_4 * (b / a))
            } else {
                (b, FRAC_PI_2 - FRAC_PI_4 * (a / b))
            };
            disk(DVec2::new(r * phi.cos(), r * phi.sin()))
        }
    }
}

/// The singular directions of a layout at `res`: square points on every texel boundary (both
/// axes, at texel centres and corners along the other), the centre, both diagonals, points a
/// hair inside the last row and column, the horizon at every eighth of a turn and a hair below
/// it, straight down.
fn singular_directions(kind: LayoutKind, res: u32) -> Vec<Vec3> {
    let n = res as f64;
    let mut squares = Vec::new();
    for i in 0..=res {
        let edge = i as f64 / n;
        for j in 0..res {
            for along in [(j as f64 + 0.5) / n, j as f64 / n] {
                squares.push(DVec2::new(edge, along));
                squares.push(DVec2::new(along, edge));
            }
        }
        // Diagonals (the concentric map's wedge boundaries).
        squares.push(DVec2::new(edge, edge));
        squares.push(DVec2::new(edge, 1.0 - edge));
    }
    for hair in [1e-9, 1e-7] {
        for j in 0..res {
            let along = (j as f64 + 0.5) / n;
            squares.push(DVec2::new(1.0 - hair, along));
            squares.push(DVec2::new(along, 1.0 - hair));
        }
        squares.push(DVec2::splat(1.0 - hair));
        squares.push(DVec2::splat(0.5 + hair));
    }
    squares.push(DVec2::splat(0.5));
    let mut dirs: Vec<Vec3> = squares
        .into_iter()
        .map(|u| direction64(kind, u).as_vec3())
        .collect();
    for k in 0..8 {
        let phi = k as f64 * FRAC_PI_4;
        for z in [0.0f64, -1e-7, 1e-7] {
            let s = (1.0 - z * z).sqrt();
            dirs.push(DVec3::new(s * phi.cos(), s * phi.sin(), z).as_vec3());
        }
    }
    dirs.push(Vec3::NEG_Z);
    dirs.push(Vec3::Z);
    dirs.push(Vec3::new(-0.0, -0.0, 1.0));
    dirs
}

/// Distance (texels) from continuous coordinates `q` to texel `t`'s cell; polar maps wrap in x.
fn distance_to_cell(layout: &HemisphereLayout, q: DVec2, t: u32) -> f64 {
    let (c, r) = layout.col_row(t);
    let res = layout.res as f64;
    let gap = |v: f64, lo: f64| (lo - v).max(v - (lo + 1.0)).max(0.0);
    let dx = if layout.kind == LayoutKind::Polar {
        [q.x - res, q.x, q.x + res]
            .into_iter()
            .map(|x| gap(x, c as f64))
            .fold(f64::INFINITY, f64::min)
    } else {
        gap(q.x, c as f64)
    };
    dx.max(gap(q.y, r as f64))
}

/// Every layout at res 1, 2, 3, 8, 32, 255, 256 over `singular_directions`.
pub fn texels() -> Vec<StabilityRow> {
    let case = "layout_singular_directions";
    let mut rows = Vec::new();
    for kind in LayoutKind::ALL {
        let (mut bad, mut worst, mut checked) = (0usize, 0.0f64, 0usize);
        for res in [1u32, 2, 3, 8, 32, 255, 256] {
            let layout = HemisphereLayout::new(kind, res);
            for d in singular_directions(kind, res) {
                let t = layout.to_texel(d);
                if t as usize >= layout.texel_count() || !layout.is_used(t) {
                    bad += 1;
                    continue;
                }
                let q = square64(kind, d.as_dvec3()) * res as f64;
                let last = res as f64 - 1.0;
                let (c, r) = (q.x.floor().clamp(0.0, last), q.y.floor().clamp(0.0, last));
                let cell = (r * res as f64 + c) as u32;
                if !layout.is_used(cell) {
                    continue; // a rejection rim point: the nearest used texel answers
                }
                worst = worst.max(distance_to_cell(&layout, q, t));
                checked += 1;
            }
        }
        rows.push(StabilityRow::new(
            case,
            format!("{}: texels out of range or unused (count)", kind.name()),
            bad as f64,
            0.0,
        ));
        rows.push(StabilityRow::new(
            case,
            format!(
                "{}: distance from the f64 square point to the texel's cell (texels, {checked} directions)",
                kind.name()
            ),
            worst,
            TEXEL_TOLERANCE,
        ));
    }
    rows
}

/// Stored distances 0, 1e-30, just under 1 (1 − 2⁻²⁴, 1 − 1/(2L), 1 − 1/L) and exactly 1, plus
/// values past either end, through every precision.
pub fn quantisation() -> Vec<StabilityRow> {
    let case = "quantisation_edges";
    let just_under = 1.0f32.next_down();
    let row = [
        0.0f32,
        1e-30,
        0.5 / 255.0,
        1.0 - 1.0 / 255.0,
        1.0 - 0.5 / 255.0,
        1.0 - 0.5 / 65535.0,
        just_under,
        1.0,
        -0.0,
        2.0,
    ];
    let hits = |i: usize| row[i] < 1.0;
    let mut rows = Vec::new();
    for p in [
        Precision::F32,
        Precision::U16,
        Precision::U8,
        Precision::Bit1,
    ] {
        let mut s = Storage::new(p, 1, row.len());
        s.map_slots()[0].store(&row);
        let got: Vec<f32> = (0..row.len()).map(|t| s.get(0, t)).collect();
        let flips = (0..row.len())
            .filter(|&i| hits(i) != (got[i] < 1.0))
            .count();
        rows.push(StabilityRow::new(
            case,
            format!(
                "{}: hits read as misses or misses as hits (count)",
                p.name()
            ),
            flips as f64,
            0.0,
        ));
        let (quantity, err, tol) = match p {
            Precision::Bit1 => {
                // Every hit reads back the map's mean hit distance, computed in f64.
                let hit: Vec<f64> = row
                    .iter()
                    .filter(|&&d| d < 1.0)
                    .map(|&d| d.max(0.0) as f64)
                    .collect();
                let mean = hit.iter().sum::<f64>() / hit.len() as f64;
                let e = max_of(
                    (0..row.len())
                        .filter(|&i| hits(i))
                        .map(|i| (got[i] as f64 - mean).abs()),
                );
                ("hits read the f64 mean (error)", e, f32::EPSILON as f64)
            }
            _ => {
                let levels = (1u64 << p.bits().min(31)) as f64 - 1.0;
                let tol = if p == Precision::F32 {
                    0.0
                } else {
                    // Half a step, except the top hit level, stored up to 1.5 steps short.
                    1.5 / levels
                };
                let e = max_of(
                    (0..row.len())
                        .filter(|&i| hits(i))
                        .map(|i| (got[i] as f64 - row[i].max(0.0) as f64).abs()),
                );
                ("hits: decoded distance error (of 2R)", e, tol)
            }
        };
        rows.push(StabilityRow::new(
            case,
            format!("{}: {quantity}", p.name()),
            err,
            tol,
        ));
        if p != Precision::Bit1 {
            // 0 decodes to exactly 0 and a miss to exactly 1.
            let e = max_of([got[0].abs() as f64, (got[7] as f64 - 1.0).abs()]);
            rows.push(StabilityRow::new(
                case,
                format!("{}: 0 and 1 exact (error)", p.name()),
                e,
                0.0,
            ));
        }
    }
    rows
}
