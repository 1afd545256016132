//! Tests of `field::lanes`: every eight-lane step against its one-ray twin, bit for bit.

use super::*;
use crate::sampling::rays::seeded_sphere_direction;

/// Directions from the origin that graze, enter and miss a sphere, with lengths off unit
/// by f32 rounding and far from it (both normalisation branches), and a non-direction.
fn directions(origin: Vec3, center: Vec3, radius: f32) -> Vec<Vec3> {
    let to = (center - origin).normalize();
    let mut v: Vec<Vec3> = (0..997).map(|i| seeded_sphere_direction(i, 5)).collect();
    for i in 0..400 {
        // Around the sphere's outline as seen from the origin.
        let side = seeded_sphere_direction(i, 9).cross(to).normalize();
        let tangent = radius / (center - origin).length();
        let k = tangent * (1.0 + (i as f32 - 200.0) * 1e-6);
        v.push((to + k * side).normalize());
    }
    v.extend([to, -to, to * 1.5, to * 1e-3, Vec3::ZERO, Vec3::NAN]);
    v
}

#[test]
fn the_culls_are_the_per_ray_test() {
    for (origin, center, radius) in [
        (Vec3::new(0.3, -0.2, 0.1), Vec3::new(0.0, 0.0, 2.0), 0.7),
        (
            Vec3::new(1e3, 2e3, -5e2),
            Vec3::new(1e3 + 3.0, 2e3, -5e2),
            1.0,
        ),
        (Vec3::new(0.1, 0.1, 0.1), Vec3::ZERO, 1.0), // inside
    ] {
        let dirs = directions(origin, center, radius);
        let meet = MayMeetFrom {
            f: center - origin,
            reach: radius * (1.0 + 1e-5),
        };
        let skip: Vec<bool> = (0..dirs.len()).map(|i| i % 7 == 3).collect();
        for tmin in [0.0, 1.0, 1e9] {
            let want: Vec<u32> = (0..dirs.len() as u32)
                .filter(|&i| !skip[i as usize] && meet.test(dirs[i as usize], tmin))
                .collect();
            assert!(!want.is_empty() || tmin > 1.0);
            assert!(want.len() < dirs.len() - dirs.len() / 7);
            for isa in Isa::all_available() {
                for n in [0, 1, 7, 8, 9, 64, dirs.len()] {
                    let mut got = vec![u32::MAX; n];
                    let kept = cull(isa, &meet, &dirs[..n], tmin, &skip[..n], &mut got);
                    got.truncate(kept);
                    let w: Vec<u32> = want.iter().copied().filter(|&i| (i as usize) < n).collect();
                    assert_eq!(got, w, "{isa:?}, {n} rays, tmin {tmin}");
                }
            }
        }
    }
}

#[test]
fn the_rotations_are_the_per_ray_rotation_bit_for_bit() {
    let dirs = directions(Vec3::new(0.3, -0.2, 0.1), Vec3::new(0.0, 0.0, 2.0), 0.7);
    for q in [
        Quat::IDENTITY,
        Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.3, 1.1),
        Quat::from_rotation_z(2.0).inverse(),
        Quat::from_axis_angle(Vec3::new(1.0, 2.0, -3.0).normalize(), 1e-4),
    ] {
        let want: Vec<Vec3> = dirs.iter().map(|&d| (q * d).normalize()).collect();
        for isa in Isa::all_available() {
            for n in [0, 5, 8, 13, dirs.len()] {
                let mut got = dirs[..n].to_vec();
                rotate_normalize(isa, q, &mut got);
                for k in 0..n {
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    // NaN inputs give NaN (any payload); every other lane the same bits.
                    if want[k].is_nan() {
                        assert!(got[k].is_nan(), "{isa:?}, {:?}", dirs[k]);
                    } else {
                        assert_eq!(bits(got[k]), bits(want[k]), "{isa:?}, {:?}", dirs[k]);
                    }
                }
            }
        }
    }
}

