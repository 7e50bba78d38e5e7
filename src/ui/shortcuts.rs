//! Every keyboard shortcut of the window, in one table ([`SHORTCUTS`]) that both the key
//! handling ([`pressed`]) and the `?` overlay ([`LoudscapeApp::shortcuts_overlay`]) read, so the
//! overlay cannot list a key the window does not answer, or miss one it does. Mouse gestures of
//! the 3D view are listed beside them ([`GESTURES`]) since the overlay is where a user looks.

use eframe::egui::{self, Key, Modifiers, RichText};

use crate::ui::state::LoudscapeApp;

/// What a shortcut does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Action {
    Fit,
    ResetView,
    PlayPause,
    SavePng,
    Open,
    Shortcuts,
    CloseOverlay,
    Confirm,
    Reextract,
    SwapAb,
}

/// One keyboard shortcut.
pub(super) struct Shortcut {
    pub(super) action: Action,
    pub(super) key: Key,
    /// `Modifiers::NONE`: the key alone (Shift ignored: `?` is Shift+/ on many layouts), and
    /// only while no text field has the keyboard.
    pub(super) modifiers: Modifiers,
    /// As the overlay shows it.
    pub(super) keys: &'static str,
    pub(super) what: &'static str,
}

/// Every keyboard shortcut the window answers.
pub(super) const SHORTCUTS: &[Shortcut] = &[
    Shortcut {
        action: Action::Fit,
        key: Key::F,
        modifiers: Modifiers::NONE,
        keys: "F",
        what: "fit: frame the data, keeping the viewing direction",
    },
    Shortcut {
        action: Action::ResetView,
        key: Key::R,
        modifiers: Modifiers::NONE,
        keys: "R",
        what: "reset: the default viewing direction, framed",
    },
    Shortcut {
        action: Action::PlayPause,
        key: Key::Space,
        modifiers: Modifiers::NONE,
        keys: "Space",
        what: "play / pause the song (Song mode)",
    },
    Shortcut {
        action: Action::SavePng,
        key: Key::S,
        modifiers: Modifiers::COMMAND,
        keys: "Ctrl+S (Cmd+S)",
        what: "save the 3D view as a PNG (the Screenshot field's name, else asks where)",
    },
    Shortcut {
        action: Action::Open,
        key: Key::O,
        modifiers: Modifiers::COMMAND,
        keys: "Ctrl+O (Cmd+O)",
        what: "open songs, a folder (a timeline) or a cloud",
    },
    Shortcut {
        action: Action::Reextract,
        key: Key::E,
        modifiers: Modifiers::COMMAND,
        keys: "Ctrl+E (Cmd+E)",
        what: "re-extract the song with the Extraction settings",
    },
    Shortcut {
        action: Action::SwapAb,
        key: Key::B,
        modifiers: Modifiers::NONE,
        keys: "B",
        what: "compare: listen to the next version (A, B, C...) at the same moment of the music",
    },
    Shortcut {
        action: Action::Shortcuts,
        key: Key::Questionmark,
        modifiers: Modifiers::NONE,
        keys: "?",
        what: "show or hide this list",
    },
    Shortcut {
        action: Action::CloseOverlay,
        key: Key::Escape,
        modifiers: Modifiers::NONE,
        keys: "Esc",
        what: "close this list",
    },
    Shortcut {
        action: Action::Confirm,
        key: Key::Enter,
        modifiers: Modifiers::NONE,
        keys: "Enter",
        what: "in the years dialog: build, once every song has a year",
    },
];

/// The 3D view's mouse gestures (not keys: listed, not handled, here).
pub(super) const GESTURES: &[(&str, &str)] = &[
    ("left drag", "orbit"),
    ("right or middle drag", "pan"),
    ("wheel", "zoom"),
    ("hover", "read-outs of the point under the cursor"),
    ("click", "seek the song / keep a timeline song"),
];

/// The shortcut of `action` in the table.
pub(super) fn shortcut(action: Action) -> &'static Shortcut {
    SHORTCUTS
        .iter()
        .find(|s| s.action == action)
        .expect("every action has a shortcut in SHORTCUTS")
}

/// Whether `action`'s key was pressed this frame (consumed, so it acts once). Keys without
/// Ctrl/Cmd wait while a text field has the keyboard (typing an F in the path field is not a
/// fit).
pub(super) fn pressed(ctx: &egui::Context, action: Action) -> bool {
    let shortcut = shortcut(action);
    // Enter confirms a dialog while its field has the keyboard.
    if shortcut.modifiers.is_none() && action != Action::Confirm && ctx.egui_wants_keyboard_input()
    {
        return false;
    }
    ctx.input_mut(|i| i.consume_key(shortcut.modifiers, shortcut.key))
}

