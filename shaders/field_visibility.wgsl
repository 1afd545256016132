// The field visibility (src/gpu/field_kernel.rs; Gaitatzes et al., WSCG 2008 / WSCG 2010):
// its header and `occluded`, over the field group's instances (src/gpu/field_binding.rs) with
// the lookup of shaders/field_lookup.wgsl. `SELECTION` is a pipeline constant the host sets
// from the lookup options (so that the compiler drops the other selection's code, which
// llvmpipe would run masked for every ray); `surface_hit` is in shaders/field_surface.wgsl,
// compiled where the normal fields are bound; `occluded` and `surface_hit` are these loops over
// every instance or the walks of the instances' own top level (shaders/field_top_level.wgsl).

// Mirrors `FieldParamsGpu` (src/gpu/field_kernel.rs), 16 bytes.
struct FieldParams {
    // Field instances.
    instance_count: u32,
    // Intra-object bias: a fraction of 2R, or the scale of the field's own tolerance.
    intra_bias: f32,
    // 1 when `intra_bias` scales the field's own tolerance (`IntraBias::Auto`), else 0.
    intra_auto: u32,
    _pad: u32,
}

@group(1) @binding(0) var<uniform> field_params: FieldParams;

// Whether any instance blocks origin + t dir, t in [tmin, tmax] (`FieldScene::occluded`; the
// instances in index order, stopping at the first that occludes): the visibility's `occluded`
// where the instances are not walked through their own top level
// (shaders/field_top_level.wgsl; the choice is made by src/gpu/field_binding.rs).
fn occluded_every_sphere(origin: vec3<f32>, dir: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    for (var k = 0u; k < field_params.instance_count; k++) {
        if instance_occludes(instances[k], origin, dir, tmin, tmax, SELECTION, field_params.intra_bias, field_params.intra_auto != 0u) {
            return true;
        }
    }
    return false;
}
