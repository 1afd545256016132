// The modern peers of the 2005 relief search in compute shaders, one invocation per segment
// E → X through the prism, operation for operation as `src/relief/peers/` (f32): the exact
// cell walk (`cellwalk::cast`), maximum mipmaps (Tevs, Ihrke, Seidel, I3D 2008;
// `MaxMip::cast`) and cone / relaxed cone stepping (Dummer 2006; Policarpo and Oliveira,
// GPU Gems 3, 2007; `cone::cast`). Fetches are counted as there: one per bilinear height
// sample, per max-mip or cone texel, per gather of a cell's four texels.
//
// Deviation from the papers: compute shaders over host-clipped segments reading storage
// buffers with the CPU's own formulas (not texture units), so GPU and CPU agree ray by ray.

// Mirrors `PeersParamsGpu` (src/gpu/relief_peers.rs), 112 bytes.
struct PeersParams {
    // Map width and height (texels).
    size: vec2<u32>,
    // Rays in this dispatch.
    count: u32,
    // Invocations per row of the dispatch grid (ray = gid.x + gid.y * stride).
    stride: u32,
    // Entries a side of max-mip level 0.
    mip_size: u32,
    // Index of the max mip's root level.
    mip_top: u32,
    // Cone steps.
    steps: u32,
    // Bisection steps (relaxed cones).
    bisections: u32,
    // 1: relaxed cones (bisect a step that lands below), 0: conservative.
    relaxed: u32,
    // Trips of the completion loop (loop_budget.wgsl).
    trips: u32,
    _pad0: u32,
    _pad1: u32,
    // Offset of max-mip level l in `mips`: offsets[l / 4][l % 4].
    offsets: array<vec4<u32>, 4>,
}

@group(0) @binding(0) var<uniform> params: PeersParams;
@group(0) @binding(1) var<storage, read> heights: array<f32>;
// Max-mip levels 0 .. mip_top, concatenated row-major.
@group(0) @binding(2) var<storage, read> mips: array<f32>;
// Cone ratios per texel (conservative or relaxed, as the host binds).
@group(0) @binding(3) var<storage, read> cones: array<f32>;
// Two per ray: E (xyz) and X (xyz).
@group(0) @binding(4) var<storage, read> segments: array<vec4<f32>>;
// Per ray: the hit λ's bits (MISS for none) and the fetches (CUT_SHORT: loop_budget.wgsl).
@group(0) @binding(5) var<storage, read_write> results: array<vec2<u32>>;

const MISS: u32 = 0xffffffffu;
const HUGE: f32 = 3.0e38;
// Cell answers of `solve_cell`.
const CLEAR: u32 = 0u;
const HIT: u32 = 1u;
const STARTS_BELOW: u32 = 2u;

var<private> fetches: u32;
// Ray in grid coordinates (`GridRay`).
var<private> ro: vec3<f32>;
var<private> rdir: vec3<f32>;
var<private> rlen: f32;
var<private> rr: vec3<f32>;
// λ of a cell's hit.
var<private> cell_hit: f32;

// `texel` and `sample_map`: shaders/height_map.wgsl.

fn gather(i: i32, j: i32) -> vec4<f32> {
    return vec4<f32>(texel(i, j), texel(i + 1, j), texel(i, j + 1), texel(i + 1, j + 1));
}

// `GridRay::new`: false where the segment has no length.
fn grid_ray(e: vec3<f32>, x: vec3<f32>) -> bool {
    let dx = x - e;
    rlen = sqrt(dx.x * dx.x + dx.y * dx.y + dx.z * dx.z);
    if !(rlen > 0.0) || rlen > HUGE {
        return false;
    }
    let w = f32(params.size.x);
    let h = f32(params.size.y);
    rr = dx / rlen;
    ro = vec3<f32>(e.x * w - 0.5, e.y * h - 0.5, e.z);
    rdir = vec3<f32>(rr.x * w, rr.y * h, rr.z);
    return true;
}

fn slab_exit(lo: f32, hi: f32, o: f32, k: f32) -> f32 {
    if k > 0.0 {
        return (hi - o) / k;
    } else if k < 0.0 {
        return (lo - o) / k;
    }
    return HUGE;
}

fn ray_z(l: f32) -> f32 {
    return ro.z + l * rdir.z;
}

