//! Ambient occlusion fields (Kontkanen & Laine 2005, `visfield::aofield`) against closed forms
//! and ray casting, and the `aofield` method's refusals.
//!
//! The closed-form caster is a tessellated unit sphere (a lat-long mesh, every vertex on the
//! sphere): its mesh M lies between the inscribed ball B(r_in) (r_in the least distance from
//! the centre to a facet's plane) and the unit ball, so its occlusion lies between theirs, and a
//! sphere subtends exactly a cap: Ω = 2π(1 − √(1 − R²/d²)) about the direction to its centre,
//! whose horizon-clipped, cosine-weighted occlusion is `cap_occlusion` (tested against
//! numerical integration in `aofield::cap`).

use glam::{DVec3, Quat, Vec3};
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;
use visfield::aofield::bake::{bake, sample_radii, BakeStats, Fitted, NEAR};
use visfield::aofield::cap::{cap_occlusion, sphere_solid_angle};
use visfield::aofield::fit::{solid_angle_cost, Quadratic};
use visfield::aofield::{AoField, AoFieldInstance, AoFieldScene, BakeParams, Inside, Precision};
use visfield::geometry::{procedural, Mesh, Similarity};
use visfield::render::ao::{AoOptions, Falloff};
use visfield::render::truth::{converged_ao, TruthOptions};
use visfield::trace::Tracer;

mod common;
use common::{tiny, ONE_FIELD};

fn triangles(mesh: &Mesh) -> Vec<[Vec3; 3]> {
    (0..mesh.triangle_count())
        .map(|t| mesh.triangle(t))
        .collect()
}

/// The least distance from the origin to a facet's plane: the inscribed ball's radius of a
/// convex mesh about the origin.
fn inradius(tris: &[[Vec3; 3]]) -> f64 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| v.as_dvec3());
            let n = (b - a).cross(c - a).normalize();
            n.dot(a).abs()
        })
        .fold(f64::INFINITY, f64::min)
}

struct SphereField {
    tris: Vec<[Vec3; 3]>,
    fitted: Fitted,
    stats: BakeStats,
    field: AoField,
    r_in: f64,
}

/// The unit sphere as 48 × 96 lat-long bands, baked at `params`, stored in f32.
fn sphere_field(params: BakeParams) -> SphereField {
    let mesh = procedural::uv_sphere(1.0, 48, 96).unwrap();
    let tris = triangles(&mesh);
    let (fitted, stats) = bake(&tris, &params).unwrap();
    let field = AoField::new(&fitted, Precision::F32);
    let r_in = inradius(&tris);
    SphereField {
        tris,
        fitted,
        stats,
        field,
        r_in,
    }
}

/// Whether every ray of a bake sample at distance `d` (model units) from the centre hits the
/// inscribed ball, so the sample's Ω is the whole cone's, the bounding sphere's own solid angle,
/// and its direction the cone's axis. A sample's rays lie in the cone the bounding sphere (radius
/// `rb`) subtends, at the centres of k × k strata of the concentric map, whose ring radius is at
/// most 1 − 1/k, so at most at `1 − cos θ = (1 − 1/k)²(1 − cos β)` from the axis; the inscribed
/// ball subtends `sin α = r_in/d`.
fn every_ray_hits(d: f64, rb: f64, r_in: f64, k: u32) -> bool {
    if d <= rb * (1.0 + 1e-6) {
        return false;
    }
    let one_minus_cos_b = 1.0 - (1.0 - (rb / d).powi(2)).sqrt();
    let ring = 1.0 - 1.0 / f64::from(k);
    let cos_t = 1.0 - ring * ring * one_minus_cos_b;
    let cos_a = (1.0 - (r_in / d).powi(2)).sqrt();
    cos_t > cos_a
}

