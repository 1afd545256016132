// Glossy reflections, the integrand (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010,
// §4.2), written once against any visibility's `surface_hit` (src/gpu/visibility.rs): each
// invocation takes one receiver point and a run of its reflection rays
// (shaders/reflect_rays.wgsl), finds each ray's closest hit from the offset origin, shades it
// with the hit's unoriented normal (`sky` on a miss), and writes the f32 sum of its kept rays'
// radiance and their count; the host adds up a point's runs in f64 and divides. An invocation
// whose loops the driver cut short writes CUT_SHORT first instead (shaders/loop_budget.wgsl).

@group(0) @binding(3) var<storage, read> lobe: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> lights: array<Light>;
@group(0) @binding(5) var<storage, read> shading: Shading;

// The radiance ray origin + t dir brings back (t >= 0): the closest hit shaded, or `sky`.
fn radiance(origin: vec3<f32>, dir: vec3<f32>) -> f32 {
    let h = surface_hit(origin, dir, 3.4028235e38);
    if !h.hit {
        return shading.sky;
    }
    return shade_hit(origin, dir, h.t, h.normal);
}

@compute @workgroup_size(64)
fn reflect_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let run = run_of(gid, params.rays_per_point);
    if !run.ok {
        return;
    }
    let rc = receivers[run.point];
    let b = reflect_base(rc.position, rc.normal, params.origin_offset, shading.eye);
    let mirror = shading.mirror != 0u;
    var sum = 0.0;
    var kept = 0.0;
    for (var r = run.first; r < run.last; r++) {
        let ray = reflection_ray(b, lobe[r].xyz, rc.rotation_cos, rc.rotation_sin, mirror);
        if ray.w == 0.0 {
            continue;
        }
        kept += 1.0;
        sum += radiance(b.origin, ray.xyz);
    }
    let done = loops_completed(params.completion_trips);
    out[2u * run.i] = select(CUT_SHORT, bitcast<u32>(sum), done);
    out[2u * run.i + 1u] = bitcast<u32>(kept);
}
