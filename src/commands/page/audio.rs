//! `loudscape page --audio`: the song's sound in the page, Opus in WebM encoded by ffmpeg (the
//! `ffmpeg` command `loudscape video` encodes its sound track with), base64 in the page, where
//! the page's script plays it with a play button, a playhead and click-to-seek.
//!
//! The sound is the source audio the cloud was made from, checked against the cloud
//! ([`checked_source`]), or the input itself when it is an audio file. Its bitrate is the
//! highest up to [`MAX_KBPS`] that keeps it within [`AUDIO_BUDGET_BYTES`] of the page; a song
//! too long for [`MIN_KBPS`] is refused. ffmpeg writes a temporary file (WebM needs a seekable
//! output for its duration and cues, which seeking in the browser reads), removed on every path.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{Context, bail};

use loudscape::data::cloud::PointCloud;
use loudscape::playback::source::{SourceError, checked_source, ffmpeg_path, ffmpeg_url};

/// What the sound may add to a page (base64 included): a page with audio stays under 20 MB,
/// the 12 MB of a page without it plus this (issue 38).
pub const AUDIO_BUDGET_BYTES: usize = 8_000_000;
/// The bitrate of a song that fits easily: transparent Opus for music at 96 kbit/s stereo.
pub const MAX_KBPS: u32 = 96;
/// Below this, music is no longer worth hearing: a longer song is refused.
pub const MIN_KBPS: u32 = 16;
/// WebM's own bytes (headers, cues, block headers), reckoned generously.
const CONTAINER_SHARE: f64 = 0.05;

/// The song's sound, encoded for the page.
pub struct PageAudio {
    /// The WebM file's bytes.
    pub webm: Vec<u8>,
    pub kbps: u32,
}

/// The bitrate for a song of `duration_s` seconds: the most, up to [`MAX_KBPS`], whose file in
/// base64 fits [`AUDIO_BUDGET_BYTES`]; None when even [`MIN_KBPS`] does not.
pub fn kbps_for(duration_s: f64) -> Option<u32> {
    let raw_bytes = AUDIO_BUDGET_BYTES as f64 * 3.0 / 4.0 * (1.0 - CONTAINER_SHARE);
    let kbps = (raw_bytes * 8.0 / 1000.0 / duration_s.max(1.0)).floor();
    let kbps = kbps.min(f64::from(MAX_KBPS)) as u32;
    (kbps >= MIN_KBPS).then_some(kbps)
}

/// The audio file of `input`: the input itself when it is audio, else the cloud's checked
/// source; one line saying why not, with the way out (leave out `--audio`).
pub fn song_sound(input: &Path, cloud: &PointCloud) -> anyhow::Result<PathBuf> {
    if loudscape::extract::is_audio(input) {
        return Ok(input.to_path_buf());
    }
    let without = "leave out --audio for a page without the song's sound";
    checked_source(cloud).map_err(|e| match e {
        SourceError::Mismatch { .. } => anyhow::anyhow!(
            "{}: {e}; {without}, or extract the cloud again from that audio",
            input.display()
        ),
        _ => anyhow::anyhow!("{}: {e}; {without}", input.display()),
    })
}

/// A file removed when dropped (every way out of [`encode`]).
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// `source` encoded as Opus in WebM at the bitrate a song of `duration_s` seconds gets.
pub fn encode(source: &Path, duration_s: f64) -> anyhow::Result<PageAudio> {
    let Some(kbps) = kbps_for(duration_s) else {
        bail!(
            "{}: the song is {:.0} minutes long, too long for the page's {} MB of audio at \
             {MIN_KBPS} kbit/s; leave out --audio",
            source.display(),
            duration_s / 60.0,
            AUDIO_BUDGET_BYTES / 1_000_000
        );
    };
    let ffmpeg = ffmpeg_path().with_context(|| {
        "ffmpeg is not installed (not found on PATH); `loudscape page --audio` encodes the \
         sound with it: install it (Debian and Ubuntu: apt install ffmpeg; macOS: brew install \
         ffmpeg), or leave out --audio"
    })?;
    let scratch = Scratch(std::env::temp_dir().join(format!(
        "loudscape-page-{}-{}.webm",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos())
    )));
    let output = Command::new(&ffmpeg)
        .args([
            "-nostdin",
            "-hide_banner",
            "-nostats",
            "-loglevel",
            "error",
            "-y",
        ])
        .arg("-i")
        .arg(ffmpeg_url(source))
        .args(["-map", "0:a:0", "-vn", "-c:a", "libopus", "-b:a"])
        .arg(format!("{kbps}k"))
        .args(["-f", "webm"])
        .arg(ffmpeg_url(&scratch.0))
        .stdin(Stdio::null())
        .output()
        .with_context(|| format!("cannot start {}", ffmpeg.display()))?;
    if !output.status.success() {
        let said = String::from_utf8_lossy(&output.stderr);
        let said = said
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        bail!(
            "{}: ffmpeg could not encode the sound ({}): {said}",
            source.display(),
            output.status
        );
    }
    let webm = std::fs::read(&scratch.0)
        .with_context(|| format!("{}: cannot read ffmpeg's output", scratch.0.display()))?;
    Ok(PageAudio { webm, kbps })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_three_minute_song_gets_the_full_bitrate_and_a_long_one_less() {
        assert_eq!(kbps_for(180.0), Some(MAX_KBPS));
        let half_hour = kbps_for(1800.0).expect("half an hour fits");
        assert!((MIN_KBPS..MAX_KBPS).contains(&half_hour), "{half_hour}");
        // What the bitrate gives, in base64 with the container, stays in the budget.
        let bytes = |kbps: u32, s: f64| f64::from(kbps) * 1000.0 / 8.0 * s * 1.05 * 4.0 / 3.0;
        assert!(bytes(half_hour, 1800.0) <= AUDIO_BUDGET_BYTES as f64);
        assert_eq!(kbps_for(3600.0), None);
    }
}
