//! Recent files: the songs, clouds and folders the window opened, newest first, kept in
//! `recent.json` in the state folder (`$LOUDSCAPE_STATE_DIR`, else `$XDG_STATE_HOME/loudscape`,
//! else `~/.local/state/loudscape`) as soon as each opens, so the list survives a crash as well
//! as a restart. The Open panel lists them; one that is no longer there is shown as missing and
//! cannot be clicked. Scripted screenshot runs keep no list unless `$LOUDSCAPE_STATE_DIR` names
//! one (tests). A timeline built in the window from a folder is listed once, by its folder,
//! whether it was opened as the folder or as its cloud in the cache (a restored session); one
//! listed by its cloud keeps the name it had when it was open (`folder/ (timeline)`), so it is
//! not a cache file's name when it is not loaded. `recent.json` stays a JSON list of paths;
//! the names are in `recent-names.json` beside it (pairs of path and name).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How many files the list keeps.
pub(super) const MAX_RECENT: usize = 10;
/// How often the panel looks again whether the files are still there.
const RECHECK: Duration = Duration::from_secs(2);

/// The recent-files list and where it is kept.
#[derive(Default)]
pub(super) struct RecentFiles {
    /// Newest first.
    pub(super) files: Vec<PathBuf>,
    /// Whether each file (or folder) was there when last looked at.
    present: Vec<bool>,
    /// The names given to some of them (a timeline built in the window: its cloud's own file
    /// name says nothing).
    names: Vec<(PathBuf, String)>,
    checked: Option<Instant>,
    /// The list's file; `None`: not kept (a scripted run).
    store: Option<PathBuf>,
}

/// The state folder's `recent.json`.
pub(super) fn default_store() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("LOUDSCAPE_STATE_DIR").filter(|d| !d.is_empty()) {
        return Some(PathBuf::from(dir).join("recent.json"));
    }
    let base = std::env::var_os("XDG_STATE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local").join("state"))
        })?;
    Some(base.join("loudscape").join("recent.json"))
}

/// Where the names of `store`'s entries are kept: `recent-names.json` beside it.
fn names_store(store: &Path) -> PathBuf {
    store.with_file_name("recent-names.json")
}

/// Writes `value` as JSON to `path`: beside it, then renamed (never half a file).
fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let fail = |e: std::io::Error| format!("{}: cannot keep the recent files: {e}", path.display());
    let text = serde_json::to_vec_pretty(value).map_err(|e| e.to_string())?;
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(fail)?;
    }
    let temporary = path.with_extension(format!("json.{}.tmp", std::process::id()));
    std::fs::write(&temporary, text).map_err(fail)?;
    std::fs::rename(&temporary, path).map_err(|e| {
        let _ = std::fs::remove_file(&temporary);
        fail(e)
    })
}

/// `path` with `file` moved to the front (absolute), without repeats, at most
/// [`MAX_RECENT`].
pub(super) fn with_first(mut files: Vec<PathBuf>, file: &Path) -> Vec<PathBuf> {
    let file = std::path::absolute(file).unwrap_or_else(|_| file.to_owned());
    files.retain(|f| f != &file);
    files.insert(0, file);
    files.truncate(MAX_RECENT);
    files
}

impl RecentFiles {
    /// The list kept in `store` (empty when it is missing or unreadable: a list of recent
    /// files is not worth an error).
    pub(super) fn load(store: Option<PathBuf>) -> Self {
        let read = |path: &Path| std::fs::read(path).ok();
        let files = store
            .as_deref()
            .and_then(read)
            .and_then(|bytes| serde_json::from_slice::<Vec<PathBuf>>(&bytes).ok())
            .unwrap_or_default();
        let names = store
            .as_deref()
            .and_then(|s| read(&names_store(s)))
            .and_then(|bytes| serde_json::from_slice::<Vec<(PathBuf, String)>>(&bytes).ok())
            .unwrap_or_default();
        let mut recent = Self {
            files,
            names,
            store,
            ..Self::default()
        };
        recent.files.truncate(MAX_RECENT);
        recent.recheck();
        recent
    }

    /// Puts `file` first and saves the list (written beside and renamed: never half a file).
    pub(super) fn add(&mut self, file: &Path) -> Result<(), String> {
        self.files = with_first(std::mem::take(&mut self.files), file);
        self.recheck();
        let Some(store) = &self.store else {
            return Ok(());
        };
        self.names.retain(|(p, _)| self.files.contains(p));
        write_json(&names_store(store), &self.names)?;
        write_json(store, &self.files)
    }

    /// The name the list gives `path`, if it was given one.
    pub(super) fn name(&self, path: &Path) -> Option<&str> {
        self.names
            .iter()
            .find(|(p, _)| p == path)
            .map(|(_, name)| name.as_str())
    }

    /// Records what was opened: `opened`, which gave the cloud `cloud`. `timeline`, for a
    /// timeline built in the window (its cloud in the cache), is the folder its songs share and
    /// its name: a timeline is listed once, by that folder when the folder was opened or is in
    /// the list already, else by its cloud, shown with that name.
    pub(super) fn add_opened(
        &mut self,
        opened: &Path,
        cloud: &Path,
        timeline: Option<(Option<&Path>, &str)>,
    ) -> Result<(), String> {
        let Some((folder, name)) = timeline else {
            return self.add(opened);
        };
        let cloud = std::path::absolute(cloud).unwrap_or_else(|_| cloud.to_owned());
        let Some(folder) = folder else {
            self.names.retain(|(p, _)| p != &cloud);
            self.names.push((cloud.clone(), name.to_string()));
            return self.add(&cloud);
        };
        let folder = std::path::absolute(folder).unwrap_or_else(|_| folder.to_owned());
        let by_folder = opened.is_dir() || self.files.contains(&folder);
        if by_folder {
            self.files.retain(|f| f != &cloud);
            self.add(&folder)
        } else {
            self.names.retain(|(p, _)| p != &cloud);
            self.names.push((cloud.clone(), name.to_string()));
            self.add(&cloud)
        }
    }

