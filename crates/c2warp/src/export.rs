//! `c2warp weights`: the nodes and sparse weights of a method (C² weights, LBC
//! coordinates), as JSON.

use std::path::Path;

use anyhow::Result;
use pipeline::{Deformer as _, WeightsListing, load_project};

use crate::{Input, Source};

/// Runs `c2warp weights`: sets up the rig file's method on the source and writes what
/// [`pipeline::Deformer::weights`] lists.
pub fn weights(source: &Source, rig_path: &Path, output: &Path) -> Result<()> {
    let project = load_project(rig_path)?;
    let files = source.files(rig_path, &project)?;
    render::refuse_input_as_output(output, &crate::inputs(rig_path, &files))?;
    if project.parts.is_some() && source.mesh.is_none() {
        return weights_by_parts(&files, source.density, &project, output);
    }
    let input = Input::load(source, &files)?;
    let progress = crate::progress::Steps::new(2);
    progress.step("meshing and weighting");
    let warper = pipeline::setup(input.source(), &project, &progress)?;
    crate::warn(&*warper.deformer);
    progress.step("writing");
    let deformer = &warper.deformer;
    let listing = WeightsListing {
        file_vertices: input.file_vertices().unwrap_or(deformer.rest().len()),
        positions: input.is_picture(),
    };
    let text = serde_json::to_string(&deformer.weights(listing)?)?;
    crate::write_text(output, text.as_bytes())?;
    progress.finish();
    Ok(())
}

/// `c2warp weights` of a picture drawn as parts (a rig file with `"parts"`): each
/// part's weights as its method lists them on its own mesh (`{"parts": [{"layer",
/// "name", "handles", "weights"}]}`, in the draw order; a part no handle binds lists
/// the part it follows instead).
fn weights_by_parts(
    files: &[std::path::PathBuf],
    density: Option<usize>,
    project: &project::Project,
    output: &Path,
) -> Result<()> {
    let artwork = crate::load_artwork_noting(files)?;
    let progress = crate::progress::Steps::new(2);
    progress.step("meshing and weighting every part");
    let parts = pipeline::PartsDeformer::new(&artwork, project, density, &progress)?;
    progress.step("writing");
    let listing = WeightsListing {
        file_vertices: 0,
        positions: true,
    };
    let text = serde_json::to_string(&parts.weights(listing)?)?;
    crate::write_text(output, text.as_bytes())?;
    progress.finish();
    Ok(())
}
