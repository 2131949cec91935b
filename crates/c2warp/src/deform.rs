//! `c2warp deform`: the deformed mesh as Wavefront OBJ, by any method.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Result, bail};
use glam::DVec2;
use pipeline::{Method, load_project};

use crate::{Input, Source};

/// Runs `c2warp deform`: meshes (or reads) the samples, sets up `method` (else the
/// rig's) for the rig's controls and pose, and writes one `v x y 0` line per vertex in
/// full precision — the file's vertices in its order, then those the command inserted
/// — and the triangles as `f a b c` (1-based).
pub fn run(source: &Source, rig_path: &Path, method: Option<Method>, output: &Path) -> Result<()> {
    let mut project = load_project(rig_path)?;
    if let Some(method) = method {
        project.method = method;
    }
    let file = source.file(rig_path, &project)?;
    render::refuse_input_as_output(output, &[rig_path, &file])?;
    let input = Input::load(source, &file)?;
    let progress = crate::progress::Steps::new(3);
    progress.step("meshing and weighting");
    // With --mesh, the given mesh is the method's own (ARAP solves on it, LBC takes it
    // as the cage's inside); with --image, each meshes the picture its own way.
    let warper = pipeline::setup(input.source(), &project, &progress)?;
    crate::warn(&*warper.deformer);
    progress.step("deforming");
    let deformer = &warper.deformer;
    let deformed = deformer.deformed();
    progress.step("writing");
    write_obj(output, project.method, &deformed, deformer.triangles())?;
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
