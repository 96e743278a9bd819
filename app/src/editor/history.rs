//! Undo/redo over whole materials.
//!
//! The editor mutates the material freely during a frame; at the end of each frame it calls
//! [`History::settle`]. A change becomes one undo step once the user lets go (no drag in
//! progress), so a slider drag or a stop drag is a single step however many frames it spans.

use lodestone_core::material::Material;

/// Most undo steps kept.
const MAX_STEPS: usize = 256;

/// Undo and redo stacks of materials.
#[derive(Debug, Clone)]
pub struct History {
    /// The state the last settled step left.
    committed: Material,
    undo: Vec<Material>,
    redo: Vec<Material>,
}

impl History {
    /// A history whose current state is `m`.
    pub fn new(m: &Material) -> Self {
        Self {
            committed: m.clone(),
            undo: Vec::new(),
            redo: Vec::new(),
        }
    }

    /// Record `current` as a step if it differs from the last settled state and the user is not
    /// in the middle of an interaction. Returns whether a step was recorded.
    pub fn settle(&mut self, current: &Material, interacting: bool) -> bool {
        if interacting || *current == self.committed {
            return false;
        }
        let prev = std::mem::replace(&mut self.committed, current.clone());
        self.undo.push(prev);
        if self.undo.len() > MAX_STEPS {
            self.undo.remove(0);
        }
        self.redo.clear();
        true
    }

    /// Replace everything (a preset was opened): no steps to undo into another file.
    pub fn reset(&mut self, m: &Material) {
        *self = Self::new(m);
    }

    /// Undo into `current`. An unsettled edit is first settled, so it can be redone.
    pub fn undo(&mut self, current: &mut Material) -> bool {
        self.settle(current, false);
        match self.undo.pop() {
            Some(prev) => {
                self.redo
                    .push(std::mem::replace(&mut self.committed, prev.clone()));
                *current = prev;
                true
            }
            None => false,
        }
    }

    /// Redo into `current`.
    pub fn redo(&mut self, current: &mut Material) -> bool {
        if *current != self.committed {
            // A fresh edit since the undo: it replaced the redo branch.
            self.settle(current, false);
            return false;
        }
        match self.redo.pop() {
            Some(next) => {
                self.undo
                    .push(std::mem::replace(&mut self.committed, next.clone()));
                *current = next;
                true
            }
            None => false,
        }
    }

    /// Whether [`History::undo`] would change anything.
    pub fn can_undo(&self, current: &Material) -> bool {
        !self.undo.is_empty() || *current != self.committed
    }

    /// Whether [`History::redo`] would change anything.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_sigma(s: f64) -> Material {
        let mut m = Material::default();
        m.heights.sigma_h = s;
        m
    }

    #[test]
    fn a_drag_is_one_step_and_undo_redo_walk_it() {
        let mut m = with_sigma(0.1);
        let mut h = History::new(&m);
        for s in [0.11, 0.12, 0.13] {
            m.heights.sigma_h = s;
            assert!(!h.settle(&m, true), "no step while dragging");
        }
        assert!(h.settle(&m, false));
        m.heights.sigma_h = 0.2;
        assert!(h.settle(&m, false));
        assert!(h.undo(&mut m));
        assert_eq!(m.heights.sigma_h, 0.13);
        assert!(h.undo(&mut m));
        assert_eq!(m.heights.sigma_h, 0.1);
        assert!(!h.undo(&mut m));
        assert!(h.redo(&mut m));
        assert!(h.redo(&mut m));
        assert_eq!(m.heights.sigma_h, 0.2);
        assert!(!h.redo(&mut m));
    }

    #[test]
    fn an_unsettled_edit_undoes_and_redoes() {
        let mut m = with_sigma(0.1);
        let mut h = History::new(&m);
        m.heights.sigma_h = 0.3;
        assert!(h.can_undo(&m));
        assert!(h.undo(&mut m));
        assert_eq!(m.heights.sigma_h, 0.1);
        assert!(h.redo(&mut m));
        assert_eq!(m.heights.sigma_h, 0.3);
    }

    #[test]
    fn a_new_edit_drops_the_redo_branch() {
        let mut m = with_sigma(0.1);
        let mut h = History::new(&m);
        m.heights.sigma_h = 0.2;
        h.settle(&m, false);
        h.undo(&mut m);
        m.heights.sigma_h = 0.5;
        assert!(!h.redo(&mut m));
        assert_eq!(m.heights.sigma_h, 0.5);
        assert!(!h.can_redo());
        assert!(h.undo(&mut m));
        assert_eq!(m.heights.sigma_h, 0.1);
    }
}
