//! Undo and redo over whole rig files: a rig file is a few hundred bytes per handle,
//! so a snapshot per step is simpler and safer than inverse commands.

use project::{HandleSpec, Project};

/// Steps kept before the oldest is forgotten.
const LIMIT: usize = 500;

/// A state to go back (or forward) to, and what the step between it and the state
/// after it did, in a few words ("a recorded take: 38 keys", "the pose of handle 2").
pub type Step = (Project, String);

/// The undo and redo stacks.
#[derive(Default)]
pub struct History {
    undo: Vec<Step>,
    redo: Vec<Step>,
}

impl History {
    /// Records `before`, the state an edit is about to leave, with what the edit does
    /// (`label`); clears the redo stack.
    pub fn push(&mut self, before: Project, label: String) {
        if self.undo.last().is_some_and(|(last, _)| *last == before) {
            return;
        }
        self.undo.push((before, label));
        if self.undo.len() > LIMIT {
            self.undo.remove(0);
        }
        self.redo.clear();
    }

    /// The state to go back to from `current`, which becomes redoable, and what the
    /// step undone did.
    pub fn undo(&mut self, current: Project) -> Option<Step> {
        let (previous, label) = self.undo.pop()?;
        self.redo.push((current, label.clone()));
        Some((previous, label))
    }

    /// The state to go forward to from `current`, which becomes undoable, and what the
    /// step redone does.
    pub fn redo(&mut self, current: Project) -> Option<Step> {
        let (next, label) = self.redo.pop()?;
        self.undo.push((current, label.clone()));
        Some((next, label))
    }

    /// The state [`History::undo`] (`back`) or [`History::redo`] would go to, without
    /// going there.
    pub fn peek(&self, back: bool) -> Option<&Project> {
        if back {
            self.undo.last().map(|(p, _)| p)
        } else {
            self.redo.last().map(|(p, _)| p)
        }
    }

    /// Puts back a state taken by [`History::undo`] or [`History::redo`] that could not
    /// be applied, so neither stack loses it.
    pub fn unpop(&mut self, undone: bool, taken: Step) {
        if undone {
            self.redo.pop();
            self.undo.push(taken);
        } else {
            self.undo.pop();
            self.redo.push(taken);
        }
    }

    /// The number of steps to undo and to redo.
    pub fn len(&self) -> (usize, usize) {
        (self.undo.len(), self.redo.len())
    }

    /// Whether there is something to undo.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is something to redo.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Forgets everything (a new document).
    pub fn clear(&mut self) {
        self.undo.clear();
        self.redo.clear();
    }
}

