//! The cloud cache: one PLY per (audio content, extraction settings), named by a SHA-256 of the
//! audio's bytes and the settings, in `$LOUDSCAPE_CACHE_DIR`, else `$XDG_CACHE_HOME/loudscape/
//! clouds`, else `~/.cache/loudscape/clouds` (beside the extractor's own timeline cache). A
//! renamed or moved song still hits; an edited one misses. Each cloud `NAME.ply` has a checksum
//! file beside it, `NAME.ply.sum` (JSON: the cloud's SHA-256 and length, and the warnings the
//! extractor printed): a cloud is used only when it matches it and loads ([`load_checked`]);
//! anything else is extracted again and replaced. A cloud without a checksum file is never
//! trusted (nothing vouches for its bytes: it is extracted again). Both files are written under
//! names of the writer's own (in its private `.extract-PID-N` folder), fsynced, then renamed into
//! place, the cloud first, while the writer holds the cache folder's lock ([`FolderLock`]);
//! readers verify a pair under the same lock, shared, so several processes storing the same song
//! at once leave the last one's pair whole and a reader never takes a new cloud with an old
//! checksum (on Windows, where the folder cannot be locked, such a mix fails its check and is
//! extracted again). The file's name carries the extractor's
//! version too (`KEY-VERSIONHASH.ply`, `version.rs`): a new extractor writes new clouds instead
//! of reusing an older one's; where no extractor can be found at all, the newest cloud of the
//! song under these settings still opens (a cached song needs no Python).

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::{ExtractError, Settings};
use crate::data::cloud::{CloudWarning, PointCloud};
use crate::files::sync_parent;

/// The checksum file of a cached cloud (`NAME.ply.sum`).
pub fn sum_path(ply: &Path) -> PathBuf {
    let mut name = ply.file_name().unwrap_or_default().to_os_string();
    name.push(".sum");
    ply.with_file_name(name)
}

/// What a checksum file holds.
#[derive(Debug, Default, PartialEq, Serialize, Deserialize)]
struct Sum {
    /// SHA-256 of the cloud file, hex.
    sha256: String,
    /// The cloud file's length in bytes.
    bytes: u64,
    /// Warnings the extractor printed (without the audio's path) that its metadata may lack.
    #[serde(default)]
    said: Vec<String>,
}

/// Largest checksum file read (it holds a hash and a few warning lines).
const MAX_SUM_BYTES: u64 = 1 << 20;

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// A reader that hashes and counts what passes through it.
struct Hashing<R> {
    inner: R,
    hasher: Sha256,
    bytes: u64,
}

impl<R: Read> Read for Hashing<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.hasher.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
}

/// Loads `ply` (a cloud file) while hashing it: the cloud and the SHA-256 and length of all the
/// file's bytes.
fn load_hashing(ply: &Path) -> Result<(PointCloud, String, u64), String> {
    let file = File::open(ply).map_err(|e| format!("cannot open it: {e}"))?;
    let len = file
        .metadata()
        .map_err(|e| format!("cannot read it: {e}"))?
        .len();
    let mut reader = Hashing {
        inner: file,
        hasher: Sha256::new(),
        bytes: 0,
    };
    let cloud = crate::data::cloud::load_from_reader(&mut reader, ply, Some(len))
        .map_err(|e| e.to_string())?;
    std::io::copy(&mut reader, &mut std::io::sink()).map_err(|e| format!("cannot read it: {e}"))?;
    let digest = hex(&reader.hasher.finalize());
    Ok((cloud, digest, reader.bytes))
}

/// Adds the warnings the extractor printed to those of the cloud's metadata (each once).
pub fn add_said(cloud: &mut PointCloud, said: &[String]) {
    for message in said {
        if !cloud.meta.warnings.iter().any(|w| &w.message == message) {
            cloud.meta.warnings.push(CloudWarning {
                kind: "extractor".into(),
                message: message.clone(),
                path: None,
            });
        }
    }
}

/// Why a cached cloud is not used.
#[derive(Debug, PartialEq)]
pub enum Unusable {
    /// No checksum file vouches for its bytes (a writer killed between its two renames, or one
    /// removed by hand): it is extracted again, and no checksum is made for it.
    NoSum,
    /// Its bytes differ from its checksum, or it does not load; the reason.
    Damaged(String),
}

impl std::fmt::Display for Unusable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unusable::NoSum => write!(f, "it has no checksum file to check it against"),
            Unusable::Damaged(reason) => write!(f, "{reason}"),
        }
    }
}

