// The CPU's lookup tables on the GPU, read before the ring search and the concentric map:
// the owner table of `SpherePoints::nearest` (src/sampling/owner_grid.rs), the candidate slots
// of its cube grid (src/sampling/cube_grid.rs) and the texel table
// (src/sampling/texel_table.rs), u16 cells two to a word in the `mesh` buffer after the
// triangulations (src/gpu/field_data.rs, `lookup_tables`). A cell the CPU left open (MIXED)
// sends the query to the exact path, as on the CPU. `OWNER_TABLES` / `TEXEL_TABLES` are false
// when no instance has such a table, and the compiler drops the reads.
// Needs: `mesh`, `Instance`, `nearest_point`, `layout_to_texel`, `sphere_point`, `fixed_or`.

const TABLE_MIXED: u32 = 0xffffu;
const NO_CELL: u32 = 0xffffffffu;
// A candidate-grid cell with more than four candidates (first slot).
const CAND_OVERFLOW: u32 = 0xffffffffu;

// Word `w` of the mesh buffer.
fn mesh_word(w: u32) -> u32 {
    return mesh[w >> 2u][w & 3u];
}

// 16-bit half `h` of the mesh buffer (low half of a word first).
fn mesh_half(h: u32) -> u32 {
    return (mesh_word(h >> 1u) >> ((h & 1u) * 16u)) & 0xffffu;
}

// `OwnerGrid::cell`: the cube-map cell of `d` at g cells per face edge (face 2 axis + sign,
// then row j, column i), NO_CELL for zero, tiny (< 1e-30) and huge (>= 1e30, where the CPU
// stops at infinity; the lookup's directions are unit) largest components, and for NaN.
fn owner_cell(g: u32, d: vec3<f32>) -> u32 {
    let a = abs(d);
    let x_wins = a.x >= a.y && a.x >= a.z;
    let y_wins = !x_wins && a.y >= a.z;
    var axis = 2u;
    var da = d.z;
    var pb = d.x;
    var pc = d.y;
    if x_wins {
        axis = 0u;
        da = d.x;
        pb = d.y;
        pc = d.z;
    } else if y_wins {
        axis = 1u;
        da = d.y;
        pb = d.z;
        pc = d.x;
    }
    let half_g = 0.5 * f32(g);
    let gf = f32(g);
    let m = abs(da);
    let k = half_g / m;
    let fi = pb * k + half_g;
    let fj = pc * k + half_g;
    if !(m > 1e-30 && m < 1e30 && fi >= 0.0 && fi <= gf && fj >= 0.0 && fj <= gf) {
        return NO_CELL;
    }
    let i = min(u32(fi), g - 1u);
    let j = min(u32(fj), g - 1u);
    let f = 2u * axis + select(0u, 1u, da < 0.0);
    return (f * g + j) * g + i;
}

// The nearest map of unit `u` on `inst`'s field: the owner table's owner, or of its pair the
// larger f32 dot product (the CPU compares in f64), else the best of the candidate grid's
// cell, else the ring search.
fn lookup_nearest(inst: Instance, u: vec3<f32>) -> u32 {
    let pbase = inst.point_base;
    if OWNER_TABLES && inst.owner_grid != 0u {
        let cell = owner_cell(inst.owner_grid, u);
        if cell != NO_CELL {
            let o = mesh_half(inst.owner_base + cell);
            if o < inst.map_count {
                return o;
            }
            if o != TABLE_MIXED {
                let pq = mesh_word(inst.pair_base + (o - inst.map_count));
                let p = pq & 0xffffu;
                let q = pq >> 16u;
                return select(p, q, dot(u, sphere_point(pbase, q)) > dot(u, sphere_point(pbase, p)));
            }
        }
        // A MIXED cell: the candidate grid's four slots (`CubeGrid::nearest`; padding repeats
        // the first, which never wins a strict comparison), unless its cell has more.
        let cc = owner_cell(inst.cand_grid, u);
        if inst.cand_grid != 0u && cc != NO_CELL {
            let slots = mesh[inst.cand_base + cc];
            if slots.x != CAND_OVERFLOW {
                var best = slots.x;
                var best_dot = dot(u, sphere_point(pbase, slots.x));
                for (var k = 1u; k < 4u; k++) {
                    let x = dot(u, sphere_point(pbase, slots[k]));
                    if x > best_dot {
                        best = slots[k];
                        best_dot = x;
                    }
                }
                return best;
            }
        }
    }
    return nearest_point(u, fixed_or(FIXED_SPHERE, inst.sphere_kind), inst.ring_param, pbase);
}

// The texel of local direction `local` on `inst`'s maps: the texel table's cell
// (`TexelTable::cell`: z >= 0 and inside the table), else the layout's map.
fn lookup_texel(inst: Instance, local: vec3<f32>) -> u32 {
    if TEXEL_TABLES && inst.texel_grid != 0u {
        let g = inst.texel_grid;
        let half_g = 0.5 * f32(g);
        let gf = f32(g);
        let fx = (local.x + 1.0) * half_g;
        let fy = (local.y + 1.0) * half_g;
        if local.z >= 0.0 && fx >= 0.0 && fx < gf && fy >= 0.0 && fy < gf {
            let t = mesh_half(inst.texel_base + u32(fy) * g + u32(fx));
            if t != TABLE_MIXED {
                return t;
            }
        }
    }
    return layout_to_texel(fixed_or(FIXED_LAYOUT, inst.layout_kind), inst.resolution, local);
}
