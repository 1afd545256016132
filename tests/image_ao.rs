//! Per-pixel AO (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, "Fast Approximate Visibility
//! on the GPU using Precomputed 4D Visibility Fields", WSCG 2010, §3, Figures 3 and 5): AO at
//! the receiver pixels of a G-buffer ([`EvalPoints::pixels`]) through field lookup, against ray
//! casting on the same rays and against a closed form.
//!
//! - A convex caster over a plane: field and ray cast agree per ray and per pixel within the
//!   tolerances of the 2008 tests on convex casters.
//! - A sphere that receives its own occlusion (the intra-object test, 2010 Figure 2): no pixel
//!   is occluded, exactly.
//! - A hemispherical bowl that receives its own occlusion: at its bottom pole, half of the
//!   cosine-weighted hemisphere is open, from ray casting and from the field.
//!
//! Each scene is viewed as the harness views an image-AO scene: primary visibility cast with
//! the reference tracer ([`gbuffer`]), each point moved off its surface by its instance's ray
//! offset ([`EvalPoints::at`]: the ray origins), the same [`RaySet`] for every backend.

use glam::{Quat, Vec3};
use std::sync::Arc;
use visfield::experiment::metrics::rms_u8;
use visfield::experiment::stability::hard::{FIELD_MAX, FIELD_RMS};
use visfield::field::bake::{bake, BakeOptions};
use visfield::field::lookup::{ray_sphere, IntraBias, LookupOptions};
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{FieldParams, Precision, Selection, VisibilityField};
use visfield::geometry::{procedural, Instance, Mesh, Scene, Similarity};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::render::camera::Camera;
use visfield::render::points::{EvalPoints, GBuffer, Support};
use visfield::render::primary::{gbuffer, PrimaryScene};
use visfield::sampling::rays::RaySet;
use visfield::sampling::Frame;
use visfield::trace::Tracer;
use visfield::visibility::Visibility;

mod common;
use common::slater_params as params;

fn baked(mesh: &Mesh, p: FieldParams) -> Arc<VisibilityField> {
    Arc::new(bake(mesh, p, &BakeOptions::default()).expect("bake").0)
}

fn instance(mesh: &Arc<Mesh>, transform: Similarity, caster: bool, receiver: bool) -> Instance {
    Instance {
        mesh: mesh.clone(),
        transform,
        caster,
        receiver,
    }
}

/// A scene seen through a camera as the harness sees an image-AO scene: its G-buffer, the AO
/// options of its bounds and the receiver pixels' points.
struct View {
    scene: Scene,
    gbuf: GBuffer,
    opts: AoOptions,
    points: EvalPoints,
}

impl View {
    fn new(scene: Scene, camera: &Camera, width: u32, height: u32) -> View {
        let gbuf = GBuffer {
            hits: gbuffer(&PrimaryScene::new(&scene), camera, width, height),
            width,
            height,
        };
        // The points' origins carry the offset: the estimator adds none.
        let opts = AoOptions {
            offset: 0.0,
            ..AoOptions::for_scene(scene.bounding_sphere())
        };
        let points = EvalPoints::pixels(&scene, &gbuf);
        View {
            scene,
            gbuf,
            opts,
            points,
        }
    }

    /// The ray-cast reference over every caster.
    fn tracer(&self) -> Tracer {
        Tracer::new(&self.scene.caster_triangles())
    }

    /// The casters' fields (in the scene's caster order) placed by their instances.
    fn fields(
        &self,
        fields: &[Arc<VisibilityField>],
        selection: Selection,
        intra_bias: IntraBias,
    ) -> FieldScene {
        FieldScene {
            instances: self
                .scene
                .casters()
                .zip(fields)
                .map(|((_, inst), f)| FieldInstance::new(f.clone(), inst.transform))
                .collect(),
            options: LookupOptions {
                selection,
                intra_bias,
            },
        }
    }

    fn ao(&self, vis: &dyn Visibility, rays: &RaySet) -> Vec<f32> {
        let p = &self.points;
        ao_at_points(vis, &p.origins, &p.normals, rays, &self.opts)
    }

    /// The ray origin and the world directions of point `i`'s rays, as `ao_at_point` forms them.
    fn rays_of(&self, i: usize, rays: &RaySet) -> (Vec3, Vec<Vec3>) {
        let (p, n) = (self.points.origins[i], self.points.normals[i]);
        let frame = Frame::from_normal(n);
        let dirs = rays.directions(i as u32);
        let dirs = dirs.into_iter().map(|d| frame.to_world(d)).collect();
        (p + self.opts.offset * n, dirs)
    }
}

