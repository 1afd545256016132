//! A cube-map grid over the unit sphere with conservative per-cell candidate lists: exact
//! nearest-point and point-location queries in a handful of dot products, for any point set.
//!
//! The sphere is split into the six faces of the cube, face (axis a, sign s) holding the
//! directions whose largest component is s·d_a; a direction maps to face coordinates
//! (u, v) = (d_b, d_c) / |d_a| ∈ [−1, 1]² (b, c the other axes in cyclic order), and each face
//! into g × g cells uniform in (u, v). Great circles are straight lines in (u, v), so the cell is
//! the cone over a planar square X(u, v) = s·e_a + u·e_b + v·e_c.
//!
//! Cells are enlarged by [`DELTA`] in (u, v) on every side; the f32 cell computation of
//! [`CubeGrid::cell`] is off by less than 1e-6 in (u, v), so every direction lies in the
//! enlarged version of the cell it is assigned to.
//!
//! **Points.** For enlarged cell C with unit centre direction c and angular radius ρ (the largest
//! angle from c to a corner, which bounds the whole cell: the directions within an angle of c form
//! a convex cone, which holds the square once it holds its corners), every d ∈ C has its nearest
//! point within angle(c, q) + 2ρ of c for any point q (triangle inequality; q = the analytic
//! nearest point of c makes this tight). Those points are found by a breadth-first search over
//! the triangulation (below), then pruned: p is dropped when another candidate q beats it by a
//! margin over the whole cell. The sign of X·w with w = p − q is linear in (u, v), so its
//! maximum over the square is at a corner: when X̂ₖ·(p − q) < −[`TAU`] at the four normalised
//! corners, d·q − d·p > TAU/√3 for every d ∈ C, far above f64 rounding, so p is never the
//! brute-force answer. Lists are kept in ascending index order and scanned with a strict
//! comparison of f64 dot products, so the answer equals the brute-force search's exactly,
//! including its choice among exact ties (the first index).
//!
//! **Triangles.** Each cell also lists the triangles of the set's triangulation that may meet it:
//! those whose bounding cap meets the cell's cap (c, ρ), minus those separated from the cell by
//! one of their edge planes or by one of the cell's four side planes. The triangle containing a
//! direction of the cell therefore is in the list; lists are ordered by how much of the cell each
//! triangle covers (on a 3 × 3 sub-grid), so the first test usually succeeds.
//!
//! **Search.** Triangles whose closed spherical triangle meets a spherically convex region with
//! interior (a cap) are connected through shared edges (a path inside the region crosses edges
//! away from vertices), and every one of them passes the conservative bounding-cap test, so a
//! breadth-first search from one such triangle through shared edges, expanding only triangles
//! that pass the test, reaches all of them. Each point within the cap belongs to one of them.

use super::mesh::{det, INSIDE_TOL};
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// Enlargement of every cell in face coordinates: ten times the f32 rounding of the cell
/// computation (< 1e-6).
const DELTA: f64 = 1e-5;
/// Dominance margin of the point pruning (in dot product at the normalised corners).
const TAU: f64 = 1e-9;
/// Candidate points held inline per cell (a cell holds 1–4 points for the papers' sets).
const SLOTS: usize = 4;
/// Marks a cell with more than [`SLOTS`] candidates.
const OVERFLOW: u32 = u32::MAX;
/// Angle between unit vectors, accurate for small and large angles.
#[inline]
fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// (axis a, sign s, axis b, axis c) of face `f` = 2a + (s < 0).
fn face_axes(f: usize) -> (usize, f64, usize, usize) {
    let a = f / 2;
    let s = if f.is_multiple_of(2) { 1.0 } else { -1.0 };
    (a, s, (a + 1) % 3, (a + 2) % 3)
}

/// s·e_a + u·e_b + v·e_c.
fn face_point(f: usize, u: f64, v: f64) -> DVec3 {
    let (a, s, b, c) = face_axes(f);
    let mut x = [0.0; 3];
    x[a] = s;
    x[b] = u;
    x[c] = v;
    DVec3::from_array(x)
}

