//! A sparse LDLᵀ factorisation of a symmetric positive definite matrix (the harmonic
//! system of the virtual handles), with a nested-dissection ordering found by
//! coordinate bisection of the unknowns' positions.
//!
//! The factorisation is the row-by-row ("up-looking") one of T. A. Davis's LDL
//! package: the elimination tree gives each row's pattern, so the work is the
//! flops of the factor. Ordered by nested dissection, a planar graph of n unknowns
//! fills to O(n log n) entries, so one factorisation and many solves cost far less
//! than an iterative solve per right-hand side.

use glam::DVec2;

const NONE: u32 = u32::MAX;

/// At most this many unknowns are ordered as they come rather than dissected further.
const LEAF: usize = 32;

/// A nested-dissection ordering of the graph `adjacency` on `points`: each set is cut
/// at the median of its longer extent, the samples of the upper half with a
/// neighbour in the lower half form the separator, and it is numbered after both
/// halves. Returns the unknowns in elimination order.
pub(crate) fn dissection_order(points: &[DVec2], adjacency: &[Vec<(u32, f64)>]) -> Vec<u32> {
    let n = points.len();
    let mut order = Vec::with_capacity(n);
    let mut mark = vec![0u32; n];
    let mut tag = 0u32;
    // Sets to dissect, with the separators waiting to be numbered after them: an
    // explicit stack of (set, separator to emit once the set is done).
    enum Task {
        Dissect(Vec<u32>),
        Emit(Vec<u32>),
    }
    let mut stack = vec![Task::Dissect((0..n as u32).collect())];
    while let Some(task) = stack.pop() {
        let mut set = match task {
            Task::Emit(separator) => {
                order.extend(separator);
                continue;
            }
            Task::Dissect(set) => set,
        };
        if set.len() <= LEAF {
            order.extend(set);
            continue;
        }
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &v in &set {
            lo = lo.min(points[v as usize]);
            hi = hi.max(points[v as usize]);
        }
        let axis = usize::from(hi.y - lo.y > hi.x - lo.x);
        set.sort_unstable_by(|&a, &b| {
            points[a as usize][axis]
                .total_cmp(&points[b as usize][axis])
                .then(a.cmp(&b))
        });
        let mid = set.len() / 2;
        tag += 1;
        for &v in &set[..mid] {
            mark[v as usize] = tag;
        }
        let mut upper = Vec::with_capacity(set.len() - mid);
        let mut separator = Vec::new();
        for &v in &set[mid..] {
            if adjacency[v as usize]
                .iter()
                .any(|&(u, _)| mark[u as usize] == tag)
            {
                separator.push(v);
            } else {
                upper.push(v);
            }
        }
        set.truncate(mid);
        // Popped in reverse: the lower half, the upper half, then the separator.
        stack.push(Task::Emit(separator));
        stack.push(Task::Dissect(upper));
        stack.push(Task::Dissect(set));
    }
    order
}

/// L D Lᵀ of a symmetric positive definite matrix, in a given elimination order.
pub(crate) struct Ldl {
    /// Column starts of the strictly lower factor L (unit diagonal not stored).
    col_start: Vec<usize>,
    /// Row (in elimination order) of each entry of L.
    rows: Vec<u32>,
    /// Value of each entry of L.
    values: Vec<f64>,
    /// The diagonal D.
    diag: Vec<f64>,
    /// Unknown eliminated `k`-th.
    order: Vec<u32>,
    /// When each unknown is eliminated.
    position: Vec<u32>,
}