/// The least `ε_Ω` over quadratics written down for the bounding sphere's exact solid angle
/// (normalised: radius 1) at `radii`: its far-field expansion `s²/π − 1/4π`, and the quadratic
/// through 1/Ω at the first, middle and last radius; each only where feasible beyond `s0`.
fn candidate_cost(radii: &[f64], s0: f64) -> f64 {
    let omega: Vec<f64> = radii.iter().map(|&s| sphere_solid_angle(1.0, s)).collect();
    let mut best = f64::INFINITY;
    let expansion = Quadratic {
        a: 1.0 / PI,
        b: 0.0,
        c: -1.0 / (4.0 * PI),
    };
    if expansion.feasible(s0) {
        best = best.min(solid_angle_cost(&expansion, radii, &omega));
    }
    let idx = [0, radii.len() / 2, radii.len() - 1];
    let m = glam::DMat3::from_cols(
        DVec3::new(
            radii[idx[0]].powi(2),
            radii[idx[1]].powi(2),
            radii[idx[2]].powi(2),
        ),
        DVec3::new(radii[idx[0]], radii[idx[1]], radii[idx[2]]),
        DVec3::ONE,
    );
    let rhs = DVec3::new(
        1.0 / omega[idx[0]],
        1.0 / omega[idx[1]],
        1.0 / omega[idx[2]],
    );
    let p = m.inverse() * rhs;
    let through = Quadratic {
        a: p.x,
        b: p.y,
        c: p.z,
    };
    if through.feasible(s0) {
        best = best.min(solid_angle_cost(&through, radii, &omega));
    }
    best
}

fn texel_quadratic(t: &[f32; 7]) -> Quadratic {
    Quadratic {
        a: f64::from(t[0]),
        b: f64::from(t[1]),
        c: f64::from(t[2]),
    }
}

/// Rounding allowance of Ω̃ read back from f32 coefficients and positions: their relative
/// rounding (2⁻²⁴) moves q, so Ω, by a few units of 1e-7 relative; 1e-5 sr is far above it.
const OMEGA_ROUNDING: f64 = 1e-5;

