//! Work that can take longer than a frame — opening a picture or project, re-meshing at
//! a new density, exporting — runs on a worker thread; the editor keeps drawing, shows what it is
//! doing, takes no edits until the result is in, and can cancel it.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use anyhow::Result;
use project::Project;

use crate::document::Document;

/// What a finished job hands back.
pub(crate) enum Outcome {
    /// A picture or project was opened.
    Opened {
        path: PathBuf,
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
}

/// A job on a worker thread.
pub(crate) struct Job {
    /// What it does, for the user ("opening lizard.png").
    pub label: String,
    pub started: Instant,
    receiver: mpsc::Receiver<Outcome>,
    cancel: CancelFlag,
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