/// One enlarged cell: unit corners (counter-clockwise in (u, v)), unit centre and angular radius.
struct CellGeometry {
    corners: [DVec3; 4],
    centre: DVec3,
    radius: f64,
}

/// A cap: unit centre and angular radius, with the radius' cosine and sine.
#[derive(Clone, Copy)]
struct Cap {
    centre: DVec3,
    radius: f64,
    cos: f64,
    sin: f64,
}

/// Slack of the cosine comparisons below (far above their rounding, far below any spacing).
const COS_SLACK: f64 = 1e-12;

impl Cap {
    fn new(centre: DVec3, radius: f64) -> Cap {
        Cap {
            centre,
            radius,
            cos: radius.cos(),
            sin: radius.sin(),
        }
    }

    /// Whether the caps may meet: angle between centres ≤ r₁ + r₂, in cosines.
    #[inline]
    fn meets(&self, other: &Cap) -> bool {
        self.radius + other.radius >= std::f64::consts::PI
            || self.centre.dot(other.centre)
                >= self.cos * other.cos - self.sin * other.sin - COS_SLACK
    }

    /// Whether unit `p` may lie in the cap.
    #[inline]
    fn holds(&self, p: DVec3) -> bool {
        self.radius >= std::f64::consts::PI || self.centre.dot(p) >= self.cos - COS_SLACK
    }
}

/// The grid: per cell, candidate points and candidate triangles (compressed rows).
#[derive(Clone, Debug)]
pub(crate) struct CubeGrid {
    g: u32,
    half_g: f32,
    /// Per cell: its first [`SLOTS`] candidates, padded with repeats of the first, or
    /// [`OVERFLOW`] when it has more.
    slots: Vec<[u32; SLOTS]>,
    point_start: Vec<u32>,
    point_items: Vec<u32>,
    tri_start: Vec<u32>,
    tri_items: Vec<u32>,
}

/// What every cell's search reads: the points in f64, the triangles' bounding caps, their
/// edge neighbours and the vertex → triangle incidence (compressed rows).
struct Shared<'a> {
    p: Vec<DVec3>,
    tris: &'a [[u32; 3]],
    caps: Vec<Cap>,
    adj: Vec<[u32; 3]>,
    inc_start: Vec<u32>,
    inc: Vec<u32>,
}

/// One thread's search scratch: visit stamps (a fresh stamp per search) and buffers.
struct Scratch {
    stamp: u32,
    tri_stamp: Vec<u32>,
    point_stamp: Vec<u32>,
    queue: Vec<u32>,
    found: Vec<u32>,
    cand: Vec<u32>,
    /// The candidates left after pruning.
    kept: Vec<u32>,
    /// Per candidate: its dot products with the cell's four unit corners.
    corner_dots: Vec<[f64; 4]>,
    keep: Vec<(std::cmp::Reverse<usize>, u32)>,
}

/// The lists of one row of cells (g cells), concatenated, with each cell's list length.
#[derive(Default)]
struct RowLists {
    point_len: Vec<u32>,
    points: Vec<u32>,
    tri_len: Vec<u32>,
    tris: Vec<u32>,
}

