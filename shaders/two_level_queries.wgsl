// Two-level ray casting's own ray queries (src/gpu/two_level.rs, `any_hits` and
// `closest_hits`): one query ray per invocation, the rays in place of the receivers (group 0,
// binding 1; shaders/integrand.wgsl for the header), the instances as group 1
// (shaders/two_level.wgsl).

// One query ray. Mirrors `RayGpu` (src/gpu/tracer.rs), 32 bytes.
struct Ray {
    // Origin.
    origin: vec3<f32>,
    // Smallest hit distance.
    tmin: f32,
    // Direction (unit length).
    direction: vec3<f32>,
    // Largest hit distance.
    tmax: f32,
}

@group(0) @binding(1) var<storage, read> rays: array<Ray>;

@compute @workgroup_size(64)
fn any_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    if i >= params.point_count {
        return;
    }
    let r = rays[i];
    out[i] = select(0u, 1u, occluded(r.origin, r.direction, r.tmin, r.tmax));
}

// Five words a ray: the distance's bits, the instance (0xffffffff on a miss), the world normal.
@compute @workgroup_size(64)
fn closest_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    if i >= params.point_count {
        return;
    }
    let r = rays[i];
    let h = two_level_trace(r.origin, r.direction, r.tmin, r.tmax, false);
    var n = vec3<f32>(0.0);
    if h.instance != NO_INSTANCE {
        n = two_level_normal(h);
    }
    out[5u * i] = bitcast<u32>(h.t);
    out[5u * i + 1u] = h.instance;
    out[5u * i + 2u] = bitcast<u32>(n.x);
    out[5u * i + 3u] = bitcast<u32>(n.y);
    out[5u * i + 4u] = bitcast<u32>(n.z);
}
