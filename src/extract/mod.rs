//! Audio in: a song file becomes a point cloud by running the Python extractor
//! (`loudscape-extract song --progress json`) as a child process, with its progress, a way to
//! cancel, and a cache so that reopening a song is instant. The Python extractor stays the one
//! implementation of the analysis; this module only finds it ([`locate`]), drives it
//! ([`child`]) and keeps what it wrote ([`cache`]).
//!
//! [`open_any`] is the one entry point the window (argument, drop, Open button) and every
//! command that takes a cloud share: a PLY file is read as it is, anything else is taken for
//! audio.

pub mod align;
pub mod cache;
pub mod child;
pub mod lines;
pub mod locate;
pub mod preview;
pub mod timeline;
pub mod version;

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use thiserror::Error;

use crate::data::cloud::{CloudError, PointCloud};
pub use preview::PointsSoFar;
pub use version::Extractor;

/// The extraction settings that change the cloud; part of the cache key.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// STFT size (even, >= 4).
    pub n_fft: u32,
    /// STFT hop in samples.
    pub hop: u32,
    /// Drop bins more than this many dB below the loudest; `None` is the extractor's default.
    pub floor_db: Option<f32>,
    /// `"linear"` or `"log"` frequency axis.
    pub freq_scale: String,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            n_fft: 2048,
            hop: 1024,
            floor_db: None,
            freq_scale: "linear".into(),
        }
    }
}

impl Settings {
    /// The extractor's flags for these settings.
    pub fn arguments(&self) -> Vec<String> {
        let mut args = vec![
            "--n-fft".into(),
            self.n_fft.to_string(),
            "--hop".into(),
            self.hop.to_string(),
            "--freq-scale".into(),
            self.freq_scale.clone(),
        ];
        if let Some(floor) = self.floor_db {
            args.extend(["--floor-db".into(), floor.to_string()]);
        }
        args
    }
}

/// Where an extraction is: the extractor's stage and the share of the work done.
#[derive(Clone, Debug, PartialEq)]
pub struct Progress {
    pub stage: String,
    /// 0 to 1.
    pub fraction: f32,
}

/// Why audio could not become a cloud. Each names the file and the reason.
#[derive(Debug, Error)]
pub enum ExtractError {
    #[error(
        "{audio}: this is not a .ply cloud, so it was taken for audio, but {}",
        locate::not_found(.looked)
    )]
    NotFound { audio: PathBuf, looked: String },
    #[error("{path}: {reason}")]
    Io { path: PathBuf, reason: String },
    #[error("{audio}: the extractor failed: {reason}")]
    Failed { audio: PathBuf, reason: String },
    /// The input is refused before it is read (a FIFO, a device); the reason names it.
    #[error("{reason}")]
    Refused { reason: String },
    #[error("{audio}: extraction cancelled")]
    Cancelled { audio: PathBuf },
    #[error(transparent)]
    Cloud(#[from] CloudError),
}

/// What [`open_any`] opened.
pub struct Opened {
    pub cloud: PointCloud,
    /// For audio: the cached cloud file (`None` when the cache could not keep it) and whether
    /// it was already there.
    pub extracted: Option<(Option<PathBuf>, bool)>,
}

/// True unless the file is a PLY: named `.ply` (a broken one gets the PLY reader's error, not
/// the extractor's) or starting with the PLY magic `ply` whatever its name.
pub fn is_audio(path: &Path) -> bool {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"))
    {
        return false;
    }
    let mut magic = [0u8; 3];
    let read = File::open(path).and_then(|mut f| f.read_exact(&mut magic));
    !(read.is_ok() && &magic == b"ply")
}

