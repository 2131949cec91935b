//! The textured triangle mesh the rasteriser draws.

use glam::Vec2;

use crate::RenderError;

/// A textured triangle mesh, borrowed from whoever computed it.
///
/// Both position arrays use image-pixel coordinates: origin at the top-left
/// corner, x to the right, y down, and pixel `(x, y)` covering the square
/// `[x, x+1] × [y, y+1]`, so its centre is `(x + 0.5, y + 0.5)`.
///
/// * `rest[i]` is vertex `i`'s position in the **source** image (the texture
///   coordinate, in source pixels, not normalised).
/// * `deformed[i]` is vertex `i`'s position in the **output** image.
/// * `triangles` lists vertex indices, three per triangle, in any winding
///   (fold-overs are drawn too).
#[derive(Clone, Copy, Debug)]
pub struct WarpMesh<'a> {
    /// Source-image (texture) position of each vertex, in source pixels.
    pub rest: &'a [Vec2],
    /// Output-image position of each vertex, in output pixels.
    pub deformed: &'a [Vec2],
    /// Vertex indices of each triangle.
    pub triangles: &'a [[u32; 3]],
}

impl WarpMesh<'_> {
    /// Number of vertices (the length of `rest`).
    pub fn vertex_count(&self) -> usize {
        self.rest.len()
    }

    /// Checks that the mesh can be drawn.
    ///
    /// # Errors
    /// * [`RenderError::MeshLengthMismatch`] if `rest` and `deformed` differ in length;
    /// * [`RenderError::NonFinitePosition`] if any position (used or not) is NaN or infinite;
    /// * [`RenderError::MeshIndexOutOfRange`] if a triangle names a missing vertex.
    pub fn validate(&self) -> Result<(), RenderError> {
        if self.rest.len() != self.deformed.len() {
            return Err(RenderError::MeshLengthMismatch {
                rest: self.rest.len(),
                deformed: self.deformed.len(),
            });
        }
        for (which, positions) in [("rest", self.rest), ("deformed", self.deformed)] {
            if let Some(vertex) = positions.iter().position(|p| !p.is_finite()) {
                return Err(RenderError::NonFinitePosition { which, vertex });
            }
        }
        let vertex_count = self.rest.len();
        for (triangle, tri) in self.triangles.iter().enumerate() {
            for &index in tri {
                if index as usize >= vertex_count {
                    return Err(RenderError::MeshIndexOutOfRange {
                        triangle,
                        index,
                        vertex_count,
                    });
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validate_reports_each_problem() {
        let rest = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let ok = WarpMesh {
            rest: &rest,
            deformed: &rest,
            triangles: &[[0, 1, 2]],
        };
        assert!(ok.validate().is_ok());

        let short = WarpMesh {
            deformed: &rest[..2],
            ..ok
        };
        assert!(matches!(
            short.validate(),
            Err(RenderError::MeshLengthMismatch {
                rest: 3,
                deformed: 2
            })
        ));

        let bad_index = WarpMesh {
            triangles: &[[0, 1, 2], [0, 3, 1]],
            ..ok
        };
        assert!(matches!(
            bad_index.validate(),
            Err(RenderError::MeshIndexOutOfRange {
                triangle: 1,
                index: 3,
                vertex_count: 3
            })
        ));

        let nan = [Vec2::ZERO, Vec2::new(f32::NAN, 0.0), Vec2::Y];
        let non_finite = WarpMesh {
            deformed: &nan,
            ..ok
        };
        assert!(matches!(
            non_finite.validate(),
            Err(RenderError::NonFinitePosition {
                which: "deformed",
                vertex: 1
            })
        ));
    }
}
