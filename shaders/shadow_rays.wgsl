// Shadow rays to spherical lights on the GPU (Gaitatzes, Andreadis, Papaioannou, Chrysanthou,
// WSCG 2010, §4.2): a port of `shadow_rays` in src/render/shadow.rs, in the same f32 order.
// At origin o (the receiver moved along its normal), light L subtends the cone about
// axis = (c - o)/|c - o| of cos θ_max = sqrt(1 - r²/d²); the host's square samples come mapped
// to the unit disk (`ConeSample`: the azimuth's cos and sin and ρ², shared by every point), and
// each is placed in the cone (cos θ = 1 - ρ²(1 - cos θ_max)), turned by the point's rotation,
// taken to the world by the Duff frame of the axis and normalised. Rays with n·ω <= 0 are
// skipped; the others end at the near side of the light and weigh intensity (n·ω) Ω / k².
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

// What every ray of one light shares at one origin.
struct LightCone {
    // Whether the origin is outside the light (else the light is skipped).
    outside: bool,
    // The origin's frame about the cone's axis.
    frame: Frame,
    // Light centre - origin.
    to: vec3<f32>,
    // |to|² - r².
    d2_minus_r2: f32,
    // cos θ_max.
    cos_max: f32,
    // intensity Ω / k²: a ray weighs this times n·ω.
    weight_scale: f32,
}

fn light_cone(light: Light, origin: vec3<f32>, cells: u32) -> LightCone {
    let to = light.center - origin;
    let d2 = dot(to, to);
    let r2 = light.radius * light.radius;
    var cone: LightCone;
    cone.outside = d2 > r2;
    if !cone.outside {
        return cone;
    }
    let axis = to / sqrt(d2);
    cone.cos_max = sqrt(max(1.0 - r2 / d2, 0.0));
    cone.frame = frame_from_normal(axis);
    cone.to = to;
    cone.d2_minus_r2 = d2 - r2;
    cone.weight_scale = light.intensity * (TAU * (1.0 - cone.cos_max)) / f32(max(cells, 1u));
    return cone;
}

// One shadow ray: direction, far end, weight (0: skipped, n·ω <= 0).
struct ShadowRay {
    dir: vec3<f32>,
    tmax: f32,
    weight: f32,
}

// The ray of sample `s` of `cone`, turned by the point's rotation (cs, sn), at normal `nrm`.
fn shadow_ray(cone: LightCone, s: ConeSample, cs: f32, sn: f32, nrm: vec3<f32>) -> ShadowRay {
    // `square_to_cone` (src/render/shadow.rs); the disk's centre has zero azimuth terms, so it
    // gives +z as on the host.
    let cos_t = 1.0 - s.radius_sq * (1.0 - cone.cos_max);
    let sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    let l = vec3<f32>(s.azimuth_cos * sin_t, s.azimuth_sin * sin_t, cos_t);
    let local = vec3<f32>(cs * l.x - sn * l.y, sn * l.x + cs * l.y, l.z);
    let w = frame_to_world(cone.frame, local);
    let dir = w * (1.0 / sqrt(dot(w, w)));
    var ray: ShadowRay;
    ray.dir = dir;
    let cos_n = dot(nrm, dir);
    if cos_n <= 0.0 {
        return ray;
    }
    // The near side of the light along dir.
    let b = dot(dir, cone.to);
    ray.tmax = b - sqrt(max(b * b - cone.d2_minus_r2, 0.0));
    ray.weight = cone.weight_scale * cos_n;
    return ray;
}
