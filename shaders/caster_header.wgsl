// The header (group 1, binding 0) of every ray-casting visibility: the CWBVH
// (shaders/bvh.wgsl), the two levels (shaders/two_level.wgsl), ray queries
// (shaders/ray_query.wgsl). Mirrors `CasterHeaderGpu` (src/gpu/tracer.rs), 16 bytes.
struct CasterHeader {
    // Nodes of the BVH walked first: the world CWBVH's, the top level's (0: nothing to hit).
    node_count: u32,
    // Instances placed (the two levels, ray queries).
    instance_count: u32,
    _pad0: u32,
    _pad1: u32,
}
