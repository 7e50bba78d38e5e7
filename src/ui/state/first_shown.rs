//! Which cloud a window that opens several files at once shows first ([`FirstShown`], the
//! `first_shown` field of `LoudscapeApp`): the loads finish in any order, so the slot shown is
//! decided by the files, not by which load came last. Reopened, it is the slot shown when the
//! window closed; from the command line, the first file named. The other files' clouds are
//! installed unseen (a click on Song or Timeline shows them). A cloud opened later by hand
//! (Open…, Recent, a drop) ends the group and is shown, as always.

use std::path::{Path, PathBuf};

use super::slot::Slot;

/// Where one of the files opened together is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Arrival {
    Waiting,
    Arrived(Slot),
    Failed,
}

/// The files opened together at start, in the order named, and the slot to show.
#[derive(Clone, Debug, Default)]
pub(in crate::ui) struct FirstShown {
    files: Vec<(PathBuf, Arrival)>,
    /// Reopened: the slot shown when the window closed.
    prefer: Option<Slot>,
}

impl FirstShown {
    /// `files` opened together (none or one: nothing to decide), `prefer` the slot to show
    /// when one of them fills it.
    pub(in crate::ui) fn new(files: &[PathBuf], prefer: Option<Slot>) -> FirstShown {
        if files.len() < 2 {
            return FirstShown::default();
        }
        FirstShown {
            files: files
                .iter()
                .map(|path| (path.clone(), Arrival::Waiting))
                .collect(),
            prefer,
        }
    }

    /// Whether files opened together are still being decided between.
    fn active(&self) -> bool {
        self.files.iter().any(|(_, a)| *a == Arrival::Waiting)
    }

    /// The slot to show now: the preferred one once its cloud is in (while it may still
    /// come, nothing); else the first file's that did not fail (nothing while it loads).
    pub(in crate::ui) fn decided(&self) -> Option<Slot> {
        let arrived = |slot: Slot| self.files.iter().any(|(_, a)| *a == Arrival::Arrived(slot));
        if let Some(prefer) = self.prefer {
            if arrived(prefer) {
                return Some(prefer);
            }
            if self.active() {
                return None;
            }
        }
        match self.files.iter().find(|(_, a)| *a != Arrival::Failed)? {
            (_, Arrival::Arrived(slot)) => Some(*slot),
            _ => None,
        }
    }

    fn mark(&mut self, path: &Path, arrival: Arrival) -> bool {
        match self
            .files
            .iter_mut()
            .find(|(p, a)| p == path && *a == Arrival::Waiting)
        {
            Some((_, a)) => {
                *a = arrival;
                true
            }
            None => false,
        }
    }

    /// The cloud of `path` came in `slot`. One of the group is shown if its slot is the one
    /// decided; any other load ends the group and is shown.
    pub(in crate::ui) fn arrived(&mut self, path: &Path, slot: Slot) -> bool {
        if !self.active() {
            *self = FirstShown::default();
            return true;
        }
        if !self.mark(path, Arrival::Arrived(slot)) {
            // Opened by hand meanwhile: the user's choice wins.
            *self = FirstShown::default();
            return true;
        }
        self.decided() == Some(slot)
    }

    /// Reopened: the slot whose remembered camera waits for its cloud, while the files load.
    pub(in crate::ui) fn restoring(&self) -> Option<Slot> {
        self.prefer.filter(|_| self.active())
    }

    /// Whether the cloud of `path` would be shown if it came in `slot` now (a song's points
    /// so far, before its whole cloud comes).
    pub(in crate::ui) fn would_show(&self, path: &Path, slot: Slot) -> bool {
        self.clone().arrived(path, slot)
    }

