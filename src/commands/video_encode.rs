//! The encoder of `loudscape video`: the `ffmpeg` command, fed raw RGBA frames through a pipe to
//! its stdin (no frame touches the disk; the pipe's buffer is all that waits, so memory stays flat
//! for any length), reading the song's passage from the source file itself (`-ss`/`-t` on the
//! audio input: ffmpeg decodes and trims it sample-exactly), writing H.264 (yuv420p) and AAC into
//! MP4 with the index up front (`+faststart`).
//!
//! Every path reaches ffmpeg as `file:` + the absolute path ([`ffmpeg_url`]), so ffmpeg reads
//! and writes exactly the files named, whatever the name (`file:x.mp4`, `a:b.mp4`, `-x.mp4`,
//! bytes that are not UTF-8): never another protocol, option or file.
//!
//! The file is written under a temporary name beside the output that carries the writer's PID
//! (`NAME.mp4.loudscape-PID.partial.mp4`) and renamed when ffmpeg has finished cleanly; ffmpeg
//! is killed and the temporary file removed on an error, on Ctrl+C and on SIGTERM
//! (`loudscape::files::{OwnedChild, TempFile}`), and dies with the command if it is killed
//! (SIGKILL); what such a run leaves is removed by the next run into that folder, once no
//! process of that PID lives ([`remove_stale_temporaries`]).
//!
//! Where the sound comes from ([`song_sound`]): the audio file the user named, or for a cloud
//! its recorded source, checked against the cloud first.
//!
//! Also the progress report of long runs: a line on a terminal, or JSON lines.

use std::ffi::{OsStr, OsString};
use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{ChildStdin, Command, Stdio};
use std::time::Instant;

use anyhow::{Context, bail};
use loudscape::data::cloud::PointCloud;
use loudscape::files::{OwnedChild, TempFile};
use loudscape::playback::source::ffmpeg_path;
pub use loudscape::playback::source::ffmpeg_url;
use loudscape::playback::{SourceError, checked_source};

/// The Debian package that brings the `ffmpeg` command.
pub const FFMPEG_PACKAGE: &str = "ffmpeg";

/// The `ffmpeg` command on PATH (or `$LOUDSCAPE_FFMPEG`), with a clear error when missing.
pub fn find_ffmpeg() -> anyhow::Result<PathBuf> {
    ffmpeg_path().with_context(|| {
        format!(
            "ffmpeg is not installed (not found on PATH); `loudscape video` encodes with it: \
             install the Debian/Ubuntu package '{FFMPEG_PACKAGE}' (apt install \
             {FFMPEG_PACKAGE}), or ffmpeg from ffmpeg.org elsewhere"
        )
    })
}

/// Where the sound of the video comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Sound {
    /// A passage of an audio file: `duration_s` seconds from `start_s`.
    Passage {
        path: PathBuf,
        start_s: f64,
        duration_s: f64,
    },
    /// A silent track of the video's length (a timeline has no one song to play).
    Silence,
}

/// The audio file whose sound a video of `input` (as the user named it) carries: an audio file
/// itself, never the source its cached cloud recorded (the same bytes may have been cached
/// under another name, since changed); for a cloud, its checked source
/// ([`loudscape::playback::checked_source`]). Errors are one line naming the file, the reason
/// and `--silent`.
pub fn song_sound(input: &Path, cloud: &PointCloud) -> anyhow::Result<PathBuf> {
    if loudscape::extract::is_audio(input) {
        return Ok(input.to_path_buf());
    }
    let silent = "pass --silent for a video without the song's sound";
    checked_source(cloud).map_err(|e| match e {
        SourceError::Mismatch { .. } => anyhow::anyhow!(
            "{}: {e}; {silent}, or extract the cloud again from that audio",
            input.display()
        ),
        _ => anyhow::anyhow!("{}: {e}; {silent}", input.display()),
    })
}

/// What to encode.
#[derive(Clone, Debug)]
pub struct EncodeSpec {
    pub width: u32,
    pub height: u32,
    pub fps: u32,
    pub frames: u64,
    pub sound: Sound,
    /// x264's constant rate factor (lower is better; 18 is visually lossless for most content).
    pub crf: u32,
}

