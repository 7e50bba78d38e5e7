//! The cloud cache: one PLY per (audio content, extraction settings), named by a SHA-256 of the
//! audio's bytes and the settings, in `$LOUDSCAPE_CACHE_DIR`, else `$XDG_CACHE_HOME/loudscape/
//! clouds`, else `~/.cache/loudscape/clouds` (beside the extractor's own timeline cache). A
//! renamed or moved song still hits; an edited one misses. The extractor writes each file
//! atomically, so a file in the cache is always whole. The file's name carries the extractor's
//! version too (`KEY-VERSIONHASH.ply`, `version.rs`): a new extractor writes new clouds instead
//! of reusing an older one's; where no extractor can be found at all, the newest cloud of the
//! song under these settings still opens (a cached song needs no Python).

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use super::{ExtractError, Settings};

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