    /// The load of `path` failed: the slot now decided, if that changed it (a cloud that came
    /// earlier and waited unseen is shown in place of the one that failed).
    pub(in crate::ui) fn failed(&mut self, path: &Path) -> Option<Slot> {
        let before = self.decided();
        if !self.mark(path, Arrival::Failed) {
            return None;
        }
        let after = self.decided();
        (after != before).then_some(after).flatten()
    }
}

#[cfg(test)]
mod tests {
    use super::{FirstShown, Slot};
    use std::path::PathBuf;

    fn files() -> (PathBuf, PathBuf, Vec<PathBuf>) {
        let song = PathBuf::from("demo_song.ply");
        let timeline = PathBuf::from("demo_timeline.ply");
        (song.clone(), timeline.clone(), vec![song, timeline])
    }

    #[test]
    fn the_first_file_named_is_shown_whichever_load_ends_last() {
        let (song, timeline, both) = files();
        // The song named first, its load ending last.
        let mut first = FirstShown::new(&both, None);
        assert!(!first.arrived(&timeline, Slot::Timeline), "waits unseen");
        assert!(first.arrived(&song, Slot::Song), "the first named");
        assert!(first.arrived(&PathBuf::from("later.ply"), Slot::Timeline));
        // Its load ending first: the timeline coming after stays unseen.
        let mut first = FirstShown::new(&both, None);
        assert!(first.arrived(&song, Slot::Song));
        assert!(
            !first.arrived(&timeline, Slot::Timeline),
            "not shown over it"
        );
        assert!(
            first.arrived(&PathBuf::from("later.ply"), Slot::Timeline),
            "the group is over: a later load is shown"
        );
        // The timeline named first.
        let mut first = FirstShown::new(&[timeline.clone(), song.clone()], None);
        assert!(!first.arrived(&song, Slot::Song));
        assert!(first.arrived(&timeline, Slot::Timeline));
        // The first fails: the second, waiting unseen, is shown.
        let mut first = FirstShown::new(&both, None);
        assert!(!first.arrived(&timeline, Slot::Timeline));
        assert_eq!(first.failed(&song), Some(Slot::Timeline));
        // A file opened by hand while the group loads is shown, and the group is over.
        let mut first = FirstShown::new(&both, None);
        assert!(first.arrived(&PathBuf::from("opened.ply"), Slot::Song));
        assert!(first.arrived(&timeline, Slot::Timeline));
        // One file: nothing to decide.
        let mut first = FirstShown::new(&both[..1], None);
        assert!(first.arrived(&song, Slot::Song));
    }

    #[test]
    fn a_reopened_window_shows_the_slot_it_closed_on_whichever_load_ends_last() {
        let (song, timeline, both) = files();
        let mut first = FirstShown::new(&both, Some(Slot::Timeline));
        assert!(
            first.arrived(&timeline, Slot::Timeline),
            "the slot closed on"
        );
        assert!(
            !first.arrived(&song, Slot::Song),
            "the song ending its load later stays unseen"
        );
        let mut first = FirstShown::new(&both, Some(Slot::Timeline));
        assert!(
            !first.would_show(&song, Slot::Song),
            "a song's points so far are not shown either"
        );
        assert!(!first.arrived(&song, Slot::Song), "the song first: unseen");
        assert!(first.arrived(&timeline, Slot::Timeline));
        // The timeline's load fails: the song that waited is shown.
        let mut first = FirstShown::new(&both, Some(Slot::Timeline));
        assert_eq!(first.restoring(), Some(Slot::Timeline));
        assert!(!first.arrived(&song, Slot::Song));
        assert_eq!(first.failed(&timeline), Some(Slot::Song));
        assert_eq!(first.restoring(), None);
        // It fails before the song comes: the song is shown when it comes.
        let mut first = FirstShown::new(&both, Some(Slot::Timeline));
        assert_eq!(first.failed(&timeline), None);
        assert_eq!(
            first.restoring(),
            Some(Slot::Timeline),
            "the song still loads"
        );
        assert!(first.arrived(&song, Slot::Song));
    }
}