/// A lock on the cache folder itself (no file of its own is left in the cache): exclusive while
/// a writer puts a cloud and its checksum file in place or a damaged pair is removed, shared
/// while a reader verifies a pair. Released when dropped. Best effort: where the folder cannot be
/// opened or locked (Windows opens no folder as a file), nothing is held, and a reader that meets
/// a new cloud with an old checksum finds them unequal and extracts again.
pub struct FolderLock {
    _folder: Option<File>,
}

impl FolderLock {
    pub fn shared(dir: &Path) -> FolderLock {
        FolderLock::take(dir, false)
    }

    pub fn exclusive(dir: &Path) -> FolderLock {
        FolderLock::take(dir, true)
    }

    fn take(dir: &Path, exclusive: bool) -> FolderLock {
        let Ok(folder) = File::open(dir) else {
            return FolderLock { _folder: None };
        };
        let locked = if exclusive {
            folder.lock()
        } else {
            folder.lock_shared()
        };
        FolderLock {
            _folder: locked.ok().map(|()| folder),
        }
    }
}

/// The folder a cache file lies in.
fn folder_of(ply: &Path) -> &Path {
    match ply.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// Loads the cached cloud `ply` if it is whole: its checksum file matches its bytes and the
/// loader accepts it (the caller holds the folder's lock: see [`FolderLock`]). The extractor's
/// printed warnings recorded beside it are added to the cloud's.
/// Errors: why it cannot be used: no checksum file, or its bytes differ from it, or it does not
/// load. Nothing is written, whatever the answer.
pub fn load_checked(ply: &Path) -> Result<PointCloud, Unusable> {
    let sum_file = sum_path(ply);
    let damaged = Unusable::Damaged;
    let recorded = match File::open(&sum_file) {
        Ok(file) => {
            let mut text = String::new();
            file.take(MAX_SUM_BYTES)
                .read_to_string(&mut text)
                .map_err(|e| damaged(format!("its checksum file cannot be read: {e}")))?;
            serde_json::from_str::<Sum>(&text)
                .map_err(|e| damaged(format!("its checksum file is damaged: {e}")))?
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(Unusable::NoSum),
        Err(e) => {
            return Err(damaged(format!("its checksum file cannot be read: {e}")));
        }
    };
    // The checksum speaks first: a damaged file is reported as such, whatever the loader says.
    let (mut cloud, sha256, bytes) = match load_hashing(ply) {
        Ok(done) => done,
        Err(reason) => {
            let actual = std::fs::metadata(ply).map(|m| m.len()).unwrap_or(0);
            return Err(damaged(if actual != recorded.bytes {
                format!(
                    "{actual} bytes where its checksum file says {} ({reason})",
                    recorded.bytes
                )
            } else {
                reason
            }));
        }
    };
    if bytes != recorded.bytes || sha256 != recorded.sha256 {
        return Err(damaged(format!(
            "its content does not match its checksum ({bytes} bytes, SHA-256 {}..., recorded {} \
             bytes, {}...)",
            &sha256[..12],
            recorded.bytes,
            recorded.sha256.get(..12).unwrap_or(&recorded.sha256)
        )));
    }
    add_said(&mut cloud, &recorded.said);
    Ok(cloud)
}

/// Writes the checksum file of a cloud to `path` (a new name in the writer's private folder),
/// fsynced.
fn write_sum(path: &Path, sha256: &str, bytes: u64, said: &[String]) -> std::io::Result<()> {
    let sum = Sum {
        sha256: sha256.to_string(),
        bytes,
        said: said.to_vec(),
    };
    let text = serde_json::to_string(&sum).map_err(std::io::Error::other)?;
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)?;
    std::io::Write::write_all(&mut file, text.as_bytes())?;
    file.sync_all()
}

/// Checks a freshly extracted cloud `partial` (it loads) and returns it with the extractor's
/// printed warnings added; see [`store`] to keep it.
pub fn load_fresh(partial: &Path, said: &[String]) -> Result<(PointCloud, String, u64), String> {
    let (mut cloud, sha256, bytes) = load_hashing(partial)?;
    add_said(&mut cloud, said);
    Ok((cloud, sha256, bytes))
}

/// Moves a checked cloud `partial` (in the writer's private folder beside the cache, same file
/// system) to `ply` with its checksum file: both written and fsynced under their names in that
/// folder, then, holding the cache folder's lock, the cloud renamed into place and then its
/// checksum file, then the folder fsynced. Whoever renames last leaves a whole pair; where the
/// second rename fails, the cloud just put there is taken away again (under the lock), so no
/// cloud stays beside a checksum that is not its own.
pub fn store(
    partial: &Path,
    ply: &Path,
    sha256: &str,
    bytes: u64,
    said: &[String],
) -> std::io::Result<()> {
    File::open(partial)?.sync_all()?;
    let sum_temporary = sum_path(partial);
    write_sum(&sum_temporary, sha256, bytes, said)?;
    let _lock = FolderLock::exclusive(folder_of(ply));
    std::fs::rename(partial, ply)?;
    if let Err(e) = std::fs::rename(&sum_temporary, sum_path(ply)) {
        remove(ply);
        return Err(e);
    }
    sync_parent(ply);
    Ok(())
}

/// Removes a damaged cloud and its checksum file.
pub fn remove(ply: &Path) {
    let _ = std::fs::remove_file(ply);
    let _ = std::fs::remove_file(sum_path(ply));
}

/// Bumped when what the key covers changes meaning (a new extractor output, say).
const KEY_VERSION: &str = "loudscape-cloud-cache 2";

/// The cache folder (not created here).
pub fn dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("LOUDSCAPE_CACHE_DIR").filter(|d| !d.is_empty()) {
        return PathBuf::from(dir);
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    base.join("loudscape").join("clouds")
}

/// The cloud file of `key` written by the extractor of `extractor_version`:
/// `KEY-VERSIONHASH.ply`, 16 hex digits of the version's SHA-256.
pub fn file_name(key: &str, extractor_version: &str) -> String {
    let version: String = Sha256::digest(extractor_version.as_bytes())
        .iter()
        .take(8)
        .map(|b| format!("{b:02x}"))
        .collect();
    format!("{key}-{version}.ply")
}

/// The newest cloud of `key` in `dir` by any extractor (when none can be found to ask).
pub fn newest_of_any_version(dir: &Path, key: &str) -> Option<PathBuf> {
    let prefix = format!("{key}-");
    std::fs::read_dir(dir)
        .ok()?
        .flatten()
        .filter(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.starts_with(&prefix) && name.ends_with(".ply") && !name.contains(".partial-")
        })
        .filter_map(|e| Some((e.metadata().ok()?.modified().ok()?, e.path())))
        .max()
        .map(|(_, path)| path)
}