impl<'a> Shared<'a> {
    fn new(points: &[Vec3], tris: &'a [[u32; 3]]) -> Self {
        let p: Vec<DVec3> = points.iter().map(|v| v.as_dvec3()).collect();
        let caps = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| p[i as usize]);
                match (a + b + c).try_normalize() {
                    Some(m) => {
                        let r = angle(m, a).max(angle(m, b)).max(angle(m, c));
                        // A cap wider than a hemisphere is not spherically convex: take it all.
                        let r = if r < 0.49 * std::f64::consts::PI {
                            r + 1e-9
                        } else {
                            std::f64::consts::TAU
                        };
                        Cap::new(m, r)
                    }
                    None => Cap::new(DVec3::Z, std::f64::consts::TAU),
                }
            })
            .collect();
        let mut inc_start = vec![0u32; p.len() + 1];
        for t in tris {
            for &v in t {
                inc_start[v as usize + 1] += 1;
            }
        }
        for i in 0..p.len() {
            inc_start[i + 1] += inc_start[i];
        }
        let mut fill = inc_start.clone();
        let mut inc = vec![0u32; inc_start[p.len()] as usize];
        for (ti, t) in tris.iter().enumerate() {
            for &v in t {
                inc[fill[v as usize] as usize] = ti as u32;
                fill[v as usize] += 1;
            }
        }
        // Edge neighbours: sort the undirected edges; each appears twice in a closed mesh
        // (a mesh with open edges leaves u32::MAX, which the search skips).
        let mut edges: Vec<(u32, u32, u32)> = tris
            .iter()
            .enumerate()
            .flat_map(|(t, v)| {
                (0..3).map(move |e| {
                    let (a, b) = (v[e], v[(e + 1) % 3]);
                    (a.min(b), a.max(b), t as u32)
                })
            })
            .collect();
        edges.sort_unstable();
        let mut adj = vec![[u32::MAX; 3]; tris.len()];
        for pair in edges.windows(2) {
            let ((a0, b0, t0), (a1, b1, t1)) = (pair[0], pair[1]);
            if (a0, b0) == (a1, b1) {
                for (t, o) in [(t0, t1), (t1, t0)] {
                    if let Some(slot) = adj[t as usize].iter_mut().find(|x| **x == u32::MAX) {
                        *slot = o;
                    }
                }
            }
        }
        Shared {
            p,
            tris,
            caps,
            adj,
            inc_start,
            inc,
        }
    }

    fn scratch(&self) -> Scratch {
        Scratch {
            stamp: 0,
            tri_stamp: vec![u32::MAX; self.tris.len()],
            point_stamp: vec![u32::MAX; self.p.len()],
            queue: Vec::new(),
            found: Vec::new(),
            cand: Vec::new(),
            kept: Vec::new(),
            corner_dots: Vec::new(),
            keep: Vec::new(),
        }
    }

    /// `row(scratch, f, j)` for every row j of cells of every face f of a g × g-per-face grid,
    /// in that order, rows in parallel (each thread with its own scratch).
    fn rows<T: Send>(&self, g: u32, row: impl Fn(&mut Scratch, usize, u32) -> T + Sync) -> Vec<T> {
        (0..6 * g)
            .into_par_iter()
            .map_init(|| self.scratch(), |s, r| row(s, (r / g) as usize, r % g))
            .collect()
    }

    /// Triangles whose bounding cap meets `cap` into `s.found`, by breadth-first search through
    /// shared edges from the triangles around point `seed` (which must lie in `cap`), under a
    /// fresh stamp.
    fn triangles_meeting(&self, cap: &Cap, seed: usize, s: &mut Scratch) {
        s.stamp += 1;
        let stamp = s.stamp;
        s.found.clear();
        s.queue.clear();
        let (s0, s1) = (self.inc_start[seed], self.inc_start[seed + 1]);
        for k in s0..s1 {
            let t = self.inc[k as usize];
            if s.tri_stamp[t as usize] != stamp {
                s.tri_stamp[t as usize] = stamp;
                s.queue.push(t);
            }
        }
        let mut head = 0;
        while head < s.queue.len() {
            let t = s.queue[head] as usize;
            head += 1;
            if !self.caps[t].meets(cap) {
                continue;
            }
            s.found.push(t as u32);
            for u in self.adj[t] {
                if u != u32::MAX && s.tri_stamp[u as usize] != stamp {
                    s.tri_stamp[u as usize] = stamp;
                    s.queue.push(u);
                }
            }
        }
    }

    /// The candidate points of `cell` that no other candidate dominates over the whole cell
    /// (module doc), ascending, into `s.kept`; `s.found` keeps the triangles searched.
    fn undominated(&self, cell: &CellGeometry, nearest: &impl Fn(Vec3) -> usize, s: &mut Scratch) {
        let q = nearest(cell.centre.as_vec3());
        // Points: within angle(c, q) + 2ρ of the centre.
        let cap = Cap::new(
            cell.centre,
            angle(cell.centre, self.p[q]) + 2.0 * cell.radius + 1e-9,
        );
        self.triangles_meeting(&cap, q, s);
        s.cand.clear();
        for &t in &s.found {
            for v in self.tris[t as usize] {
                if s.point_stamp[v as usize] != s.stamp && cap.holds(self.p[v as usize]) {
                    s.point_stamp[v as usize] = s.stamp;
                    s.cand.push(v);
                }
            }
        }
        s.cand.sort_unstable();
        // X̂ₖ·(p − q) = X̂ₖ·p − X̂ₖ·q up to 1e-16, far below TAU.
        s.corner_dots.clear();
        s.corner_dots.extend(
            s.cand
                .iter()
                .map(|&p| cell.corners.map(|x| x.dot(self.p[p as usize]))),
        );
        let dominated = |a: usize| {
            (0..s.cand.len()).any(|b| {
                let (da, db) = (s.corner_dots[a], s.corner_dots[b]);
                b != a && (0..4).all(|k| da[k] - db[k] < -TAU)
            })
        };
        s.kept = (0..s.cand.len())
            .filter(|&a| !dominated(a))
            .map(|a| s.cand[a])
            .collect();
    }

    /// Appends the candidate points and triangles of cell (i, j) of face `f` to `row`.
    fn cell_lists(
        &self,
        (f, i, j, g): (usize, u32, u32, u32),
        nearest: &impl Fn(Vec3) -> usize,
        s: &mut Scratch,
        row: &mut RowLists,
    ) {
        let cell = CubeGrid::geometry(f, i, j, g);
        self.undominated(&cell, nearest, s);
        row.points.extend_from_slice(&s.kept);
        row.point_len.push(s.kept.len() as u32);

        // Triangles: bounding cap meets the cell's cap (a subset of the cap above, so `found`
        // holds them all), not separated by a plane; most covered first.
        let small = Cap::new(cell.centre, cell.radius + 1e-9);
        s.keep.clear();
        for &t in &s.found {
            let v = self.tris[t as usize].map(|k| self.p[k as usize]);
            if self.caps[t as usize].meets(&small) && !separated(&v, &cell.corners) {
                let hits = CubeGrid::sub_samples(f, i, j, g)
                    .filter(|&d| inside(&v, d))
                    .count();
                s.keep.push((std::cmp::Reverse(hits), t));
            }
        }
        s.keep.sort_unstable();
        row.tris.extend(s.keep.iter().map(|&(_, t)| t));
        row.tri_len.push(s.keep.len() as u32);
    }
}

