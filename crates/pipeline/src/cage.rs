//! Local barycentric coordinates of a rig file's cage (the `lbc` crate): the cage's
//! inside triangulated (or a given mesh of it), the coordinates solved, and the
//! posed cage.
//!
//! LBC is a cage method: it moves what lies inside the cage by the cage's vertices;
//! it has no handles. The command line's `render`, `weights`, `deform` and `bench`
//! use it; the editor's cage tool is not built yet.

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
    /// The paper's locality statistics `P(t)` (at `t` = 0, `10⁻³/n`, 0.01, 0.05, 0.1,
    /// 0.2, …, 1) and `Q(k)`, of the coordinates before compaction.
    pub locality: lbc::Locality,
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
    let n = coordinates.cage_vertices().max(1) as f64;
    let mut t = vec![0.0, 1e-3 / n, 0.01, 0.05];
    t.extend((1..=10).map(|k| f64::from(k) / 10.0));
    let locality = lbc::locality(&domain, &coordinates, &t);
    Ok(CageCoordinates {
        weights: coordinates.compact(),
        domain,
        report,
        locality,
        pose,
    })
}

/// Whether `project` (with `method` overriding its own) warps by a cage.
pub fn uses_cage(project: &Project, method: Option<Method>) -> bool {
    method.unwrap_or(project.method) == Method::Lbc
}

/// The picture warped by a cage, as GIMP's cage tool does it: what lies inside the
/// rest cage is taken out and drawn where the posed cage takes it; what lies outside
/// stays as it is, and shows wherever the warped inside does not cover it (the warped
/// inside is drawn over it, alpha blended). Drawn on the CPU at full resolution, 8 bits
/// per channel.
///
/// # Errors
/// Non-finite deformed positions, or a picture too large to draw.
pub fn warp_by_cage(
    image: &image::RgbaImage,
    solved: &CageCoordinates,
) -> Result<image::RgbaImage> {
    let deformed = solved.deformed()?;
    if deformed.iter().any(|p| !p.is_finite()) {
        bail!("the cage sent a vertex to a non-finite position");
    }
    let rest: Vec<glam::Vec2> = solved
        .domain
        .positions()
        .iter()
        .map(|p| p.as_vec2())
        .collect();
    let deformed: Vec<glam::Vec2> = deformed.iter().map(|p| p.as_vec2()).collect();
    let (w, h) = image.dimensions();
    let layer = render::warp_cpu(
        image,
        &render::WarpMesh {
            rest: &rest,
            deformed: &deformed,
            triangles: solved.domain.triangles(),
        },
        w,
        h,
        &render::RasterOptions::default(),
    )?;
    let mut out = image.clone();
    clear_inside(&mut out, solved.domain.cage().vertices());
    for (base, top) in out.pixels_mut().zip(layer.pixels()) {
        *base = over(top.0, base.0).into();
    }
    Ok(out)
}

/// Makes every pixel whose centre lies inside the polygon `cage` transparent (even-odd
/// rule, one scan line per row).
fn clear_inside(image: &mut image::RgbaImage, cage: &[DVec2]) {
    let (w, h) = image.dimensions();
    let mut crossings = Vec::new();
    for y in 0..h {
        let cy = f64::from(y) + 0.5;
        crossings.clear();
        for (i, &a) in cage.iter().enumerate() {
            let b = cage[(i + 1) % cage.len()];
            if (a.y <= cy) != (b.y <= cy) {
                crossings.push(a.x + (cy - a.y) / (b.y - a.y) * (b.x - a.x));
            }
        }
        crossings.sort_by(f64::total_cmp);
        for span in crossings.chunks_exact(2) {
            // Pixels whose centre x + 0.5 lies in [span[0], span[1]).
            let first = (span[0] - 0.5).ceil().max(0.0);
            let last = (span[1] - 0.5).ceil().min(f64::from(w));
            let (first, last) = (first as u32, last as u32);
            for x in first..last.max(first) {
                image.put_pixel(x, y, image::Rgba([0, 0, 0, 0]));
            }
        }
    }
}

/// `top` over `base`, straight (not premultiplied) alpha.
fn over(top: [u8; 4], base: [u8; 4]) -> [u8; 4] {
    let (ta, ba) = (f32::from(top[3]) / 255.0, f32::from(base[3]) / 255.0);
    let a = ta + ba * (1.0 - ta);
    if a <= 0.0 {
        return [0; 4];
    }
    let mut out = [0u8; 4];
    for c in 0..3 {
        let v = (f32::from(top[c]) * ta + f32::from(base[c]) * ba * (1.0 - ta)) / a;
        out[c] = v.round().clamp(0.0, 255.0) as u8;
    }
    out[3] = (a * 255.0).round() as u8;
    out
}
