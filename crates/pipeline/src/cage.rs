//! Local barycentric coordinates of a rig file's cage (the `lbc` crate): the cage's
//! inside triangulated (or a given mesh of it), the coordinates solved, and the
//! posed cage.
//!
//! LBC is a cage method: it moves what lies inside the cage by the cage's vertices;
//! it has no handles. Behind the method seam it is a [`CageDeformer`]: the command
//! line sets it up through [`crate::setup`] and the editor from the coordinates its
//! cage tool solved ([`CageDeformer::new`]); both mesh the cage's inside to
//! [`cage_vertices`] and draw through [`crate::Warper`], so the editor's export is
//! what `c2warp render` gives for the saved project. [`cage_from_outline`] makes a
//! cage around a cut-out's visible shape.

use std::any::Any;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail, ensure};
use glam::DVec2;
use project::{MAX_CAGE_VERTICES, Method, Project, Tau};
use serde::Serialize;

use crate::deformer::{
    Backdrop, Deformer, Follow, Listener, Output, SkinTable, Skinning, Source, WeightsListing,
    json, median,
};

/// Mesh vertices inside a cage when neither a `--density` nor the rig names a count:
/// the picture's own default density ([`crate::DEFAULT_DENSITY`]), so that a picture
/// warped by a cage is as fine as one warped by handles (the solve takes 1.5–2.5 s at
/// this size on a 2-core machine; see docs/performance.md).
pub const DEFAULT_CAGE_VERTICES: usize = crate::DEFAULT_DENSITY;

/// How many mesh vertices the inside of `project`'s cage is triangulated to: `density`
/// (a command line's `--density`) if given, else the rig's `lbc.density`, else its
/// `density`, else [`default_cage_vertices`] for its cage.
pub fn cage_vertices(project: &Project, density: Option<usize>) -> usize {
    density
        .or(project.lbc.and_then(|l| l.density))
        .or(project.density)
        .unwrap_or_else(|| default_cage_vertices(project.cage.as_ref().map_or(0, |c| c.rest.len())))
}

/// Mesh vertices inside a cage of `corners` vertices when nothing names a count:
/// [`DEFAULT_CAGE_VERTICES`], or fewer where a cage has so many vertices that the solve
/// would pass [`MAX_CAGE_WORK`] (a default is never refused).
pub fn default_cage_vertices(corners: usize) -> usize {
    DEFAULT_CAGE_VERTICES.min(MAX_CAGE_WORK / corners.max(1))
}

/// The most work a solve may take: mesh vertices inside the cage times cage vertices.
/// An ADMM iteration costs about that many operations, and a solve a few hundred
/// iterations: at this size it takes about a minute on a 2-core machine (92,000
/// vertices in a 16-vertex cage: 34 s). A larger request is refused, naming the limit.
pub const MAX_CAGE_WORK: usize = 3_000_000;

/// Mesh vertices inside a cage of `area` px² at most: as many per px² as a picture's
/// mesh may have ([`mesh::MAX_VERTICES_PER_PIXEL`]); more would only slice pixels.
pub fn cage_vertex_cap(area: f64) -> usize {
    (mesh::MAX_VERTICES_PER_PIXEL * area).ceil().max(1.0) as usize
}

/// Refuses a solve of `cage_vertices` with `mesh_vertices` inside that would take
/// more than about a minute.
fn check_work(mesh_vertices: usize, cage_vertices: usize) -> Result<()> {
    let work = mesh_vertices.saturating_mul(cage_vertices);
    ensure!(
        work <= MAX_CAGE_WORK,
        "a cage of {cage_vertices} vertices with {mesh_vertices} mesh vertices inside would \
         take minutes to solve: mesh vertices × cage vertices may be at most \
         {MAX_CAGE_WORK} (about a minute), here {work}; ask for at most {} mesh vertices \
         (--density or the rig's lbc.density) or use fewer cage vertices",
        MAX_CAGE_WORK / cage_vertices.max(1)
    );
    Ok(())
}

/// The solver's settings for `tau` (everything else at the `lbc` crate's defaults).
pub fn solver_settings(tau: Tau) -> lbc::Settings {
    lbc::Settings {
        tau: match tau {
            Tau::Square => lbc::Tau::Square,
            Tau::Linear => lbc::Tau::Linear,
            Tau::Constant => lbc::Tau::Constant,
            Tau::Sqrt => lbc::Tau::Sqrt,
        },
        ..lbc::Settings::default()
    }
}

/// Where the mesh of the cage's inside comes from.
pub enum CageMesh {
    /// Triangulate the inside to about this many vertices (split along the rig file's
    /// cuts, if it has any: [`cut_inside`]).
    Triangulate {
        /// Target vertex count.
        target_vertices: usize,
    },
    /// A given triangulation of the inside (e.g. read from an OBJ file); the cage's
    /// vertices are found among its vertices by position.
    Given {
        /// Vertex positions.
        positions: Vec<DVec2>,
        /// Triangles.
        triangles: Vec<[u32; 3]>,
    },
}

