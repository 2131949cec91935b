//! The triangle mesh type and its point queries and edits.

use geometry::orient;
use glam::DVec2;

use crate::MeshError;

/// Distance (pixels) within which [`Mesh::insert_point`] reuses an existing vertex, or
/// splits an edge rather than a triangle.
const SNAP_DISTANCE: f64 = 1e-9;

/// A 2-D triangle mesh in image pixel coordinates (origin top-left, y down; pixel
/// `(x, y)` covers `[x, x+1] × [y, y+1]`).
///
/// Orientation: every triangle `[a, b, c]` has positive signed area by the shoelace
/// formula in pixel coordinates, `(b - a).perp_dot(c - a) > 0`. That is counter-clockwise
/// in a y-up frame, and clockwise as seen on screen (y down).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in pixels.
    pub vertices: Vec<DVec2>,
    /// Triangles as indices into [`Mesh::vertices`], oriented as described on [`Mesh`].
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// The three corner positions of triangle `t`.
    ///
    /// # Panics
    /// Panics if `t` or one of its indices is out of range.
    pub fn triangle_positions(&self, t: usize) -> [DVec2; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// Signed area of triangle `t` in px² (positive for the crate's orientation).
    ///
    /// # Panics
    /// Panics if `t` or one of its indices is out of range.
    pub fn triangle_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangle_positions(t);
        0.5 * orient(a, b, c)
    }

    /// Total signed area of all triangles in px².
    ///
    /// # Panics
    /// Panics if a triangle index is out of range (see [`Mesh::sanity_check`]).
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| self.triangle_area(t))
            .sum()
    }

    /// The smallest axis-aligned box `(min, max)` holding every vertex; `(0, 0)` twice for
    /// a mesh without vertices.
    pub fn bounding_box(&self) -> (DVec2, DVec2) {
        if self.vertices.is_empty() {
            return (DVec2::ZERO, DVec2::ZERO);
        }
        self.vertices.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        )
    }

    /// Finds a triangle containing `p` (boundary included) and `p`'s barycentric
    /// coordinates in it, `[w0, w1, w2]` with `p = w0·a + w1·b + w2·c` and `Σw = 1`.
    ///
    /// Brute force: O(number of triangles). Returns `None` when no triangle contains `p`
    /// or `p` is not finite. When `p` lies on an edge or vertex shared by several
    /// triangles, the one where `p` is deepest inside is returned.
    pub fn locate(&self, p: DVec2) -> Option<(usize, [f64; 3])> {
        if !p.is_finite() {
            return None;
        }
        let mut best: Option<(usize, [f64; 3])> = None;
        let mut best_min = f64::NEG_INFINITY;
        for (t, tri) in self.triangles.iter().enumerate() {
            let Some([a, b, c]) = self.get_positions(tri) else {
                continue;
            };
            let lo = a.min(b).min(c);
            let hi = a.max(b).max(c);
            let slack = 1e-12 * (1.0 + hi.abs().max_element());
            if p.x < lo.x - slack || p.x > hi.x + slack || p.y < lo.y - slack || p.y > hi.y + slack
            {
                continue;
            }
            let Some(w) = barycentric(a, b, c, p) else {
                continue;
            };
            // Tolerance relative to the triangle size, so points on shared edges are found.
            let m = w[0].min(w[1]).min(w[2]);
            if m >= -1e-12 && m > best_min {
                best_min = m;
                best = Some((t, w));
                if m > 1e-6 {
                    break; // Strictly inside: no other triangle can contain p.
                }
            }
        }
        best
    }

    fn get_positions(&self, tri: &[u32; 3]) -> Option<[DVec2; 3]> {
        let a = *self.vertices.get(tri[0] as usize)?;
        let b = *self.vertices.get(tri[1] as usize)?;
        let c = *self.vertices.get(tri[2] as usize)?;
        Some([a, b, c])
    }

    /// Returns the index of a vertex at `p`, inserting one if needed.
    ///
    /// * A vertex within 1e-9 px of `p` is reused (its position is not changed).
    /// * If `p` lies within 1e-9 px of an edge, that edge is split: the two triangles
    ///   sharing it become four (one becomes two on the mesh boundary).
    /// * Otherwise the triangle containing `p` is split into three.
    ///
    /// New triangles keep the mesh's orientation; the new vertex is appended, so existing
    /// indices stay valid. Triangles are replaced in place and appended.
    ///
    /// # Errors
    /// [`MeshError::NonFinite`] for a NaN or infinite `p`,
    /// [`MeshError::PointOutsideMesh`] when no triangle contains `p`.
    pub fn insert_point(&mut self, p: DVec2) -> Result<u32, MeshError> {
        if !p.is_finite() {
            return Err(MeshError::NonFinite {
                what: "inserted point".into(),
            });
        }
        let outside = MeshError::PointOutsideMesh { x: p.x, y: p.y };
        let (t, _) = self.locate(p).ok_or(outside)?;
        let tri = self.triangles[t];
        let pos = tri.map(|i| self.vertices[i as usize]);
        // Existing vertex?
        for k in 0..3 {
            if pos[k].distance(p) <= SNAP_DISTANCE {
                return Ok(tri[k]);
            }
        }
        // Also reuse a vertex of a neighbouring triangle (p may lie just outside `t`).
        let snap2 = SNAP_DISTANCE * SNAP_DISTANCE;
        for &v in self.triangles.iter().flatten() {
            if self.vertices[v as usize].distance_squared(p) <= snap2 {
                return Ok(v);
            }
        }
        let new = u32::try_from(self.vertices.len())
            .map_err(|_| MeshError::InvalidMesh("too many vertices for u32 indices".into()))?;
        // On an edge of `t`? Edge k goes from tri[k] to tri[(k + 1) % 3].
        let mut on_edge = None;
        for k in 0..3 {
            let (a, b) = (pos[k], pos[(k + 1) % 3]);
            let len = a.distance(b);
            if len > 0.0 && orient(a, b, p).abs() / len <= SNAP_DISTANCE {
                on_edge = Some(k);
            }
        }
        let mut replaced: Vec<(usize, [u32; 3])> = Vec::new();
        let mut added: Vec<[u32; 3]> = Vec::new();
        match on_edge {
            None => {
                let [a, b, c] = tri;
                replaced.push((t, [a, b, new]));
                added.push([b, c, new]);
                added.push([c, a, new]);
            }
            Some(k) => {
                let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                replaced.push((t, [a, new, c]));
                added.push([new, b, c]);
                // The triangle on the other side holds the directed edge b -> a.
                let other = self.triangles.iter().enumerate().find_map(|(u, tr)| {
                    (u != t)
                        .then(|| (0..3).find(|&j| tr[j] == b && tr[(j + 1) % 3] == a))
                        .flatten()
                        .map(|j| (u, tr[(j + 2) % 3]))
                });
                if let Some((u, d)) = other {
                    replaced.push((u, [b, new, d]));
                    added.push([new, a, d]);
                }
            }
        }
        // Check the new triangles before touching the mesh.
        let pos_of = |i: u32| {
            if i == new {
                p
            } else {
                self.vertices[i as usize]
            }
        };
        let all_ok = replaced
            .iter()
            .map(|(_, tr)| tr)
            .chain(added.iter())
            .all(|tr| orient(pos_of(tr[0]), pos_of(tr[1]), pos_of(tr[2])) > 0.0);
        if !all_ok {
            return Err(MeshError::InvalidMesh(format!(
                "inserting ({}, {}) would create a degenerate triangle",
                p.x, p.y
            )));
        }
        self.vertices.push(p);
        for (u, tr) in replaced {
            self.triangles[u] = tr;
        }
        self.triangles.extend(added);
        Ok(new)
    }

    /// Checks the mesh invariants: finite coordinates, indices in range, no repeated index
    /// in a triangle, positive signed area for every triangle (see [`Mesh`]), every
    /// directed edge used by at most one triangle (consistent orientation, no overlapping
    /// duplicates), and every vertex used by some triangle.
    ///
    /// # Errors
    /// [`MeshError::InvalidMesh`] naming the first violation found.
    pub fn sanity_check(&self) -> Result<(), MeshError> {
        let bad = |m: String| Err(MeshError::InvalidMesh(m));
        for (i, v) in self.vertices.iter().enumerate() {
            if !v.is_finite() {
                return bad(format!("vertex {i} is not finite"));
            }
        }
        let n = self.vertices.len();
        let mut used = vec![false; n];
        let mut edges: Vec<u64> = Vec::with_capacity(self.triangles.len() * 3);
        for (t, tri) in self.triangles.iter().enumerate() {
            for &i in tri {
                if i as usize >= n {
                    return bad(format!("triangle {t} refers to missing vertex {i}"));
                }
                used[i as usize] = true;
            }
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return bad(format!("triangle {t} repeats a vertex: {tri:?}"));
            }
            let area = self.triangle_area(t);
            if area.is_nan() || area <= 0.0 {
                return bad(format!(
                    "triangle {t} {tri:?} has non-positive signed area {area}"
                ));
            }
            for k in 0..3 {
                edges.push((u64::from(tri[k]) << 32) | u64::from(tri[(k + 1) % 3]));
            }
        }
        if let Some(i) = used.iter().position(|&u| !u) {
            return bad(format!("vertex {i} is used by no triangle"));
        }
        edges.sort_unstable();
        if let Some(w) = edges.windows(2).find(|w| w[0] == w[1]) {
            return bad(format!(
                "directed edge {} -> {} belongs to two triangles",
                w[0] >> 32,
                w[0] & 0xffff_ffff
            ));
        }
        Ok(())
    }
}