/// Per-pixel field AO under a convex caster equals per-pixel ray-cast AO on the same rays.
///
/// A 48 × 96 UV sphere of radius 0.4 hovering 0.1 above a 2 × 2 plane receiver, seen from
/// above at 64 × 64 pixels (about 2,500 receiver pixels), 64 rays per pixel; the sphere's
/// field is the Figure 6 cell 1090 × 32² u8, read with nearest and interpolated selection.
///
/// Tolerances, reused from the 2008 vertex-AO tests on convex casters:
/// - per ray, over the rays that enter the caster's bounding sphere (the rays whose answer comes
///   from the field; the others miss it in both backends by construction): at least 99% agree,
///   the bound of `sphere_caster_nearest_lookup_agrees_with_ray_casting` in `tests/field.rs`
///   (a 64 × 128 UV sphere, rays from outside aimed into its sphere). There it holds at
///   1090 × 128² f32; on a caster that fills its bounding sphere the stored distance from any
///   sample is about 0 for every inward direction, so only rays grazing the polygonal outline
///   can differ, whatever the resolution or precision.
/// - per pixel: an 8-bit image RMS of at most `FIELD_RMS` = 6 and no pixel off by more than
///   `FIELD_MAX` = 0.25, the field tolerances of `src/experiment/stability/hard.rs` for the same
///   field cell, among them the sphere resting on a plane (`receiver_touching_caster`, run by
///   `tests/stability.rs`).
///
/// Measured, both selections: 99.92% of 19,724 entering rays agree (the 15 that differ graze
/// the outline: the field reports the sphere, the ray passes between it and the inscribed
/// polygon), RMS 0.31/255, max |Δ| 1/64 (one ray).
#[test]
fn per_pixel_field_ao_matches_ray_casting_under_a_convex_caster() {
    let sphere = Arc::new(procedural::uv_sphere(0.4, 48, 96).expect("sphere"));
    let plane = Arc::new(procedural::plane(2.0, 2).expect("plane"));
    let centre = Vec3::new(0.0, 0.5, 0.0);
    let view = View::new(
        Scene {
            instances: vec![
                instance(&plane, Similarity::default(), false, true),
                instance(
                    &sphere,
                    Similarity::new(Quat::IDENTITY, centre, 1.0),
                    true,
                    false,
                ),
            ],
        },
        &Camera {
            eye: Vec3::new(0.0, 2.2, 1.4),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 45.0,
        },
        64,
        64,
    );
    let pts = &view.points;
    assert!(pts.len() > 2000, "{} receiver pixels", pts.len());
    let rays = RaySet::new(8, 1);
    let tracer = view.tracer();
    let exact = view.ao(&tracer, &rays);
    // Not agreeing on nothing: the sphere occludes some pixels strongly.
    let darkest = exact.iter().copied().fold(1.0, f32::min);
    assert!(darkest < 0.5, "darkest ray-cast pixel {darkest}");
    let field = baked(&sphere, params(1090, 32, Precision::U8));
    let (reference, mask) = pts.image(&view.scene, &view.gbuf, &exact);
    for selection in [Selection::Nearest, Selection::Interpolated] {
        let fs = view.fields(
            std::slice::from_ref(&field),
            selection,
            IntraBias::default(),
        );
        let inst = &fs.instances[0];
        // Per ray, over the rays entering the caster's sphere.
        let (mut entering, mut agree) = (0usize, 0usize);
        for i in 0..pts.len() {
            let (o, dirs) = view.rays_of(i, &rays);
            for d in dirs {
                let enters = ray_sphere(o, d, inst.world_center, inst.world_radius)
                    .is_some_and(|(_, t1)| t1 >= 0.0);
                if enters {
                    entering += 1;
                    let f = fs.occluded(o, d, 0.0, f32::INFINITY);
                    agree += (f == tracer.occluded(o, d, 0.0, f32::INFINITY)) as usize;
                }
            }
        }
        let share = agree as f64 / entering as f64;
        // Per pixel.
        let ao = view.ao(&fs, &rays);
        let (image, _) = pts.image(&view.scene, &view.gbuf, &ao);
        let rms = rms_u8(&image.data, &reference.data, Some(&mask));
        let max = ao
            .iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).abs() as f64)
            .fold(0.0, f64::max);
        eprintln!(
            "{selection:?}: {} pixels, {entering} entering rays, agreement {share:.4}, \
             RMS {rms:.3}/255, max |Δ| {max:.4}",
            pts.len()
        );
        assert!(entering > 10_000, "{selection:?}: {entering} entering rays");
        assert!(share >= 0.99, "{selection:?}: per-ray agreement {share:.4}");
        assert!(rms <= FIELD_RMS, "{selection:?}: image RMS {rms:.3}");
        assert!(max <= FIELD_MAX, "{selection:?}: max |Δ| {max:.4}");
    }
}

