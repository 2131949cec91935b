//! Animations written frame by frame, at full resolution with alpha: animated PNG,
//! animated WebP (muxed here around image-webp's lossless frames), GIF, or a
//! directory of numbered PNG files. Frames stream to disk as they come; the
//! result is put in place atomically at the end.

use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::fs::{self, File};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use image::RgbaImage;
use rayon::prelude::*;

use crate::atomic::Replacement;
use crate::files::is_frame_name;
use crate::{Picture, RenderError, write_png};

/// What an animation is written as.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AnimationFormat {
    /// Animated PNG (`.png`): lossless, RGBA with 8 bits per channel, or 16 when the
    /// frames have 16. Viewers without APNG support show the first frame.
    Apng,
    /// Animated WebP (`.webp`): lossless, RGBA with 8 bits per channel (16-bit
    /// frames are rounded to 8).
    WebP,
    /// GIF (`.gif`): an 8-bit palette of at most 256 colours per frame, so it is
    /// lossy. Frames of at most 255 opaque colours keep them exactly; others are
    /// reduced with NeuQuant. Alpha is one bit: pixels with alpha below 128 are
    /// transparent, the others opaque. Delays are whole hundredths of a second and
    /// players slow down frames shorter than 2, so a GIF plays at most 50 frames
    /// per second.
    Gif,
    /// A directory of PNG files `frame_00000.png`, `frame_00001.png`, … (more digits
    /// beyond 100,000 frames), each RGBA in the depth of its frame, byte for byte
    /// what [`save_png_atomic`](crate::save_png_atomic) writes for it.
    PngSequence,
}

impl AnimationFormat {
    /// The format an output path asks for: a path ending in `/` (or the platform's
    /// separator) or naming an existing directory is a [`PngSequence`](Self::PngSequence);
    /// otherwise the extension decides, in any case: `.png` is
    /// [`Apng`](Self::Apng), `.webp` [`WebP`](Self::WebP), `.gif` [`Gif`](Self::Gif).
    ///
    /// # Errors
    /// [`RenderError::Animation`] for any other path, naming the accepted forms.
    pub fn from_path(path: &Path) -> Result<Self, RenderError> {
        let text = path.as_os_str().to_string_lossy();
        if text.chars().last().is_some_and(std::path::is_separator) || path.is_dir() {
            return Ok(Self::PngSequence);
        }
        let extension = path
            .extension()
            .map(|extension| extension.to_string_lossy().to_ascii_lowercase());
        match extension.as_deref() {
            Some("png") => Ok(Self::Apng),
            Some("webp") => Ok(Self::WebP),
            Some("gif") => Ok(Self::Gif),
            _ => Err(animation_error(
                path,
                "the name must end in .png (animated PNG), .webp (animated WebP) or .gif, \
                 or name a directory for a PNG sequence (end it with /)",
            )),
        }
    }

    /// A short name for messages: `"animated PNG"`, `"animated WebP"`, `"GIF"` or
    /// `"PNG sequence"`.
    pub fn label(self) -> &'static str {
        match self {
            Self::Apng => "animated PNG",
            Self::WebP => "animated WebP",
            Self::Gif => "GIF",
            Self::PngSequence => "PNG sequence",
        }
    }

    /// The highest frame rate the format plays, in frames per second:
    /// [`AnimationWriter::MAX_FPS`], or 50 for a GIF.
    pub fn max_fps(self) -> f64 {
        match self {
            Self::Gif => 50.0,
            _ => AnimationWriter::MAX_FPS,
        }
    }

    /// The longest a frame may last, in seconds, or `None` for no limit (a PNG
    /// sequence has no timing).
    fn max_frame_seconds(self) -> Option<f64> {
        match self {
            // fcTL delay 65535/1 s; ANMF duration 2^24 - 1 ms; GCE delay 65535 cs.
            Self::Apng => Some(65_535.0),
            Self::WebP => Some(16_777.215),
            Self::Gif => Some(655.35),
            Self::PngSequence => None,
        }
    }

    /// The largest width and height of a frame in pixels (beyond what memory allows).
    fn max_side(self) -> u32 {
        match self {
            // PNG's limit is 2^31 - 1.
            Self::Apng | Self::PngSequence => i32::MAX as u32,
            // VP8L stores 14 bits per side.
            Self::WebP => 16_384,
            Self::Gif => u32::from(u16::MAX),
        }
    }
}

/// Writes an animation frame by frame, streaming: each [`push`](Self::push)
/// encodes one frame and writes it out, and [`push_all`](Self::push_all) encodes a
/// run of frames side by side (on rayon's threads) and writes them out in order,
/// so no more than those frames are held in memory. The animation loops forever.
///
/// The file appears at its path only when [`finish`](Self::finish) succeeds: the
/// frames go to a temporary file in the same directory, which is synced and
/// renamed over the path, as [`write_atomic`](crate::write_atomic) does (a
/// symbolic link is followed; a device or FIFO is written through, except for
/// animated WebP, which must seek back). After an error, or when the writer is
/// dropped unfinished, the temporary file is removed and an existing file is
/// left untouched; the writer refuses further frames after an error.
///
/// A [`PngSequence`](AnimationFormat::PngSequence) writes and syncs each frame to
/// a temporary file beside its name as it comes, and renames them all into place
/// at `finish`. The directory remembers which frames the writer put there (in a
/// small hidden list, `.c2warp-frames`), so that a later sequence into it removes
/// the frames of the earlier one it does not replace (a longer one, or one numbered
/// with more digits) and the directory holds exactly this animation; a frame file
/// (`frame_<digits>.png`) the writer did not put there is never replaced or
/// removed: such a directory is refused. Each file is replaced atomically; the set
/// of them only nearly so (a crash during the renames leaves a mix). The directory
/// is created if missing (not its parent), and removed again if the writer is
/// dropped unfinished.
///
/// Timing: animated PNG gives every frame the delay `num / den` seconds (each at
/// most 65535) closest to `1 / fps`; animated WebP (milliseconds) and GIF
/// (hundredths of a second) round each frame's start time, so that delays
/// alternate (4 and 5 cs at 24 fps) and the total stays right. Browsers play
/// frames of 10 ms or less as 100 ms, so rates above 100 frames per second are
/// for players that keep them.
///
/// # Example
/// ```
/// use image::{Rgba, RgbaImage};
/// use render::{AnimationFormat, AnimationWriter, Picture};
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("pulse.png");
/// let format = AnimationFormat::from_path(&path)?;
/// let mut writer = AnimationWriter::create(&path, format, 32, 24, 3, 12.0)?;
/// for i in 0..3u8 {
///     let frame = RgbaImage::from_pixel(32, 24, Rgba([100 * i, 0, 0, 255]));
///     writer.push(&Picture::from(frame))?;
/// }
/// assert!(!path.exists()); // not until it is finished
/// writer.finish()?;
/// assert!(path.is_file());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct AnimationWriter {
    /// The output path as given, for errors.
    path: PathBuf,
    format: AnimationFormat,
    width: u32,
    height: u32,
    frames: usize,
    pushed: usize,
    /// The format's encoder; `None` once a frame failed (the animation is abandoned).
    sink: Option<Box<dyn FrameSink + Send + Sync>>,
}