/// Fields whose tables differ: concentric layouts with a texel table (two resolutions) and
/// without (res 256, every texel through the fast path or the exact one), a polar one, Slater
/// and Fibonacci point sets.
fn read_fields() -> Vec<crate::field::VisibilityField> {
    use crate::field::{storage::Storage, FieldParams, Precision, VisibilityField};
    use crate::sampling::{LayoutKind, SphereKind};
    let bounds = crate::geometry::Sphere {
        center: Vec3::new(0.2, -0.1, 0.3),
        radius: 1.3,
    };
    [
        (SphereKind::Slater, 290, LayoutKind::Concentric, 32),
        (SphereKind::Fibonacci, 1000, LayoutKind::Concentric, 8),
        (SphereKind::Slater, 1090, LayoutKind::Polar, 16),
        (SphereKind::Fibonacci, 40, LayoutKind::Concentric, 256),
    ]
    .into_iter()
    .map(|(sphere, count, layout, res)| {
        let params = FieldParams {
            sphere,
            count,
            layout,
            res,
            precision: Precision::F32,
        };
        let texels = (res * res) as usize;
        let storage = Storage::F32 {
            texels,
            data: (0..count * texels)
                .map(|i| (i % 97) as f32 / 97.0)
                .collect(),
        };
        VisibilityField::from_storage(params, bounds, storage).expect("field")
    })
    .collect()
}

/// Where the lookups read: random unit positions and directions, and positions on the cube
/// grid's face edges and corners and on the axes (ties of the face choice), some off unit
/// length, with directions along the maps' frame axes (the texel table's edges) and through
/// the maps' texel edges.
fn read_crossings(field: &crate::field::VisibilityField) -> Vec<Crossed> {
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let mut u: Vec<Vec3> = (0..3000).map(|i| seeded_sphere_direction(i, 21)).collect();
    u.extend([
        Vec3::X,
        -Vec3::Y,
        Vec3::Z,
        Vec3::new(s, s, 0.0),
        Vec3::new(0.0, -s, s),
        Vec3::new(-s, 0.0, -s),
        Vec3::splat(1.0 / 3f32.sqrt()),
        Vec3::new(0.6, 0.8, 0.0) * 1.5,
        Vec3::new(0.0, 0.6, -0.8) * 0.5,
    ]);
    // Square points on the layout's texel edges (k / res, either axis), nudged by a few ulps:
    // their directions, turned into a map's frame and back, land within rounding of an edge,
    // where the fast texel path must defer to the exact one.
    let res = field.layout.res;
    let edge = |i: usize| {
        let k = (i / 7 % res as usize) as f32 / res as f32;
        let along = ((i * 7919) % 1000) as f32 / 1000.0;
        let nudge = f32::EPSILON * ((i % 7) as f32 - 3.0);
        let p = if i.is_multiple_of(2) {
            glam::Vec2::new(k + nudge, along)
        } else {
            glam::Vec2::new(along, k + nudge)
        };
        crate::sampling::warp::square_to_cosine_hemisphere(p)
    };
    u.iter()
        .enumerate()
        .map(|(i, &u)| {
            let m = field.points.nearest(u);
            let f = field.frames[m];
            let dir = match i % 5 {
                0 => f.z,
                1 => (f.z + f.x).normalize(),
                2 | 3 => f.to_world(edge(i)),
                _ => seeded_sphere_direction(i as u64, 22),
            };
            let mut c = Crossed::default();
            (c.u, c.dir) = (u, dir);
            c
        })
        .collect()
}

#[test]
fn the_staged_reads_are_the_per_ray_reads() {
    for field in read_fields() {
        let at = read_crossings(&field);
        let want: Vec<NearestRead> = at
            .iter()
            .map(|c| <NearestRead as crate::field::lookup::Reads>::of(&field, c.u, c.dir))
            .collect();
        // The test reaches both table answers and both fallbacks.
        let owned = at
            .iter()
            .filter(|c| field.points.nearest_owned(c.u).is_some());
        assert!(owned.count() > at.len() / 2);
        let certified = at.iter().zip(&want).filter(|(c, r)| {
            let local = field.frames[r.map as usize].to_local(c.dir);
            field.texels.certified(local).is_some()
        });
        let certified = certified.count();
        if field.texels.bytes() > 0 {
            assert!(certified > 100 && certified < at.len(), "{certified}");
        } else {
            assert_eq!(certified, 0);
        }
        for isa in Isa::all_available() {
            for n in [0, 1, 7, 8, 9, 15, 16, 17, 40, at.len()] {
                let mut got = vec![NearestRead::default(); n];
                nearest_reads(isa, &field, &at[..n], &mut got);
                assert_eq!(got, want[..n], "{isa:?}, {n} crossings");
            }
        }
    }
}

