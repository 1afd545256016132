// What every field kernel shares (src/gpu/field_kernel.rs): the parameter header, the receivers
// and the output words, bindings 0-2 of the kernel's own group; a kernel's own inputs follow
// from binding 3 (FIRST_OWN_BINDING). `tables`, `mesh`, `instances` and the stored distances are
// the field group's (src/gpu/field_binding.rs). The per-object peers' kernels (SDF, AO fields)
// share this header and bind everything of theirs in group 0.

// Mirrors `KernelParamsGpu` (src/gpu/field_kernel.rs), 64 bytes.
struct Params {
    // Receiver points in this dispatch.
    point_count: u32,
    // Rays per point (AO: the base directions in `dirs`; shadows: per light, the cone samples
    // in `samples`; reflections: 1 for the mirror, k^2 for a Phong lobe).
    rays_per_point: u32,
    // Field instances.
    instance_count: u32,
    // Invocations per row of the dispatch grid (i = gid.x + gid.y * row_stride).
    row_stride: u32,
    // Selection (SELECT_NEAREST, SELECT_INTERPOLATED); the AO kernels read the pipeline's
    // constant AO_SELECTION, which the host sets to the same.
    selection: u32,
    // Rays one invocation traces.
    rays_per_invocation: u32,
    // Invocations per point.
    invocations_per_point: u32,
    // Trips of the completion loop (loop_budget.wgsl).
    completion_trips: u32,
    // Ray origin offset along the normal.
    origin_offset: f32,
    // Intra-object bias: a fraction of 2R, or the scale of the field's own tolerance.
    intra_bias: f32,
    // 1 when `intra_bias` scales the field's own tolerance (`IntraBias::Auto`), else 0.
    intra_auto: u32,
    // AO: the largest hit distance.
    tmax: f32,
    // Shadows: the lights.
    light_count: u32,
    // SDF kernels: steps per ray, cone and volume (`SdfTrace::max_steps`).
    max_steps: u32,
    // SDF cone kernels: a cone's least step, a share of its radius (`ConeTrace::step`).
    cone_step: f32,
    // SDF cone AO: tan of the cones' common half-angle (`ConeSet::tan_half`).
    cone_tan: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> receivers: array<Receiver>;
@group(0) @binding(2) var<storage, read_write> out: array<u32>;