impl CubeGrid {
    /// Cells per face edge for `n` points: about `cells_per_point` cells per point in all.
    pub fn resolution_for(n: usize, cells_per_point: f64) -> u32 {
        ((n as f64 * cells_per_point / 6.0).sqrt().ceil() as u32).clamp(1, 1024)
    }

    /// Builds a g × g-per-face grid over `points` with triangulation `tris` (closed, covering
    /// the sphere, counter-clockwise seen from outside); `nearest` is any nearest-point query
    /// (only the tightness of the lists depends on its exactness). Rows of cells are built in
    /// parallel; the result does not depend on the thread count.
    pub fn new(
        points: &[Vec3],
        tris: &[[u32; 3]],
        g: u32,
        nearest: impl Fn(Vec3) -> usize + Sync,
    ) -> CubeGrid {
        let shared = Shared::new(points, tris);
        let rows = shared.rows(g, |s, f, j| {
            let mut row = RowLists::default();
            for i in 0..g {
                shared.cell_lists((f, i, j, g), &nearest, s, &mut row);
            }
            row
        });
        let prefix = |lens: &mut dyn Iterator<Item = u32>| {
            let mut start = vec![0u32];
            for n in lens {
                start.push(start[start.len() - 1] + n);
            }
            start
        };
        let point_start = prefix(&mut rows.iter().flat_map(|r| r.point_len.iter().copied()));
        let tri_start = prefix(&mut rows.iter().flat_map(|r| r.tri_len.iter().copied()));
        let point_items: Vec<u32> = rows.iter().flat_map(|r| r.points.iter().copied()).collect();
        let tri_items: Vec<u32> = rows.iter().flat_map(|r| r.tris.iter().copied()).collect();
        let slots = point_start
            .windows(2)
            .map(|w| {
                let list = &point_items[w[0] as usize..w[1] as usize];
                let mut slot = [OVERFLOW; SLOTS];
                if list.len() <= SLOTS {
                    for (k, s) in slot.iter_mut().enumerate() {
                        *s = list.get(k).copied().unwrap_or(list[0]);
                    }
                }
                slot
            })
            .collect();
        CubeGrid {
            g,
            half_g: 0.5 * g as f32,
            slots,
            point_start,
            point_items,
            tri_start,
            tri_items,
        }
    }

