//! The mesh's connectivity, kept apart from its geometry: vertex adjacency (the
//! sparsity pattern of both steps' matrices), connected components, and the
//! edge-connected pieces that decide where step one is determined.

/// Compressed rows: row `r` is `items[ptr[r]..ptr[r + 1]]`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Rows<T> {
    pub ptr: Vec<u32>,
    pub items: Vec<T>,
}

impl<T: Copy + Default> Rows<T> {
    /// Row `r`.
    #[inline]
    pub fn row(&self, r: usize) -> &[T] {
        &self.items[self.ptr[r] as usize..self.ptr[r + 1] as usize]
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.ptr.len().saturating_sub(1)
    }

    /// Builds rows from `(row, item)` pairs with a counting sort; within a row, items
    /// keep the order they were given in.
    pub fn from_pairs(rows: usize, pairs: impl Iterator<Item = (u32, T)> + Clone) -> Self {
        let mut count = vec![0u32; rows + 1];
        for (r, _) in pairs.clone() {
            count[r as usize + 1] += 1;
        }
        for r in 0..rows {
            count[r + 1] += count[r];
        }
        let ptr = count.clone();
        let total = ptr[rows] as usize;
        let mut items = vec![T::default(); total];
        let mut next = count;
        for (r, item) in pairs {
            let at = &mut next[r as usize];
            items[*at as usize] = item;
            *at += 1;
        }
        Self { ptr, items }
    }
}

/// Union–find with path halving and union by size.
pub(crate) struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    pub fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let grand = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = grand;
            x = grand;
        }
        x
    }

    pub fn union(&mut self, a: u32, b: u32) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a as usize] < self.size[b as usize] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b as usize] = a;
        self.size[a as usize] += self.size[b as usize];
    }

    /// Dense labels `0..count` for the sets, numbered by first appearance.
    pub fn labels(&mut self) -> (Vec<u32>, usize) {
        let n = self.parent.len();
        let mut label = vec![u32::MAX; n];
        let mut out = vec![0u32; n];
        let mut count = 0u32;
        for x in 0..n as u32 {
            let r = self.find(x) as usize;
            if label[r] == u32::MAX {
                label[r] = count;
                count += 1;
            }
            out[x as usize] = label[r];
        }
        (out, count as usize)
    }
}

/// Connectivity of the non-degenerate triangles.
#[derive(Clone, Debug, Default)]
pub(crate) struct Topology {
    /// For each vertex, its neighbours through the kept triangles and itself, sorted.
    /// A vertex in no kept triangle has only itself.
    pub adjacency: Rows<u32>,
    /// For each kept triangle (others: unused), the adjacency slot of each ordered
    /// pair of its corners: `slots[t][3 * a + b]` is where `(tri[a], tri[b])` lives.
    pub slots: Vec<[u32; 9]>,
    /// Connected component of each vertex (through kept triangles; a vertex in none is
    /// a component of its own).
    pub component: Vec<u32>,
    /// Edge-connected piece of each kept triangle (`u32::MAX` for skipped ones):
    /// triangles sharing an edge are in one piece, triangles sharing only a vertex may
    /// not be.
    pub piece: Vec<u32>,
    /// The vertices of each piece.
    pub piece_vertices: Rows<u32>,
    /// The pieces at each vertex.
    pub vertex_pieces: Rows<u32>,
}

