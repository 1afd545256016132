//! Triangulations of the sphere by a point set: adjacency, point location by walking, barycentric
//! weights, validation, Lawson flips to Delaunay and the spacing metrics derived from it.

use glam::{DVec3, Vec3};
use std::collections::HashMap;

/// A closed, consistently oriented triangle mesh on the unit sphere. Triangles are
/// counter-clockwise seen from outside: det(p0, p1, p2) > 0.
#[derive(Clone, Debug)]
pub(crate) struct SphereMesh {
    tris: Vec<[u32; 3]>,
    /// `adj[t][i]`: the triangle across the edge opposite vertex i of triangle t.
    adj: Vec<[u32; 3]>,
    /// One triangle incident to each vertex.
    incident: Vec<u32>,
}

#[inline]
fn p64(points: &[Vec3], i: u32) -> DVec3 {
    points[i as usize].as_dvec3()
}

/// Relative tolerance of the point-in-triangle test ([`SphereMesh::try_locate`] and the cube
/// grid's `locate`): `d` on an edge gives a numerator that is zero up to rounding.
pub(super) const INSIDE_TOL: f64 = 1e-14;

#[inline]
pub(super) fn det(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    a.dot(b.cross(c))
}

impl SphereMesh {
    /// Builds the mesh, orienting each triangle outward; fails when the triangles do not form a
    /// closed 2-manifold (an edge not shared by exactly two triangles in opposite directions) or
    /// leave a point without triangles.
    pub fn new(points: &[Vec3], mut tris: Vec<[u32; 3]>) -> Result<Self, String> {
        for t in &mut tris {
            if det(p64(points, t[0]), p64(points, t[1]), p64(points, t[2])) < 0.0 {
                t.swap(1, 2);
            }
        }
        let mut half: HashMap<(u32, u32), u32> = HashMap::with_capacity(tris.len() * 3);
        for (ti, t) in tris.iter().enumerate() {
            for e in 0..3 {
                let key = (t[(e + 1) % 3], t[(e + 2) % 3]);
                if half.insert(key, (ti * 3 + e) as u32).is_some() {
                    return Err(format!("directed edge {key:?} appears twice"));
                }
            }
        }
        let mut adj = vec![[u32::MAX; 3]; tris.len()];
        for (ti, t) in tris.iter().enumerate() {
            for (e, slot) in adj[ti].iter_mut().enumerate() {
                let (a, b) = (t[(e + 1) % 3], t[(e + 2) % 3]);
                match half.get(&(b, a)) {
                    Some(&h) => *slot = h / 3,
                    None => return Err(format!("edge ({a}, {b}) has no twin")),
                }
            }
        }
        let mut incident = vec![u32::MAX; points.len()];
        for (ti, t) in tris.iter().enumerate() {
            for &v in t {
                incident[v as usize] = ti as u32;
            }
        }
        if let Some(v) = incident.iter().position(|&t| t == u32::MAX) {
            return Err(format!("point {v} belongs to no triangle"));
        }
        Ok(SphereMesh {
            tris,
            adj,
            incident,
        })
    }

    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.tris
    }

    /// Unnormalised barycentric numerators of `d` in triangle `t`: w_i = det(d at slot i).
    /// All ≥ 0 exactly when d lies in the spherical triangle; their sum is d · N with N the
    /// (outward) normal of the triangle's plane, so w / Σw are the planar barycentrics of the
    /// point where the ray along d meets that plane.
    #[inline]
    fn numerators(&self, points: &[Vec3], t: usize, d: DVec3) -> [f64; 3] {
        let [a, b, c] = self.tris[t].map(|v| p64(points, v));
        [det(d, b, c), det(a, d, c), det(a, b, d)]
    }

    /// Finds the triangle containing `d` by walking from a triangle incident to vertex `start`
    /// (the nearest point, so the walk is short), always crossing the edge with the most negative
    /// numerator. Returns the triangle and its normalised, non-negative weights; `None` if the
    /// walk did not settle within `max_steps`.
    pub fn try_locate(
        &self,
        points: &[Vec3],
        d: DVec3,
        start: usize,
        max_steps: usize,
    ) -> Option<(usize, [f64; 3])> {
        let mut t = self.incident[start] as usize;
        for _ in 0..max_steps {
            let w = self.numerators(points, t, d);
            let scale = w[0].abs() + w[1].abs() + w[2].abs();
            let (mut imin, mut wmin) = (0, w[0]);
            for (i, &wi) in w.iter().enumerate().skip(1) {
                if wi < wmin {
                    (imin, wmin) = (i, wi);
                }
            }
            if wmin >= -INSIDE_TOL * scale {
                let w = w.map(|x| x.max(0.0));
                let sum = w[0] + w[1] + w[2];
                if sum > 0.0 {
                    return Some((t, w.map(|x| x / sum)));
                }
            }
            t = self.adj[t][imin] as usize;
        }
        None
    }

    /// Like [`Self::try_locate`], falling back to a scan of all triangles for the one whose
    /// smallest normalised numerator is largest.
    pub fn locate(&self, points: &[Vec3], d: DVec3, start: usize) -> (usize, [f64; 3]) {
        let steps = 64 + 4 * (points.len() as f64).sqrt() as usize;
        if let Some(hit) = self.try_locate(points, d, start, steps) {
            return hit;
        }
        let mut best = (0usize, f64::NEG_INFINITY);
        for t in 0..self.tris.len() {
            let w = self.numerators(points, t, d);
            let sum = w[0] + w[1] + w[2];
            if sum > 0.0 {
                let m = w[0].min(w[1]).min(w[2]) / sum;
                if m > best.1 {
                    best = (t, m);
                }
            }
        }
        let w = self.numerators(points, best.0, d).map(|x| x.max(0.0));
        let sum = (w[0] + w[1] + w[2]).max(f64::MIN_POSITIVE);
        (best.0, w.map(|x| x / sum))
    }

    /// Checks that the mesh covers the sphere exactly once: every triangle positively oriented,
    /// Euler characteristic 2, and spherical areas summing to 4π (to `area_tol` relative).
    /// Positive orientation plus total area 4π means the map from the mesh to the sphere has
    /// degree one everywhere, so the triangles neither overlap nor leave gaps.
    pub fn validate(&self, points: &[Vec3], area_tol: f64) -> Result<(), String> {
        let mut area = 0.0;
        for (ti, t) in self.tris.iter().enumerate() {
            let [a, b, c] = t.map(|v| p64(points, v));
            let dt = det(a, b, c);
            if dt <= 0.0 {
                return Err(format!(
                    "triangle {ti} {t:?} is not positively oriented ({dt})"
                ));
            }
            // Van Oosterom–Strackee: tan(E/2) = det / (1 + a·b + b·c + c·a) for unit vectors.
            area += 2.0 * dt.atan2(1.0 + a.dot(b) + b.dot(c) + c.dot(a));
        }
        let v = points.len() as i64;
        let f = self.tris.len() as i64;
        let e = 3 * f / 2;
        if v - e + f != 2 {
            return Err(format!(
                "Euler characteristic V − E + F = {} ≠ 2",
                v - e + f
            ));
        }
        let full = 4.0 * std::f64::consts::PI;
        if ((area - full) / full).abs() > area_tol {
            return Err(format!("triangle areas sum to {area}, not 4π"));
        }
        Ok(())
    }

    /// Height of the apex of the triangle across edge `e` of `t` above the plane of `t`,
    /// along its unit outward normal: > 0 means that apex lies inside t's circumcircle.
    fn opposite_height(&self, points: &[Vec3], t: usize, e: usize) -> f64 {
        let [a, b, c] = self.tris[t].map(|v| p64(points, v));
        let n = (b - a).cross(c - a).normalize();
        (p64(points, self.apex(t, e)) - a).dot(n)
    }

    /// The vertex of the triangle across edge `e` of `t` that is not on that edge.
    fn apex(&self, t: usize, e: usize) -> u32 {
        let tri = self.tris[t];
        let (x, y) = (tri[(e + 1) % 3], tri[(e + 2) % 3]);
        self.tris[self.adj[t][e] as usize]
            .into_iter()
            .find(|&v| v != x && v != y)
            .expect("a triangle has a vertex off its edge")
    }

    #[cfg(test)]
    /// The largest [`Self::opposite_height`] over all edges: ≤ 0 (up to rounding) exactly when
    /// the triangulation is Delaunay (locally Delaunay everywhere implies globally).
    pub fn max_delaunay_violation(&self, points: &[Vec3]) -> f64 {
        let mut worst = f64::NEG_INFINITY;
        for t in 0..self.tris.len() {
            for e in 0..3 {
                worst = worst.max(self.opposite_height(points, t, e));
            }
        }
        worst
    }

    /// Lawson flips until no apex lies more than `tol` above a neighbour's plane: the Delaunay
    /// triangulation (the convex hull) up to `tol`. Used for spacing metrics.
    pub fn delaunay(&self, points: &[Vec3], tol: f64) -> Result<SphereMesh, String> {
        let mut mesh = self.clone();
        for _pass in 0..10_000 {
            let mut touched = vec![false; mesh.tris.len()];
            let mut flips = 0usize;
            for t in 0..mesh.tris.len() {
                for e in 0..3 {
                    let u = mesh.adj[t][e] as usize;
                    if touched[t] || touched[u] || mesh.opposite_height(points, t, e) <= tol {
                        continue;
                    }
                    let tri = mesh.tris[t];
                    let (c, x, y) = (tri[e], tri[(e + 1) % 3], tri[(e + 2) % 3]);
                    let apex = mesh.apex(t, e);
                    // (c, x, y) and (apex, y, x) become (x, apex, c) and (y, c, apex).
                    mesh.tris[t] = [x, apex, c];
                    mesh.tris[u] = [y, c, apex];
                    touched[t] = true;
                    touched[u] = true;
                    flips += 1;
                }
            }
            mesh = SphereMesh::new(points, mesh.tris)?;
            if flips == 0 {
                return Ok(mesh);
            }
        }
        Err("Lawson flips did not converge".into())
    }

    /// Angular circumradius (radians) of each triangle: the distance from its circumcentre to
    /// its vertices. For a Delaunay mesh the circumcentres are the Voronoi vertices, so the
    /// largest is the covering radius of the point set.
    pub fn circumradii<'a>(
        &'a self,
        points: &'a [Vec3],
    ) -> impl Iterator<Item = (DVec3, f64)> + 'a {
        self.tris.iter().map(move |t| {
            let [a, b, c] = t.map(|v| p64(points, v));
            let centre = (b - a).cross(c - a).normalize();
            (centre, centre.dot(a).clamp(-1.0, 1.0).acos())
        })
    }

    /// Angular length (radians) of the shortest edge. For a Delaunay mesh this is the smallest
    /// separation of the set (the closest pair is always a Delaunay edge).
    pub fn min_edge(&self, points: &[Vec3]) -> f64 {
        let mut best = f64::INFINITY;
        for t in &self.tris {
            for e in 0..3 {
                let (a, b) = (p64(points, t[e]), p64(points, t[(e + 1) % 3]));
                best = best.min(a.cross(b).length().atan2(a.dot(b)));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn octahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = vec![
            Vec3::X,
            Vec3::Y,
            Vec3::NEG_X,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
        ];
        let t = vec![
            [0, 1, 4],
            [1, 2, 4],
            [2, 3, 4],
            [3, 0, 4],
            [1, 0, 5],
            [2, 1, 5],
            [3, 2, 5],
            [0, 3, 5],
        ];
        (p, t)
    }

    #[test]
    fn octahedron_is_valid_and_locates_axes() {
        let (p, t) = octahedron();
        let mesh = SphereMesh::new(&p, t).unwrap();
        mesh.validate(&p, 1e-7).unwrap();
        // The octant direction (1,1,1)/√3 lies in the face (X, Y, Z) with equal weights ⅓.
        let (tri, w) = mesh.locate(&p, DVec3::ONE.normalize(), 5);
        let mut verts = mesh.triangles()[tri];
        verts.sort();
        assert_eq!(verts, [0, 1, 4]);
        assert!(w.iter().all(|&x| (x - 1.0 / 3.0).abs() < 1e-12), "{w:?}");
        // Octahedron: circumradius of each face is the angle from (1,1,1)/√3 to X: acos(1/√3).
        let r = (1.0f64 / 3.0f64.sqrt()).acos();
        assert!(mesh.circumradii(&p).all(|(_, x)| (x - r).abs() < 1e-12));
        assert!((mesh.min_edge(&p) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn validation_rejects_holes_and_overlaps() {
        let (p, mut t) = octahedron();
        t.pop();
        assert!(
            SphereMesh::new(&p, t.clone()).is_err(),
            "a hole must be rejected"
        );
        let (p, mut t) = octahedron();
        t[0] = [0, 1, 5]; // duplicates face 4 → directed edge twice
        assert!(SphereMesh::new(&p, t).is_err());
    }

    #[test]
    fn flips_repair_a_non_delaunay_edge() {
        // A square of four points around the north pole, the pole slightly lifted off-centre:
        // split along the wrong diagonal, the Lawson pass must flip it.
        let s = 0.3f32;
        let p: Vec<Vec3> = [
            Vec3::new(s, 0.0, 1.0),
            Vec3::new(0.0, s * 0.5, 1.0),
            Vec3::new(-s, 0.0, 1.0),
            Vec3::new(0.0, -s * 0.5, 1.0),
            Vec3::NEG_Z,
        ]
        .iter()
        .map(|v| v.normalize())
        .collect();
        // Diagonal 1–3 is the Delaunay one (short); start with 0–2.
        let t = vec![
            [0, 1, 2],
            [0, 2, 3],
            [1, 0, 4],
            [2, 1, 4],
            [3, 2, 4],
            [0, 3, 4],
        ];
        let mesh = SphereMesh::new(&p, t).unwrap();
        assert!(mesh.max_delaunay_violation(&p) > 1e-6);
        let del = mesh.delaunay(&p, 1e-12).unwrap();
        del.validate(&p, 1e-7).unwrap();
        assert!(del.max_delaunay_violation(&p) <= 1e-12);
    }
}