    /// Geometry of enlarged cell (i, j) of face `f`.
    fn geometry(f: usize, i: u32, j: u32, g: u32) -> CellGeometry {
        let ((u0, u1), (v0, v1)) = enlarged_cell(g, i, j, DELTA);
        let corners =
            [(u0, v0), (u1, v0), (u1, v1), (u0, v1)].map(|(u, v)| face_point(f, u, v).normalize());
        let centre = face_point(f, 0.5 * (u0 + u1), 0.5 * (v0 + v1)).normalize();
        let radius = corners
            .iter()
            .map(|&x| angle(centre, x))
            .fold(0.0, f64::max);
        CellGeometry {
            corners,
            centre,
            radius,
        }
    }

    /// 3 × 3 directions spread over cell (i, j) of face `f`.
    fn sub_samples(f: usize, i: u32, j: u32, g: u32) -> impl Iterator<Item = DVec3> {
        let h = 2.0 / g as f64;
        (0..9).map(move |k| {
            let u = -1.0 + h * (i as f64 + (k % 3) as f64 / 3.0 + 1.0 / 6.0);
            let v = -1.0 + h * (j as f64 + (k / 3) as f64 / 3.0 + 1.0 / 6.0);
            face_point(f, u, v)
        })
    }

    /// Cells in all.
    #[cfg(test)]
    pub fn cell_count(&self) -> usize {
        self.point_start.len() - 1
    }

    /// The raw candidate slots for the GPU lookup (src/gpu/field_data.rs): cells per face edge
    /// g and per cell its first four candidates (padded with repeats of the first) or, in the
    /// first slot, `u32::MAX` when it has more.
    pub(crate) fn raw_slots(&self) -> (u32, &[[u32; SLOTS]]) {
        (self.g, &self.slots)
    }

    /// The cell of direction `d` (any length; zero and NaN give some valid cell).
    #[inline]
    pub fn cell(&self, d: Vec3) -> usize {
        cell_of(self.g, self.half_g, d)
    }

    /// Candidate points of cell `c` (ascending, never empty).
    #[inline]
    pub fn points_of(&self, c: usize) -> &[u32] {
        &self.point_items[self.point_start[c] as usize..self.point_start[c + 1] as usize]
    }

    /// Candidate triangles of cell `c`, most likely first.
    #[inline]
    pub fn triangles_of(&self, c: usize) -> &[u32] {
        &self.tri_items[self.tri_start[c] as usize..self.tri_start[c + 1] as usize]
    }

    /// The point nearest to `d`: the first largest f64 dot product among the cell's candidates,
    /// equal to the brute-force answer (module doc).
    #[inline]
    pub fn nearest(&self, points: &[Vec3], d: Vec3) -> usize {
        let c = self.cell(d);
        let slot = self.slots[c];
        let dd = d.as_dvec3();
        if slot[0] == OVERFLOW {
            let cand = self.points_of(c).iter().map(|&i| i as usize);
            return first_nearest(points, dd, cand);
        }
        // Branch-free scan of the four slots (padding repeats the first, which never wins a
        // strict comparison).
        let dot = |k: usize| dd.dot(points[slot[k] as usize].as_dvec3());
        let (mut best, mut best_dot) = (slot[0], dot(0));
        for (k, &index) in slot.iter().enumerate().skip(1) {
            let x = dot(k);
            let better = x > best_dot;
            best = if better { index } else { best };
            best_dot = if better { x } else { best_dot };
        }
        best as usize
    }

