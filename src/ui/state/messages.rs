//! What the app is telling the user (the `messages` field of `LoudscapeApp`): errors, warnings
//! and confirmations, kept here and drawn in one place, the status overlay at the bottom of the
//! 3D view (`ui/messages.rs`), which never changes the view's size. Progress of loads and
//! blocking work is drawn there too, from the loads themselves.
//!
//! Any code of the window says something with [`Messages::error`], [`Messages::warn`] or
//! [`Messages::info`]; what a cloud's file says about its input with [`Messages::warn_about`],
//! shown only while that cloud is; a line that a later one answers (an export under way, then
//! its result) with [`Messages::say`] under a topic, which replaces the topic's line. A line
//! already kept is not repeated, each error and warning is written to stderr once (a log for
//! scripts and tests; a cloud's warnings are written there by its loader), and a confirmation
//! stays until the next one replaces it.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

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
    /// The cloud file it is about (shown only while that cloud is); None: the window's own.
    pub(in crate::ui) about: Option<PathBuf>,
    /// The topic whose latest line this is ([`Messages::say`]); confirmations share one.
    topic: Option<&'static str>,
}

/// The topic of a video export: "exporting to …", then its result in its place.
pub(in crate::ui) const VIDEO_EXPORT: &str = "video export";

/// The topic of confirmations: each replaces the one before.
const CONFIRMATION: &str = "confirmation";

/// The lines the status overlay shows, oldest first.
#[derive(Default)]
pub(in crate::ui) struct Messages {
    lines: Vec<Message>,
    /// Write errors and warnings to stderr as well (off in unit tests, which read `echoed`).
    quiet: bool,
    /// What went to stderr (in unit tests: what would have), so nothing goes there twice.
    echoed: HashSet<(bool, String)>,
    /// The whole list is open (its button in the overlay); closed, the latest line and a count.
    open: bool,
}

impl Messages {
    /// Messages that are not written to stderr (unit tests).
    #[cfg(test)]
    pub(in crate::ui) fn quiet() -> Self {
        Self {
            quiet: true,
            ..Default::default()
        }
    }

    /// Something failed (a file that cannot be opened, a save that failed).
    pub(in crate::ui) fn error(&mut self, text: impl Into<String>) {
        self.push(Kind::Error, text.into(), None, None);
    }

    /// Something the user should know that did not stop the work (no dialog can open here).
    pub(in crate::ui) fn warn(&mut self, text: impl Into<String>) {
        self.push(Kind::Warning, text.into(), None, None);
    }

    /// What the cloud file `about` says about its input (its `warnings`): shown while that
    /// cloud is, not on stderr (its loader wrote it there).
    pub(in crate::ui) fn warn_about(&mut self, about: &Path, text: impl Into<String>) {
        self.push(Kind::Warning, text.into(), Some(about.to_path_buf()), None);
    }

    /// A confirmation (where a screenshot went); it stays until the next one replaces it.
    pub(in crate::ui) fn info(&mut self, text: impl Into<String>) {
        self.push(Kind::Info, text.into(), None, Some(CONFIRMATION));
    }

    /// The latest line of `topic` (an export's start, then its result), replacing the last.
    pub(in crate::ui) fn say(&mut self, topic: &'static str, kind: Kind, text: impl Into<String>) {
        self.push(kind, text.into(), None, Some(topic));
    }

    fn push(
        &mut self,
        kind: Kind,
        text: String,
        about: Option<PathBuf>,
        topic: Option<&'static str>,
    ) {
        let text = text.trim().to_string();
        if text.is_empty() {
            return;
        }
        if let Some(topic) = topic {
            self.lines.retain(|m| m.topic != Some(topic));
        }
        // A line already kept is not repeated.
        if self
            .lines
            .iter()
            .any(|m| m.kind == kind && m.text == text && m.about == about)
        {
            return;
        }
        // Each error and warning once on stderr, however often it comes back; confirmations
        // each time (a second save to the same file is news). A cloud's own lines were
        // written there by its loader.
        let first = about.is_none()
            && (kind == Kind::Info || self.echoed.insert((kind == Kind::Warning, text.clone())));
        if !self.quiet && first {
            match kind {
                Kind::Error => eprintln!("loudscape: error: {text}"),
                Kind::Warning => eprintln!("loudscape: warning: {text}"),
                Kind::Info => eprintln!("loudscape: {text}"),
            }
        }
        self.lines.push(Message {
            kind,
            text,
            about,
            topic,
        });
        if self.lines.len() > MOST {
            self.lines.remove(0);
        }
    }

