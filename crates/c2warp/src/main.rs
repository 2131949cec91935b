//! `c2warp`: warp images with C² handle weights from the command line.

mod animate;
mod bench;
mod deform;
mod export;
mod flags;
mod progress;
mod runtime_dir;

use std::io::{IsTerminal, Write as _};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use pipeline::{DEFAULT_IMAGE, DEFAULT_RIG, Deformer, Method, load_project};
use project::Project;
use render::Picture;
use weights_core::Rig;

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
    /// A picture (PNG, JPEG, WebP, TIFF, BMP, GIF, PSD, OpenRaster) or a project (.json)
    /// to open in the editor; several pictures open as the layers of one, bottom first.
    files: Vec<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Open the editor on a picture (PNG, JPEG, WebP, TIFF, BMP, GIF) or a project (.json).
    Open {
        /// The file to open (several pictures: the layers of one, bottom first).
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// Warp an image by a rig and write a PNG of the same size (alpha kept; 16 bits
    /// per channel for a 16-bit source).
    Render {
        /// The picture (PNG, JPEG, WebP, TIFF, BMP, or a GIF's first frame) with
        /// `--rig`; or the project (a rig file, .json) alone, whose "image" names the
        /// picture (relative to the project's folder).
        input: PathBuf,
        /// The rig file (RIG.json), when INPUT is the picture.
        #[arg(long)]
        rig: Option<PathBuf>,
        /// Where to write the PNG (`-`: standard output). A file is replaced
        /// atomically (never one of the inputs); a device or FIFO is written to; a
        /// symbolic link's target is written.
        #[arg(short, long, required_unless_present = "layers")]
        output: Option<PathBuf>,
        /// Also (or instead) write OUT.ora: an OpenRaster file with each layer of the
        /// picture warped on a layer of its own, in its order, with its name, opacity
        /// and visibility (a flat picture gives one layer), drawn on the CPU. Krita
        /// and GIMP open it; replaced atomically like the PNG.
        #[arg(long, value_name = "OUT.ora")]
        layers: Option<PathBuf>,
        /// Warp a layered picture as parts: every visible layer meshed along its own
        /// outline and deformed by the handles on it (a handle where two layers
        /// overlap binds both), then composited in order; the density is shared among
        /// the parts by area, the canvas kept. Not with a cage (LBC) or `--gpu`.
        #[arg(long)]
        parts: bool,
        /// Target number of mesh vertices (overrides the rig's `density`).
        #[arg(long, allow_negative_numbers = true, value_parser = flags::density)]
        density: Option<usize>,
        /// Draw with the GPU (a software Vulkan driver works too) instead of on the
        /// CPU: a skinned method's transforms are blended in the vertex shader. The GPU
        /// draws in 8 bits per channel: a 16-bit source gives an 8-bit PNG.
        #[arg(long)]
        gpu: bool,
        /// The warping method (overrides the rig's `method`).
        #[arg(long, value_parser = methods())]
        method: Option<Method>,
        /// The output's frame: `keep` the picture's size (what the warp moves beyond
        /// its edge is cut off), or `fit` it to the warped picture (grown to hold all
        /// of it). Overrides the rig's `canvas`.
        #[arg(long)]
        canvas: Option<project::Canvas>,
    },
    /// Render every frame of a project's animation (its "animation" keys) and write
    /// them as an animated PNG, animated WebP, GIF or a folder of PNGs. Each frame is
    /// what `render` draws for the rig posed at its time.
    Animate {
        /// The project: a rig file with "animation" keys, whose "image" names the
        /// picture (relative to the project file).
        project: PathBuf,
        /// Where to write: OUT.png (animated PNG), OUT.webp (animated WebP), OUT.gif,
        /// or a folder (DIR/, or one that exists) for frame_00000.png, … A file is
        /// replaced atomically (never one of the inputs); nothing is left behind on
        /// failure or when interrupted. A folder takes only frames: those of an
        /// earlier run into it that this one does not replace are removed, and a
        /// folder holding frames this program did not write there is refused.
        #[arg(short, long)]
        output: PathBuf,
        /// The picture (overrides the project's "image").
        #[arg(long)]
        image: Option<PathBuf>,
        /// Frames per second (default: the project's animation.fps, else 24; at most
        /// 240, 50 for a GIF).
        #[arg(long, allow_negative_numbers = true,
              value_parser = flags::number(0.0..=render::AnimationWriter::MAX_FPS, true, " frames per second"))]
        fps: Option<f64>,
        /// Time of the first frame in seconds (default 0).
        #[arg(long, allow_negative_numbers = true,
              value_parser = flags::number(0.0..=project::animation::MAX_TIME, false, " s"))]
        from: Option<f64>,
        /// Time of the last frame in seconds (default: the last key's).
        #[arg(long, allow_negative_numbers = true,
              value_parser = flags::number(0.0..=project::animation::MAX_TIME, false, " s"))]
        to: Option<f64>,
        /// Draw with the GPU (8 bits per channel) instead of on the CPU.
        #[arg(long)]
        gpu: bool,
        /// Animate a layered picture as parts (as `render --parts` draws each pose).
        /// Not with a cage (LBC) or `--gpu`.
        #[arg(long)]
        parts: bool,
    },
    /// Write the deformed mesh as Wavefront OBJ: one `v x y 0` line per vertex (the
    /// input's order, inserted vertices after), then the faces.
    Deform {
        #[command(flatten)]
        source: Source,
        /// The rig file (RIG.json).
        #[arg(long)]
        rig: PathBuf,
        /// The warping method (overrides the rig's `method`).
        #[arg(long, value_parser = methods())]
        method: Option<Method>,
        /// Deform a layered picture part by part (as `render --parts`): one OBJ
        /// object (`o` and the layer's name) per visible layer, in the layers' order.
        #[arg(long)]
        parts: bool,
        /// Where to write the OBJ (`-`: standard output).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Write the nodes actually used and every mesh vertex's non-zero weights as JSON.
    Weights {
        #[command(flatten)]
        source: Source,
        /// The rig file (RIG.json).
        #[arg(long)]
        rig: PathBuf,
        /// Where to write the JSON (`-`: standard output).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Time the method's steps and print JSON: for C², the rig build, handle insertion
    /// and removal, and deformation; for the others, their setup and a pose.
    Bench {
        #[command(flatten)]
        source: Source,
        /// The rig file (RIG.json).
        #[arg(long)]
        rig: PathBuf,
        /// Random positions to insert and remove a handle at.
        #[arg(long, default_value_t = 31, allow_negative_numbers = true,
              value_parser = flags::count(1..=MAX_POSITIONS))]
        positions: usize,
        /// The method to time (overrides the rig's `method`).
        #[arg(long, value_parser = methods())]
        method: Option<Method>,
    },
    /// Write a rig whose cage (LBC) encloses every visible pixel of a picture: the
    /// picture's outline a few pixels out, brought down to `--vertices` vertices
    /// without crossing itself (more where that few cannot enclose it, with a note).
    Cage {
        /// The picture (PNG, JPEG, WebP, TIFF, BMP, or a GIF's first frame).
        image: PathBuf,
        /// Vertices of the cage.
        #[arg(long, default_value_t = 16, allow_negative_numbers = true,
              value_parser = flags::count(3..=project::MAX_CAGE_VERTICES))]
        vertices: usize,
        /// How far outside the visible pixels the cage runs at least, in pixels
        /// (default: 1% of the picture's diagonal, 3 to 20).
        #[arg(long, allow_negative_numbers = true,
              value_parser = flags::number(0.0..=MAX_CAGE_OFFSET, false, " px"))]
        offset: Option<f64>,
        /// A rig to start from: its handles and settings are kept, its cage replaced.
        #[arg(long)]
        rig: Option<PathBuf>,
        /// Where to write the rig (`-`: standard output; never one of the inputs);
        /// `"method"` is `"lbc"`, the cage at rest, `"image"` the picture relative to
        /// the rig's folder.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Render the sample rig on the built-in image and say where the PNG went.
    Demo {
        /// Where to write the PNG (`-`: standard output).
        #[arg(short, long, default_value = "c2warp-demo.png")]
        output: PathBuf,
    },
}

