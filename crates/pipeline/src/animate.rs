//! A rig's animation drawn frame by frame and written as one file (animated PNG,
//! animated WebP, GIF) or a PNG sequence: `c2warp animate` and the editor's
//! File → Export animation.
//!
//! **Each frame is what `c2warp render` draws for the rig posed at its time**
//! ([`animation::posed_at`]), bit for bit on the CPU. The method is set up once, on
//! the rig posed at the first frame's time; every frame then only *follows* its pose
//! ([`crate::Deformer::follow`]: new transforms for C², a solve with the factorisation
//! kept for ARAP, a precomputed fit for MLS, the solved coordinates posed for LBC) and
//! is drawn by [`crate::warp_picture`] (or on the GPU, by [`crate::warp_gpu`]'s path).
//!
//! Frames are drawn in parallel, in chunks of a few frames a thread, each thread with
//! its own copy of the method; while a chunk is drawn, the one before it is encoded in
//! order on a thread of its own. At most three chunks exist at once (one drawn, one
//! waiting, one encoded), so memory stays bounded however long the animation.
//!
//! ```no_run
//! # fn main() -> anyhow::Result<()> {
//! use std::sync::atomic::AtomicBool;
//! use pipeline::animate::{self, Span};
//! let project = pipeline::load_project("walk.json".as_ref())?;
//! let picture = pipeline::load_picture("walk.png".as_ref())?;
//! let output = std::path::Path::new("walk.png");
//! let format = render::AnimationFormat::from_path(output)?;
//! let frames = animate::plan(&project, Span::default(), format)?;
//! let (gpu, cancel) = (false, AtomicBool::new(false));
//! let progress = |done, total| eprintln!("{done} of {total} frames");
//! animate::write(&picture, &project, &frames, output, format, gpu, &progress, &cancel)?;
//! # Ok(())
//! # }
//! ```

use std::borrow::Cow;
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;

use anyhow::{Context, Result, bail, ensure};
use image::RgbaImage;
use project::Project;
use project::animation::{MAX_FPS, MAX_TIME};
use rayon::prelude::*;
use render::{AnimationFormat, AnimationWriter, Picture};

use crate::{Follow, Frame, Listener, Source, Warper};

/// The most frames an animation may have (ten hours at 24 frames a second): a range
/// and rate asking for more are refused before any work.
pub const MAX_FRAMES: usize = 1_000_000;

/// The most bytes of frames a chunk holds (three chunks at most exist at once).
const CHUNK_BYTES: usize = 128 << 20;

/// Which frames to draw: each left out takes the rig's own.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Span {
    /// Frames per second (default: the rig's `animation.fps`, else 24).
    pub fps: Option<f64>,
    /// The first frame's time in seconds (default 0).
    pub from: Option<f64>,
    /// The latest time a frame may have, in seconds (default: the last key's time).
    pub to: Option<f64>,
}

/// The frames of an animation: its rate and each frame's time.
#[derive(Clone, Debug, PartialEq)]
pub struct Frames {
    /// Frames per second.
    pub fps: f64,
    /// Each frame's time in seconds, `from + i / fps`, in order (at least one).
    pub times: Vec<f64>,
}

/// An animation's writing was cancelled (through the `cancel` flag of
/// [`Animator::write`]): nothing was written, and a file that was there is as it was.
/// Find it with `error.is::<Cancelled>()`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled;

impl std::fmt::Display for Cancelled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("cancelled")
    }
}

impl std::error::Error for Cancelled {}

