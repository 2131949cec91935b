//! Compilation (§4.3, step 2): split the unknowns into free and constrained ones for
//! a given set of constrained vertices and rigidity weights, and factorise step one's
//! and step two's systems once.

use std::sync::Arc;

use faer::c64;
use glam::DVec2;
use rayon::prelude::*;

use crate::error::ArapError;
use crate::registration::{Mesh, Registration};
use crate::solver::{Cholesky, Complex, LowerPattern, Structure};

/// A system compiled for one set of constrained vertices (handles) and rigidity
/// weights: the paper's "compilation" (§4.3 step 2), a function from the handles'
/// positions to the deformed mesh. Build it with [`Registration::compile`]; pose it
/// with [`Compiled::update`] or [`Compiled::update_into`], which factorise nothing.
///
/// It is `Send + Sync` and shares the registration's data.
pub struct Compiled {
    pub(crate) mesh: Arc<Mesh>,
    pub(crate) constrained: Vec<u32>,
    /// Free vertices in the registration's fill-reducing order, which the factors
    /// keep: free unknown `i` is vertex `free[i]`.
    pub(crate) free: Vec<u32>,
    /// The constant part of step one's right-hand side (non-zero only where step
    /// one's similarity is not pinned down, see [`Compiled::loose_triangles`]).
    pub(crate) step_one_rhs: Vec<DVec2>,
    /// Couplings of free unknowns to constrained vertices.
    pub(crate) couplings: Vec<Coupling>,
    /// How a pose solves step one (eq. 8); `None` when nothing is free.
    pub(crate) step_one: Option<StepOne>,
    /// `H'` of eq. 16 (`m × m`, for x and y alike), factorised.
    pub(crate) step_two: Option<Cholesky<f64>>,
    /// Kept triangles in components that have a constraint: the per-triangle pass.
    pub(crate) triangles: Vec<PassTriangle>,
    pub(crate) loose: Vec<u32>,
}

/// Step one's solve `G'u = −Bq` (eq. 8) as a pose does it.
pub(crate) enum StepOne {
    /// Back-substitution with `G'`'s factor (`2m × 2m`, stored as the `m × m`
    /// Hermitian matrix whose real form it is).
    Substitution(Cholesky<Complex>),
    /// The paper's own way (§4.3, steps 2-1 and 3-1): `G'⁻¹B` formed at
    /// compilation, so that `u = base + Σⱼ columns[i·k + j]·qⱼ`, `k` the number of
    /// constrained vertices. `B`'s blocks are complex numbers, so each constraint
    /// contributes one complex column.
    Product {
        base: Vec<DVec2>,
        columns: Vec<Complex>,
    },
}

/// Step one uses [`StepOne::Product`] when the `k·m` entries of `G'⁻¹B` are at most
/// this fraction of the factor's: a pose then reads an eighth of what two
/// substitutions read, and compilation pays `k` extra substitutions at most a
/// quarter of the factor's size in number.
const PRODUCT_FRACTION: usize = 4;

/// A triangle of the per-triangle pass, laid out for it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PassTriangle {
    pub vertices: [u32; 3],
    /// Step two's fitting coefficients.
    pub fit: [DVec2; 2],
    /// Rest edges `v0 → v1` and `v1 → v2` times the rigidity weight.
    pub edges: [DVec2; 2],
    /// The rigidity weight.
    pub weight: f64,
    /// One over the rigidity weight (the energy's terms are the weighted edges'
    /// differences, squared, divided by the weight).
    pub inverse_weight: f64,
}

/// One block of `B` (eq. 8) and `D` (eq. 16): how free unknown `free` depends on the
/// position of constraint `constraint`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coupling {
    pub free: u32,
    pub constraint: u32,
    /// Step one's 2×2 block `p·I + q·R90` as the complex number `p − i·q`.
    pub g: Complex,
    /// Step two's scalar entry.
    pub h: f64,
}

impl std::fmt::Debug for Compiled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Compiled")
            .field("constrained", &self.constrained.len())
            .field("free", &self.free.len())
            .field("active_triangles", &self.triangles.len())
            .field("loose_triangles", &self.loose.len())
            .finish_non_exhaustive()
    }
}

