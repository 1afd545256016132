// Vertex ambient occlusion, the integrand (Gaitatzes et al., WSCG 2008 / WSCG 2010), written
// once against any visibility's `occluded` (src/gpu/visibility.rs): each invocation takes one
// receiver point and a run of its k^2 stratified cosine rays (the host's ray set: base
// directions in `dirs`, the point's rotation in the receiver record), tests each from the
// offset origin up to `params.tmax`, and writes the number of free rays; the host adds up a
// point's runs. An invocation whose loops the driver cut short writes CUT_SHORT instead
// (shaders/loop_budget.wgsl).

@group(0) @binding(3) var<storage, read> dirs: array<vec4<f32>>;

// Ray r of a point with frame `frame` and rotation (cs, sn), in the world.
fn ao_dir(frame: Frame, cs: f32, sn: f32, r: u32) -> vec3<f32> {
    let b = dirs[r].xyz;
    let local = vec3<f32>(cs * b.x - sn * b.y, sn * b.x + cs * b.y, b.z);
    return frame_to_world(frame, local);
}

@compute @workgroup_size(64)
fn ao_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let run = run_of(gid, params.rays_per_point);
    if !run.ok {
        return;
    }
    let rc = receivers[run.point];
    let nrm = rc.normal;
    let frame = frame_from_normal(nrm);
    let origin = rc.position + params.origin_offset * nrm;
    var free = 0u;
    for (var r = run.first; r < run.last; r++) {
        if !occluded(origin, ao_dir(frame, rc.rotation_cos, rc.rotation_sin, r), 0.0, params.tmax) {
            free += 1u;
        }
    }
    out[run.i] = select(CUT_SHORT, free, loops_completed(params.completion_trips));
}