/// The frames `span` asks of `project`'s animation, written as `format`, checked
/// before any work: the rate (above 0, at most [`MAX_FPS`], and at most what the
/// format plays: 50 for a GIF), the range (finite, from 0 to [`MAX_TIME`] seconds, not
/// backwards), at most [`MAX_FRAMES`] frames, and a rig with keys.
///
/// # Errors
/// Each of those, as one sentence.
pub fn plan(project: &Project, span: Span, format: AnimationFormat) -> Result<Frames> {
    let animation = project.animation.as_ref().filter(|a| !a.keys.is_empty());
    let Some(animation) = animation else {
        bail!(
            "the rig has no animation keys: set keys in the editor's timeline, or add \
             \"animation\": {{\"keys\": [...]}}"
        );
    };
    let fps = span.fps.unwrap_or(animation.fps);
    ensure!(
        fps.is_finite() && fps > 0.0 && fps <= MAX_FPS,
        "the frame rate must be above 0 and at most {MAX_FPS} frames per second, got {fps}"
    );
    ensure!(
        fps <= format.max_fps(),
        "a {} plays at most {} frames per second, not {fps}: lower the rate, or write an \
         animated PNG or WebP",
        format.label(),
        format.max_fps()
    );
    let time = |value: Option<f64>, default: f64, what: &str| -> Result<f64> {
        let value = value.unwrap_or(default);
        ensure!(
            value.is_finite() && (0.0..=MAX_TIME).contains(&value),
            "the {what} time must be from 0 to {MAX_TIME} seconds, got {value}"
        );
        Ok(value)
    };
    let from = time(span.from, 0.0, "start")?;
    let to = time(span.to, animation.duration(), "end")?;
    ensure!(
        from <= to,
        "the animation would run backwards: from {from} s to {to} s{}",
        if span.to.is_none() {
            " (the last key's time; give an end time)"
        } else {
            ""
        }
    );
    let count = (to - from) * fps + 1.0;
    ensure!(
        count <= MAX_FRAMES as f64,
        "{} frames asked ({from} s to {to} s at {fps} frames per second); at most \
         {MAX_FRAMES} are written",
        count.floor()
    );
    Ok(Frames {
        fps,
        times: animation::frame_times(fps, from, to),
    })
}

/// Where frames are drawn.
enum Device {
    /// On the CPU, in the picture's depth.
    Cpu,
    /// On the GPU, 8 bits per channel, one context for every frame.
    Gpu(Box<render::GpuContext>),
}

/// A rig's animation on a picture, set up to draw any of its frames.
pub struct Animator<'a> {
    /// What every frame shares.
    scene: Scene<'a>,
    /// The method, in the last pose drawn (first: the first frame's); behind a lock
    /// so that an animator is shared between threads (each frame drawn on a copy).
    warper: Mutex<Warper>,
}

/// What every frame of an animation shares (read by every drawing thread).
struct Scene<'a> {
    picture: &'a Picture,
    /// The picture in 8 bits (what a method is set up on and the GPU samples).
    rgba8: Cow<'a, RgbaImage>,
    /// The rig with its animation.
    project: &'a Project,
    device: Device,
    /// Every frame's rectangle over the picture's pixels.
    frame: Frame,
}

impl<'a> Animator<'a> {
    /// Sets `project`'s method up on `picture` (as [`crate::prepare_warper`] does, at the
    /// rig's density) for the pose at `frames`' first time, telling `listener` how the
    /// setup comes along; with `gpu`, makes the GPU context every frame will use.
    ///
    /// # Errors
    /// What the setup refuses; no GPU adapter; a grown canvas (`"canvas": "fit"`)
    /// that the animation's frames, together, make too large.
    pub fn new(
        picture: &'a Picture,
        project: &'a Project,
        frames: &Frames,
        gpu: bool,
        listener: &dyn Listener,
    ) -> Result<Self> {
        let rgba8 = picture.to_rgba8();
        let first = animation::posed_at(project, frames.times.first().copied().unwrap_or(0.0));
        let warper = crate::prepare_warper(&rgba8, &first, None, listener)?;
        Self::with_warper(picture, project, warper, frames, gpu)
    }

