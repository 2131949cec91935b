//! A step counter on stderr for work that takes more than a moment (drawn only when
//! stderr is a terminal).

use indicatif::{ProgressBar, ProgressStyle};

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
