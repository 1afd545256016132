// A receiver point of the integrands (group 0, binding 1; shaders/integrand.wgsl). Mirrors
// `ReceiverGpu` (src/gpu/rays.rs), 32 bytes.
struct Receiver {
    // Position (world space); the probe kernel's unit sphere position.
    position: vec3<f32>,
    // Cos of the point's rotation of the shared base directions about its normal.
    rotation_cos: f32,
    // Unit normal (world space); the probe kernel's model direction.
    normal: vec3<f32>,
    // Sin of the point's rotation.
    rotation_sin: f32,
}

@group(0) @binding(1) var<storage, read> receivers: array<Receiver>;