/// The solved coordinates of a rig file's cage.
pub struct CageCoordinates {
    /// The mesh of the cage's inside.
    pub domain: lbc::Domain,
    /// Every mesh vertex's compact row: `(cage vertex, weight)` pairs, weights below
    /// `10⁻³/n` dropped and the row renormalised.
    pub weights: lbc::CompactWeights,
    /// Iterations, residuals, objective and times of the solve.
    pub report: lbc::Report,
    /// The paper's locality statistics `P(t)` (at `t` = 0, `10⁻³/n`, 0.01, 0.05, 0.1,
    /// 0.2, …, 1) and `Q(k)`, of the coordinates before compaction.
    pub locality: lbc::Locality,
    /// The rest cage it was solved for, as the rig file gives it.
    pub rest: Vec<DVec2>,
    /// The locality weighting it was solved with.
    pub tau: Tau,
    /// The posed cage (the rest cage where the rig gives no pose).
    pub pose: Vec<DVec2>,
}

impl CageCoordinates {
    /// Where every mesh vertex goes for the posed cage.
    ///
    /// # Errors
    /// Only on a bug (a pose of the wrong length).
    pub fn deformed(&self) -> Result<Vec<DVec2>> {
        Ok(self.weights.deform(&self.pose)?)
    }
}

/// Solves the local barycentric coordinates of `project`'s cage on `mesh`, telling
/// `progress` each ADMM iteration (it returns `false` to cancel).
///
/// # Errors
/// No cage in the rig file, a cage that is not a simple polygon, a given mesh that
/// does not hold the cage's vertices, or a cancelled solve.
pub fn cage_coordinates(
    project: &Project,
    mesh: CageMesh,
    progress: &mut dyn FnMut(&lbc::Progress) -> bool,
) -> Result<CageCoordinates> {
    let Some(spec) = &project.cage else {
        bail!("the rig has no \"cage\" (LBC warps by a cage)");
    };
    let rest: Vec<DVec2> = spec.rest.iter().map(|&p| DVec2::from(p)).collect();
    let pose: Vec<DVec2> = spec.pose.as_ref().map_or_else(
        || rest.clone(),
        |p| p.iter().map(|&q| DVec2::from(q)).collect(),
    );
    let cage = lbc::Cage::new(rest.clone()).context("the rig's cage")?;
    let domain = match mesh {
        CageMesh::Triangulate { target_vertices } => {
            let target = target_vertices.min(cage_vertex_cap(cage.area()));
            check_work(target, cage.len())?;
            if project.cuts.is_empty() {
                lbc::Domain::triangulate(&cage, target).context("cannot triangulate the cage")?
            } else {
                let (positions, triangles) = cut_inside(&cage, target, &project.cuts)?;
                lbc::Domain::from_mesh(&cage, positions, triangles)
                    .context("cannot mesh the cage along its cuts")?
            }
        }
        CageMesh::Given {
            positions,
            triangles,
        } => {
            check_work(positions.len(), cage.len())?;
            lbc::Domain::from_mesh(&cage, positions, triangles)
                .context("the mesh does not fit the cage")?
        }
    };
    let tau = project.lbc.unwrap_or_default().tau;
    let settings = solver_settings(tau);
    let coordinates = lbc::solve(&domain, &settings, progress)?;
    let report = coordinates.report.clone();
    let n = coordinates.cage_vertices().max(1) as f64;
    let mut t = vec![0.0, 1e-3 / n, 0.01, 0.05];
    t.extend((1..=10).map(|k| f64::from(k) / 10.0));
    let locality = lbc::locality(&domain, &coordinates, &t);
    Ok(CageCoordinates {
        weights: coordinates.compact(),
        domain,
        report,
        locality,
        rest,
        tau,
        pose,
    })
}

/// The inside of `cage` triangulated to about `target` vertices and split along `cuts`
/// as a picture's mesh is ([`crate::mesh_picture`]): each stroke's parts inside the
/// cage meshed as edges, then the vertices along them doubled, one copy per side
/// ([`mesh::split_along`]), so that no distance and no coordinate crosses a cut and
/// the two sides move apart where the cage pulls them apart. The cage's vertices are
/// vertices of the mesh, at their positions.
///
/// # Errors
/// A failure of the triangulator.
pub fn cut_inside(
    cage: &lbc::Cage,
    target: usize,
    cuts: &[project::Cut],
) -> Result<(Vec<DVec2>, Vec<[u32; 3]>)> {
    let outer = cage.vertices().to_vec();
    let far = outer.iter().fold(DVec2::ZERO, |m, p| m.max(p.abs())).ceil();
    let domain = mesh::Domain {
        polygons: vec![mesh::Polygon {
            outer,
            holes: Vec::new(),
        }],
        is_full_rectangle: false,
        width: far.x as u32,
        height: far.y as u32,
    };
    let options = mesh::MeshOptions {
        target_vertices: target,
        ..mesh::MeshOptions::default()
    };
    let (mesh, _) = crate::mesh_along_cuts(&domain, &options, cuts)
        .context("cannot triangulate the cage along its cuts")?;
    Ok((mesh.vertices, mesh.triangles))
}

