//! Closed forms of the paths: interpolated keys, rigid turns about a pivot and an axis,
//! orbits' radii and angles, tumbles about the centre, walks' step lengths, and the identity
//! and translations of the whole scene kept exactly.

use super::*;
use glam::{Quat, Vec3Swizzles};

/// A placement with every part non-trivial: rotated, scaled, translated, with an offset.
fn placement(translation: DVec3) -> Placement {
    Placement {
        rotation: Quat::from_euler(EulerRot::YXZ, 0.4, -0.3, 1.1),
        translation,
        scale: 0.75,
        offset: DVec3::new(0.125, -0.25, 0.5),
    }
}

/// A key of a [`Motion`]'s keyframes.
fn key(time: f64, translate: DVec3, rotate_deg: DVec3) -> Keyframe {
    Keyframe {
        time,
        translate,
        rotate_deg,
    }
}

const M: Vec3 = Vec3::new(0.5, -0.25, 1.0);

/// A model point's world position under the placement moved by `pose`.
fn world(pose: &Pose, p: &Placement, x: Vec3) -> DVec3 {
    pose.apply(p, M).to_world_point(x)
}

fn close(a: DVec3, b: DVec3, tol: f64) {
    assert!((a - b).length() <= tol, "{a} vs {b}");
}

/// f32 rotations and positions: a few units of 6e-8 of the unit-sized coordinates.
const TOL: f64 = 1e-5;

const PROBES: [Vec3; 3] = [
    Vec3::new(0.0, 0.0, 0.0),
    Vec3::new(1.0, 2.0, -1.0),
    Vec3::new(-0.5, 0.25, 3.0),
];

#[test]
fn the_identity_keeps_the_placement_bit_for_bit() {
    let p = placement(DVec3::new(1e4, -3.0, 2.0));
    assert_eq!(Pose::IDENTITY.apply(&p, M), p);
    let still = Motion {
        keyframes: vec![key(0.0, DVec3::ZERO, DVec3::ZERO)],
        ..Motion::default()
    };
    assert_eq!(still.pose(3, 0.1, &p, M), Pose::IDENTITY);
}

#[test]
fn keys_interpolate_linearly_and_by_slerp_and_hold_at_the_ends() {
    let m = Motion {
        keyframes: vec![
            key(1.0, DVec3::ZERO, DVec3::ZERO),
            key(3.0, DVec3::new(2.0, 0.0, -4.0), DVec3::new(0.0, 90.0, 0.0)),
        ],
        ..Motion::default()
    };
    let p = placement(DVec3::ZERO);
    // Frame f is at f · 0.5 s: before the first key, halfway, after the last.
    assert_eq!(m.pose(1, 0.5, &p, M), Pose::IDENTITY);
    let half = m.pose(4, 0.5, &p, M);
    close(half.displacement, DVec3::new(1.0, 0.0, -2.0), 1e-12);
    let (axis, angle) = half.rotation.to_axis_angle();
    assert!((angle - 45f64.to_radians()).abs() < 1e-12, "{angle}");
    close(axis, DVec3::Y, 1e-12);
    let end = m.pose(20, 0.5, &p, M);
    close(end.displacement, DVec3::new(2.0, 0.0, -4.0), 0.0);
    assert!((end.rotation.to_axis_angle().1 - 90f64.to_radians()).abs() < 1e-12);
}

#[test]
fn keys_about_a_pivot_move_every_instance_as_one_rigid_body() {
    let pivot = DVec3::new(0.5, 0.0, 0.5);
    let (r, d) = (DVec3::new(30.0, -45.0, 10.0), DVec3::new(0.25, 1.0, -0.5));
    let m = Motion {
        keyframes: vec![key(0.0, d, r)],
        pivot: Some(pivot),
        ..Motion::default()
    };
    let rigid = |x: DVec3| pivot + euler(r) * (x - pivot) + d;
    for p in [
        placement(DVec3::ZERO),
        placement(DVec3::new(-2.0, 1.0, 3.0)),
    ] {
        let pose = m.pose(0, 1.0, &p, M);
        for x in PROBES {
            close(world(&pose, &p, x), rigid(p.to_world_point(x)), TOL);
        }
    }
}