impl Registration {
    /// Compiles the system for the vertices in `constrained` (the handles) with
    /// optional per-triangle `rigidity` weights (§5.2; the paper paints 10000 and
    /// uses 1 elsewhere; `None` means 1 everywhere). A weight multiplies its
    /// triangle's terms in step one and in step two's final solve. Targets are later
    /// given to [`Compiled::update`] in the order of `constrained`.
    ///
    /// Where the paper's systems would be singular, this defines the answer instead:
    /// - a connected component (through triangles) without any constrained vertex
    ///   stays at rest, and so does a vertex in no kept triangle unless constrained;
    /// - a component with a single constrained vertex translates with it (step one
    ///   and the final result alike);
    /// - more generally, step one's similarity error leaves each edge-connected piece
    ///   of the mesh free to turn and scale unless two vertices of the piece at
    ///   distinct rest positions are pinned down (constrained, or in a piece that is
    ///   pinned down, transitively). On pieces left loose that way (a component with
    ///   one handle, a flap hanging off the rest by a single vertex, handles that
    ///   share one rest position), step one also keeps each triangle's rest edges
    ///   (the step-two term with the rest shape as target), so they follow by
    ///   translation. Everywhere else the systems are exactly the paper's.
    ///   [`Compiled::loose_triangles`] lists them.
    ///
    /// Both systems are factorised here (faer's supernodal sparse Cholesky, one
    /// approximate-minimum-degree ordering for both). When the constrained vertices
    /// are few next to the mesh, step one is also solved for each of them, as the
    /// paper does (§4.3, 2-1: `G'⁻¹B`), so that a pose's step one is one product
    /// (3-1); otherwise a pose back-substitutes with `G'`'s factor. Either way a pose
    /// ([`Compiled::update`]) factorises nothing and back-substitutes once for step
    /// two, x and y together.
    ///
    /// # Errors
    /// [`ArapError::VertexOutOfRange`] for an index past the last vertex,
    /// [`ArapError::DuplicateConstraint`] for a vertex given twice,
    /// [`ArapError::RigidityLength`] / [`ArapError::BadRigidity`] for a rigidity list
    /// of the wrong length or with a weight that is not finite and positive.
    pub fn compile(
        &self,
        constrained: &[u32],
        rigidity: Option<&[f64]>,
    ) -> Result<Compiled, ArapError> {
        self.compile_with(constrained, rigidity, None)
    }

