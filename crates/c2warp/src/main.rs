//! `c2warp`: warp images with C² handle weights from the command line.

mod bench;
mod export;
mod progress;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use pipeline::{DEFAULT_IMAGE, DEFAULT_RIG, load_image, load_project};
use project::Project;

#[derive(Parser)]
#[command(
    name = "c2warp",
    version,
    about = "Handle-driven image warping with closed-form C² weights",
    long_about = "Handle-driven image warping with closed-form C² weights.\n\n\
        With no command, opens the editor (on FILE, or on the built-in picture).",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// A picture (PNG, JPEG) or a project (.json) to open in the editor.
    file: Option<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Open the editor on a picture (PNG, JPEG) or a project (.json).
    Open {
        /// The file to open.
        file: PathBuf,
    },
    /// Warp an image by a rig and write a PNG of the same size (alpha kept).
    Render {
        /// The image (PNG or JPEG).
        image: PathBuf,
        /// The rig file (RIG.json).
        #[arg(long)]
        rig: PathBuf,
        /// Where to write the PNG.
        #[arg(short, long)]
        output: PathBuf,
        /// Target number of mesh vertices (overrides the rig's `density`).
        #[arg(long)]
        density: Option<usize>,
        /// Draw with the GPU (a software Vulkan driver works too), blending the handle
        /// transforms in the vertex shader, instead of on the CPU.
        #[arg(long)]
        gpu: bool,
    },
    /// Write the nodes actually used and every mesh vertex's non-zero weights as JSON.
    Weights {
        #[command(flatten)]
        source: Source,
        /// The rig file (RIG.json).
        #[arg(long)]
        rig: PathBuf,
        /// Where to write the JSON.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Time the rig build, handle insertion and removal, and deformation; print JSON.
    Bench {
        #[command(flatten)]
        source: Source,
        /// The rig file (RIG.json).
        #[arg(long)]
        rig: PathBuf,
        /// Random positions to insert and remove a handle at.
        #[arg(long, default_value_t = 31)]
        positions: usize,
    },
    /// Render the sample rig on the built-in image and say where the PNG went.
    Demo {
        /// Where to write the PNG.
        #[arg(short, long, default_value = "c2warp-demo.png")]
        output: PathBuf,
    },
}

/// Where the samples come from.
#[derive(Args)]
#[group(skip)]
struct Source {
    /// A 2-D mesh as Wavefront OBJ (`v x y [z]`, `f a b c`); vertices used as given.
    #[arg(long, required_unless_present = "image", conflicts_with = "image")]
    mesh: Option<PathBuf>,
    /// An image to mesh (alpha outlines, or the full rectangle).
    #[arg(long)]
    image: Option<PathBuf>,
    /// Target number of mesh vertices when meshing an image.
    #[arg(long, conflicts_with = "mesh")]
    density: Option<usize>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None => editor::run(cli.file),
        Some(command) => run(command),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(command: Command) -> Result<()> {
    match command {
        Command::Open { file } => editor::run(Some(file)),
        Command::Render {
            image,
            rig,
            output,
            density,
            gpu,
        } => render(&image, &rig, &output, density, gpu),
        Command::Weights {
            source,
            rig,
            output,
        } => export::weights(&source, &rig, &output),
        Command::Bench {
            source,
            rig,
            positions,
        } => bench::run(&source, &rig, positions),
        Command::Demo { output } => demo(&output),
    }
}

fn render(
    image: &Path,
    rig: &Path,
    output: &Path,
    density: Option<usize>,
    gpu: bool,
) -> Result<()> {
    let project = load_project(rig)?;
    let picture = load_image(image)?;
    warp_and_save(&picture, &project, density, output, gpu)?;
    Ok(())
}

/// Meshes, weights, warps and writes `picture` by `project`, with a progress counter;
/// returns the rig.
fn warp_and_save(
    picture: &image::RgbaImage,
    project: &Project,
    density: Option<usize>,
    output: &Path,
    gpu: bool,
) -> Result<weights_core::Rig> {
    let progress = progress::Steps::new(3);
    progress.step("meshing and weighting");
    let prepared = pipeline::prepare(picture, project, density)?;
    progress.step("rendering");
    let warped = if gpu {
        pipeline::warp_gpu(picture, &prepared.rig)?
    } else {
        pipeline::warp(picture, &prepared.rig)?
    };
    progress.step("writing");
    render::save_png_atomic(output, &warped)?;
    progress.finish();
    Ok(prepared.rig)
}

fn demo(output: &Path) -> Result<()> {
    let picture = render::decode_image(DEFAULT_IMAGE, &render::ImageLimits::default())?;
    let project = Project::from_json(DEFAULT_RIG).context("built-in rig")?;
    let rig = warp_and_save(&picture, &project, None, output, false)?;
    let stats = rig.stats();
    println!(
        "Warped the built-in lizard ({} × {} px, {} mesh vertices, {} handles + {} virtual) into {}",
        picture.width(),
        picture.height(),
        stats.samples,
        stats.real_handles,
        stats.virtual_nodes,
        std::path::absolute(output)
            .unwrap_or_else(|_| output.to_path_buf())
            .display()
    );
    Ok(())
}
