//! Registration (§4.3, step 1): everything that depends on the rest mesh alone.

use std::sync::Arc;

use glam::DVec2;

use crate::error::ArapError;
use crate::solver::{LowerPattern, amd_order};
use crate::topology::Topology;
use crate::triangle::{fitting_coefficients, is_degenerate, step_one_matrix};

/// The rest mesh with what the paper computes once per rest shape ("registration",
/// §4.3 step 1): each triangle's share of step one's error matrix `G` (eq. 5), from
/// the local coordinates `(x, y)` of every corner in the frame of the opposite edge,
/// and each triangle's fitting matrix `F` of step two (eq. 11), inverted; also a
/// fill-reducing order of the vertices for the factorisations.
///
/// Positions are in any consistent unit (image pixels in C2Warp); nothing depends on
/// where the origin is.
///
/// Triangles whose rest corners span no area (a repeated vertex, coincident or
/// collinear corners; see [`Registration::skipped_triangles`]) are left out of both
/// steps: they have no local frame. A vertex that no kept triangle uses stays at rest
/// unless it is constrained.
///
/// Cloning is cheap (the data is shared).
///
/// ```
/// use arap::Registration;
/// use glam::DVec2;
///
/// // A unit square split into two triangles.
/// let rest = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)];
/// let registration = Registration::new(&rest, &[[0, 1, 2], [0, 2, 3]])?;
/// assert_eq!(registration.vertex_count(), 4);
/// # Ok::<(), arap::ArapError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Registration {
    pub(crate) mesh: Arc<Mesh>,
}

/// The registered rest mesh, shared by every compiled system built from it.
#[derive(Debug)]
pub(crate) struct Mesh {
    pub rest: Vec<DVec2>,
    pub triangles: Vec<[u32; 3]>,
    /// Whether each triangle takes part (is not degenerate).
    pub kept: Vec<bool>,
    pub skipped: Vec<u32>,
    /// Step one's error matrix of each triangle, see
    /// [`crate::triangle::step_one_matrix`].
    pub step_one: Vec<[f64; 9]>,
    /// Step two's fitting (`F⁻¹` folded with `C`'s map) as two complex
    /// coefficients, see [`crate::triangle::fitting_coefficients`].
    pub fit: Vec<[DVec2; 2]>,
    pub topology: Topology,
    /// A fill-reducing order of all vertices (approximate minimum degree on the
    /// mesh graph): compilation numbers the free vertices in this order.
    pub order: Vec<u32>,
    /// Two rest positions closer than this count as one point when deciding whether
    /// step one's similarity is pinned down.
    pub tolerance: f64,
}

/// Approximate minimum degree on the whole mesh graph. A compiled system's free
/// vertices are a subset, numbered in this order: removing the constrained vertices
/// (and any component left at rest) from a graph keeps this a good order for what
/// remains, and one ordering per mesh spares every compilation its own.
fn vertex_order(topology: &Topology) -> Result<Vec<u32>, ArapError> {
    let adjacency = &topology.adjacency;
    let n = adjacency.len();
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    for v in 0..n {
        row_idx.extend(adjacency.row(v).iter().filter(|&&u| u as usize >= v));
        col_ptr.push(row_idx.len() as u32);
    }
    amd_order(&LowerPattern {
        n,
        col_ptr,
        row_idx,
    })
}

impl Registration {
    /// Registers a rest mesh: `rest[i]` is vertex `i`'s position, each triangle names
    /// three vertices. Either orientation is accepted, also mixed.
    ///
    /// # Errors
    /// [`ArapError::NonFiniteRest`] for a NaN or infinite position,
    /// [`ArapError::TriangleVertexOutOfRange`] for a triangle naming a vertex past the
    /// end, [`ArapError::TooManyVertices`] past `u32::MAX` vertices.
    pub fn new(rest: &[DVec2], triangles: &[[u32; 3]]) -> Result<Self, ArapError> {
        if rest.len() > u32::MAX as usize {
            return Err(ArapError::TooManyVertices {
                vertices: rest.len(),
            });
        }
        if let Some(vertex) = rest.iter().position(|p| !p.is_finite()) {
            return Err(ArapError::NonFiniteRest { vertex });
        }
        for (triangle, tri) in triangles.iter().enumerate() {
            if let Some(&vertex) = tri.iter().find(|&&v| v as usize >= rest.len()) {
                return Err(ArapError::TriangleVertexOutOfRange {
                    triangle,
                    vertex,
                    vertices: rest.len(),
                });
            }
        }
        let corners = |tri: &[u32; 3]| tri.map(|v| rest[v as usize]);
        let mut kept = Vec::with_capacity(triangles.len());
        let mut step_one = Vec::with_capacity(triangles.len());
        let mut fit = Vec::with_capacity(triangles.len());
        let mut skipped = Vec::new();
        for (t, tri) in triangles.iter().enumerate() {
            let p = corners(tri);
            let matrix = if is_degenerate(p) {
                None
            } else {
                fitting_coefficients(p)
            };
            match matrix {
                Some(m) => {
                    kept.push(true);
                    step_one.push(step_one_matrix(p));
                    fit.push(m);
                }
                None => {
                    kept.push(false);
                    skipped.push(t as u32);
                    step_one.push([0.0; 9]);
                    fit.push([DVec2::ZERO; 2]);
                }
            }
        }
        let topology = Topology::new(rest.len(), triangles, &kept);
        let order = vertex_order(&topology)?;
        let (lo, hi) = rest.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let diagonal = if rest.is_empty() {
            0.0
        } else {
            (hi - lo).length()
        };
        Ok(Self {
            mesh: Arc::new(Mesh {
                rest: rest.to_vec(),
                triangles: triangles.to_vec(),
                kept,
                skipped,
                step_one,
                order,
                fit,
                topology,
                tolerance: 1e-9 * diagonal,
            }),
        })
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.mesh.rest.len()
    }

    /// Number of triangles, skipped ones included (rigidity lists have this length).
    pub fn triangle_count(&self) -> usize {
        self.mesh.triangles.len()
    }

    /// The rest positions.
    pub fn rest(&self) -> &[DVec2] {
        &self.mesh.rest
    }

    /// The triangles as given.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.mesh.triangles
    }

    /// Triangles left out because their rest corners span no area (twice the area at
    /// most `1e-12` times the longest edge squared), in increasing order.
    pub fn skipped_triangles(&self) -> &[u32] {
        &self.mesh.skipped
    }

    /// The vertices that share a kept triangle with `vertex` (its one-ring), in
    /// increasing order, without `vertex` itself.
    ///
    /// # Errors
    /// [`ArapError::VertexOutOfRange`] if there is no such vertex.
    pub fn neighbours(&self, vertex: u32) -> Result<Vec<u32>, ArapError> {
        self.check_vertex(vertex)?;
        Ok(self
            .mesh
            .topology
            .adjacency
            .row(vertex as usize)
            .iter()
            .copied()
            .filter(|&v| v != vertex)
            .collect())
    }

    pub(crate) fn check_vertex(&self, vertex: u32) -> Result<(), ArapError> {
        if (vertex as usize) < self.mesh.rest.len() {
            Ok(())
        } else {
            Err(ArapError::VertexOutOfRange {
                vertex,
                vertices: self.mesh.rest.len(),
            })
        }
    }
}