    /// [`Registration::compile`], choosing step one's way by size unless `product`
    /// says.
    pub(crate) fn compile_with(
        &self,
        constrained: &[u32],
        rigidity: Option<&[f64]>,
        product: Option<bool>,
    ) -> Result<Compiled, ArapError> {
        let mesh = &self.mesh;
        let n = mesh.rest.len();
        let topo = &mesh.topology;

        let mut constraint_of = vec![u32::MAX; n];
        for (i, &v) in constrained.iter().enumerate() {
            self.check_vertex(v)?;
            let slot = &mut constraint_of[v as usize];
            if *slot != u32::MAX {
                return Err(ArapError::DuplicateConstraint {
                    vertex: v,
                    first: *slot as usize,
                    second: i,
                });
            }
            *slot = i as u32;
        }
        if let Some(w) = rigidity {
            if w.len() != mesh.triangles.len() {
                return Err(ArapError::RigidityLength {
                    got: w.len(),
                    triangles: mesh.triangles.len(),
                });
            }
            if let Some((triangle, &weight)) = w
                .iter()
                .enumerate()
                .find(|(_, w)| !(w.is_finite() && **w > 0.0))
            {
                return Err(ArapError::BadRigidity { triangle, weight });
            }
        }
        let weight = |t: usize| rigidity.map_or(1.0, |w| w[t]);

        // Components that some constraint reaches; the others stay at rest.
        let components = topo
            .component
            .iter()
            .map(|&c| c as usize + 1)
            .max()
            .unwrap_or(0);
        let mut reached = vec![false; components];
        for &v in constrained {
            reached[topo.component[v as usize] as usize] = true;
        }

        let pinned = pinned_pieces(mesh, constrained);

        // Free unknowns: vertices of reached components that are not constrained,
        // numbered in the registration's fill-reducing order. (A reached vertex in
        // no kept triangle is a component of its own, reached only through its own
        // constraint.)
        let mut free_index = vec![u32::MAX; n];
        let mut free: Vec<u32> = Vec::new();
        for &v in &mesh.order {
            let v = v as usize;
            if constraint_of[v] == u32::MAX && reached[topo.component[v] as usize] {
                free_index[v] = free.len() as u32;
                free.push(v as u32);
            }
        }
        let m = free.len();

        // Per adjacency slot: step one's block (p, q) and step two's entry.
        let slots = topo.adjacency.items.len();
        let mut g = vec![(0.0, 0.0); slots];
        let mut h = vec![0.0; slots];
        let mut rest_pull = vec![DVec2::ZERO; n];
        let mut active = Vec::new();
        let mut loose = Vec::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            if !mesh.kept[t] || !reached[topo.component[tri[0] as usize] as usize] {
                continue;
            }
            active.push(t as u32);
            let w = weight(t);
            let s = &topo.slots[t];
            let is_loose = !pinned[topo.piece[t] as usize];
            if is_loose {
                loose.push(t as u32);
            }
            // Step one (eq. 5): the triangle's error matrix; on a loose piece also
            // the rest edges. Step two (eq. 13): each edge once from this side, so
            // 2 on the diagonal and −1 off it.
            let e = &mesh.step_one[t];
            let extra = if is_loose { w } else { 0.0 };
            for a in 0..3 {
                g[s[4 * a] as usize].0 += w * e[a] + 2.0 * extra;
                h[s[4 * a] as usize] += 2.0 * w;
            }
            for (a, b, p, q) in [(0, 1, e[3], e[4]), (1, 2, e[5], e[6]), (0, 2, e[7], e[8])] {
                let (ab, ba) = (s[3 * a + b] as usize, s[3 * b + a] as usize);
                g[ab].0 += w * p - extra;
                g[ab].1 += w * q;
                g[ba].0 += w * p - extra;
                g[ba].1 -= w * q;
                h[ab] -= w;
                h[ba] -= w;
            }
            if is_loose {
                for i in 0..3 {
                    let j = (i + 1) % 3;
                    let e = mesh.rest[tri[j] as usize] - mesh.rest[tri[i] as usize];
                    rest_pull[tri[i] as usize] -= w * e;
                    rest_pull[tri[j] as usize] += w * e;
                }
            }
        }

        // The lower triangles of G' and H' share one pattern (vertex pairs); G' is
        // stored as the Hermitian matrix whose real form it is (see solver.rs): its
        // block p·I + q·R90 at (a, b) is p − i·q, and the entry below the diagonal,
        // at (b, a), is the conjugate p + i·q.
        // Vertices are visited in mesh order (neighbours near in memory), each
        // free one filling its column; the columns are sorted by row afterwards.
        let mut col_ptr = vec![0u32; m + 1];
        let mut couplings = Vec::new();
        for (a, &fa) in free_index.iter().enumerate() {
            if fa == u32::MAX {
                continue;
            }
            let start = topo.adjacency.ptr[a] as usize;
            for (k, &b) in topo.adjacency.row(a).iter().enumerate() {
                let fb = free_index[b as usize];
                if fb != u32::MAX {
                    if fb >= fa {
                        col_ptr[fa as usize + 1] += 1;
                    }
                } else if constraint_of[b as usize] != u32::MAX {
                    let (p, q) = g[start + k];
                    couplings.push(Coupling {
                        free: fa,
                        constraint: constraint_of[b as usize],
                        g: Complex(DVec2::new(p, -q)),
                        h: h[start + k],
                    });
                }
            }
        }
        for i in 0..m {
            col_ptr[i + 1] += col_ptr[i];
        }
        let entries = col_ptr[m] as usize;
        let mut row_idx = vec![0u32; entries];
        let mut h_values = vec![0.0; entries];
        let mut g_values = vec![c64::new(0.0, 0.0); entries];
        let mut next = col_ptr.clone();
        for (a, &fa) in free_index.iter().enumerate() {
            if fa == u32::MAX {
                continue;
            }
            let start = topo.adjacency.ptr[a] as usize;
            for (k, &b) in topo.adjacency.row(a).iter().enumerate() {
                let fb = free_index[b as usize];
                if fb != u32::MAX && fb >= fa {
                    let at = next[fa as usize] as usize;
                    next[fa as usize] += 1;
                    let (p, q) = g[start + k];
                    row_idx[at] = fb;
                    h_values[at] = h[start + k];
                    g_values[at] = c64::new(p, q);
                }
            }
        }
        for c in 0..m {
            // Insertion sort: a column holds a handful of entries.
            let (lo, hi) = (col_ptr[c] as usize, col_ptr[c + 1] as usize);
            for i in lo + 1..hi {
                let mut j = i;
                while j > lo && row_idx[j - 1] > row_idx[j] {
                    row_idx.swap(j - 1, j);
                    h_values.swap(j - 1, j);
                    g_values.swap(j - 1, j);
                    j -= 1;
                }
            }
        }