/// The ffmpeg arguments that encode `spec` into `output`.
pub fn ffmpeg_args(spec: &EncodeSpec, output: &Path) -> Vec<OsString> {
    let seconds = |s: f64| format!("{s:.6}");
    let video_s = spec.frames as f64 / f64::from(spec.fps);
    let mut args: Vec<String> = [
        "-hide_banner",
        "-nostats",
        "-loglevel",
        "error",
        "-y",
        "-f",
        "rawvideo",
        "-pix_fmt",
        "rgba",
    ]
    .map(String::from)
    .to_vec();
    args.extend([
        "-s".into(),
        format!("{}x{}", spec.width, spec.height),
        "-framerate".into(),
        spec.fps.to_string(),
        "-i".into(),
        "pipe:0".into(),
    ]);
    let mut audio_input = None;
    match &spec.sound {
        Sound::Passage {
            path,
            start_s,
            duration_s,
        } => {
            args.extend([
                "-ss".into(),
                seconds(*start_s),
                "-t".into(),
                seconds(*duration_s),
            ]);
            audio_input = Some(ffmpeg_url(path));
        }
        Sound::Silence => {
            args.extend(["-f".into(), "lavfi".into(), "-t".into(), seconds(video_s)]);
        }
    }
    let mut args: Vec<OsString> = args.into_iter().map(OsString::from).collect();
    args.push("-i".into());
    args.push(
        audio_input.unwrap_or_else(|| "anullsrc=channel_layout=stereo:sample_rate=48000".into()),
    );
    let mut rest: Vec<String> = [
        "-map", "0:v:0", "-map", "1:a:0", "-c:v", "libx264", "-preset", "veryfast", "-crf",
    ]
    .map(String::from)
    .to_vec();
    rest.push(spec.crf.to_string());
    // BT.709 colour (HD video's), converted and tagged, so players do not guess (untagged HD
    // is shown as BT.709 by most, while ffmpeg converts with BT.601 unless told).
    rest.extend(
        [
            "-vf",
            "scale=out_color_matrix=bt709:out_range=tv",
            "-pix_fmt",
            "yuv420p",
            "-colorspace",
            "bt709",
            "-color_primaries",
            "bt709",
            "-color_trc",
            "bt709",
            "-color_range",
            "tv",
            "-c:a",
            "aac",
            "-b:a",
            "192k",
            "-movflags",
            "+faststart",
            "-f",
            "mp4",
        ]
        .map(String::from),
    );
    args.extend(rest.into_iter().map(OsString::from));
    args.push(ffmpeg_url(output));
    args
}

/// The mark of a temporary video file: `.loudscape-PID` + this, after the output's name.
const PARTIAL_SUFFIX: &str = ".partial.mp4";

/// The temporary file's suffix for this process: `.loudscape-PID.partial.mp4`.
fn partial_suffix() -> String {
    format!(".loudscape-{}{PARTIAL_SUFFIX}", std::process::id())
}

/// The PID in the name of a temporary video file (`….loudscape-PID.partial.mp4`), if it is one.
#[cfg_attr(not(unix), allow(dead_code))]
pub fn partial_owner(name: &OsStr) -> Option<u32> {
    let name = name.as_encoded_bytes();
    let rest = name.strip_suffix(PARTIAL_SUFFIX.as_bytes())?;
    let marker = b".loudscape-";
    let at = rest.windows(marker.len()).rposition(|w| w == marker)?;
    let digits = &rest[at + marker.len()..];
    if digits.is_empty() || digits.len() > 10 || !digits.iter().all(u8::is_ascii_digit) {
        return None;
    }
    std::str::from_utf8(digits)
        .ok()?
        .parse()
        .ok()
        .filter(|&pid| pid > 0)
}

/// Removes what killed video runs left beside `output`: every regular file of its folder named
/// `….loudscape-PID.partial.mp4` whose PID no longer lives (SIGKILL gives no chance to clean
/// up), and `NAME.partial.mp4`, the temporary of `output` that versions without the PID wrote.
/// Best effort: a file that cannot be removed stays. Returns the names removed.
pub fn remove_stale_temporaries(output: &Path) -> Vec<PathBuf> {
    #[cfg_attr(not(unix), allow(unused_mut))]
    let mut removed = Vec::new();
    #[cfg(unix)]
    {
        let folder = match output.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        let mut legacy = output.file_name().unwrap_or_default().to_os_string();
        legacy.push(PARTIAL_SUFFIX);
        let Ok(entries) = std::fs::read_dir(folder) else {
            return removed;
        };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let stale = match partial_owner(&name) {
                // Removed only when surely gone (a process of another user's lives).
                Some(pid) => {
                    pid != std::process::id() && loudscape::files::process_runs(pid) == Some(false)
                }
                None => name == legacy,
            };
            let regular = entry.file_type().is_ok_and(|t| t.is_file());
            if stale && regular && std::fs::remove_file(entry.path()).is_ok() {
                removed.push(entry.path());
            }
        }
    }
    #[cfg(not(unix))]
    let _ = output;
    removed
}

/// A running ffmpeg taking frames.
pub struct Encoder {
    // Field order is drop order: the pipe closes, ffmpeg is killed, then its file is removed.
    stdin: Option<ChildStdin>,
    child: Option<OwnedChild>,
    stderr: Option<std::thread::JoinHandle<String>>,
    tmp: Option<TempFile>,
    frame_bytes: usize,
    output: PathBuf,
}