impl AnimationWriter {
    /// The highest frame rate accepted, in frames per second.
    pub const MAX_FPS: f64 = 240.0;

    /// Starts writing `frames` frames of `width`×`height` pixels at `fps` frames
    /// per second to `path` as `format` (see [`AnimationFormat::from_path`]). For
    /// a [`PngSequence`](AnimationFormat::PngSequence), `path` is the directory.
    ///
    /// # Errors
    /// [`RenderError::Animation`] if `frames` is 0, `fps` is not finite, not
    /// positive or above the format's [`max_fps`](AnimationFormat::max_fps) (or so
    /// low that a frame outlasts the format's longest delay), a side is 0 or above
    /// the format's limit (16384 for WebP, 65535 for GIF), or an animated PNG is
    /// asked for more than `u32::MAX` frames; for a PNG sequence whose directory's
    /// parent is missing, [`RenderError::MissingDirectory`]; the errors of
    /// [`write_atomic`](crate::write_atomic) when the file cannot be created.
    pub fn create(
        path: &Path,
        format: AnimationFormat,
        width: u32,
        height: u32,
        frames: usize,
        fps: f64,
    ) -> Result<Self, RenderError> {
        let label = format.label();
        if frames == 0 {
            return Err(animation_error(
                path,
                "an animation needs at least one frame",
            ));
        }
        if !fps.is_finite() || fps <= 0.0 || fps > Self::MAX_FPS {
            return Err(animation_error(
                path,
                format!(
                    "{fps} frames per second is not a frame rate (above 0, at most {})",
                    Self::MAX_FPS
                ),
            ));
        }
        if fps > format.max_fps() {
            return Err(animation_error(
                path,
                format!(
                    "{label} plays at most {} frames per second, not {fps} \
                     (animated PNG and WebP play faster)",
                    format.max_fps()
                ),
            ));
        }
        if let Some(longest) = format.max_frame_seconds()
            && 1.0 / fps > longest
        {
            return Err(animation_error(
                path,
                format!(
                    "at {fps} frames per second a frame outlasts the {label} limit of {longest} s"
                ),
            ));
        }
        let max_side = format.max_side();
        if width == 0 || height == 0 || width > max_side || height > max_side {
            return Err(animation_error(
                path,
                format!(
                    "{label} frames cannot be {width}x{height} pixels (each side from 1 to {max_side})"
                ),
            ));
        }
        let sink: Box<dyn FrameSink + Send + Sync> = match format {
            AnimationFormat::Apng => Box::new(ApngSink::create(path, width, height, frames, fps)?),
            AnimationFormat::WebP => Box::new(WebpSink::create(path, width, height, fps)?),
            AnimationFormat::Gif => Box::new(GifSink::create(path, width, height, fps)?),
            AnimationFormat::PngSequence => Box::new(SequenceSink::create(path, frames)?),
        };
        Ok(Self {
            path: path.to_owned(),
            format,
            width,
            height,
            frames,
            pushed: 0,
            sink: Some(sink),
        })
    }

    /// Appends the next frame: a [`Picture`] of 8 or 16 bits per channel, of the
    /// size given to [`create`](Self::create). Its depth is kept where the format
    /// allows (16-bit animated PNG and PNG sequence); an animated PNG takes the
    /// depth of its first frame and converts later frames of the other depth to it
    /// (16 to 8 bits rounds).
    ///
    /// # Errors
    /// [`RenderError::Animation`] if all frames were already given, the frame has
    /// another size, or an earlier frame failed; [`RenderError::Encode`] if the
    /// encoder fails; [`RenderError::Io`] if writing fails. After an encoding or
    /// writing error the animation is abandoned (its temporary files removed).
    pub fn push(&mut self, frame: &Picture) -> Result<(), RenderError> {
        self.push_all(std::slice::from_ref(frame))
    }

    /// Appends the next `frames.len()` frames, as [`push`](Self::push) each, but
    /// encodes them side by side on rayon's threads (compression is most of an
    /// animated PNG's or a GIF's cost) before writing them out in order. The file
    /// is byte for byte what pushing them one by one writes.
    ///
    /// # Errors
    /// As [`push`](Self::push); frames are checked before any is encoded, and after
    /// an error none of them is written.
    pub fn push_all(&mut self, frames: &[Picture]) -> Result<(), RenderError> {
        let first = self.pushed;
        if first + frames.len() > self.frames {
            return Err(animation_error(
                &self.path,
                format!(
                    "frame {} is one too many: the animation was started for {} frames",
                    self.frames + 1,
                    self.frames
                ),
            ));
        }
        for (offset, frame) in frames.iter().enumerate() {
            let (width, height) = frame.dimensions();
            if (width, height) != (self.width, self.height) {
                return Err(animation_error(
                    &self.path,
                    format!(
                        "frame {} of {} is {width}x{height} pixels, not {}x{}",
                        first + offset + 1,
                        self.frames,
                        self.width,
                        self.height
                    ),
                ));
            }
        }
        let Some(sink) = self.sink.as_mut() else {
            return Err(self.abandoned());
        };
        let result = Self::encode_and_write(sink.as_mut(), first, frames);
        if result.is_err() {
            self.sink = None;
        } else {
            self.pushed += frames.len();
        }
        result
    }

