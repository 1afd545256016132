//! Embree (`trace::embree::EmbreeTracer`, the `embree` feature) against our reference tracer on
//! the same rays: the AO rays of two procedural scenes (a supershape over the corner, and the
//! same with the corner casting too), the disagreements counted and characterised, the
//! `Visibility` contract (occluded == hit_distance.is_some(), packets == single rays) and the
//! normals. Without the feature every test here reports itself ignored, with the reason.

#[test]
#[cfg_attr(
    not(feature = "embree"),
    ignore = "needs --features embree and libembree-dev"
)]
fn ao_rays_agree_up_to_edge_and_contact_rays() {
    #[cfg(feature = "embree")]
    imp::ao_rays_agree_up_to_edge_and_contact_rays();
}

#[test]
#[cfg_attr(
    not(feature = "embree"),
    ignore = "needs --features embree and libembree-dev"
)]
fn occluded_is_hit_distance_is_some() {
    #[cfg(feature = "embree")]
    imp::occluded_is_hit_distance_is_some();
}

#[test]
#[cfg_attr(
    not(feature = "embree"),
    ignore = "needs --features embree and libembree-dev"
)]
fn packets_equal_single_rays() {
    #[cfg(feature = "embree")]
    imp::packets_equal_single_rays();
}

#[test]
#[cfg_attr(
    not(feature = "embree"),
    ignore = "needs --features embree and libembree-dev"
)]
fn surface_hit_normals_are_the_triangle_normals() {
    #[cfg(feature = "embree")]
    imp::surface_hit_normals_are_the_triangle_normals();
}

#[test]
#[cfg_attr(
    not(feature = "embree"),
    ignore = "needs --features embree and libembree-dev"
)]
fn closed_form_hits_and_intervals() {
    #[cfg(feature = "embree")]
    imp::closed_form_hits_and_intervals();
}

#[cfg(feature = "embree")]
mod imp {
    use glam::{Quat, Vec3};
    use visfield::geometry::procedural::{default_scene, over_corner, supershape, Supershape};
    use visfield::geometry::Scene;
    use visfield::render::ao::instance_epsilon;
    use visfield::render::receivers::Receivers;
    use visfield::sampling::rays::RaySet;
    use visfield::sampling::Frame;
    use visfield::trace::embree::{EmbreeRays, EmbreeTracer};
    use visfield::trace::Tracer;
    use visfield::visibility::{SurfaceHit, Visibility};

    /// The AO rays of a scene's receivers, as the renderers cast them: origin offset along
    /// the normal by the receiver's instance epsilon, k² directions per point.
    struct AoRays {
        origins: Vec<Vec3>,
        dirs: Vec<Vec<Vec3>>,
        offset: f32,
    }

    fn ao_rays(scene: &Scene, k: u32, stride: usize) -> AoRays {
        let recv = Receivers::of(scene);
        let offset = instance_epsilon(&scene.instances[0]);
        let prepared = RaySet::new(k, 1).prepare();
        let mut origins = Vec::new();
        let mut dirs = Vec::new();
        let mut scratch = Vec::new();
        for i in (0..recv.points.len()).step_by(stride) {
            let (p, n) = (recv.points[i], recv.normals[i]);
            prepared.fill(i as u32, &mut scratch);
            let f = Frame::from_normal(n);
            origins.push(p + offset * n);
            dirs.push(scratch.iter().map(|&d| f.to_world(d)).collect());
        }
        AoRays {
            origins,
            dirs,
            offset,
        }
    }

    /// The caster over the corner, and the same with the corner casting too (its AO origins
    /// then lie one offset above a caster's surface, and rays near the creases graze the
    /// other two planes).
    fn scenes() -> Vec<(&'static str, Scene, Vec<[Vec3; 3]>)> {
        let a = default_scene();
        let ta = a.caster_triangles();
        let mut b = over_corner(
            supershape(&Supershape::default(), 4000).expect("supershape"),
            Quat::from_rotation_y(0.3),
        );
        b.instances[0].caster = true;
        let tb = b.caster_triangles();
        vec![("supershape-10k", a, ta), ("corner+supershape-4k", b, tb)]
    }

    /// Distance from `p` to the nearest edge of triangle `t`.
    fn edge_distance(p: Vec3, t: [Vec3; 3]) -> f32 {
        (0..3)
            .map(|i| {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                let ab = b - a;
                let s = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                (a + s * ab - p).length()
            })
            .fold(f32::INFINITY, f32::min)
    }

