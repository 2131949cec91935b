//! The coordinates as computed (dense) and in the paper's compact form (sparse rows).

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::error::LbcError;
use crate::projection::project_row;
use crate::report::Report;

/// Dense coordinates: `n` weights per mesh vertex, vertex-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Coordinates {
    n: usize,
    weights: Vec<f64>,
    /// How the solve went.
    pub report: Report,
    /// `(x, y, 1)` of each cage vertex in the solver's frame (centred, unit size), and
    /// each mesh vertex's position in that frame: what a compact row must reproduce.
    cage: Vec<DVec3>,
    positions: Vec<DVec2>,
}

fn check_pose(pose: &[DVec2], n: usize) -> Result<(), LbcError> {
    if pose.len() != n || pose.iter().any(|p| !p.is_finite()) {
        return Err(LbcError::BadPose {
            expected: n,
            got: pose.len(),
        });
    }
    Ok(())
}

impl Coordinates {
    pub(crate) fn new(
        n: usize,
        weights: Vec<f64>,
        report: Report,
        cage: Vec<DVec3>,
        positions: Vec<DVec2>,
    ) -> Self {
        Self {
            n,
            weights,
            report,
            cage,
            positions,
        }
    }

    /// The same coordinates with vertex `old_of[v]` numbered `v` before now numbered
    /// `old_of[v]`: back to the caller's numbering after a solve on a renumbered mesh.
    pub(crate) fn renumbered(mut self, old_of: &[u32]) -> Self {
        let n = self.n;
        let mut weights = vec![0.0; self.weights.len()];
        let mut positions = vec![DVec2::ZERO; self.positions.len()];
        for (new, &old) in old_of.iter().enumerate() {
            let old = old as usize;
            weights[old * n..(old + 1) * n].copy_from_slice(&self.weights[new * n..(new + 1) * n]);
            positions[old] = self.positions[new];
        }
        self.weights = weights;
        self.positions = positions;
        self
    }

    /// Number of cage vertices.
    pub fn cage_vertices(&self) -> usize {
        self.n
    }

    /// Number of mesh vertices.
    pub fn vertices(&self) -> usize {
        self.weights.len() / self.n.max(1)
    }

    /// The weights `w_1(v) … w_n(v)` of mesh vertex `v`.
    pub fn row(&self, v: usize) -> &[f64] {
        &self.weights[v * self.n..(v + 1) * self.n]
    }

    /// `Σ_i w_i(v) pose_i` for every mesh vertex.
    ///
    /// # Errors
    /// [`LbcError::BadPose`] if `pose` does not have one finite point per cage vertex.
    pub fn deform(&self, pose: &[DVec2]) -> Result<Vec<DVec2>, LbcError> {
        check_pose(pose, self.n)?;
        Ok(self
            .weights
            .par_chunks(self.n)
            .map(|row| row.iter().zip(pose).map(|(w, p)| *w * *p).sum())
            .collect())
    }

    /// The paper's compact form: weights below `10⁻³/n` dropped, the rest corrected
    /// so that each row still reproduces its vertex exactly.
    ///
    /// Dropping weights alone (and dividing by what remains, as the paper's Table 1
    /// implies) keeps partition of unity but not linear precision: a vertex moves by
    /// up to the dropped weight times the cage's size, so the cage at rest would not
    /// be the identity. Here each row is instead the projection of its kept weights
    /// onto `{w ≥ 0, Σ wᵢ = 1, Σ wᵢ cᵢ = x}` with the dropped ones held at zero (the
    /// least-norm correction, kept non-negative): rest is the identity and every
    /// affine motion of the cage is reproduced, to rounding. Where no such row exists
    /// on the kept support (fewer than three kept weights off the cage, say, or a
    /// vertex on a cage edge next to a cage vertex), the row keeps every non-zero
    /// weight, as solved.
    pub fn compact(&self) -> CompactWeights {
        let n = self.n;
        let threshold = 1e-3 / n as f64;
        let rows: Vec<Vec<(u32, f64)>> = self
            .weights
            .par_chunks(n.max(1))
            .zip(&self.positions)
            .map(|(row, &x)| compact_row(row, &self.cage, x, threshold))
            .collect();
        let mut offsets = Vec::with_capacity(rows.len() + 1);
        let mut entries = Vec::with_capacity(rows.iter().map(Vec::len).sum());
        offsets.push(0u32);
        for row in rows {
            entries.extend(row);
            offsets.push(entries.len() as u32);
        }
        CompactWeights {
            n,
            offsets,
            entries,
        }
    }
}

/// One compact row (see [`Coordinates::compact`]): the weights of `row` at least
/// `threshold`, corrected to reproduce `x` (solver frame) with the cage rows `cage`.
fn compact_row(row: &[f64], cage: &[DVec3], x: DVec2, threshold: f64) -> Vec<(u32, f64)> {
    let nonzero = |w: &[f64]| -> Vec<(u32, f64)> {
        w.iter()
            .enumerate()
            .filter(|(_, w)| **w > 0.0)
            .map(|(i, w)| (i as u32, *w))
            .collect()
    };
    let support: Vec<bool> = row.iter().map(|&w| w >= threshold).collect();
    if support.iter().zip(row).all(|(&kept, &w)| kept || w == 0.0) {
        // Nothing to drop: the row is as solved.
        return nonzero(row);
    }
    let kept: Vec<f64> = row
        .iter()
        .zip(&support)
        .map(|(&w, &s)| if s { w } else { 0.0 })
        .collect();
    match project_row(&kept, cage, x.extend(1.0), Some(&support)) {
        Ok(projected) => nonzero(&projected),
        Err(_) => nonzero(row),
    }
}

/// Sparse rows: per mesh vertex, its `(cage vertex, weight)` pairs, ascending by
/// cage vertex, weights summing to one.
#[derive(Clone, Debug, PartialEq)]
pub struct CompactWeights {
    n: usize,
    offsets: Vec<u32>,
    entries: Vec<(u32, f64)>,
}

impl CompactWeights {
    /// Number of cage vertices.
    pub fn cage_vertices(&self) -> usize {
        self.n
    }

    /// Number of mesh vertices.
    pub fn vertices(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Mesh vertex `v`'s pairs.
    pub fn row(&self, v: usize) -> &[(u32, f64)] {
        &self.entries[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    /// Total number of stored pairs.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True if nothing is stored (no mesh vertices).
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// `Σ_i w_i(v) pose_i` over the stored pairs, for every mesh vertex.
    ///
    /// # Errors
    /// [`LbcError::BadPose`] if `pose` does not have one finite point per cage vertex.
    pub fn deform(&self, pose: &[DVec2]) -> Result<Vec<DVec2>, LbcError> {
        check_pose(pose, self.n)?;
        Ok((0..self.vertices())
            .into_par_iter()
            .map(|v| self.row(v).iter().map(|&(i, w)| w * pose[i as usize]).sum())
            .collect())
    }
}
