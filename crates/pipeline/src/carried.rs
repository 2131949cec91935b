//! The shape a part carries from following another ([`project::CarriedShape`]).
//!
//! A part that no handle binds follows the part beneath it, bending as that part's
//! warp bends under it. When a pin first binds it in a posed state, its own method
//! takes over, and what the method gives it (with one pin: the part at rest, moved by
//! the pin's similarity) is not the shape following gave it. So that placing the pin
//! moves nothing, the part keeps that shape as an offset of each vertex from where
//! its own method puts it, written in the method's local frame there: the closest
//! similarity to the warp around the vertex ([`local_frames`]), its rotation and scale
//! undone. Drawn, each vertex goes where the method puts it plus its offset in the
//! local frame of the moment, so the carried shape turns and scales with the part as
//! its handles move it, and in the pose the pin was placed in it is exactly the shape
//! shown before.

use anyhow::{Context, Result};
use glam::DVec2;
use project::CarriedShape;
use weights_core::{Domain, Metric};

/// A part's carried shape on the mesh its method is set up on: the rig file's record
/// and each of the mesh's vertices' offset.
#[derive(Clone, Debug)]
pub(crate) struct Carried {
    /// What the rig file keeps.
    pub record: CarriedShape,
    /// Each vertex's offset, in its local frame.
    offsets: Vec<DVec2>,
}

impl Carried {
    /// `record` on the mesh whose vertices rest at `rest` (canvas pixels): each
    /// vertex's offset interpolated over the record's triangles (a vertex outside
    /// them takes its nearest listed vertex's), the record's own where the meshes
    /// are one.
    ///
    /// # Errors
    /// A record whose triangles are not a mesh.
    pub fn on(record: &CarriedShape, rest: &[DVec2]) -> Result<Self> {
        let listed: Vec<DVec2> = record.rest.iter().map(|&p| DVec2::from(p)).collect();
        let offset = |i: usize| DVec2::from(record.offset[i]);
        let offsets = if listed == rest {
            (0..rest.len()).map(offset).collect()
        } else {
            let mesh = Domain::new(listed, record.triangles.clone(), Metric::Euclidean)
                .with_context(|| format!("layer {}'s carried shape", record.part))?;
            rest.iter()
                .map(|&p| match mesh.locate(p) {
                    Some((t, b)) => {
                        let [i, j, k] = mesh.triangles()[t].map(|v| v as usize);
                        offset(i) * b[0] + offset(j) * b[1] + offset(k) * b[2]
                    }
                    None => mesh
                        .nearest_vertex(p)
                        .map_or(DVec2::ZERO, |v| offset(v as usize)),
                })
                .collect()
        };
        Ok(Self {
            record: record.clone(),
            offsets,
        })
    }

    /// The record of the shape `shown` (each vertex's place before the pin) carried
    /// by a part whose method puts its vertices (at rest at `rest`, in `triangles`)
    /// at `placed`: each vertex's offset from `placed` to `shown` in its local frame.
    pub fn record(
        part: usize,
        rest: &[DVec2],
        triangles: &[[u32; 3]],
        placed: &[DVec2],
        shown: &[DVec2],
    ) -> CarriedShape {
        let frames = local_frames(rest, placed, triangles);
        let offset = (frames.iter().zip(placed.iter().zip(shown)))
            .map(|(&[a, b], (&p, &q))| {
                // The frame's inverse: [a b; -b a] / (a² + b²).
                let d = q - p;
                let n = a * a + b * b;
                [(a * d.x + b * d.y) / n, (a * d.y - b * d.x) / n]
            })
            .collect();
        CarriedShape {
            part,
            rest: rest.iter().map(|p| p.to_array()).collect(),
            offset,
            triangles: triangles.to_vec(),
        }
    }

    /// `placed` (where the part's method puts its vertices, at rest at `rest`, in
    /// `triangles`) with the carried shape's offsets added in the local frames.
    pub fn apply(&self, rest: &[DVec2], triangles: &[[u32; 3]], placed: &mut [DVec2]) {
        let frames = local_frames(rest, placed, triangles);
        for ((p, &[a, b]), d) in placed.iter_mut().zip(&frames).zip(&self.offsets) {
            *p += DVec2::new(a * d.x - b * d.y, b * d.x + a * d.y);
        }
    }
}

