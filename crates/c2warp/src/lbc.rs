//! The command line's side of LBC cages: the cage's inside meshed (or read), the
//! coordinates solved with a progress counter, and `c2warp weights` / `bench` output.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use pipeline::cage::{CageCoordinates, CageMesh, cage_coordinates};
use project::Project;
use serde::Serialize;

use crate::Source;

/// Meshes the inside of `project`'s cage (`--image`: triangulated to `--density`, the
/// rig's `lbc.density`, its `density` or [`pipeline::cage::DEFAULT_CAGE_VERTICES`]:
/// [`pipeline::cage::cage_vertices`]; `--mesh`: the file's triangulation, as is) and
/// solves its coordinates, with a progress counter.
pub fn solve(source: &Source, project: &Project) -> Result<CageCoordinates> {
    let mesh = if let Some(path) = &source.image {
        let image = pipeline::load_image(path)?;
        project.validate(Some(image.dimensions()))?;
        let target_vertices = pipeline::cage::cage_vertices(project, source.density);
        project::validate_density(target_vertices)?;
        CageMesh::Triangulate { target_vertices }
    } else {
        let path = source.mesh.as_deref().context("give --mesh or --image")?;
        let mesh = pipeline::load_obj(path)?;
        mesh.sanity_check()
            .with_context(|| format!("mesh {}", path.display()))?;
        CageMesh::Given {
            positions: mesh.vertices,
            triangles: mesh.triangles,
        }
    };
    solve_on(project, mesh)
}

/// Solves `project`'s cage on `mesh` with a progress counter.
pub fn solve_on(project: &Project, mesh: CageMesh) -> Result<CageCoordinates> {
    let progress = crate::progress::Steps::new(1);
    progress.step("solving the cage's coordinates");
    let solved = cage_coordinates(project, mesh, &mut |p| {
        progress.message(format!(
            "solving the cage's coordinates: iteration {}, residuals {:.1e} / {:.1e}",
            p.iteration, p.primal_residual, p.dual_residual
        ));
        true
    })?;
    progress.finish();
    let report = &solved.report;
    if !report.converged {
        let residuals = report.last.map_or(String::new(), |p| {
            format!(
                " (relative residuals {:.1e} and {:.1e} of their thresholds)",
                p.primal_residual / p.primal_threshold,
                p.dual_residual / p.dual_threshold
            )
        });
        eprintln!(
            "warning: the cage's coordinates did not converge in {} ADMM iterations{residuals}; \
             the warp may be off",
            report.iterations
        );
    }
    Ok(solved)
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

/// `c2warp render` for a cage: the inside of the rest cage drawn where the posed cage
/// takes it, the rest of the picture as it is (8 bits per channel; with `gpu` the
/// inside is drawn by the GPU's skinning shader from the compact rows).
pub fn render(
    picture: &render::Picture,
    project: &Project,
    density: Option<usize>,
    gpu: bool,
) -> Result<render::Picture> {
    let image = picture.to_rgba8();
    project.validate(Some(image.dimensions()))?;
    let target_vertices = pipeline::cage::cage_vertices(project, density);
    project::validate_density(target_vertices)?;
    let solved = solve_on(project, CageMesh::Triangulate { target_vertices })?;
    let warped = if gpu {
        pipeline::cage::warp_by_cage_gpu(&image, &solved, project.canvas)?
    } else {
        pipeline::cage::warp_by_cage(&image, &solved, project.canvas)?
    };
    Ok(render::Picture::Rgba8(warped))
}

/// `c2warp weights` for a cage: the nodes are the cage's vertices in order; every mesh
/// vertex lists its non-zero `[cage vertex, weight]` pairs.
pub fn weights(source: &Source, project: &Project, output: &Path) -> Result<()> {
    let solved = solve(source, project)?;
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
    let out = LbcWeights {
        method: "lbc",
        samples: positions.len(),
        file_vertices: positions.len(),
        nodes,
        vertices: source
            .image
            .as_ref()
            .map(|_| positions.iter().map(|p| p.to_array()).collect()),
        weights: (0..positions.len())
            .map(|v| solved.weights.row(v).to_vec())
            .collect(),
        iterations: solved.report.iterations,
        converged: solved.report.converged,
        objective: solved.report.objective,
    };
    let text = serde_json::to_string(&out)?;
    crate::write_text(output, text.as_bytes())?;
    Ok(())
}

#[derive(Serialize)]
struct LbcBench {
    method: &'static str,
    samples: usize,
    triangles: usize,
    cage_vertices: usize,
    geodesics_ms: f64,
    factorisation_ms: f64,
    admm_iterations: usize,
    admm_ms: f64,
    projection_ms: f64,
    converged: bool,
    nonzeros_per_vertex: f64,
    deform_ms_median: f64,
    /// The paper's P(t) as `[t, P(t)]` pairs (eq. 20).
    locality_p: Vec<[f64; 2]>,
    /// The paper's Q(k) for k = 0, 1, … n (eq. 21).
    locality_q: Vec<f64>,
}

/// `c2warp bench` for a cage.
pub fn bench(source: &Source, project: &Project) -> Result<()> {
    let solved = solve(source, project)?;
    let mut deform = Vec::new();
    for _ in 0..15 {
        let clock = Instant::now();
        std::hint::black_box(solved.deformed()?);
        deform.push(clock.elapsed().as_secs_f64() * 1e3);
    }
    deform.sort_by(f64::total_cmp);
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    let report = &solved.report;
    let out = LbcBench {
        method: "lbc",
        samples: solved.domain.positions().len(),
        triangles: solved.domain.triangles().len(),
        cage_vertices: solved.domain.cage_vertices().len(),
        geodesics_ms: ms(report.geodesics),
        factorisation_ms: ms(report.factorisation),
        admm_iterations: report.iterations,
        admm_ms: ms(report.admm),
        projection_ms: ms(report.projection),
        converged: report.converged,
        nonzeros_per_vertex: solved.weights.len() as f64
            / solved.domain.positions().len().max(1) as f64,
        deform_ms_median: deform[deform.len() / 2],
        locality_p: solved
            .locality
            .t
            .iter()
            .zip(&solved.locality.p)
            .map(|(&t, &p)| [t, p])
            .collect(),
        locality_q: solved.locality.q.clone(),
    };
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
