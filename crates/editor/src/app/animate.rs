//! The timeline's actions: the time shown, playback, keys set, moved, copied and
//! deleted, keying a pose changed at a time (After Effects' convention: a pose
//! changed while keys exist is keyed at the current time, in the same undo step), and
//! recording a live drag as keys.

use std::time::Instant;

use project::{Animation, Interpolation, Pose};

use super::*;
use crate::timeline::{Record, Take, snap};

impl EditorApp {
    /// The animation's keys in time (none without a document or keys).
    pub fn keys(&self) -> &[project::Key] {
        self.doc.as_ref().map_or(&[], Document::keys)
    }

    /// The document's frame rate (the default without an animation).
    pub fn fps(&self) -> f64 {
        self.doc
            .as_ref()
            .and_then(|d| d.project().animation.as_ref())
            .map_or(project::animation::DEFAULT_FPS, |a| a.fps)
    }

    /// Shows the pose at `time` (seconds, snapped to a frame): the keys' interpolation.
    pub fn set_time(&mut self, time: f64) {
        if !time.is_finite() {
            return;
        }
        let time = snap(time, self.fps());
        self.timeline.time = time;
        self.show_current_time();
    }

    /// Shows the keys' pose at the timeline's time (after an undo, or a change of the
    /// keys). Without keys nothing moves.
    pub(crate) fn show_current_time(&mut self) {
        let time = self.timeline.time;
        let Some(doc) = &mut self.doc else { return };
        if let Err(e) = doc.show_time(time) {
            self.timeline.playing = None;
            self.error(&e.context(format!("the pose at {time:.2} s")));
        }
    }

    /// Shows the keys' pose at the timeline's time as a frame of playback (live; solved
    /// in full when playback stops).
    fn play_current_time(&mut self) {
        let time = self.timeline.time;
        let Some(doc) = &mut self.doc else { return };
        match doc.play_time(time) {
            Ok(_) => self.timeline.played = true,
            Err(e) => {
                self.timeline.playing = None;
                self.error(&e.context(format!("the pose at {time:.2} s")));
            }
        }
    }

    /// Starts or pauses playback (from the start when at or after the last key).
    pub fn toggle_play(&mut self) {
        if self.timeline.playing.is_some() {
            self.timeline.playing = None;
            return;
        }
        let keys = self.keys();
        if keys.len() < 2 {
            self.info(
                "set two keys or more to play: pose the handles, then Set key (I) at two times",
            );
            return;
        }
        let (first, last) = (keys[0].time, keys[keys.len() - 1].time);
        let from = if self.timeline.time >= last || self.timeline.time < first {
            first
        } else {
            self.timeline.time
        };
        self.end_gesture();
        self.timeline.playing = Some((Instant::now(), from));
    }

    /// Steps `frames` frames (negative: back), pausing playback.
    pub fn step_frames(&mut self, frames: i32) {
        self.timeline.playing = None;
        let fps = self.fps();
        self.set_time(self.timeline.time + f64::from(frames) / fps);
    }

    /// Goes to the previous (`back`) or next key.
    pub fn step_key(&mut self, back: bool) {
        self.timeline.playing = None;
        let now = self.timeline.time;
        let keys = self.keys();
        let target = if back {
            keys.iter().rev().find(|k| k.time < now - 1e-9)
        } else {
            keys.iter().find(|k| k.time > now + 1e-9)
        };
        if let Some(time) = target.map(|k| k.time) {
            self.set_time(time);
        }
    }

    /// Advances playback and a take by the wall clock; called once a frame.
    pub(crate) fn tick(&mut self, ctx: &egui::Context) {
        (self.timeline.clock, self.timeline.pressed_at) =
            ctx.input(|i| (i.time, i.pointer.press_start_time()));
        if self.is_busy() {
            self.timeline.playing = None;
        }
        if self.timeline.played && self.timeline.playing.is_none() {
            // Playback stopped (however it did): the pose shown is solved in full, as a
            // file of it renders.
            self.timeline.played = false;
            if let Some(doc) = &mut self.doc
                && let Err(e) = doc.settle()
            {
                self.error(&e);
            }
        }
        if let Some((since, from)) = self.timeline.playing {
            let keys = self.keys();
            let (first, last) = match (keys.first(), keys.last()) {
                (Some(a), Some(b)) if b.time > a.time => (a.time, b.time),
                _ => {
                    self.timeline.playing = None;
                    return;
                }
            };
            let mut time = from + since.elapsed().as_secs_f64();
            if time > last {
                if self.timeline.looping {
                    time = first + (time - first) % (last - first);
                } else {
                    time = last;
                    self.timeline.playing = None;
                }
            }
            // Unsnapped: playback shows every instant the screen can.
            self.timeline.time = time;
            self.play_current_time();
            ctx.request_repaint();
        }
        // A take samples each pose a drag shows (every frame of it, holding still too),
        // at the time of its pointer event; nothing to do here but keep drawing.
        if self.timeline.is_taking() {
            ctx.request_repaint();
        }
    }

