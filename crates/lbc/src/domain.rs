//! The discretised domain: a triangulation of the cage interior whose boundary
//! vertices carry the Lagrange/linear boundary values.

use geometry::{closest_point_on_segment, orient, point_segment_distance};
use glam::DVec2;
use spade::handles::FixedVertexHandle;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

use crate::cage::Cage;
use crate::error::LbcError;

/// Where a mesh vertex lies on the cage: on edge `edge` (from cage vertex `edge` to
/// `edge + 1`) at parameter `t ∈ [0, 1)`; `t = 0` is the cage vertex itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OnCage {
    /// The cage edge.
    pub edge: u32,
    /// Parameter along it.
    pub t: f64,
}

/// A triangulation of the cage's interior: every cage vertex a mesh vertex, every cage
/// edge a chain of boundary edges, triangles counter-clockwise.
#[derive(Clone, Debug)]
pub struct Domain {
    cage: Cage,
    positions: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    cage_vertices: Vec<u32>,
    on_cage: Vec<Option<OnCage>>,
    /// Whether the vertices and triangles are numbered as [`spatial_order`] numbers
    /// them.
    ordered: bool,
}

impl Domain {
    /// Triangulates the cage's interior with spade: a constrained Delaunay
    /// triangulation with the cage edges as constraints, refined (smallest angle
    /// about 25°) until no triangle is larger than `0.85·area / target_vertices`, which
    /// gives roughly `target_vertices` vertices (refinement splits cage edges too, so
    /// they become chains of boundary edges). Triangles outside the polygon are
    /// dropped.
    ///
    /// # Errors
    /// [`LbcError::Triangulation`] if spade refuses the cage.
    pub fn triangulate(cage: &Cage, target_vertices: usize) -> Result<Self, LbcError> {
        let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
        let mut handles: Vec<FixedVertexHandle> = Vec::with_capacity(cage.len());
        for v in cage.vertices() {
            let h = cdt
                .insert(Point2::new(v.x, v.y))
                .map_err(|e| LbcError::Triangulation(format!("{e:?}")))?;
            handles.push(h);
        }
        if cdt.num_vertices() != cage.len() {
            return Err(LbcError::Triangulation("cage vertices were merged".into()));
        }
        let n = handles.len();
        for i in 0..n {
            let (a, b) = (handles[i], handles[(i + 1) % n]);
            if !cdt.can_add_constraint(a, b) {
                return Err(LbcError::Triangulation(format!(
                    "cage edge {i} crosses another"
                )));
            }
            cdt.add_constraint(a, b);
        }
        let target = target_vertices.max(cage.len());
        // Refined triangles average below the cap; 0.85 was measured to land near
        // the target on stars and rectangles (±10%).
        let max_area = 0.85 * cage.area() / target as f64;
        let params = RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .with_angle_limit(AngleLimit::from_deg(25.0))
            .with_max_allowed_area(max_area)
            .with_max_additional_vertices(10 * target + 1000);
        cdt.refine(params);

        let mut index = vec![u32::MAX; cdt.num_vertices()];
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for face in cdt.inner_faces() {
            let p = face.positions().map(|q| DVec2::new(q.x, q.y));
            let centroid = (p[0] + p[1] + p[2]) / 3.0;
            if !cage.contains(centroid) || orient(p[0], p[1], p[2]) <= 0.0 {
                continue;
            }
            let tri = face.vertices().map(|v| {
                let i = v.fix().index();
                if index[i] == u32::MAX {
                    index[i] = positions.len() as u32;
                    positions.push(p_of(v.position()));
                }
                index[i]
            });
            triangles.push(tri);
        }
        // Spade refines in no spatial order.
        let (positions, renumber) = spatial_order(&positions, &mut triangles);
        for i in index.iter_mut().filter(|i| **i != u32::MAX) {
            *i = renumber[*i as usize];
        }
        let cage_vertices = handles
            .iter()
            .enumerate()
            .map(|(i, h)| {
                let k = index[h.index()];
                if k == u32::MAX {
                    Err(LbcError::CageVertexNotInMesh { vertex: i })
                } else {
                    Ok(k)
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut domain = Self::assemble(cage.clone(), positions, triangles, Some(cage_vertices))?;
        domain.ordered = true;
        Ok(domain)
    }

    /// Uses a given triangulation of the cage's interior as it is. Cage vertices are
    /// found among its vertices by position (within `1e-9` of the cage's size), in
    /// any vertex order; mesh vertices on a cage edge (same tolerance) are boundary
    /// vertices. Triangles may come in either orientation.
    ///
    /// # Errors
    /// [`LbcError::InvalidMesh`] for an out-of-range index, a non-finite position, a
    /// zero-area triangle or a vertex in no triangle;
    /// [`LbcError::OutsideCage`] for a vertex outside the cage (or a triangle whose
    /// centroid is: one that spans a notch of the cage);
    /// [`LbcError::CageVertexNotInMesh`] if a cage vertex has no mesh vertex.
    pub fn from_mesh(
        cage: &Cage,
        positions: Vec<DVec2>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, LbcError> {
        if positions.len() >= u32::MAX as usize {
            return Err(LbcError::InvalidMesh("too many vertices".into()));
        }
        if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
            return Err(LbcError::InvalidMesh(format!("vertex {v} is not finite")));
        }
        let mut used = vec![false; positions.len()];
        let mut oriented = Vec::with_capacity(triangles.len());
        for (s, t) in triangles.iter().enumerate() {
            if t.iter().any(|&v| v as usize >= positions.len()) {
                return Err(LbcError::InvalidMesh(format!(
                    "triangle {s} names a vertex beyond the {} given",
                    positions.len()
                )));
            }
            let p = t.map(|v| positions[v as usize]);
            let o = orient(p[0], p[1], p[2]);
            if o == 0.0 || !o.is_finite() {
                return Err(LbcError::InvalidMesh(format!("triangle {s} has no area")));
            }
            for &v in t {
                used[v as usize] = true;
            }
            oriented.push(if o > 0.0 { *t } else { [t[0], t[2], t[1]] });
        }
        if let Some(v) = used.iter().position(|u| !u) {
            return Err(LbcError::InvalidMesh(format!(
                "vertex {v} is in no triangle"
            )));
        }
        let (lo, hi) = cage.bounds();
        let tol = 1e-9 * (hi - lo).length();
        let c = cage.vertices();
        let inside = |p: DVec2| {
            cage.contains(p)
                || (0..c.len())
                    .any(|e| point_segment_distance(p, c[e], c[(e + 1) % c.len()]) <= tol)
        };
        let outside = |v: usize, p: DVec2| LbcError::OutsideCage {
            vertex: v,
            x: p.x,
            y: p.y,
        };
        if let Some(v) = positions.iter().position(|&p| !inside(p)) {
            return Err(outside(v, positions[v]));
        }
        for t in &oriented {
            let p = t.map(|v| positions[v as usize]);
            if !cage.contains((p[0] + p[1] + p[2]) / 3.0) {
                let v = t[0] as usize;
                return Err(outside(v, positions[v]));
            }
        }
        Self::assemble(cage.clone(), positions, oriented, None)
    }

    fn assemble(
        cage: Cage,
        positions: Vec<DVec2>,
        triangles: Vec<[u32; 3]>,
        cage_vertices: Option<Vec<u32>>,
    ) -> Result<Self, LbcError> {
        let (lo, hi) = cage.bounds();
        let tol = 1e-9 * (hi - lo).length();
        let c = cage.vertices();
        let n = c.len();
        let cage_vertices = match cage_vertices {
            Some(v) => v,
            None => c
                .iter()
                .enumerate()
                .map(|(i, &ci)| {
                    positions
                        .iter()
                        .enumerate()
                        .map(|(k, p)| (k, p.distance(ci)))
                        .filter(|&(_, d)| d <= tol)
                        .min_by(|a, b| a.1.total_cmp(&b.1))
                        .map(|(k, _)| k as u32)
                        .ok_or(LbcError::CageVertexNotInMesh { vertex: i })
                })
                .collect::<Result<Vec<_>, _>>()?,
        };
        let mut on_cage: Vec<Option<OnCage>> = positions
            .iter()
            .map(|&p| {
                (0..n)
                    .map(|e| {
                        let (q, t) = closest_point_on_segment(p, c[e], c[(e + 1) % n]);
                        (e, (q.distance(p), t))
                    })
                    .filter(|&(_, (d, _))| d <= tol)
                    .min_by(|a, b| a.1.0.total_cmp(&b.1.0))
                    .map(|(e, (_, t))| {
                        if t >= 1.0 {
                            OnCage {
                                edge: ((e + 1) % n) as u32,
                                t: 0.0,
                            }
                        } else {
                            OnCage { edge: e as u32, t }
                        }
                    })
            })
            .collect();
        // Cage vertices exactly: weight 1 at their own vertex whatever the rounding.
        for (i, &v) in cage_vertices.iter().enumerate() {
            on_cage[v as usize] = Some(OnCage {
                edge: i as u32,
                t: 0.0,
            });
        }
        Ok(Self {
            cage,
            positions,
            triangles,
            cage_vertices,
            on_cage,
            ordered: false,
        })
    }

    /// The cage.
    pub fn cage(&self) -> &Cage {
        &self.cage
    }

    /// Mesh vertex positions.
    pub fn positions(&self) -> &[DVec2] {
        &self.positions
    }

    /// Triangles, counter-clockwise.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The mesh vertex of each cage vertex.
    pub fn cage_vertices(&self) -> &[u32] {
        &self.cage_vertices
    }

    /// For each mesh vertex, where it lies on the cage (`None`: interior).
    pub fn on_cage(&self) -> &[Option<OnCage>] {
        &self.on_cage
    }

    /// The boundary values of a vertex on the cage: the linear interpolation of the
    /// Lagrange values along its edge, as `(cage vertex, weight)` pairs.
    pub(crate) fn boundary_weights(&self, at: OnCage) -> [(usize, f64); 2] {
        let n = self.cage.len();
        let e = at.edge as usize;
        [(e, 1.0 - at.t), ((e + 1) % n, at.t)]
    }
}

impl Domain {
    /// The same domain numbered by [`spatial_order`], and the old number of each new
    /// vertex; `None` if it is numbered so already (as [`Domain::triangulate`]
    /// numbers it).
    pub(crate) fn spatially_ordered(&self) -> Option<(Self, Vec<u32>)> {
        if self.ordered {
            return None;
        }
        let mut triangles = self.triangles.clone();
        let (positions, renumber) = spatial_order(&self.positions, &mut triangles);
        let mut old_of = vec![0u32; renumber.len()];
        for (old, &new) in renumber.iter().enumerate() {
            old_of[new as usize] = old as u32;
        }
        Some((
            Self {
                cage: self.cage.clone(),
                positions,
                triangles,
                cage_vertices: self
                    .cage_vertices
                    .iter()
                    .map(|&v| renumber[v as usize])
                    .collect(),
                on_cage: old_of
                    .iter()
                    .map(|&old| self.on_cage[old as usize])
                    .collect(),
                ordered: true,
            },
            old_of,
        ))
    }
}

/// Numbers the vertices along a Z-order curve and the triangles by their first
/// vertex, so that neighbours sit near each other in memory (the solve's passes over
/// the triangles read their corners' rows, and its pass over the rows reads each
/// row's triangles). Renumbers `triangles` in place; returns the positions in the
/// new order and the new number of each old vertex.
fn spatial_order(positions: &[DVec2], triangles: &mut [[u32; 3]]) -> (Vec<DVec2>, Vec<u32>) {
    let order = geometry::z_order(positions);
    let mut renumber = vec![0u32; positions.len()];
    for (new, &old) in order.iter().enumerate() {
        renumber[old as usize] = new as u32;
    }
    let positions = order.iter().map(|&old| positions[old as usize]).collect();
    for t in triangles.iter_mut() {
        *t = t.map(|v| renumber[v as usize]);
    }
    triangles.sort_unstable_by_key(|t| (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2])));
    (positions, renumber)
}

fn p_of(p: Point2<f64>) -> DVec2 {
    DVec2::new(p.x, p.y)
}