/// LBC behind the method seam: a cage's solved coordinates and the cage's pose.
///
/// It moves the mesh of the cage's inside (not the picture's mesh) and keeps the
/// picture outside the rest cage in place ([`Backdrop::PictureOutsideMesh`]), as
/// GIMP's cage tool does: what lies inside the rest cage is taken out and drawn where
/// the posed cage takes it, over what lies outside. It draws skinned: the compact rows
/// are the weight rows, and each cage vertex a node whose transform has no linear part
/// and the posed vertex as its translation ([`skinning_table`], [`pose_transforms`]).
#[derive(Clone)]
pub struct CageDeformer {
    solved: Arc<CageCoordinates>,
    pose: Vec<DVec2>,
    positions: Vec<DVec2>,
}

impl CageDeformer {
    /// The cage of `solved` in `pose` (one point per cage vertex).
    ///
    /// # Errors
    /// A pose of the wrong length.
    pub fn new(solved: Arc<CageCoordinates>, pose: Vec<DVec2>) -> Result<Self> {
        let positions = solved.weights.deform(&pose)?;
        Ok(Self {
            solved,
            pose,
            positions,
        })
    }

    /// Solves `project`'s cage on `source` (a picture: the cage's inside triangulated
    /// to [`cage_vertices`]; a mesh: the cage's inside as given), telling `listener`
    /// each iteration, and poses it as the rig file does.
    ///
    /// # Errors
    /// As [`cage_coordinates`], a density out of range, and a cage off the picture.
    pub fn set_up(source: Source<'_>, project: &Project, listener: &dyn Listener) -> Result<Self> {
        let mesh = match source {
            Source::Picture { image, density } => {
                project.validate(Some(image.dimensions()))?;
                let target_vertices = cage_vertices(project, density);
                project::validate_density(target_vertices)?;
                CageMesh::Triangulate { target_vertices }
            }
            Source::Mesh(mesh) => {
                project.validate(None)?;
                CageMesh::Given {
                    positions: mesh.vertices.clone(),
                    triangles: mesh.triangles.clone(),
                }
            }
        };
        let solved = cage_coordinates(project, mesh, &mut |p| listener.solving(p))?;
        let pose = solved.pose.clone();
        Self::new(Arc::new(solved), pose)
    }

    /// The solved coordinates.
    pub fn solution(&self) -> &Arc<CageCoordinates> {
        &self.solved
    }

    /// The cage's pose.
    pub fn pose(&self) -> &[DVec2] {
        &self.pose
    }

    /// Every vertex of the solved cage's mesh where the pose takes it.
    pub fn positions(&self) -> &[DVec2] {
        &self.positions
    }
}

impl Skinning for CageDeformer {
    fn table(&self) -> SkinTable {
        let (rows, nodes, weights) = skinning_table(&self.solved.weights);
        SkinTable {
            rows,
            nodes,
            weights,
        }
    }

    fn transforms(&self) -> Vec<render::Affine> {
        pose_transforms(&self.pose)
    }
}

impl Deformer for CageDeformer {
    fn method(&self) -> Method {
        Method::Lbc
    }

    fn rest(&self) -> &[DVec2] {
        self.solved.domain.positions()
    }

    fn triangles(&self) -> &[[u32; 3]] {
        self.solved.domain.triangles()
    }

    fn follow(&mut self, project: &Project) -> Result<Follow> {
        let Some(spec) = &project.cage else {
            bail!("the rig has no \"cage\" (LBC warps by a cage)");
        };
        let rest: Vec<DVec2> = spec.rest.iter().map(|&p| DVec2::from(p)).collect();
        if rest != self.solved.rest || project.lbc.unwrap_or_default().tau != self.solved.tau {
            return Ok(Follow::NeedsSetup);
        }
        let pose = spec
            .pose
            .as_ref()
            .map_or(rest, |p| p.iter().map(|&q| DVec2::from(q)).collect());
        self.positions = self.solved.weights.deform(&pose)?;
        self.pose = pose;
        Ok(Follow::Followed)
    }

    fn deformed(&self) -> Vec<DVec2> {
        self.positions.clone()
    }

