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

use std::any::Any;
use std::sync::Arc;

use anyhow::Result;
use glam::DVec2;
use project::{CarriedShape, Project};
use weights_core::{Domain, Metric};

use crate::deformer::{Backdrop, Deformer, Follow, Method, Output, WeightsListing};

/// A part's carried shape on the mesh its method is set up on: the rig file's record
/// and each of the mesh's vertices' offset.
#[derive(Clone, Debug)]
pub(crate) struct Carried {
    /// What the rig file keeps.
    pub record: Arc<CarriedShape>,
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
    pub fn on(record: &Arc<CarriedShape>, rest: &[DVec2]) -> Result<Self> {
        let listed: Vec<DVec2> = record.rest.iter().map(|&p| DVec2::from(p)).collect();
        let offset = |i: usize| DVec2::from(record.offset[i]);
        let offsets = if listed == rest {
            (0..rest.len()).map(offset).collect()
        } else {
            let (mesh, index) = delaunay(&listed)?;
            let offset = |v: u32| offset(index[v as usize]);
            rest.iter()
                .map(
                    |&p| match mesh.as_ref().and_then(|m| Some((m, m.locate(p)?))) {
                        Some((mesh, (t, b))) => {
                            let [i, j, k] = mesh.triangles()[t];
                            offset(i) * b[0] + offset(j) * b[1] + offset(k) * b[2]
                        }
                        None => nearest(&listed, p)
                            .map_or(DVec2::ZERO, |i| DVec2::from(record.offset[i])),
                    },
                )
                .collect()
        };
        Ok(Self {
            record: Arc::clone(record),
            offsets,
        })
    }

