//! Save PNG under way: the picture was rendered (or copied from the view's own, complete one)
//! and its read-back submitted in the frame of the click (`ui/window_screenshot.rs`); a thread
//! waits for the GPU's copy, draws the labels, encodes the PNG and writes it, while the window
//! keeps drawing frames. One save at a time; the window waits for it before it closes (the
//! thread is joined when the save is dropped), so a PNG is never left half written.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A picture rendered for the save in one frame.
pub(in crate::ui) const RENDERED: &str = "rendered for the picture";
/// The view's own picture, copied.
pub(in crate::ui) const COPIED: &str = "the view's picture, copied";
/// A picture drawn for the save a slice a frame.
pub(in crate::ui) const SLICED: &str = "drawn for the picture in slices";

/// What a finished save says: the picture's size, or why nothing was saved.
pub(in crate::ui) type Saved = Result<(u32, u32), String>;

/// A picture being read back, encoded and written on a thread.
pub(in crate::ui) struct PictureSave {
    receiver: Receiver<Saved>,
    thread: Option<JoinHandle<()>>,
    /// Where it goes.
    pub(in crate::ui) path: PathBuf,
    /// What the "saved …" line adds (a name kept, no dialog here).
    pub(in crate::ui) notes: String,
    started: Instant,
    /// Frames the window drew while the thread worked.
    frames: u32,
    /// How the picture was made, for the "picture: saved" line: [`RENDERED`], [`COPIED`] (the
    /// view's own, not drawn again) or [`SLICED`] (drawn for the save over frames).
    pub(in crate::ui) how: &'static str,
    /// Frames the save waited for the view to fill in before its picture was taken
    /// (`save_wait.rs`); they are counted among the frames drawn meanwhile.
    pub(in crate::ui) waited: u32,
}

/// A finished save: its result, how long it took and the frames drawn meanwhile.
pub(in crate::ui) struct Finished {
    pub(in crate::ui) saved: Saved,
    pub(in crate::ui) took: Duration,
    pub(in crate::ui) frames: u32,
}

impl PictureSave {
    /// Runs `work` (wait for the picture, encode it, write `path`) on a thread.
    pub(in crate::ui) fn start(
        path: PathBuf,
        notes: String,
        work: impl FnOnce() -> Saved + Send + 'static,
    ) -> Self {
        let (sender, receiver) = channel();
        let thread = std::thread::Builder::new()
            .name("save-png".into())
            .spawn(move || {
                let _ = sender.send(work());
            });
        // No thread: the receiver's sender is gone, which `poll` tells as an error.
        let thread = match thread {
            Ok(thread) => Some(thread),
            Err(e) => {
                log::warn!("no thread for Save PNG: {e}");
                None
            }
        };
        Self {
            receiver,
            thread,
            path,
            notes,
            started: Instant::now(),
            frames: 0,
            how: RENDERED,
            waited: 0,
        }
    }

    /// The save began `frames` frames before, at `since`, waiting for the view: its time and
    /// its frames count from the click.
    pub(in crate::ui) fn waited_since(mut self, since: Instant, frames: u32) -> Self {
        self.started = since;
        self.frames = frames;
        self.waited = frames;
        self
    }

    /// Called once a frame: None while the thread works (the frame is counted), then what it
    /// did.
    pub(in crate::ui) fn poll(&mut self) -> Option<Finished> {
        let saved = match self.receiver.try_recv() {
            Ok(saved) => saved,
            Err(TryRecvError::Empty) => {
                self.frames += 1;
                return None;
            }
            Err(TryRecvError::Disconnected) => {
                Err(format!("{}: the save stopped", self.path.display()))
            }
        };
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
        Some(Finished {
            saved,
            took: self.started.elapsed(),
            frames: self.frames,
        })
    }
}

impl Drop for PictureSave {
    /// The window closing mid-save waits for the file (written whole or its partial removed).
    fn drop(&mut self) {
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc::sync_channel;

    /// The window's frames go on while the thread works: each poll before the answer is a frame
    /// drawn meanwhile, and the answer comes once, with that count.
    #[test]
    fn frames_go_on_until_the_thread_answers() {
        let (release, wait) = sync_channel::<()>(0);
        let mut save = PictureSave::start("x.png".into(), String::new(), move || {
            wait.recv().map_err(|e| e.to_string())?;
            Ok((640, 400))
        });
        for _ in 0..3 {
            assert!(save.poll().is_none(), "no answer before the thread's");
        }
        release.send(()).unwrap();
        let deadline = Instant::now() + Duration::from_secs(30);
        let finished = loop {
            if let Some(finished) = save.poll() {
                break finished;
            }
            assert!(Instant::now() < deadline, "no answer from the thread");
            std::thread::sleep(Duration::from_millis(2));
        };
        assert_eq!(finished.saved, Ok((640, 400)));
        assert!(finished.frames >= 3, "{} frames", finished.frames);
    }

    /// A thread that stops without an answer is an error naming the file.
    #[test]
    fn a_stopped_thread_is_an_error() {
        let mut save = PictureSave::start("x.png".into(), String::new(), || panic!("stopped"));
        let deadline = Instant::now() + Duration::from_secs(30);
        let finished = loop {
            if let Some(finished) = save.poll() {
                break finished;
            }
            assert!(Instant::now() < deadline, "no answer");
            std::thread::sleep(Duration::from_millis(2));
        };
        assert_eq!(finished.saved, Err("x.png: the save stopped".into()));
    }
}