    /// As [`Animator::new`] with the method already set up (the editor's, whose cage
    /// is solved): `warper` must be `project`'s method on `picture`, in any pose.
    ///
    /// # Errors
    /// As [`Animator::new`], but for the setup.
    pub fn with_warper(
        picture: &'a Picture,
        project: &'a Project,
        mut warper: Warper,
        frames: &Frames,
        gpu: bool,
    ) -> Result<Self> {
        let device = if gpu {
            Device::Gpu(Box::new(render::GpuContext::new()?))
        } else {
            Device::Cpu
        };
        let mut scene = Scene {
            picture,
            rgba8: picture.to_rgba8(),
            project,
            device,
            frame: Frame {
                origin: [0, 0],
                width: 0,
                height: 0,
            },
        };
        scene.frame = scene.frame_of_all(&mut warper, &frames.times)?;
        if let Some(&first) = frames.times.first() {
            scene.follow(&mut warper, first)?;
        }
        Ok(Self {
            scene,
            warper: Mutex::new(warper),
        })
    }

    /// What the method says of its setup (a solve that did not converge).
    pub fn notes(&self) -> Vec<String> {
        lock(&self.warper).map_or_else(|_| Vec::new(), |w| w.deformer.notes())
    }

    /// The size of every frame in pixels: the picture's, or with `"canvas": "fit"` the
    /// smallest rectangle holding each frame's own grown canvas.
    pub fn size(&self) -> (u32, u32) {
        (self.scene.frame.width, self.scene.frame.height)
    }

    /// The frame at `time`: what `c2warp render` draws for
    /// [`animation::posed_at`]`(project, time)` — on the CPU in the picture's depth,
    /// bit for bit; on the GPU in 8 bits. With `"canvas": "fit"` that picture lies at
    /// its place in [`Animator::size`]'s rectangle, transparent around it.
    ///
    /// # Errors
    /// What the method refuses of the pose; a GPU failure.
    pub fn render(&mut self, time: f64) -> Result<Picture> {
        let warper = self
            .warper
            .get_mut()
            .map_err(|_| anyhow::anyhow!("a thread drawing the animation stopped unexpectedly"))?;
        self.scene.draw(warper, time)
    }

    /// Draws the frames at `frames.times` and writes them to `output` as `format`,
    /// atomically (see [`AnimationWriter`]): the file (or the sequence) appears only
    /// when every frame is in, and an existing one stays as it was after any error or
    /// a cancel. `progress(done, total)` is told, from another thread, each time a
    /// frame has been written; setting `cancel` stops the work within a chunk of
    /// frames.
    ///
    /// Call it from a thread of its own (a command's main thread, an editor's worker),
    /// not from inside a rayon pool: from there the frames are drawn and written in
    /// turn rather than side by side (see [`Animator::for_each_frame`]).
    ///
    /// # Errors
    /// What drawing a frame or the writer refuses (a frame rate the format cannot
    /// play, a missing folder, a full disk); [`Cancelled`] when `cancel` was set.
    pub fn write(
        &self,
        frames: &Frames,
        output: &Path,
        format: AnimationFormat,
        progress: &(dyn Fn(usize, usize) + Sync),
        cancel: &AtomicBool,
    ) -> Result<()> {
        let total = frames.times.len();
        let (width, height) = self.size();
        let mut writer = AnimationWriter::create(output, format, width, height, total, frames.fps)?;
        progress(0, total);
        // A chunk's frames are compressed side by side, on threads of their own: the
        // operating system lets them fill the gaps the drawing leaves (a chunk's last
        // frame, the writer waiting on the disk), which the drawing's pool cannot.
        let encoding = rayon::ThreadPoolBuilder::new()
            .num_threads(rayon::current_num_threads())
            .thread_name(|i| format!("encode-{i}"))
            .build()
            .context("starting the animation's encoding threads")?;
        self.for_each_frame(
            &frames.times,
            &mut |_, pictures| {
                encoding.install(|| writer.push_all(&pictures))?;
                progress(writer.pushed(), total);
                Ok(())
            },
            cancel,
        )?;
        writer.finish()?;
        Ok(())
    }

