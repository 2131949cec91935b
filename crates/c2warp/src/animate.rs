//! `c2warp animate`: every frame of a project's animation, written as an animated
//! PNG, animated WebP, GIF or PNG sequence.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use anyhow::{Context, Result};
use pipeline::animate::{Animator, Span, plan};
use pipeline::load_project;
use render::AnimationFormat;

/// What `c2warp animate` was asked.
pub struct Request<'a> {
    /// The project (a rig file with keys).
    pub project: &'a Path,
    /// The picture, if given (else the project's `"image"`).
    pub image: Option<&'a Path>,
    /// The animation's file, or a folder for a PNG sequence.
    pub output: &'a Path,
    /// Rate and range (each defaulting to the project's).
    pub span: Span,
    /// Draw on the GPU.
    pub gpu: bool,
    /// Animate a layered picture as parts.
    pub parts: bool,
}

/// Runs `c2warp animate`: checks the output's form, the rate and the range before any
/// work, sets the method up once, then draws and writes every frame (with a progress
/// counter on a terminal).
pub fn run(request: &Request) -> Result<()> {
    let format = AnimationFormat::from_path(request.output)?;
    let project = load_project(request.project)?;
    let frames = plan(&project, request.span, format)
        .with_context(|| format!("cannot animate {}", request.project.display()))?;
    let pictures = match request.image {
        Some(image) => vec![image.to_path_buf()],
        None => crate::named_pictures(request.project, &project)?,
    };
    render::refuse_input_as_output(request.output, &crate::inputs(request.project, &pictures))?;
    if request.parts || project.parts.is_some() {
        anyhow::ensure!(!request.gpu, "parts are drawn on the CPU: leave out --gpu");
        let artwork = crate::load_artwork_noting(&pictures)?;
        let progress = crate::progress::Steps::new(1);
        progress.step("meshing every part, then drawing and writing frames");
        let listener = &progress;
        pipeline::animate_parts(
            &artwork,
            &project,
            &frames,
            request.output,
            format,
            &|done, total| progress.frames(done, total),
            listener,
        )?;
        progress.finish();
        return Ok(());
    }
    let picture = crate::load_flattened(&pictures)?;
    let progress = crate::progress::Steps::new(2);
    progress.step("meshing and weighting");
    let animator = Animator::new(&picture, &project, &frames, request.gpu, &progress)?;
    for note in animator.notes() {
        eprintln!("warning: {note}");
    }
    progress.step("drawing and writing frames");
    animator.write(
        &frames,
        request.output,
        format,
        &|done, total| progress.frames(done, total),
        &AtomicBool::new(false),
    )?;
    progress.finish();
    Ok(())
}