impl Encoder {
    /// Starts ffmpeg writing to a temporary file beside `output`.
    pub fn start(spec: &EncodeSpec, output: &Path) -> anyhow::Result<Encoder> {
        let ffmpeg = find_ffmpeg()?;
        remove_stale_temporaries(output);
        let tmp = TempFile::create(output, &partial_suffix())
            .with_context(|| format!("{}: cannot write", output.display()))?;
        let mut command = Command::new(&ffmpeg);
        command
            .args(ffmpeg_args(spec, tmp.path()))
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        // Its own process group: Ctrl+C in the terminal reaches loudscape alone, whose handler
        // kills ffmpeg before removing the file (ffmpeg would otherwise finish the file itself);
        // and on Linux killed with loudscape (SIGKILL), not left to finish a stray file.
        loudscape::files::own_process_group(&mut command);
        let mut child = command
            .spawn()
            .with_context(|| format!("cannot start {}", ffmpeg.display()))?;
        let stdin = child.stdin.take();
        let mut stderr = child.stderr.take();
        // ffmpeg's messages, kept (the tail) for the error line.
        let stderr = std::thread::Builder::new()
            .name("loudscape::ffmpeg-stderr".into())
            .spawn(move || {
                let mut text = String::new();
                if let Some(err) = stderr.as_mut() {
                    let _ = err.read_to_string(&mut text);
                }
                text
            })
            .ok();
        Ok(Encoder {
            stdin,
            child: Some(OwnedChild::new(child)),
            stderr,
            tmp: Some(tmp),
            frame_bytes: spec.width as usize * spec.height as usize * 4,
            output: output.to_path_buf(),
        })
    }

    /// Sends one frame (RGBA, rows top to bottom, exactly width x height).
    pub fn push(&mut self, rgba: &[u8]) -> anyhow::Result<()> {
        if rgba.len() != self.frame_bytes {
            bail!(
                "internal: a frame of {} bytes, expected {}",
                rgba.len(),
                self.frame_bytes
            );
        }
        let Some(stdin) = self.stdin.as_mut() else {
            bail!("internal: the encoder is closed");
        };
        if stdin.write_all(rgba).is_err() {
            // ffmpeg stopped reading: it failed; its own words say why.
            self.stdin = None;
            self.wait_quietly();
            let said = self.ffmpeg_said();
            bail!("{}: ffmpeg stopped: {said}", self.output.display());
        }
        Ok(())
    }

    fn wait_quietly(&mut self) {
        if let Some(child) = self.child.take() {
            let _ = child.wait();
        }
    }

    fn ffmpeg_said(&mut self) -> String {
        let text = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        let last = text
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("no message");
        last.trim().to_string()
    }

    /// Closes the pipe, waits for ffmpeg to finish the file and renames it to the output.
    pub fn finish(mut self) -> anyhow::Result<()> {
        drop(self.stdin.take());
        let status = match self.child.take() {
            Some(child) => child.wait().context("waiting for ffmpeg")?,
            None => bail!("internal: ffmpeg was already waited for"),
        };
        let said = self.ffmpeg_said();
        if !status.success() {
            bail!(
                "{}: ffmpeg failed ({status}): {said}",
                self.output.display()
            );
        }
        let Some(tmp) = self.tmp.take() else {
            bail!("internal: the temporary file is gone");
        };
        tmp.persist(&self.output)
            .with_context(|| format!("{}: cannot write", self.output.display()))
    }
}

/// How progress is reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ProgressMode {
    /// A line on stderr when it is a terminal, nothing otherwise.
    Auto,
    /// One JSON object a line on stdout.
    Json,
    None,
}

/// Frames done, frames a second and the time left.
pub struct Progress {
    mode: ProgressMode,
    terminal: bool,
    total: u64,
    started: Instant,
    last: Option<Instant>,
}

impl Progress {
    pub fn new(mode: ProgressMode, total: u64) -> Self {
        Self {
            mode,
            terminal: std::io::stderr().is_terminal(),
            total,
            started: Instant::now(),
            last: None,
        }
    }

