//! `c2warp bench`: one JSON object of timings for a rig, by its method.

use std::path::Path;

use anyhow::Result;
use pipeline::{Deformer as _, Method, load_project};

use crate::{Input, Source};

/// Runs `c2warp bench` for `method` (else the rig's): sets it up on the source (no
/// progress shown: it would disturb the timings) and prints what
/// [`pipeline::Deformer::bench`] measures.
pub fn run(
    source: &Source,
    rig_path: &Path,
    positions: usize,
    method: Option<Method>,
) -> Result<()> {
    let mut project = load_project(rig_path)?;
    if let Some(method) = method {
        project.method = method;
    }
    let files = source.files(rig_path, &project)?;
    let report = if project.parts.is_some() && source.mesh.is_none() {
        // A picture drawn as parts: every part set up, each pose posing them all.
        let artwork = crate::load_artwork_noting(&files)?;
        let mut parts = pipeline::PartsDeformer::new(&artwork, &project, source.density, &())?;
        parts.bench(&project, positions)?
    } else {
        let input = Input::load(source, &files)?;
        let mut warper = pipeline::setup(input.source(), &project, &())?;
        crate::warn(&*warper.deformer);
        warper.deformer.bench(&project, positions)?
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
