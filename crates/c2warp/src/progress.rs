//! A step counter on stderr for work that takes more than a moment (drawn only when
//! stderr is a terminal).

use std::sync::atomic::{AtomicU32, Ordering};

use indicatif::{ProgressBar, ProgressStyle};
use weights_core::{Phase, Progress};

/// Numbered steps with a spinner.
pub struct Steps {
    bar: ProgressBar,
}

impl Steps {
    /// A counter of `total` steps.
    pub fn new(total: u64) -> Self {
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template("{spinner} [{pos}/{len}] {msg} ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        Self { bar }
    }

    /// Starts the next step.
    pub fn step(&self, message: &'static str) {
        self.bar.inc(1);
        self.bar.set_message(message);
    }

    /// A callback for a rig build ([`pipeline::prepare_with_progress`]) that shows
    /// its phase and percentage in the current step's message.
    pub fn weighting(&self) -> impl Fn(Progress) + Sync + '_ {
        let shown = AtomicU32::new(u32::MAX);
        move |progress: Progress| {
            let percent = (progress.fraction() * 100.0) as u32;
            let key = percent * 4 + progress.phase as u32;
            if shown.swap(key, Ordering::Relaxed) != key {
                let phase = match progress.phase {
                    Phase::Partition => "Voronoi cells",
                    Phase::VirtualHandles => "virtual handles",
                    Phase::Weights => "weights",
                    Phase::Transforms => "harmonic coordinates",
                };
                self.bar
                    .set_message(format!("meshing and weighting: {phase}, {percent}%"));
            }
        }
    }

    /// Replaces the current step's message.
    pub fn message(&self, message: String) {
        self.bar.set_message(message);
    }

    /// Clears the counter.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Drop for Steps {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