        let (step_one, step_two) = if m == 0 {
            (None, None)
        } else {
            let pattern = LowerPattern {
                n: m,
                col_ptr,
                row_idx,
            };
            let structure = Structure::new(&pattern)?;
            let (one, two) = rayon::join(
                || Cholesky::<Complex>::new(&structure, &pattern, &g_values),
                || Cholesky::<f64>::new(&structure, &pattern, &h_values),
            );
            (Some(one?), Some(two?))
        };

        let step_one_rhs: Vec<DVec2> = free.iter().map(|&v| rest_pull[v as usize]).collect();
        let step_one = step_one.map(|factor| {
            let k = constrained.len();
            let small = (k * m).saturating_mul(PRODUCT_FRACTION) <= factor.len();
            if product.unwrap_or(small) {
                product_form(&factor, k, &couplings, &step_one_rhs)
            } else {
                StepOne::Substitution(factor)
            }
        });

        // The per-triangle pass of every update: fitting coefficients and the rest
        // edges 0 → 1, 1 → 2, weighted.
        let triangles = active
            .iter()
            .map(|&t| {
                let tri = mesh.triangles[t as usize];
                let r = tri.map(|v| mesh.rest[v as usize]);
                let w = weight(t as usize);
                PassTriangle {
                    vertices: tri,
                    fit: mesh.fit[t as usize],
                    edges: [w * (r[1] - r[0]), w * (r[2] - r[1])],
                    weight: w,
                    inverse_weight: 1.0 / w,
                }
            })
            .collect();

        Ok(Compiled {
            mesh: Arc::clone(mesh),
            constrained: constrained.to_vec(),
            free,
            step_one_rhs,
            couplings,
            step_one,
            step_two,
            triangles,
            loose,
        })
    }
}

/// `G'⁻¹B` and `G'⁻¹·(constant part)` by one substitution per constraint, the
/// constraints side by side.
fn product_form(
    factor: &Cholesky<Complex>,
    k: usize,
    couplings: &[Coupling],
    constant: &[DVec2],
) -> StepOne {
    let m = factor.n();
    let mut base = constant.to_vec();
    if base.iter().any(|p| *p != DVec2::ZERO) {
        factor.solve_in_place(&mut base, &mut Vec::new());
    }
    let solved: Vec<Vec<DVec2>> = (0..k)
        .into_par_iter()
        .map(|j| {
            let mut column = vec![DVec2::ZERO; m];
            for c in couplings.iter().filter(|c| c.constraint as usize == j) {
                column[c.free as usize] -= c.g.0;
            }
            factor.solve_in_place(&mut column, &mut Vec::new());
            column
        })
        .collect();
    let mut columns = vec![Complex(DVec2::ZERO); m * k];
    for (j, column) in solved.iter().enumerate() {
        for (i, &u) in column.iter().enumerate() {
            columns[i * k + j] = Complex(u);
        }
    }
    StepOne::Product { base, columns }
}