#[test]
fn an_orbit_keeps_its_radius_and_height_and_turns_by_the_period() {
    let centre = DVec3::new(0.5, 0.0, 0.5);
    let p = placement(DVec3::new(1.0, 0.5, 0.0));
    let c0 = p.to_world_point(M);
    let m = |turn: bool| Motion {
        orbit: Some(Orbit {
            center: Some(centre),
            axis: DVec3::new(0.0, 2.0, 0.0),
            radius: None,
            period: 4.0,
            phase_deg: 0.0,
            turn,
        }),
        ..Motion::default()
    };
    // A quarter period: the centre turned 90° about the vertical through `centre`.
    let q = DQuat::from_rotation_y(90f64.to_radians());
    let pose = m(false).pose(1, 1.0, &p, M);
    close(c0 + pose.displacement, centre + q * (c0 - centre), 1e-12);
    assert_eq!(pose.rotation, DQuat::IDENTITY);
    // Every frame: the same distance from the axis and height.
    for f in 0..9 {
        let c = c0 + m(false).pose(f, 0.7, &p, M).displacement - centre;
        let d0 = c0 - centre;
        assert!((c.y - d0.y).abs() < 1e-12);
        assert!((c.xz().length() - d0.xz().length()).abs() < 1e-12);
    }
    // Turning with it: a rigid turn about the axis line.
    let turned = m(true).pose(1, 1.0, &p, M);
    for x in PROBES {
        let w = p.to_world_point(x);
        close(world(&turned, &p, x), centre + q * (w - centre), TOL);
    }
}

#[test]
fn an_orbit_about_its_own_centre_circles_at_its_radius() {
    let p = placement(DVec3::ZERO);
    let m = Motion {
        orbit: Some(Orbit {
            center: None,
            axis: DVec3::Z,
            radius: Some(0.25),
            period: -2.0,
            phase_deg: 30.0,
            turn: false,
        }),
        ..Motion::default()
    };
    let mut seen = Vec::new();
    for f in 0..8 {
        let d = m.pose(f, 0.25, &p, M).displacement;
        assert!(
            (d.length() - 0.25).abs() < 1e-12 && d.z.abs() < 1e-15,
            "{d}"
        );
        seen.push(d);
    }
    // 1/8 turn a frame, clockwise about +z (a negative period).
    for w in seen.windows(2) {
        let a = w[0].y.atan2(w[0].x) - w[1].y.atan2(w[1].x);
        assert!((a.rem_euclid(TAU) - TAU / 8.0).abs() < 1e-12, "{a}");
    }
}

#[test]
fn a_tumble_turns_about_the_centre_at_its_rate() {
    let p = placement(DVec3::new(3.0, 1.0, 0.0));
    let m = |axis| Motion {
        tumble: Some(Tumble {
            rate_deg: 36.0,
            axis,
            seed: 9,
        }),
        ..Motion::default()
    };
    let pose = m(Some(DVec3::X)).pose(5, 0.5, &p, M);
    assert_eq!(pose.displacement, DVec3::ZERO);
    let (axis, angle) = pose.rotation.to_axis_angle();
    close(axis, DVec3::X, 1e-12);
    assert!((angle - 90f64.to_radians()).abs() < 1e-12);
    // The centre stays; another point turns about it.
    let c0 = p.to_world_point(M);
    close(world(&pose, &p, M), c0, TOL);
    // A seeded axis: unit, the same for the same seed, another for another seed.
    let a = m(None).pose(1, 1.0, &p, M).rotation.to_axis_angle().0;
    let b = m(None).pose(2, 1.0, &p, M).rotation.to_axis_angle().0;
    close(a, b, 1e-12);
    let mut other = m(None);
    other.tumble.as_mut().unwrap().seed = 10;
    let c = other.pose(1, 1.0, &p, M).rotation.to_axis_angle().0;
    assert!((a - c).length() > 1e-3, "{a} {c}");
}

#[test]
fn a_walk_steps_its_speed_times_the_time_step_in_its_plane() {
    let p = placement(DVec3::ZERO);
    let walk = |plane_normal| Motion {
        walk: Some(Walk {
            speed: 2.0,
            seed: 4,
            plane_normal,
        }),
        ..Motion::default()
    };
    for n in [None, Some(DVec3::new(0.0, 3.0, 0.0))] {
        let m = walk(n);
        assert_eq!(m.pose(0, 0.1, &p, M).displacement, DVec3::ZERO);
        let d: Vec<DVec3> = (0..6).map(|f| m.pose(f, 0.1, &p, M).displacement).collect();
        for w in d.windows(2) {
            assert!(((w[1] - w[0]).length() - 0.2).abs() < 1e-12);
            if n.is_some() {
                assert_eq!(w[1].y, 0.0);
            }
        }
        // Seeded directions, not one line.
        assert!((d[5] - d[0]).length() < 1.0 - 1e-6);
    }
}