    /// Encodes `frames` (from frame `first`) side by side, then writes them in order.
    fn encode_and_write(
        sink: &mut (dyn FrameSink + Send + Sync),
        first: usize,
        frames: &[Picture],
    ) -> Result<(), RenderError> {
        if first == 0
            && let Some(frame) = frames.first()
        {
            sink.begin(frame)?;
        }
        let encoded: Vec<Encoded> = {
            let sink = &*sink;
            if frames.len() == 1 {
                vec![sink.encode(first, &frames[0])?]
            } else {
                frames
                    .par_iter()
                    .enumerate()
                    .map(|(offset, frame)| sink.encode(first + offset, frame))
                    .collect::<Result<_, _>>()?
            }
        };
        for (offset, frame) in encoded.into_iter().enumerate() {
            sink.write(first + offset, frame)?;
        }
        Ok(())
    }

    /// Ends the animation and puts it in place (see the type's documentation).
    ///
    /// # Errors
    /// [`RenderError::Animation`] if fewer frames were given than
    /// [`create`](Self::create) was told, or an earlier frame failed;
    /// [`RenderError::Io`] if writing, syncing or renaming fails. In every case
    /// nothing is left behind and an existing file is untouched.
    pub fn finish(mut self) -> Result<(), RenderError> {
        if self.pushed < self.frames {
            return Err(animation_error(
                &self.path,
                format!(
                    "only {} of its {} frames were given",
                    self.pushed, self.frames
                ),
            ));
        }
        let sink = self.sink.take().ok_or_else(|| self.abandoned())?;
        sink.finish()
    }

    /// The format being written.
    pub fn format(&self) -> AnimationFormat {
        self.format
    }

    /// How many frames have been pushed so far.
    pub fn pushed(&self) -> usize {
        self.pushed
    }

    /// The error for a writer whose earlier frame failed.
    fn abandoned(&self) -> RenderError {
        animation_error(
            &self.path,
            format!(
                "frame {} failed earlier, so the animation was abandoned",
                self.pushed + 1
            ),
        )
    }
}

/// One format's encoder behind [`AnimationWriter`], which has already checked
/// each frame's size and the count. Encoding takes the sink shared, so that frames
/// are encoded side by side; writing takes it alone, in order.
trait FrameSink {
    /// Sees the first frame before any frame is encoded (an animated PNG takes its
    /// depth and writes its header).
    fn begin(&mut self, _first: &Picture) -> Result<(), RenderError> {
        Ok(())
    }
    /// Encodes frame `index` (from 0).
    fn encode(&self, index: usize, frame: &Picture) -> Result<Encoded, RenderError>;
    /// Writes out frame `index`, encoded; frames come in order.
    fn write(&mut self, index: usize, frame: Encoded) -> Result<(), RenderError>;
    /// Ends the file and puts it in place.
    fn finish(self: Box<Self>) -> Result<(), RenderError>;
}

/// A frame as a [`FrameSink`] encoded it.
enum Encoded {
    /// The bytes the format wraps: a zlib stream (animated PNG), a `VP8L` chunk
    /// (WebP) or a whole PNG file (sequence).
    Bytes(Vec<u8>),
    /// A GIF frame with its LZW data.
    Gif(gif::Frame<'static>),
}

impl Encoded {
    /// The bytes, for a sink that encodes to bytes (a sink only ever sees its own
    /// kind, so `Gif` is an error that cannot happen).
    fn into_bytes(self, path: &Path) -> Result<Vec<u8>, RenderError> {
        match self {
            Self::Bytes(bytes) => Ok(bytes),
            Self::Gif(_) => Err(RenderError::Encode {
                path: path.to_owned(),
                detail: "a GIF frame was handed to another format's writer".to_owned(),
            }),
        }
    }
}

/// A [`RenderError::Animation`] for `path`.
fn animation_error(path: &Path, detail: impl Into<String>) -> RenderError {
    RenderError::Animation {
        path: path.to_owned(),
        detail: detail.into(),
    }
}

/// A [`RenderError::Io`] maker for writing `path`.
fn write_error(path: &Path) -> impl Fn(io::Error) -> RenderError + '_ {
    move |source| RenderError::Io {
        path: path.to_owned(),
        action: "write",
        source,
    }
}

/// How many ticks of `1 / ticks_per_second` s frame `index` lasts at `fps`: the
/// difference of the rounded start times of it and the next frame, so that any
/// run of frames lasts what it should to within a tick; at most `max`.
fn frame_ticks(index: usize, fps: f64, ticks_per_second: f64, max: u32) -> u32 {
    let start = |i: usize| (i as f64 * ticks_per_second / fps).round();
    let ticks = start(index + 1) - start(index);
    (ticks as u32).min(max)
}

/// The fraction `num / den` (each from 1 to 65535) closest to `1 / fps` seconds,
/// the smallest denominator on a tie: an animated PNG frame's delay.
fn apng_delay(fps: f64) -> (u16, u16) {
    let target = 1.0 / fps;
    let mut best = (1, 1);
    let mut best_error = f64::INFINITY;
    for den in 1..=u16::MAX {
        let num = (f64::from(den) * target).round().clamp(1.0, 65_535.0);
        let error = (num / f64::from(den) - target).abs();
        if error < best_error {
            best_error = error;
            best = (num as u16, den);
        }
    }
    best
}

// ---------------------------------------------------------------- animated PNG