/// Opens a cloud file, or extracts (or finds in the cache) the cloud of an audio file and opens
/// that. `on_progress` hears every stage; setting `cancel` stops the extractor.
pub fn open_any(
    path: &Path,
    settings: &Settings,
    cancel: &AtomicBool,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<Opened, ExtractError> {
    open_any_watching(path, settings, cancel, on_progress, &mut |_| {})
}

/// [`open_any`], with `on_points` hearing the points written so far while a song is
/// extracted (see [`preview`]).
pub fn open_any_watching(
    path: &Path,
    settings: &Settings,
    cancel: &AtomicBool,
    on_progress: &mut dyn FnMut(&Progress),
    on_points: &mut dyn FnMut(&PointsSoFar),
) -> Result<Opened, ExtractError> {
    // Before anything opens it: a FIFO or a device would block or never end.
    crate::files::check_regular(path).map_err(|reason| ExtractError::Refused { reason })?;
    if !is_audio(path) {
        return Ok(Opened {
            cloud: crate::data::cloud::load(path)?,
            extracted: None,
        });
    }
    let song = cloud_for_audio_watching(
        path,
        settings,
        &cache::dir(),
        || find_extractor(path),
        cancel,
        on_progress,
        on_points,
    )?;
    let mut cloud = song.cloud;
    // The song names the cloud (panel, messages, what the window remembers: reopened through
    // the cache), not the cache file's hash.
    cloud.path = path.to_owned();
    Ok(Opened {
        cloud,
        extracted: Some((song.ply, song.hit)),
    })
}

/// The cloud of a song, checked, with where it is kept.
pub struct SongCloud {
    /// Loaded and checked; its warnings hold those the extractor only printed.
    pub cloud: PointCloud,
    /// The cache file; `None` when the cache folder cannot be written (the cloud was extracted
    /// to a temporary folder, already removed).
    pub ply: Option<PathBuf>,
    /// Whether it came from the cache.
    pub hit: bool,
}

/// The cloud of `audio` under `settings`, from the cache or extracted first.
pub fn cloud_for_audio(
    audio: &Path,
    settings: &Settings,
    cancel: &AtomicBool,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<SongCloud, ExtractError> {
    cloud_for_audio_with(
        audio,
        settings,
        &cache::dir(),
        || find_extractor(audio),
        cancel,
        on_progress,
    )
}

/// The extractor (see [`locate`]) and its version (see [`version`]); errors name `audio`.
pub fn find_extractor(audio: &Path) -> Result<Extractor, ExtractError> {
    let path = locate::extractor().map_err(|looked| ExtractError::NotFound {
        audio: audio.to_owned(),
        looked,
    })?;
    let version = version::of(&path).map_err(|reason| ExtractError::Failed {
        audio: audio.to_owned(),
        reason,
    })?;
    Ok(Extractor { path, version })
}

/// The cached cloud `ply` of `audio` if it is whole ([`cache::load_checked`], under the cache
/// folder's shared lock); one that is not is removed, with one line saying why. The removal
/// holds the lock exclusively and checks the pair again first: a writer may have just put a whole
/// one in its place.
fn cached(audio: &Path, ply: &Path) -> Option<PointCloud> {
    let dir = ply.parent().unwrap_or(Path::new("."));
    {
        let _lock = cache::FolderLock::shared(dir);
        if let Ok(cloud) = cache::load_checked(ply) {
            return Some(cloud);
        }
    }
    let _lock = cache::FolderLock::exclusive(dir);
    let reason = match cache::load_checked(ply) {
        Ok(cloud) => return Some(cloud),
        Err(reason) => reason,
    };
    let what = match reason {
        cache::Unusable::NoSum => "cannot be trusted",
        cache::Unusable::Damaged(_) => "is damaged",
    };
    eprintln!(
        "loudscape: {}: the cached cloud {} {what} ({}); extracting it again",
        audio.display(),
        ply.display(),
        crate::data::cloud::one_line(&reason.to_string())
    );
    cache::remove(ply);
    None
}

/// Says once per run that the cache folder cannot be written, and why.
fn cache_not_writable(dir: &Path, reason: &dyn std::fmt::Display) {
    static SAID: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    if !SAID.swap(true, std::sync::atomic::Ordering::Relaxed) {
        eprintln!(
            "loudscape: warning: {}: cannot write the cloud cache ({}); songs are \
             extracted to a temporary folder and not kept",
            dir.display(),
            crate::data::cloud::one_line(&reason.to_string())
        );
    }
}

/// A private folder for one extraction in the system's temporary folder (the cache cannot be
/// written).
fn temporary_scratch() -> Result<crate::files::TempDir, ExtractError> {
    crate::files::TempDir::create_in(&std::env::temp_dir(), "loudscape-extract").map_err(|e| {
        ExtractError::Io {
            path: std::env::temp_dir(),
            reason: format!("cannot create a temporary folder: {e}"),
        }
    })
}

/// The extractor's reason where a failed extraction into `scratch` failed writing there (a full
/// disk, a quota): that reason names its output, which lies in `scratch`, where a failure about
/// the input names the audio.
fn failed_writing_in<'a>(error: &'a ExtractError, scratch: &Path) -> Option<&'a str> {
    match error {
        ExtractError::Failed { reason, .. } if reason.contains(&*scratch.to_string_lossy()) => {
            Some(reason)
        }
        _ => None,
    }
}