    /// The lines shown while the cloud file `shown` is (None: no cloud), oldest first, with
    /// their indices: the window's own lines and those about that cloud.
    pub(in crate::ui) fn shown<'a>(
        &'a self,
        shown: Option<&'a Path>,
    ) -> impl Iterator<Item = (usize, &'a Message)> + 'a {
        self.lines
            .iter()
            .enumerate()
            .filter(move |(_, m)| m.about.as_deref().is_none_or(|about| Some(about) == shown))
    }

    /// What the closed list says of the lines shown with `shown`: "2 warnings, 1 error"
    /// (None for one line or none: that line is the whole list).
    pub(in crate::ui) fn count(&self, shown: Option<&Path>) -> Option<String> {
        let lines: Vec<_> = self.shown(shown).map(|(_, m)| m.kind).collect();
        if lines.len() < 2 {
            return None;
        }
        let counted = |kind: Kind, one: &str, many: &str| {
            let n = lines.iter().filter(|&&k| k == kind).count();
            (n > 0).then(|| format!("{n} {}", if n == 1 { one } else { many }))
        };
        let parts: Vec<String> = [
            counted(Kind::Error, "error", "errors"),
            counted(Kind::Warning, "warning", "warnings"),
            counted(Kind::Info, "message", "messages"),
        ]
        .into_iter()
        .flatten()
        .collect();
        Some(parts.join(", "))
    }

    /// Whether the whole list is open.
    pub(in crate::ui) fn is_open(&self) -> bool {
        self.open
    }

    /// Opens or closes the whole list (its button in the overlay).
    pub(in crate::ui) fn set_open(&mut self, open: bool) {
        self.open = open;
    }

    /// Removes line `index` (its × button).
    pub(in crate::ui) fn dismiss(&mut self, index: usize) {
        if index < self.lines.len() {
            self.lines.remove(index);
        }
    }

    /// Removes every line shown with `shown` (the others wait for their cloud).
    pub(in crate::ui) fn clear(&mut self, shown: Option<&Path>) {
        self.lines
            .retain(|m| m.about.as_deref().is_some_and(|about| Some(about) != shown));
        self.open = false;
    }

    /// Whether an error is shown (a scripted screenshot run takes its picture then).
    pub(in crate::ui) fn has_errors(&self) -> bool {
        self.lines.iter().any(|m| m.kind == Kind::Error)
    }

    /// Whether `text` is kept with `kind`.
    #[cfg(test)]
    pub(in crate::ui) fn contains(&self, kind: Kind, text: &str) -> bool {
        self.lines.iter().any(|m| m.kind == kind && m.text == text)
    }

    /// Whether nothing at all is kept.
    #[cfg(test)]
    pub(in crate::ui) fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// The lines that went (or, quiet, would have gone) to stderr.
    #[cfg(test)]
    fn echoed(&self) -> usize {
        self.echoed.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(m: &Messages, shown: Option<&Path>) -> Vec<String> {
        m.shown(shown).map(|(_, l)| l.text.clone()).collect()
    }

    #[test]
    fn lines_are_kept_once_in_order_and_a_confirmation_stays_until_replaced() {
        let mut m = Messages::quiet();
        m.error("a.ogg: not audio");
        m.info("saved /tmp/x.png (10×10)");
        m.warn("a.ogg: truncated");
        m.error("a.ogg: not audio");
        assert_eq!(
            texts(&m, None),
            [
                "a.ogg: not audio",
                "saved /tmp/x.png (10×10)",
                "a.ogg: truncated",
            ],
            "a repeated line is shown once; a confirmation does not fade"
        );
        m.info("saved /tmp/y.png (10×10)");
        assert_eq!(
            texts(&m, None),
            [
                "a.ogg: not audio",
                "a.ogg: truncated",
                "saved /tmp/y.png (10×10)",
            ],
            "the next confirmation replaces it"
        );
        assert!(m.has_errors());
        assert!(m.contains(Kind::Warning, "a.ogg: truncated"));
    }

    #[test]
    fn a_clouds_warnings_show_only_with_that_cloud_and_never_twice_on_stderr() {
        let mut m = Messages::quiet();
        let timeline = Path::new("/music/timeline.ply");
        let song = Path::new("/music/song.ply");
        m.warn_about(timeline, "other.flac: clipped");
        m.warn_about(timeline, "third.flac: clipped");
        m.warn("no file dialog can open here");
        assert_eq!(m.echoed(), 1, "the loader wrote the cloud's warnings");
        assert_eq!(
            texts(&m, Some(song)),
            ["no file dialog can open here"],
            "another song shown: the timeline's warnings wait"
        );
        assert_eq!(texts(&m, Some(timeline)).len(), 3);
        assert_eq!(
            m.count(Some(timeline)).as_deref(),
            Some("3 warnings"),
            "the closed list's count"
        );
        assert_eq!(m.count(Some(song)), None, "one line: no count");
        // Loaded again (every launch): still once each, and still not on stderr.
        m.warn_about(timeline, "other.flac: clipped");
        assert_eq!(texts(&m, Some(timeline)).len(), 3);
        m.dismiss(2);
        m.warn("no file dialog can open here");
        assert_eq!(
            m.echoed(),
            1,
            "a warning back after its dismissal is not printed again"
        );
        // Clearing the list shown leaves the lines of other clouds.
        m.clear(Some(song));
        assert_eq!(texts(&m, Some(timeline)).len(), 2);
        m.error("x: broken");
        assert_eq!(
            m.count(Some(timeline)).as_deref(),
            Some("1 error, 2 warnings")
        );
    }

    #[test]
    fn a_topics_line_is_replaced_by_its_next() {
        let mut m = Messages::quiet();
        m.say("video", Kind::Warning, "song: exporting to song.mp4");
        m.info("saved a.png");
        m.say("video", Kind::Info, "saved video song.mp4 (100 frames)");
        assert_eq!(
            texts(&m, None),
            ["saved a.png", "saved video song.mp4 (100 frames)"],
            "the export's result replaces \"exporting to\""
        );
        m.say(
            "video",
            Kind::Error,
            "video export to song.mp4 failed: disk full",
        );
        assert_eq!(texts(&m, None).len(), 2);
        assert!(m.has_errors());
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
        assert_eq!(m.shown(None).count(), 1);
        m.open = true;
        m.clear(None);
        assert!(m.is_empty() && !m.open);
        for i in 0..MOST + 5 {
            m.warn(format!("w{i}"));
        }
        let first = m.shown(None).next().unwrap().1.text.clone();
        assert_eq!(first, "w5", "the oldest go first");
    }
}