/// A crossing's fields by their bits (NaN-free, so bit for bit is equality).
fn crossing_bits(c: Option<SphereCrossing>) -> Option<[u64; 5]> {
    c.map(|c| {
        [
            c.t0.to_bits() as u64,
            c.t1.to_bits() as u64,
            c.entry.x.to_bits(),
            c.entry.y.to_bits(),
            c.entry.z.to_bits(),
        ]
    })
}

#[test]
fn the_crossings_are_the_per_ray_crossing_bit_for_bit() {
    for (origin, center, radius) in [
        (Vec3::new(0.3, -0.2, 0.1), Vec3::new(0.0, 0.0, 2.0), 0.7),
        (Vec3::new(1e6, -3e5, 2e6), Vec3::new(1.0, 2.0, 3.0), 0.5),
        (Vec3::new(0.1, 0.1, 0.1), Vec3::ZERO, 1.0),
    ] {
        let from = SphereOrigin::new(origin, center, radius);
        let dirs = directions(origin, center, radius);
        let want: Vec<_> = dirs.iter().map(|&d| from.crossing(d)).collect();
        let hits = want.iter().filter(|c| c.is_some()).count();
        assert!(hits > 150 && hits < dirs.len(), "{hits} of {}", dirs.len());
        for isa in Isa::all_available() {
            for n in [0, 3, 8, 13, dirs.len()] {
                let mut got = vec![None; n];
                crossings(isa, &from, &dirs[..n], &mut got);
                for k in 0..n {
                    assert_eq!(
                        crossing_bits(got[k]),
                        crossing_bits(want[k]),
                        "{isa:?}, ray {k}: {:?}",
                        dirs[k]
                    );
                }
            }
        }
    }
}

/// Short runs from anywhere in a set (a call's last few rays, which the AVX2 steps take one at
/// a time): the cull, the rotation and the crossing of every slice of 1 to 9 rays, bit for bit
/// against one ray at a time.
#[test]
fn short_runs_are_the_per_ray_steps_bit_for_bit() {
    let (origin, center, radius) = (Vec3::new(0.3, -0.2, 0.1), Vec3::new(0.0, 0.0, 2.0), 0.7);
    let dirs = directions(origin, center, radius);
    let meet = MayMeetFrom {
        f: center - origin,
        reach: radius * (1.0 + 1e-5),
    };
    let from = SphereOrigin::new(origin, center, radius);
    let q = Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.3, 1.1);
    let skip: Vec<bool> = (0..dirs.len()).map(|i| i % 5 == 2).collect();
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    let mut met = 0;
    for start in (0..dirs.len() - 9).step_by(7) {
        for n in 1..=9 {
            let (d, s) = (&dirs[start..start + n], &skip[start..start + n]);
            let want: Vec<u32> = (0..n as u32)
                .filter(|&i| !s[i as usize] && meet.test(d[i as usize], 0.0))
                .collect();
            met += want.len();
            for isa in Isa::all_available() {
                let mut got = vec![u32::MAX; n];
                let kept = cull(isa, &meet, d, 0.0, s, &mut got);
                assert_eq!(&got[..kept], &want[..], "{isa:?}, rays {start}..+{n}");
                let mut turned = d.to_vec();
                rotate_normalize(isa, q, &mut turned);
                for (t, &r) in turned.iter().zip(d) {
                    let w = (q * r).normalize();
                    assert!(w.is_nan() || bits(*t) == bits(w), "{isa:?}, {r}");
                }
                let mut crossed = vec![None; n];
                crossings(isa, &from, d, &mut crossed);
                for (c, &r) in crossed.iter().zip(d) {
                    assert_eq!(
                        crossing_bits(*c),
                        crossing_bits(from.crossing(r)),
                        "{isa:?}, {r}"
                    );
                }
            }
        }
    }
    assert!(met > 1000, "{met} rays pass the cull");
}
