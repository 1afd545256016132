// Glossy reflection rays and their shading on the GPU (Gaitatzes, Andreadis, Papaioannou,
// Chrysanthou, WSCG 2010, §4.2 and Figure 9): a port of `reflection_rays` and `shade`
// (src/render/reflect.rs), in the same f32 order.
// At a receiver p with normal n seen from the eye e, r = v - 2(v.n)n with v = (p - e)/|p - e|;
// the mirror lobe is the single ray r, the Phong lobe the host's lobe directions (the shared
// square samples mapped by `square_to_phong` on the host: powf, cos and sin are not the GPU's)
// turned by the point's rotation and taken to the world by the Duff frame of r. Rays with
// n.w <= 0 are dropped. A ray brings back `sky` on a miss, else the hit shaded as a diffuse
// surface lit by the lights' centres. Needs frame.wgsl, shadow_rays.wgsl (`Light`) and a
// module-scope `lights: array<Light>` and `shading: Shading`.

// The shading and the eye. Mirrors `ShadingGpu` (src/gpu/reflect_rays.rs), 32 bytes.
struct Shading {
    // The eye the receivers are seen from (world).
    eye: vec3<f32>,
    // Diffuse albedo of the reflected surfaces.
    albedo: f32,
    // Radiance of a ray that meets nothing.
    sky: f32,
    // Sum of the lights' intensities, as the host adds them.
    light_total: f32,
    // Lights.
    light_count: u32,
    // 1: mirror lobe (one ray along r), 0: the lobe directions of `lobe`.
    mirror: u32,
}

// glam's `normalize_or_zero`: v / |v| where 1 / |v| is finite and positive, else 0.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / sqrt(dot(v, v));
    if rcp > 0.0 && rcp <= 3.4028235e38 {
        return v * rcp;
    }
    return vec3<f32>(0.0);
}

// What every reflection ray of one receiver shares.
struct ReflectBase {
    // The ray origin p + offset n.
    origin: vec3<f32>,
    // The receiver's normal.
    nrm: vec3<f32>,
    // The mirror direction r.
    r: vec3<f32>,
    // The Duff frame of r (the Phong lobe's).
    frame: Frame,
}

fn reflect_base(p: vec3<f32>, nrm: vec3<f32>, offset: f32, eye: vec3<f32>) -> ReflectBase {
    var b: ReflectBase;
    b.origin = p + offset * nrm;
    b.nrm = nrm;
    let v = normalize_or_zero(p - eye);
    b.r = normalize_or_zero(v - (2.0 * dot(v, nrm)) * nrm);
    b.frame = frame_from_normal(b.r);
    return b;
}

// Reflection ray `lobe_dir` (a Phong lobe direction about +z; ignored for the mirror) turned
// by the point's rotation (cs, sn): xyz the world direction, w 1 when kept (n.w > 0), else 0.
fn reflection_ray(b: ReflectBase, lobe_dir: vec3<f32>, cs: f32, sn: f32, mirror: bool) -> vec4<f32> {
    var dir = b.r;
    if !mirror {
        let l = lobe_dir;
        let local = vec3<f32>(cs * l.x - sn * l.y, sn * l.x + cs * l.y, l.z);
        let w = frame_to_world(b.frame, local);
        dir = w * (1.0 / sqrt(dot(w, w)));
    }
    return vec4<f32>(dir, select(0.0, 1.0, dot(b.nrm, dir) > 0.0));
}

// `shade` (src/render/reflect.rs) of a hit at distance t with unoriented unit normal `normal`.
fn shade_hit(origin: vec3<f32>, dir: vec3<f32>, t: f32, normal: vec3<f32>) -> f32 {
    let q = origin + t * dir;
    var m = normal;
    if dot(normal, dir) > 0.0 {
        m = -normal;
    }
    var lit = 0.0;
    for (var l = 0u; l < shading.light_count; l++) {
        let light = lights[l];
        lit += light.intensity * max(dot(m, normalize_or_zero(light.center - q)), 0.0);
    }
    if shading.light_total > 0.0 {
        return shading.albedo * min(lit / shading.light_total, 1.0);
    }
    return 0.0;
}