    /// Draws the frames at `times` in parallel and hands them, a chunk at a time in
    /// order, to `each` (with the index of the chunk's first frame), on a thread of its
    /// own while the next chunk is drawn: what [`Animator::write`] does with a writer.
    /// Chunks of two frames a thread are drawn at once, each thread with its own copy
    /// of the method; `each` runs on the chunk before. Called from inside a rayon
    /// pool, it draws a chunk and then hands it over, in turn (a thread of the pool
    /// waiting on `each` could hold up work that `each` waits for).
    ///
    /// # Errors
    /// What drawing a frame refuses, or `each`'s first error (no frame is drawn or
    /// handed over after either); [`Cancelled`] when `cancel` is set (checked before
    /// each chunk is drawn and handed over).
    pub fn for_each_frame(
        &self,
        times: &[f64],
        each: &mut (dyn FnMut(usize, Vec<Picture>) -> Result<()> + Send),
        cancel: &AtomicBool,
    ) -> Result<()> {
        let scene = &self.scene;
        let chunk = scene.chunk_len();
        // A copy of the method for each frame drawn at once, reused chunk after chunk
        // (more than one a thread where a thread waiting inside one frame's drawing
        // takes up another).
        let template = &self.warper;
        let spare: Mutex<Vec<Warper>> = Mutex::new(Vec::new());
        let draw_chunk = |times: &[f64]| -> Result<Vec<Picture>> {
            times
                .par_iter()
                .map(|&time| {
                    let taken = spare.lock().ok().and_then(|mut s| s.pop());
                    let mut warper = match taken {
                        Some(warper) => warper,
                        None => lock(template)?.clone(),
                    };
                    let picture = scene.draw(&mut warper, time);
                    lock(&spare)?.push(warper);
                    picture
                })
                .collect()
        };
        let cancelled = || cancel.load(Ordering::Relaxed);
        let mut next = 0;
        let mut hand_over = |pictures: Vec<Picture>| -> Result<()> {
            if cancelled() {
                return Err(Cancelled.into());
            }
            let count = pictures.len();
            each(next, pictures)?;
            next += count;
            Ok(())
        };
        if rayon::current_thread_index().is_some() {
            for times in times.chunks(chunk) {
                if cancelled() {
                    return Err(Cancelled.into());
                }
                hand_over(draw_chunk(times)?)?;
            }
        } else {
            std::thread::scope(|scope| -> Result<()> {
                let (send, receive) = mpsc::sync_channel::<Vec<Picture>>(1);
                let taker = scope.spawn(move || -> Result<()> {
                    for pictures in receive {
                        hand_over(pictures)?;
                    }
                    Ok(())
                });
                let mut drawn = Ok(());
                for times in times.chunks(chunk) {
                    if cancelled() {
                        drawn = Err(Cancelled.into());
                        break;
                    }
                    match draw_chunk(times) {
                        Ok(pictures) => {
                            // A closed channel: `each` failed, and says why below.
                            if send.send(pictures).is_err() {
                                break;
                            }
                        }
                        Err(error) => {
                            drawn = Err(error);
                            break;
                        }
                    }
                }
                drop(send);
                let taken = taker
                    .join()
                    .unwrap_or_else(|_| bail!("the animation's writer stopped unexpectedly"));
                // `each`'s error first: a drawing loop that stopped because `each` did
                // has nothing to add.
                taken.and(drawn)
            })?;
        }
        if cancelled() {
            return Err(Cancelled.into());
        }
        Ok(())
    }
}

/// `mutex` locked (a thread that panicked holding it leaves an error, not a panic).
fn lock<T>(mutex: &Mutex<T>) -> Result<std::sync::MutexGuard<'_, T>> {
    mutex
        .lock()
        .map_err(|_| anyhow::anyhow!("a thread drawing the animation stopped unexpectedly"))
}