    /// The first candidate triangle of `d`'s cell containing `d` (the acceptance test of the
    /// mesh walk), with its normalised non-negative planar barycentric weights; `None` only if
    /// rounding defeats every candidate.
    #[inline]
    pub fn locate(&self, points: &[Vec3], tris: &[[u32; 3]], d: Vec3) -> Option<(usize, [f64; 3])> {
        let dd = d.as_dvec3();
        for &t in self.triangles_of(self.cell(d)) {
            let [a, b, c] = tris[t as usize].map(|v| points[v as usize].as_dvec3());
            let w = [det(dd, b, c), det(a, dd, c), det(a, b, dd)];
            let scale = w[0].abs() + w[1].abs() + w[2].abs();
            if w[0].min(w[1]).min(w[2]) >= -INSIDE_TOL * scale {
                let w = w.map(|x| x.max(0.0));
                let sum = w[0] + w[1] + w[2];
                if sum > 0.0 {
                    return Some((t as usize, w.map(|x| x / sum)));
                }
            }
        }
        None
    }

    /// (mean, largest) candidate points per cell, and the same for triangles.
    #[cfg(test)]
    pub fn list_sizes(&self) -> ((f64, usize), (f64, usize)) {
        let stats = |start: &[u32]| {
            let n = start.len() - 1;
            let max = start.windows(2).map(|w| (w[1] - w[0]) as usize).max();
            (start[n] as f64 / n as f64, max.unwrap_or(0))
        };
        (stats(&self.point_start), stats(&self.tri_start))
    }
}

/// The first of `cand` with the largest f64 dot product with `dd` (0 when there is none): the
/// brute-force search's answer among them, exact ties to the first.
#[inline]
pub(super) fn first_nearest(
    points: &[Vec3],
    dd: DVec3,
    cand: impl IntoIterator<Item = usize>,
) -> usize {
    let mut best = (0usize, f64::NEG_INFINITY);
    for i in cand {
        let dot = dd.dot(points[i].as_dvec3());
        if dot > best.1 {
            best = (i, dot);
        }
    }
    best.0
}

/// The cell of direction `d` in a g × g-per-face grid (`half_g` = g/2): [`CubeGrid::cell`], for
/// any grid over the same faces.
#[inline]
fn cell_of(g: u32, half_g: f32, d: Vec3) -> usize {
    // Branch-free face selection (random directions would mispredict branches): the axis
    // of the largest |component|, ties to the lower axis.
    let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
    let x_wins = (ax >= ay) & (ax >= az);
    let y_wins = !x_wins & (ay >= az);
    let a = if x_wins {
        0
    } else if y_wins {
        1
    } else {
        2
    };
    let comp = [d.x, d.y, d.z, d.x, d.y];
    let (da, pb, pc) = (comp[a], comp[a + 1], comp[a + 2]);
    let (f, m) = (2 * a + (da < 0.0) as usize, da.abs());
    // (u + 1)·g/2 with u = p/m; float → int casts saturate (NaN → 0).
    let k = half_g / m;
    let last = g - 1;
    let i = ((pb * k + half_g) as u32).min(last) as usize;
    let j = ((pc * k + half_g) as u32).min(last) as usize;
    (f * g as usize + j) * g as usize + i
}

/// What the pruning of the module doc leaves in one cell of [`few_candidates`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Few {
    /// One point, nearest to every direction of the cell.
    One(u32),
    /// Two points (ascending): every direction's nearest point is one of them.
    Two(u32, u32),
    /// More than two.
    Many,
}

