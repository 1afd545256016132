// The integrand layer's header (src/gpu/integrand.rs), group 0 of every kernel: the parameter
// header, the receivers (shaders/receiver.wgsl) and the output words at bindings 0-2, then the
// integrand's own inputs from binding 3 (FIRST_OWN_BINDING). The visibility is group 1 (its own
// header and data; src/gpu/visibility.rs): it defines `occluded` and, where it answers closest
// hits, `surface_hit`. The direct estimators (SDF cones, AO fields) share this group too.

// Mirrors `IntegrandParamsGpu` (src/gpu/integrand.rs), 48 bytes.
struct Params {
    // Receiver points (ray queries: rays) in this dispatch.
    point_count: u32,
    // Rays per point (AO: the base directions in `dirs`; shadows: per light, the cone samples
    // in `samples`; reflections: 1 for the mirror, k^2 for a Phong lobe; cones: cones).
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
    // AO and cones: the largest hit distance.
    tmax: f32,
    // Shadows: the lights.
    light_count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read_write> out: array<u32>;

// A visibility's closest hit (`surface_hit`): hit, its distance along the ray and the
// unoriented unit normal there.
struct SurfaceHit {
    hit: bool,
    t: f32,
    normal: vec3<f32>,
}
