//! The cage: a simple polygon, validated once.

use geometry::{orient, point_segment_distance, segment_distance, signed_area};
use glam::DVec2;

use crate::error::LbcError;

/// A simple polygon (either orientation): the control points `c_i` of the paper,
/// in order along the boundary. Edge `i` runs from vertex `i` to vertex `i + 1`
/// (the last edge closes the polygon).
#[derive(Clone, Debug, PartialEq)]
pub struct Cage {
    vertices: Vec<DVec2>,
}

/// A cage whose area is at most this share of its bounding box diagonal squared is
/// refused as too thin ([`LbcError::TooThin`]).
pub const THIN: f64 = 1e-6;

impl Cage {
    /// Validates a polygon.
    ///
    /// # Errors
    /// Fewer than 3 vertices, a non-finite coordinate, two coinciding vertices, zero
    /// area (or an area of at most [`THIN`] times the squared diagonal of the bounding
    /// box: a sliver), or two edges that cross or touch (other than neighbours at their
    /// shared vertex) are refused. Coincidence and touching are judged with a tolerance of
    /// `1e-12` of the bounding-box diagonal, so that what is refused here is also
    /// what a triangulation could not represent.
    pub fn new(vertices: Vec<DVec2>) -> Result<Self, LbcError> {
        let n = vertices.len();
        if n < 3 {
            return Err(LbcError::TooFewVertices { vertices: n });
        }
        if let Some(vertex) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(LbcError::NonFinite { vertex });
        }
        let (lo, hi) = bounds(&vertices);
        let diag = (hi - lo).length();
        let tol = 1e-12 * diag;
        for i in 0..n {
            for j in i + 1..n {
                if vertices[i].distance(vertices[j]) <= tol {
                    return Err(LbcError::RepeatedVertex {
                        first: i,
                        second: j,
                    });
                }
            }
        }
        // All on one line: no area (checked before crossings, which such a polygon
        // also has, as the more telling answer).
        let far = (1..n)
            .max_by(|&a, &b| {
                vertices[a]
                    .distance(vertices[0])
                    .total_cmp(&vertices[b].distance(vertices[0]))
            })
            .unwrap_or(1);
        if vertices
            .iter()
            .all(|&p| orient(vertices[0], vertices[far], p).abs() <= 1e-12 * diag * diag)
        {
            return Err(LbcError::ZeroArea);
        }
        let edge = |i: usize| (vertices[i], vertices[(i + 1) % n]);
        for i in 0..n {
            let (a, b) = edge(i);
            for j in i + 1..n {
                let (c, d) = edge(j);
                let adjacent_after = j == i + 1;
                let adjacent_before = i == 0 && j == n - 1;
                let hit = if adjacent_after {
                    // Shared vertex b = c: they overlap only if d folds back along ab.
                    folds_back(a, b, d, tol)
                } else if adjacent_before {
                    // Shared vertex a = d.
                    folds_back(b, a, c, tol)
                } else {
                    // Crossing, or closer than `tol` anywhere.
                    segment_distance([a, b], [c, d]) <= tol
                };
                if hit {
                    return Err(LbcError::SelfIntersection {
                        first: i,
                        second: j,
                    });
                }
            }
        }
        // A simple polygon that is not flat has area, but one thinner than a millionth
        // of its size cannot be triangulated into anything a solve can use.
        let area = signed_area(&vertices).abs();
        if area <= 1e-12 * diag * diag {
            return Err(LbcError::ZeroArea);
        }
        if area <= THIN * diag * diag {
            return Err(LbcError::TooThin { area, size: diag });
        }
        Ok(Self { vertices })
    }

    /// The vertices, in the order given.
    pub fn vertices(&self) -> &[DVec2] {
        &self.vertices
    }

    /// Number of vertices (`n`).
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Always false: a cage has at least three vertices.
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Enclosed area (positive whatever the orientation).
    pub fn area(&self) -> f64 {
        signed_area(&self.vertices).abs()
    }

    /// Whether `p` lies strictly inside (crossing parity; points on the boundary may
    /// go either way).
    pub fn contains(&self, p: DVec2) -> bool {
        let n = self.vertices.len();
        let mut inside = false;
        for i in 0..n {
            let a = self.vertices[i];
            let b = self.vertices[(i + 1) % n];
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if x > p.x {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// Lower and upper corners of the bounding box.
    pub fn bounds(&self) -> (DVec2, DVec2) {
        bounds(&self.vertices)
    }
}

fn bounds(v: &[DVec2]) -> (DVec2, DVec2) {
    v.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

/// Edges `a→b` and `b→d` meet at `b`; true if `d` turns back onto `ab` (or `a` lies on
/// `bd`), so that they share more than `b`.
fn folds_back(a: DVec2, b: DVec2, d: DVec2, tol: f64) -> bool {
    point_segment_distance(d, a, b) <= tol || point_segment_distance(a, b, d) <= tol
}
