//! The encoder of `loudscape video`: the `ffmpeg` command, fed raw RGBA frames through a pipe to
//! its stdin (no frame touches the disk; the pipe's buffer is all that waits, so memory stays flat
//! for any length), reading the song's passage from the source file itself (`-ss`/`-t` on the
//! audio input: ffmpeg decodes and trims it sample-exactly), writing H.264 (yuv420p) and AAC into
//! MP4 with the index up front (`+faststart`).
//!
//! The file is written under a temporary name beside the output and renamed when ffmpeg has
//! finished cleanly; ffmpeg is killed and the temporary file removed on an error, on Ctrl+C and
//! on SIGTERM (`loudscape::files::{OwnedChild, TempFile}`).
//!
//! Also the progress report of long runs: a line on a terminal, or JSON lines.

use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{ChildStdin, Command, Stdio};
use std::time::Instant;

use anyhow::{Context, bail};
use loudscape::files::{OwnedChild, TempFile};

/// The Debian package that brings the `ffmpeg` command.
pub const FFMPEG_PACKAGE: &str = "ffmpeg";

/// The `ffmpeg` command on PATH (or `$LOUDSCAPE_FFMPEG`), with a clear error when missing.
pub fn find_ffmpeg() -> anyhow::Result<PathBuf> {
    if let Some(path) = std::env::var_os("LOUDSCAPE_FFMPEG") {
        return Ok(PathBuf::from(path));
    }
    let name = if cfg!(windows) {
        "ffmpeg.exe"
    } else {
        "ffmpeg"
    };
    std::env::var_os("PATH")
        .iter()
        .flat_map(std::env::split_paths)
        .map(|dir| dir.join(name))
        .find(|p| p.is_file())
        .with_context(|| {
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
pub fn ffmpeg_args(spec: &EncodeSpec, output: &Path) -> Vec<String> {
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
                "-i".into(),
                path.display().to_string(),
            ]);
        }
        Sound::Silence => {
            args.extend([
                "-f".into(),
                "lavfi".into(),
                "-t".into(),
                seconds(video_s),
                "-i".into(),
                "anullsrc=channel_layout=stereo:sample_rate=48000".into(),
            ]);
        }
    }
    args.extend(
        [
            "-map", "0:v:0", "-map", "1:a:0", "-c:v", "libx264", "-preset", "veryfast", "-crf",
        ]
        .map(String::from),
    );
    args.push(spec.crf.to_string());
    // BT.709 colour (HD video's), converted and tagged, so players do not guess (untagged HD
    // is shown as BT.709 by most, while ffmpeg converts with BT.601 unless told).
    args.extend(
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
    args.push(output.display().to_string());
    args
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
        let tmp = TempFile::create(output, ".partial.mp4")
            .with_context(|| format!("{}: cannot write", output.display()))?;
        let mut command = Command::new(&ffmpeg);
        command
            .args(ffmpeg_args(spec, tmp.path()))
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        // Its own process group: Ctrl+C in the terminal reaches loudscape alone, whose handler
        // kills ffmpeg before removing the file (ffmpeg would otherwise finish the file itself).
        #[cfg(unix)]
        std::os::unix::process::CommandExt::process_group(&mut command, 0);
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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgressMode {
    /// A line on stderr when it is a terminal, nothing otherwise.
    Auto,
    /// One JSON object a line on stdout.
    Json,
    None,
}

impl ProgressMode {
    pub fn parse(text: &str) -> anyhow::Result<Self> {
        match text.to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "json" => Ok(Self::Json),
            "none" => Ok(Self::None),
            _ => bail!("--progress '{text}' is not one of auto, json, none"),
        }
    }
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
        let args = ffmpeg_args(&spec, Path::new("out.mp4.partial.mp4"));
        let joined = args.join(" ");
        assert!(
            joined.contains("-s 640x360 -framerate 25 -i pipe:0"),
            "{joined}"
        );
        assert!(
            joined.contains("-ss 1.500000 -t 2.000000 -i song.flac"),
            "{joined}"
        );
        assert!(joined.contains("-pix_fmt yuv420p"), "{joined}");
        assert!(joined.contains("-movflags +faststart"), "{joined}");
        assert_eq!(args.last().map(String::as_str), Some("out.mp4.partial.mp4"));
        let silent = ffmpeg_args(
            &EncodeSpec {
                sound: Sound::Silence,
                ..spec
            },
            Path::new("o.mp4"),
        )
        .join(" ");
        assert!(
            silent.contains("-f lavfi -t 2.000000 -i anullsrc"),
            "{silent}"
        );
    }
}