/// Animated PNG, muxed here: each frame is compressed by the `png` crate as a PNG of
/// its own (fdeflate, adaptive filters: what [`save_png_atomic`](crate::save_png_atomic)
/// uses), frames side by side, and its `IDAT` data is written as the first frame's
/// `IDAT` or a later frame's `fdAT` chunks. Every frame is full size, blended by
/// replacing (`blend_op` source), not disposed.
struct ApngSink {
    path: PathBuf,
    width: u32,
    height: u32,
    frames: u32,
    /// The delay of every frame, `num / den` seconds.
    delay: (u16, u16),
    /// Whether frames have 16 bits per channel (the first frame's depth), once it
    /// came.
    sixteen: Option<bool>,
    /// The next `fcTL` / `fdAT` sequence number.
    sequence: u32,
    out: BufWriter<File>,
    /// Bytes written since the file was last synced.
    unsynced: usize,
    replacement: Replacement,
}

/// The most data an `IDAT` or `fdAT` chunk holds (the `png` crate's choice too).
const APNG_CHUNK_DATA: usize = 1 << 20;
/// An animated PNG's file is synced each time this many bytes were written, while
/// frames are still being drawn, so that the sync before it is put in place has
/// little left to do (a 16-bit animation runs to hundreds of megabytes).
const APNG_SYNC_BYTES: usize = 64 << 20;

impl ApngSink {
    fn create(
        path: &Path,
        width: u32,
        height: u32,
        frames: usize,
        fps: f64,
    ) -> Result<Self, RenderError> {
        let frames = u32::try_from(frames).map_err(|_| {
            animation_error(path, "an animated PNG holds at most 4294967295 frames")
        })?;
        let (replacement, file) = Replacement::begin(path)?;
        Ok(Self {
            path: path.to_owned(),
            width,
            height,
            frames,
            delay: apng_delay(fps),
            sixteen: None,
            sequence: 0,
            out: BufWriter::new(file),
            unsynced: 0,
            replacement,
        })
    }

    /// Writes one chunk: length, type, data, CRC of type and data.
    fn chunk(&mut self, kind: &[u8; 4], data: &[&[u8]]) -> Result<(), RenderError> {
        let length: usize = data.iter().map(|part| part.len()).sum();
        let mut crc = crc32fast::Hasher::new();
        crc.update(kind);
        for part in data {
            crc.update(part);
        }
        let write = write_error(&self.path);
        self.out
            .write_all(&(length as u32).to_be_bytes())
            .map_err(&write)?;
        self.out.write_all(kind).map_err(&write)?;
        for part in data {
            self.out.write_all(part).map_err(&write)?;
        }
        self.out
            .write_all(&crc.finalize().to_be_bytes())
            .map_err(&write)?;
        self.unsynced += 12 + length;
        if self.unsynced >= APNG_SYNC_BYTES && !self.replacement.writes_through() {
            self.unsynced = 0;
            self.out.flush().map_err(&write)?;
            self.out.get_ref().sync_data().map_err(&write)?;
        }
        Ok(())
    }
}

impl FrameSink for ApngSink {
    fn begin(&mut self, first: &Picture) -> Result<(), RenderError> {
        let sixteen = first.bits_per_channel() == 16;
        self.sixteen = Some(sixteen);
        self.out
            .write_all(b"\x89PNG\r\n\x1a\n")
            .map_err(write_error(&self.path))?;
        let mut header = [0u8; 13];
        header[..4].copy_from_slice(&self.width.to_be_bytes());
        header[4..8].copy_from_slice(&self.height.to_be_bytes());
        // Depth, colour type 6 (RGBA); deflate, adaptive filtering, no interlace.
        header[8] = if sixteen { 16 } else { 8 };
        header[9] = 6;
        self.chunk(b"IHDR", &[&header])?;
        let mut control = [0u8; 8];
        control[..4].copy_from_slice(&self.frames.to_be_bytes());
        // Plays: 0, forever.
        self.chunk(b"acTL", &[&control])
    }