/// The same motion on a scene translated by a multiple of a power of two, its points with it,
/// gives the same poses bit for bit, and the same coordinates relative to the translated
/// origin.
#[test]
fn a_translated_scene_moves_as_the_untranslated_one() {
    let shift = DVec3::new(1048576.0, -2097152.0, 65536.0);
    let m = |s: DVec3| Motion {
        keyframes: vec![
            key(0.0, DVec3::ZERO, DVec3::ZERO),
            key(1.0, DVec3::new(0.5, 0.0, 0.25), DVec3::new(0.0, 60.0, 20.0)),
        ],
        pivot: Some(DVec3::new(0.5, 0.25, 0.5) + s),
        orbit: Some(Orbit {
            center: Some(DVec3::new(0.25, 0.0, 0.75) + s),
            axis: DVec3::Y,
            radius: None,
            period: 3.0,
            phase_deg: 10.0,
            turn: true,
        }),
        tumble: Some(Tumble {
            rate_deg: 50.0,
            axis: None,
            seed: 2,
        }),
        walk: Some(Walk {
            speed: 0.5,
            seed: 1,
            plane_normal: None,
        }),
    };
    let (near, far) = (placement(DVec3::ZERO), placement(shift));
    for f in 0..6 {
        let (a, b) = (
            m(DVec3::ZERO).pose(f, 0.3, &near, M),
            m(shift).pose(f, 0.3, &far, M),
        );
        assert_eq!(a, b, "frame {f}");
        let (pa, pb) = (a.apply(&near, M), b.apply(&far, M));
        assert_eq!(
            pa.relative_to(DVec3::ZERO),
            pb.relative_to(shift),
            "frame {f}"
        );
    }
}

/// A displacement by a multiple of a power of two joins the translation exactly: the placement
/// relative to the origin moved with it is the unmoved one, bit for bit.
#[test]
fn a_move_by_a_multiple_of_the_step_keeps_the_coordinates() {
    let p = placement(DVec3::new(0.0, 0.5, 0.0));
    let shift = DVec3::new(256.0, -512.0, 128.0);
    let moved = Pose {
        rotation: DQuat::IDENTITY,
        displacement: shift,
    }
    .apply(&p, M);
    assert_eq!(moved.relative_to(shift), p.relative_to(DVec3::ZERO));
}

/// Keys at ±1e308 are finite, increasing and accepted; their span overflows f64. Halfway in
/// time the translation is halfway (before, the infinite span made every fraction 0: the
/// instance held the first key at every frame).
#[test]
fn keys_at_the_ends_of_f64_still_interpolate() {
    let m = |a: f64, b: f64| Motion {
        keyframes: vec![
            key(a, DVec3::ZERO, DVec3::ZERO),
            key(b, DVec3::new(2.0, 0.0, -4.0), DVec3::new(0.0, 90.0, 0.0)),
        ],
        ..Motion::default()
    };
    let p = placement(DVec3::ZERO);
    for (a, b) in [(-1e308, 1e308), (-f64::MAX, f64::MAX)] {
        assert!((b - a).is_infinite());
        assert!(m(a, b).problem(3, 1.0, 1e18).is_none(), "accepted");
        // Frames 0–2 lie within a few units of the middle: u = 1/2 to 1e-300.
        for f in 0..3 {
            let pose = m(a, b).pose(f, 1.0, &p, M);
            close(pose.displacement, DVec3::new(1.0, 0.0, -2.0), 1e-12);
            let angle = pose.rotation.to_axis_angle().1;
            assert!((angle - 45f64.to_radians()).abs() < 1e-12, "{angle}");
        }
    }
    // A quarter of the way: t = 0 between −0.5e308 and 1.5e308.
    let q = m(-0.5e308, 1.5e308).pose(0, 1.0, &p, M).displacement;
    close(q, DVec3::new(0.5, 0.0, -1.0), 1e-12);
    // Finite spans keep their formula bit for bit.
    assert_eq!(key_fraction(0.3, 0.1, 0.7), (0.3 - 0.1) / (0.7 - 0.1));
}

/// The walk's displacement at `frame` as every pose once formed it: the other paths'
/// displacement `before`, then each step from frame 1 added to it in turn.
fn walked_from_scratch(before: DVec3, w: &Walk, frame: u32, dt: f64) -> DVec3 {
    let step = w.speed * dt;
    let plane = w.plane_normal.and_then(DVec3::try_normalize).map(|n| {
        let e1 = n.any_orthonormal_vector();
        (e1, n.cross(e1))
    });
    let mut displacement = before;
    for i in 1..=frame as usize {
        let dir = match plane {
            Some((e1, e2)) => {
                let a = TAU * seeded_unit(i, w.seed) as f64;
                a.cos() * e1 + a.sin() * e2
            }
            None => seeded_direction(i, w.seed),
        };
        displacement += step * dir;
    }
    displacement
}