/// Where the samples come from.
#[derive(Args)]
#[group(skip)]
struct Source {
    /// A 2-D mesh as Wavefront OBJ (`v x y [z]`, `f a b c`); vertices used as given.
    #[arg(long, conflicts_with = "image")]
    mesh: Option<PathBuf>,
    /// An image to mesh (alpha outlines, or the full rectangle). With neither
    /// `--mesh` nor `--image`, the picture the rig file's "image" names.
    #[arg(long)]
    image: Option<PathBuf>,
    /// Target number of mesh vertices when meshing an image.
    #[arg(long, conflicts_with = "mesh", allow_negative_numbers = true,
          value_parser = flags::density)]
    density: Option<usize>,
}

/// The most positions `c2warp bench --positions` times.
const MAX_POSITIONS: usize = 10_000;

/// The farthest `c2warp cage --offset` reaches, in pixels (a picture's side is at
/// most 65,535 px; a cage that far out is the picture's rectangle).
const MAX_CAGE_OFFSET: f64 = 10_000.0;

/// `--method`: every method by its rig-file name.
fn methods() -> impl clap::builder::TypedValueParser<Value = Method> {
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(Method::ALL.map(Method::name))
        .try_map(|name| name.parse::<Method>())
}

/// A [`Source`] loaded: the picture to mesh, or the mesh given.
enum Input {
    Picture {
        image: image::RgbaImage,
        density: Option<usize>,
    },
    Mesh(pipeline::Mesh),
}