// `solve_cell`: CLEAR, HIT (λ in `cell_hit`) or STARTS_BELOW.
fn solve_cell(i: i32, j: i32, c: vec4<f32>, lo: f32, hi: f32) -> u32 {
    let b = rdir.x;
    let e = rdir.y;
    let fx0 = clamp(ro.x + lo * b - f32(i), 0.0, 1.0);
    let fy0 = clamp(ro.y + lo * e - f32(j), 0.0, 1.0);
    let z0 = ray_z(lo);
    let p = c.y - c.x;
    let q = c.z - c.x;
    let k = c.x - c.y - c.z + c.w;
    let m0 = c.x + p * fx0 + q * fy0 + k * fx0 * fy0;
    let qc = z0 - m0;
    if qc < 0.0 {
        return STARTS_BELOW;
    }
    if qc == 0.0 {
        cell_hit = lo;
        return HIT;
    }
    let qa = -k * b * e;
    let qb = rdir.z - (p * b + q * e + k * (fx0 * e + b * fy0));
    let span = hi - lo;
    let end = (qa * span + qb) * span + qc;
    var t = HUGE;
    if qa == 0.0 {
        if qb < 0.0 {
            t = -qc / qb;
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let sq = sqrt(disc);
            var s = -0.5 * (qb - sq);
            if qb >= 0.0 {
                s = -0.5 * (qb + sq);
            }
            let r1 = s / qa;
            var r2 = HUGE;
            if s != 0.0 {
                r2 = qc / s;
            }
            if r1 >= 0.0 {
                t = min(t, r1);
            }
            if r2 >= 0.0 {
                t = min(t, r2);
            }
        }
    }
    if end <= 0.0 {
        cell_hit = lo + min(t, span);
        return HIT;
    } else if t <= span {
        cell_hit = lo + t;
        return HIT;
    }
    return CLEAR;
}

fn step_of(k: f32) -> i32 {
    if k > 0.0 {
        return 1;
    } else if k < 0.0 {
        return -1;
    }
    return 0;
}

fn finish(ray: u32, hit: u32) {
    results[ray] = vec2<u32>(hit, select(CUT_SHORT, fetches, loops_completed(params.trips)));
}

fn load(ray: u32) -> bool {
    fetches = 0u;
    return grid_ray(segments[2u * ray].xyz, segments[2u * ray + 1u].xyz);
}

@compute @workgroup_size(64)
fn cellwalk_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let ray = gid.x + gid.y * params.stride;
    if ray >= params.count {
        return;
    }
    if !load(ray) {
        finish(ray, MISS);
        return;
    }
    finish(ray, cell_walk());
}

// `cellwalk::cast`.
fn cell_walk() -> u32 {
    let w = i32(params.size.x);
    let h = i32(params.size.y);
    var i = clamp(i32(floor(ro.x)), -1, w - 1);
    var j = clamp(i32(floor(ro.y)), -1, h - 1);
    let si = step_of(rdir.x);
    let sj = step_of(rdir.y);
    var lam = 0.0;
    loop {
        let eu = slab_exit(f32(i), f32(i + 1), ro.x, rdir.x);
        let ev = slab_exit(f32(j), f32(j + 1), ro.y, rdir.y);
        let out = min(min(eu, ev), rlen);
        fetches += 1u;
        let a = solve_cell(i, j, gather(i, j), lam, out);
        if a == HIT {
            return bitcast<u32>(cell_hit);
        }
        if a == STARTS_BELOW {
            if lam == 0.0 {
                return MISS;
            }
            return bitcast<u32>(lam);
        }
        if out >= rlen {
            return MISS;
        }
        if eu <= ev {
            i += si;
        }
        if ev <= eu {
            j += sj;
        }
        lam = out;
    }
    return MISS;
}

fn mip_at(level: u32, ni: i32, nj: i32) -> f32 {
    let offset = params.offsets[level / 4u][level % 4u];
    return mips[offset + u32(nj) * (params.mip_size >> level) + u32(ni)];
}

// `next_cell`.
fn next_cell(crossed: bool, c: i32, n: i32, s: i32, at: f32, k: f32) -> i32 {
    if crossed {
        if k > 0.0 {
            return (n + 1) * s;
        }
        return n * s - 1;
    } else if s == 1 {
        return c;
    }
    return clamp(i32(floor(at)) + 1, n * s, (n + 1) * s - 1);
}

