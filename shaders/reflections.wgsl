// Glossy reflections by ray casting (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010,
// §4.2; the reference the field lookup is compared with): as shaders/field_reflect.wgsl, each
// reflection ray a closest-hit query of the CWBVH (shaders/bvh.wgsl) from the offset origin,
// the hit shaded with the triangle's unit geometric normal (v1 - v0) x (v2 - v0), as the CPU
// tracer's `Hit::normal`. `receivers` holds the points (binding 6, shaders/bvh.wgsl), `lights`
// the lights (binding 8, shaders/bvh_shadow.wgsl), `params.rays_per_point` the rays per point;
// each invocation writes the f32 sum of its kept rays' radiance and their count, or CUT_SHORT
// first when the driver cut its loops short.

@group(0) @binding(9) var<storage, read> lobe: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> shading: Shading;

// The radiance ray origin + t dir brings back (t >= 0): the closest triangle shaded, or `sky`.
fn traced_radiance(origin: vec3<f32>, dir: vec3<f32>) -> f32 {
    let h = trace_ray(origin, dir, 0.0, 3.4028235e38, false);
    if h.id == 0xffffffffu {
        return shading.sky;
    }
    let v0 = tris[3u * h.id].xyz;
    let v1 = tris[3u * h.id + 1u].xyz;
    let v2 = tris[3u * h.id + 2u].xyz;
    let c = cross(v1 - v0, v2 - v0);
    let n = c * (1.0 / sqrt(dot(c, c)));
    return shade_hit(origin, dir, h.t, n);
}

@compute @workgroup_size(64)
fn reflect_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    let per_point = params.invocations_per_point;
    if i >= params.ray_count * per_point {
        return;
    }
    let first = (i % per_point) * params.rays_per_invocation;
    let last = min(first + params.rays_per_invocation, params.rays_per_point);
    let rc = receivers[i / per_point];
    let b = reflect_base(rc.position, rc.normal, params.origin_offset, shading.eye);
    let mirror = shading.mirror != 0u;
    var sum = 0.0;
    var kept = 0.0;
    for (var r = first; r < last; r++) {
        let ray = reflection_ray(b, lobe[r].xyz, rc.rotation_cos, rc.rotation_sin, mirror);
        if ray.w == 0.0 {
            continue;
        }
        kept += 1.0;
        sum += traced_radiance(b.origin, ray.xyz);
    }
    let done = loops_completed(params.completion_trips);
    out[2u * i] = select(CUT_SHORT, bitcast<u32>(sum), done);
    out[2u * i + 1u] = bitcast<u32>(kept);
}