    fn output(&self) -> Output<'_> {
        Output::Skinned(self)
    }

    fn backdrop(&self) -> Backdrop {
        Backdrop::PictureOutsideMesh
    }

    fn notes(&self) -> Vec<String> {
        let report = &self.solved.report;
        if report.converged {
            return Vec::new();
        }
        let residuals = report.last.map_or(String::new(), |p| {
            format!(
                " (relative residuals {:.1e} and {:.1e} of their thresholds)",
                p.primal_residual / p.primal_threshold,
                p.dual_residual / p.dual_threshold
            )
        });
        vec![format!(
            "the cage's coordinates did not converge in {} ADMM iterations{residuals}; the \
             warp may be off",
            report.iterations
        )]
    }

    /// The nodes are the cage's vertices in order; every mesh vertex lists its non-zero
    /// `[cage vertex, weight]` pairs.
    fn weights(&self, listing: WeightsListing) -> Result<serde_json::Value> {
        let solved = &self.solved;
        let positions = solved.domain.positions();
        let nodes = solved
            .domain
            .cage_vertices()
            .iter()
            .enumerate()
            .map(|(index, &vertex)| CageNode {
                index,
                kind: "cage",
                vertex,
                position: positions[vertex as usize].to_array(),
            })
            .collect();
        json(&LbcWeights {
            method: "lbc",
            samples: positions.len(),
            file_vertices: listing.file_vertices,
            nodes,
            vertices: listing
                .positions
                .then(|| positions.iter().map(|p| p.to_array()).collect()),
            weights: (0..positions.len())
                .map(|v| solved.weights.row(v).to_vec())
                .collect(),
            iterations: solved.report.iterations,
            converged: solved.report.converged,
            objective: solved.report.objective,
        })
    }

    /// The solve's phases (as measured when it was solved) and 15 deformations.
    fn bench(&mut self, _project: &Project, _poses: usize) -> Result<serde_json::Value> {
        let solved = &self.solved;
        let mut deform = Vec::new();
        for _ in 0..15 {
            let clock = Instant::now();
            std::hint::black_box(solved.weights.deform(&self.pose)?);
            deform.push(clock.elapsed().as_secs_f64() * 1e3);
        }
        let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
        let report = &solved.report;
        json(&LbcBench {
            method: "lbc",
            samples: solved.domain.positions().len(),
            triangles: solved.domain.triangles().len(),
            cage_vertices: solved.domain.cage_vertices().len(),
            geodesics_ms: ms(report.geodesics),
            factorisation_ms: ms(report.factorisation),
            admm_iterations: report.iterations,
            admm_ms: ms(report.admm),
            admm_threads: report.threads,
            projection_ms: ms(report.projection),
            converged: report.converged,
            objective: report.objective,
            nonzeros_per_vertex: solved.weights.len() as f64
                / solved.domain.positions().len().max(1) as f64,
            deform_ms_median: median(deform),
            locality_p: solved
                .locality
                .t
                .iter()
                .zip(&solved.locality.p)
                .map(|(&t, &p)| [t, p])
                .collect(),
            locality_q: solved.locality.q.clone(),
        })
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn clone_box(&self) -> Box<dyn Deformer> {
        Box::new(self.clone())
    }
}

#[derive(Serialize)]
struct CageNode {
    index: usize,
    kind: &'static str,
    vertex: u32,
    position: [f64; 2],
}

#[derive(Serialize)]
struct LbcWeights {
    method: &'static str,
    samples: usize,
    file_vertices: usize,
    nodes: Vec<CageNode>,
    #[serde(skip_serializing_if = "Option::is_none")]
    vertices: Option<Vec<[f64; 2]>>,
    weights: Vec<Vec<(u32, f64)>>,
    iterations: usize,
    converged: bool,
    objective: f64,
}

#[derive(Serialize)]
struct LbcBench {
    method: &'static str,
    samples: usize,
    triangles: usize,
    cage_vertices: usize,
    /// The geodesics, and the Y-update's factorisation run beside them.
    geodesics_ms: f64,
    /// The factorisation alone (within `geodesics_ms`).
    factorisation_ms: f64,
    admm_iterations: usize,
    admm_ms: f64,
    /// Threads the iterations ran on (the faster of all and one, after a trial).
    admm_threads: usize,
    projection_ms: f64,
    converged: bool,
    /// Eq. (14) of the coordinates, in the rig's units.
    objective: f64,
    nonzeros_per_vertex: f64,
    deform_ms_median: f64,
    /// The paper's P(t) as `[t, P(t)]` pairs (eq. 20).
    locality_p: Vec<[f64; 2]>,
    /// The paper's Q(k) for k = 0, 1, … n (eq. 21).
    locality_q: Vec<f64>,
}

