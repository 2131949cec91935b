//! The timeline's state: the time shown, playback, the key being dragged on the
//! strip, the clipboard, onion skin and recording. The keys themselves live in the
//! rig file (`project::Animation`), so undo covers them; what acts on them is
//! `app/animate.rs`, the strip is drawn by `panels/timeline.rs`.

use std::time::Instant;

use project::{Pose, Project};

/// The tolerance (pixels) a recorded take is simplified to by default.
pub const DEFAULT_TOLERANCE: f64 = animation::DEFAULT_TOLERANCE;

/// The timeline's state.
#[derive(Clone, Debug)]
pub struct Timeline {
    /// The time shown, in seconds.
    pub time: f64,
    /// Playing: since when, and from which time.
    pub(crate) playing: Option<(Instant, f64)>,
    /// The pose shown is a frame of playback, not yet solved in full (see
    /// [`crate::document::Document::play_time`]).
    pub(crate) played: bool,
    /// Playback starts again at the first key after the last.
    pub looping: bool,
    /// Show the previous and next keys' pictures ghosted behind the current one.
    pub onion: bool,
    /// A key's pose copied, for pasting at another time.
    pub(crate) clipboard: Option<Pose>,
    /// A key being dragged along the strip: its index when the drag began, and the rig
    /// file before (for the one undo step).
    pub(crate) key_drag: Option<(usize, Project)>,
    /// Recording: armed for the next drag, or taking one.
    pub(crate) record: Record,
    /// Keep every recorded frame as a key instead of simplifying the take.
    pub keep_every_frame: bool,
    /// How far (pixels) a simplified take may stray from what was recorded.
    pub tolerance: f64,
    /// The input's clock this frame (seconds): what a take's samples are timed by.
    pub(crate) clock: f64,
    /// When the primary button went down for the gesture under way (input clock): a
    /// take starts then, not when the drag is first recognised.
    pub(crate) pressed_at: Option<f64>,
}

impl Default for Timeline {
    fn default() -> Self {
        Self {
            clock: 0.0,
            pressed_at: None,
            time: 0.0,
            playing: None,
            played: false,
            looping: true,
            onion: false,
            clipboard: None,
            key_drag: None,
            record: Record::Off,
            keep_every_frame: false,
            tolerance: DEFAULT_TOLERANCE,
        }
    }
}

/// Recording a performance.
#[derive(Clone, Debug, Default)]
pub(crate) enum Record {
    /// Not recording.
    #[default]
    Off,
    /// The next live drag (a handle, cage vertices, the control cursor) is recorded.
    Armed,
    /// A drag is being recorded.
    Taking(Box<Take>),
}

/// A take under way: the poses of a live drag, each with when it was shown.
#[derive(Clone, Debug)]
pub(crate) struct Take {
    /// When it started, on the input's clock (seconds).
    pub started: f64,
    /// The timeline's time at its start.
    pub from: f64,
    /// The rig file before the drag (the take is one undo step).
    pub before: Project,
    /// The poses so far, each with its time since the start (seconds), in order:
    /// one per drawn frame that changed it. The take's frames are resampled from
    /// them at the project's rate ([`animation::resample`]).
    pub samples: Vec<(f64, Pose)>,
}

impl Timeline {
    /// Whether playback is running.
    pub fn is_playing(&self) -> bool {
        self.playing.is_some()
    }

    /// Whether recording is armed or under way.
    pub fn is_recording(&self) -> bool {
        !matches!(self.record, Record::Off)
    }

    /// Whether a take is under way.
    pub fn is_taking(&self) -> bool {
        matches!(self.record, Record::Taking(_))
    }

    /// Stops playback and drops a key drag (a new document, a job).
    pub fn stop(&mut self) {
        self.playing = None;
        self.key_drag = None;
    }
}

/// `time` rounded to the nearest frame at `fps`.
pub fn snap(time: f64, fps: f64) -> f64 {
    ((time * fps).round() / fps).max(0.0)
}