    /// The record of the shape `shown` (each vertex's place before the pin) carried
    /// by a part whose method puts its vertices (at rest at `rest`, in `triangles`)
    /// at `placed`: each vertex's offset from `placed` to `shown` in its local frame.
    pub fn record(
        part: Option<usize>,
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
                [(a * d.x + b * d.y) / n, (a * d.y - b * d.x) / n].map(tenth_micro)
            })
            .collect();
        CarriedShape {
            part,
            rest: rest.iter().map(|p| p.to_array()).collect(),
            offset,
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

/// How much of what is shown an edit keeps at each rest point (1: all of it, 0:
/// none, letting the method's new answer show).
pub type Keep = dyn Fn(DVec2) -> f64;

/// `x` to 10⁻⁷ (what a rig file keeps of an offset, in pixels: the same in memory as
/// written and read back).
fn tenth_micro(x: f64) -> f64 {
    (x * 1e7).round() / 1e7
}

/// The Delaunay triangles of `points` as a mesh to locate points in, and for each of
/// its vertices the index of its point (points at one place share a vertex); `None`
/// for fewer than three points not all on a line.
///
/// # Errors
/// Points the triangulation refuses (not finite).
fn delaunay(points: &[DVec2]) -> Result<(Option<Domain>, Vec<usize>)> {
    use spade::{DelaunayTriangulation, Point2, Triangulation};
    let mut triangulation: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    let mut index = Vec::new();
    for (i, p) in points.iter().enumerate() {
        let handle = triangulation
            .insert(Point2::new(p.x, p.y))
            .map_err(|e| anyhow::anyhow!("a carried shape's vertex {i}: {e:?}"))?;
        if handle.index() == index.len() {
            index.push(i);
        }
    }
    let positions: Vec<DVec2> = (triangulation.vertices())
        .map(|v| DVec2::new(v.position().x, v.position().y))
        .collect();
    let triangles: Vec<[u32; 3]> = (triangulation.inner_faces())
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect();
    if triangles.is_empty() {
        return Ok((None, index));
    }
    let mesh = Domain::new(positions, triangles, Metric::Euclidean)
        .map_err(|e| anyhow::anyhow!("a carried shape's vertices: {e}"))?;
    Ok((Some(mesh), index))
}

/// The index of the point of `points` nearest `p`.
fn nearest(points: &[DVec2], p: DVec2) -> Option<usize> {
    (0..points.len()).min_by(|&a, &b| {
        points[a]
            .distance_squared(p)
            .total_cmp(&points[b].distance_squared(p))
    })
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
    use rayon::prelude::*;
    // Each triangle's closest similarity, weighted by its rest area (in parallel: the
    // Jacobians are the work), then summed into its corners.
    let weighted: Vec<[f64; 3]> = triangles
        .par_iter()
        .with_min_len(4096)
        .map(|t| {
            let [i, j, k] = t.map(|v| v as usize);
            let (e1, e2) = (rest[j] - rest[i], rest[k] - rest[i]);
            let det = e1.perp_dot(e2);
            if det.abs() < 1e-12 {
                return [0.0; 3];
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
            [area * (j00 + j11) / 2.0, area * (j10 - j01) / 2.0, area]
        })
        .collect();
    let mut sums = vec![[0.0f64; 3]; rest.len()];
    for (t, w) in triangles.iter().zip(&weighted) {
        for v in *t {
            let sum = &mut sums[v as usize];
            sum[0] += w[0];
            sum[1] += w[1];
            sum[2] += w[2];
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
        let record = Arc::new(Carried::record(Some(3), &rest, &triangles, &placed, &shown));
        let carried = Carried::on(&record, &rest).expect("on its own mesh");
        let mut drawn = placed.clone();
        carried.apply(&rest, &triangles, &mut drawn);
        // (Offsets are kept to 10⁻⁷ px, scaled here by the frame's 0.9.)
        for (p, q) in drawn.iter().zip(&shown) {
            assert!(p.distance(*q) < 2e-7, "{p} for {q}");
        }
        // The whole part turned a quarter turn further: the shape turns with it.
        let quarter = |p: DVec2| DVec2::new(-p.y, p.x);
        let mut turned: Vec<DVec2> = placed.iter().map(|&p| quarter(p)).collect();
        carried.apply(&rest, &triangles, &mut turned);
        for (p, q) in turned.iter().zip(&shown) {
            assert!(p.distance(quarter(*q)) < 2e-7, "{p} for {q}");
        }
    }

    #[test]
    fn offsets_are_interpolated_on_another_mesh_of_the_part() {
        let (rest, _) = square();
        let record = Arc::new(CarriedShape {
            part: None,
            rest: rest.iter().map(|p| p.to_array()).collect(),
            offset: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 4.0], [0.0, 4.0]],
        });
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

/// A handle method on the picture drawn with the shape the picture carries (the rig
/// file's `carried` entry without a part), if it carries one: every ARAP and MLS
/// setup on a picture is wrapped so, so that following a rig file that gains, loses
/// or changes its shape needs no new setup. Everything but the positions is the
/// method's own ([`Deformer::as_any`] too: the editor's overlays see the method).
#[derive(Clone)]
pub(crate) struct Carrying {
    method: Box<dyn Deformer>,
    carried: Option<Carried>,
    /// Where the method puts the vertices with the carried offsets added (empty
    /// without a shape).
    positions: Vec<DVec2>,
}

impl Carrying {
    /// `method` (set up for `project`) drawn with the shape `project` has the picture
    /// carry.
    ///
    /// # Errors
    /// A shape whose triangles are not a mesh.
    pub fn new(method: Box<dyn Deformer>, project: &Project) -> Result<Self> {
        let mut carrying = Self {
            method,
            carried: None,
            positions: Vec::new(),
        };
        carrying.carry(project)?;
        Ok(carrying)
    }

    /// Takes `project`'s shape for the picture (none: none), and places the vertices.
    fn carry(&mut self, project: &Project) -> Result<()> {
        let record = picture_shape(project);
        if !same_shape(self.carried.as_ref(), record) {
            self.carried = (record.map(|r| Carried::on(r, self.method.rest()))).transpose()?;
        }
        self.place();
        Ok(())
    }

    /// The method's positions with the carried offsets added.
    fn place(&mut self) {
        self.positions.clear();
        if let Some(carried) = &self.carried {
            self.positions = self.method.deformed();
            let (rest, triangles) = (self.method.rest(), self.method.triangles());
            carried.apply(rest, triangles, &mut self.positions);
        }
    }
}

/// Whether `carried` is the shape `record` (none: none): the same shared record, or an
/// equal one.
pub(crate) fn same_shape(carried: Option<&Carried>, record: Option<&Arc<CarriedShape>>) -> bool {
    match (carried.map(|c| &c.record), record) {
        (Some(a), Some(b)) => Arc::ptr_eq(a, b) || a == b,
        (a, b) => a.is_none() && b.is_none(),
    }
}

/// The shape `project` has the picture (not a part) carry.
pub fn picture_shape(project: &Project) -> Option<&Arc<CarriedShape>> {
    project.carried.iter().find(|c| c.part.is_none())
}

impl Deformer for Carrying {
    fn method(&self) -> Method {
        self.method.method()
    }

    fn rest(&self) -> &[DVec2] {
        self.method.rest()
    }

    fn triangles(&self) -> &[[u32; 3]] {
        self.method.triangles()
    }

    fn follow(&mut self, project: &Project) -> Result<Follow> {
        let followed = self.method.follow(project)?;
        if followed == Follow::Followed {
            self.carry(project)?;
        }
        Ok(followed)
    }

    fn set_live(&mut self, live: bool) -> Result<()> {
        self.method.set_live(live)?;
        self.place();
        Ok(())
    }

    fn deformed(&self) -> Vec<DVec2> {
        match self.carried {
            Some(_) => self.positions.clone(),
            None => self.method.deformed(),
        }
    }

    fn output(&self) -> Output<'_> {
        match self.carried {
            Some(_) => Output::Positions(&self.positions),
            None => self.method.output(),
        }
    }

    fn backdrop(&self) -> Backdrop {
        self.method.backdrop()
    }

    fn notes(&self) -> Vec<String> {
        self.method.notes()
    }

    fn holds(&self, project: &Project, index: usize) -> Vec<project::Hold> {
        // What the method's solve has where the handle is placed: held there, the
        // solve does not change, and neither do the local frames the shape is in.
        self.method.holds(project, index)
    }

    fn weights(&self, listing: WeightsListing) -> Result<serde_json::Value> {
        self.method.weights(listing)
    }

    fn bench(&mut self, project: &Project, poses: usize) -> Result<serde_json::Value> {
        self.method.bench(project, poses)
    }

    fn as_any(&self) -> &dyn Any {
        self.method.as_any()
    }

    fn clone_box(&self) -> Box<dyn Deformer> {
        Box::new(self.clone())
    }
}

/// The shape that keeps the picture as it was shown (`before`, each vertex of
/// `method`'s mesh) where `keep` is 1, lets it go where `keep` is 0 and blends in
/// between, now that `method` (which has followed the edited rig file, without the
/// picture's shape) puts the vertices elsewhere: where it lets go, the vertices take
/// the method's place with the shape `old` (the one carried until now) still on it.
/// `None` where that is the method's place alone (nothing to carry).
///
/// # Errors
/// An `old` shape whose triangles are not a mesh.
pub fn keep(
    method: &dyn Deformer,
    before: &[DVec2],
    old: Option<&Arc<CarriedShape>>,
    keep: &Keep,
) -> Result<Option<Arc<CarriedShape>>> {
    let (rest, triangles) = (method.rest(), method.triangles());
    let placed = method.deformed();
    anyhow::ensure!(
        before.len() == rest.len(),
        "the picture shown has {} vertices, its method's mesh {}",
        before.len(),
        rest.len()
    );
    let mut let_go = placed.clone();
    if let Some(old) = old {
        Carried::on(old, rest)?.apply(rest, triangles, &mut let_go);
    }
    Ok(between(None, rest, triangles, &placed, &let_go, before, keep).map(Arc::new))
}

/// The shape (of `part`, `None`: the picture) of a mesh at rest at `rest` (in
/// `triangles`) whose method puts its vertices at `placed`, that shows each vertex
/// at `before` where `keep` (at its rest point) is 1 and at `let_go` where it is 0,
/// blending in between; `None` where that is `placed` itself (nothing to carry).
pub(crate) fn between(
    part: Option<usize>,
    rest: &[DVec2],
    triangles: &[[u32; 3]],
    placed: &[DVec2],
    let_go: &[DVec2],
    before: &[DVec2],
    keep: &Keep,
) -> Option<CarriedShape> {
    let shown: Vec<DVec2> = (rest.iter().zip(before.iter().zip(let_go)))
        .map(|(&p, (&kept, &gone))| {
            let s = keep(p).clamp(0.0, 1.0);
            gone + (kept - gone) * s
        })
        .collect();
    let record = Carried::record(part, rest, triangles, placed, &shown);
    (record.offset.iter())
        .any(|d| DVec2::from(*d).length() >= 1e-9)
        .then_some(record)
}

/// How much of the picture a handle removed in a posed state leaves where it was, at
/// each rest point: nothing within the distance from the handle to the nearest other
/// handle (at rest), all of it beyond twice that distance, smoothly in between — so
/// that what the removed handle was moving relaxes to what the others give, and the
/// picture away from it stays. `removed` and `others` are the handles' rest
/// geometries (a point, or a bar's two ends).
pub fn away_from(removed: [DVec2; 2], others: &[[DVec2; 2]]) -> impl Fn(DVec2) -> f64 + use<> {
    let near = (others.iter())
        .map(|&o| geometry::segment_distance(removed, o))
        .fold(f64::INFINITY, f64::min);
    move |p: DVec2| {
        if !near.is_finite() {
            return 0.0;
        }
        let d = geometry::point_segment_distance(p, removed[0], removed[1]);
        if near <= 0.0 {
            return 1.0;
        }
        let t = ((d - near) / near).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    }
}

/// Where the mesh `rest`, warped to `moved`, takes each of `points` (at rest): through
/// the rest triangle holding it, barycentrically; off the mesh, as its nearest vertex
/// moved. (A picture meshed anew is shown where the old mesh showed it.)
pub fn resample(rest: &Domain, moved: &[DVec2], points: &[DVec2]) -> Vec<DVec2> {
    points
        .iter()
        .map(|&p| match rest.locate(p) {
            Some((t, b)) => {
                let [i, j, k] = rest.triangles()[t].map(|v| v as usize);
                moved[i] * b[0] + moved[j] * b[1] + moved[k] * b[2]
            }
            None => rest.nearest_vertex(p).map_or(p, |v| {
                let v = v as usize;
                p + moved[v] - rest.positions()[v]
            }),
        })
        .collect()
}