impl Ldl {
    /// Factors the matrix with diagonal `diagonal` and off-diagonal entries `−w` for
    /// every `(j, w)` in `adjacency[i]` (symmetric), eliminating in `order`. `None` if a
    /// pivot is not positive (the matrix is not positive definite).
    pub(crate) fn factor(
        diagonal: &[f64],
        adjacency: &[Vec<(u32, f64)>],
        order: Vec<u32>,
    ) -> Option<Self> {
        let n = diagonal.len();
        let mut position = vec![0u32; n];
        for (k, &v) in order.iter().enumerate() {
            position[v as usize] = k as u32;
        }
        // Column k of the permuted matrix above the diagonal: (row < k, value).
        let upper = |k: usize| {
            adjacency[order[k] as usize]
                .iter()
                .map(|&(j, w)| (position[j as usize], -w))
                .filter(move |&(i, _)| (i as usize) < k)
        };
        // Elimination tree and column counts.
        let mut parent = vec![NONE; n];
        let mut flag = vec![NONE; n];
        let mut count = vec![0usize; n];
        for k in 0..n {
            flag[k] = k as u32;
            for (i, _) in upper(k) {
                let mut i = i as usize;
                while flag[i] != k as u32 {
                    if parent[i] == NONE {
                        parent[i] = k as u32;
                    }
                    count[i] += 1;
                    flag[i] = k as u32;
                    i = parent[i] as usize;
                }
            }
        }
        let mut col_start = Vec::with_capacity(n + 1);
        col_start.push(0);
        for k in 0..n {
            col_start.push(col_start[k] + count[k]);
        }
        let total = col_start[n];
        let mut rows = vec![0u32; total];
        let mut values = vec![0.0; total];
        let mut diag = vec![0.0; n];
        let mut filled = vec![0usize; n];
        let mut y = vec![0.0; n];
        let mut pattern = vec![0u32; n];
        flag.fill(NONE);
        for k in 0..n {
            // Row k's pattern (the reach of column k's entries in the tree), top first.
            let mut top = n;
            flag[k] = k as u32;
            y[k] = 0.0;
            for (i, a) in upper(k) {
                let mut i = i as usize;
                y[i] += a;
                let mut len = 0;
                while flag[i] != k as u32 {
                    pattern[len] = i as u32;
                    len += 1;
                    flag[i] = k as u32;
                    i = parent[i] as usize;
                }
                while len > 0 {
                    top -= 1;
                    len -= 1;
                    pattern[top] = pattern[len];
                }
            }
            let mut d = diagonal[order[k] as usize];
            for &i in &pattern[top..n] {
                let i = i as usize;
                let yi = y[i];
                y[i] = 0.0;
                let (start, end) = (col_start[i], col_start[i] + filled[i]);
                for p in start..end {
                    y[rows[p] as usize] -= values[p] * yi;
                }
                let l = yi / diag[i];
                d -= l * yi;
                rows[end] = k as u32;
                values[end] = l;
                filled[i] += 1;
            }
            if d.is_nan() || d <= 0.0 {
                return None;
            }
            diag[k] = d;
        }
        Some(Self {
            col_start,
            rows,
            values,
            diag,
            order,
            position,
        })
    }

    /// Number of unknowns.
    pub(crate) fn len(&self) -> usize {
        self.diag.len()
    }

    /// Stored entries of L.
    #[cfg(test)]
    pub(crate) fn fill(&self) -> usize {
        self.values.len()
    }

    /// Solves `A x = b` for `b` given as `(unknown, value)` pairs (repeats add up),
    /// into `x` (length [`Ldl::len`]); `work` is scratch of the same length. (The
    /// reference that [`Ldl::solve_block`], which the crate uses, is tested against.)
    #[cfg(test)]
    pub(crate) fn solve(&self, b: &[(u32, f64)], x: &mut [f64], work: &mut [f64]) {
        let n = self.len();
        let y = work;
        y.fill(0.0);
        let mut position = n;
        // Only the columns from the first non-zero of the permuted b on take part in
        // the forward solve.
        for &(i, v) in b {
            let k = self.position[i as usize] as usize;
            y[k] += v;
            position = position.min(k);
        }
        for j in position..n {
            let yj = y[j];
            if yj != 0.0 {
                for p in self.col_start[j]..self.col_start[j + 1] {
                    y[self.rows[p] as usize] -= self.values[p] * yj;
                }
            }
        }
        for (yj, d) in y.iter_mut().zip(&self.diag) {
            *yj /= d;
        }
        for j in (0..n).rev() {
            let mut s = y[j];
            for p in self.col_start[j]..self.col_start[j + 1] {
                s -= self.values[p] * y[self.rows[p] as usize];
            }
            y[j] = s;
        }
        for (k, &v) in self.order.iter().enumerate() {
            x[v as usize] = y[k];
        }
    }

