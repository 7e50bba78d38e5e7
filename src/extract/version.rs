//! Which extractor made a cloud: its version is part of the cache key, so that a new extractor
//! (new analysis, new file layout) never reuses clouds an older one wrote. Asking the extractor
//! (`loudscape-extract --version`) starts Python and imports the analysis, seconds on a busy
//! machine, which a reopen from the cache must not wait for; so the version is read first from
//! the package's installed metadata beside the script (`VENV/bin/loudscape-extract` ->
//! `VENV/lib/python*/site-packages/loudscape_extract-*.dist-info/METADATA`, the file pip writes
//! from `preprocess/pyproject.toml`, kept equal to `loudscape_extract.version.__version__` by a
//! Python test), and only when there is none by running it, once a process.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

/// The extractor to run and its version.
#[derive(Clone, Debug, PartialEq)]
pub struct Extractor {
    pub path: PathBuf,
    /// As `loudscape-extract --version` prints it, without the name: `0.1.0`.
    pub version: String,
}

/// `Version: X` of a `METADATA` (or `PKG-INFO`) text.
pub fn parse_metadata(text: &str) -> Option<String> {
    text.lines()
        .take_while(|line| !line.is_empty())
        .find_map(|line| line.strip_prefix("Version:"))
        .map(|v| v.trim().to_string())
        .filter(|v| !v.is_empty())
}

/// The version in `loudscape-extract --version`'s answer (`loudscape-extract 0.1.0`).
pub fn parse_version_line(text: &str) -> Option<String> {
    let line = text.lines().find(|l| !l.trim().is_empty())?;
    let version = line.trim().rsplit(' ').next()?;
    version
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_digit())
        .then(|| version.to_string())
}

/// The installed package's version, from the metadata of the environment the script is in.
pub fn from_installed_metadata(script: &Path) -> Option<String> {
    // The script is VENV/bin/NAME (VENV/Scripts/NAME on Windows).
    let venv = script.parent()?.parent()?;
    let mut site_packages = vec![venv.join("Lib").join("site-packages")];
    if let Ok(entries) = std::fs::read_dir(venv.join("lib")) {
        let mut pythons: Vec<PathBuf> = entries
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with("python"))
            .map(|e| e.path().join("site-packages"))
            .collect();
        pythons.sort();
        site_packages.extend(pythons);
    }
    for dir in site_packages {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with("loudscape_extract-") && name.ends_with(".dist-info") {
                let text = std::fs::read_to_string(entry.path().join("METADATA"));
                if let Some(version) = text.ok().as_deref().and_then(parse_metadata) {
                    return Some(version);
                }
            }
        }
    }
    None
}

/// The version of the extractor at `path`: its installed metadata, else its own answer to
/// `--version` (asked once a process).
pub fn of(path: &Path) -> Result<String, String> {
    if let Some(version) = from_installed_metadata(path) {
        return Ok(version);
    }
    static ASKED: OnceLock<Mutex<HashMap<PathBuf, String>>> = OnceLock::new();
    let asked = ASKED.get_or_init(Default::default);
    if let Some(version) = asked.lock().ok().and_then(|m| m.get(path).cloned()) {
        return Ok(version);
    }
    let output = std::process::Command::new(path)
        .arg("--version")
        .stdin(std::process::Stdio::null())
        .output()
        .map_err(|e| format!("cannot start {}: {e}", path.display()))?;
    let text = String::from_utf8_lossy(&output.stdout);
    let version = parse_version_line(&text)
        .filter(|_| output.status.success())
        .ok_or_else(|| {
            format!(
                "{} --version did not say its version ({})",
                path.display(),
                text.trim()
            )
        })?;
    if let Ok(mut map) = asked.lock() {
        map.insert(path.to_owned(), version.clone());
    }
    Ok(version)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_parse() {
        let metadata = "Metadata-Version: 2.4\nName: loudscape-extract\nVersion: 0.2.0\n\
                        Summary: x\n\nVersion: 9 (in the description)\n";
        assert_eq!(parse_metadata(metadata).as_deref(), Some("0.2.0"));
        assert_eq!(parse_metadata("Name: x\n"), None);
        assert_eq!(
            parse_version_line("loudscape-extract 0.1.0\n").as_deref(),
            Some("0.1.0")
        );
        assert_eq!(parse_version_line("usage: loudscape-extract"), None);
    }

    #[test]
    fn the_version_is_read_from_the_venv_beside_the_script() {
        let venv = std::env::temp_dir().join(format!("loudscape-version-{}", std::process::id()));
        let info = venv.join("lib/python3.12/site-packages/loudscape_extract-0.3.1.dist-info");
        std::fs::create_dir_all(&info).unwrap();
        std::fs::create_dir_all(venv.join("bin")).unwrap();
        std::fs::write(
            info.join("METADATA"),
            "Name: loudscape-extract\nVersion: 0.3.1\n",
        )
        .unwrap();
        let script = venv.join("bin/loudscape-extract");
        std::fs::write(&script, "#!/bin/sh\nexit 1\n").unwrap();
        assert_eq!(from_installed_metadata(&script).as_deref(), Some("0.3.1"));
        assert_eq!(of(&script).as_deref(), Ok("0.3.1"));
        std::fs::remove_dir_all(&venv).unwrap();
        assert_eq!(from_installed_metadata(&script), None);
    }
}