@compute @workgroup_size(64)
fn maxmip_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let ray = gid.x + gid.y * params.stride;
    if ray >= params.count {
        return;
    }
    if !load(ray) {
        finish(ray, MISS);
        return;
    }
    finish(ray, max_mip());
}

// `MaxMip::cast`.
fn max_mip() -> u32 {
    let top = params.mip_top;
    let last = i32(params.mip_size) - 1;
    var ci = clamp(i32(floor(ro.x)) + 1, 0, i32(params.size.x));
    var cj = clamp(i32(floor(ro.y)) + 1, 0, i32(params.size.y));
    var level = top;
    var lam = 0.0;
    loop {
        let s = 1 << level;
        let ni = ci >> level;
        let nj = cj >> level;
        let eu = slab_exit(f32(ni * s - 1), f32((ni + 1) * s - 1), ro.x, rdir.x);
        let ev = slab_exit(f32(nj * s - 1), f32((nj + 1) * s - 1), ro.y, rdir.y);
        let out = min(min(eu, ev), rlen);
        let zmin = min(ray_z(lam), ray_z(out));
        fetches += 1u;
        if level == 0u {
            let i = ci - 1;
            let j = cj - 1;
            let c = gather(i, j);
            if zmin <= max(max(c.x, c.y), max(c.z, c.w)) {
                let a = solve_cell(i, j, c, lam, out);
                if a == HIT {
                    return bitcast<u32>(cell_hit);
                }
                if a == STARTS_BELOW {
                    if lam == 0.0 {
                        return MISS;
                    }
                    return bitcast<u32>(lam);
                }
            }
        } else if zmin <= mip_at(level, ni, nj) {
            level -= 1u;
            continue;
        }
        if out >= rlen {
            return MISS;
        }
        let nci = next_cell(eu <= ev, ci, ni, s, ro.x + out * rdir.x, rdir.x);
        let ncj = next_cell(ev <= eu, cj, nj, s, ro.y + out * rdir.y, rdir.y);
        ci = clamp(nci, 0, last);
        cj = clamp(ncj, 0, last);
        lam = out;
        level = min(level + 1u, top);
    }
    return MISS;
}

@compute @workgroup_size(64)
fn cone_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let ray = gid.x + gid.y * params.stride;
    if ray >= params.count {
        return;
    }
    fetches = 0u;
    finish(ray, cone_walk(segments[2u * ray].xyz, segments[2u * ray + 1u].xyz));
}

// `cone::cast`.
fn cone_walk(e: vec3<f32>, x: vec3<f32>) -> u32 {
    let dx = x - e;
    let len = sqrt(dx.x * dx.x + dx.y * dx.y + dx.z * dx.z);
    if !(len > 0.0) || len > HUGE {
        return MISS;
    }
    let r = dx / len;
    let rho = sqrt(r.x * r.x + r.y * r.y);
    let w = i32(params.size.x);
    let h = i32(params.size.y);
    var lam = 0.0;
    var prev = 0.0;
    for (var k = 0u; k < params.steps; k++) {
        let p = e + lam * r;
        fetches += 2u;
        let d = p.z - sample_map(p.xy);
        let i = clamp(i32(floor(p.x * f32(params.size.x))), 0, w - 1);
        let j = clamp(i32(floor(p.y * f32(params.size.y))), 0, h - 1);
        let c = cones[j * w + i];
        if d <= 0.0 {
            if lam == 0.0 {
                if d < 0.0 {
                    return MISS;
                }
                return 0u; // the bits of λ = 0
            }
            if params.relaxed == 0u {
                return bitcast<u32>(lam);
            }
            var la = prev;
            var lb = lam;
            for (var s = 0u; s < params.bisections; s++) {
                let mid = 0.5 * (la + lb);
                let pm = e + mid * r;
                fetches += 1u;
                if pm.z - sample_map(pm.xy) <= 0.0 {
                    lb = mid;
                } else {
                    la = mid;
                }
            }
            return bitcast<u32>(lb);
        }
        if lam >= len {
            return MISS;
        }
        let denom = rho - c * r.z;
        if denom <= 0.0 {
            return MISS;
        }
        prev = lam;
        lam = min(lam + c * d / denom, len);
    }
    if lam >= len {
        return MISS;
    }
    return bitcast<u32>(lam);
}
