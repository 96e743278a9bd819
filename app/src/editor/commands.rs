//! Every editor command in one closed set, with its keyboard shortcut: the menu shows the shortcut
//! (formatted by egui for the platform) and the key handler consumes the same constant, so the two
//! cannot disagree.

use super::EditorApp;
use super::view_state::{AbSwipe, Mode, Sweep};
use egui::{Key, KeyboardShortcut, Modifiers};

/// An editor command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// Start a new material from the default (asks first when there are unsaved changes).
    New,
    /// Open a preset by file dialog.
    Open,
    /// Save to the current file (or ask where).
    Save,
    /// Save to a new file.
    SaveAs,
    /// Undo one edit.
    Undo,
    /// Redo one edit.
    Redo,
    /// Show or hide the error heat maps against ground truth.
    ToggleErrorMaps,
    /// Switch the baseline between naive MIP and view-independent filtering.
    ToggleBaseline,
    /// Start or stop the zoom sweep.
    ToggleSweep,
    /// Show or hide the A/B swipe view.
    ToggleAbSwipe,
}

/// Ctrl (Cmd on macOS) + key.
const fn command(key: Key) -> KeyboardShortcut {
    KeyboardShortcut::new(Modifiers::COMMAND, key)
}

/// Ctrl+Shift + key.
const fn command_shift(key: Key) -> KeyboardShortcut {
    KeyboardShortcut::new(
        Modifiers {
            alt: false,
            ctrl: false,
            shift: true,
            mac_cmd: false,
            command: true,
        },
        key,
    )
}

/// A plain key (only when no text field has the keyboard).
const fn plain(key: Key) -> KeyboardShortcut {
    KeyboardShortcut::new(Modifiers::NONE, key)
}

/// Ctrl+N.
pub const NEW: KeyboardShortcut = command(Key::N);
/// Ctrl+O.
pub const OPEN: KeyboardShortcut = command(Key::O);
/// Ctrl+S.
pub const SAVE: KeyboardShortcut = command(Key::S);
/// Ctrl+Shift+S.
pub const SAVE_AS: KeyboardShortcut = command_shift(Key::S);
/// Ctrl+Z.
pub const UNDO: KeyboardShortcut = command(Key::Z);
/// Ctrl+Shift+Z.
pub const REDO: KeyboardShortcut = command_shift(Key::Z);
/// Ctrl+Y, the other redo.
pub const REDO_ALT: KeyboardShortcut = command(Key::Y);
/// E.
pub const ERROR_MAPS: KeyboardShortcut = plain(Key::E);
/// B.
pub const BASELINE: KeyboardShortcut = plain(Key::B);
/// W.
pub const SWEEP: KeyboardShortcut = plain(Key::W);
/// A.
pub const AB_SWIPE: KeyboardShortcut = plain(Key::A);

impl Command {
    /// Every command, in the order shortcuts are matched: the Shift variants before the plain
    /// ones (Ctrl+Shift+S is Save as, not Save).
    pub const ALL: [Self; 10] = [
        Self::SaveAs,
        Self::Save,
        Self::Open,
        Self::New,
        Self::Redo,
        Self::Undo,
        Self::ToggleErrorMaps,
        Self::ToggleBaseline,
        Self::ToggleSweep,
        Self::ToggleAbSwipe,
    ];

    /// The shortcuts that run the command (the first is the one the menu shows).
    pub fn shortcuts(self) -> &'static [KeyboardShortcut] {
        match self {
            Self::New => &[NEW],
            Self::Open => &[OPEN],
            Self::Save => &[SAVE],
            Self::SaveAs => &[SAVE_AS],
            Self::Undo => &[UNDO],
            Self::Redo => &[REDO, REDO_ALT],
            Self::ToggleErrorMaps => &[ERROR_MAPS],
            Self::ToggleBaseline => &[BASELINE],
            Self::ToggleSweep => &[SWEEP],
            Self::ToggleAbSwipe => &[AB_SWIPE],
        }
    }

    /// Whether the shortcut is a plain key, which must not fire while a text field is focused.
    fn is_plain_key(self) -> bool {
        self.shortcuts()[0].modifiers.is_none()
    }

    /// The menu's text for the shortcut, formatted by egui for this platform ("Ctrl+S", "⌘S").
    pub fn shortcut_text(self, ctx: &egui::Context) -> String {
        ctx.format_shortcut(&self.shortcuts()[0])
    }
}

impl EditorApp {
    /// Run a command.
    pub(super) fn run(&mut self, ctx: &egui::Context, command: Command) {
        match command {
            Command::New => {
                if self.doc.dirty() {
                    self.pending = Some(super::Pending::New);
                } else {
                    self.new_material();
                }
            }
            Command::Open => self.open_dialog(ctx),
            Command::Save => {
                self.save(ctx);
            }
            Command::SaveAs => {
                self.save_as(ctx);
            }
            Command::Undo => {
                self.doc.undo();
            }
            Command::Redo => {
                self.doc.redo();
            }
            Command::ToggleErrorMaps => self.view.show_error = !self.view.show_error,
            Command::ToggleBaseline => self.toggle_baseline(),
            Command::ToggleSweep => self.toggle_sweep(ctx),
            Command::ToggleAbSwipe => self.toggle_ab(),
        }
    }

    /// The keyboard: the first command whose shortcut was pressed this frame runs (plain keys only
    /// when no text field wants the keyboard).
    pub(super) fn shortcuts(&mut self, ctx: &egui::Context) {
        let typing = ctx.egui_wants_keyboard_input();
        let pressed = Command::ALL.into_iter().find(|c| {
            (!c.is_plain_key() || !typing)
                && c.shortcuts()
                    .iter()
                    .any(|s| ctx.input_mut(|i| i.consume_shortcut(s)))
        });
        if let Some(c) = pressed {
            self.run(ctx, c);
        }
    }

    pub(super) fn toggle_baseline(&mut self) {
        self.view.baseline = match self.view.baseline {
            Mode::Naive => Mode::ViewIndependent,
            _ => Mode::Naive,
        };
    }

    pub(super) fn toggle_ab(&mut self) {
        self.view.ab = match self.view.ab {
            Some(_) => None,
            None => Some(AbSwipe {
                left: self.view.baseline,
                right: Mode::Filtered,
                split: 0.5,
            }),
        };
    }

    pub(super) fn toggle_sweep(&mut self, ctx: &egui::Context) {
        self.sweep = match self.sweep {
            Some(s) => {
                self.view.camera.distance = s.start_distance;
                None
            }
            None => Some(Sweep {
                start_distance: self.view.camera.distance,
                start_time: ctx.input(|i| i.time),
                period: 12.0,
            }),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No two commands share a shortcut, and the menu text is the platform's formatting.
    #[test]
    fn shortcuts_are_distinct() {
        let all: Vec<KeyboardShortcut> = Command::ALL
            .iter()
            .flat_map(|c| c.shortcuts().iter().copied())
            .collect();
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert_ne!(a, b);
            }
        }
        let ctx = egui::Context::default();
        assert_eq!(
            Command::SaveAs.shortcut_text(&ctx),
            ctx.format_shortcut(&SAVE_AS)
        );
        assert!(Command::Save.shortcut_text(&ctx).ends_with('S'));
    }
}