impl Scene<'_> {
    /// Brings `warper` to the pose at `time`: cheaply, or (if the method asks for it,
    /// which a pose alone should never do) by a new setup.
    fn follow(&self, warper: &mut Warper, time: f64) -> Result<()> {
        let posed = animation::posed_at(self.project, time);
        let followed = warper
            .follow(&posed)
            .with_context(|| format!("the pose at {time} s"))?;
        if followed == Follow::NeedsSetup {
            let source = Source::Picture {
                image: &self.rgba8,
                density: None,
            };
            *warper = crate::setup(source, &posed, &())?;
        }
        Ok(())
    }

    /// The frame at `time`, drawn with `warper` (posed to it).
    fn draw(&self, warper: &mut Warper, time: f64) -> Result<Picture> {
        self.follow(warper, time)?;
        let (width, height) = self.picture.dimensions();
        let own = warper.frame(width, height)?;
        let picture = match &self.device {
            Device::Cpu => crate::warp_picture(self.picture, warper)?,
            Device::Gpu(gpu) => Picture::Rgba8(crate::warp_gpu_with(gpu, &self.rgba8, warper)?),
        };
        place(picture, own, self.frame)
    }

    /// The rectangle holding every frame at `times` (the picture's own, unless the
    /// canvas grows to fit).
    fn frame_of_all(&self, warper: &mut Warper, times: &[f64]) -> Result<Frame> {
        let (width, height) = self.picture.dimensions();
        if warper.canvas == project::Canvas::Keep || times.is_empty() {
            return warper.frame(width, height);
        }
        let (mut lo, mut hi) = ([i64::MAX; 2], [i64::MIN; 2]);
        for &time in times {
            self.follow(warper, time)?;
            let f = warper.frame(width, height)?;
            let end = [
                f.origin[0] + i64::from(f.width),
                f.origin[1] + i64::from(f.height),
            ];
            for axis in 0..2 {
                lo[axis] = lo[axis].min(f.origin[axis]);
                hi[axis] = hi[axis].max(end[axis]);
            }
        }
        let limits = render::ImageLimits::default();
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        ensure!(
            w <= i64::from(limits.max_width) && h <= i64::from(limits.max_height),
            "the canvas grown to hold every frame of the animation would be {w} × {h} \
             pixels, more than the {} × {} a picture may have: keep the picture's canvas, \
             or pose the handles nearer the picture",
            limits.max_width,
            limits.max_height
        );
        Ok(Frame {
            origin: lo,
            width: w as u32,
            height: h as u32,
        })
    }

    /// Frames in a chunk: two a thread, fewer for large frames.
    fn chunk_len(&self) -> usize {
        let depth = match self.device {
            Device::Cpu => usize::from(self.picture.bits_per_channel() / 8),
            Device::Gpu(_) => 1,
        };
        let bytes = self.frame.width as usize * self.frame.height as usize * 4 * depth;
        (2 * rayon::current_num_threads()).clamp(1, (CHUNK_BYTES / bytes.max(1)).max(1))
    }
}

/// `picture`, drawn in frame `own`, at its place in `all` (a rectangle holding it).
fn place(picture: Picture, own: Frame, all: Frame) -> Result<Picture> {
    if own == all {
        return Ok(picture);
    }
    crate::placed(
        &picture,
        all,
        [own.origin[0] - all.origin[0], own.origin[1] - all.origin[1]],
    )
}