/// [`cloud_for_audio`] with the cache folder given and the extractor found by `find` (its
/// version names the cloud; it is run only on a cache miss, and where none is found the newest
/// cloud of the song under these settings opens: a cached song opens without Python). A cached
/// cloud is used only when whole (checksum and loader); a damaged one is extracted again. When
/// the cache folder cannot be written the song is extracted to a temporary folder, with one
/// warning.
pub fn cloud_for_audio_with(
    audio: &Path,
    settings: &Settings,
    dir: &Path,
    find: impl FnOnce() -> Result<Extractor, ExtractError>,
    cancel: &AtomicBool,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<SongCloud, ExtractError> {
    cloud_for_audio_watching(audio, settings, dir, find, cancel, on_progress, &mut |_| {})
}

/// [`cloud_for_audio_with`], with `on_points` hearing the points written so far while the song
/// is extracted (see [`preview`]; a cached cloud has none).
pub fn cloud_for_audio_watching(
    audio: &Path,
    settings: &Settings,
    dir: &Path,
    find: impl FnOnce() -> Result<Extractor, ExtractError>,
    cancel: &AtomicBool,
    on_progress: &mut dyn FnMut(&Progress),
    on_points: &mut dyn FnMut(&PointsSoFar),
) -> Result<SongCloud, ExtractError> {
    // The extractor gets the absolute path: it is recorded in the cloud for playback.
    let absolute = std::path::absolute(audio).unwrap_or_else(|_| audio.to_owned());
    on_progress(&Progress {
        stage: "hashing".into(),
        fraction: 0.0,
    });
    let key = cache::key(audio, settings)?;
    // What killed runs left in the cache goes first, hit or miss.
    child::remove_stale_partials(dir);
    let extractor = match find() {
        Ok(extractor) => extractor,
        // No extractor to ask for its version: the newest cloud of the song still opens.
        Err(not_found) => {
            let Some(ply) = cache::newest_of_any_version(dir, &key) else {
                return Err(not_found);
            };
            return match cached(audio, &ply) {
                Some(cloud) => Ok(SongCloud {
                    cloud,
                    ply: Some(ply),
                    hit: true,
                }),
                None => Err(not_found),
            };
        }
    };
    let ply = dir.join(cache::file_name(&key, &extractor.version));
    if ply.is_file()
        && let Some(cloud) = cached(audio, &ply)
    {
        return Ok(SongCloud {
            cloud,
            ply: Some(ply),
            hit: true,
        });
    }
    // A private folder in the cache (same file system: the cloud is renamed into place), or,
    // where the cache cannot be written, in the system's temporary folder.
    let in_cache = std::fs::create_dir_all(dir)
        .and_then(|()| crate::files::TempDir::create_in(dir, child::SCRATCH_PREFIX));
    let (mut scratch, mut keep) = match in_cache {
        Ok(scratch) => (scratch, true),
        Err(reason) => {
            cache_not_writable(dir, &reason);
            (temporary_scratch()?, false)
        }
    };
    let mut extract_in = |scratch: &Path| {
        child::run(
            &extractor.path,
            &absolute,
            audio,
            scratch,
            settings,
            cancel,
            &mut *on_progress,
            &mut *on_points,
        )
    };
    let mut extracted = extract_in(scratch.path());
    // No room in the cache folder (a full disk): the cache stops nothing, the song is
    // extracted again in the temporary folder.
    if keep
        && let Err(error) = &extracted
        && let Some(reason) = failed_writing_in(error, scratch.path())
    {
        cache_not_writable(dir, &reason);
        drop(scratch);
        scratch = temporary_scratch()?;
        keep = false;
        extracted = extract_in(scratch.path());
    }
    let (partial, said) = extracted?;
    let (cloud, sha256, bytes) =
        cache::load_fresh(&partial, &said).map_err(|reason| ExtractError::Failed {
            audio: audio.to_owned(),
            reason: format!("it wrote a cloud that does not load: {reason}"),
        })?;
    let ply = match keep {
        true => match cache::store(&partial, &ply, &sha256, bytes, &said) {
            Ok(()) => Some(ply),
            Err(reason) => {
                cache_not_writable(dir, &reason);
                None
            }
        },
        false => None,
    };
    Ok(SongCloud {
        cloud,
        ply,
        hit: false,
    })
}

/// [`open_any`] with default settings for the command line: progress lines (see
/// [`open_reporting`]) only when stderr is a terminal, as the extractor does, so that scripts
/// see one line on failure and nothing on success.
pub fn open_for_command(path: &Path) -> Result<PointCloud, ExtractError> {
    use std::io::IsTerminal;
    let verbose = std::io::stderr().is_terminal();
    let cancel = AtomicBool::new(false);
    open_reporting(path, &Settings::default(), &cancel, verbose, &mut |_| {})
}

/// [`open_any`] telling stderr about it when `verbose`: one line a stage, and for audio where
/// the cloud came from (extracted, or from the cache); `also` hears every progress report.
/// The cloud's warnings are always said, one `warning: FILE: MESSAGE` line each.
pub fn open_reporting(
    path: &Path,
    settings: &Settings,
    cancel: &AtomicBool,
    verbose: bool,
    also: &mut dyn FnMut(&Progress),
) -> Result<PointCloud, ExtractError> {
    open_reporting_watching(path, settings, cancel, verbose, also, &mut |_| {})
}

/// [`open_reporting`], with `on_points` hearing the points written so far while a song is
/// extracted (the window shows them: see [`preview`]).
pub fn open_reporting_watching(
    path: &Path,
    settings: &Settings,
    cancel: &AtomicBool,
    verbose: bool,
    also: &mut dyn FnMut(&Progress),
    on_points: &mut dyn FnMut(&PointsSoFar),
) -> Result<PointCloud, ExtractError> {
    let name = path.display().to_string();
    let start = std::time::Instant::now();
    let mut last_stage = String::new();
    let mut report = |progress: &Progress| {
        also(progress);
        // Hashing is local and quick; stderr hears only the extractor's stages.
        if verbose && progress.stage != last_stage && progress.stage != "hashing" {
            eprintln!(
                "loudscape: {name}: {} ({:.0}%)",
                progress.stage,
                progress.fraction * 100.0
            );
            last_stage.clone_from(&progress.stage);
        }
    };
    let opened = open_any_watching(path, settings, cancel, &mut report, on_points)?;
    if let Some((ply, hit)) = opened.extracted.as_ref().filter(|_| verbose) {
        let how = if *hit { "from the cache" } else { "extracted" };
        let seconds = start.elapsed().as_secs_f32();
        let kept = match ply {
            Some(ply) => ply.display().to_string(),
            None => "not cached".into(),
        };
        eprintln!("loudscape: {name}: cloud {how} in {seconds:.2} s: {kept}");
    }
    // What the extractor found wrong or odd in the input, fresh or cached, always said.
    for line in opened.cloud.warning_lines() {
        eprintln!("{line}");
    }
    Ok(opened.cloud)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ply_by_magic_audio_otherwise() {
        let dir = std::env::temp_dir().join(format!("loudscape-is-audio-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cloud = dir.join("named-like-audio.ogg");
        std::fs::write(&cloud, b"ply\nformat binary_little_endian 1.0\n").unwrap();
        let audio = dir.join("song.ply.wav");
        std::fs::write(&audio, b"RIFF....WAVE").unwrap();
        let broken = dir.join("broken.PLY");
        std::fs::write(&broken, b"hello world\n").unwrap();
        assert!(!is_audio(&cloud));
        assert!(is_audio(&audio));
        assert!(!is_audio(&broken));
        assert!(!is_audio(&dir.join("missing.ply")));
        assert!(is_audio(&dir.join("missing.flac")));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn settings_become_flags() {
        let mut settings = Settings::default();
        assert!(!settings.arguments().contains(&"--floor-db".to_string()));
        settings.floor_db = Some(60.0);
        let args = settings.arguments();
        assert_eq!(
            args[args.len() - 2..],
            ["--floor-db".to_string(), "60".into()]
        );
    }
}