/// Per cell of a g × g-per-face grid over `points` (triangulation `tris`, as for
/// [`CubeGrid::new`]): the candidates of the (enlarged) cell when the pruning of the module doc
/// leaves one or two. Every point left out is beaten by a kept one by more than TAU/√3 in dot
/// product over the whole cell, so the first largest f64 dot product among the kept points (in
/// ascending order) is the brute-force answer there, ties included.
pub(super) fn few_candidates(
    points: &[Vec3],
    tris: &[[u32; 3]],
    g: u32,
    nearest: impl Fn(Vec3) -> usize + Sync,
) -> Vec<Few> {
    let shared = Shared::new(points, tris);
    let rows = shared.rows(g, |s, f, j| {
        (0..g)
            .map(|i| {
                shared.undominated(&CubeGrid::geometry(f, i, j, g), &nearest, s);
                match *s.kept.as_slice() {
                    [only] => Few::One(only),
                    [p, q] => Few::Two(p, q),
                    _ => Few::Many,
                }
            })
            .collect::<Vec<Few>>()
    });
    rows.into_iter().flatten().collect()
}

/// Whether a plane separates spherical triangle `v` (counter-clockwise) from the cone over the
/// cell's unit `corners` (in order around the cell): a triangle edge
/// plane with all corners strictly outside, or a cell side plane with all vertices strictly
/// outside. Conservative: `false` does not prove that they meet.
fn separated(v: &[DVec3; 3], corners: &[DVec3; 4]) -> bool {
    for e in 0..3 {
        let n = v[(e + 1) % 3].cross(v[(e + 2) % 3]);
        if corners.iter().all(|&x| n.dot(x) < -TAU * n.length()) {
            return true;
        }
    }
    for e in 0..4 {
        // Oriented so that the opposite corner (inside the cell) is on the positive side.
        let n = corners[e].cross(corners[(e + 1) % 4]);
        let n = if n.dot(corners[(e + 2) % 4]) < 0.0 {
            -n
        } else {
            n
        };
        if v.iter().all(|&x| n.dot(x) < -TAU * n.length()) {
            return true;
        }
    }
    false
}

/// Whether `d` lies in spherical triangle `v` (counter-clockwise), up to rounding.
fn inside(v: &[DVec3; 3], d: DVec3) -> bool {
    let w = [det(d, v[1], v[2]), det(v[0], d, v[2]), det(v[0], v[1], d)];
    w.iter().all(|&x| x >= 0.0)
}

