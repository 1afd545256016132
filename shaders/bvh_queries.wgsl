// The CWBVH's own ray queries (src/gpu/tracer.rs, `any_hits` and `closest_hits`): one query ray
// per invocation, the rays in place of the receivers (group 0, binding 1; shaders/integrand.wgsl
// for the header), the CWBVH as group 1 (shaders/bvh.wgsl).

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

fn original_index(id: u32) -> u32 {
    return bitcast<u32>(tris[3u * id].w);
}

@compute @workgroup_size(64)
fn any_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    if i >= params.point_count {
        return;
    }
    let r = rays[i];
    out[i] = select(0u, 1u, occluded(r.origin, r.direction, r.tmin, r.tmax));
}

@compute @workgroup_size(64)
fn closest_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    if i >= params.point_count {
        return;
    }
    let r = rays[i];
    let h = trace_ray(r.origin, r.direction, r.tmin, r.tmax, false);
    out[2u * i] = bitcast<u32>(h.t);
    out[2u * i + 1u] = select(0xffffffffu, original_index(h.id), h.id != 0xffffffffu);
}