/// At every texel centre and every one of its sample distances, around a tessellated unit sphere,
/// with normals up (points on horizontal planes below and beside the sphere, the cap above, on
/// and below their horizon): the field's Ω̃ and occlusion against the exact sphere's, within
///
/// - the fit: the least-squares fit is at least as good as any feasible quadratic, so each
///   sample's |Ω̃ − Ω_data| ≤ √ε_Ω ≤ √(least candidate ε_Ω) (asserted here: our fit reaches it);
/// - the data: every ray hits (`every_ray_hits`), so Ω_data is the bounding sphere's, between
///   the inscribed ball's and the unit sphere's: |Ω_data − Ω₁| ≤ Ω₁ − Ω(r_in);
/// - the cap: Ã is 1/π-Lipschitz in Ω (growing the cap adds at most its new solid angle, each
///   direction weighing ≤ 1/π) and 2-Lipschitz in the axis angle (moving the axis by δ sweeps
///   at most the cap's rim, 2π sin α · δ, weighing ≤ 1/π); the axis comes from C, so it is off
///   the centre's direction by at most asin(|C|/(s − |C|)) plus the bounding centre's offset.
#[test]
fn sphere_field_matches_the_exact_cap_at_its_samples_within_the_derived_bound() {
    let params = BakeParams {
        res: 8,
        radial_samples: 16,
        rays: 256,
        reach: 6.0,
    };
    let sf = sphere_field(params);
    let rb = f64::from(sf.fitted.bounds.radius);
    let cb = sf.fitted.bounds.center.as_dvec3();
    assert!(sf.r_in > 0.99 && sf.r_in < rb, "r_in {}", sf.r_in);
    let k = params.rays_per_side();
    let up = Vec3::Y;
    let (mut points, mut clipped, mut below) = (0, 0, 0);
    let mut worst_ratio = 0.0f64;
    for t in 0..sf.field.cube.len() {
        let texel = sf.field.stored.texel(t);
        let s0 = f64::from(texel[3]);
        let radii = sample_radii(s0, &params);
        let q = texel_quadratic(&texel);
        // The fit against the candidates, on the exact data.
        let omega: Vec<f64> = radii.iter().map(|&s| sphere_solid_angle(1.0, s)).collect();
        let ours = solid_angle_cost(&q, &radii, &omega);
        let candidate = candidate_cost(&radii, s0);
        assert!(
            ours <= candidate * (1.0 + 1e-6) + 1e-12,
            "texel {t}: ε_Ω {ours} above a candidate's {candidate}"
        );
        let fit = ours.sqrt();
        let w = sf.field.cube.texel_direction(t);
        let c = Vec3::new(texel[4], texel[5], texel[6]).as_dvec3().length();
        for &s in &radii {
            let p = (cb + s * rb * w.as_dvec3()).as_vec3();
            let d = p.as_dvec3().length();
            assert!(every_ray_hits(d, rb, sf.r_in, k), "texel {t} at s {s}");
            let cap = sf.field.cap_at(p);
            let omega_1 = sphere_solid_angle(1.0, d);
            let tess = omega_1 - sphere_solid_angle(sf.r_in, d);
            let d_omega = fit + tess + OMEGA_ROUNDING;
            assert!(
                (cap.omega - omega_1).abs() <= d_omega,
                "texel {t} s {s}: Ω̃ {} vs exact {omega_1} ± {d_omega}",
                cap.omega
            );
            let d_theta = (c / (s - c)).asin() + cb.length() / d + 1e-6;
            let towards = (-p.as_dvec3()).normalize();
            let cos_t = f64::from(up.y) * towards.y;
            let exact = cap_occlusion(omega_1, cos_t);
            let ours = f64::from(sf.field.occlusion(p, up, &Inside::default()));
            let bound = d_omega / PI + 2.0 * d_theta;
            assert!(
                (ours - exact).abs() <= bound,
                "texel {t} s {s}: Ã {ours} vs exact {exact} ± {bound}"
            );
            worst_ratio = worst_ratio.max((ours - exact).abs() / bound);
            points += 1;
            let sin_a = (1.0 / d).min(1.0);
            if cos_t.abs() < sin_a {
                clipped += 1;
            } else if cos_t <= -sin_a {
                below += 1;
            }
        }
    }
    eprintln!(
        "{points} points ({clipped} horizon-clipped, {below} below the horizon); worst error \
         {worst_ratio:.3} of its bound; bake: max Ω residual {:.4} sr, rms {:.4}",
        sf.stats.max_omega_residual, sf.stats.rms_omega_residual
    );
    assert!(
        clipped > 50 && below > 50,
        "{clipped} clipped, {below} below"
    );
}

/// A similarity applied to the occluder and to the points and normals together leaves the
/// field's occlusion unchanged: the field is read in model space, and Ω and the cap's angle to
/// the normal are invariant under rotation, translation and uniform scale. The allowance is
/// rounding: the point comes back into model space within a few f32 ulps of its coordinates
/// (≤ 1e-6 of its distance), which moves Ã by far less than 1e-4 at these distances (its
/// derivative in the point is at most of order Ω̃'/π + 2/s ≲ 10 per bounding radius).
#[test]
fn a_rigid_motion_of_occluder_and_points_leaves_the_occlusion_unchanged() {
    let sf = sphere_field(BakeParams {
        res: 6,
        radial_samples: 8,
        rays: 64,
        reach: 5.0,
    });
    let field = Arc::new(sf.field);
    let motion = Similarity::new(
        Quat::from_euler(glam::EulerRot::YXZ, 0.8, -0.4, 1.9),
        Vec3::new(3.0, -7.5, 12.0),
        2.5,
    );
    let moved = AoFieldInstance {
        field: field.clone(),
        transform: motion,
    };
    let inside = Inside::default();
    let mut compared = 0;
    for i in 0..400 {
        let a = i as f32 * 0.618_034;
        let p = Vec3::new(a.sin() * 2.5, (1.3 * a).cos() * 2.0, (0.7 * a).sin() * 2.2);
        let n = Vec3::new((2.1 * a).cos(), (0.9 * a).sin(), 0.3).normalize();
        let local = field.occlusion(p, n, &inside);
        let world = moved.occlusion(motion.to_world_point(p), motion.to_world_dir(n), &inside);
        assert!(
            (local - world).abs() <= 1e-4,
            "{p} {n}: {local} in model space, {world} moved"
        );
        compared += usize::from(local > 0.01);
    }
    assert!(compared > 100, "too few occluded points: {compared}");
}

