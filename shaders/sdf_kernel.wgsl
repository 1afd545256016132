// The SDF's direct estimators (src/gpu/sdf_kernel.rs), over the volumes of
// shaders/sdf_volume.wgsl (its AO by sphere tracing is the AO integrand, shaders/ao.wgsl, on the
// SDF visibility's `occluded`):
// - `cone_ao_main`: cone-traced AO (`SdfScene::cone_ao`): each invocation takes one point and a
//   run of the cones (axes in `sdf_dirs`, in the normal's frame) and writes each cone's
//   visibility; the host takes the cosine-weighted mean in the CPU's order.
// - `cone_shadow_main`: one cone per spherical light (`SdfScene::cone_light_fraction`; lights
//   in `sdf_dirs` as centre and radius): each invocation writes its lights' cone visibilities;
//   the host weighs them by the lights' unshadowed irradiance, computed on the host.
// An invocation whose loops the driver cut short writes CUT_SHORT instead (in every word it
// owns; shaders/loop_budget.wgsl).

@group(0) @binding(3) var<storage, read> sdf_dirs: array<vec4<f32>>;

// Writes the run's words (src/gpu/loop_budget.rs, `ray_words`): word i·rays_per_invocation + j
// is ray first + j of this invocation's point.
fn write_cut_short(i: u32, n: u32) {
    for (var j = 0u; j < n; j++) {
        out[i * params.rays_per_invocation + j] = CUT_SHORT;
    }
}

@compute @workgroup_size(64)
fn cone_ao_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let run = run_of(gid, params.rays_per_point);
    if !run.ok {
        return;
    }
    let rc = receivers[run.point];
    let nrm = rc.normal;
    let frame = frame_from_normal(nrm);
    let origin = rc.position + params.origin_offset * nrm;
    for (var r = run.first; r < run.last; r++) {
        let axis = normalize_exact(frame_to_world(frame, sdf_dirs[r].xyz));
        let v = cone_scene(origin, axis, sdf.cone_tan, params.tmax);
        out[run.i * params.rays_per_invocation + r - run.first] = bitcast<u32>(v);
    }
    if !loops_completed(params.completion_trips) {
        write_cut_short(run.i, run.last - run.first);
    }
}

@compute @workgroup_size(64)
fn cone_shadow_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let run = run_of(gid, params.rays_per_point);
    if !run.ok {
        return;
    }
    let rc = receivers[run.point];
    let origin = rc.position + params.origin_offset * rc.normal;
    for (var r = run.first; r < run.last; r++) {
        // `LightCone::new`'s cone; a light the host does not count (the point inside it or
        // at its centre) reads 1, unused.
        let light = sdf_dirs[r];
        let to = light.xyz - origin;
        let d2 = dot(to, to);
        let r2 = light.w * light.w;
        var v = 1.0;
        if !(d2 <= r2 || d2 == 0.0) {
            let d = sqrt(d2);
            let axis = to / d;
            var tan = 0.0;
            var far = d;
            if light.w != 0.0 {
                tan = light.w / sqrt(d2 - r2);
                far = d - light.w;
            }
            v = cone_scene(origin, axis, tan, far);
        }
        out[run.i * params.rays_per_invocation + r - run.first] = bitcast<u32>(v);
    }
    if !loops_completed(params.completion_trips) {
        write_cut_short(run.i, run.last - run.first);
    }
}
