//! File → Export animation…: the format, range and rate asked in a window, the file
//! asked next, and the frames drawn and written on the worker — the same frames
//! `c2warp animate` writes for the saved project, each what `c2warp render` draws for
//! the rig posed at its time.

use pipeline::animate::{Animator, Span};
use render::AnimationFormat;

use super::files::ExportSetup;
use super::*;
use crate::jobs::FrameProgress;

/// What the export window asks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnimationExport {
    /// Animated PNG, WebP, GIF, or a numbered PNG sequence.
    pub format: AnimationFormat,
    /// The first frame's time, seconds.
    pub from: f64,
    /// The last frame's time at most, seconds.
    pub to: f64,
    /// Frames per second.
    pub fps: f64,
}

/// The formats, in the order the window lists them.
const FORMATS: [AnimationFormat; 4] = [
    AnimationFormat::Apng,
    AnimationFormat::WebP,
    AnimationFormat::Gif,
    AnimationFormat::PngSequence,
];

impl EditorApp {
    /// Opens the export window with the animation's range and rate (or says why there
    /// is nothing to export).
    pub fn ask_animation_export(&mut self) {
        let keys = self.keys();
        let Some(last) = keys.last().map(|k| k.time) else {
            self.info(
                "nothing to export yet: set keys on the timeline (Set key, I) or record a take",
            );
            return;
        };
        let format = self
            .animation_export
            .map_or(AnimationFormat::Apng, |e| e.format);
        self.animation_export = Some(AnimationExport {
            format,
            from: 0.0,
            to: last,
            fps: self.fps(),
        });
    }

    /// The export window, while open.
    pub(crate) fn animation_export_window(&mut self, ctx: &egui::Context) {
        let Some(mut export) = self.animation_export else {
            return;
        };
        let mut open = true;
        let mut go = false;
        egui::Window::new("Export animation")
            .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
            .open(&mut open)
            .collapsible(false)
            .resizable(false)
            .show(ctx, |ui| {
                egui::ComboBox::from_label("Format")
                    .selected_text(export.format.label())
                    .show_ui(ui, |ui| {
                        for format in FORMATS {
                            ui.selectable_value(&mut export.format, format, format.label());
                        }
                    });
                egui::Grid::new("export animation").show(ui, |ui| {
                    ui.label("From");
                    ui.add(
                        egui::DragValue::new(&mut export.from)
                            .range(0.0..=project::animation::MAX_TIME)
                            .speed(0.05)
                            .suffix(" s"),
                    );
                    ui.end_row();
                    ui.label("To");
                    ui.add(
                        egui::DragValue::new(&mut export.to)
                            .range(0.0..=project::animation::MAX_TIME)
                            .speed(0.05)
                            .suffix(" s"),
                    );
                    ui.end_row();
                    ui.label("Rate");
                    ui.add(
                        egui::DragValue::new(&mut export.fps)
                            .range(1.0..=export.format.max_fps())
                            .speed(0.2)
                            .suffix(" fps"),
                    );
                    ui.end_row();
                });
                let frames = animation::frame_count(export.fps, export.from, export.to);
                ui.label(format!(
                    "{frames} frames at the picture's full size, with alpha{}",
                    match export.format {
                        AnimationFormat::Gif => " (GIF: 256 colours a frame, alpha on or off)",
                        AnimationFormat::PngSequence =>
                            "; the folder is named after the file you choose",
                        _ => "",
                    }
                ));
                if ui.button("Export…").clicked() {
                    go = true;
                }
            });
        self.animation_export = open.then_some(export);
        if go {
            self.ask_file(FileAction::ExportAnimation);
        }
    }

    /// The file name the dialog offers: the picture's, with the format's extension.
    pub(super) fn suggested_animation_name(&self) -> String {
        let format = self
            .animation_export
            .map_or(AnimationFormat::Apng, |e| e.format);
        self.suggested_name(match format {
            AnimationFormat::Apng => "animation.png",
            AnimationFormat::WebP => "animation.webp",
            AnimationFormat::Gif => "animation.gif",
            AnimationFormat::PngSequence => "frames.png",
        })
    }

    /// Exports the animation as the export window asks, to `path` (for a PNG sequence,
    /// into the folder `path` names without its extension), on the worker with its
    /// progress shown; Cancel writes nothing.
    pub fn export_animation_to(&mut self, path: PathBuf) {
        let Some(export) = self.animation_export else {
            return;
        };
        if let Some(job) = &self.job {
            let running = job.label.clone();
            return self.error(&anyhow::anyhow!(
                "the export waits: {running}… is still running (cancel it with Escape)"
            ));
        }
        let Some(doc) = &self.doc else { return };
        let project = doc.project_for_saving(None);
        let span = Span {
            fps: Some(export.fps),
            from: Some(export.from),
            to: Some(export.to),
        };
        // Checked now, so a bad range is said at once.
        let frames = match pipeline::animate::plan(&project, span, export.format) {
            Ok(frames) => frames,
            Err(e) => return self.error(&e),
        };
        let output = match export.format {
            AnimationFormat::PngSequence => path.with_extension(""),
            _ => path,
        };
        if let Err(e) = self.refuse_sources(&output) {
            return self.error(&e);
        }
        let Some(doc) = &self.doc else { return };
        let image = doc.image.clone();
        let picture = doc
            .deep
            .as_deref()
            .cloned()
            .unwrap_or_else(|| render::Picture::Rgba8((*image).clone()));
        let setup = ExportSetup::of(doc, &project);
        let cancel = CancelFlag::default();
        let progress = FrameProgress::default();
        let (flag, shown) = (cancel.clone(), progress.clone());
        let format = export.format;
        let label = format!("Exporting {} frames", frames.times.len());
        let work = move || {
            let clock = Instant::now();
            let result = (|| -> Result<()> {
                let warper = setup.warper(&image, &project, &flag)?;
                let animator = Animator::with_warper(&picture, &project, warper, &frames, false)?;
                animator.write(
                    &frames,
                    &output,
                    format,
                    &|done, total| shown.set(done, total),
                    flag.flag(),
                )
            })()
            .with_context(|| format!("cannot export {}", output.display()));
            Outcome::Exported {
                path: output,
                result,
                ms: clock.elapsed().as_secs_f64() * 1e3,
            }
        };
        self.start_job(label, cancel, work);
        if let Some(job) = &mut self.job {
            job.frames = Some(progress);
        }
        self.animation_export = None;
    }

    /// Frames written and in all, while an animation is being exported.
    pub fn frames_progress(&self) -> Option<(usize, usize)> {
        Some(self.job.as_ref()?.frames.as_ref()?.get())
    }
}