    fn encode(&self, _index: usize, frame: &Picture) -> Result<Encoded, RenderError> {
        let sixteen = self.sixteen.unwrap_or(frame.bits_per_channel() == 16);
        let converted: Vec<u8>;
        let data: &[u8] = match (frame, sixteen) {
            (Picture::Rgba8(image), false) => image.as_raw(),
            (Picture::Rgba16(image), true) => {
                converted = big_endian(image.as_raw());
                &converted
            }
            (Picture::Rgba8(image), true) => {
                let widened: Vec<u16> =
                    image.as_raw().iter().map(|&v| u16::from(v) * 257).collect();
                converted = big_endian(&widened);
                &converted
            }
            (Picture::Rgba16(_), false) => {
                converted = frame.to_rgba8().into_owned().into_raw();
                &converted
            }
        };
        let error = |error| png_error(&self.path, error);
        let mut png = Vec::with_capacity(data.len() / 2);
        let mut encoder = png::Encoder::new(&mut png, self.width, self.height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(if sixteen {
            png::BitDepth::Sixteen
        } else {
            png::BitDepth::Eight
        });
        encoder.set_compression(png::Compression::Fast);
        encoder.set_filter(png::Filter::Adaptive);
        let mut writer = encoder.write_header().map_err(error)?;
        writer.write_image_data(data).map_err(error)?;
        writer.finish().map_err(error)?;
        idat_data(&png)
            .map(Encoded::Bytes)
            .ok_or_else(|| RenderError::Encode {
                path: self.path.clone(),
                detail: "the PNG encoder wrote no image data".to_owned(),
            })
    }

    fn write(&mut self, index: usize, frame: Encoded) -> Result<(), RenderError> {
        let data = frame.into_bytes(&self.path)?;
        let mut control = [0u8; 26];
        control[..4].copy_from_slice(&self.sequence.to_be_bytes());
        control[4..8].copy_from_slice(&self.width.to_be_bytes());
        control[8..12].copy_from_slice(&self.height.to_be_bytes());
        // Bytes 12..20: offset (0, 0).
        control[20..22].copy_from_slice(&self.delay.0.to_be_bytes());
        control[22..24].copy_from_slice(&self.delay.1.to_be_bytes());
        // Dispose op 0 (none), blend op 0 (source).
        self.sequence += 1;
        self.chunk(b"fcTL", &[&control])?;
        for piece in data.chunks(APNG_CHUNK_DATA) {
            if index == 0 {
                self.chunk(b"IDAT", &[piece])?;
            } else {
                let sequence = self.sequence.to_be_bytes();
                self.sequence += 1;
                self.chunk(b"fdAT", &[&sequence, piece])?;
            }
        }
        Ok(())
    }

    fn finish(mut self: Box<Self>) -> Result<(), RenderError> {
        self.chunk(b"IEND", &[])?;
        let Self {
            path,
            out,
            replacement,
            ..
        } = *self;
        let file = out
            .into_inner()
            .map_err(|error| write_error(&path)(error.into_error()))?;
        replacement.commit(file)
    }
}

/// 16-bit samples as PNG stores them, big-endian.
fn big_endian(samples: &[u16]) -> Vec<u8> {
    let mut bytes = vec![0; 2 * samples.len()];
    for (pair, sample) in bytes.chunks_exact_mut(2).zip(samples) {
        pair.copy_from_slice(&sample.to_be_bytes());
    }
    bytes
}

/// The image data of a PNG file: its `IDAT` chunks' data, joined (one zlib stream);
/// `None` if it has none or its chunks do not add up.
fn idat_data(png: &[u8]) -> Option<Vec<u8>> {
    let mut rest = png.get(8..)?;
    let mut data = Vec::new();
    while rest.len() >= 12 {
        let length = u32::from_be_bytes(rest[..4].try_into().ok()?) as usize;
        let kind = &rest[4..8];
        let body = rest.get(8..8 + length)?;
        if kind == b"IDAT" {
            data.extend_from_slice(body);
        }
        rest = rest.get(12 + length..)?;
    }
    (!data.is_empty()).then_some(data)
}

/// A `png` encoding error as a [`RenderError`] for `path`.
fn png_error(path: &Path, error: png::EncodingError) -> RenderError {
    match error {
        png::EncodingError::IoError(source) => write_error(path)(source),
        other => RenderError::Encode {
            path: path.to_owned(),
            detail: other.to_string(),
        },
    }
}

// --------------------------------------------------------------- animated WebP

/// Animated WebP, muxed here: a `VP8X` chunk (animation and alpha), `ANIM` (loop
/// forever), then per frame an `ANMF` chunk (full size, not blended, not disposed)
/// around the `VP8L` chunk of image-webp's lossless encoding of the frame. The
/// RIFF size is patched at the end.
struct WebpSink {
    path: PathBuf,
    width: u32,
    height: u32,
    fps: f64,
    out: BufWriter<File>,
    /// Bytes after the RIFF header's size field so far (the RIFF size).
    riff_size: u64,
    replacement: Replacement,
}

/// The `VP8X` flags: animation and alpha.
const VP8X_ANIMATION_ALPHA: u8 = 0x02 | 0x10;
/// The `ANMF` flags: do not blend (bit 1), dispose of nothing (bit 0 clear).
const ANMF_NO_BLEND: u8 = 0x02;

impl WebpSink {
    fn create(path: &Path, width: u32, height: u32, fps: f64) -> Result<Self, RenderError> {
        let (replacement, mut file) = Replacement::begin(path)?;
        if replacement.writes_through() && file.stream_position().is_err() {
            return Err(animation_error(
                path,
                "an animated WebP cannot go to a pipe or terminal: its size is written last",
            ));
        }
        let mut header = Vec::with_capacity(38);
        header.extend_from_slice(b"RIFF\0\0\0\0WEBP");
        header.extend_from_slice(b"VP8X");
        header.extend_from_slice(&10u32.to_le_bytes());
        header.extend_from_slice(&[VP8X_ANIMATION_ALPHA, 0, 0, 0]);
        header.extend_from_slice(&u24(width - 1));
        header.extend_from_slice(&u24(height - 1));
        header.extend_from_slice(b"ANIM");
        header.extend_from_slice(&6u32.to_le_bytes());
        // Background colour (transparent black), loop count (0: forever).
        header.extend_from_slice(&[0, 0, 0, 0, 0, 0]);
        let mut out = BufWriter::new(file);
        out.write_all(&header).map_err(write_error(path))?;
        Ok(Self {
            path: path.to_owned(),
            width,
            height,
            fps,
            out,
            riff_size: header.len() as u64 - 8,
            replacement,
        })
    }
}

impl FrameSink for WebpSink {
    fn encode(&self, _index: usize, frame: &Picture) -> Result<Encoded, RenderError> {
        let rgba = frame.to_rgba8();
        let mut file = Vec::new();
        image_webp::WebPEncoder::new(&mut file)
            .encode(
                rgba.as_raw(),
                self.width,
                self.height,
                image_webp::ColorType::Rgba8,
            )
            .map_err(|error| match error {
                image_webp::EncodingError::IoError(source) => write_error(&self.path)(source),
                other => RenderError::Encode {
                    path: self.path.clone(),
                    detail: other.to_string(),
                },
            })?;
        // The encoder writes a simple file: RIFF, size, WEBP, then the VP8L chunk
        // (header, data, padding to an even length), which is what ANMF wraps.
        if file.starts_with(b"RIFF") && file.get(12..).is_some_and(|c| c.starts_with(b"VP8L")) {
            file.drain(..12);
            Ok(Encoded::Bytes(file))
        } else {
            Err(RenderError::Encode {
                path: self.path.clone(),
                detail: "the WebP encoder wrote no VP8L chunk".to_owned(),
            })
        }
    }

    fn write(&mut self, index: usize, frame: Encoded) -> Result<(), RenderError> {
        let vp8l = frame.into_bytes(&self.path)?;
        let anmf_size = 16 + vp8l.len() as u64;
        self.riff_size += 8 + anmf_size;
        if self.riff_size > u64::from(u32::MAX) {
            return Err(animation_error(
                &self.path,
                format!(
                    "frame {} takes the animated WebP past its 4 GiB limit",
                    index + 1
                ),
            ));
        }
        let duration = frame_ticks(index, self.fps, 1000.0, 0xff_ffff);
        let mut header = [0u8; 24];
        header[..4].copy_from_slice(b"ANMF");
        header[4..8].copy_from_slice(&(anmf_size as u32).to_le_bytes());
        // Bytes 8..14: frame offset (0, 0).
        header[14..17].copy_from_slice(&u24(self.width - 1));
        header[17..20].copy_from_slice(&u24(self.height - 1));
        header[20..23].copy_from_slice(&u24(duration));
        header[23] = ANMF_NO_BLEND;
        let write = write_error(&self.path);
        self.out.write_all(&header).map_err(&write)?;
        self.out.write_all(&vp8l).map_err(&write)
    }

