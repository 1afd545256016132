// Vertex ambient occlusion by field lookup (Gaitatzes et al., WSCG 2008 / WSCG 2010): each
// invocation takes one receiver point and a run of its k^2 stratified cosine rays (the host's
// ray set: base directions in `dirs`, the point's rotation in the receiver record), loops over
// them and over the field instances, stopping at the first occluding instance, and writes the
// number of free rays; the host adds up a point's runs. An invocation whose loops the driver cut
// short writes CUT_SHORT instead (shaders/loop_budget.wgsl).
//
// `probe_main` answers single lookups (nearest map, texel, both selections) so that the host
// can compare every stage with the CPU path.

// Mirrors `AoParamsGpu` (src/gpu/field_ao.rs).
struct Params {
    // Points, rays per point, instances, threads per dispatch row.
    counts: vec4<u32>,
    // Selection (0 nearest, 1 interpolated), rays per invocation, invocations per point, trips
    // of the completion loop.
    mode: vec4<u32>,
    // Origin offset along the normal, tmax, intra-object bias (a fraction of 2R, or the scale of
    // the field's own tolerance), 1 when the bias is such a scale (`IntraBias::Auto`).
    ray: vec4<f32>,
}

// Mirrors `ReceiverGpu`: position and cos of the point's ray rotation; normal and sin.
struct Receiver {
    p: vec4<f32>,
    n: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> receivers: array<Receiver>;
@group(0) @binding(2) var<storage, read> tables: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> mesh: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> instances: array<Instance>;
@group(0) @binding(5) var<storage, read_write> out: array<u32>;
@group(0) @binding(6) var<storage, read> dirs: array<vec4<f32>>;

@compute @workgroup_size(64)
fn ao_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.counts.w;
    let per_point = params.mode.z;
    if i >= params.counts.x * per_point {
        return;
    }
    let first = (i % per_point) * params.mode.y;
    let last = min(first + params.mode.y, params.counts.y);
    let rc = receivers[i / per_point];
    let nrm = rc.n.xyz;
    let cs = rc.p.w;
    let sn = rc.n.w;
    let frame = frame_from_normal(nrm);
    let origin = rc.p.xyz + params.ray.x * nrm;
    let tmax = params.ray.y;
    var free = 0u;
    for (var r = first; r < last; r++) {
        let b = dirs[r].xyz;
        let local = vec3<f32>(cs * b.x - sn * b.y, sn * b.x + cs * b.y, b.z);
        let dir = frame_to_world(frame, local);
        var blocked = false;
        for (var k = 0u; k < params.counts.z; k++) {
            if instance_occludes(instances[k], origin, dir, 0.0, tmax, params.mode.x, params.ray.z, params.ray.w != 0.0) {
                blocked = true;
                break;
            }
        }
        if !blocked {
            free += 1u;
        }
    }
    out[i] = select(CUT_SHORT, free, loops_completed(params.mode.w));
}

// Probe i: unit point u = receivers[i].p.xyz and model direction receivers[i].n.xyz on the
// field of instance 0; writes (nearest map, texel, nearest sample bits, interpolated bits).
@compute @workgroup_size(64)
fn probe_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.counts.w;
    if i >= params.counts.x {
        return;
    }
    let inst = instances[0];
    let u = receivers[i].p.xyz;
    let dir = receivers[i].n.xyz;
    let pbase = inst.tables.x;
    let m = nearest_point(u, inst.kind.x, inst.kind.z, pbase);
    let local = frame_to_local(frame_from_normal(-sphere_point(pbase, m)), dir);
    let t = layout_to_texel(inst.kind.w, inst.data.x, local);
    out[4u * i] = m;
    out[4u * i + 1u] = t;
    out[4u * i + 2u] = bitcast<u32>(field_sample(inst, u, dir, SELECT_NEAREST));
    out[4u * i + 3u] = bitcast<u32>(field_sample(inst, u, dir, SELECT_INTERPOLATED));
}