impl Source {
    /// The files the samples come from: the mesh or the image given, else the
    /// pictures the rig file at `rig` names (its `"image"`, or its `"images"` drawn
    /// as layers).
    fn files(&self, rig: &Path, project: &Project) -> Result<Vec<PathBuf>> {
        match (&self.mesh, &self.image) {
            (Some(path), _) | (None, Some(path)) => Ok(vec![path.clone()]),
            (None, None) => named_pictures(rig, project).context("give --mesh or --image"),
        }
    }
}

/// The picture a project names (its `"image"`, relative to the project file's
/// folder).
///
/// # Errors
/// A project that names none.
pub(crate) fn named_pictures(path: &Path, project: &Project) -> Result<Vec<PathBuf>> {
    let folder = path.parent().unwrap_or(Path::new(""));
    let named: Vec<PathBuf> = (project.image.iter().chain(&project.images))
        .map(|p| folder.join(p))
        .collect();
    if named.is_empty() {
        bail!(
            "{} names no picture (\"image\"): give one with --image PATH",
            path.display()
        );
    }
    Ok(named)
}

impl Input {
    /// Reads `files`, the OBJ mesh or the pictures `source` stands for (a mesh is
    /// checked; pictures are flattened).
    fn load(source: &Source, files: &[PathBuf]) -> Result<Self> {
        if source.mesh.is_none() {
            return Ok(Self::Picture {
                image: load_flattened(files)?.to_rgba8().into_owned(),
                density: source.density,
            });
        }
        let file = &files[0];
        let mesh = pipeline::load_obj(file)?;
        mesh.sanity_check()
            .with_context(|| format!("mesh {}", file.display()))?;
        Ok(Self::Mesh(mesh))
    }

    /// What a method is set up on.
    fn source(&self) -> pipeline::Source<'_> {
        match self {
            Self::Picture { image, density } => pipeline::Source::Picture {
                image,
                density: *density,
            },
            Self::Mesh(mesh) => pipeline::Source::Mesh(mesh),
        }
    }

    /// Whether the mesh is made from a picture.
    fn is_picture(&self) -> bool {
        matches!(self, Self::Picture { .. })
    }

    /// The vertices a mesh file had.
    fn file_vertices(&self) -> Option<usize> {
        match self {
            Self::Picture { .. } => None,
            Self::Mesh(mesh) => Some(mesh.vertices.len()),
        }
    }
}

/// Prints what the method says of its setup (a solve that did not converge).
fn warn(deformer: &dyn Deformer) {
    for note in deformer.notes() {
        eprintln!("warning: {note}");
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) => match flags::value_error_line(&error) {
            Some(line) => {
                eprintln!("{line}");
                return ExitCode::from(2);
            }
            None => error.exit(),
        },
    };
    // Before any thread starts: the GPU path's Vulkan layer (the editor's too)
    // complains on stderr without it (see runtime_dir.rs).
    let _runtime_dir = match &cli.command {
        Some(
            Command::Render { gpu: true, .. }
            | Command::Animate { gpu: true, .. }
            | Command::Open { .. },
        )
        | None => runtime_dir::ensure(),
        _ => None,
    };
    // Interrupted (Ctrl-C, SIGTERM, SIGHUP), a run removes the temporary files of the
    // writes it has in progress, so every output stays as it was and nothing is left.
    if let Err(error) = ctrlc::set_handler(|| {
        render::remove_temporary_files();
        std::process::exit(130);
    }) {
        eprintln!(
            "warning: cannot watch for Ctrl-C ({error}): an interrupted run may leave temporary files"
        );
    }
    let result = match cli.command {
        None => editor::run(cli.files),
        Some(command) => run(command),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", pipeline::error_line(&e));
            ExitCode::FAILURE
        }
    }
}

