// The 2005 relief caster (Kolb and Rezk-Salama, VMV 2005, §3.1–3.4) in a compute shader: one
// invocation per ray segment E → X through the prism, the same steps as `src/relief/cast.rs`
// (`intersect`, `skip`, `forward_skip`, `backward_skip`, `bisect`), read for read.
//
// Deviation from the paper: a compute shader over precomputed segments instead of a pixel shader
// rasterising the prism; the displacement map and the zones are storage buffers read with the
// CPU's own bilinear and nearest formulas (not texture units), so that GPU and CPU agree ray by
// ray.

// Mirrors `ReliefParamsGpu` (src/gpu/relief.rs), 64 bytes.
struct ReliefParams {
    // Map width and height (texels).
    size: vec2<u32>,
    // Rays in this dispatch.
    count: u32,
    // Invocations per row of the dispatch grid (ray = gid.x + gid.y * stride).
    stride: u32,
    // Linear-search samples per unit of segment length.
    samples_per_unit: f32,
    // Bisection steps after the linear search.
    bisections: u32,
    // Rounds of safety-zone skips (0: none).
    skips: u32,
    // Zone channels in use (entries of `deltas`).
    channels: u32,
    // Half-widths δ of the zone channels (texture units).
    deltas: vec4<f32>,
    // Trips of the completion loop (loop_budget.wgsl).
    trips: u32,
    // 1 / samples_per_unit, the lattice step, computed on the host as the CPU does.
    step: f32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: ReliefParams;
@group(0) @binding(1) var<storage, read> heights: array<f32>;
@group(0) @binding(2) var<storage, read> dilation: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> erosion: array<vec4<f32>>;
// Two per ray: E (xyz) and X (xyz).
@group(0) @binding(4) var<storage, read> segments: array<vec4<f32>>;
// Per ray: the hit λ's bits (MISS for none) and the texture fetches (CUT_SHORT when the
// driver's loop budget stopped the invocation: loop_budget.wgsl).
@group(0) @binding(5) var<storage, read_write> results: array<vec2<u32>>;

const MISS: u32 = 0xffffffffu;
// Stands for the CPU's infinity (WGSL leaves infinities undefined); any skip this long ends
// the ray, as infinity does there.
const HUGE: f32 = 3.0e38;

var<private> fetches: u32;

// `texel` and `sample_map`: shaders/height_map.wgsl.

fn dist(p: vec3<f32>) -> f32 {
    return p.z - sample_map(p.xy);
}

// The zone texel holding s (nearest sampling, `SafetyZones::at`).
fn zone_index(s: vec2<f32>) -> i32 {
    let w = i32(params.size.x);
    let h = i32(params.size.y);
    let i = clamp(i32(floor(s.x * f32(params.size.x))), 0, w - 1);
    let j = clamp(i32(floor(s.y * f32(params.size.y))), 0, h - 1);
    return j * w + i;
}

fn sideways(c: u32, norm: f32) -> f32 {
    if norm == 0.0 {
        return HUGE;
    }
    return params.deltas[c] / norm;
}

fn forward_skip(p: vec3<f32>, r: vec3<f32>, norm: f32) -> f32 {
    let dil = dilation[zone_index(p.xy)];
    var best = 0.0;
    for (var c = 0u; c < params.channels; c++) {
        if p.z <= dil[c] {
            continue;
        }
        var vertical = HUGE;
        if r.z < 0.0 {
            vertical = (dil[c] - p.z) / r.z;
        } else if r.z > 0.0 {
            vertical = (1.0 - p.z) / r.z;
        }
        best = max(best, min(vertical, sideways(c, norm)));
    }
    return best;
}

fn backward_skip(p: vec3<f32>, r: vec3<f32>, norm: f32) -> f32 {
    let k = zone_index(p.xy);
    let dil = dilation[k];
    let ero = erosion[k];
    var best = 0.0;
    for (var c = 0u; c < params.channels; c++) {
        var vertical = HUGE;
        if p.z > dil[c] {
            if r.z > 0.0 {
                vertical = (p.z - dil[c]) / r.z;
            } else if r.z < 0.0 {
                vertical = (1.0 - p.z) / -r.z;
            }
        } else if p.z < ero[c] {
            if r.z < 0.0 {
                vertical = (ero[c] - p.z) / -r.z;
            } else if r.z > 0.0 {
                vertical = p.z / r.z;
            }
        } else {
            continue;
        }
        best = max(best, min(vertical, sideways(c, norm)));
    }
    return best;
}

@compute @workgroup_size(64)
fn relief_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let ray = gid.x + gid.y * params.stride;
    if ray >= params.count {
        return;
    }
    let e = segments[2u * ray].xyz;
    let x = segments[2u * ray + 1u].xyz;
    let hit = cast_ray(e, x);
    results[ray] = vec2<u32>(hit, select(CUT_SHORT, fetches, loops_completed(params.trips)));
}