/// A convex body does not occlude itself: a UV sphere that is both caster and receiver, its
/// own field answering through the intra-object test (2010 Figure 2), has per-pixel AO exactly
/// 1 at every pixel that sees it, with nearest and interpolated selection, for the Figure 6
/// cell 1090 × 32² u8 and for 4226 × 32² u8 (half its positional tolerance).
///
/// Why exactly 1 (tolerance 0): a pixel's ray leaves a facet of the inscribed mesh, so its
/// origin lies inside the bounding sphere and the lookup takes the intra-object branch, which
/// reports an occluder at `t = d1 − d2 ≤ d1` (d1 the distance to the exit point, d2 ≥ 0 the
/// stored distance) only when `t` exceeds the field's tolerance `positional + directional·d1`
/// (`IntraTolerance`). The test checks that every ray's d1 lies below `positional` (measured:
/// d1 ≤ 0.002 R on this 48 × 96 sphere, where the sliver between facets and sphere is thin;
/// `positional` is 0.08 R at 1090 maps and 0.04 R at 4226): then no stored distance can make a
/// ray occluded. The ray cast gives 1 too (the offset origin is in front of its facet).
/// Measured: 0 of 1,476 pixels below 1 for both cells and selections.
///
/// Negative control: the paper's own test, d1 > d2 without tolerance (`IntraBias::Fixed(0)`),
/// marks most pixels occluded on the same sphere (measured: 1,467 of 1,476): the sample nearest
/// the exit point lies on the sphere too, outside the inscribed mesh, and reads the surface
/// right under it (d2 ≈ 0).
#[test]
fn a_sphere_does_not_occlude_its_own_pixels() {
    let sphere = Arc::new(procedural::uv_sphere(0.5, 48, 96).expect("sphere"));
    let view = View::new(
        Scene {
            instances: vec![instance(&sphere, Similarity::default(), true, true)],
        },
        &Camera {
            eye: Vec3::new(0.6, 1.2, 1.6),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 40.0,
        },
        64,
        64,
    );
    let pts = &view.points;
    assert!(pts.len() > 1000, "{} sphere pixels", pts.len());
    let rays = RaySet::new(8, 1);
    let raycast = view.ao(&view.tracer(), &rays);
    assert!(raycast.iter().all(|&a| a == 1.0), "ray cast self-occludes");
    // The largest distance from a ray origin to the sphere's exit point.
    let bounds = sphere.bounding_sphere();
    let d1_max = (0..pts.len())
        .flat_map(|i| {
            let (o, dirs) = view.rays_of(i, &rays);
            dirs.into_iter().map(move |d| {
                let (t0, t1) = ray_sphere(o, d, bounds.center, bounds.radius).expect("inside");
                assert!(t0 < 0.0, "origin {o} outside the bounding sphere");
                t1
            })
        })
        .fold(0.0f32, f32::max);
    for p in [
        params(1090, 32, Precision::U8),
        params(4226, 32, Precision::U8),
    ] {
        let field = baked(&sphere, p);
        let positional = field.intra.positional();
        eprintln!(
            "{} × {}²: d1 ≤ {:.5} R, positional tolerance {:.4} R",
            p.count,
            p.res,
            d1_max / bounds.radius,
            positional / bounds.radius
        );
        assert!(d1_max < positional, "d1 {d1_max} vs tolerance {positional}");
        for selection in [Selection::Nearest, Selection::Interpolated] {
            let fs = view.fields(
                std::slice::from_ref(&field),
                selection,
                IntraBias::default(),
            );
            let ao = view.ao(&fs, &rays);
            let below = ao.iter().filter(|&&a| a < 1.0).count();
            let least = ao.iter().copied().fold(1.0, f32::min);
            eprintln!(
                "{} × {}² {selection:?}: {below} of {} pixels below 1 (least {least})",
                p.count,
                p.res,
                ao.len()
            );
            assert_eq!(below, 0, "{selection:?}: least AO {least}");
        }
        let paper = view.fields(
            std::slice::from_ref(&field),
            Selection::Nearest,
            IntraBias::Fixed(0.0),
        );
        let ao = view.ao(&paper, &rays);
        let below = ao.iter().filter(|&&a| a < 1.0).count();
        eprintln!("  without tolerance: {below} pixels below 1");
        assert!(below * 2 > ao.len(), "without tolerance: {below} below 1");
    }
}