/// For each vertex of a mesh (at rest at `rest`, in `triangles`) warped to `moved`,
/// the closest similarity to the warp around it as `[a, b]` (the linear map
/// `[a -b; b a]`): the rest-area-weighted mean over its triangles of each triangle's
/// closest similarity to its Jacobian, which is linear in the positions and exact for
/// a similarity. A vertex in no triangle, or whose frame has all but collapsed, takes
/// the identity, so that an offset can always be written in it and read back.
pub(crate) fn local_frames(
    rest: &[DVec2],
    moved: &[DVec2],
    triangles: &[[u32; 3]],
) -> Vec<[f64; 2]> {
    let mut sums = vec![[0.0f64; 3]; rest.len()];
    for t in triangles {
        let [i, j, k] = t.map(|v| v as usize);
        let (e1, e2) = (rest[j] - rest[i], rest[k] - rest[i]);
        let det = e1.perp_dot(e2);
        if det.abs() < 1e-12 {
            continue;
        }
        let (f1, f2) = (moved[j] - moved[i], moved[k] - moved[i]);
        // J = [f1 f2] [e1 e2]⁻¹; its closest similarity's a = (J₀₀ + J₁₁) / 2 and
        // b = (J₁₀ - J₀₁) / 2.
        let inv = [[e2.y / det, -e2.x / det], [-e1.y / det, e1.x / det]];
        let j00 = f1.x * inv[0][0] + f2.x * inv[1][0];
        let j01 = f1.x * inv[0][1] + f2.x * inv[1][1];
        let j10 = f1.y * inv[0][0] + f2.y * inv[1][0];
        let j11 = f1.y * inv[0][1] + f2.y * inv[1][1];
        let area = det.abs();
        for v in [i, j, k] {
            sums[v][0] += area * (j00 + j11) / 2.0;
            sums[v][1] += area * (j10 - j01) / 2.0;
            sums[v][2] += area;
        }
    }
    sums.iter()
        .map(|&[a, b, area]| {
            if area <= 0.0 {
                return [1.0, 0.0];
            }
            let (a, b) = (a / area, b / area);
            if a * a + b * b < 1e-12 || !(a.is_finite() && b.is_finite()) {
                [1.0, 0.0]
            } else {
                [a, b]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles of a unit square, at rest.
    fn square() -> (Vec<DVec2>, Vec<[u32; 3]>) {
        let rest = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(10.0, 0.0),
            DVec2::new(10.0, 10.0),
            DVec2::new(0.0, 10.0),
        ];
        (rest, vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn a_similarity_is_its_own_local_frame_everywhere() {
        let (rest, triangles) = square();
        let (s, angle) = (1.7, 0.6);
        let (a, b) = (s * f64::cos(angle), s * f64::sin(angle));
        let moved: Vec<DVec2> = (rest.iter())
            .map(|p| DVec2::new(a * p.x - b * p.y + 3.0, b * p.x + a * p.y - 8.0))
            .collect();
        for [fa, fb] in local_frames(&rest, &moved, &triangles) {
            assert!((fa - a).abs() < 1e-12 && (fb - b).abs() < 1e-12);
        }
    }

    #[test]
    fn a_shape_recorded_where_it_was_placed_is_shown_exactly_and_turns_with_the_part() {
        let (rest, triangles) = square();
        // The method put the part a little turned; the shape shown was bent.
        let placed: Vec<DVec2> = (rest.iter())
            .map(|p| DVec2::new(p.x * 0.9 - p.y * 0.1, p.x * 0.1 + p.y * 0.9))
            .collect();
        let shown: Vec<DVec2> = (placed.iter().enumerate())
            .map(|(i, p)| *p + DVec2::new(i as f64, -(i as f64) * 0.5))
            .collect();
        let record = Carried::record(3, &rest, &triangles, &placed, &shown);
        let carried = Carried::on(&record, &rest).expect("on its own mesh");
        let mut drawn = placed.clone();
        carried.apply(&rest, &triangles, &mut drawn);
        for (p, q) in drawn.iter().zip(&shown) {
            assert!(p.distance(*q) < 1e-12, "{p} for {q}");
        }
        // The whole part turned a quarter turn further: the shape turns with it.
        let quarter = |p: DVec2| DVec2::new(-p.y, p.x);
        let mut turned: Vec<DVec2> = placed.iter().map(|&p| quarter(p)).collect();
        carried.apply(&rest, &triangles, &mut turned);
        for (p, q) in turned.iter().zip(&shown) {
            assert!(p.distance(quarter(*q)) < 1e-9, "{p} for {q}");
        }
    }

    #[test]
    fn offsets_are_interpolated_on_another_mesh_of_the_part() {
        let (rest, triangles) = square();
        let record = CarriedShape {
            part: 0,
            rest: rest.iter().map(|p| p.to_array()).collect(),
            offset: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 4.0], [0.0, 4.0]],
            triangles,
        };
        let other = [
            DVec2::new(5.0, 5.0),
            DVec2::new(10.0, 5.0),
            DVec2::new(20.0, 0.0),
        ];
        let carried = Carried::on(&record, &other).expect("another mesh");
        assert!(carried.offsets[0].distance(DVec2::new(1.0, 2.0)) < 1e-12);
        assert!(carried.offsets[1].distance(DVec2::new(2.0, 2.0)) < 1e-12);
        // Outside the record's mesh: its nearest vertex's offset.
        assert_eq!(carried.offsets[2], DVec2::new(2.0, 0.0));
    }
}