// The point λ of the segment, X itself at its end (`intersect`'s `at`).
fn point_at(e: vec3<f32>, x: vec3<f32>, r: vec3<f32>, len: f32, l: f32) -> vec3<f32> {
    if l >= len {
        return x;
    }
    return e + l * r;
}

// `intersect`: λ's bits, or MISS; the fetches are left in `fetches`. A hit is d ≤ 0.
fn cast_ray(e: vec3<f32>, x: vec3<f32>) -> u32 {
    let len = length(x - e);
    fetches = 1u;
    let de = dist(e);
    if de < 0.0 || !(len > 0.0) {
        return MISS;
    }
    if de <= 0.0 {
        // The bits of λ = 0.
        return 0u;
    }
    let r = (x - e) / len;
    // `skip`: rounds of forward and backward skips.
    let norm = max(abs(r.x), abs(r.y));
    var l1 = 0.0;
    var l2 = len;
    for (var round = 0u; round < params.skips; round++) {
        // The dilation forward, the dilation and the erosion backward.
        fetches += 3u;
        l1 += forward_skip(e + l1 * r, r, norm);
        l2 -= backward_skip(e + l2 * r, r, norm);
        if l1 > l2 {
            return MISS;
        }
    }
    let step = params.step;
    // The last lattice point λ_k = k·step at or before λ1.
    var k = u32(floor(l1 * params.samples_per_unit));
    if f32(k) * step > l1 {
        k -= 1u;
    }
    var la = 0.0;
    var da = de;
    if k > 0u {
        fetches += 1u;
        la = f32(k) * step;
        da = dist(point_at(e, x, r, len, la));
    }
    if da <= 0.0 {
        return bitcast<u32>(la);
    }
    loop {
        k += 1u;
        let lb = min(f32(k) * step, l2);
        let db = dist(point_at(e, x, r, len, lb));
        fetches += 1u;
        if db <= 0.0 {
            return bitcast<u32>(bisect(e, x, r, len, la, da, lb, db));
        }
        if lb >= l2 {
            return MISS;
        }
        la = lb;
        da = db;
    }
    return MISS;
}

// The paper's interpolating bisection, keeping the sign change da > 0 ≥ db (`bisect`).
fn bisect(
    e: vec3<f32>,
    x: vec3<f32>,
    r: vec3<f32>,
    len: f32,
    la0: f32,
    da0: f32,
    lb0: f32,
    db0: f32,
) -> f32 {
    var la = la0;
    var da = da0;
    var lb = lb0;
    var db = db0;
    var l = lb;
    for (var s = 0u; s < params.bisections; s++) {
        l = la + da / (da - db) * (lb - la);
        let dl = dist(point_at(e, x, r, len, l));
        fetches += 1u;
        if dl > 0.0 {
            la = l;
            da = dl;
        } else {
            lb = l;
            db = dl;
        }
    }
    return l;
}
