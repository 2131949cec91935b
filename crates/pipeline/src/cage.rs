//! Local barycentric coordinates of a rig file's cage (the `lbc` crate): the cage's
//! inside triangulated (or a given mesh of it), the coordinates solved, and the
//! posed cage.
//!
//! LBC is a cage method: it moves what lies inside the cage by the cage's vertices;
//! it has no handles. The command line's `weights`, `deform` and `bench` use it; the
//! editor's cage tool and drawing a picture by it are not built yet.

use anyhow::{Context, Result, bail};
use glam::DVec2;
use project::{Method, Project, Tau};

/// Where the mesh of the cage's inside comes from.
pub enum CageMesh {
    /// Triangulate the inside to about this many vertices.
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
    let cage = lbc::Cage::new(rest).context("the rig's cage")?;
    let domain = match mesh {
        CageMesh::Triangulate { target_vertices } => {
            lbc::Domain::triangulate(&cage, target_vertices)
                .context("cannot triangulate the cage")?
        }
        CageMesh::Given {
            positions,
            triangles,
        } => lbc::Domain::from_mesh(&cage, positions, triangles)
            .context("the mesh does not fit the cage")?,
    };
    let settings = lbc::Settings {
        tau: match project.lbc.unwrap_or_default().tau {
            Tau::Square => lbc::Tau::Square,
            Tau::Linear => lbc::Tau::Linear,
            Tau::Constant => lbc::Tau::Constant,
            Tau::Sqrt => lbc::Tau::Sqrt,
        },
        ..lbc::Settings::default()
    };
    let coordinates = lbc::solve(&domain, &settings, progress)?;
    let report = coordinates.report.clone();
    Ok(CageCoordinates {
        weights: coordinates.compact(),
        domain,
        report,
        pose,
    })
}

/// Whether `project` (with `method` overriding its own) warps by a cage.
pub fn uses_cage(project: &Project, method: Option<Method>) -> bool {
    method.unwrap_or(project.method) == Method::Lbc
}
