//! Undo and redo over whole rig files: a rig file is a few hundred bytes per handle,
//! so a snapshot per step is simpler and safer than inverse commands.

use project::Project;

/// Steps kept before the oldest is forgotten.
const LIMIT: usize = 500;

/// The undo and redo stacks.
#[derive(Default)]
pub struct History {
    undo: Vec<Project>,
    redo: Vec<Project>,
}

impl History {
    /// Records `before`, the state an edit is about to leave; clears the redo stack.
    pub fn push(&mut self, before: Project) {
        if self.undo.last() == Some(&before) {
            return;
        }
        self.undo.push(before);
        if self.undo.len() > LIMIT {
            self.undo.remove(0);
        }
        self.redo.clear();
    }

    /// The state to go back to from `current`, which becomes redoable.
    pub fn undo(&mut self, current: Project) -> Option<Project> {
        let previous = self.undo.pop()?;
        self.redo.push(current);
        Some(previous)
    }

    /// The state to go forward to from `current`, which becomes undoable.
    pub fn redo(&mut self, current: Project) -> Option<Project> {
        let next = self.redo.pop()?;
        self.undo.push(current);
        Some(next)
    }

    /// The state [`History::undo`] (`back`) or [`History::redo`] would go to, without
    /// going there.
    pub fn peek(&self, back: bool) -> Option<&Project> {
        if back {
            self.undo.last()
        } else {
            self.redo.last()
        }
    }

    /// Puts back a state taken by [`History::undo`] or [`History::redo`] that could not
    /// be applied, so neither stack loses it.
    pub fn unpop(&mut self, undone: bool, taken: Project) {
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
    fn undo_and_redo_walk_the_states() {
        let mut h = History::default();
        h.push(state(0.1));
        h.push(state(0.2));
        assert_eq!(h.peek(true), Some(&state(0.2)));
        assert_eq!(h.peek(false), None);
        assert_eq!(h.undo(state(0.3)), Some(state(0.2)));
        assert_eq!(h.peek(false), Some(&state(0.3)));
        assert_eq!(h.undo(state(0.2)), Some(state(0.1)));
        assert_eq!(h.undo(state(0.1)), None);
        assert_eq!(h.redo(state(0.1)), Some(state(0.2)));
        assert_eq!(h.redo(state(0.2)), Some(state(0.3)));
        assert!(!h.can_redo());
        h.undo(state(0.3));
        h.push(state(0.2));
        assert!(!h.can_redo(), "a new edit drops the redo stack");
    }

    #[test]
    fn a_failed_undo_is_put_back() {
        let mut h = History::default();
        h.push(state(0.1));
        let taken = h.undo(state(0.2)).expect("a step");
        h.unpop(true, taken);
        assert!(h.can_undo() && !h.can_redo());
        assert_eq!(h.undo(state(0.2)), Some(state(0.1)));
    }
}