/// The cache key of `audio` under `settings`: hex SHA-256 of the key version, the settings'
/// flags and the file's bytes (the extractor's version goes into the file name:
/// [`file_name`]).
pub fn key(audio: &Path, settings: &Settings) -> Result<String, ExtractError> {
    let io = |e: std::io::Error| ExtractError::Io {
        path: audio.to_owned(),
        reason: format!("cannot read the audio file: {e}"),
    };
    let mut file = File::open(audio).map_err(io)?;
    if file.metadata().map_err(io)?.is_dir() {
        return Err(ExtractError::Io {
            path: audio.to_owned(),
            reason: "is a folder, not an audio file".into(),
        });
    }
    let mut hasher = Sha256::new();
    hasher.update(KEY_VERSION.as_bytes());
    hasher.update([0]);
    for arg in settings.arguments() {
        hasher.update(arg.as_bytes());
        hasher.update([0]);
    }
    let mut buffer = vec![0u8; 1 << 20];
    loop {
        let n = file.read(&mut buffer).map_err(io)?;
        if n == 0 {
            break;
        }
        hasher.update(&buffer[..n]);
    }
    Ok(hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_follows_content_settings_and_extractor_not_the_name() {
        let dir = std::env::temp_dir().join(format!("loudscape-cache-key-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b, c) = (dir.join("a.wav"), dir.join("b.wav"), dir.join("c.wav"));
        std::fs::write(&a, b"some audio bytes").unwrap();
        std::fs::write(&b, b"some audio bytes").unwrap();
        std::fs::write(&c, b"other audio bytes").unwrap();
        let settings = Settings::default();
        let key_a = key(&a, &settings).unwrap();
        assert_eq!(key_a.len(), 64);
        assert_eq!(key_a, key(&b, &settings).unwrap());
        assert_ne!(key_a, key(&c, &settings).unwrap());
        let (old, new) = (file_name(&key_a, "0.1.0"), file_name(&key_a, "0.1.1"));
        assert_ne!(old, new, "a new extractor, a new cloud");
        assert!(
            old.starts_with(&key_a) && old.len() == 64 + 1 + 16 + 4,
            "{old}"
        );
        assert_eq!(newest_of_any_version(&dir, &key_a), None);
        std::fs::write(dir.join(&old), b"ply").unwrap();
        assert_eq!(newest_of_any_version(&dir, &key_a), Some(dir.join(&old)));
        let log = Settings {
            freq_scale: "log".into(),
            ..Settings::default()
        };
        assert_ne!(key_a, key(&a, &log).unwrap());
        for changed in [
            Settings {
                n_fft: 4096,
                ..Settings::default()
            },
            Settings {
                floor_db: Some(60.0),
                ..Settings::default()
            },
        ] {
            assert_ne!(key_a, key(&a, &changed).unwrap(), "{changed:?}");
        }
        assert!(key(&dir, &settings).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