fn run(command: Command) -> Result<()> {
    match command {
        Command::Open { files } => editor::run(files),
        Command::Render {
            input,
            rig,
            output,
            layers,
            parts,
            density,
            gpu,
            method,
            canvas,
        } => render(
            &input,
            rig.as_deref(),
            Outputs {
                png: output.as_deref(),
                layers: layers.as_deref(),
                parts,
            },
            density,
            gpu,
            method,
            canvas,
        ),
        Command::Animate {
            project,
            output,
            image,
            fps,
            from,
            to,
            gpu,
            parts,
        } => animate::run(&animate::Request {
            project: &project,
            image: image.as_deref(),
            output: &output,
            span: pipeline::animate::Span { fps, from, to },
            gpu,
            parts,
        }),
        Command::Deform {
            source,
            rig,
            method,
            parts,
            output,
        } => deform::run(&source, &rig, method, parts, &output),
        Command::Weights {
            source,
            rig,
            output,
        } => export::weights(&source, &rig, &output),
        Command::Bench {
            source,
            rig,
            positions,
            method,
        } => bench::run(&source, &rig, positions, method),
        Command::Cage {
            image,
            vertices,
            offset,
            rig,
            output,
        } => cage(&image, vertices, offset, rig.as_deref(), &output),
        Command::Demo { output } => demo(&output),
    }
}

fn cage(
    image: &Path,
    vertices: usize,
    offset: Option<f64>,
    rig: Option<&Path>,
    output: &Path,
) -> Result<()> {
    let inputs: Vec<&Path> = std::iter::once(image).chain(rig).collect();
    render::refuse_input_as_output(output, &inputs)?;
    let mut project = match rig {
        Some(rig) => load_project(rig)?,
        None => Project::default(),
    };
    // Only the alpha channel matters, read a row at a time: a huge picture with a
    // small figure on it costs its bitmap, not its pixels.
    let coverage = pipeline::cage::coverage_of_file(image)?;
    let (w, h) = coverage.dimensions();
    let offset = offset.unwrap_or_else(|| pipeline::cage::outline_offset(w, h));
    let ring = pipeline::cage::cage_around(&coverage, vertices, offset)?;
    if let Some(note) = pipeline::cage::outline_note(vertices, ring.len()) {
        eprintln!("note: {note}");
    }
    if pipeline::cage::is_whole_picture(&ring, w, h) && !coverage.is_opaque() {
        eprintln!(
            "note: at {offset} px out the cage reaches every edge: it is the picture's rectangle"
        );
    }
    project.cage = Some(project::CageSpec {
        rest: ring.iter().map(|p| p.to_array()).collect(),
        pose: None,
    });
    project.method = Method::for_controls(project::Controls::Cage);
    let folder = if is_stdout(output) {
        Path::new("")
    } else {
        output.parent().unwrap_or(Path::new(""))
    };
    project.image = Some(pipeline::relative_path(image, folder));
    project.validate(Some((w, h)))?;
    write_text(output, project.to_json().as_bytes())
}

/// The rig file, the project it holds and the pictures a command warps: `first` is
/// the picture and `rig` the rig file, or, without `rig`, `first` is the project and
/// names its pictures.
fn project_and_picture(
    first: &Path,
    rig: Option<&Path>,
) -> Result<(PathBuf, Project, Vec<PathBuf>)> {
    if let Some(rig) = rig {
        return Ok((
            rig.to_path_buf(),
            load_project(rig)?,
            vec![first.to_path_buf()],
        ));
    }
    let is_json = first
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    if !is_json {
        bail!(
            "{} is a picture: give its rig with --rig RIG.json, or give the project (.json) alone",
            first.display()
        );
    }
    let project = load_project(first)?;
    let pictures = named_pictures(first, &project)?;
    Ok((first.to_path_buf(), project, pictures))
}