    /// Whether `p` lies within `band` of triangle `t` (its plane, and inside or near an edge).
    fn on_triangle(p: Vec3, t: [Vec3; 3], band: f32) -> bool {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        if n.length_squared() == 0.0 {
            return false;
        }
        let n = n.normalize();
        let h = (p - t[0]).dot(n);
        if h.abs() > band {
            return false;
        }
        let q = p - h * n;
        let inside = (0..3).all(|i| (t[(i + 1) % 3] - t[i]).cross(q - t[i]).dot(n) >= 0.0);
        inside || edge_distance(q, t) <= band
    }

    pub fn ao_rays_agree_up_to_edge_and_contact_rays() {
        for (name, scene, tris) in scenes() {
            let ours = Tracer::new(&tris);
            let embree = EmbreeTracer::new(&tris).expect("Embree device");
            let rays = ao_rays(&scene, 16, 1);
            let extent = scene.bounding_sphere().radius * 2.0;
            // The band around an edge within which two f32 edge tests (Woop's, Embree's
            // Plücker) may round differently: a few hundred ulps of the coordinates (≤ 1 here).
            let band = 256.0 * f32::EPSILON * extent;
            let (mut total, mut hits, mut in_band, mut near_origin) = (0u64, 0u64, 0u64, 0u64);
            // Origins on a caster's surface (the corner's crease points, whose offset along
            // one face's normal stays in the other face's plane).
            let on_surface = rays
                .origins
                .iter()
                .filter(|&&o| tris.iter().any(|&t| on_triangle(o, t, band)))
                .count();
            let mut disagree = Vec::new();
            for (o, dirs) in rays.origins.iter().zip(&rays.dirs) {
                for &d in dirs {
                    total += 1;
                    let a = ours.closest_hit(*o, d, 0.0, f32::INFINITY);
                    let b = embree.any_hit(*o, d, 0.0, f32::INFINITY);
                    // Candidates for a disagreement: a hit (either caster's) within the band of
                    // an edge, or a hit within a few offsets of the origin (contact rays).
                    let e = embree.closest_hit(*o, d, 0.0, f32::INFINITY);
                    let edge = [a, e]
                        .iter()
                        .flatten()
                        .any(|h| edge_distance(*o + h.t * d, tris[h.triangle as usize]) <= band);
                    let contact = [a, e].iter().flatten().any(|h| h.t <= 4.0 * rays.offset);
                    hits += a.is_some() as u64;
                    in_band += edge as u64;
                    near_origin += contact as u64;
                    if a.is_some() != b {
                        disagree.push((a.is_some(), edge, contact));
                    }
                }
            }
            let unexplained = disagree.iter().filter(|(_, e, c)| !e && !c).count();
            let by_contact = disagree.iter().filter(|(_, _, c)| *c).count();
            let by_edge = disagree.iter().filter(|(_, e, c)| *e && !c).count();
            let ours_only = disagree.iter().filter(|(a, _, _)| *a).count();
            eprintln!(
                "{name}: {total} rays, {hits} hit (ours); {} disagree ({ours_only} only ours hit): \
                 {by_contact} contact rays (a hit within 4 offsets), {by_edge} other rays through \
                 an edge band of {band:.2e}, {unexplained} other; candidates: {in_band} in an \
                 edge band, {near_origin} hitting within 4 offsets; {on_surface} of {} origins \
                 on a caster's surface",
                disagree.len(),
                rays.origins.len()
            );
            // Every disagreement is a ray through an edge or vertex, or a contact ray.
            assert_eq!(unexplained, 0, "{name}: disagreements off every edge");
            // ... so they are bounded by those candidate rays, a vanishing share of all.
            assert!(
                disagree.len() as u64 <= in_band + near_origin,
                "{name}: {} disagreements, {in_band} + {near_origin} candidates",
                disagree.len()
            );
            // Contact rays disagree only from origins on a surface: at most all their rays.
            let k2 = rays.dirs.first().map_or(0, Vec::len);
            assert!(
                by_contact <= on_surface * k2,
                "{name}: {by_contact} contact disagreements from {on_surface} origins on a surface"
            );
            // The edge band's share of the hits is at most its share of the caster's area:
            // perimeter · band / area per triangle, summed (cosine weighting aside: a factor
            // of 4 for the projected area of the grazing hits).
            let (area, band_area): (f64, f64) = tris.iter().fold((0.0, 0.0), |(a, b), t| {
                let ar = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length() as f64;
                let per = ((t[1] - t[0]).length() + (t[2] - t[1]).length() + (t[0] - t[2]).length())
                    as f64;
                (a + ar, b + (per * band as f64).min(ar))
            });
            let bound = 4.0 * 2.0 * hits as f64 * band_area / area + 10.0;
            assert!(
                (by_edge as f64) <= bound,
                "{name}: {by_edge} edge disagreements above the area bound {bound:.1}"
            );
        }
    }

