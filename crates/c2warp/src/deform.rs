//! `c2warp deform`: the deformed mesh as Wavefront OBJ, by any method.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Result, bail};
use glam::DVec2;
use pipeline::{Method, load_project};

use crate::Source;
use crate::export::{self, Built};

/// Runs `c2warp deform`: meshes (or reads) the samples, sets up `method` (else the
/// rig's) for the rig's handles and pose, and writes one `v x y 0` line per vertex in
/// full precision — the file's vertices in its order, then those the command inserted
/// — and the triangles as `f a b c` (1-based).
pub fn run(source: &Source, rig_path: &Path, method: Option<Method>, output: &Path) -> Result<()> {
    let mut project = load_project(rig_path)?;
    let method = method.unwrap_or(project.method);
    project.method = method;
    if method == Method::Lbc {
        let solved = crate::lbc::solve(source, &project)?;
        let deformed = solved.deformed()?;
        return write_obj(output, method, &deformed, solved.domain.triangles());
    }
    let progress = crate::progress::Steps::new(3);
    progress.step("meshing and weighting");
    let Built { rig, picture, .. } = export::build(source, &project, &progress.weighting())?;
    progress.step("deforming");
    // With --mesh, the given mesh is ARAP's own; with --image, ARAP meshes the picture.
    let deformer = pipeline::deformer(&project, rig, picture.as_ref())?;
    let deformed = deformer.deformed();
    progress.step("writing");
    write_obj(output, method, &deformed, deformer.domain().triangles())?;
    progress.finish();
    Ok(())
}

/// Writes the deformed mesh as OBJ to `output` (`-`: standard output), atomically
/// for a regular file.
fn write_obj(
    output: &Path,
    method: Method,
    deformed: &[DVec2],
    triangles: &[[u32; 3]],
) -> Result<()> {
    if let Some(v) = deformed.iter().position(|p| !p.is_finite()) {
        bail!("the deformation sent vertex {v} to a non-finite position");
    }
    let mut text = String::with_capacity(deformed.len() * 40 + triangles.len() * 24);
    let _ = writeln!(
        text,
        "# c2warp deform, method {}: {} vertices, {} triangles",
        method.name(),
        deformed.len(),
        triangles.len()
    );
    for p in deformed {
        // `{}` prints the shortest decimal that reads back as the same f64.
        let _ = writeln!(text, "v {} {} 0", p.x, p.y);
    }
    for t in triangles {
        let _ = writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    crate::write_text(output, text.as_bytes())?;
    Ok(())
}
