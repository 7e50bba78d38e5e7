//! The checked source of a cloud: the audio file it records ([`super::resolve_source`]), as
//! long as it is the audio the cloud was made from. The extractor records no hash of the
//! audio, so the file's sample rate, channels and length are held against the cloud's
//! (read as playback reads them, else by ffprobe for the formats only ffmpeg reads). Every
//! command and view that uses a cloud's audio (its video's sound, a comparison, an alignment)
//! takes it from [`checked_source`], so a source replaced by another song is refused in one
//! line, never silently used.
//!
//! Also where ffmpeg is ([`ffmpeg_path`]) and how a path is handed to it ([`ffmpeg_url`]).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use thiserror::Error;

use super::PlaybackError;
use crate::data::cloud::PointCloud;

/// How far the source's length may be from the cloud's: MP3 decoders differ by the encoder's
/// delay and padding (under 4,096 frames), and the length is written rounded.
const LENGTH_TOLERANCE_FRAMES: f64 = 4096.0;

/// Why a cloud's recorded source cannot be used as its audio. The messages name the source,
/// not the cloud: the caller puts the cloud's name in front and its way out behind.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SourceError {
    /// No file is found where the cloud says (or the cloud names none).
    #[error("its source audio: {0}")]
    NotFound(PlaybackError),
    /// The file is there but cannot be read to hold it against the cloud.
    #[error("cannot check its source audio {} against the cloud ({why})", path.display())]
    Unchecked { path: PathBuf, why: String },
    /// The cloud records no length to hold the file against.
    #[error(
        "the cloud records no length of its source audio {} to check it by",
        path.display()
    )]
    NoLength { path: PathBuf },
    /// The file is another audio than the cloud's (`why`: what differs).
    #[error(
        "its source audio {} is not the audio the cloud was made from ({why})",
        path.display()
    )]
    Mismatch { path: PathBuf, why: String },
}

/// The audio file `cloud` was made from: its recorded source, found as playback finds it
/// ([`super::resolve_source`]) and checked against the cloud: sample rate, channels and length
/// must be the ones the cloud was made from (a truncated or corrupt source, decoded as far as
/// it went, may be longer than the cloud says).
pub fn checked_source(cloud: &PointCloud) -> Result<PathBuf, SourceError> {
    let path = super::resolve_source(cloud).map_err(SourceError::NotFound)?;
    // resolve_source finds a file only where the cloud records a source.
    let recorded = cloud.meta.source.as_ref();
    let found = probe_audio(&path).map_err(|why| SourceError::Unchecked {
        path: path.clone(),
        why,
    })?;
    let mismatch = |why: String| SourceError::Mismatch {
        path: path.clone(),
        why,
    };
    if let Some(rate) = recorded.and_then(|r| r.sample_rate)
        && rate != found.sample_rate
    {
        return Err(mismatch(format!(
            "{} Hz, the cloud's {rate} Hz",
            found.sample_rate
        )));
    }
    if let (Some(channels), Some(found_channels)) =
        (recorded.and_then(|r| r.channels), found.channels)
        && channels != found_channels
    {
        return Err(mismatch(format!(
            "{found_channels} channels, the cloud's {channels}"
        )));
    }
    let Some(length) = recorded
        .and_then(|r| r.duration_s)
        .filter(|d| d.is_finite() && *d > 0.0)
    else {
        return Err(SourceError::NoLength { path });
    };
    let tolerance = LENGTH_TOLERANCE_FRAMES / f64::from(found.sample_rate.max(1)) + 0.001;
    // A truncated or corrupt source was decoded as far as it goes: its header promises more.
    let cut_short = cloud
        .warnings()
        .iter()
        .any(|w| w.kind == "truncated" || w.kind == "corrupt");
    let fits = if cut_short {
        found.duration_s >= length - tolerance
    } else {
        (found.duration_s - length).abs() <= tolerance
    };
    if !fits {
        return Err(mismatch(format!(
            "{:.3} s long, the cloud's {length:.3} s",
            found.duration_s
        )));
    }
    Ok(path)
}

/// What [`probe_audio`] reads of an audio file.
struct AudioFacts {
    sample_rate: u32,
    channels: Option<u32>,
    duration_s: f64,
}

/// The sample rate, channels and length of an audio file: read as playback reads it (WAV,
/// FLAC, Ogg Vorbis, MP3), else by ffprobe (the formats only ffmpeg reads).
fn probe_audio(path: &Path) -> Result<AudioFacts, String> {
    match super::decode(path) {
        Ok(track) => Ok(AudioFacts {
            sample_rate: track.sample_rate,
            channels: Some(u32::from(track.channels)),
            duration_s: track.duration_s(),
        }),
        Err(PlaybackError::Unsupported { .. }) => ffprobe_audio(path),
        Err(e) => Err(e.to_string()),
    }
}

/// The `ffmpeg` command: `$LOUDSCAPE_FFMPEG`, else the first on PATH; None when there is none.
pub fn ffmpeg_path() -> Option<PathBuf> {
    if let Some(path) = std::env::var_os("LOUDSCAPE_FFMPEG") {
        return Some(PathBuf::from(path));
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
}

/// `path` as ffmpeg must be given it: `file:` + the absolute path, so that no name is taken
/// for another protocol (`a:b.mp4`), an option (`-x.mp4`) or a `file:` URL of another file
/// (`file:c.ogg`); the bytes pass as they are (a name that is not UTF-8).
pub fn ffmpeg_url(path: &Path) -> OsString {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut url = OsString::from("file:");
    url.push(absolute.as_os_str());
    url
}

/// [`probe_audio`] by ffprobe (beside ffmpeg, or on PATH): the first audio stream's rate and
/// channels, and the file's length.
fn ffprobe_audio(path: &Path) -> Result<AudioFacts, String> {
    let name = if cfg!(windows) {
        "ffprobe.exe"
    } else {
        "ffprobe"
    };
    let beside = ffmpeg_path()
        .and_then(|f| f.parent().map(|d| d.join(name)))
        .filter(|p| p.is_file());
    let program = beside.unwrap_or_else(|| PathBuf::from(name));
    let output = Command::new(&program)
        .args(["-v", "error", "-select_streams", "a:0", "-show_entries"])
        .args(["stream=sample_rate,channels:format=duration", "-of", "json"])
        .arg(ffmpeg_url(path))
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("ffprobe cannot start: {e}"))?;
    let said = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        return Err(format!(
            "ffprobe: {}",
            said.lines().next().unwrap_or("it failed").trim()
        ));
    }
    let json: serde_json::Value = serde_json::from_slice(&output.stdout)
        .map_err(|e| format!("ffprobe's answer is not JSON: {e}"))?;
    let stream = &json["streams"][0];
    let number = |v: &serde_json::Value| {
        v.as_f64()
            .or_else(|| v.as_str().and_then(|s| s.trim().parse().ok()))
    };
    let sample_rate = number(&stream["sample_rate"])
        .filter(|r| *r >= 1.0 && *r <= f64::from(u32::MAX))
        .ok_or("ffprobe finds no audio stream")? as u32;
    let duration_s = number(&json["format"]["duration"])
        .filter(|d| d.is_finite() && *d > 0.0)
        .ok_or("ffprobe states no length")?;
    Ok(AudioFacts {
        sample_rate,
        channels: number(&stream["channels"]).map(|c| c as u32),
        duration_s,
    })
}