    pub fn occluded_is_hit_distance_is_some() {
        for (name, scene, tris) in scenes() {
            let embree = EmbreeTracer::new(&tris).expect("Embree device");
            let rays = ao_rays(&scene, 16, 3);
            let mut n = 0u64;
            for (o, dirs) in rays.origins.iter().zip(&rays.dirs) {
                for &d in dirs {
                    for tmax in [f32::INFINITY, 0.05] {
                        let occ = embree.occluded(*o, d, 0.0, tmax);
                        let hd = embree.hit_distance(*o, d, 0.0, tmax);
                        assert_eq!(occ, hd.is_some(), "{name}: {o} {d} tmax {tmax}: {hd:?}");
                        assert_eq!(
                            embree.surface_hit(*o, d, 0.0, tmax).map(|h| h.t),
                            hd,
                            "{name}"
                        );
                        if let Some(t) = hd {
                            assert!((0.0..=tmax).contains(&t), "{name}: t {t} off [0, {tmax}]");
                        }
                        n += 1;
                    }
                }
            }
            eprintln!("{name}: {n} queries, occluded == hit_distance.is_some() on every one");
        }
    }

    pub fn packets_equal_single_rays() {
        for (name, scene, tris) in scenes() {
            let single = EmbreeTracer::new(&tris)
                .expect("Embree device")
                .with_rays(EmbreeRays::Single);
            let packets = EmbreeTracer::new(&tris)
                .expect("Embree device")
                .with_rays(EmbreeRays::Packet8);
            let rays = ao_rays(&scene, 16, 1);
            let (mut n, mut hits) = (0usize, 0usize);
            for (i, (o, dirs)) in rays.origins.iter().zip(&rays.dirs).enumerate() {
                // A count that is not a multiple of 8 leaves the last packet part-masked.
                let dirs = &dirs[..dirs.len() - i % 8];
                let (mut a, mut b) = (vec![false; dirs.len()], vec![false; dirs.len()]);
                single.occluded_many(*o, dirs, 0.0, f32::INFINITY, &mut a);
                packets.occluded_many(*o, dirs, 0.0, f32::INFINITY, &mut b);
                assert_eq!(a, b, "{name}: point {i}, occluded_many");
                // Per-ray ends, some empty (tmin > tmax) and some NaN: misses, as in the tracer.
                let tmaxs: Vec<f32> = (0..dirs.len())
                    .map(|j| match j % 11 {
                        0 => -1.0,
                        1 => f32::NAN,
                        j => 0.02 * j as f32,
                    })
                    .collect();
                single.occluded_many_to(*o, dirs, 0.0, &tmaxs, &mut a);
                packets.occluded_many_to(*o, dirs, 0.0, &tmaxs, &mut b);
                assert_eq!(a, b, "{name}: point {i}, occluded_many_to");
                for (j, &d) in dirs.iter().enumerate() {
                    assert_eq!(a[j], single.occluded(*o, d, 0.0, tmaxs[j]), "{name}");
                }
                // Closest hits (reflection rays), unbounded and ending halfway.
                for tmax in [f32::INFINITY, 0.5] {
                    let (mut a, mut b) = (vec![None; dirs.len()], vec![None; dirs.len()]);
                    single.surface_hit_many(*o, dirs, 0.0, tmax, &mut a);
                    packets.surface_hit_many(*o, dirs, 0.0, tmax, &mut b);
                    let bits = |h: &[Option<SurfaceHit>]| -> Vec<Option<[u32; 4]>> {
                        h.iter()
                            .map(|h| {
                                h.map(|h| {
                                    [
                                        h.t.to_bits(),
                                        h.normal.x.to_bits(),
                                        h.normal.y.to_bits(),
                                        h.normal.z.to_bits(),
                                    ]
                                })
                            })
                            .collect()
                    };
                    assert_eq!(bits(&a), bits(&b), "{name}: point {i}, surface_hit_many");
                    for (j, &d) in dirs.iter().enumerate() {
                        let one = single.surface_hit(*o, d, 0.0, tmax);
                        assert_eq!(bits(&a[j..=j]), bits(&[one]), "{name}");
                    }
                    hits += a.iter().flatten().count();
                }
                n += 4 * dirs.len();
            }
            assert!(hits > 0, "{name}: no closest hit to compare");
            eprintln!(
                "{name}: {n} rays ({hits} closest hits), packets == single rays on every one"
            );
        }
    }

