// The ray queries every ray-casting visibility answers (src/gpu/tracer.rs, `query_rays`: the
// CWBVH, the two levels, ray queries): one query ray per invocation, the rays in place of the
// receivers (group 0, binding 1; shaders/integrand.wgsl for the header). `any_main` asks the
// visibility's `occluded`; `closest_main` hands the ray to the visibility's own
// `write_closest`, which traces it and writes its words (shaders/bvh_queries.wgsl,
// shaders/two_level_queries.wgsl, shaders/ray_query_queries.wgsl).

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

@compute @workgroup_size(64)
fn closest_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    if i >= params.point_count {
        return;
    }
    write_closest(i, rays[i]);
}
