//! The status bar and the windows over the canvas: the message log, the keyboard
//! shortcuts, and the questions that wait for an answer.

use super::*;

impl EditorApp {
    pub(super) fn status_bar(&mut self, ui: &mut Ui) {
        ui.horizontal(|ui| {
            if let Some(doc) = &self.doc {
                for (k, (text, hover)) in
                    self.set(doc.controls()).status(doc).into_iter().enumerate()
                {
                    if k > 0 {
                        ui.separator();
                    }
                    let label = ui.label(text);
                    if let Some(hover) = hover {
                        label.on_hover_text(hover);
                    }
                }
                ui.separator();
                ui.label(format!("frame {:.1} ms", self.frame_ms));
                ui.separator();
                ui.label(format!("zoom {:.0}%", self.viewport.zoom * 100.0));
                if self.dirty {
                    ui.separator();
                    ui.label("unsaved");
                }
            }
            if let Some((what, seconds)) = self.busy_with() {
                ui.separator();
                turning_arc(ui, seconds);
                ui.label(format!("{what}… {seconds:.1} s"));
                if let Some((first, last)) = self.solve_progress() {
                    ui.add(
                        egui::ProgressBar::new(solve_fraction(&first, &last))
                            .desired_width(120.0)
                            .text(format!("iteration {}", last.iteration)),
                    )
                    .on_hover_text(solve_text(&last));
                    ui.label(format!(
                        "residuals {:.1e} / {:.1e}",
                        last.primal_residual, last.dual_residual
                    ));
                }
                if let Some((done, total)) = self.frames_progress() {
                    let fraction = if total > 0 {
                        done as f32 / total as f32
                    } else {
                        0.0
                    };
                    ui.add(
                        egui::ProgressBar::new(fraction)
                            .desired_width(160.0)
                            .text(format!("frame {done} of {total}")),
                    );
                }
                if ui.button("Cancel").on_hover_text("Escape").clicked() {
                    self.cancel_job();
                }
            }
            if let Some(message) = &self.message {
                ui.separator();
                let color = if message.is_error {
                    ui.visuals().error_fg_color
                } else {
                    ui.visuals().text_color()
                };
                // One line, cut at the window's edge: the whole message is in the
                // tooltip and in the messages window (a click opens it).
                let label = egui::Label::new(egui::RichText::new(&message.text).color(color))
                    .truncate()
                    .sense(egui::Sense::click());
                let text = message.text.clone();
                if ui
                    .add(label)
                    .on_hover_text(format!("{text}\n\n(click for all messages)"))
                    .clicked()
                {
                    self.log_open = true;
                }
            }
        });
    }

    pub(super) fn log_window(&mut self, ctx: &egui::Context) {
        let mut open = self.log_open;
        egui::Window::new("Messages")
            .open(&mut open)
            .default_size([560.0, 260.0])
            .show(ctx, |ui| {
                egui::ScrollArea::vertical()
                    .stick_to_bottom(true)
                    .show(ui, |ui| {
                        for message in &self.log {
                            let color = if message.is_error {
                                ui.visuals().error_fg_color
                            } else {
                                ui.visuals().text_color()
                            };
                            ui.add(
                                egui::Label::new(egui::RichText::new(&message.text).color(color))
                                    .wrap()
                                    .selectable(true),
                            );
                            ui.separator();
                        }
                    });
            });
        self.log_open = open;
    }

    pub(super) fn help_window(&mut self, ctx: &egui::Context) {
        let mut open = self.help_open;
        // Never taller than the window: the list scrolls.
        let height = (ctx.content_rect().height() - 80.0).max(120.0);
        egui::Window::new("Keyboard shortcuts")
            .open(&mut open)
            .resizable(false)
            .default_height(height)
            .max_height(height)
            .show(ctx, |ui| {
                egui::ScrollArea::vertical()
                    .max_height(height)
                    .min_scrolled_height(height)
                    .show(ui, |ui| {
                        egui::Grid::new("shortcuts").striped(true).show(ui, |ui| {
                            for (keys, what) in SHORTCUTS {
                                ui.strong(*keys);
                                ui.label(*what);
                                ui.end_row();
                            }
                        });
                    });
            });
        self.help_open = open;
    }