/// The compact rows as a skinning shader reads them: row `v` is
/// `nodes[rows[v]..rows[v + 1]]` with `weights` alongside (cage vertex indices and
/// their weights), as [`render::SkinnedMesh`] takes them.
pub fn skinning_table(weights: &lbc::CompactWeights) -> (Vec<u32>, Vec<u32>, Vec<f32>) {
    let mut rows = Vec::with_capacity(weights.vertices() + 1);
    let mut nodes = Vec::with_capacity(weights.len());
    let mut values = Vec::with_capacity(weights.len());
    rows.push(0);
    for v in 0..weights.vertices() {
        for &(k, w) in weights.row(v) {
            nodes.push(k);
            values.push(w as f32);
        }
        rows.push(nodes.len() as u32);
    }
    (rows, nodes, values)
}

/// The node transforms that pose a cage in the skinning shader: no linear part, the
/// posed vertex as the translation, so that `Σ wᵢ (Aᵢ x + tᵢ) = Σ wᵢ cᵢ'`.
pub fn pose_transforms(pose: &[DVec2]) -> Vec<render::Affine> {
    pose.iter()
        .map(|p| [0.0, 0.0, 0.0, 0.0, p.x as f32, p.y as f32])
        .collect()
}

/// A cage around `image`'s visible shape (every pixel with alpha > 0, in every piece;
/// for an opaque picture, the picture's rectangle), as a user would click it:
/// `offset` pixels or more outside the shape, with `vertices` vertices.
///
/// The cage encloses every visible pixel whole ([`mesh::enclosing_ring`]: the alpha
/// mask dilated by `offset`, its pieces joined, its outline traced, then brought down
/// to `vertices` vertices by steps that only add area, the cheapest first, never
/// letting edges cross). Where `vertices` cannot enclose the shape without crossing,
/// the cage has more (compare its length with `vertices` to say so); a shape whose
/// outline has fewer gets its longest edges split. It lies within the picture.
///
/// # Errors
/// `vertices` outside 3 to [`MAX_CAGE_VERTICES`], a non-finite or negative `offset`,
/// or a picture without a visible pixel.
pub fn cage_from_outline(
    image: &image::RgbaImage,
    vertices: usize,
    offset: f64,
) -> Result<Vec<DVec2>> {
    cage_around(&mesh::Coverage::of_image(image), vertices, offset)
}

/// [`cage_from_outline`] of the visible pixels `coverage` marks (for a picture read
/// row by row, [`coverage_of_file`]).
///
/// # Errors
/// As [`cage_from_outline`].
pub fn cage_around(coverage: &mesh::Coverage, vertices: usize, offset: f64) -> Result<Vec<DVec2>> {
    ensure!(
        (3..=MAX_CAGE_VERTICES).contains(&vertices),
        "a cage needs 3 to {MAX_CAGE_VERTICES} vertices, not {vertices}"
    );
    ensure!(
        offset.is_finite() && offset >= 0.0,
        "the cage's offset must be a number of pixels, not {offset}"
    );
    let enclosure = match mesh::enclosing_ring_of(coverage, vertices, offset) {
        Err(mesh::MeshError::EmptyDomain) => {
            bail!("the picture has no visible pixel to put a cage around")
        }
        other => other?,
    };
    let mut ring = enclosure.ring;
    split_longest_edges(&mut ring, vertices);
    lbc::Cage::new(ring.clone()).context("the outline does not make a simple cage")?;
    Ok(ring)
}

/// Which pixels of the picture at `path` are visible, read a row at a time (a PNG
/// is never held whole: a 16384² one costs its 32 MB bitmap).
///
/// # Errors
/// A missing, unreadable, corrupt or oversized picture, naming it.
pub fn coverage_of_file(path: &std::path::Path) -> Result<mesh::Coverage> {
    let mut reader = render::AlphaReader::open(path, &render::ImageLimits::default())
        .map_err(|e| crate::read_error(e, "image"))?;
    let (w, h) = reader.dimensions();
    let mut coverage = mesh::Coverage::new(w, h);
    let mut alpha = Vec::with_capacity(w as usize);
    let mut y = 0;
    while reader.next_row(&mut alpha)? {
        coverage.set_row(y, &alpha);
        y += 1;
    }
    Ok(coverage)
}

/// Whether `ring` is the `width × height` picture's rectangle (its four corners,
/// and any other vertices on its edges).
pub fn is_whole_picture(ring: &[DVec2], width: u32, height: u32) -> bool {
    let (w, h) = (f64::from(width), f64::from(height));
    let on_edge = |p: &DVec2| p.x == 0.0 || p.y == 0.0 || p.x == w || p.y == h;
    let corners = [
        DVec2::ZERO,
        DVec2::new(w, 0.0),
        DVec2::new(w, h),
        DVec2::new(0.0, h),
    ];
    ring.iter().all(on_edge) && corners.iter().all(|c| ring.contains(c))
}

/// How far outside a `width × height` picture's visible pixels a cage from its outline
/// runs by default: 1% of its diagonal, 3 to 20 pixels.
pub fn outline_offset(width: u32, height: u32) -> f64 {
    (0.01 * f64::from(width).hypot(f64::from(height))).clamp(3.0, 20.0)
}