/// Several occluders blend as the paper's multiplicative blending of accessibilities:
/// `1 − A = Π (1 − Ãᵢ)`, bit for bit with the single-occluder values.
#[test]
fn two_occluders_combine_by_the_papers_multiplicative_rule() {
    let sf = sphere_field(BakeParams {
        res: 4,
        radial_samples: 6,
        rays: 64,
        reach: 4.0,
    });
    let field = Arc::new(sf.field);
    let place = |x: f32| AoFieldInstance {
        field: field.clone(),
        transform: Similarity::new(Quat::IDENTITY, Vec3::new(x, 1.5, 0.0), 1.0),
    };
    let (a, b) = (place(-1.2), place(1.4));
    let both = AoFieldScene {
        instances: vec![a.clone(), b.clone()],
        inside: Inside::default(),
    };
    let inside = Inside::default();
    let mut overlapping = 0;
    for i in 0..200 {
        let x = -4.0 + 8.0 * i as f32 / 199.0;
        let p = Vec3::new(x, 0.0, 0.3);
        let (oa, ob) = (
            a.occlusion(p, Vec3::Y, &inside),
            b.occlusion(p, Vec3::Y, &inside),
        );
        let ao = both.ao(p, Vec3::Y);
        assert_eq!(ao, (1.0 - oa) * (1.0 - ob), "at {p}");
        if oa > 0.05 && ob > 0.05 {
            overlapping += 1;
            // Neither the sum of the occlusions nor the larger one.
            assert!(ao > 1.0 - oa - ob && ao < 1.0 - oa.max(ob));
        }
    }
    assert!(overlapping > 20, "{overlapping} points see both occluders");
    assert_eq!(
        both.bytes(),
        field.bytes(),
        "an instanced field is counted once"
    );
}

