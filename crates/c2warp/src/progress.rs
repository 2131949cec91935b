//! A step counter on stderr for work that takes more than a moment (drawn only when
//! stderr is a terminal).

use std::sync::atomic::{AtomicU32, Ordering};

use indicatif::{ProgressBar, ProgressStyle};
use weights_core::{Phase, Progress};

/// Numbered steps with a spinner; as a [`pipeline::Listener`], it shows a setup's
/// progress (the rig build's phase and percentage, a cage solve's iterations) in the
/// current step's message.
pub struct Steps {
    bar: ProgressBar,
    /// The rig build's phase and percentage last shown.
    shown: AtomicU32,
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
        Self {
            bar,
            shown: AtomicU32::new(u32::MAX),
        }
    }

    /// Starts the next step.
    pub fn step(&self, message: &'static str) {
        self.bar.inc(1);
        self.bar.set_message(message);
    }

    /// Shows how many of an animation's frames are written.
    pub fn frames(&self, done: usize, total: usize) {
        self.bar
            .set_message(format!("drawing and writing frames: {done} of {total}"));
    }

    /// Clears the counter.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl pipeline::Listener for Steps {
    fn weighting(&self, progress: Progress) {
        let percent = (progress.fraction() * 100.0) as u32;
        let key = percent * 4 + progress.phase as u32;
        if self.shown.swap(key, Ordering::Relaxed) != key {
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

    fn solving(&self, progress: &pipeline::SolveProgress) -> bool {
        self.bar.set_message(format!(
            "solving the cage's coordinates: iteration {}, residuals {:.1e} / {:.1e}",
            progress.iteration, progress.primal_residual, progress.dual_residual
        ));
        true
    }
}

impl Drop for Steps {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