/// What changed from `from` to `to`, in a few words for the status line ("a handle
/// added", "the method: ARAP", "the pose of handle 2"…).
pub fn describe_change(from: &Project, to: &Project) -> String {
    let rest = |h: &HandleSpec| match h {
        HandleSpec::Point { rest, .. } => vec![rest[0], rest[1]],
        HandleSpec::Bar { rest, .. } => vec![rest[0][0], rest[0][1], rest[1][0], rest[1][1]],
    };
    let mut parts: Vec<String> = Vec::new();
    if from.method != to.method {
        parts.push(format!("the method: {}", to.method.label()));
    }
    let (a, b) = (from.handles.len(), to.handles.len());
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    if b > a {
        parts.push(format!("{} handle{} added", b - a, plural(b - a)));
    } else if a > b {
        parts.push(format!("{} handle{} removed", a - b, plural(a - b)));
    } else if from
        .handles
        .iter()
        .map(rest)
        .ne(to.handles.iter().map(rest))
    {
        parts.push("the handles".to_owned());
    } else {
        let posed: Vec<usize> = from
            .handles
            .iter()
            .zip(&to.handles)
            .enumerate()
            .filter(|(_, (x, y))| x != y)
            .map(|(i, _)| i + 1)
            .collect();
        match posed.as_slice() {
            [] => {}
            [one] => parts.push(format!("the pose of handle {one}")),
            _ => parts.push(format!("the pose of {} handles", posed.len())),
        }
    }
    if from.density != to.density {
        parts.push(format!(
            "the mesh density ({})",
            to.density.map_or("default".to_owned(), |d| d.to_string())
        ));
    }
    if (
        from.alpha,
        from.degree,
        from.middle,
        from.fixed_boundary,
        from.metric,
        from.placement,
    ) != (
        to.alpha,
        to.degree,
        to.middle,
        to.fixed_boundary,
        to.metric,
        to.placement,
    ) {
        parts.push("the weights' settings".to_owned());
    }
    if from.rigidity != to.rigidity {
        parts.push("the painted rigidity".to_owned());
    }
    if from.cuts != to.cuts {
        let (a, b) = (from.cuts.len(), to.cuts.len());
        parts.push(match b.cmp(&a) {
            std::cmp::Ordering::Greater => "a cut".to_owned(),
            std::cmp::Ordering::Less => "a cut removed".to_owned(),
            std::cmp::Ordering::Equal => "the cuts".to_owned(),
        });
    }
    match (&from.cage, &to.cage) {
        (None, Some(_)) => parts.push("a cage".to_owned()),
        (Some(_), None) => parts.push("the cage removed".to_owned()),
        (Some(x), Some(y)) if x.rest != y.rest => parts.push("the cage".to_owned()),
        (Some(x), Some(y)) if x.pose != y.pose => parts.push("the cage's pose".to_owned()),
        _ => {}
    }
    if from.lbc != to.lbc {
        parts.push("the cage's settings".to_owned());
    }
    if from.canvas != to.canvas {
        parts.push("the export canvas".to_owned());
    }
    if from.auto_depth != to.auto_depth {
        parts.push(format!(
            "automatic depth {}",
            if to.auto_depth { "on" } else { "off" }
        ));
    }
    if from.arap != to.arap {
        parts.push("ARAP's settings".to_owned());
    }
    if from.mls != to.mls {
        parts.push("MLS's settings".to_owned());
    }
    let empty = project::Animation::default();
    let (x, y) = (
        from.animation.as_ref().unwrap_or(&empty),
        to.animation.as_ref().unwrap_or(&empty),
    );
    if x.keys != y.keys {
        parts.push(match (x.keys.len(), y.keys.len()) {
            (a, b) if b > a => "a key set".to_owned(),
            (a, b) if b < a => "a key deleted".to_owned(),
            _ => "the keys".to_owned(),
        });
    }
    if x.spatial_keys != y.spatial_keys {
        parts.push("the pose markers".to_owned());
    }
    if (x.fps, x.interpolation) != (y.fps, y.interpolation) {
        parts.push("the animation's settings".to_owned());
    }
    if parts.is_empty() {
        "nothing visible".to_owned()
    } else {
        parts.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(alpha: f64) -> Project {
        Project {
            alpha,
            ..Project::default()
        }
    }

    #[test]
    fn undo_and_redo_walk_the_states_and_name_the_steps() {
        let mut h = History::default();
        let step = |a: f64, label: &str| (state(a), label.to_owned());
        h.push(state(0.1), "first".into());
        h.push(state(0.2), "second".into());
        assert_eq!(h.peek(true), Some(&state(0.2)));
        assert_eq!(h.peek(false), None);
        assert_eq!(h.undo(state(0.3)), Some(step(0.2, "second")));
        assert_eq!(h.peek(false), Some(&state(0.3)));
        assert_eq!(h.undo(state(0.2)), Some(step(0.1, "first")));
        assert_eq!(h.undo(state(0.1)), None);
        // Redo names the same step the undo did.
        assert_eq!(h.redo(state(0.1)), Some(step(0.2, "first")));
        assert_eq!(h.redo(state(0.2)), Some(step(0.3, "second")));
        assert!(!h.can_redo());
        assert_eq!(h.undo(state(0.3)), Some(step(0.2, "second")));
        h.push(state(0.2), "again".into());
        assert!(!h.can_redo(), "a new edit drops the redo stack");
    }

    #[test]
    fn a_failed_undo_is_put_back() {
        let mut h = History::default();
        h.push(state(0.1), "a step".into());
        let taken = h.undo(state(0.2)).expect("a step");
        h.unpop(true, taken);
        assert!(h.can_undo() && !h.can_redo());
        assert_eq!(h.undo(state(0.2)), Some((state(0.1), "a step".to_owned())));
    }
}