/// Plane points below a tessellated sphere: the field against converged ray casting of the same
/// mesh (our tracer), two-sided on the RMS over the points.
///
/// Upper: per point, |Ã − A_mesh| ≤ |Ã − Ã₁| + |Ã₁ − A_mesh| (Ã₁ the exact unit sphere's,
/// A_mesh between the inscribed ball's and the unit sphere's). For the field's Ω̃ between two
/// samples sᵢ < s < sᵢ₊₁ of a texel it reads (its q increasing there, asserted, so Ω̃ falls),
/// Ω̃(s) ∈ [Ω(r_in; sᵢ₊₁) − e, Ω₁(sᵢ) + e], e the fit's bound at the samples (as in the test
/// above), so |Ω̃(s) − Ω₁(s)| ≤ max(Ω₁(sᵢ) − Ω₁(s), Ω₁(s) − Ω(r_in; sᵢ₊₁)) + e; bilinear
/// interpolation keeps Ω̃ between its texels' values, so the worst of the four texels bounds it.
/// The truth's own noise adds at most 3× its RMS standard error (a 3σ bound on its mean square).
///
/// Lower: the truth's noise is independent of the field, so the expected mean square of
/// Ã − truth is at least the mean squared standard error; half the RMS standard error is a
/// floor no value can pass unless it reproduces the ray cast's own noise.
#[test]
fn plane_below_a_sphere_against_ray_casting_two_sided() {
    let params = BakeParams {
        res: 8,
        radial_samples: 40,
        rays: 256,
        reach: 6.0,
    };
    let sf = sphere_field(params);
    let rb = f64::from(sf.fitted.bounds.radius);
    let cb = sf.fitted.bounds.center.as_dvec3();
    let k = params.rays_per_side();
    // Per texel: its radii and its fit's bound at them.
    let per_texel: Vec<(Vec<f64>, f64, Quadratic)> = (0..sf.field.cube.len())
        .map(|t| {
            let texel = sf.field.stored.texel(t);
            let s0 = f64::from(texel[3]);
            let radii = sample_radii(s0, &params);
            for &s in &radii {
                assert!(every_ray_hits(s * rb, rb, sf.r_in, k));
            }
            let q = texel_quadratic(&texel);
            let omega: Vec<f64> = radii.iter().map(|&s| sphere_solid_angle(1.0, s)).collect();
            let e = solid_angle_cost(&q, &radii, &omega).sqrt() + OMEGA_ROUNDING;
            (radii, e, q)
        })
        .collect();
    let n = 25;
    let mut points = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let x = -3.0 + 6.0 * i as f32 / (n - 1) as f32;
            let z = -3.0 + 6.0 * j as f32 / (n - 1) as f32;
            points.push(Vec3::new(x, -1.6, z));
        }
    }
    let normals = vec![Vec3::Y; points.len()];
    let scene = AoFieldScene {
        instances: vec![AoFieldInstance {
            field: Arc::new(sf.field.clone()),
            transform: Similarity::default(),
        }],
        inside: Inside::default(),
    };
    let ours = scene.ao_at_points(&points, &normals);
    let tracer = Tracer::new(&sf.tris);
    let opts = AoOptions {
        max_distance: None,
        offset: 0.0,
        falloff: Falloff::Step,
    };
    let truth = converged_ao(&tracer, &points, &normals, &opts, &TruthOptions::default());
    let (mut sq, mut bound_sq, mut noise_sq) = (0.0, 0.0, 0.0);
    for (idx, &p) in points.iter().enumerate() {
        let d = p.as_dvec3().length();
        let s = (p.as_dvec3() - cb).length() / rb;
        let w = ((p.as_dvec3() - cb) / (s * rb)).as_vec3();
        let b = sf.field.cube.bilinear(w);
        let mut d_omega: f64 = 0.0;
        for (&t, &wt) in b.texels.iter().zip(&b.weights) {
            if wt == 0.0 {
                continue;
            }
            let (radii, e, q) = &per_texel[t];
            let i = radii.iter().rposition(|&r| r <= s).expect("past the hull");
            assert!(i + 1 < radii.len(), "point {p} beyond reach");
            assert!(
                2.0 * q.a * radii[i] + q.b >= 0.0,
                "q not increasing at {}",
                radii[i]
            );
            let here = sphere_solid_angle(1.0, d);
            let spread = (sphere_solid_angle(1.0, radii[i] * rb) - here)
                .max(here - sphere_solid_angle(sf.r_in, radii[i + 1] * rb));
            d_omega = d_omega.max(spread + e);
        }
        let towards = (-p.as_dvec3()).normalize();
        let omega_1 = sphere_solid_angle(1.0, d);
        let tess = (omega_1 - sphere_solid_angle(sf.r_in, d)) / PI;
        let d_theta = cb.length() / d + 1e-5;
        let exact = cap_occlusion(omega_1, towards.y);
        let field_occ = 1.0 - f64::from(ours[idx]);
        assert!(
            (field_occ - exact).abs() <= d_omega / PI + 2.0 * d_theta,
            "{p}: field {field_occ}, exact {exact}"
        );
        let bound = d_omega / PI + 2.0 * d_theta + tess;
        let err = f64::from(ours[idx]) - f64::from(truth.values[idx]);
        sq += err * err;
        bound_sq += bound * bound;
        noise_sq += f64::from(truth.stderr[idx]).powi(2);
    }
    let m = points.len() as f64;
    let rms = (sq / m).sqrt();
    let noise = (noise_sq / m).sqrt();
    let upper = (bound_sq / m).sqrt() + 3.0 * noise;
    let lower = 0.5 * noise;
    eprintln!(
        "RMS vs ray casting {:.3}/255, bounds [{:.3}, {:.3}]/255",
        rms * 255.0,
        lower * 255.0,
        upper * 255.0
    );
    assert!(
        rms >= lower && rms <= upper,
        "RMS {rms} outside [{lower}, {upper}]"
    );
}

