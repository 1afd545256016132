// Shadow rays to spherical lights on the GPU (Gaitatzes, Andreadis, Papaioannou, Chrysanthou,
// WSCG 2010, §4.2): a port of `shadow_rays` in src/render/shadow.rs, in the same f32 order.
// At origin o (the receiver moved along its normal), light L subtends the cone about
// axis = (c - o)/|c - o| of 1 - cos θ_max = (r²/d²) / (1 + cos θ_max); the host's square
// samples come mapped to the unit disk (`ConeSample`: the azimuth's cos and sin and ρ², shared
// by every point), and each is placed in the cone (1 - cos θ = ρ²(1 - cos θ_max)), turned by
// the point's rotation, taken to the world by the Duff frame of the axis and normalised. Rays
// with n·ω <= 0 are skipped; the others end at the near side of the light and weigh
// intensity (n·ω) Ω / k². A light of radius 0 is a point light: sample 0 alone, along the
// axis to the centre, weighing intensity (n·ω) / d².
// Needs frame.wgsl.

// One spherical light. Mirrors `LightGpu` (src/gpu/shadow_rays.rs), 32 bytes.
struct Light {
    // Centre (world space).
    center: vec3<f32>,
    // Radius.
    radius: f32,
    // Radiance.
    intensity: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// One square sample on the unit disk (the concentric map, computed on the host). Mirrors
// `ConeSampleGpu` (src/gpu/shadow_rays.rs), 16 bytes.
struct ConeSample {
    // x / ρ of the disk point (0 at the centre).
    azimuth_cos: f32,
    // y / ρ of the disk point (0 at the centre).
    azimuth_sin: f32,
    // ρ², the squared distance from the disk's centre.
    radius_sq: f32,
    _pad0: u32,
}

// What every ray of one light shares at one origin (`LightCone` in src/render/shadow.rs).
struct LightCone {
    // Whether the origin is outside the light (else the light is skipped).
    outside: bool,
    // Radius 0: one ray (sample 0), along the axis, to the centre.
    point: bool,
    // The origin's frame about the cone's axis.
    frame: Frame,
    // Light centre - origin, its length squared, r².
    to: vec3<f32>,
    d2: f32,
    r2: f32,
    // The unit axis.
    axis: vec3<f32>,
    // 1 - cos θ_max = (r²/d²) / (1 + cos θ_max), without cancellation.
    one_minus_cos: f32,
    // intensity Ω / k² (intensity / d² for a point light): a ray weighs this times n·ω.
    weight_scale: f32,
}

fn light_cone(light: Light, origin: vec3<f32>, cells: u32) -> LightCone {
    let to = light.center - origin;
    let d2 = dot(to, to);
    let r2 = light.radius * light.radius;
    var cone: LightCone;
    cone.outside = d2 > r2 && d2 != 0.0;
    if !cone.outside {
        return cone;
    }
    let axis = to / sqrt(d2);
    let q = r2 / d2;
    cone.point = light.radius == 0.0;
    cone.one_minus_cos = q / (1.0 + sqrt(max(1.0 - q, 0.0)));
    cone.frame = frame_from_normal(axis);
    cone.to = to;
    cone.d2 = d2;
    cone.r2 = r2;
    cone.axis = axis;
    if cone.point {
        cone.weight_scale = light.intensity / d2;
    } else {
        cone.weight_scale = light.intensity * (TAU * cone.one_minus_cos) / f32(max(cells, 1u));
    }
    return cone;
}

// One shadow ray: direction, far end, weight (0: skipped, n·ω <= 0, or a point light's
// samples after the first).
struct ShadowRay {
    dir: vec3<f32>,
    tmax: f32,
    weight: f32,
}

// The ray of sample `j` (`s`) of `cone`, turned by the point's rotation (cs, sn), at normal
// `nrm`.
fn shadow_ray(cone: LightCone, j: u32, s: ConeSample, cs: f32, sn: f32, nrm: vec3<f32>) -> ShadowRay {
    var ray: ShadowRay;
    var dir: vec3<f32>;
    if cone.point {
        if j != 0u {
            return ray;
        }
        dir = cone.axis;
    } else {
        // `square_to_cone` (src/render/shadow.rs): t = 1 - cos θ = ρ²(1 - cos θ_max),
        // sin θ = sqrt(t(2 - t)); the disk's centre has zero azimuth terms, so it gives +z as
        // on the host.
        let t = s.radius_sq * cone.one_minus_cos;
        let sin_t = sqrt(max(t * (2.0 - t), 0.0));
        let l = vec3<f32>(s.azimuth_cos * sin_t, s.azimuth_sin * sin_t, 1.0 - t);
        let local = vec3<f32>(cs * l.x - sn * l.y, sn * l.x + cs * l.y, l.z);
        let w = frame_to_world(cone.frame, local);
        dir = w * (1.0 / sqrt(dot(w, w)));
    }
    ray.dir = dir;
    let cos_n = dot(nrm, dir);
    if cos_n <= 0.0 {
        return ray;
    }
    // The near side of the light along dir, `LightCone::far_end`: the near root as
    // (d² - r²) / (b + sqrt(r² - h²)), h the centre's distance from the ray; d for a point light.
    if cone.point {
        ray.tmax = sqrt(cone.d2);
    } else {
        let b = dot(dir, cone.to);
        let h = cone.to - b * dir;
        ray.tmax = (cone.d2 - cone.r2) / (b + sqrt(max(cone.r2 - dot(h, h), 0.0)));
    }
    ray.weight = cone.weight_scale * cos_n;
    return ray;
}