    /// Looks again which files are there.
    pub(super) fn recheck(&mut self) {
        self.present = self.files.iter().map(|f| f.exists()).collect();
        self.checked = Some(Instant::now());
    }

    /// The files with whether each is there (looked at again every few seconds).
    pub(super) fn entries(&mut self) -> Vec<(PathBuf, bool)> {
        if self.checked.is_none_or(|t| t.elapsed() > RECHECK) {
            self.recheck();
        }
        self.files
            .iter()
            .cloned()
            .zip(self.present.iter().copied())
            .collect()
    }
}

/// The deepest folder holding every one of `paths` (`None` for none).
pub(super) fn common_folder(paths: impl IntoIterator<Item = PathBuf>) -> Option<PathBuf> {
    let mut common: Option<PathBuf> = None;
    for path in paths {
        let folder = path.parent()?.to_path_buf();
        common = Some(match common {
            None => folder,
            Some(mut c) => {
                while !folder.starts_with(&c) {
                    if !c.pop() {
                        break;
                    }
                }
                c
            }
        });
    }
    common.filter(|c| !c.as_os_str().is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_timeline_built_from_a_folder_is_listed_once_by_its_folder() {
        let dir = std::env::temp_dir().join(format!("loudscape-recent-tl-{}", std::process::id()));
        let folder = dir.join("albums");
        let other = dir.join("singles");
        let cache = dir.join("cache");
        for d in [&folder, &other, &cache] {
            std::fs::create_dir_all(d).unwrap();
        }
        let built = cache.join("timeline-0123456789abcdef.ply");
        let elsewhere = cache.join("timeline-fedcba9876543210.ply");
        std::fs::write(&built, b"ply").unwrap();
        std::fs::write(&elsewhere, b"ply").unwrap();
        let song = dir.join("song.wav");
        std::fs::write(&song, b"RIFF").unwrap();
        let store = dir.join("state").join("recent.json");
        let mut recent = RecentFiles::load(Some(store.clone()));
        // The folder opened in the window, then its cloud restored at the next launch.
        let albums = Some((Some(folder.as_path()), "albums/ (timeline)"));
        recent.add_opened(&folder, &built, albums).unwrap();
        recent.add_opened(&song, &song, None).unwrap();
        recent.add_opened(&built, &built, albums).unwrap();
        assert_eq!(recent.files, [folder.clone(), song.clone()]);
        // A timeline whose folder was never opened is listed by its cloud, with its name, also
        // after a restart, until the folder is opened.
        let singles = Some((Some(other.as_path()), "singles/ (timeline)"));
        recent.add_opened(&elsewhere, &elsewhere, singles).unwrap();
        assert_eq!(recent.files[0], elsewhere);
        let again = RecentFiles::load(Some(store.clone()));
        assert_eq!(again.files, recent.files);
        assert_eq!(again.name(&elsewhere), Some("singles/ (timeline)"));
        assert_eq!(again.name(&song), None);
        recent.add_opened(&other, &elsewhere, singles).unwrap();
        assert_eq!(recent.files, [other.clone(), folder.clone(), song.clone()]);
        // The list itself stays a list of paths (for other tools, and older versions).
        let kept: Vec<PathBuf> = serde_json::from_slice(&std::fs::read(&store).unwrap()).unwrap();
        assert_eq!(kept, recent.files);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_common_folder_of_songs() {
        let p = |s: &str| PathBuf::from(s);
        assert_eq!(
            common_folder([p("/m/a/1.wav"), p("/m/a/b/2.wav"), p("/m/a/3.wav")]),
            Some(p("/m/a"))
        );
        assert_eq!(
            common_folder([p("/m/x/1.wav"), p("/m/y/2.wav")]),
            Some(p("/m"))
        );
        assert_eq!(common_folder(Vec::<PathBuf>::new()), None);
    }

    #[test]
    fn newest_first_no_repeats_capped_kept_and_missing_seen() {
        let dir = std::env::temp_dir().join(format!("loudscape-recent-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let store = dir.join("state").join("recent.json");
        let mut recent = RecentFiles::load(Some(store.clone()));
        assert!(recent.files.is_empty());
        for i in 0..12 {
            let file = dir.join(format!("song{i}.wav"));
            std::fs::write(&file, b"x").unwrap();
            recent.add(&file).unwrap();
        }
        recent.add(&dir.join("song5.wav")).unwrap();
        assert_eq!(recent.files.len(), MAX_RECENT);
        assert_eq!(recent.files[0], dir.join("song5.wav"));
        assert_eq!(recent.files[1], dir.join("song11.wav"));
        assert_eq!(
            recent
                .files
                .iter()
                .filter(|f| f.ends_with("song5.wav"))
                .count(),
            1
        );
        std::fs::remove_file(dir.join("song11.wav")).unwrap();
        let mut again = RecentFiles::load(Some(store));
        assert_eq!(again.files, recent.files, "the list survives a restart");
        let entries = again.entries();
        assert_eq!(entries[1], (dir.join("song11.wav"), false));
        assert!(entries[0].1);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
