// Soft shadows from spherical lights, the integrand (Gaitatzes, Andreadis, Papaioannou,
// Chrysanthou, WSCG 2010, §4.2), written once against any visibility's `occluded`
// (src/gpu/visibility.rs): each invocation takes one receiver point and a run of its shadow
// rays (light-major: ray r is sample r % cells of light r / cells, shaders/shadow_rays.wgsl),
// tests each from the offset origin up to the ray's own far end (the near side of its light),
// and writes the f32 weight of its unblocked rays and of all its rays; the host adds up a
// point's runs in f64 and divides. An invocation whose loops the driver cut short writes
// CUT_SHORT first instead (shaders/loop_budget.wgsl).

@group(0) @binding(3) var<storage, read> samples: array<ConeSample>;
@group(0) @binding(4) var<storage, read> lights: array<Light>;

@compute @workgroup_size(64)
fn shadow_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let cells = arrayLength(&samples);
    let run = run_of(gid, params.rays_per_point);
    if !run.ok {
        return;
    }
    let rc = receivers[run.point];
    let nrm = rc.normal;
    let origin = rc.position + params.origin_offset * nrm;
    var lit = 0.0;
    var total = 0.0;
    var r = run.first;
    while r < run.last {
        let li = r / cells;
        let end = min((li + 1u) * cells, run.last);
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
            if !occluded(origin, ray.dir, 0.0, ray.tmax) {
                lit += ray.weight;
            }
        }
    }
    let done = loops_completed(params.completion_trips);
    out[2u * run.i] = select(CUT_SHORT, bitcast<u32>(lit), done);
    out[2u * run.i + 1u] = bitcast<u32>(total);
}
