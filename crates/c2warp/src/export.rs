//! `c2warp weights`: the nodes and sparse weights of a method (C² weights, LBC
//! coordinates), as JSON.

use std::path::Path;

use anyhow::Result;
use pipeline::{WeightsListing, load_project};

use crate::{Input, Source};

/// Runs `c2warp weights`: sets up the rig file's method on the source and writes what
/// [`pipeline::Deformer::weights`] lists.
pub fn weights(source: &Source, rig_path: &Path, output: &Path) -> Result<()> {
    let project = load_project(rig_path)?;
    let files = source.files(rig_path, &project)?;
    render::refuse_input_as_output(output, &crate::inputs(rig_path, &files))?;
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