/// The lower half of a lat-long sphere of radius `r` about the origin, open at the equator
/// (the rim), `rings` latitude rings from the bottom pole to the rim and `slices` longitudes,
/// wound so that its inside (facing the centre) is its front.
fn bowl(r: f32, rings: usize, slices: usize) -> Mesh {
    use std::f64::consts::{FRAC_PI_2, TAU};
    let mut positions = vec![Vec3::new(0.0, -r, 0.0)];
    for j in 1..=rings {
        let a = FRAC_PI_2 * j as f64 / rings as f64; // angle from the bottom pole
        for i in 0..slices {
            let phi = TAU * i as f64 / slices as f64;
            let p = glam::DVec3::new(a.sin() * phi.cos(), -a.cos(), a.sin() * phi.sin());
            positions.push((p * r as f64).as_vec3());
        }
    }
    let v = |j: usize, i: usize| (1 + (j - 1) * slices + i % slices) as u32;
    let mut triangles = Vec::new();
    for i in 0..slices {
        triangles.push([0, v(1, i + 1), v(1, i)]);
        for j in 1..rings {
            triangles.push([v(j, i), v(j + 1, i + 1), v(j + 1, i)]);
            triangles.push([v(j, i), v(j, i + 1), v(j + 1, i + 1)]);
        }
    }
    Mesh::from_parts("bowl", positions, triangles).expect("bowl")
}