    /// The animation with `change` made to it (starting from an empty one), applied
    /// as one undo step.
    fn change_animation(&mut self, change: impl FnOnce(&mut Animation)) -> bool {
        // A drag (or a take) under way ends first, as its own step: the change is made
        // to what it leaves.
        self.end_gesture();
        let Some(doc) = &self.doc else { return false };
        let mut animation = doc.project().animation.clone().unwrap_or_default();
        change(&mut animation);
        let keep = !animation.is_empty()
            || animation.fps != project::animation::DEFAULT_FPS
            || animation.interpolation != Interpolation::Linear;
        self.edit(Edit::Animation(keep.then(|| Box::new(animation))))
    }

    /// Keys the current pose at the timeline's time (one undo step).
    pub fn set_key(&mut self) {
        // A drag (or a take) under way ends first, as its own step: the key holds the
        // pose it leaves, at the time it leaves.
        self.end_gesture();
        let Some(doc) = &self.doc else { return };
        let time = snap(self.timeline.time, self.fps());
        let animation = doc.keyed_at(time);
        let count = animation.keys.len();
        // The timeline moves to the key's frame before the edit, which shows the keys'
        // pose at the timeline's time: at the time it was (between frames, after
        // playback or a scrub) that is the new key blended with the next one, not the
        // pose just keyed.
        let was = std::mem::replace(&mut self.timeline.time, time);
        if self.edit(Edit::Animation(Some(Box::new(animation)))) {
            let keys = if count == 1 { "key" } else { "keys" };
            self.info(format!("key set at {time:.2} s ({count} {keys})"));
        } else {
            self.timeline.time = was;
        }
    }

    /// Deletes the key at the timeline's time, if there is one (one undo step).
    pub fn delete_key(&mut self) {
        let time = self.timeline.time;
        let Some(index) = self.key_index_at(time) else {
            self.info("no key at this time: move to a key (Shift + , or .) to delete it");
            return;
        };
        if self.change_animation(|a| {
            a.keys.remove(index);
        }) {
            self.show_current_time();
            self.info(format!("key at {time:.2} s deleted"));
        }
    }

    /// The key at `time` (within half a frame), if any.
    pub fn key_index_at(&self, time: f64) -> Option<usize> {
        let half = 0.5 / self.fps();
        self.keys()
            .iter()
            .position(|k| (k.time - time).abs() < half)
    }

    /// Holds (or stops holding) the key at the timeline's time until the next.
    pub fn set_hold(&mut self, hold: bool) {
        if let Some(index) = self.key_index_at(self.timeline.time) {
            self.change_animation(|a| a.keys[index].hold = hold);
            self.show_current_time();
        }
    }

    /// Copies the pose shown, for pasting as a key at another time.
    pub fn copy_pose(&mut self) {
        if let Some(doc) = &self.doc {
            self.timeline.clipboard = Some(Pose::of(doc.project()));
            self.info("pose copied: move to another time and Paste key");
        }
    }

    /// Keys the copied pose at the timeline's time (one undo step).
    pub fn paste_key(&mut self) {
        let Some(pose) = self.timeline.clipboard.clone() else {
            self.info("copy a pose first");
            return;
        };
        let time = snap(self.timeline.time, self.fps());
        let Some(doc) = &mut self.doc else { return };
        if pose.handles.len() != doc.project().handles.len() {
            self.info("the copied pose is for other handles: copy again");
            return;
        }
        let before = doc.snapshot();
        if let Err(e) = doc.show_pose(&pose) {
            self.error(&e);
            return;
        }
        let animation = doc.keyed_at(time);
        let result = doc.apply(Edit::Animation(Some(Box::new(animation))));
        self.finish_pose_edit(before, result.map(|()| "pasted"));
    }

    /// The rate of playback and export (one undo step).
    pub fn set_fps(&mut self, fps: f64) {
        if self.change_animation(|a| a.fps = fps) {
            self.set_time(self.timeline.time);
        }
    }

    /// Linear or smooth interpolation between keys (one undo step).
    pub fn set_interpolation(&mut self, interpolation: Interpolation) {
        if self.change_animation(|a| a.interpolation = interpolation) {
            self.show_current_time();
        }
    }