    /// As [`Ldl::solve`] for up to [`BLOCK`] right-hand sides at once (`x[v][r]` for
    /// the r-th): one pass over the factor serves them all, and each gets exactly the
    /// values [`Ldl::solve`] would give it.
    pub(crate) fn solve_block(
        &self,
        bs: &[&[(u32, f64)]],
        x: &mut [[f64; BLOCK]],
        work: &mut [[f64; BLOCK]],
    ) {
        debug_assert!(bs.len() <= BLOCK);
        let n = self.len();
        let y = work;
        y.fill([0.0; BLOCK]);
        let mut position = n;
        for (r, b) in bs.iter().enumerate() {
            for &(i, v) in *b {
                let k = self.position[i as usize] as usize;
                y[k][r] += v;
                position = position.min(k);
            }
        }
        for j in position..n {
            let yj = y[j];
            if yj != [0.0; BLOCK] {
                let (start, end) = (self.col_start[j], self.col_start[j + 1]);
                for (&i, &value) in self.rows[start..end].iter().zip(&self.values[start..end]) {
                    let row = &mut y[i as usize];
                    for r in 0..BLOCK {
                        row[r] -= value * yj[r];
                    }
                }
            }
        }
        for (yj, d) in y.iter_mut().zip(&self.diag) {
            for v in yj.iter_mut() {
                *v /= d;
            }
        }
        for j in (0..n).rev() {
            let mut s = y[j];
            let (start, end) = (self.col_start[j], self.col_start[j + 1]);
            for (&i, &value) in self.rows[start..end].iter().zip(&self.values[start..end]) {
                let row = y[i as usize];
                for r in 0..BLOCK {
                    s[r] -= value * row[r];
                }
            }
            y[j] = s;
        }
        for (k, &v) in self.order.iter().enumerate() {
            x[v as usize] = y[k];
        }
    }
}

/// Right-hand sides [`Ldl::solve_block`] takes at once.
pub(crate) const BLOCK: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;

    /// The Laplacian of an nx × ny grid plus `shift` on the diagonal, as adjacency.
    fn grid(nx: usize, ny: usize) -> (Vec<DVec2>, Vec<Vec<(u32, f64)>>) {
        let id = |i: usize, j: usize| (j * nx + i) as u32;
        let mut points = Vec::new();
        let mut adjacency = vec![Vec::new(); nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                points.push(DVec2::new(i as f64, j as f64));
                if i + 1 < nx {
                    adjacency[id(i, j) as usize].push((id(i + 1, j), 1.0));
                    adjacency[id(i + 1, j) as usize].push((id(i, j), 1.0));
                }
                if j + 1 < ny {
                    adjacency[id(i, j) as usize].push((id(i, j + 1), 0.5));
                    adjacency[id(i, j + 1) as usize].push((id(i, j), 0.5));
                }
            }
        }
        (points, adjacency)
    }

    #[test]
    fn solves_a_grid_laplacian_to_rounding() {
        let (points, adjacency) = grid(60, 45);
        let n = points.len();
        // Diagonally dominant: the row sums plus a little (edges to fixed values).
        let diagonal: Vec<f64> = adjacency
            .iter()
            .enumerate()
            .map(|(i, a)| a.iter().map(|e| e.1).sum::<f64>() + if i % 97 == 0 { 1.0 } else { 0.0 })
            .collect();
        let order = dissection_order(&points, &adjacency);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n as u32).collect::<Vec<_>>(), "a permutation");
        let ldl = Ldl::factor(&diagonal, &adjacency, order).expect("positive definite");
        // Nested dissection keeps the fill far below the dense n²/2.
        assert!(ldl.fill() < 40 * n, "fill {}", ldl.fill());
        let b = [(5u32, 1.0), (1000, 2.0), (5, 0.5)];
        let (mut x, mut work) = (vec![0.0; n], vec![0.0; n]);
        ldl.solve(&b, &mut x, &mut work);
        let mut dense_b = vec![0.0; n];
        for &(i, v) in &b {
            dense_b[i as usize] += v;
        }
        for i in 0..n {
            let ax = diagonal[i] * x[i]
                - adjacency[i]
                    .iter()
                    .map(|&(j, w)| w * x[j as usize])
                    .sum::<f64>();
            assert!(
                (ax - dense_b[i]).abs() < 1e-12,
                "row {i}: {ax} vs {}",
                dense_b[i]
            );
        }
        // Blocks of right-hand sides give each exactly what a solve of its own gives.
        let others = [(7u32, 1.0), (2000, -0.5)];
        let bs: [&[(u32, f64)]; 3] = [&b, &others, &[(1500, 3.0)]];
        let mut block = vec![[0.0; BLOCK]; n];
        let mut block_work = vec![[0.0; BLOCK]; n];
        ldl.solve_block(&bs, &mut block, &mut block_work);
        for (r, rhs) in bs.iter().enumerate() {
            ldl.solve(rhs, &mut x, &mut work);
            for v in 0..n {
                assert_eq!(block[v][r].to_bits(), x[v].to_bits(), "right-hand side {r}");
            }
        }
    }
}
