//! The coordinates as computed (dense) and in the paper's compact form (sparse rows).

use glam::DVec2;
use rayon::prelude::*;

use crate::error::LbcError;
use crate::solve::Report;

/// Dense coordinates: `n` weights per mesh vertex, vertex-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Coordinates {
    n: usize,
    weights: Vec<f64>,
    /// How the solve went.
    pub report: Report,
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
    pub(crate) fn new(n: usize, weights: Vec<f64>, report: Report) -> Self {
        Self { n, weights, report }
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

    /// The paper's compact form: weights below `10⁻³/n` dropped, each row divided by
    /// its remaining sum. Partition of unity stays exact; reproduction then holds to
    /// within the dropped weight times the cage's size (at most `n · 10⁻³/n = 10⁻³`
    /// of the distance to the farthest cage vertex, in practice far less).
    pub fn compact(&self) -> CompactWeights {
        let n = self.n;
        let threshold = 1e-3 / n as f64;
        let mut offsets = Vec::with_capacity(self.vertices() + 1);
        let mut entries = Vec::new();
        offsets.push(0u32);
        for row in self.weights.chunks(n) {
            let start = entries.len();
            entries.extend(
                row.iter()
                    .enumerate()
                    .filter(|(_, w)| **w >= threshold)
                    .map(|(i, w)| (i as u32, *w)),
            );
            let kept = &mut entries[start..];
            let sum: f64 = kept.iter().map(|e| e.1).sum();
            if sum > 0.0 {
                kept.iter_mut().for_each(|e| e.1 /= sum);
            }
            offsets.push(entries.len() as u32);
        }
        CompactWeights {
            n,
            offsets,
            entries,
        }
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