    fn finish(self: Box<Self>) -> Result<(), RenderError> {
        let Self {
            path,
            out,
            riff_size,
            replacement,
            ..
        } = *self;
        let write = write_error(&path);
        let mut file = out
            .into_inner()
            .map_err(|error| write(error.into_error()))?;
        let size = u32::try_from(riff_size)
            .map_err(|_| animation_error(&path, "the animated WebP is past its 4 GiB limit"))?;
        file.seek(SeekFrom::Start(4)).map_err(&write)?;
        file.write_all(&size.to_le_bytes()).map_err(&write)?;
        replacement.commit(file)
    }
}

/// The low three bytes of `value`, little-endian (WebP's 24-bit fields).
fn u24(value: u32) -> [u8; 3] {
    let [a, b, c, _] = value.to_le_bytes();
    [a, b, c]
}

// ------------------------------------------------------------------------- GIF

/// The NeuQuant sampling factor for frames of more than 255 colours (1 is best and
/// slowest, 30 fastest; 10 is the gif crate's choice).
const GIF_QUANTIZER_SPEED: i32 = 10;
/// The most opaque pixels of a frame NeuQuant learns its palette from (evenly spaced;
/// with [`GIF_QUANTIZER_SPEED`], it visits a tenth of them).
const GIF_LEARNING_PIXELS: usize = 1 << 18;
/// Bits a channel of the cells of the colour cube whose centres are matched to the
/// palette (a pixel is at most 2 levels a channel from its cell's centre, well within
/// a 255-colour palette's own error).
const GIF_CELL_BITS: u32 = 6;

/// GIF through the `gif` crate: a palette per frame, every frame full size and
/// disposed to the background (transparent) so that transparent pixels show
/// nothing of the frame before.
struct GifSink {
    path: PathBuf,
    fps: f64,
    encoder: gif::Encoder<BufWriter<File>>,
    /// The temporary file (the encoder writes to a clone of it).
    file: File,
    replacement: Replacement,
}

impl GifSink {
    fn create(path: &Path, width: u32, height: u32, fps: f64) -> Result<Self, RenderError> {
        let (replacement, file) = Replacement::begin(path)?;
        let clone = file.try_clone().map_err(write_error(path))?;
        let too_large = || animation_error(path, "a GIF is at most 65535x65535 pixels");
        let width = u16::try_from(width).map_err(|_| too_large())?;
        let height = u16::try_from(height).map_err(|_| too_large())?;
        let mut encoder = gif::Encoder::new(BufWriter::new(clone), width, height, &[])
            .map_err(|error| gif_error(path, error))?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .map_err(|error| gif_error(path, error))?;
        Ok(Self {
            path: path.to_owned(),
            fps,
            encoder,
            file,
            replacement,
        })
    }
}

impl FrameSink for GifSink {
    fn encode(&self, index: usize, frame: &Picture) -> Result<Encoded, RenderError> {
        let rgba = frame.to_rgba8();
        let (palette, indices, transparent) = quantize(&rgba);
        let (width, height) = rgba.dimensions();
        let mut gif_frame = gif::Frame {
            delay: frame_ticks(index, self.fps, 100.0, u32::from(u16::MAX)) as u16,
            dispose: gif::DisposalMethod::Background,
            transparent: Some(transparent),
            width: width as u16,
            height: height as u16,
            palette: Some(palette),
            buffer: Cow::Owned(indices),
            ..gif::Frame::default()
        };
        gif_frame.make_lzw_pre_encoded();
        Ok(Encoded::Gif(gif_frame))
    }

    fn write(&mut self, _index: usize, frame: Encoded) -> Result<(), RenderError> {
        let Encoded::Gif(frame) = frame else {
            return Err(RenderError::Encode {
                path: self.path.clone(),
                detail: "another format's frame was handed to the GIF writer".to_owned(),
            });
        };
        self.encoder
            .write_lzw_pre_encoded_frame(&frame)
            .map_err(|error| gif_error(&self.path, error))
    }