fn error_of(text: &str) -> String {
    use visfield::experiment::spec::Spec;
    Spec::parse(text, Path::new("specs/bad.json"))
        .expect_err("the spec should be rejected")
        .to_string()
}

fn with_methods(spec: &str, methods: &str) -> String {
    spec.replace(
        r#""reference": {"#,
        &format!(r#""methods": {methods}, "reference": {{"#),
    )
}

const LIGHTS: &str = r#"[{ "center": [2.5, 2.6, 2.2], "radius": 0.3, "intensity": 1 }]"#;

#[test]
fn the_method_refuses_what_it_cannot_answer_naming_the_field_and_value() {
    let m = r#"[{"method": "aofield", "res": [8]}]"#;
    let ao = with_methods(&tiny(ONE_FIELD, ""), m);
    // The tiny AO spec is accepted as it is.
    visfield::experiment::spec::Spec::parse(&ao, Path::new("ok.json")).unwrap();
    let render = r#""render": { "rays_per_point": 16, "image": { "width": 32, "height": 32 } }"#;
    let shadows = ao.replace(
        render,
        &format!(
            r#""render": {{ "what": "shadows", "rays_per_point": 16, "image": {{ "width": 32, "height": 32 }}, "lights": {LIGHTS} }}"#
        ),
    );
    let e = error_of(&shadows);
    assert!(
        e.contains("methods[0]") && e.contains("\"aofield-8-12-f32\"") && e.contains("shadows"),
        "{e}"
    );
    let reflections = ao.replace(
        render,
        &format!(
            r#""render": {{ "what": "reflections", "rays_per_point": 4, "image": {{ "width": 32, "height": 32 }}, "lights": {LIGHTS}, "gloss": "mirror" }}"#
        ),
    );
    let e = error_of(&reflections.replace(
        r#""reference": { "rays_per_point": 16,"#,
        r#""reference": { "rays_per_point": 4,"#,
    ));
    assert!(e.contains("methods[0]") && e.contains("reflections"), "{e}");
    let radius = ao.replace(
        render,
        r#""render": { "rays_per_point": 16, "max_distance": 0.5, "image": { "width": 32, "height": 32 } }"#,
    );
    let e = error_of(&radius);
    assert!(e.contains("render.max_distance = 0.5"), "{e}");
    let falloff = ao.replace(
        render,
        r#""render": { "rays_per_point": 16, "max_distance": 0.5, "falloff": "linear", "image": { "width": 32, "height": 32 } }"#,
    );
    assert!(error_of(&falloff).contains("render.max_distance"));
    // Intra-object: the caster also receives.
    let intra = ao.replace(r#""caster": true,"#, r#""caster": true, "receiver": true,"#);
    assert_ne!(intra, ao);
    let e = error_of(&intra);
    assert!(
        e.contains("methods[0]")
            && e.contains("both caster and receiver")
            && e.contains("scene `tiny`"),
        "{e}"
    );
    // Bad keys, each named with its value.
    for (keys, field, value) in [
        (r#""res": [1]"#, "methods[0].res[0]", "1"),
        (r#""res": [8], "rays": 200"#, "methods[0].rays", "200"),
        (
            r#""res": [8], "radial_samples": 2"#,
            "methods[0].radial_samples",
            "2",
        ),
        (r#""res": [8], "reach": 1.0"#, "methods[0].reach", "1"),
        (
            r#""res": [8], "inner_ao": 1.5"#,
            "methods[0].inner_ao",
            "1.5",
        ),
        (
            r#""res": [8], "inner_power": 0"#,
            "methods[0].inner_power",
            "0",
        ),
        (r#""res": []"#, "methods[0].res", "at least one"),
        (
            r#""res": [8], "precision": []"#,
            "methods[0].precision",
            "at least one",
        ),
    ] {
        let e = error_of(&with_methods(
            &tiny(ONE_FIELD, ""),
            &format!(r#"[{{"method": "aofield", {keys}}}]"#),
        ));
        assert!(e.contains(field) && e.contains(value), "{keys}: {e}");
    }
    for (keys, word) in [
        (r#""res": [8], "colour": 1"#, "colour"),
        (r#""res": [8], "precision": ["f8"]"#, "f8"),
    ] {
        let e = error_of(&with_methods(
            &tiny(ONE_FIELD, ""),
            &format!(r#"[{{"method": "aofield", {keys}}}]"#),
        ));
        assert!(e.contains(word) && e.contains("aofield"), "{keys}: {e}");
    }
}

/// The method end to end on the tiny spec (a supershape over a corner, vertex AO): one row per
/// (res, precision), answered directly, its bytes the stored fields' exactly (7 channels per
/// texel at the precision, u8's 56 bytes of ranges, the 16-byte bounding sphere).
#[test]
fn the_method_runs_end_to_end_with_exact_bytes() {
    use visfield::experiment::columns::{read_csv, NamedRow};
    use visfield::experiment::run::run;
    let dir = tempfile::tempdir().unwrap();
    let spec = with_methods(
        &tiny(ONE_FIELD, ""),
        r#"[{"method": "aofield", "res": [4, 8], "precision": ["f32", "u8"], "radial_samples": 6, "rays": 64}]"#,
    );
    let ls = common::loaded(dir.path(), &spec);
    let out = dir.path().join("out");
    run(&ls, &common::options(out.clone())).unwrap();
    let rows: Vec<NamedRow> = read_csv(&out.join("methods.csv")).unwrap();
    let settings: Vec<&str> = rows.iter().map(|r| r.get("setting").unwrap()).collect();
    assert_eq!(
        settings,
        [
            "aofield-4-6-f32",
            "aofield-4-6-u8",
            "aofield-8-6-f32",
            "aofield-8-6-u8"
        ]
    );
    for r in &rows {
        let res: u64 = r.get("res").unwrap().parse().unwrap();
        let texels = 6 * res * res;
        let bytes = match r.get("precision").unwrap() {
            "f32" => texels * 28 + 16,
            "u8" => texels * 7 + 56 + 16,
            other => panic!("{other}"),
        };
        assert_eq!(r.number("bytes"), Some(bytes as f64));
        assert_eq!(r.get("through"), Some("direct"));
        let rms = r.number("rms_vs_truth").unwrap();
        assert!(rms > 0.0 && rms.is_finite(), "{rms}");
    }
}

/// The bake is a pure function of the mesh and the parameters, the sample radii follow the
/// documented rule, and a sample's rays stay in the bounding sphere's cone.
#[test]
fn sample_radii_follow_the_documented_rule() {
    let params = BakeParams {
        res: 2,
        radial_samples: 5,
        rays: 16,
        reach: 7.0,
    };
    let r = sample_radii(0.4, &params);
    assert_eq!(r.len(), 5);
    assert!((r[0] - (0.4 + NEAR)).abs() < 1e-12);
    assert!((r[4] - 7.0).abs() < 1e-12);
    // Logarithmic in the distance from the hull: constant ratios.
    let ratio = (r[1] - 0.4) / (r[0] - 0.4);
    for i in 1..4 {
        assert!(((r[i + 1] - 0.4) / (r[i] - 0.4) - ratio).abs() < 1e-9);
    }
}