/// Which edge-connected pieces step one pins down: a piece is pinned once two of its
/// vertices at distinct rest positions are (constrained vertices are; every vertex of
/// a pinned piece is).
fn pinned_pieces(mesh: &Mesh, constrained: &[u32]) -> Vec<bool> {
    let topo = &mesh.topology;
    let pieces = topo.piece_vertices.len();
    let mut pinned = vec![false; pieces];
    let mut first: Vec<Option<DVec2>> = vec![None; pieces];
    let mut known = vec![false; mesh.rest.len()];
    let mut queue: Vec<u32> = Vec::new();
    for &v in constrained {
        known[v as usize] = true;
        queue.push(v);
    }
    while let Some(v) = queue.pop() {
        let at = mesh.rest[v as usize];
        for &p in topo.vertex_pieces.row(v as usize) {
            let p = p as usize;
            if pinned[p] {
                continue;
            }
            match first[p] {
                None => first[p] = Some(at),
                Some(f) if (at - f).length() > mesh.tolerance => {
                    pinned[p] = true;
                    for &u in topo.piece_vertices.row(p) {
                        if !known[u as usize] {
                            known[u as usize] = true;
                            queue.push(u);
                        }
                    }
                }
                Some(_) => {}
            }
        }
    }
    pinned
}

impl Compiled {
    /// The constrained vertices, in the order targets are given.
    pub fn constrained(&self) -> &[u32] {
        &self.constrained
    }

    /// Number of vertices of the mesh.
    pub fn vertex_count(&self) -> usize {
        self.mesh.rest.len()
    }

    /// Number of free unknowns (vertices solved for; `m` in the paper).
    pub fn free_count(&self) -> usize {
        self.free.len()
    }

    /// Triangles on which step one's similarity error alone would leave the shape
    /// free to turn and scale, and which step one therefore also holds to their rest
    /// edges (see [`Registration::compile`]); empty for an edge-connected mesh with
    /// two handles at distinct rest positions.
    pub fn loose_triangles(&self) -> &[u32] {
        &self.loose
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A jittered 6 × 5 grid.
    fn grid() -> (Vec<DVec2>, Vec<[u32; 3]>) {
        let mut rest = Vec::new();
        for j in 0..6 {
            for i in 0..7 {
                let wobble = ((i * 7 + j * 13) % 5) as f64 * 0.05;
                rest.push(DVec2::new(i as f64 + wobble, j as f64 - wobble));
            }
        }
        let mut triangles = Vec::new();
        for j in 0..5u32 {
            for i in 0..6u32 {
                let v = j * 7 + i;
                triangles.extend([[v, v + 1, v + 8], [v, v + 8, v + 7]]);
            }
        }
        (rest, triangles)
    }

    /// Step one by `G'⁻¹B` (the paper's way) and by back-substitution agree.
    #[test]
    fn product_and_substitution_agree() {
        let (rest, triangles) = grid();
        let registration = Registration::new(&rest, &triangles).expect("valid");
        let rigidity: Vec<f64> = (0..triangles.len()).map(|t| 1.0 + (t % 3) as f64).collect();
        for (constrained, targets) in [
            (
                vec![0u32, 41, 20],
                vec![
                    DVec2::new(-1.0, 0.5),
                    DVec2::new(7.0, 6.0),
                    DVec2::new(3.0, 2.0),
                ],
            ),
            (vec![17u32], vec![DVec2::new(4.0, -2.0)]),
        ] {
            let a = registration
                .compile_with(&constrained, Some(&rigidity), Some(true))
                .and_then(|c| c.update(&targets))
                .expect("poses");
            let b = registration
                .compile_with(&constrained, Some(&rigidity), Some(false))
                .and_then(|c| c.update(&targets))
                .expect("poses");
            for (p, q) in a
                .positions
                .iter()
                .zip(&b.positions)
                .chain(a.step_one.iter().zip(&b.step_one))
            {
                assert!((*p - *q).length() < 1e-10, "{p} vs {q}");
            }
        }
    }
}