/// What `render` writes: the warped picture, its layers, or both.
#[derive(Clone, Copy)]
struct Outputs<'a> {
    /// The PNG (`-`: standard output).
    png: Option<&'a Path>,
    /// The OpenRaster file of warped layers.
    layers: Option<&'a Path>,
    /// Whether the layers are warped as parts ([`pipeline::warp_parts`]).
    parts: bool,
}

fn render(
    input: &Path,
    rig: Option<&Path>,
    outputs: Outputs,
    density: Option<usize>,
    gpu: bool,
    method: Option<Method>,
    canvas: Option<project::Canvas>,
) -> Result<()> {
    let (rig, mut project, pictures) = project_and_picture(input, rig)?;
    for output in [outputs.png, outputs.layers].into_iter().flatten() {
        render::refuse_input_as_output(output, &inputs(&rig, &pictures))?;
    }
    if let Some(layers) = outputs.layers {
        let is_ora = layers
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ora"));
        if !is_ora {
            bail!(
                "--layers writes OpenRaster: name the file OUT.ora, not {}",
                layers.display()
            );
        }
        if outputs.png.is_some_and(|png| same_file_name(png, layers)) {
            bail!(
                "-o and --layers both name {}: give them different files",
                layers.display()
            );
        }
    }
    if let Some(method) = method {
        project.method = method;
    }
    if let Some(canvas) = canvas {
        project.canvas = canvas;
    }
    let artwork = load_artwork_noting(&pictures)?;
    if outputs.parts || project.parts.is_some() {
        if gpu {
            bail!("--parts draws on the CPU: leave out --gpu");
        }
        if canvas == Some(project::Canvas::Fit) {
            bail!("--parts keeps the picture's canvas: leave out --canvas fit");
        }
        return render_parts(&artwork, &project, outputs, density);
    }
    let picture = artwork.flatten();
    let steps = 1 + 2 * u64::from(outputs.png.is_some()) + u64::from(outputs.layers.is_some());
    let progress = progress::Steps::new(steps);
    progress.step("meshing and weighting");
    let warper = {
        let rgba8 = picture.to_rgba8();
        pipeline::prepare_warper(&rgba8, &project, density, &progress)?
    };
    warn(&*warper.deformer);
    if let Some(output) = outputs.png {
        progress.step("rendering");
        let warped = if gpu {
            Picture::Rgba8(pipeline::warp_gpu(&picture.to_rgba8(), &warper)?)
        } else {
            pipeline::warp_picture(&picture, &warper)?
        };
        progress.step("writing");
        write_png(output, &warped)?;
    }
    if let Some(output) = outputs.layers {
        progress.step("rendering and writing the layers");
        let warped = pipeline::warp_layers(&artwork, &warper)?;
        pipeline::write_ora(output, &warped)?;
    }
    progress.finish();
    Ok(())
}

/// `render --parts`: each visible layer warped as a part, the parts composited.
fn render_parts(
    artwork: &pipeline::Artwork,
    project: &project::Project,
    outputs: Outputs,
    density: Option<usize>,
) -> Result<()> {
    let steps = 1 + u64::from(outputs.png.is_some()) + u64::from(outputs.layers.is_some());
    let progress = progress::Steps::new(steps);
    progress.step("meshing, weighting and warping every part");
    let parts = pipeline::warp_parts(artwork, project, density, &progress)?;
    if let Some(output) = outputs.png {
        progress.step("writing");
        write_png(output, &parts.composite)?;
    }
    if let Some(output) = outputs.layers {
        progress.step("writing the layers");
        pipeline::write_ora(output, &parts.warped)?;
    }
    progress.finish();
    Ok(())
}

/// Whether `a` and `b` name the same file by their paths as given (the files may not
/// exist yet; [`render::refuse_input_as_output`] covers files that do).
fn same_file_name(a: &Path, b: &Path) -> bool {
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    absolute(a) == absolute(b)
}

