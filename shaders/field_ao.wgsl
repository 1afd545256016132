// The field visibility's batched form of the AO integrand (shaders/ao.wgsl; Gaitatzes et al.,
// WSCG 2008 / WSCG 2010): the same rays (`ao_dir`), answered by the same lookup as the field's
// `occluded` (shaders/field_visibility.wgsl), but shared over the workgroup (`ao_queue_main`,
// the field AO kernel's default; `queue_rays: false` runs the integrand's `ao_main`).
//
// `probe_main` answers single lookups (nearest map, texel, both selections) so that the host
// can compare every stage with the CPU path.

// Rays are answered in two steps per round of AO_CHUNK rays an invocation: every invocation
// culls its rays against the instances' world spheres and queues the ones that meet a sphere
// in workgroup memory; then the workgroup's invocations share the queue, AO_GROUP entries at a
// time. llvmpipe runs 8 invocations as the lanes of one SIMD program, masked, so a ray that
// misses every sphere would otherwise wait through a whole lookup whenever a neighbouring
// lane's ray entered one (docs/gpu.md, "Field kernel speed on lavapipe").
// The same arithmetic decides every ray (the cull is the lookup's own world-sphere test).
const AO_GROUP: u32 = 64u;
const AO_CHUNK: u32 = 32u;

var<workgroup> queue: array<u32, 2048>;
var<workgroup> queue_len: atomic<u32>;
// Set when any invocation of the group (one past the points too) had its loops cut short.
var<workgroup> group_cut_short: atomic<u32>;
var<workgroup> blocked_rays: array<atomic<u32>, AO_GROUP>;
// Per invocation: frame x and cos, frame y and sin, normal, origin.
var<workgroup> frame_x: array<vec4<f32>, AO_GROUP>;
var<workgroup> frame_y: array<vec4<f32>, AO_GROUP>;
var<workgroup> frame_z: array<vec3<f32>, AO_GROUP>;
var<workgroup> origins: array<vec3<f32>, AO_GROUP>;
var<workgroup> firsts: array<u32, AO_GROUP>;

// Whether the world segment origin + t dir, t in [0, tmax], meets any instance's world sphere
// (the first test of `instance_occludes`); `first` is instance 0's record, from registers.
fn meets_any_sphere(origin: vec3<f32>, dir: vec3<f32>, tmax: f32, first: Instance) -> bool {
    let w0 = ray_sphere(origin, dir, first.world_center, first.world_radius);
    if w0.z != 0.0 && w0.y >= 0.0 && w0.x <= tmax {
        return true;
    }
    if SINGLE_INSTANCE {
        return false;
    }
    for (var k = 1u; k < field_params.instance_count; k++) {
        let ws = ray_sphere(origin, dir, instances[k].world_center, instances[k].world_radius);
        if ws.z != 0.0 && ws.y >= 0.0 && ws.x <= tmax {
            return true;
        }
    }
    return false;
}

fn world_dir(lid: u32, r: u32) -> vec3<f32> {
    let fx = frame_x[lid];
    let fy = frame_y[lid];
    return ao_dir(Frame(fx.xyz, fy.xyz, frame_z[lid]), fx.w, fy.w, r);
}

