// The integrand layer's header (src/gpu/integrand.rs), group 0 of every kernel: the parameter
// header, the receivers (shaders/receiver.wgsl) and the output words at bindings 0-2, then the
// integrand's own inputs from binding 3 (FIRST_OWN_BINDING). The visibility is group 1 (its own
// header and data; src/gpu/visibility.rs): it defines `occluded` and, where it answers closest
// hits, `surface_hit`. The direct estimators (SDF cones, AO fields) share this group too.

// Mirrors `IntegrandParamsGpu` (src/gpu/integrand.rs), 48 bytes.
struct Params {
    // Receiver points (ray queries: rays) in this dispatch.
    point_count: u32,
    // Rays per point (AO: the base directions in `dirs`; shadows: the cone samples in
    // `samples` per light; reflections: 1 for the mirror, k^2 for a Phong lobe; cones: cones).
    rays_per_point: u32,
    // Invocations per row of the dispatch grid (i = gid.x + gid.y * row_stride).
    row_stride: u32,
    // Rays one invocation traces.
    rays_per_invocation: u32,
    // Invocations per point.
    invocations_per_point: u32,
    // Trips of the completion loop (loop_budget.wgsl).
    completion_trips: u32,
    // Ray origin offset along the normal.
    origin_offset: f32,
    // The rays' far end, where an integrand's rays share one (AO, cones; shadows and
    // reflections compute each ray's own).
    tmax: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    _pad3: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read_write> out: array<u32>;

// Invocation `gid`'s run of a point's rays (a point's rays are spread over
// `invocations_per_point` invocations): its index `i`, its point, and its rays [first, last)
// of the point's `rays`; `ok` is false past the last point.
struct Run {
    ok: bool,
    i: u32,
    point: u32,
    first: u32,
    last: u32,
}

fn run_of(gid: vec3<u32>, rays: u32) -> Run {
    let i = gid.x + gid.y * params.row_stride;
    let per_point = params.invocations_per_point;
    let first = (i % per_point) * params.rays_per_invocation;
    let last = min(first + params.rays_per_invocation, rays);
    return Run(i < params.point_count * per_point, i, i / per_point, first, last);
}

// A visibility's closest hit (`surface_hit`): hit, its distance along the ray and the
// unoriented unit normal there.
struct SurfaceHit {
    hit: bool,
    t: f32,
    normal: vec3<f32>,
}