/// Sets `project`'s method up on `picture` and writes the frames at `frames.times` to
/// `output` as `format` ([`Animator::new`], then [`Animator::write`]): on the CPU in
/// the picture's depth, or with `gpu` on the GPU in 8 bits.
///
/// # Errors
/// As [`Animator::new`] and [`Animator::write`].
#[allow(clippy::too_many_arguments)]
pub fn write(
    picture: &Picture,
    project: &Project,
    frames: &Frames,
    output: &Path,
    format: AnimationFormat,
    gpu: bool,
    progress: &(dyn Fn(usize, usize) + Sync),
    cancel: &AtomicBool,
) -> Result<()> {
    Animator::new(picture, project, frames, gpu, &())?
        .write(frames, output, format, progress, cancel)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 48 × 32 opaque picture with something to see in every pixel.
    fn picture() -> Picture {
        Picture::Rgba8(RgbaImage::from_fn(48, 32, |x, y| {
            image::Rgba([(x * 5) as u8, (y * 7) as u8, ((x + y) * 3) as u8, 255])
        }))
    }

    /// Two point handles, the second moving right over two keys (by `reach` pixels).
    fn project(canvas: &str, reach: f64) -> Project {
        Project::from_json(&format!(
            r#"{{"version": 1, "density": 150, "canvas": "{canvas}",
                "handles": [{{"type": "point", "rest": [8, 8]}},
                            {{"type": "point", "rest": [40, 24]}}],
                "animation": {{"fps": 8, "keys": [
                    {{"time": 0, "pose": [{{}}, {{}}]}},
                    {{"time": 1, "pose": [{{}}, {{"translate": [{reach}, -3]}}]}}]}}}}"#
        ))
        .expect("a rig")
    }

    #[test]
    fn plan_takes_the_rigs_rate_and_range_and_refuses_what_cannot_be_drawn() {
        let project = project("keep", 6.0);
        let frames = plan(&project, Span::default(), AnimationFormat::Apng).expect("a plan");
        assert_eq!(frames.fps, 8.0);
        assert_eq!(frames.times.len(), 9);
        assert_eq!(frames.times.last(), Some(&1.0));
        let span = Span {
            fps: Some(2.0),
            from: Some(0.5),
            to: Some(3.0),
        };
        let frames = plan(&project, span, AnimationFormat::Gif).expect("a plan");
        assert_eq!(frames.times, [0.5, 1.0, 1.5, 2.0, 2.5, 3.0]);
        let refused = |span: Span, format| {
            plan(&project, span, format)
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default()
        };
        let fps = |fps| Span {
            fps: Some(fps),
            ..Span::default()
        };
        assert!(refused(fps(0.0), AnimationFormat::Apng).contains("above 0"));
        assert!(refused(fps(f64::NAN), AnimationFormat::Apng).contains("got NaN"));
        assert!(refused(fps(241.0), AnimationFormat::WebP).contains("at most 240"));
        assert!(refused(fps(51.0), AnimationFormat::Gif).contains("GIF plays at most 50"));
        let from = |from| Span {
            from: Some(from),
            ..Span::default()
        };
        assert!(refused(from(-0.5), AnimationFormat::Apng).contains("got -0.5"));
        assert!(refused(from(1.5), AnimationFormat::Apng).contains("the last key's time"));
        let many = Span {
            fps: Some(240.0),
            to: Some(project::animation::MAX_TIME),
            ..Span::default()
        };
        assert!(refused(many, AnimationFormat::PngSequence).contains("at most 1000000"));
        let mut still = project.clone();
        still.animation = None;
        assert!(
            plan(&still, Span::default(), AnimationFormat::Apng)
                .err()
                .is_some_and(|e| e.to_string().contains("no animation keys"))
        );
    }

    #[test]
    fn a_cancelled_export_leaves_no_file_and_an_old_one_as_it_was() {
        let dir = tempfile::tempdir().expect("a folder");
        let picture = picture();
        let project = project("keep", 6.0);
        let frames = plan(&project, Span::default(), AnimationFormat::Apng).expect("a plan");
        let animator = Animator::new(&picture, &project, &frames, false, &()).expect("set up");
        for (name, format) in [
            ("old.png", AnimationFormat::Apng),
            ("frames/", AnimationFormat::PngSequence),
        ] {
            let output = dir.path().join(name);
            if format == AnimationFormat::Apng {
                std::fs::write(&output, b"old").expect("write");
            }
            let cancel = AtomicBool::new(false);
            let seen = Mutex::new(Vec::new());
            let progress = |done, total| {
                if let Ok(mut seen) = seen.lock() {
                    seen.push((done, total));
                }
                // Cancelled once the first chunk of frames is written.
                if done > 0 {
                    cancel.store(true, Ordering::Relaxed);
                }
            };
            let error = animator
                .write(&frames, &output, format, &progress, &cancel)
                .expect_err("cancelled");
            assert!(error.is::<Cancelled>(), "{error}");
            let seen = seen.lock().expect("seen").clone();
            assert_eq!(seen.len(), 2, "{seen:?}");
            assert_eq!(seen[0], (0, 9));
            assert!(seen[1].0 > 0 && seen[1].0 < 9 && seen[1].1 == 9, "{seen:?}");
            let left: Vec<_> = std::fs::read_dir(dir.path())
                .expect("list")
                .map(|e| e.expect("an entry").file_name())
                .collect();
            assert_eq!(left, ["old.png"], "{name}");
            assert_eq!(
                std::fs::read(dir.path().join("old.png")).expect("read"),
                b"old"
            );
        }
    }

    #[test]
    fn frames_drawn_side_by_side_or_in_turn_are_the_frames_drawn_one_by_one() {
        let dir = tempfile::tempdir().expect("a folder");
        let picture = picture();
        let project = project("keep", 6.0);
        let frames = plan(&project, Span::default(), AnimationFormat::PngSequence).expect("a plan");
        let mut animator = Animator::new(&picture, &project, &frames, false, &()).expect("set up");
        let one_by_one: Vec<Vec<u8>> = frames
            .times
            .iter()
            .map(|&t| match animator.render(t).expect("a frame") {
                Picture::Rgba8(image) => image.into_raw(),
                Picture::Rgba16(_) => unreachable!("an 8-bit picture"),
            })
            .collect();
        let side_by_side = dir.path().join("side/");
        let in_turn = dir.path().join("turn/");
        let none = AtomicBool::new(false);
        let format = AnimationFormat::PngSequence;
        animator
            .write(&frames, &side_by_side, format, &|_, _| {}, &none)
            .expect("written");
        // From inside a pool: drawn and written in turn.
        let target = in_turn.clone();
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a pool")
            .install(move || animator.write(&frames, &target, format, &|_, _| {}, &none))
            .expect("written");
        for (i, expected) in one_by_one.iter().enumerate() {
            for folder in [&side_by_side, &in_turn] {
                let path = folder.join(format!("frame_{i:05}.png"));
                let got = image::open(&path).expect("a frame").into_rgba8();
                assert!(got.as_raw() == expected, "{}", path.display());
            }
        }
        assert_ne!(one_by_one[0], one_by_one[8], "it moved");
    }

    #[test]
    fn a_grown_canvas_holds_every_frame_each_at_its_place() {
        let picture = picture();
        // The handle goes 20 px beyond the right edge by the last frame.
        let project = project("fit", 28.0);
        let frames = plan(&project, Span::default(), AnimationFormat::Apng).expect("a plan");
        let mut animator = Animator::new(&picture, &project, &frames, false, &()).expect("set up");
        let (width, height) = animator.size();
        let rgba8 = picture.to_rgba8();
        let mut widths = Vec::new();
        for &time in &frames.times {
            let posed = animation::posed_at(&project, time);
            let warper = crate::prepare_warper(&rgba8, &posed, None, &()).expect("set up");
            let own = warper.frame(48, 32).expect("a frame");
            let alone = crate::warp_picture(&picture, &warper)
                .expect("drawn")
                .into_rgba8();
            let framed = animator.render(time).expect("drawn").into_rgba8();
            assert_eq!(framed.dimensions(), (width, height));
            let all = animator.scene.frame;
            let (dx, dy) = (own.origin[0] - all.origin[0], own.origin[1] - all.origin[1]);
            for (x, y, p) in framed.enumerate_pixels() {
                let (ax, ay) = (i64::from(x) - dx, i64::from(y) - dy);
                let inside = (0..i64::from(own.width)).contains(&ax)
                    && (0..i64::from(own.height)).contains(&ay);
                let expected = if inside {
                    *alone.get_pixel(ax as u32, ay as u32)
                } else {
                    image::Rgba([0; 4])
                };
                assert_eq!(*p, expected, "({x}, {y}) at {time} s");
            }
            widths.push(own.width);
        }
        assert_eq!(widths[0], 48);
        assert_eq!(width, *widths.iter().max().expect("frames"));
        assert!(width > 48);
    }
}