/// What to tell a user who asked for a cage of `asked` vertices from the outline and
/// got `got`: nothing when they are the same.
pub fn outline_note(asked: usize, got: usize) -> Option<String> {
    (got > asked).then(|| {
        format!(
            "{asked} vertices cannot enclose the whole picture without the cage crossing \
             itself; it has {got}"
        )
    })
}

/// Splits the longest edge at its middle until `ring` has `target` vertices.
fn split_longest_edges(ring: &mut Vec<DVec2>, target: usize) {
    while ring.len() < target {
        let n = ring.len();
        let Some(longest) = (0..n).max_by(|&i, &j| {
            let len = |k: usize| ring[k].distance_squared(ring[(k + 1) % n]);
            len(i).total_cmp(&len(j))
        }) else {
            return;
        };
        let middle = (ring[longest] + ring[(longest + 1) % n]) * 0.5;
        ring.insert(longest + 1, middle);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn pose_transforms_translate_by_the_posed_vertex() {
        let a = super::pose_transforms(&[DVec2::new(3.0, -4.0)]);
        assert_eq!(a, vec![[0.0, 0.0, 0.0, 0.0, 3.0, -4.0]]);
    }

    use super::*;
    use project::Canvas;

    /// A disc and a thin bar off it, as a cut-out.
    fn cut_out() -> image::RgbaImage {
        image::RgbaImage::from_fn(200, 160, |x, y| {
            let (fx, fy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let disc = (fx - 80.0).hypot(fy - 80.0) < 50.0;
            let bar = (120.0..180.0).contains(&fx) && (70.0..90.0).contains(&fy);
            image::Rgba([10, 200, 30, if disc || bar { 255 } else { 0 }])
        })
    }

    /// The coordinates of the cage `rest` posed at `pose`, solved on `count` vertices.
    fn solved(
        rest: Vec<[f64; 2]>,
        pose: Option<Vec<[f64; 2]>>,
        count: usize,
    ) -> Arc<CageCoordinates> {
        let project = Project {
            method: Method::Lbc,
            cage: Some(project::CageSpec { rest, pose }),
            ..Project::default()
        };
        let solved = cage_coordinates(
            &project,
            CageMesh::Triangulate {
                target_vertices: count,
            },
            &mut |_| true,
        );
        Arc::new(solved.expect("solved"))
    }

    /// The warper of `solved` with the cage in `pose`.
    fn warper(solved: &Arc<CageCoordinates>, pose: &[DVec2], canvas: Canvas) -> crate::Warper {
        let deformer = CageDeformer::new(solved.clone(), pose.to_vec()).expect("a pose");
        let project = Project {
            canvas,
            ..Project::default()
        };
        crate::Warper::in_mesh_order(Box::new(deformer), &project)
    }

    /// `image` warped by the cage of `solved` in `pose`.
    fn warp_by_cage_posed(
        image: &image::RgbaImage,
        solved: &Arc<CageCoordinates>,
        pose: &[DVec2],
        canvas: Canvas,
    ) -> image::RgbaImage {
        crate::warp(image, &warper(solved, pose, canvas)).expect("warp")
    }

    /// `image` warped by the cage of `solved` in the pose it was solved with.
    fn warp_by_cage(
        image: &image::RgbaImage,
        solved: &Arc<CageCoordinates>,
        canvas: Canvas,
    ) -> image::RgbaImage {
        warp_by_cage_posed(image, solved, &solved.pose, canvas)
    }

    /// A 60 × 40 picture of colour ramps.
    fn ramps() -> image::RgbaImage {
        image::RgbaImage::from_fn(60, 40, |x, y| {
            image::Rgba([(x * 4) as u8, (y * 6) as u8, 90, 255])
        })
    }

    #[test]
    fn an_outline_cage_has_the_vertices_asked_for_and_encloses_the_whole_shape() {
        let image = cut_out();
        for n in [6, 16, 40] {
            let ring = cage_from_outline(&image, n, 6.0).expect("a cage");
            assert_eq!(ring.len(), n);
            assert_eq!(outline_note(n, ring.len()), None);
            let cage = lbc::Cage::new(ring.clone()).expect("simple");
            // Outside the shape: no vertex on a visible pixel.
            for p in &ring {
                let (x, y) = (p.x.floor() as u32, p.y.floor() as u32);
                if x < 200 && y < 160 {
                    assert_eq!(image.get_pixel(x, y).0[3], 0, "vertex {p} on the shape");
                }
            }
            for (x, y, px) in image.enumerate_pixels() {
                if px.0[3] > 0 {
                    let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                    assert!(cage.contains(c), "{n} vertices leave ({x}, {y}) out");
                }
            }
        }
        assert!(outline_note(8, 9).is_some_and(|m| m.contains("has 9")));
    }

    #[test]
    fn an_opaque_picture_gets_its_rectangle_split_evenly() {
        let image = image::RgbaImage::from_pixel(100, 50, image::Rgba([1, 2, 3, 255]));
        let ring = cage_from_outline(&image, 12, 4.0).expect("a cage");
        assert_eq!(ring.len(), 12);
        let cage = lbc::Cage::new(ring.clone()).expect("simple");
        assert!((cage.area() - 5000.0).abs() < 1e-9);
        assert!(
            ring.iter()
                .all(|p| p.x >= 0.0 && p.x <= 100.0 && p.y >= 0.0 && p.y <= 50.0)
        );
    }

    #[test]
    fn bad_requests_are_refused() {
        let image = cut_out();
        assert!(cage_from_outline(&image, 2, 4.0).is_err());
        assert!(cage_from_outline(&image, 5000, 4.0).is_err());
        assert!(cage_from_outline(&image, 8, f64::NAN).is_err());
        assert!(cage_from_outline(&image::RgbaImage::new(30, 30), 8, 4.0).is_err());
    }

    #[test]
    fn cage_density_follows_the_command_line_then_lbc_then_the_rig() {
        let mut project = Project::default();
        assert_eq!(cage_vertices(&project, None), DEFAULT_CAGE_VERTICES);
        // By default, as fine as the picture's own mesh…
        assert_eq!(DEFAULT_CAGE_VERTICES, crate::DEFAULT_DENSITY);
        // …unless the cage has so many vertices that the solve would be refused.
        let ring = |n: usize| {
            (0..n)
                .map(|i| {
                    let a = i as f64 / n as f64 * std::f64::consts::TAU;
                    [100.0 * a.cos(), 100.0 * a.sin()]
                })
                .collect()
        };
        project.cage = Some(project::CageSpec {
            rest: ring(1000),
            pose: None,
        });
        assert_eq!(cage_vertices(&project, None), 3000);
        assert!(check_work(cage_vertices(&project, None), 1000).is_ok());
        project.cage = Some(project::CageSpec {
            rest: ring(26),
            pose: None,
        });
        assert_eq!(cage_vertices(&project, None), DEFAULT_CAGE_VERTICES);
        project.density = Some(5000);
        assert_eq!(cage_vertices(&project, None), 5000);
        project.lbc = Some(project::LbcSettings {
            density: Some(300),
            ..Default::default()
        });
        assert_eq!(cage_vertices(&project, None), 300);
        assert_eq!(cage_vertices(&project, Some(700)), 700);
    }

    #[test]
    fn a_cage_at_rest_gives_the_picture_back_exactly() {
        // Every kind of pixel (opaque, half-covered, transparent), and cages inside
        // the picture, on its border (edges through pixel edges and corners) and
        // around a concave notch, each at a density where many weights are dropped.
        let image = image::RgbaImage::from_fn(90, 70, |x, y| {
            let a = [255, 128, 0, 37][((x / 3 + y / 5) % 4) as usize];
            image::Rgba([(x * 3) as u8, (y * 3) as u8, ((x * y) % 256) as u8, a])
        });
        let cages = [
            vec![[10.5, 8.25], [61.0, 12.0], [70.0, 50.5], [20.0, 60.0]],
            vec![[0.0, 0.0], [90.0, 0.0], [90.0, 70.0], [0.0, 70.0]],
            vec![
                [0.0, 0.0],
                [90.0, 0.0],
                [90.0, 70.0],
                [60.0, 70.0],
                [45.0, 20.0],
                [30.0, 70.0],
                [0.0, 70.0],
            ],
        ];
        for rest in cages {
            let solved = solved(rest, None, 400);
            let at_rest = warp_by_cage(&image, &solved, Canvas::Keep);
            let changed = at_rest
                .pixels()
                .zip(image.pixels())
                .filter(|(a, b)| a != b)
                .count();

            assert_eq!(changed, 0, "{:?}", solved.domain.cage().vertices());
        }
    }

    #[test]
    fn a_grown_canvas_holds_what_the_cage_takes_beyond_the_picture() {
        let image = ramps();
        let square = vec![[10.0, 10.0], [40.0, 10.0], [40.0, 30.0], [10.0, 30.0]];
        let moved = vec![[40.0, -5.0], [70.0, -5.0], [70.0, 15.0], [40.0, 15.0]];
        let solved = solved(square, Some(moved), 120);
        let kept = warp_by_cage(&image, &solved, Canvas::Keep);
        let grown = warp_by_cage(&image, &solved, Canvas::Fit);
        assert_eq!(kept.dimensions(), (60, 40));
        // Moved 30 right and 15 up: the canvas grows to x ∈ [0, 70], y ∈ [−5, 40].
        assert_eq!(grown.dimensions(), (70, 45));
        // The picture's frame sits 5 px down in it, as kept.
        let frame = image::imageops::crop_imm(&grown, 0, 5, 60, 40).to_image();
        assert_eq!(frame, kept);
        // Beyond the picture's right edge: the cage's inside, not nothing.
        assert_eq!(grown.get_pixel(65, 10).0[3], 255);
        assert_eq!(grown.get_pixel(65, 30).0[3], 0);
    }

    #[test]
    fn a_posed_warp_moves_the_inside_and_keeps_the_outside() {
        let image = ramps();
        let square = vec![[10.0, 10.0], [40.0, 10.0], [40.0, 30.0], [10.0, 30.0]];
        let solved = solved(square, None, 120);
        let at_rest = warp_by_cage(&image, &solved, Canvas::Keep);
        let shift: Vec<DVec2> = solved
            .pose
            .iter()
            .map(|p| *p + DVec2::new(5.0, 0.0))
            .collect();
        let moved = warp_by_cage_posed(&image, &solved, &shift, Canvas::Keep);
        // Outside the rest cage and away from its moved copy: untouched.
        for (x, y) in [(2, 2), (55, 35), (5, 20)] {
            assert_eq!(moved.get_pixel(x, y), image.get_pixel(x, y));
        }
        // Inside: the picture shifted right by 5 pixels.
        assert_eq!(moved.get_pixel(30, 20), at_rest.get_pixel(25, 20));
        assert_ne!(moved.get_pixel(30, 20), image.get_pixel(30, 20));
    }

    #[test]
    fn a_sixteen_bit_picture_warps_by_its_cage_in_sixteen_bits() {
        let wide = render::Rgba16Image::from_fn(60, 40, |x, y| {
            image::Rgba([(x * 1000) as u16 + 7, (y * 1500) as u16 + 3, 40_001, 65_535])
        });
        let picture = render::Picture::Rgba16(wide.clone());
        let square = vec![[10.0, 10.0], [40.0, 10.0], [40.0, 30.0], [10.0, 30.0]];
        let solved = solved(square, None, 120);
        // At rest: every 16-bit value back, inside the cage and out.
        let at_rest = crate::warp_picture(&picture, &warper(&solved, &solved.pose, Canvas::Keep))
            .expect("warp");
        assert_eq!(at_rest, picture);
        // Moved 5 px right: the inside shifted in 16 bits, the outside kept.
        let shift: Vec<DVec2> = solved.pose.iter().map(|p| *p + DVec2::X * 5.0).collect();
        let moved =
            crate::warp_picture(&picture, &warper(&solved, &shift, Canvas::Keep)).expect("warp");
        let render::Picture::Rgba16(moved) = moved else {
            panic!("16 bits in, 16 bits out");
        };
        assert_eq!(moved.get_pixel(30, 20), wide.get_pixel(25, 20));
        assert_eq!(moved.get_pixel(55, 35), wide.get_pixel(55, 35));
    }

    #[test]
    fn the_deformer_follows_a_new_pose_and_asks_for_a_solve_for_a_new_cage() {
        let square = vec![[10.0, 10.0], [40.0, 10.0], [40.0, 30.0], [10.0, 30.0]];
        let solved = solved(square.clone(), None, 120);
        let mut deformer = CageDeformer::new(solved.clone(), solved.pose.clone()).expect("pose");
        let mut project = Project {
            method: Method::Lbc,
            cage: Some(project::CageSpec {
                rest: square.clone(),
                pose: Some(square.iter().map(|p| [p[0] + 3.0, p[1] - 2.0]).collect()),
            }),
            ..Project::default()
        };
        assert_eq!(deformer.follow(&project).expect("a pose"), Follow::Followed);
        // A translated cage translates everything inside it, to rounding.
        for (p, q) in deformer.rest().iter().zip(deformer.deformed()) {
            assert!((q - *p - DVec2::new(3.0, -2.0)).length() < 1e-9);
        }
        assert_eq!(deformer.backdrop(), Backdrop::PictureOutsideMesh);
        // Another rest cage, or another τ: a new solve; nothing changed meanwhile.
        let before = deformer.deformed();
        let mut other = project.clone();
        other.cage.as_mut().expect("a cage").rest[0] = [9.0, 10.0];
        assert_eq!(
            deformer.follow(&other).expect("no error"),
            Follow::NeedsSetup
        );
        other = project.clone();
        other.lbc = Some(project::LbcSettings {
            tau: Tau::Linear,
            ..Default::default()
        });
        assert_eq!(
            deformer.follow(&other).expect("no error"),
            Follow::NeedsSetup
        );
        assert_eq!(deformer.deformed(), before);
        // A pose of the wrong length is an error.
        project.cage.as_mut().expect("a cage").pose = Some(vec![[0.0, 0.0]]);
        assert!(deformer.follow(&project).is_err());
        assert_eq!(deformer.deformed(), before);
    }
}
