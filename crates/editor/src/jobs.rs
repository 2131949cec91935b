//! Work that can take longer than a frame — opening a picture or project, re-meshing at
//! a new density, solving a cage, exporting — runs on a worker thread; the editor keeps
//! drawing, shows what it is doing (a cage's solve: its iterations and residuals), takes
//! no edits until the result is in, and can cancel it.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::Result;
use pipeline::cage::CageCoordinates;
use project::Project;

use crate::document::{CageKey, Document};

/// What a finished job hands back.
pub(crate) enum Outcome {
    /// A picture or project was opened.
    Opened {
        /// The files opened: one picture or project, or several pictures.
        paths: Vec<PathBuf>,
        is_project: bool,
        document: Result<Document>,
    },
    /// The warped picture was written.
    Exported {
        path: PathBuf,
        result: Result<()>,
        /// How long it took.
        ms: f64,
    },
    /// The picture was re-meshed for new parameters.
    Rebuilt {
        /// Why: an edit, or a step through the history.
        cause: Rebuild,
        document: Result<Document>,
    },
    /// A cage's coordinates were solved.
    CageSolved {
        key: CageKey,
        solution: Result<Arc<CageCoordinates>>,
        /// Undo (`true`) or redo to the state the cage was solved for, now that it is.
        then: Option<bool>,
        ms: f64,
    },
}

/// The last ADMM iteration of a cage being solved, and the first (to tell how far the
/// residuals have come), shared by the worker and the window.
#[derive(Clone, Default)]
pub(crate) struct SolveProgress(Arc<Mutex<[Option<lbc::Progress>; 2]>>);

impl SolveProgress {
    /// Records an iteration.
    pub fn set(&self, progress: lbc::Progress) {
        if let Ok(mut steps) = self.0.lock() {
            steps[0].get_or_insert(progress);
            steps[1] = Some(progress);
        }
    }

    /// The first and the latest iteration, once there is one.
    pub fn get(&self) -> Option<(lbc::Progress, lbc::Progress)> {
        let steps = *self.0.lock().ok()?;
        Some((steps[0]?, steps[1]?))
    }
}

/// The frames of an animation written so far, and how many there are, shared by the
/// worker and the window.
#[derive(Clone, Default)]
pub(crate) struct FrameProgress(Arc<[std::sync::atomic::AtomicUsize; 2]>);

impl FrameProgress {
    /// Records `done` frames of `total`.
    pub fn set(&self, done: usize, total: usize) {
        self.0[0].store(done, Ordering::Relaxed);
        self.0[1].store(total, Ordering::Relaxed);
    }

    /// Frames written and frames in all (`(0, 0)` before the first).
    pub fn get(&self) -> (usize, usize) {
        (
            self.0[0].load(Ordering::Relaxed),
            self.0[1].load(Ordering::Relaxed),
        )
    }
}

/// Why the picture was re-meshed.
pub(crate) enum Rebuild {
    /// A new density; `before` is the state to record in the undo history.
    Edit { before: Box<Project> },
    /// Undo (`back`) or redo to a state with another density.
    History { back: bool },
}

/// Set when the user cancels a job: work that checks it stops before it writes
/// anything.
#[derive(Clone, Default)]
pub(crate) struct CancelFlag(Arc<AtomicBool>);

impl CancelFlag {
    /// Whether the job was cancelled.
    pub fn is_set(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    fn set(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// The flag itself, for work that takes one.
    pub fn flag(&self) -> &AtomicBool {
        &self.0
    }
}

/// A job on a worker thread.
pub(crate) struct Job {
    /// What it does, for the user ("opening lizard.png").
    pub label: String,
    pub started: Instant,
    receiver: mpsc::Receiver<Outcome>,
    cancel: CancelFlag,
    /// A cage's solve under way, for the progress display.
    pub progress: Option<SolveProgress>,
    /// An animation's frames being written, for the progress display.
    pub frames: Option<FrameProgress>,
}

impl Job {
    /// Runs `work` on a new thread; `wake` (the UI context) repaints when it is done.
    /// Work that can write something checks `cancel` first.
    pub fn spawn_cancellable(
        label: String,
        wake: Option<egui::Context>,
        cancel: CancelFlag,
        work: impl FnOnce() -> Outcome + Send + 'static,
    ) -> Self {
        let (sender, receiver) = mpsc::channel();
        std::thread::spawn(move || {
            // The receiver may be gone (the job was cancelled, or the editor closed):
            // the outcome is dropped then.
            let _ = sender.send(work());
            if let Some(ctx) = wake {
                ctx.request_repaint();
            }
        });
        Self {
            label,
            started: Instant::now(),
            receiver,
            cancel,
            progress: None,
            frames: None,
        }
    }

    /// The outcome if the job has finished, without waiting. A job whose thread died
    /// (it cannot, short of a bug) reports nothing and never finishes: it can still be
    /// cancelled.
    pub fn poll(&self) -> Option<Outcome> {
        self.receiver.try_recv().ok()
    }

    /// Waits for the outcome.
    pub fn wait(self) -> Option<Outcome> {
        self.receiver.recv().ok()
    }

    /// Gives up on the job: its outcome, whenever it comes, is dropped, and work that
    /// checks the flag writes nothing. (A thread stuck in a system call cannot be
    /// stopped; it ends when the call does.)
    pub fn cancel(self) {
        self.cancel.set();
    }
}
