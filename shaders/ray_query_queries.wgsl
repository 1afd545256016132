// The ray-query visibility's own queries (src/gpu/ray_query.rs, `any_hits` and
// `closest_hits`): one query ray per invocation, the rays in place of the receivers (group 0,
// binding 1; shaders/integrand.wgsl for the header), the acceleration structures as group 1
// (shaders/ray_query.wgsl).

// One query ray. Mirrors `RayGpu` (src/gpu/tracer.rs, the query rays of every ray-casting visibility), 32 bytes.
struct QueryRay {
    // Origin.
    origin: vec3<f32>,
    // Smallest hit distance.
    tmin: f32,
    // Direction.
    direction: vec3<f32>,
    // Largest hit distance.
    tmax: f32,
}

@group(0) @binding(1) var<storage, read> query_rays: array<QueryRay>;

@compute @workgroup_size(64)
fn rq_any_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    if i >= params.point_count {
        return;
    }
    let r = query_rays[i];
    out[i] = select(0u, 1u, occluded(r.origin, r.direction, r.tmin, r.tmax));
}

// Six words a ray: t, the triangle's index in its mesh (0xffffffff: no hit), the normal, the
// instance.
@compute @workgroup_size(64)
fn rq_closest_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    if i >= params.point_count {
        return;
    }
    let r = query_rays[i];
    let h = closest_hit(r.origin, r.direction, r.tmin, r.tmax);
    var original = 0xffffffffu;
    if h.triangle != 0xffffffffu {
        original = bitcast<u32>(rq_tris[3u * h.triangle].w);
    }
    out[6u * i] = bitcast<u32>(h.t);
    out[6u * i + 1u] = original;
    out[6u * i + 2u] = bitcast<u32>(h.normal.x);
    out[6u * i + 3u] = bitcast<u32>(h.normal.y);
    out[6u * i + 4u] = bitcast<u32>(h.normal.z);
    out[6u * i + 5u] = h.instance;
}