/// Reads pictures as [`pipeline::load_artworks`] does (several: the layers of one),
/// saying on standard error what of a layered file is drawn otherwise than it asks.
pub(crate) fn load_artwork_noting(paths: &[PathBuf]) -> Result<pipeline::Artwork> {
    let artwork = pipeline::load_artworks(paths)?;
    for note in &artwork.notes {
        eprintln!("note: {}: {note}", paths[0].display());
    }
    Ok(artwork)
}

/// Reads pictures as [`load_artwork_noting`] does, flattened.
pub(crate) fn load_flattened(paths: &[PathBuf]) -> Result<render::Picture> {
    Ok(load_artwork_noting(paths)?.flatten())
}

/// A command's inputs: its rig file and its pictures.
pub(crate) fn inputs<'a>(rig: &'a Path, pictures: &'a [PathBuf]) -> Vec<&'a Path> {
    std::iter::once(rig)
        .chain(pictures.iter().map(PathBuf::as_path))
        .collect()
}

/// Meshes, weights, warps and writes `picture` by `project` (with its method), with a
/// progress counter; returns the method's deformer.
///
/// The CPU draws in the picture's depth (a 16-bit picture gives a 16-bit PNG); the
/// GPU draws in 8 bits per channel, so with `gpu` the PNG has 8.
fn warp_and_save(
    picture: &Picture,
    project: &Project,
    density: Option<usize>,
    output: &Path,
    gpu: bool,
) -> Result<Box<dyn Deformer>> {
    let progress = progress::Steps::new(3);
    progress.step("meshing and weighting");
    let rgba8 = picture.to_rgba8();
    let warper = pipeline::prepare_warper(&rgba8, project, density, &progress)?;
    warn(&*warper.deformer);
    progress.step("rendering");
    let warped = if gpu {
        Picture::Rgba8(pipeline::warp_gpu(&rgba8, &warper)?)
    } else {
        drop(rgba8);
        pipeline::warp_picture(picture, &warper)?
    };
    progress.step("writing");
    write_png(output, &warped)?;
    progress.finish();
    Ok(warper.deformer)
}

/// Whether `output` names standard output (`-`).
pub(crate) fn is_stdout(output: &Path) -> bool {
    output.as_os_str() == "-"
}

/// Writes `bytes` (a JSON or OBJ file) to `output`: standard output for `-`, else
/// through [`render::write_atomic`] (atomic for a regular file, through to a device or
/// FIFO, to a symbolic link's target).
pub(crate) fn write_text(output: &Path, bytes: &[u8]) -> Result<()> {
    if is_stdout(output) {
        let mut stdout = std::io::stdout().lock();
        stdout
            .write_all(bytes)
            .and_then(|()| stdout.flush())
            .context("cannot write to standard output")?;
    } else {
        render::write_atomic(output, bytes)?;
    }
    Ok(())
}

/// Writes `picture` as a PNG to `output`: standard output for `-` (unless it is a
/// terminal), else through [`render::save_png_atomic`] (atomic for a regular file,
/// through to a device or FIFO, to a symbolic link's target).
fn write_png(output: &Path, picture: &Picture) -> Result<()> {
    if is_stdout(output) {
        let stdout = std::io::stdout();
        if stdout.is_terminal() {
            bail!(
                "refusing to write a PNG to a terminal: redirect standard output, or name a file with -o"
            );
        }
        render::write_png(stdout.lock(), picture, Path::new("<standard output>"))?;
    } else {
        render::save_png_atomic(output, picture)?;
    }
    Ok(())
}

fn demo(output: &Path) -> Result<()> {
    let picture = render::decode_picture(DEFAULT_IMAGE, &render::ImageLimits::default())?;
    let project = Project::from_json(DEFAULT_RIG).context("built-in rig")?;
    let deformer = warp_and_save(&picture, &project, None, output, false)?;
    let Some(rig) = deformer.as_any().downcast_ref::<Rig>() else {
        bail!("the built-in rig uses the C² weights");
    };
    let stats = rig.stats();
    if is_stdout(output) {
        return Ok(());
    }
    let (width, height) = picture.dimensions();
    println!(
        "Warped the built-in lizard ({} × {} px, {} mesh vertices, {} handles + {} virtual) into {}",
        width,
        height,
        stats.samples,
        stats.real_handles,
        stats.virtual_nodes,
        std::path::absolute(output)
            .unwrap_or_else(|_| output.to_path_buf())
            .display()
    );
    Ok(())
}