    fn finish(self: Box<Self>) -> Result<(), RenderError> {
        let Self {
            path,
            encoder,
            file,
            replacement,
            ..
        } = *self;
        let mut out = encoder
            .into_inner()
            .map_err(|error| gif_error(&path, error))?;
        out.flush().map_err(write_error(&path))?;
        drop(out);
        replacement.commit(file)
    }
}

/// A `gif` encoding error as a [`RenderError`] for `path`.
fn gif_error(path: &Path, error: gif::EncodingError) -> RenderError {
    match error {
        gif::EncodingError::Io(source) => write_error(path)(source),
        other => RenderError::Encode {
            path: path.to_owned(),
            detail: other.to_string(),
        },
    }
}

/// A GIF frame's palette (RGB triples), pixel indices and transparent index.
/// Pixels with alpha below 128 are transparent (the last palette entry), the
/// others opaque: up to 255 distinct opaque colours keep an exact palette, more
/// are reduced to 255 by NeuQuant (learnt from at most [`GIF_LEARNING_PIXELS`]
/// of them), each pixel taking the entry nearest its cell of the colour cube.
fn quantize(image: &RgbaImage) -> (Vec<u8>, Vec<u8>, u8) {
    let pixels = image.as_raw();
    let opaque = |p: &[u8]| p[3] >= 128;
    let mut exact: HashMap<[u8; 3], u8> = HashMap::new();
    let mut palette = Vec::new();
    let mut few = true;
    for p in pixels.chunks_exact(4).filter(|p| opaque(p)) {
        let rgb = [p[0], p[1], p[2]];
        if !exact.contains_key(&rgb) {
            // Index 255 is kept for the transparent colour.
            if exact.len() == 255 {
                few = false;
                break;
            }
            exact.insert(rgb, exact.len() as u8);
            palette.extend_from_slice(&rgb);
        }
    }
    if few {
        let transparent = exact.len() as u8;
        palette.extend_from_slice(&[0, 0, 0]);
        let indices = pixels
            .par_chunks_exact(4)
            .map(|p| {
                if opaque(p) {
                    exact
                        .get(&[p[0], p[1], p[2]])
                        .copied()
                        .unwrap_or(transparent)
                } else {
                    transparent
                }
            })
            .collect();
        return (palette, indices, transparent);
    }
    // NeuQuant learns from at most `GIF_LEARNING_PIXELS` opaque pixels, evenly spaced.
    let count = pixels.chunks_exact(4).filter(|p| opaque(p)).count();
    let stride = count.div_ceil(GIF_LEARNING_PIXELS).max(1);
    let samples: Vec<u8> = pixels
        .chunks_exact(4)
        .filter(|p| opaque(p))
        .step_by(stride)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    let quantizer = color_quant::NeuQuant::new(GIF_QUANTIZER_SPEED, 255, &samples);
    let mut palette = quantizer.color_map_rgb();
    palette.truncate(255 * 3);
    let transparent = (palette.len() / 3) as u8;
    palette.extend_from_slice(&[0, 0, 0]);
    // Each pixel takes the palette entry nearest the centre of its cell of the colour
    // cube (`GIF_CELL_BITS` bits a channel), looked up once per cell in use.
    let cell = |p: &[u8]| {
        let shift = 8 - GIF_CELL_BITS;
        (usize::from(p[0] >> shift) << (2 * GIF_CELL_BITS))
            | (usize::from(p[1] >> shift) << GIF_CELL_BITS)
            | usize::from(p[2] >> shift)
    };
    let mut used = vec![false; 1 << (3 * GIF_CELL_BITS)];
    for p in pixels.chunks_exact(4).filter(|p| opaque(p)) {
        used[cell(p)] = true;
    }
    let mask = (1 << GIF_CELL_BITS) - 1;
    let centre = |c: usize| ((c & mask) << (8 - GIF_CELL_BITS) | (1 << (7 - GIF_CELL_BITS))) as u8;
    let table: Vec<u8> = used
        .par_iter()
        .enumerate()
        .map(|(c, &used)| {
            if used {
                let rgba = [
                    centre(c >> (2 * GIF_CELL_BITS)),
                    centre(c >> GIF_CELL_BITS),
                    centre(c),
                    255,
                ];
                quantizer.index_of(&rgba) as u8
            } else {
                transparent
            }
        })
        .collect();
    let indices = pixels
        .par_chunks_exact(4)
        .map(|p| {
            if opaque(p) {
                table[cell(p)]
            } else {
                transparent
            }
        })
        .collect();
    (palette, indices, transparent)
}

// ---------------------------------------------------------------- PNG sequence

/// A directory of `frame_NNNNN.png` files, each sealed in a temporary file as it
/// comes and renamed into place at the end.
struct SequenceSink {
    dir: PathBuf,
    frames: usize,
    /// Digits in a frame's number: 5, or as many as the last number needs.
    digits: usize,
    /// The frames an earlier sequence of the writer's left in the directory.
    earlier: Vec<String>,
    /// The frames written so far, waiting to be renamed into place.
    written: Vec<Replacement>,
    /// Whether `create` made the directory (removed again if abandoned).
    created_dir: bool,
    finished: bool,
}

impl SequenceSink {
    fn create(dir: &Path, frames: usize) -> Result<Self, RenderError> {
        let created_dir = match fs::metadata(dir) {
            Ok(meta) if meta.is_dir() => false,
            Ok(_) => {
                return Err(animation_error(
                    dir,
                    "a PNG sequence needs a directory, and this is a file",
                ));
            }
            Err(error) if error.kind() == io::ErrorKind::NotFound => create_dir(dir)?,
            Err(source) => {
                return Err(RenderError::Io {
                    path: dir.to_owned(),
                    action: "inspect",
                    source,
                });
            }
        };
        let digits = (frames - 1).to_string().len().max(5);
        let earlier = if created_dir {
            Vec::new()
        } else {
            let earlier = read_frame_list(dir);
            refuse_other_frames(dir, &earlier)?;
            earlier
        };
        Ok(Self {
            dir: dir.to_owned(),
            frames,
            digits,
            earlier,
            written: Vec::new(),
            created_dir,
            finished: false,
        })
    }

    /// The file name of frame `index`.
    fn frame_name(&self, index: usize) -> String {
        format!("frame_{index:0width$}.png", width = self.digits)
    }

