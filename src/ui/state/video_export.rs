//! An "Export video…" on its way (`ui/video_export.rs`): the `loudscape video` child the window
//! started, the thread reading its `--progress json` lines, the last progress it sent and the
//! tail of its stderr; the save dialog while it is open; the Video row's name field and passage.

use std::path::PathBuf;
use std::process::Child;
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex};

/// One `--progress json` line of `loudscape video`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(in crate::ui) struct VideoProgress {
    pub(in crate::ui) frame: u64,
    pub(in crate::ui) frames: u64,
    pub(in crate::ui) fps: f64,
    pub(in crate::ui) eta_s: f64,
}

impl VideoProgress {
    /// Reads one stdout line; `None` for anything that is not a progress object.
    pub(in crate::ui) fn parse(line: &str) -> Option<Self> {
        let value: serde_json::Value = serde_json::from_str(line.trim()).ok()?;
        Some(Self {
            frame: value.get("frame")?.as_u64()?,
            frames: value.get("frames")?.as_u64()?,
            fps: value.get("fps").and_then(|v| v.as_f64()).unwrap_or(0.0),
            eta_s: value.get("eta_s").and_then(|v| v.as_f64()).unwrap_or(0.0),
        })
    }

    /// The share of the frames done, in [0, 1].
    pub(in crate::ui) fn fraction(&self) -> f32 {
        if self.frames == 0 {
            0.0
        } else {
            (self.frame as f64 / self.frames as f64).clamp(0.0, 1.0) as f32
        }
    }
}

/// A running export: the child, where it writes, and what its reader threads share.
pub(in crate::ui) struct RunningExport {
    pub(in crate::ui) child: Child,
    pub(in crate::ui) output: PathBuf,
    /// Progress lines, parsed, from the stdout reader thread (closed when stdout closes).
    pub(in crate::ui) progress: Receiver<VideoProgress>,
    pub(in crate::ui) latest: Option<VideoProgress>,
    /// The child's last non-empty stderr line (its error, when it fails).
    pub(in crate::ui) last_error: Arc<Mutex<String>>,
    /// The thread reading stderr: done once the child and what it started closed it.
    pub(in crate::ui) stderr_reader: Option<std::thread::JoinHandle<()>>,
    /// Cancel was pressed: SIGTERM sent, waiting for the child to stop.
    pub(in crate::ui) cancelled: bool,
}

impl RunningExport {
    /// Asks the child to stop: SIGTERM on Unix (the command removes its partial file and stops
    /// at once), a kill elsewhere.
    pub(in crate::ui) fn stop(&mut self) {
        #[cfg(unix)]
        crate::files::terminate(&self.child);
        #[cfg(not(unix))]
        let _ = self.child.kill();
    }
}

impl Drop for RunningExport {
    /// The window closing (or the app ending) stops an export still running and waits for it,
    /// so its partial file is removed.
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            self.stop();
            let _ = self.child.wait();
        }
    }
}

/// The Video row's state: its name field, the passage, the export under way.
#[derive(Default)]
pub(in crate::ui) struct VideoExport {
    /// The Video field: where to write (empty: `<song>.mp4` in the current folder); the save
    /// dialog starts from it.
    pub(in crate::ui) path: String,
    /// The start and end fields, seconds, once edited (`None`: the loop range when one is set,
    /// else the whole song), and the cloud they were edited for (another song starts afresh).
    pub(in crate::ui) passage: Option<(f64, f64)>,
    pub(in crate::ui) passage_for: Option<u64>,
    /// The videos written in this run: only these are written again under their own name.
    pub(in crate::ui) made: super::written::MadeHere,
    /// The export under way, if one is.
    pub(in crate::ui) running: Option<RunningExport>,
    /// The save dialog's answer, while it is open.
    pub(in crate::ui) save_dialog: Option<Receiver<Option<PathBuf>>>,
    /// Scripted runs (tests): cancel the export as soon as it has started.
    pub(in crate::ui) cancel_at_start: bool,
}

/// The name a timeline's video gets unless one is typed (without its extension): the one its
/// legend shows, so a timeline built in the window from a folder is named by that folder (its
/// file in the cloud cache is named by a hash, which said nothing), else its file's stem.
pub(in crate::ui) fn timeline_video_stem(cloud: &crate::data::cloud::PointCloud) -> String {
    let name = crate::annotate::legend::timeline_name(cloud);
    match name.strip_suffix('/') {
        // A folder: its whole name ("Vol. 2" keeps its dot).
        Some(folder) => folder.to_string(),
        None => std::path::Path::new(&name)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or(name),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A timeline built in the window from a folder is exported as that folder's name, not as
    /// its cache file's hash; a timeline file opened from elsewhere keeps its own name.
    #[test]
    fn a_folder_timeline_s_video_is_named_by_its_folder() {
        let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut cloud = crate::data::cloud::load(&repo.join("data/demo_timeline.ply")).unwrap();
        assert_eq!(timeline_video_stem(&cloud), "demo_timeline");
        for (i, song) in cloud.meta.songs.iter_mut().enumerate() {
            song.path = Some(format!("/music/Vol. 2/disc {}/song{i}.flac", i % 2));
            song.path_bytes = None;
        }
        cloud.path = crate::extract::cache::dir().join("timeline-41b95712d880b9b1.ply");
        assert_eq!(timeline_video_stem(&cloud), "Vol. 2");
        cloud.path = std::path::PathBuf::from("/somewhere/timeline-41b95712d880b9b1.ply");
        assert_eq!(timeline_video_stem(&cloud), "timeline-41b95712d880b9b1");
    }

    #[test]
    fn progress_lines_are_read_and_other_lines_ignored() {
        let p = VideoProgress::parse(r#"{"frame":15,"frames":60,"fps":7.5,"eta_s":6.0}"#)
            .expect("a progress line");
        assert_eq!(
            p,
            VideoProgress {
                frame: 15,
                frames: 60,
                fps: 7.5,
                eta_s: 6.0
            }
        );
        assert!((p.fraction() - 0.25).abs() < 1e-6);
        assert!(VideoProgress::parse("wrote out.mp4").is_none());
        assert!(VideoProgress::parse(r#"{"frames":3}"#).is_none());
    }
}
