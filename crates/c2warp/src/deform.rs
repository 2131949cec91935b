//! `c2warp deform`: the deformed mesh as Wavefront OBJ, by any method.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use glam::DVec2;
use pipeline::{Method, load_project};
use project::Project;

use crate::{Input, Source};

/// Runs `c2warp deform`: meshes (or reads) the samples, sets up `method` (else the
/// rig's) for the rig's controls and pose, and writes one `v x y 0` line per vertex in
/// full precision — the file's vertices in its order, then those the command inserted
/// — and the triangles as `f a b c` (1-based).
pub fn run(
    source: &Source,
    rig_path: &Path,
    method: Option<Method>,
    parts: bool,
    output: &Path,
) -> Result<()> {
    let mut project = load_project(rig_path)?;
    if let Some(method) = method {
        project.method = method;
    }
    let files = source.files(rig_path, &project)?;
    render::refuse_input_as_output(output, &crate::inputs(rig_path, &files))?;
    if parts || (project.parts.is_some() && source.mesh.is_none()) {
        if source.mesh.is_some() {
            bail!("--parts meshes each layer of a picture: give --image, not --mesh");
        }
        return run_parts(&files, source.density, &project, output);
    }
    let input = Input::load(source, &files)?;
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

/// `deform --parts`: every visible layer of the picture `file` set up as a part
/// ([`pipeline::set_up_parts`]), each written as an OBJ object (`o` and the layer's
/// name) of its deformed vertices and triangles, in the draw order.
fn run_parts(
    files: &[PathBuf],
    density: Option<usize>,
    project: &Project,
    output: &Path,
) -> Result<()> {
    let artwork = crate::load_artwork_noting(files)?;
    let progress = crate::progress::Steps::new(2);
    progress.step("meshing, weighting and posing every part");
    let set = pipeline::set_up_parts(&artwork, project, density, &progress)?;
    progress.step("writing");
    let parts: Vec<(&str, &pipeline::PartMesh)> = (set.order.iter())
        .filter_map(|&k| Some((artwork.layers[k].name.as_str(), set.meshes[k].as_ref()?)))
        .collect();
    let vertices: usize = parts.iter().map(|(_, m)| m.deformed.len()).sum();
    let triangles: usize = parts.iter().map(|(_, m)| m.triangles.len()).sum();
    let mut text = String::with_capacity(vertices * 40 + triangles * 24);
    let _ = writeln!(
        text,
        "# c2warp deform --parts, method {}: {} parts, {vertices} vertices, {triangles} triangles",
        project.method.name(),
        parts.len(),
    );
    let mut first = 1;
    for (name, mesh) in parts {
        if let Some(v) = mesh.deformed.iter().position(|p| !p.is_finite()) {
            bail!("the deformation sent vertex {v} of part \"{name}\" to a non-finite position");
        }
        // An object's name is the rest of its line: one line, whatever the layer's.
        let name: String = name
            .chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .collect();
        let _ = writeln!(text, "o {name}");
        for p in &mesh.deformed {
            let _ = writeln!(text, "v {} {} 0", p.x, p.y);
        }
        for t in &mesh.triangles {
            let _ = writeln!(
                text,
                "f {} {} {}",
                t[0] as usize + first,
                t[1] as usize + first,
                t[2] as usize + first
            );
        }
        first += mesh.deformed.len();
    }
    crate::write_text(output, text.as_bytes())?;
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