    /// Moves key `index` to `time` (snapped to a frame) while its drag lasts: no undo
    /// step until [`EditorApp::end_key_drag`]. Refused onto another key's frame.
    pub fn drag_key(&mut self, index: usize, time: f64) {
        let time = snap(time, self.fps());
        let Some(doc) = &mut self.doc else { return };
        let Some(animation) = &doc.project().animation else {
            return;
        };
        let Some(key) = animation.keys.get(index) else {
            return;
        };
        if key.time == time || animation.keys.iter().any(|k| k.time == time) {
            return;
        }
        if self.timeline.key_drag.is_none() {
            self.timeline.key_drag = Some((index, doc.snapshot()));
        }
        let mut animation = animation.clone();
        let mut key = animation.keys.remove(index);
        key.time = time;
        let at = animation.keys.partition_point(|k| k.time < time);
        animation.keys.insert(at, key);
        let mut project = doc.project().clone();
        project.animation = Some(animation);
        match doc.restore(project) {
            Ok(()) => {
                self.timeline.time = time;
                self.timeline.key_drag = self.timeline.key_drag.take().map(|(_, b)| (at, b));
                self.show_current_time();
            }
            Err(e) => self.error(&e),
        }
    }

    /// Ends a key's drag along the strip: one undo step.
    pub fn end_key_drag(&mut self) {
        if let Some((_, before)) = self.timeline.key_drag.take() {
            Host::record(self, before);
        }
    }

    /// After a pose change at the timeline's time (an edit, or a drag's end, from
    /// `before`): with keys, the pose is keyed there, in the same undo step. A take
    /// under way keys its own frames; with *Record* merely armed, a pose changed
    /// otherwise than by a take's drag (*Reset pose*, a pasted pose) is keyed as
    /// always, or the keys would show another pose at that time.
    pub(crate) fn autokey(&mut self, before: &project::Project) {
        if self.timeline.is_taking() || self.tool == Tool::Perform {
            return;
        }
        let time = snap(self.timeline.time, self.fps());
        let Some(doc) = &mut self.doc else { return };
        if doc.keys().is_empty() || Pose::of(before).same_controls(&Pose::of(doc.project())) {
            return;
        }
        let animation = doc.keyed_at(time);
        if doc.project().animation.as_ref() == Some(&animation) {
            return;
        }
        let (before_keys, count) = (doc.keys().len(), animation.keys.len());
        if let Err(e) = doc.apply(Edit::Animation(Some(Box::new(animation)))) {
            self.error(&e.context("cannot key the pose"));
        } else {
            // Keyed at the frame (playback may have left the time between two): the
            // keys' pose there is what shows.
            let snapped = self.timeline.time != time;
            self.timeline.time = time;
            if snapped {
                self.show_current_time();
            }
            let keys = if count == 1 { "key" } else { "keys" };
            self.info(if count > before_keys {
                format!("key set at {time:.2} s ({count} {keys})")
            } else {
                format!("key at {time:.2} s changed ({count} {keys})")
            });
        }
    }

    /// Ends an action that changed the document from `before` as one undo step named
    /// `label` (else by what changed), keying the pose it left when keys exist. Every
    /// action replaces the message: one that says nothing clears the last.
    pub(crate) fn record_step(&mut self, before: project::Project, label: Option<String>) {
        self.message = None;
        // With keys, the pose the action left is keyed at the time shown (this step).
        self.autokey(&before);
        if let Some(doc) = &self.doc
            && doc.project() != &without_virtuals(&before)
        {
            let label =
                label.unwrap_or_else(|| crate::history::describe_change(&before, doc.project()));
            self.history.push(before, label);
            self.dirty = true;
        }
    }

    /// Ends a pose change made on the document directly (`result`: what it was, or why
    /// it failed), as one undo step from `before`.
    fn finish_pose_edit(&mut self, before: project::Project, result: Result<&str>) {
        match result {
            Ok(what) => {
                Host::record(self, before);
                self.info(format!("key {what} at {:.2} s", self.timeline.time));
            }
            Err(e) => {
                if let Some(doc) = &mut self.doc
                    && let Err(undo) = doc.restore(without_virtuals(&before))
                {
                    self.error(&undo);
                }
                self.error(&e);
            }
        }
    }

    /// Arms recording (the next live drag becomes keys) or disarms it.
    pub fn toggle_record(&mut self) {
        self.timeline.record = match self.timeline.record {
            Record::Off => {
                self.timeline.playing = None;
                self.info(
                    "recording: drag a handle, cage vertices or the control cursor (Perform); \
                     every frame of the drag becomes the animation from the current time",
                );
                Record::Armed
            }
            _ => Record::Off,
        };
    }