impl Topology {
    /// `kept[t]` says whether triangle `t` takes part.
    pub fn new(vertices: usize, triangles: &[[u32; 3]], kept: &[bool]) -> Self {
        let kept_triangles = || {
            triangles
                .iter()
                .enumerate()
                .filter(move |(t, _)| kept[*t])
                .map(|(t, tri)| (t as u32, tri))
        };
        // Adjacency: every ordered pair of corners, plus the diagonal.
        let pairs = kept_triangles()
            .flat_map(|(_, tri)| (0..9).map(move |k| (tri[k / 3], tri[k % 3])))
            .chain((0..vertices as u32).map(|v| (v, v)));
        let mut adjacency = Rows::from_pairs(vertices, pairs);
        // Sort and deduplicate each row in place, then compact.
        let mut write = 0usize;
        let mut new_ptr = Vec::with_capacity(vertices + 1);
        new_ptr.push(0u32);
        for v in 0..vertices {
            let (s, e) = (adjacency.ptr[v] as usize, adjacency.ptr[v + 1] as usize);
            adjacency.items[s..e].sort_unstable();
            let mut last = u32::MAX;
            for i in s..e {
                let x = adjacency.items[i];
                if x != last {
                    adjacency.items[write] = x;
                    write += 1;
                    last = x;
                }
            }
            new_ptr.push(write as u32);
        }
        adjacency.items.truncate(write);
        adjacency.ptr = new_ptr;

        let slot_of = |a: u32, b: u32| -> u32 {
            let row = adjacency.row(a as usize);
            let at = row.binary_search(&b).unwrap_or_default();
            adjacency.ptr[a as usize] + at as u32
        };
        let mut slots = vec![[0u32; 9]; triangles.len()];
        for (t, tri) in kept_triangles() {
            for k in 0..9 {
                slots[t as usize][k] = slot_of(tri[k / 3], tri[k % 3]);
            }
        }

        // The corners `3 * triangle + corner` of kept triangles at each vertex.
        let corners = Rows::from_pairs(
            vertices,
            kept_triangles().flat_map(|(t, tri)| (0..3).map(move |c| (tri[c], 3 * t + c as u32))),
        );

        let mut vertex_sets = UnionFind::new(vertices);
        for (_, tri) in kept_triangles() {
            vertex_sets.union(tri[0], tri[1]);
            vertex_sets.union(tri[1], tri[2]);
        }
        let (component, _) = vertex_sets.labels();

        // Pieces: the first triangle seen on each (undirected) edge, keyed by the
        // edge's slot from its smaller end.
        let mut first_on_edge = vec![u32::MAX; adjacency.items.len()];
        let mut triangle_sets = UnionFind::new(triangles.len());
        for (t, tri) in kept_triangles() {
            for c in 0..3 {
                let (a, b) = (tri[c], tri[(c + 1) % 3]);
                let key = if a < b {
                    slots[t as usize][3 * c + (c + 1) % 3]
                } else {
                    slots[t as usize][3 * ((c + 1) % 3) + c]
                } as usize;
                if first_on_edge[key] == u32::MAX {
                    first_on_edge[key] = t;
                } else {
                    triangle_sets.union(first_on_edge[key], t);
                }
            }
        }
        let (labels, _) = triangle_sets.labels();
        // Renumber the labels of kept triangles densely.
        let mut renumber = vec![u32::MAX; triangles.len()];
        let mut pieces = 0u32;
        let mut piece = vec![u32::MAX; triangles.len()];
        for (t, _) in kept_triangles() {
            let l = labels[t as usize] as usize;
            if renumber[l] == u32::MAX {
                renumber[l] = pieces;
                pieces += 1;
            }
            piece[t as usize] = renumber[l];
        }
        // Pieces at each vertex, from its corners, deduplicated.
        let mut vertex_pieces_pairs: Vec<(u32, u32)> = Vec::new();
        let mut scratch: Vec<u32> = Vec::new();
        for v in 0..vertices {
            scratch.clear();
            scratch.extend(corners.row(v).iter().map(|&c| piece[(c / 3) as usize]));
            scratch.sort_unstable();
            scratch.dedup();
            vertex_pieces_pairs.extend(scratch.iter().map(|&p| (v as u32, p)));
        }
        let vertex_pieces = Rows::from_pairs(vertices, vertex_pieces_pairs.iter().copied());
        let piece_vertices = Rows::from_pairs(
            pieces as usize,
            vertex_pieces_pairs.iter().map(|&(v, p)| (p, v)),
        );
        Self {
            adjacency,
            slots,
            component,
            piece,
            piece_vertices,
            vertex_pieces,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bowtie_has_one_component_and_two_pieces() {
        // Two triangles sharing vertex 2 only, and an isolated vertex 5.
        let tris = [[0, 1, 2], [2, 3, 4]];
        let t = Topology::new(6, &tris, &[true, true]);
        assert_eq!(t.component[0], t.component[4]);
        assert_ne!(t.component[0], t.component[5]);
        assert_ne!(t.piece[0], t.piece[1]);
        assert_eq!(t.vertex_pieces.row(2).len(), 2);
        assert_eq!(t.adjacency.row(5), &[5]);
        assert_eq!(t.adjacency.row(2), &[0, 1, 2, 3, 4]);
        for (tri, slots) in tris.iter().zip(&t.slots) {
            for k in 0..9 {
                assert_eq!(t.adjacency.items[slots[k] as usize], tri[k % 3]);
            }
        }
    }

    #[test]
    fn triangles_sharing_an_edge_are_one_piece() {
        let tris = [[0, 1, 2], [2, 1, 3], [5, 6, 7]];
        let t = Topology::new(8, &tris, &[true, true, false]);
        assert_eq!(t.piece[0], t.piece[1]);
        assert_eq!(t.piece[2], u32::MAX);
        assert_eq!(t.piece_vertices.row(t.piece[0] as usize), &[0, 1, 2, 3]);
        assert_eq!(t.vertex_pieces.row(5).len(), 0);
    }
}
