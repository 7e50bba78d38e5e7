//! What the app is telling the user (the `messages` field of `LoudscapeApp`): errors, warnings
//! and confirmations, kept here and drawn in one place, the status area under the 3D view
//! (`ui/messages.rs`), which stays in sight whatever the side panel's scroll. Progress of loads
//! and blocking work is drawn there too, from the loads themselves.
//!
//! Any code of the window says something with [`Messages::error`], [`Messages::warn`] or
//! [`Messages::info`]: a line already shown is not repeated, errors and warnings are also
//! written to stderr (a log for scripts and tests), and confirmations fade after a while.

use std::time::{Duration, Instant};

/// How long a confirmation (`info`) stays before it fades; errors and warnings stay until
/// dismissed.
pub(in crate::ui) const INFO_SHOWN_FOR: Duration = Duration::from_secs(12);
/// The most lines kept: the oldest go first.
const MOST: usize = 12;

/// How serious a message is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum Kind {
    Error,
    Warning,
    Info,
}

/// One line the app tells the user.
#[derive(Clone, Debug, PartialEq)]
pub(in crate::ui) struct Message {
    pub(in crate::ui) kind: Kind,
    pub(in crate::ui) text: String,
    pub(in crate::ui) at: Instant,
}

/// The lines the status area shows, oldest first.
#[derive(Default)]
pub(in crate::ui) struct Messages {
    lines: Vec<Message>,
    /// Write errors and warnings to stderr as well (off in unit tests).
    quiet: bool,
}

impl Messages {
    /// Messages that are not written to stderr (unit tests).
    #[cfg(test)]
    pub(in crate::ui) fn quiet() -> Self {
        Self {
            lines: Vec::new(),
            quiet: true,
        }
    }

    /// Something failed (a file that cannot be opened, a save that failed).
    pub(in crate::ui) fn error(&mut self, text: impl Into<String>) {
        self.push(Kind::Error, text.into());
    }

    /// Something the user should know that did not stop the work (a cloud's `warnings`, no
    /// dialog can open here).
    pub(in crate::ui) fn warn(&mut self, text: impl Into<String>) {
        self.push(Kind::Warning, text.into());
    }

    /// A confirmation (where a screenshot went); it fades after [`INFO_SHOWN_FOR`].
    pub(in crate::ui) fn info(&mut self, text: impl Into<String>) {
        self.push(Kind::Info, text.into());
    }

    fn push(&mut self, kind: Kind, text: String) {
        let text = text.trim().to_string();
        if text.is_empty() {
            return;
        }
        // A line already shown is not repeated; a confirmation again (a second save to the
        // same file) moves to the end, fresh.
        let same = |m: &Message| m.kind == kind && m.text == text;
        if kind != Kind::Info && self.lines.iter().any(same) {
            return;
        }
        let before = self.lines.len();
        self.lines.retain(|m| !same(m));
        let repeated = self.lines.len() != before;
        if !self.quiet && !repeated {
            match kind {
                Kind::Error => eprintln!("loudscape: error: {text}"),
                Kind::Warning => eprintln!("loudscape: warning: {text}"),
                Kind::Info => eprintln!("loudscape: {text}"),
            }
        }
        self.lines.push(Message {
            kind,
            text,
            at: Instant::now(),
        });
        if self.lines.len() > MOST {
            self.lines.remove(0);
        }
    }

    /// The lines shown at `now`, oldest first (faded confirmations left out).
    pub(in crate::ui) fn shown(&self, now: Instant) -> impl Iterator<Item = (usize, &Message)> {
        self.lines
            .iter()
            .enumerate()
            .filter(move |(_, m)| m.kind != Kind::Info || now - m.at < INFO_SHOWN_FOR)
    }

    /// When the next confirmation fades (to draw the window again then).
    pub(in crate::ui) fn next_fade(&self, now: Instant) -> Option<Duration> {
        self.lines
            .iter()
            .filter(|m| m.kind == Kind::Info)
            .map(|m| (m.at + INFO_SHOWN_FOR).saturating_duration_since(now))
            .filter(|d| !d.is_zero())
            .min()
    }

    /// Removes line `index` (its × button).
    pub(in crate::ui) fn dismiss(&mut self, index: usize) {
        if index < self.lines.len() {
            self.lines.remove(index);
        }
    }

    /// Removes every line.
    pub(in crate::ui) fn clear(&mut self) {
        self.lines.clear();
    }

    /// Whether an error is shown (a scripted screenshot run takes its picture then).
    pub(in crate::ui) fn has_errors(&self) -> bool {
        self.lines.iter().any(|m| m.kind == Kind::Error)
    }

    /// Whether `text` is shown with `kind`.
    #[cfg(test)]
    pub(in crate::ui) fn contains(&self, kind: Kind, text: &str) -> bool {
        self.lines.iter().any(|m| m.kind == kind && m.text == text)
    }

    /// Whether nothing at all is kept.
    #[cfg(test)]
    pub(in crate::ui) fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_kept_once_in_order_and_infos_fade() {
        let mut m = Messages::quiet();
        m.error("a.ogg: not audio");
        m.info("saved /tmp/x.png (10×10)");
        m.warn("a.ogg: truncated");
        m.error("a.ogg: not audio");
        m.info("saved /tmp/x.png (10×10)");
        let now = Instant::now();
        let texts: Vec<_> = m.shown(now).map(|(_, l)| l.text.clone()).collect();
        assert_eq!(
            texts,
            [
                "a.ogg: not audio",
                "a.ogg: truncated",
                "saved /tmp/x.png (10×10)",
            ],
            "a repeated line is shown once; a confirmation again moves to the end"
        );
        assert!(m.has_errors());
        assert!(m.contains(Kind::Warning, "a.ogg: truncated"));
        assert!(m.next_fade(now).is_some_and(|d| d <= INFO_SHOWN_FOR));
        let later = now + INFO_SHOWN_FOR + Duration::from_secs(1);
        let kinds: Vec<_> = m.shown(later).map(|(_, l)| l.kind).collect();
        assert!(m.has_errors());
        assert_eq!(
            kinds,
            [Kind::Error, Kind::Warning],
            "the confirmation faded"
        );
        assert_eq!(m.next_fade(later), None);
    }

    #[test]
    fn dismiss_clear_and_blank_lines() {
        let mut m = Messages::quiet();
        m.warn("   ");
        assert!(m.is_empty(), "a blank line says nothing");
        m.error("one");
        m.warn("two");
        m.dismiss(0);
        assert!(!m.has_errors());
        m.dismiss(7);
        assert_eq!(m.shown(Instant::now()).count(), 1);
        m.clear();
        assert!(m.is_empty());
        for i in 0..MOST + 5 {
            m.warn(format!("w{i}"));
        }
        let first = m.shown(Instant::now()).next().unwrap().1.text.clone();
        assert_eq!(first, "w5", "the oldest go first");
    }
}
