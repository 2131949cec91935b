//! Work that can take longer than a frame — opening a picture or project, re-meshing at
//! a new density, exporting — runs on a worker thread; the editor keeps drawing, shows what it is
//! doing, and takes no edits until the result is in.

use std::path::PathBuf;
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
        /// The state before, for the undo history.
        before: Project,
        document: Result<Document>,
    },
}

/// A job on a worker thread.
pub(crate) struct Job {
    /// What it does, for the user ("opening lizard.png").
    pub label: String,
    pub started: Instant,
    receiver: mpsc::Receiver<Outcome>,
}

impl Job {
    /// Runs `work` on a new thread; `wake` (the UI context) repaints when it is done.
    pub fn spawn(
        label: String,
        wake: Option<egui::Context>,
        work: impl FnOnce() -> Outcome + Send + 'static,
    ) -> Self {
        let (sender, receiver) = mpsc::channel();
        std::thread::spawn(move || {
            // The receiver may be gone (the editor closed): nothing to do then.
            let _ = sender.send(work());
            if let Some(ctx) = wake {
                ctx.request_repaint();
            }
        });
        Self {
            label,
            started: Instant::now(),
            receiver,
        }
    }

    /// The outcome if the job has finished, without waiting. A job whose thread died
    /// (it cannot, short of a bug) reports nothing and never finishes.
    pub fn poll(&self) -> Option<Outcome> {
        self.receiver.try_recv().ok()
    }

    /// Waits for the outcome.
    pub fn wait(self) -> Option<Outcome> {
        self.receiver.recv().ok()
    }
}