/// [`Motion::poses`] steps a walk once a frame: its poses equal [`Motion::pose`]'s at every
/// frame and, for a walk (with a tumble and keys turning about the centre, which displace
/// nothing), the former per-frame sum bit for bit; beside an orbit, the walk's sum is added
/// as a whole, within rounding of the former running sum.
#[test]
fn poses_over_a_run_equal_the_per_frame_sums() {
    let p = placement(DVec3::new(3.0, -1.0, 0.5));
    let walk = |plane_normal| Walk {
        speed: 0.7,
        seed: 11,
        plane_normal,
    };
    let keys = vec![
        key(0.0, DVec3::ZERO, DVec3::ZERO),
        key(9.0, DVec3::ZERO, DVec3::new(10.0, 80.0, -20.0)),
    ];
    let (frames, dt) = (300, 0.05);
    for n in [None, Some(DVec3::new(0.0, 0.0, 2.0))] {
        let alone = Motion {
            walk: Some(walk(n)),
            ..Motion::default()
        };
        let turning = Motion {
            keyframes: keys.clone(),
            tumble: Some(Tumble {
                rate_deg: 25.0,
                axis: None,
                seed: 3,
            }),
            ..alone.clone()
        };
        for m in [&alone, &turning] {
            let poses = m.poses(frames, dt, &p, M);
            assert_eq!(poses.len(), frames as usize);
            for f in [0, 1, 2, 17, 150, frames - 1] {
                let still = Motion {
                    walk: None,
                    ..m.clone()
                };
                let before = if still.is_empty() {
                    Pose::IDENTITY
                } else {
                    still.pose(f, dt, &p, M)
                };
                assert_eq!(before.displacement, DVec3::ZERO);
                let old = Pose {
                    rotation: before.rotation,
                    displacement: walked_from_scratch(DVec3::ZERO, &walk(n), f, dt),
                };
                assert_eq!(poses[f as usize], old, "frame {f}");
                assert_eq!(poses[f as usize], m.pose(f, dt, &p, M), "frame {f}");
            }
        }
        let orbiting = Motion {
            orbit: Some(Orbit {
                center: Some(DVec3::new(1.0, 0.0, 0.0)),
                axis: DVec3::Y,
                radius: None,
                period: 2.0,
                phase_deg: 0.0,
                turn: false,
            }),
            ..alone.clone()
        };
        let poses = orbiting.poses(frames, dt, &p, M);
        for f in [0, 1, 150, frames - 1] {
            let still = Motion {
                walk: None,
                ..orbiting.clone()
            };
            let before = still.pose(f, dt, &p, M).displacement;
            let old = walked_from_scratch(before, &walk(n), f, dt);
            assert_eq!(poses[f as usize], orbiting.pose(f, dt, &p, M));
            close(poses[f as usize].displacement, old, 1e-13);
        }
    }
}

/// Values each finite whose use over the animation is not (an orbit's turns, a walk's step)
/// are refused naming the field.
#[test]
fn scalars_whose_use_overflows_are_refused_naming_the_field() {
    let orbit = |period| Motion {
        orbit: Some(Orbit {
            center: None,
            axis: DVec3::Y,
            radius: Some(0.1),
            period,
            phase_deg: 0.0,
            turn: false,
        }),
        ..Motion::default()
    };
    for period in [5e-324, -5e-324, 1e-308] {
        let (field, why) = orbit(period).problem(3, 1.0, 1e18).expect("refused");
        assert_eq!(field, "orbit.period", "{why}");
        assert!(why.contains("turns"), "{why}");
    }
    // The shortest period whose turns stay finite is accepted, and its poses are finite.
    let m = orbit(1e-300);
    assert!(m.problem(3, 1.0, 1e18).is_none());
    for f in 0..3 {
        assert!(m
            .pose(f, 1.0, &placement(DVec3::ZERO), M)
            .displacement
            .is_finite());
    }
    let walk = Motion {
        walk: Some(Walk {
            speed: 1e300,
            seed: 0,
            plane_normal: None,
        }),
        ..Motion::default()
    };
    let (field, why) = walk.problem(2, 1e10, 1e18).expect("refused");
    assert_eq!(field, "walk.speed", "{why}");
}