    pub fn surface_hit_normals_are_the_triangle_normals() {
        for (name, scene, tris) in scenes() {
            let ours = Tracer::new(&tris);
            let embree = EmbreeTracer::new(&tris).expect("Embree device");
            let rays = ao_rays(&scene, 8, 2);
            let (mut hits, mut same_triangle, mut other_shared) = (0u64, 0u64, 0u64);
            for (o, dirs) in rays.origins.iter().zip(&rays.dirs) {
                for &d in dirs {
                    let Some((h, ng)) = embree.closest_hit_raw(*o, d, 0.0, f32::INFINITY) else {
                        continue;
                    };
                    hits += 1;
                    let [v0, v1, v2] = tris[h.triangle as usize];
                    let n = (v1 - v0).cross(v2 - v0).normalize();
                    assert!(
                        (h.normal - n).length() <= 1e-6,
                        "{name}: {} vs {n}",
                        h.normal
                    );
                    // Embree's own geometric normal is the same line (its sign is Embree's).
                    assert!(
                        ng.normalize().dot(n).abs() >= 1.0 - 1e-5,
                        "{name}: Embree's Ng {ng} against {n}"
                    );
                    let s = embree.surface_hit(*o, d, 0.0, f32::INFINITY).unwrap();
                    assert_eq!((s.t, s.normal), (h.t, h.normal));
                    let r = ours.closest_hit(*o, d, 0.0, f32::INFINITY);
                    match r {
                        Some(r) if r.triangle == h.triangle => {
                            same_triangle += 1;
                            // The same triangle gives the same normal, bit for bit, and t up
                            // to the two tests' rounding.
                            assert_eq!(r.normal, h.normal, "{name}");
                            assert!(
                                (r.t - h.t).abs() <= 1e-5 * r.t.max(1.0),
                                "{name}: t {} vs {}",
                                r.t,
                                h.t
                            );
                        }
                        // Another triangle: the same point through a shared edge or vertex (the
                        // corner's coplanar pairs), or Embree's hit at the origin (contact).
                        _ => {
                            let shared =
                                r.is_some_and(|r| (r.t - h.t).abs() <= 1e-5 * r.t.max(1.0));
                            assert!(
                                shared || h.t <= 4.0 * rays.offset,
                                "{name}: {o} {d}: ours {r:?}, Embree {h:?}"
                            );
                            other_shared += shared as u64;
                        }
                    }
                }
            }
            eprintln!(
                "{name}: {hits} hits, {same_triangle} on the same triangle as ours, \
                 {other_shared} on a neighbour at the same t, the rest at the origin"
            );
            assert!(hits > 0 && same_triangle > 0, "{name}");
        }
    }

    pub fn closed_form_hits_and_intervals() {
        let tri = [
            Vec3::new(-1.0, -1.0, 2.0),
            Vec3::new(1.0, -1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        ];
        let e = EmbreeTracer::new(&[tri]).expect("Embree device");
        assert_eq!(e.len(), 1);
        assert!(e.version().starts_with("3."), "{}", e.version());
        let (o, d) = (Vec3::ZERO, Vec3::Z);
        let h = e.closest_hit(o, d, 0.0, 10.0).expect("hit");
        // Embree's t is within rounding of 2 (its division is a refined reciprocal).
        assert!((h.t - 2.0).abs() <= 4.0 * f32::EPSILON, "{h:?}");
        assert_eq!(h.triangle, 0);
        assert_eq!(h.normal, Vec3::Z);
        // p = (1-u-v)·v0 + u·v1 + v·v2 = (0, 0, 2): u = 1/4, v = 1/2.
        assert!(
            (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6,
            "{h:?}"
        );
        // A direction of length 2 gives t in its units.
        let t = e.closest_hit(o, 2.0 * d, 0.0, 10.0).unwrap().t;
        assert!((t - 1.0).abs() <= 2.0 * f32::EPSILON, "{t}");
        // From behind: no culling.
        assert!(e.occluded(Vec3::new(0.0, 0.0, 4.0), -d, 0.0, 10.0));
        // The segment ends before the triangle, starts after it, or is empty or NaN.
        assert!(!e.occluded(o, d, 0.0, 1.9));
        assert!(!e.occluded(o, d, 2.1, 10.0));
        assert!(!e.occluded(o, d, 3.0, 1.0));
        assert!(!e.occluded(o, d, 0.0, f32::NAN));
        assert_eq!(e.hit_distance(o, d, 0.0, f32::NAN), None);
        // Beside the triangle.
        assert!(!e.occluded(Vec3::new(5.0, 0.0, 0.0), d, 0.0, 10.0));
        // No triangles: every query misses.
        let empty = EmbreeTracer::new(&[]).expect("Embree device");
        assert!(empty.is_empty());
        assert!(!empty.occluded(o, d, 0.0, f32::INFINITY));
        let mut out = [true; 9];
        empty.occluded_many(o, &[d; 9], 0.0, f32::INFINITY, &mut out);
        assert_eq!(out, [false; 9]);
    }
}
