// Soft shadows from spherical lights by ray casting (Gaitatzes, Andreadis, Papaioannou,
// Chrysanthou, WSCG 2010, §4.2; the reference the field lookup is compared with): as
// shaders/field_shadow.wgsl, each shadow ray an any-hit query of the CWBVH (shaders/bvh.wgsl)
// from the offset origin to the near side of its light. `receivers` holds the points
// (binding 6, shaders/bvh.wgsl); each invocation writes the f32 weight of its unblocked rays
// and of all its rays, or CUT_SHORT first when the driver cut its loops short.

@group(0) @binding(7) var<storage, read> samples: array<ConeSample>;
@group(0) @binding(8) var<storage, read> lights: array<Light>;

@compute @workgroup_size(64)
fn shadow_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    let per_point = params.invocations_per_point;
    if i >= params.ray_count * per_point {
        return;
    }
    let cells = params.cells;
    let first = (i % per_point) * params.rays_per_invocation;
    let last = min(first + params.rays_per_invocation, cells * params.light_count);
    let rc = receivers[i / per_point];
    let nrm = rc.normal;
    let origin = rc.position + params.origin_offset * nrm;
    var lit = 0.0;
    var total = 0.0;
    var r = first;
    while r < last {
        let li = r / cells;
        let end = min((li + 1u) * cells, last);
        let cone = light_cone(lights[li], origin, cells);
        if !cone.outside {
            r = end;
            continue;
        }
        for (; r < end; r++) {
            let ray = shadow_ray(cone, r - li * cells, samples[r - li * cells], rc.rotation_cos, rc.rotation_sin, nrm);
            if ray.weight <= 0.0 {
                continue;
            }
            total += ray.weight;
            if trace_ray(origin, ray.dir, 0.0, ray.tmax, true).id == 0xffffffffu {
                lit += ray.weight;
            }
        }
    }
    let done = loops_completed(params.completion_trips);
    out[2u * i] = select(CUT_SHORT, bitcast<u32>(lit), done);
    out[2u * i + 1u] = bitcast<u32>(total);
}