@compute @workgroup_size(64)
fn ao_queue_main(@builtin(global_invocation_id) gid: vec3<u32>,
                 @builtin(local_invocation_index) lid: u32) {
    let i = gid.x + gid.y * params.row_stride;
    let per_point = params.invocations_per_point;
    let in_range = i < params.point_count * per_point;
    var first = 0u;
    var last = 0u;
    // This invocation's receiver in registers for the cull (the queue's readers take it from
    // workgroup memory).
    var frame = Frame(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var origin = vec3<f32>(0.0);
    var cs = 0.0;
    var sn = 0.0;
    if in_range {
        first = (i % per_point) * params.rays_per_invocation;
        last = min(first + params.rays_per_invocation, params.rays_per_point);
        let rc = receivers[i / per_point];
        let nrm = rc.normal;
        frame = frame_from_normal(nrm);
        cs = rc.rotation_cos;
        sn = rc.rotation_sin;
        origin = rc.position + params.origin_offset * nrm;
        frame_x[lid] = vec4<f32>(frame.x, cs);
        frame_y[lid] = vec4<f32>(frame.y, sn);
        frame_z[lid] = frame.z;
        origins[lid] = origin;
    }
    firsts[lid] = first;
    atomicStore(&blocked_rays[lid], 0u);
    if lid == 0u {
        atomicStore(&group_cut_short, 0u);
    }
    let tmax = params.tmax;
    let first_instance = instances[0];
    for (var base = 0u; base < params.rays_per_invocation; base += AO_CHUNK) {
        if lid == 0u {
            atomicStore(&queue_len, 0u);
        }
        workgroupBarrier();
        let end = min(first + base + AO_CHUNK, last);
        // The round's rays that meet a sphere as bits, then queued with one atomic add per
        // invocation (lavapipe runs a workgroup atomic lane by lane).
        var mask = 0u;
        for (var r = first + base; r < end; r++) {
            if meets_any_sphere(origin, ao_dir(frame, cs, sn, r), tmax, first_instance) {
                mask |= 1u << (r - first - base);
            }
        }
        if mask != 0u {
            var slot = atomicAdd(&queue_len, countOneBits(mask));
            var left = mask;
            while left != 0u {
                queue[slot] = lid * AO_CHUNK + firstTrailingBit(left);
                slot++;
                left &= left - 1u;
            }
        }
        workgroupBarrier();
        let queued = atomicLoad(&queue_len);
        for (var q = lid; q < queued; q += AO_GROUP) {
            let e = queue[q];
            let owner = e / AO_CHUNK;
            let r = firsts[owner] + base + e % AO_CHUNK;
            let origin = origins[owner];
            let dir = world_dir(owner, r);
            // The first instance comes from registers (read once per invocation): lavapipe
            // reads a 144-byte record lane by lane.
            var blocked = instance_occludes(first_instance, origin, dir, 0.0, tmax, SELECTION, field_params.intra_bias, field_params.intra_auto != 0u);
            // A second inlined lookup, even never run, slows lavapipe's queue loop by a third
            // (register pressure): one-instance fields compile without it.
            if !SINGLE_INSTANCE {
                for (var k = 1u; k < field_params.instance_count && !blocked; k++) {
                    blocked = instance_occludes(instances[k], origin, dir, 0.0, tmax, SELECTION, field_params.intra_bias, field_params.intra_auto != 0u);
                }
            }
            if blocked {
                atomicAdd(&blocked_rays[owner], 1u);
            }
        }
        workgroupBarrier();
    }
    // Queue entries are answered by any invocation of the group: one whose loops were cut
    // short spoils its neighbours' counts, so the whole group reports it.
    if !loops_completed(params.completion_trips) {
        atomicStore(&group_cut_short, 1u);
    }
    workgroupBarrier();
    if in_range {
        let free = (last - first) - atomicLoad(&blocked_rays[lid]);
        out[i] = select(free, CUT_SHORT, atomicLoad(&group_cut_short) != 0u);
    }
}

// Probe i: unit point u = receivers[i].position and model direction receivers[i].normal on the
// field of instance 0; writes (nearest map, texel, nearest sample bits, interpolated bits).
@compute @workgroup_size(64)
fn probe_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    if i >= params.point_count {
        return;
    }
    let inst = instances[0];
    let u = receivers[i].position;
    let dir = receivers[i].normal;
    let pbase = inst.point_base;
    let m = lookup_nearest(inst, u);
    let local = frame_to_local(frame_from_normal(-sphere_point(pbase, m)), dir);
    let t = lookup_texel(inst, local);
    out[4u * i] = m;
    out[4u * i + 1u] = t;
    out[4u * i + 2u] = bitcast<u32>(field_sample(inst, u, dir, SELECT_NEAREST));
    out[4u * i + 3u] = bitcast<u32>(field_sample(inst, u, dir, SELECT_INTERPOLATED));
}
