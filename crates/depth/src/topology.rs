//! What a mesh's connectivity says once, so that a pose without overlaps costs little:
//! the paper's "first locate boundary intersections". A warped mesh overlaps itself
//! only if a triangle turned over, two boundary edges cross, or one piece of the mesh
//! (a connected component) lies wholly over another: where no triangle turns over, each
//! piece is one-to-one onto the inside of its warped boundary, so two of its triangles
//! can only overlap where its boundary crosses itself, and two pieces only where their
//! boundaries cross or one holds the other.

use glam::DVec2;

/// A mesh's boundary, pieces and triangle orientations at rest.
#[derive(Clone, Debug)]
pub struct Topology {
    /// The triangles it was made for.
    triangles: Vec<[u32; 3]>,
    /// Each triangle's orientation at rest (+1, −1, or 0 for none).
    signs: Vec<i8>,
    /// Edges used by one triangle, each with its piece.
    boundary: Vec<([u32; 2], u32)>,
    /// How many pieces, and a vertex of each.
    pieces: Vec<u32>,
}

impl Topology {
    /// The topology of `triangles` with rest positions `rest`.
    pub fn new(rest: &[DVec2], triangles: &[[u32; 3]]) -> Self {
        let signs = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| rest[v as usize]);
                let o = geometry::orient(a, b, c);
                if o > 0.0 {
                    1
                } else if o < 0.0 {
                    -1
                } else {
                    0
                }
            })
            .collect();
        // Pieces: vertices joined through their triangles.
        let n = rest.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                let up = parent[parent[v as usize] as usize];
                parent[v as usize] = up;
                v = up;
            }
            v
        }
        for t in triangles {
            let r = root(&mut parent, t[0]);
            for &v in &t[1..] {
                let s = root(&mut parent, v);
                parent[s as usize] = r;
            }
        }
        let mut piece_of = vec![u32::MAX; n];
        let mut pieces = Vec::new();
        for t in triangles {
            let r = root(&mut parent, t[0]) as usize;
            if piece_of[r] == u32::MAX {
                piece_of[r] = pieces.len() as u32;
                pieces.push(t[0]);
            }
        }
        let mut edges: Vec<([u32; 2], u32)> = triangles
            .iter()
            .flat_map(|t| {
                [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])].map(|(u, v)| ([u.min(v), u.max(v)], 0))
            })
            .collect();
        edges.sort_unstable();
        let mut boundary = Vec::new();
        let mut k = 0;
        while k < edges.len() {
            let mut m = k + 1;
            while m < edges.len() && edges[m].0 == edges[k].0 {
                m += 1;
            }
            if m - k == 1 {
                let e = edges[k].0;
                let piece = piece_of[root(&mut parent, e[0]) as usize];
                boundary.push((e, piece));
            }
            k = m;
        }
        Self {
            triangles: triangles.to_vec(),
            signs,
            boundary,
            pieces,
        }
    }

    /// Whether it was made for `triangles`.
    pub fn is_for(&self, triangles: &[[u32; 3]]) -> bool {
        self.triangles == triangles
    }

    /// Whether the mesh warped to `positions` may overlap itself (`false`: it surely
    /// does not): a triangle turned over or flattened, two boundary edges crossing, or
    /// a piece with a vertex inside another piece's boundary.
    pub fn may_overlap(&self, positions: &[DVec2]) -> bool {
        let turned = self.triangles.iter().zip(&self.signs).any(|(t, &sign)| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            let o = geometry::orient(a, b, c);
            // (Turned over, flattened, or not a number.)
            sign != 0
                && (o * f64::from(sign)).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        });
        if turned {
            return true;
        }
        if self.boundary_crosses(positions) {
            return true;
        }
        if self.pieces.len() > 1 {
            // A vertex of each piece against the other pieces' boundaries (even-odd).
            for (k, &v) in self.pieces.iter().enumerate() {
                let p = positions[v as usize];
                let inside = |piece: u32| {
                    let mut crossings = 0u32;
                    for &([a, b], q) in &self.boundary {
                        if q != piece {
                            continue;
                        }
                        let (a, b) = (positions[a as usize], positions[b as usize]);
                        if (a.y > p.y) != (b.y > p.y) {
                            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                            crossings += u32::from(x > p.x);
                        }
                    }
                    crossings % 2 == 1
                };
                if (0..self.pieces.len() as u32).any(|q| q != k as u32 && inside(q)) {
                    return true;
                }
            }
        }
        false
    }

    /// Whether two boundary edges that share no vertex cross or touch (a grid over
    /// their boxes).
    fn boundary_crosses(&self, positions: &[DVec2]) -> bool {
        let edges = &self.boundary;
        if edges.len() < 2 {
            return false;
        }
        let ends = |e: usize| {
            let [a, b] = edges[e].0;
            (positions[a as usize], positions[b as usize])
        };
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        let mut total = 0.0;
        for e in 0..edges.len() {
            let (a, b) = ends(e);
            lo = lo.min(a).min(b);
            hi = hi.max(a).max(b);
            total += (b - a).length();
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return true;
        }
        let span = (hi - lo).max(DVec2::splat(1e-9));
        let cell = (total / edges.len() as f64)
            .max((span.x * span.y / (4.0 * edges.len() as f64)).sqrt())
            .max(1e-9);
        let columns = (span.x / cell) as usize + 1;
        let rows = (span.y / cell) as usize + 1;
        let at = |p: DVec2| {
            let q = (p - lo) / cell;
            (
                (q.x as usize).min(columns - 1),
                (q.y as usize).min(rows - 1),
            )
        };
        let mut cells: Vec<Vec<u32>> = vec![Vec::new(); columns * rows];
        for e in 0..edges.len() {
            let (a, b) = ends(e);
            let ((x0, y0), (x1, y1)) = (at(a.min(b)), at(a.max(b)));
            for y in y0..=y1 {
                for x in x0..=x1 {
                    cells[y * columns + x].push(e as u32);
                }
            }
        }
        cells.iter().any(|members| {
            members.iter().enumerate().any(|(i, &e)| {
                members[i + 1..].iter().any(|&f| {
                    let ([a, b], [c, d]) = (edges[e as usize].0, edges[f as usize].0);
                    if a == c || a == d || b == c || b == d {
                        return false;
                    }
                    let (p, q) = ends(e as usize);
                    let (r, s) = ends(f as usize);
                    geometry::segments_touch(p, q, r, s)
                })
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two unit squares side by side, as two pieces.
    fn squares(shift: f64) -> (Vec<DVec2>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        for dx in [0.0, shift] {
            positions.extend(
                [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
                    .map(|[x, y]| DVec2::new(x + dx, y)),
            );
        }
        let triangles = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        (positions, triangles)
    }

    #[test]
    fn overlaps_are_suspected_exactly_where_they_can_be() {
        let (apart, triangles) = squares(3.0);
        let topology = Topology::new(&apart, &triangles);
        assert_eq!(topology.pieces.len(), 2);
        assert_eq!(topology.boundary.len(), 8);
        assert!(!topology.may_overlap(&apart));
        // Crossing boundaries.
        let (half, _) = squares(0.5);
        assert!(topology.may_overlap(&half));
        // One piece wholly inside the other: no boundary crosses.
        let mut inside = apart.clone();
        for (k, p) in inside.iter_mut().enumerate() {
            *p = if k < 4 {
                *p * 10.0
            } else {
                *p - DVec2::new(3.0, 0.0) + DVec2::splat(4.0)
            };
        }
        assert!(topology.may_overlap(&inside));
        // A triangle turned over.
        let mut turned = apart.clone();
        turned[2] = DVec2::new(-1.0, -1.0);
        assert!(topology.may_overlap(&turned));
    }
}