/// A concave closed form through the intra-object test: the bottom pole of a hemispherical
/// bowl sees half the sky.
///
/// The bowl is the lower half of a sphere of radius R about O, open at the rim (the equator,
/// a circle of radius R), its inside facing up (32 rings × 128 slices); it is both caster and
/// receiver. At the bottom pole P the normal points at O. A direction at angle θ from the
/// normal leaves P along a chord PQ; the triangle OPQ is isosceles (OP = OQ = R), so its angle
/// at Q is θ too and the central angle ∠POQ = 180° − 2θ (the inscribed angle theorem: θ is
/// half the arc from Q to the antipode of P). Q lies on the rim when ∠POQ = 90°, at θ₀ = 45°:
/// directions within 45° of the normal leave through the opening, all others hit the bowl. With
/// the cosine density the open fraction is ∫₀^θ₀ 2 cos θ sin θ dθ = sin²θ₀ = 1/2. The pixel's
/// normal is the pole fan triangle's, tilted by δ ≈ 1.4° from the axis; the open cone then
/// contributes (n · axis) sin²θ₀ (the cosine-weighted integral of a cone's directions is
/// π sin²θ₀ along its axis), so the expected value is ½ cos δ (0.49985).
///
/// Tolerances, at the pole pixel of a 65 × 65 view from straight above (its centre pixel looks
/// exactly at P), with 64² rays under 8 rotations (8 copies of the point):
/// - ray cast against the closed form: 2/k = 1/32, the per-point bound for k² centred cosine
///   strata of `RAYCAST_CLOSED_FORM_MAX` in `src/experiment/stability/hard.rs` (an outline
///   crosses about 4k strata, each off by at most 1/N, errors of one sign averaging ½).
/// - field (4226 × 64² u8, γ its covering angle, 2.3°): P lies on the bowl's bounding sphere
///   (centre O, radius R), so the lookup reads the map of the sample s nearest the exit point
///   Q, within γ of Q. A sample above the rim sees down through the opening to the bowl near P
///   (d2 ≈ d1, within the intra tolerance: free); a sample on the bowl sees the wall right under
///   it (d2 ≈ 0: occluded). So a ray can be misjudged only when Q lies within γ of the rim
///   (nearest selection: ∠POQ within 90° ± γ, θ within 45° ± γ/2) or within 2γ of it
///   (interpolated: the three blended samples span a Delaunay triangle of circumradius ≤ γ, so
///   θ within 45° ± γ). The map resolution does not enter: a half-texel direction error
///   (0.02 rad at 64²) moves the end of the read chord near P, not across the rim, and is
///   absorbed by the tolerance's directional part. Hence (a) on the same rays, field and ray
///   cast differ only on rays within that band b of 45° (checked ray by ray), and (b) the
///   field's open region lies between the cones of θ₀ ∓ b, whose open fractions are
///   ½ ∓ ½ sin 2b, so the field's estimate is within ½ sin 2b + 2/k of ½ cos δ (0.051 nearest,
///   0.072 interpolated).
///
/// Measured: ray cast 0.4976–0.4978; field, nearest 0.4944–0.4946 (22–24 of 4096 rays differ,
/// all within 1.1° of 45°, band 1.15°), interpolated 0.4775–0.4780 (80–82 rays, within 1.8°,
/// band 2.3°). Both lean toward occlusion: the Slater set has a ring of samples on its equator,
/// that is on the rim, just outside the inscribed rim polygon, and they see the back of the
/// wall right under them.
#[test]
fn the_bottom_of_a_bowl_sees_half_the_sky() {
    let r = 0.5f32;
    let mesh = Arc::new(bowl(r, 32, 128));
    let pole = Vec3::new(0.0, -r, 0.0);
    let (w, h) = (65u32, 65u32);
    let mut view = View::new(
        Scene {
            instances: vec![instance(&mesh, Similarity::default(), true, true)],
        },
        &Camera {
            eye: Vec3::new(0.0, 1.5, 0.0),
            target: pole,
            up: Vec3::Z,
            fov_y_deg: 30.0,
        },
        w,
        h,
    );
    let centre = (h / 2 * w + w / 2) as usize;
    let Support::Pixels(pixels) = &view.points.support else {
        unreachable!("pixel points")
    };
    let j = pixels
        .iter()
        .position(|&px| px == centre)
        .expect("the centre pixel sees the bowl");
    let (p, n) = (view.points.points[j], view.points.normals[j]);
    assert!(
        p.distance(pole) < 1e-6 * r,
        "centre pixel sees {p}, not the pole"
    );
    assert!(!view.points.crease[j]);
    let copies = 8;
    view.points.origins = vec![view.points.origins[j]; copies];
    view.points.normals = vec![n; copies];
    let axis = Vec3::Y;
    let theta0 = std::f64::consts::FRAC_PI_4;
    let expected = (n.dot(axis) as f64) * theta0.sin().powi(2);
    let k = 64u32;
    let rays = RaySet::new(k, 1);
    let strata = 2.0 / k as f64;
    let raycast = view.ao(&view.tracer(), &rays);
    let field = baked(&mesh, params(4226, 64, Precision::U8));
    let gamma = (field.intra.covering / field.bounds.radius) as f64;
    eprintln!(
        "pole normal tilt {:.2}°, expected {expected:.5}, covering angle γ {:.2}°",
        n.dot(axis).acos().to_degrees(),
        gamma.to_degrees()
    );
    for (i, &a) in raycast.iter().enumerate() {
        let e = (a as f64 - expected).abs();
        assert!(e <= strata, "rotation {i}: ray cast {a} vs {expected}");
    }
    let tracer = view.tracer();
    for (selection, band) in [
        (Selection::Nearest, gamma / 2.0),
        (Selection::Interpolated, gamma),
    ] {
        let fs = view.fields(
            std::slice::from_ref(&field),
            selection,
            IntraBias::default(),
        );
        let ao = view.ao(&fs, &rays);
        let closed = 0.5 * (2.0 * band).sin() + strata;
        for (i, (&a, &rc)) in ao.iter().zip(&raycast).enumerate() {
            // (a) Per ray: every disagreement lies within the band about 45°.
            let (o, dirs) = view.rays_of(i, &rays);
            let (mut flipped, mut worst) = (0, 0.0f64);
            for d in &dirs {
                let f = fs.occluded(o, *d, 0.0, f32::INFINITY);
                if f != tracer.occluded(o, *d, 0.0, f32::INFINITY) {
                    flipped += 1;
                    worst = worst.max(((d.dot(axis) as f64).acos() - theta0).abs());
                }
            }
            // (b) The pixel's AO against the closed form.
            let e = (a as f64 - expected).abs();
            eprintln!(
                "{selection:?} rotation {i}: ray cast {rc:.4}, field {a:.4} ({flipped} rays \
                 differ, at most {:.2}° from 45°, band {:.2}°); field vs ½ cos δ {e:.4} \
                 (tolerance {closed:.4})",
                worst.to_degrees(),
                band.to_degrees()
            );
            assert!(
                worst <= band,
                "{selection:?} rotation {i}: a ray {:.2}° from the rim's 45° differs",
                worst.to_degrees()
            );
            assert!(e <= closed, "{selection:?} rotation {i}: {a} vs {expected}");
        }
    }
}