/// The key event `name` (`?`, `F`, `Ctrl+S`) stands for, for the scripted `--press` of tests:
/// they go through [`pressed`] as a real key does.
pub(super) fn key_event(name: &str) -> Option<egui::Event> {
    if let Some(text) = name.strip_prefix("text:") {
        return Some(egui::Event::Text(text.to_string()));
    }
    let (modifiers, key_name) = match name.strip_prefix("Ctrl+") {
        Some(rest) => (Modifiers::COMMAND, rest),
        None => (Modifiers::NONE, name),
    };
    let key = Key::from_name(key_name)?;
    let modifiers = if key == Key::Questionmark {
        Modifiers::SHIFT
    } else {
        modifiers
    };
    Some(egui::Event::Key {
        key,
        physical_key: None,
        pressed: true,
        repeat: false,
        modifiers,
    })
}

/// Splits a frame's input events after the first Tab press: egui moves the keyboard focus at
/// the end of a frame, so what was typed after a Tab in the same frame (a slow frame, or fast
/// typing) went to the field that had the focus before it ("19962" in one year field, "0001"
/// in the next). The events after the Tab wait for the next frame, when the focus has moved.
pub(super) fn split_after_focus_move(events: &mut Vec<egui::Event>) -> Vec<egui::Event> {
    let tab = events.iter().position(|e| {
        matches!(
            e,
            egui::Event::Key {
                key: Key::Tab,
                pressed: true,
                ..
            }
        )
    });
    match tab {
        Some(i) => {
            // The Tab's release stays with it.
            let mut cut = i + 1;
            while let Some(egui::Event::Key {
                key: Key::Tab,
                pressed: false,
                ..
            }) = events.get(cut)
            {
                cut += 1;
            }
            events.split_off(cut)
        }
        None => Vec::new(),
    }
}

impl LoudscapeApp {
    /// The `?` overlay: every shortcut of [`SHORTCUTS`] and the mouse gestures.
    pub(super) fn shortcuts_overlay(&mut self, ctx: &egui::Context) {
        if pressed(ctx, Action::Shortcuts) {
            self.open.show_shortcuts = !self.open.show_shortcuts;
        }
        if self.open.show_shortcuts && pressed(ctx, Action::CloseOverlay) {
            self.open.show_shortcuts = false;
        }
        if !self.open.show_shortcuts {
            return;
        }
        let mut open = true;
        egui::Window::new("Keyboard shortcuts")
            .open(&mut open)
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ctx, |ui| {
                egui::Grid::new("shortcuts")
                    .num_columns(2)
                    .spacing([18.0, 6.0])
                    .show(ui, |ui| {
                        for shortcut in SHORTCUTS {
                            ui.label(RichText::new(shortcut.keys).monospace().strong());
                            ui.label(shortcut.what);
                            ui.end_row();
                        }
                        for (gesture, what) in GESTURES {
                            ui.label(RichText::new(*gesture).italics());
                            ui.label(*what);
                            ui.end_row();
                        }
                    });
            });
        if !open {
            self.open.show_shortcuts = false;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_action_has_one_key_and_no_key_two_actions() {
        for action in [
            Action::Fit,
            Action::ResetView,
            Action::PlayPause,
            Action::SavePng,
            Action::Open,
            Action::Shortcuts,
            Action::CloseOverlay,
            Action::Confirm,
            Action::Reextract,
        ] {
            assert_eq!(SHORTCUTS.iter().filter(|s| s.action == action).count(), 1);
        }
        for (i, a) in SHORTCUTS.iter().enumerate() {
            for b in &SHORTCUTS[i + 1..] {
                assert!(
                    a.key != b.key || a.modifiers != b.modifiers,
                    "{} and {} share a key",
                    a.keys,
                    b.keys
                );
            }
        }
    }

    #[test]
    fn scripted_presses_reach_the_table_keys() {
        let ctx = egui::Context::default();
        let mut input = egui::RawInput::default();
        input.events.push(key_event("?").unwrap());
        input.events.push(key_event("Ctrl+S").unwrap());
        let mut seen = (false, false, false);
        let mut output = ctx.run_ui(input, |ui| {
            let ctx = ui.ctx();
            seen = (
                pressed(ctx, Action::Shortcuts),
                pressed(ctx, Action::SavePng),
                pressed(ctx, Action::Fit),
            );
        });
        output.textures_delta.clear();
        assert_eq!(seen, (true, true, false));
        assert!(key_event("NoSuchKey").is_none());
    }

    #[test]
    fn typing_after_a_tab_waits_for_the_next_frame() {
        let text = |t: &str| egui::Event::Text(t.into());
        let mut events = vec![
            text("1996"),
            key_event("Tab").unwrap(),
            text("2"),
            text("001"),
            key_event("Tab").unwrap(),
            text("1987"),
        ];
        let later = split_after_focus_move(&mut events);
        assert_eq!(events.len(), 2, "up to the first Tab: {events:?}");
        assert_eq!(later.first(), Some(&text("2")));
        let mut later = later;
        let last = split_after_focus_move(&mut later);
        assert_eq!(later, [text("2"), text("001"), key_event("Tab").unwrap()]);
        assert_eq!(last, [text("1987")]);
        let mut no_tab = vec![text("12")];
        assert!(split_after_focus_move(&mut no_tab).is_empty());
        assert_eq!(no_tab.len(), 1);
    }
}