    /// A live drag previewed a pose: with recording armed, a take starts.
    pub(crate) fn start_take(&mut self) {
        if !matches!(self.timeline.record, Record::Armed) {
            return;
        }
        let Some(doc) = &self.doc else { return };
        let from = snap(self.timeline.time, self.fps());
        // The take starts when the button went down, at the pose before the drag (the
        // drag is recognised a few points of movement later).
        let before = doc.snapshot();
        let clock = self.timeline.clock;
        let started = self
            .timeline
            .pressed_at
            .filter(|&t| t <= clock)
            .unwrap_or(clock);
        let first = Pose::of(&before);
        self.timeline.record = Record::Taking(Box::new(Take {
            started,
            from,
            samples: vec![(0.0, first)],
            before,
        }));
    }

    /// Adds the pose shown now to the take, timed by the input's clock (the pointer's
    /// time this frame), and moves the time shown along.
    pub(crate) fn sample_take(&mut self) {
        let clock = self.timeline.clock;
        let Some(doc) = &self.doc else { return };
        let Record::Taking(take) = &mut self.timeline.record else {
            return;
        };
        let since = (clock - take.started).max(0.0);
        let pose = Pose::of(doc.project());
        match take.samples.last_mut() {
            // The same instant (several changes in one frame): the latest pose.
            Some((t, last)) if *t >= since => *last = pose,
            _ => take.samples.push((since, pose)),
        }
        self.timeline.time = take.from + since;
    }

    /// The live drag of a take ended: its frames become keys from the take's start
    /// (simplified within the tolerance, or one a frame), replacing the keys they
    /// cover, as one undo step with the drag. Returns whether a take ended.
    pub(crate) fn end_take(&mut self) -> bool {
        self.sample_take();
        let Record::Taking(take) = std::mem::take(&mut self.timeline.record) else {
            return false;
        };
        let fps = self.fps();
        let Some(doc) = &mut self.doc else {
            return true;
        };
        let tolerance = if self.timeline.keep_every_frame {
            0.0
        } else {
            self.timeline.tolerance
        };
        let mut frames = animation::resample(doc.project(), &take.samples, fps);
        // The take ends on the pose shown when it ended (the release can come a little
        // after the last frame's time): what the keys show there is what is on screen.
        if let Some(last) = frames.last_mut() {
            *last = Pose::of(doc.project());
        }
        let taken = animation::simplify(doc.project(), &frames, take.from, fps, tolerance);
        let to = take.from + (frames.len() - 1) as f64 / fps;
        let mut animation = doc.project().animation.clone().unwrap_or_default();
        animation
            .keys
            .retain(|k| k.time < take.from - 1e-9 || k.time > to + 1e-9);
        let count = taken.len();
        animation.keys.extend(taken);
        animation.keys.sort_by(|a, b| a.time.total_cmp(&b.time));
        let result = doc.apply(Edit::Animation(Some(Box::new(animation))));
        self.timeline.time = to;
        let frames = frames.len();
        match result {
            Ok(()) => {
                let label = format!(
                    "a recorded take: {count} key{}",
                    if count == 1 { "" } else { "s" }
                );
                self.record_step(take.before, Some(label));
                self.info(format!(
                    "recorded {frames} frames ({:.2} s) as {count} keys",
                    (frames - 1) as f64 / fps
                ));
            }
            Err(e) => self.error(&e.context("cannot keep the take")),
        }
        true
    }

    /// The timeline's part of [`EditorApp::sanity_check`]: a finite time, and with keys
    /// the pose shown is theirs at that time whenever nothing previews another (no
    /// playback between frames, take, drag of handles or cage vertices, perform tool or
    /// job).
    pub(crate) fn timeline_sanity_check(&self, doc: &Document) -> Result<()> {
        let time = self.timeline.time;
        if !(time.is_finite() && time >= 0.0) {
            anyhow::bail!("the timeline's time is {time}");
        }
        let previewing = self.timeline.is_playing()
            || self.timeline.is_taking()
            || self.timeline.key_drag.is_some()
            || self.handles.dragging()
            || self.cage.gesture_under_way()
            || self.perform.dragging()
            || self.tool == Tool::Perform
            || self.is_busy();
        if previewing {
            return Ok(());
        }
        if let Some(pose) = animation::pose_at(doc.project(), time) {
            let shown = Pose::of(doc.project());
            if let Some(i) =
                (0..pose.handles.len()).find(|&i| pose.handles.get(i) != shown.handles.get(i))
            {
                anyhow::bail!(
                    "handle {i} shows {:?}, but the keys' pose at {time} s is {:?}",
                    shown.handles.get(i),
                    pose.handles[i]
                );
            }
            // (The overlaps' orders follow from the pose and the drag that led to it.)
            if pose.cage != shown.cage {
                anyhow::bail!(
                    "the cage shows {:?}, but the keys' pose at {time} s has {:?}",
                    shown.cage,
                    pose.cage
                );
            }
        }
        Ok(())
    }
}