    pub(super) fn pending_modal(&mut self, ctx: &egui::Context) {
        let Some(pending) = self.pending.clone() else {
            return;
        };
        let mut answer = None;
        let unsaved = matches!(pending, Pending::Open(_) | Pending::Close);
        let (heading, question, yes) = match &pending {
            Pending::Replace(_, path) => (
                "Replace file?",
                format!("{} exists. Replace it?", path.display()),
                "Replace",
            ),
            Pending::Open(_) | Pending::Close => (
                "Unsaved changes",
                "The current project has changes that are not saved. Save them first?".to_owned(),
                "Discard",
            ),
        };
        egui::Modal::new(egui::Id::unique("question")).show(ctx, |ui| {
            ui.heading(heading);
            ui.label(question);
            ui.horizontal(|ui| {
                if unsaved && ui.button("Save").clicked() {
                    answer = Some(Answer::Save);
                }
                if ui.button(yes).clicked() {
                    answer = Some(Answer::Go);
                }
                if ui.button("Cancel").on_hover_text("Escape").clicked() {
                    answer = Some(Answer::Cancel);
                }
            });
        });
        match answer {
            Some(Answer::Save) => {
                self.pending = None;
                // Saved where it was, the question's action follows at once; a project
                // never saved asks where first, and follows when it is saved there.
                self.after_save = Some(pending);
                self.save();
                self.continue_after_save(ctx);
            }
            Some(Answer::Go) => {
                self.pending = None;
                self.go_on(pending, ctx);
            }
            Some(Answer::Cancel) => self.pending = None,
            None => {}
        }
    }

    /// Does what a question was asked for, now that it is answered.
    pub(crate) fn go_on(&mut self, pending: Pending, ctx: &egui::Context) {
        match pending {
            Pending::Open(paths) => self.open_all_in_background(paths),
            Pending::Replace(action, path) => self.file_chosen(action, path),
            Pending::Close => {
                self.allow_close = true;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        }
    }

    /// After a save the unsaved-changes question asked for: once nothing is unsaved,
    /// what the question was about goes on; a save that failed (or is still waiting
    /// for its file dialog) keeps it waiting.
    pub(crate) fn continue_after_save(&mut self, ctx: &egui::Context) {
        if !self.dirty
            && let Some(pending) = self.after_save.take()
        {
            self.go_on(pending, ctx);
        }
    }
}

/// How the question was answered.
enum Answer {
    /// Save, then go on (unsaved changes).
    Save,
    /// Go on: discard the changes, or replace the file.
    Go,
    /// Do nothing.
    Cancel,
}

/// How far a cage's solve has come, 0 to 1: the share of the way (in orders of
/// magnitude) from the first iteration's residuals to their thresholds, the slower of
/// the two.
fn solve_fraction(first: &lbc::Progress, last: &lbc::Progress) -> f32 {
    let share = |r0: f64, r: f64, goal: f64| {
        if r <= goal || r0 <= goal {
            1.0
        } else {
            ((r0 / r).ln() / (r0 / goal).ln()).clamp(0.0, 1.0)
        }
    };
    let primal = share(
        first.primal_residual,
        last.primal_residual,
        last.primal_threshold,
    );
    let dual = share(first.dual_residual, last.dual_residual, last.dual_threshold);
    if primal.is_finite() && dual.is_finite() {
        primal.min(dual) as f32
    } else {
        0.0
    }
}

/// One ADMM iteration in words.
fn solve_text(p: &lbc::Progress) -> String {
    format!(
        "ADMM iteration {}: primal residual {:.2e} (to reach {:.2e}), dual residual {:.2e} \
         (to reach {:.2e}), penalty {:.3}",
        p.iteration,
        p.primal_residual,
        p.primal_threshold,
        p.dual_residual,
        p.dual_threshold,
        p.penalty
    )
}

/// A spinner that turns with `seconds`: the frame loop's repaints while a job runs
/// (ten a second) move it. (egui's own spinner asks for a repaint every frame, which
/// on a machine drawing in software took the cores a solve on the worker needs: a
/// cage took three times as long in the editor as on the command line.)
fn turning_arc(ui: &mut egui::Ui, seconds: f64) {
    let size = ui.spacing().interact_size.y;
    let (rect, _) = ui.allocate_exact_size(egui::vec2(size, size), egui::Sense::hover());
    if !ui.is_rect_visible(rect) {
        return;
    }
    let radius = rect.height() / 2.0 - 2.0;
    let start = (seconds * std::f64::consts::TAU) as f32;
    let points: Vec<egui::Pos2> = (0..=20)
        .map(|i| {
            let angle = start + i as f32 / 20.0 * std::f32::consts::PI * 1.5;
            rect.center() + radius * egui::vec2(angle.cos(), angle.sin())
        })
        .collect();
    let stroke = ui.visuals().widgets.noninteractive.fg_stroke;
    ui.painter().add(egui::Shape::line(points, stroke));
}