/// The bounds `((x0, x1), (y0, y1))` of cell (i, j) of a `g × g` grid over `[−1, 1]²`,
/// enlarged by `delta` on every side (the cube faces' cells here, the disk's in
/// `texel_table`).
pub(crate) fn enlarged_cell(g: u32, i: u32, j: u32, delta: f64) -> ((f64, f64), (f64, f64)) {
    let h = 2.0 / g as f64;
    let span = |k: u32| {
        (
            -1.0 + h * k as f64 - delta,
            -1.0 + h * (k + 1) as f64 + delta,
        )
    };
    (span(i), span(j))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rays::seeded_sphere_direction;
    use crate::sampling::{SphereKind, SpherePoints};

    fn sets() -> Vec<SpherePoints> {
        [
            (SphereKind::Slater, 10),
            (SphereKind::Slater, 290),
            (SphereKind::Slater, 1090),
            (SphereKind::Slater, 4226),
            (SphereKind::LatLong, 6),
            (SphereKind::LatLong, 1122),
            (SphereKind::Fibonacci, 4),
            (SphereKind::Fibonacci, 5),
            (SphereKind::Fibonacci, 290),
            (SphereKind::Fibonacci, 4226),
        ]
        .map(|(k, n)| SpherePoints::new(k, n).unwrap())
        .into()
    }

    /// Directions on the grid's own seams: cell boundaries of every face (u or v = −1 + 2i/g in
    /// f32, and one ulp either side), face edges and cube corners.
    fn seam_directions(g: u32) -> Vec<Vec3> {
        let mut v = Vec::new();
        for i in 0..=g {
            let b = -1.0 + 2.0 * i as f32 / g as f32;
            for k in 0..16 {
                let t = -1.0 + 2.0 * (k as f32 + 0.31) / 16.0;
                for b in [b.next_down(), b, b.next_up()] {
                    for s in [1.0f32, -1.0] {
                        v.push(Vec3::new(s, b, t));
                        v.push(Vec3::new(t, s, b));
                        v.push(Vec3::new(b, t, s));
                        v.push(Vec3::new(s, t, b));
                    }
                }
            }
        }
        for x in [-1.0f32, 1.0] {
            for y in [-1.0f32, 1.0] {
                v.extend([
                    Vec3::new(x, y, 1.0),
                    Vec3::new(x, y, -1.0),
                    Vec3::new(x, y, 0.0),
                ]);
            }
        }
        v
    }

    #[test]
    fn nearest_is_the_brute_force_index_itself() {
        // Not just up to ties: the lists are ascending and scanned with a strict comparison of
        // the same f64 dot products, so even the tie-break (first index) matches.
        for set in sets() {
            let n = set.len();
            let g = set.grid().g;
            let mut dirs: Vec<Vec3> = (0..(4_000_000 / n).clamp(2000, 100_000) as u64)
                .map(|i| seeded_sphere_direction(i, 21))
                .collect();
            dirs.extend(seam_directions(g));
            dirs.extend(set.points());
            // Edge midpoints and circumcentres: two- and three-way ties.
            for t in set.triangles().iter().take(20_000) {
                let [a, b, c] = t.map(|i| set.point(i as usize));
                dirs.push((a + b).normalize());
                dirs.push((b - a).cross(c - a).normalize());
            }
            for d in dirs {
                assert_eq!(
                    set.nearest(d),
                    set.nearest_brute_force(d),
                    "{} {n}: {d}",
                    set.kind.name()
                );
            }
        }
    }

    #[test]
    fn lists_are_non_empty_short_and_consistent() {
        for set in sets() {
            let grid = set.grid();
            assert_eq!(grid.cell_count(), 6 * (grid.g * grid.g) as usize);
            for c in 0..grid.cell_count() {
                let pts = grid.points_of(c);
                assert!(
                    !pts.is_empty(),
                    "{} {}: cell {c}",
                    set.kind.name(),
                    set.len()
                );
                assert!(pts.windows(2).all(|w| w[0] < w[1]), "ascending, no repeats");
                assert!(!grid.triangles_of(c).is_empty());
                let slot = grid.slots[c];
                if pts.len() <= SLOTS {
                    assert!(slot.iter().all(|s| pts.contains(s)) && slot[..pts.len()] == *pts);
                } else {
                    assert_eq!(slot[0], OVERFLOW);
                }
            }
            // Four cells per point: about 2.4 candidate points and 3.6 triangles per cell.
            let ((mean_p, _), (mean_t, _)) = grid.list_sizes();
            if set.len() >= 290 {
                assert!(mean_p < 3.0 && mean_t < 4.5, "{mean_p} {mean_t}");
            }
        }
    }

    #[test]
    fn locate_agrees_with_the_mesh_walk() {
        for set in sets() {
            let (points, tris) = (set.points(), set.triangles());
            for i in 0..20_000u64 {
                let d = seeded_sphere_direction(i, 23);
                let (t, w) = set
                    .grid()
                    .locate(points, tris, d)
                    .expect("a candidate contains every direction");
                let (tw, ww) = set.mesh().locate(points, d.as_dvec3(), set.nearest(d));
                // Random directions are interior to one triangle (ties have measure zero).
                assert_eq!(t, tw, "{} {}: {d}", set.kind.name(), set.len());
                assert_eq!(w, ww);
            }
            for d in seam_directions(set.grid().g) {
                let (t, _) = set.grid().locate(points, tris, d).expect("seams too");
                let v = tris[t].map(|k| points[k as usize].as_dvec3());
                let d = d.as_dvec3();
                let w = [det(d, v[1], v[2]), det(v[0], d, v[2]), det(v[0], v[1], d)];
                let scale: f64 = w.iter().map(|x| x.abs()).sum();
                assert!(w.iter().all(|&x| x >= -INSIDE_TOL * scale));
            }
        }
    }
}