    /// Removes the frames of the earlier sequence that this one did not replace, then
    /// records this one's.
    fn replace_frame_list(&self) -> Result<(), RenderError> {
        let ours: HashSet<String> = (0..self.frames).map(|i| self.frame_name(i)).collect();
        for name in &self.earlier {
            if ours.contains(name) {
                continue;
            }
            let stale = self.dir.join(name);
            match fs::symlink_metadata(&stale) {
                Ok(meta) if meta.is_file() => {}
                _ => continue,
            }
            fs::remove_file(&stale).map_err(|source| RenderError::Io {
                path: stale.clone(),
                action: "remove the stale frame",
                source,
            })?;
        }
        let mut list = String::from(FRAME_LIST_HEADER);
        list.push('\n');
        for index in 0..self.frames {
            list.push_str(&self.frame_name(index));
            list.push('\n');
        }
        crate::write_atomic(&self.dir.join(FRAME_LIST), list.as_bytes())
    }
}

/// The hidden file in a PNG sequence's directory that lists the frames the writer
/// put there, one name a line after [`FRAME_LIST_HEADER`].
const FRAME_LIST: &str = ".c2warp-frames";
/// The first line of [`FRAME_LIST`].
const FRAME_LIST_HEADER: &str = "# frames c2warp wrote here; a later sequence replaces them";

/// The frame names `dir`'s [`FRAME_LIST`] holds (none when there is no list, or it
/// is not one).
fn read_frame_list(dir: &Path) -> Vec<String> {
    let Ok(text) = fs::read_to_string(dir.join(FRAME_LIST)) else {
        return Vec::new();
    };
    let mut lines = text.lines();
    if lines.next() != Some(FRAME_LIST_HEADER) {
        return Vec::new();
    }
    lines
        .filter(|name| is_frame_name(name))
        .map(str::to_owned)
        .collect()
}

/// Refuses a directory holding a frame file (`frame_<digits>.png`) that is not in
/// `earlier`, the writer's own list: it would be replaced, or left among the new
/// frames.
fn refuse_other_frames(dir: &Path, earlier: &[String]) -> Result<(), RenderError> {
    let list_error = |source| RenderError::Io {
        path: dir.to_owned(),
        action: "list",
        source,
    };
    let earlier: HashSet<&str> = earlier.iter().map(String::as_str).collect();
    let mut others: Vec<String> = Vec::new();
    for entry in fs::read_dir(dir).map_err(list_error)? {
        let name = entry.map_err(list_error)?.file_name();
        if let Some(name) = name.to_str()
            && is_frame_name(name)
            && !earlier.contains(name)
        {
            others.push(name.to_owned());
        }
    }
    others.sort();
    let Some(first) = others.first() else {
        return Ok(());
    };
    let more = match others.len() {
        1 => String::new(),
        n => format!(" and {} more", n - 1),
    };
    Err(animation_error(
        dir,
        format!(
            "the folder holds {first}{more}, which no earlier animation of this program \
             wrote there; choose an empty folder, or move those frames away"
        ),
    ))
}

/// Creates the directory `dir` (not its parents); true when done.
fn create_dir(dir: &Path) -> Result<bool, RenderError> {
    match fs::create_dir(dir) {
        Ok(()) => Ok(true),
        Err(error) if error.kind() == io::ErrorKind::AlreadyExists && dir.is_dir() => Ok(false),
        Err(error) if error.kind() == io::ErrorKind::NotFound => {
            let parent = match dir.parent() {
                Some(parent) if !parent.as_os_str().is_empty() => parent.to_owned(),
                _ => PathBuf::from("."),
            };
            Err(RenderError::MissingDirectory {
                path: dir.to_owned(),
                dir: parent,
            })
        }
        Err(source) => Err(RenderError::Io {
            path: dir.to_owned(),
            action: "create the directory",
            source,
        }),
    }
}

impl FrameSink for SequenceSink {
    fn encode(&self, index: usize, frame: &Picture) -> Result<Encoded, RenderError> {
        let mut png = Vec::new();
        write_png(&mut png, frame, &self.dir.join(self.frame_name(index)))?;
        Ok(Encoded::Bytes(png))
    }

    fn write(&mut self, index: usize, frame: Encoded) -> Result<(), RenderError> {
        let path = self.dir.join(self.frame_name(index));
        let png = frame.into_bytes(&path)?;
        let (replacement, mut file) = Replacement::begin(&path)?;
        file.write_all(&png).map_err(write_error(&path))?;
        replacement.seal(file)?;
        self.written.push(replacement);
        Ok(())
    }

    fn finish(mut self: Box<Self>) -> Result<(), RenderError> {
        for frame in std::mem::take(&mut self.written) {
            frame.publish()?;
        }
        self.finished = true;
        self.replace_frame_list()
    }
}

impl Drop for SequenceSink {
    fn drop(&mut self) {
        if !self.finished && self.created_dir {
            // Remove the temporary frames first, then the directory if now empty.
            self.written.clear();
            let _ = fs::remove_dir(&self.dir);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delays_add_up_at_fractional_rates() {
        let cs: Vec<u32> = (0..6).map(|i| frame_ticks(i, 24.0, 100.0, 65535)).collect();
        assert_eq!(cs, [4, 4, 5, 4, 4, 4]);
        for fps in [24.0, 29.97, 30.0, 12.5, 50.0, 7.0] {
            let total: u32 = (0..1000).map(|i| frame_ticks(i, fps, 100.0, 65535)).sum();
            assert!(
                (f64::from(total) - 100_000.0 / fps).abs() <= 0.5,
                "{fps}: {total}"
            );
            let total: u32 = (0..1000)
                .map(|i| frame_ticks(i, fps, 1000.0, 0xff_ffff))
                .sum();
            assert!(
                (f64::from(total) - 1_000_000.0 / fps).abs() <= 0.5,
                "{fps}: {total}"
            );
        }
    }

    #[test]
    fn apng_delay_is_the_closest_fraction() {
        assert_eq!(apng_delay(24.0), (1, 24));
        assert_eq!(apng_delay(240.0), (1, 240));
        assert_eq!(apng_delay(29.97), (100, 2997));
        assert_eq!(apng_delay(0.5), (2, 1));
        let (num, den) = apng_delay(23.976);
        assert!((f64::from(num) / f64::from(den) - 1.0 / 23.976).abs() < 1e-9);
    }

    #[test]
    fn gif_palette_is_exact_for_few_colours() {
        let image = RgbaImage::from_fn(4, 2, |x, _| match x {
            0 => image::Rgba([10, 20, 30, 255]),
            1 => image::Rgba([200, 100, 0, 128]),
            2 => image::Rgba([1, 2, 3, 127]),
            _ => image::Rgba([10, 20, 30, 0]),
        });
        let (palette, indices, transparent) = quantize(&image);
        assert_eq!(palette, [10, 20, 30, 200, 100, 0, 0, 0, 0]);
        assert_eq!(transparent, 2);
        assert_eq!(indices, [0, 1, 2, 2, 0, 1, 2, 2]);
    }

    #[test]
    fn gif_palette_reduces_many_colours_to_255_plus_transparent() {
        let image = RgbaImage::from_fn(64, 64, |x, y| {
            image::Rgba([
                (x * 4) as u8,
                (y * 4) as u8,
                77,
                if x == 0 { 0 } else { 255 },
            ])
        });
        let (palette, indices, transparent) = quantize(&image);
        assert_eq!(palette.len(), 256 * 3);
        assert_eq!(transparent, 255);
        for (i, &index) in indices.iter().enumerate() {
            assert_eq!(index == transparent, i % 64 == 0, "pixel {i}");
        }
    }
}