/// Barycentric coordinates of `p` in triangle `a b c`, or `None` for a degenerate triangle.
fn barycentric(a: DVec2, b: DVec2, c: DVec2, p: DVec2) -> Option<[f64; 3]> {
    let d = orient(a, b, c);
    if d == 0.0 || !d.is_finite() {
        return None;
    }
    let w0 = orient(p, b, c) / d;
    let w1 = orient(a, p, c) / d;
    Some([w0, w1, 1.0 - w0 - w1])
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn square() -> Mesh {
        Mesh {
            vertices: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(2.0, 0.0),
                DVec2::new(2.0, 2.0),
                DVec2::new(0.0, 2.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn square_is_sane() {
        let m = square();
        m.sanity_check().unwrap();
        assert_eq!(m.area(), 4.0);
        assert_eq!(m.bounding_box(), (DVec2::ZERO, DVec2::splat(2.0)));
    }

    #[test]
    fn locate_finds_barycentrics() {
        let m = square();
        let (t, w) = m.locate(DVec2::new(1.5, 0.5)).unwrap();
        assert_eq!(t, 0);
        let [a, b, c] = m.triangle_positions(t);
        let q = a * w[0] + b * w[1] + c * w[2];
        assert!(q.distance(DVec2::new(1.5, 0.5)) < 1e-12);
        assert!(m.locate(DVec2::new(3.0, 0.5)).is_none());
        assert!(m.locate(DVec2::new(f64::NAN, 0.5)).is_none());
        assert!(m.locate(DVec2::new(2.0, 2.0)).is_some());
    }

    #[test]
    fn insert_splits_face_edge_and_boundary_edge() {
        let mut m = square();
        let v = m.insert_point(DVec2::new(1.5, 0.5)).unwrap();
        assert_eq!(v, 4);
        assert_eq!(m.triangles.len(), 4);
        m.sanity_check().unwrap();
        // Diagonal 0-2 is shared by two triangles: 2 -> 4.
        let v = m.insert_point(DVec2::new(0.5, 0.5)).unwrap();
        assert_eq!(v, 5);
        m.sanity_check().unwrap();
        assert!((m.area() - 4.0).abs() < 1e-12);
        // A point on the boundary edge 3-0.
        let n = m.triangles.len();
        let v = m.insert_point(DVec2::new(0.0, 1.0)).unwrap();
        assert_eq!(m.triangles.len(), n + 1);
        m.sanity_check().unwrap();
        assert!((m.area() - 4.0).abs() < 1e-12);
        // Existing vertices are reused.
        assert_eq!(m.insert_point(DVec2::new(0.0, 1.0 + 1e-12)).unwrap(), v);
        assert_eq!(m.insert_point(DVec2::new(2.0, 2.0)).unwrap(), 2);
        assert!(matches!(
            m.insert_point(DVec2::new(5.0, 1.0)),
            Err(MeshError::PointOutsideMesh { .. })
        ));
        assert!(matches!(
            m.insert_point(DVec2::new(f64::NAN, 1.0)),
            Err(MeshError::NonFinite { .. })
        ));
    }

    #[test]
    fn sanity_check_catches_problems() {
        let mut m = square();
        m.triangles[1] = [0, 3, 2];
        assert!(m.sanity_check().is_err());
        let mut m = square();
        m.vertices.push(DVec2::new(5.0, 5.0));
        assert!(m.sanity_check().is_err());
        let mut m = square();
        m.triangles[0] = [0, 1, 9];
        assert!(m.sanity_check().is_err());
        let mut m = square();
        m.vertices[0].x = f64::NAN;
        assert!(m.sanity_check().is_err());
        let mut m = square();
        m.triangles.push([0, 1, 2]);
        assert!(m.sanity_check().is_err());
    }
}
