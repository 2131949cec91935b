//! Point handles that turn and scale: the paper's handles are vertices and carry only
//! a position, so a handle's rotation and scale are given to the method by pinning
//! its neighbours too.

use geometry::Similarity;
use glam::DVec2;

use crate::error::ArapError;
use crate::registration::Registration;

/// Constraints that give a point handle on `vertex` a rotation and scale: the vertex
/// itself and its one-ring (every vertex sharing a kept triangle with it), each sent
/// where `similarity` about the vertex's rest position takes it. The handle vertex
/// comes first, then its neighbours in increasing order.
///
/// Intended use: the paper's handles are single vertices and know no rotation or
/// scale. For a handle that has them, constrain the ring instead of the vertex alone:
/// compile once with the returned vertices (they depend only on the mesh, so a drag
/// does not recompile), and on every pose pass the returned targets. A small ring
/// turns the surroundings with the handle as a bone's end would; a large rotation of
/// a ring on a coarse mesh folds the triangles right outside it, as any pinned region
/// would. Rings of two handles must not share vertices (compilation refuses
/// duplicates); [`similarity_constraints`] takes any neighbour set.
///
/// ```
/// use arap::{Registration, Similarity, ring_constraints};
/// use glam::DVec2;
///
/// let rest: Vec<DVec2> = (0..25).map(|i| DVec2::new((i % 5) as f64, (i / 5) as f64)).collect();
/// let mut triangles = Vec::new();
/// for y in 0..4u32 {
///     for x in 0..4u32 {
///         let v = y * 5 + x;
///         triangles.extend([[v, v + 1, v + 6], [v, v + 6, v + 5]]);
///     }
/// }
/// let registration = Registration::new(&rest, &triangles)?;
/// let turn = Similarity { translation: DVec2::new(0.5, 0.0), rotation: 0.3, scale: 1.0 };
/// let pins = ring_constraints(&registration, 12, &turn)?; // the centre vertex and its ring
/// let (vertices, targets): (Vec<u32>, Vec<DVec2>) = pins.into_iter().unzip();
/// let compiled = registration.compile(&vertices, None)?;
/// let pose = compiled.update(&targets)?;
/// assert_eq!(pose.positions[12], DVec2::new(2.5, 2.0));
/// # Ok::<(), arap::ArapError>(())
/// ```
///
/// # Errors
/// [`ArapError::VertexOutOfRange`] for a vertex that does not exist,
/// [`ArapError::NonFiniteSimilarity`] for a NaN or infinite component.
pub fn ring_constraints(
    registration: &Registration,
    vertex: u32,
    similarity: &Similarity,
) -> Result<Vec<(u32, DVec2)>, ArapError> {
    let ring = registration.neighbours(vertex)?;
    similarity_constraints(registration, vertex, &ring, similarity)
}

/// Constraints sending `vertex` and each of `neighbours` where `similarity` about the
/// rest position of `vertex` takes them: [`ring_constraints`] with a neighbour set of
/// the caller's choice (a two-ring, or the vertices within some radius). `vertex`
/// comes first; a neighbour equal to `vertex` is left out.
///
/// # Errors
/// [`ArapError::VertexOutOfRange`] for a vertex that does not exist,
/// [`ArapError::NonFiniteSimilarity`] for a NaN or infinite component.
pub fn similarity_constraints(
    registration: &Registration,
    vertex: u32,
    neighbours: &[u32],
    similarity: &Similarity,
) -> Result<Vec<(u32, DVec2)>, ArapError> {
    registration.check_vertex(vertex)?;
    for &v in neighbours {
        registration.check_vertex(v)?;
    }
    if !similarity.is_finite() {
        return Err(ArapError::NonFiniteSimilarity);
    }
    let rest = registration.rest();
    let centre = rest[vertex as usize];
    Ok(std::iter::once(vertex)
        .chain(neighbours.iter().copied().filter(|&v| v != vertex))
        .map(|v| (v, similarity.apply_rotating_first(centre, rest[v as usize])))
        .collect())
}