    /// Reports `done` frames, at most a few times a second (and always the last frame).
    pub fn frame(&mut self, done: u64) {
        let now = Instant::now();
        let interval = match self.mode {
            ProgressMode::Json => 1.0,
            _ => 0.25,
        };
        let due = self
            .last
            .is_none_or(|t| now.duration_since(t).as_secs_f64() >= interval);
        if !(due || done == self.total) {
            return;
        }
        self.last = Some(now);
        let elapsed = now.duration_since(self.started).as_secs_f64().max(1e-6);
        let fps = done as f64 / elapsed;
        let eta = if fps > 0.0 {
            (self.total - done.min(self.total)) as f64 / fps
        } else {
            0.0
        };
        match self.mode {
            ProgressMode::Json => {
                let line = serde_json::json!({
                    "frame": done,
                    "frames": self.total,
                    "fps": (fps * 100.0).round() / 100.0,
                    "eta_s": (eta * 10.0).round() / 10.0,
                });
                let mut out = std::io::stdout().lock();
                let _ = writeln!(out, "{line}");
                let _ = out.flush();
            }
            ProgressMode::Auto if self.terminal => {
                let percent = 100.0 * done as f64 / self.total.max(1) as f64;
                eprint!(
                    "\r\x1b[Kframe {done}/{} ({percent:.0}%)  {fps:.1} fps  ETA {}",
                    self.total,
                    loudscape::playback::format_clock(eta)
                );
                if done == self.total {
                    eprintln!();
                }
            }
            _ => {}
        }
    }

    /// Clears the terminal line (after an error).
    pub fn abandon(&self) {
        if self.mode == ProgressMode::Auto && self.terminal && self.last.is_some() {
            eprint!("\r\x1b[K");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_audio_passage_is_cut_on_the_audio_input() {
        let spec = EncodeSpec {
            width: 640,
            height: 360,
            fps: 25,
            frames: 50,
            sound: Sound::Passage {
                path: PathBuf::from("song.flac"),
                start_s: 1.5,
                duration_s: 2.0,
            },
            crf: 18,
        };
        let text = |args: Vec<OsString>| -> Vec<String> {
            args.iter()
                .map(|a| a.to_string_lossy().into_owned())
                .collect()
        };
        let args = text(ffmpeg_args(&spec, Path::new("out.mp4.partial.mp4")));
        let joined = args.join(" ");
        let here = std::env::current_dir().unwrap();
        assert!(
            joined.contains("-s 640x360 -framerate 25 -i pipe:0"),
            "{joined}"
        );
        let song = format!("file:{}", here.join("song.flac").display());
        assert!(
            joined.contains(&format!("-ss 1.500000 -t 2.000000 -i {song}")),
            "{joined}"
        );
        assert!(joined.contains("-pix_fmt yuv420p"), "{joined}");
        assert!(joined.contains("-movflags +faststart"), "{joined}");
        let out = format!("file:{}", here.join("out.mp4.partial.mp4").display());
        assert_eq!(args.last(), Some(&out));
        let silent = text(ffmpeg_args(
            &EncodeSpec {
                sound: Sound::Silence,
                ..spec
            },
            Path::new("o.mp4"),
        ))
        .join(" ");
        assert!(
            silent.contains("-f lavfi -t 2.000000 -i anullsrc"),
            "{silent}"
        );
    }

    #[test]
    fn every_path_is_a_file_url_of_its_absolute_path() {
        let here = std::env::current_dir().unwrap();
        for name in ["file:c.ogg", "a:b.mp4", "-x.mp4", "pipe:1"] {
            let url = ffmpeg_url(Path::new(name));
            let expected = format!("file:{}", here.join(name).display());
            assert_eq!(url.to_string_lossy(), expected);
        }
        assert_eq!(
            ffmpeg_url(Path::new("/m/a.mp4")),
            OsString::from("file:/m/a.mp4")
        );
        #[cfg(unix)]
        {
            use std::os::unix::ffi::OsStrExt;
            let odd = OsStr::from_bytes(b"/m/caf\xe9 \xff.wav");
            let url = ffmpeg_url(Path::new(odd));
            assert_eq!(url.as_encoded_bytes(), b"file:/m/caf\xe9 \xff.wav");
        }
    }

    #[test]
    fn the_temporary_names_its_owner() {
        let mine = partial_suffix();
        let name = OsString::from(format!("out.mp4{mine}"));
        assert_eq!(partial_owner(&name), Some(std::process::id()));
        let owner = |s: &str| partial_owner(OsStr::new(s));
        assert_eq!(owner("a.mp4.loudscape-42.partial.mp4"), Some(42));
        assert_eq!(owner(".loudscape-7-0.loudscape-7.partial.mp4"), Some(7));
        assert_eq!(owner("a.mp4.partial.mp4"), None);
        assert_eq!(owner("holiday.2019.partial.mp4"), None);
        assert_eq!(owner("a.mp4.loudscape-.partial.mp4"), None);
        assert_eq!(owner("a.mp4.loudscape-0.partial.mp4"), None);
        assert_eq!(owner("a.mp4.loudscape-4x2.partial.mp4"), None);
        assert_eq!(owner("a.mp4.loudscape-42.partial.mp4.txt"), None);
    }
}
