//! Finding `loudscape-extract`: `$LOUDSCAPE_EXTRACT` when set (and then only there); beside the
//! binary (where `pip install .` puts both, the environment's `bin/` or `Scripts/`); the
//! project's virtual environment (`.venv/bin/`, on Windows `.venv/Scripts/`) in the folder of the
//! `loudscape` binary or any folder above it (a checkout's `target/release/loudscape`) or in the
//! current folder or above; on `PATH`.

use std::path::{Path, PathBuf};

const NAME: &str = if cfg!(windows) {
    "loudscape-extract.exe"
} else {
    "loudscape-extract"
};

fn venv_candidates(start: &Path) -> Vec<PathBuf> {
    start
        .ancestors()
        .flat_map(|dir| {
            [
                dir.join(".venv").join("bin").join(NAME),
                dir.join(".venv").join("Scripts").join(NAME),
            ]
        })
        .collect()
}

/// Every place looked in without `$LOUDSCAPE_EXTRACT`, in order.
pub fn candidates() -> Vec<PathBuf> {
    let exe_dir = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(Path::to_path_buf));
    let cwd = std::env::current_dir().ok();
    let mut places = places_in(exe_dir.as_deref(), cwd.as_deref());
    if let Some(path) = std::env::var_os("PATH") {
        places.extend(std::env::split_paths(&path).map(|dir| dir.join(NAME)));
    }
    places
}

/// Beside the binary first (an installed environment: the extractor installed with the app,
/// not the one of a checkout the command happens to run in), then the virtual environments.
fn places_in(exe_dir: Option<&Path>, cwd: Option<&Path>) -> Vec<PathBuf> {
    let mut places = Vec::new();
    if let Some(dir) = exe_dir {
        places.push(dir.join(NAME));
        places.extend(venv_candidates(dir));
    }
    if let Some(dir) = cwd {
        places.extend(venv_candidates(dir));
    }
    places
}

/// What to tell the user when the extractor is missing: where it was looked for (`looked`, the
/// error of [`extractor`]) and how to install it.
pub fn not_found(looked: &str) -> String {
    format!(
        "the extractor loudscape-extract was not found (looked in: {looked}); install it with \
         `make venv` (or: python3 -m venv .venv && .venv/bin/pip install -e ./preprocess)"
    )
}

/// The extractor to run, or (as the error) a short list of where it was looked for.
pub fn extractor() -> Result<PathBuf, String> {
    if let Some(explicit) = std::env::var_os("LOUDSCAPE_EXTRACT").filter(|p| !p.is_empty()) {
        let explicit = PathBuf::from(explicit);
        if explicit.is_file() {
            return Ok(explicit);
        }
        return Err(format!("$LOUDSCAPE_EXTRACT = {}", explicit.display()));
    }
    if let Some(found) = candidates().into_iter().find(|p| p.is_file()) {
        return Ok(found);
    }
    Err("beside the loudscape binary, .venv/bin above it and above the current folder, PATH".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_venv_is_looked_for_in_every_folder_above() {
        let places = venv_candidates(Path::new("/repo/target/release"));
        let venv = Path::new("/repo/.venv/bin").join(NAME);
        assert!(places.contains(&venv));
        assert!(places.len() >= 8);
    }

    #[test]
    fn beside_the_binary_comes_before_any_venv() {
        let bin = Path::new("/env/bin");
        let places = places_in(Some(bin), Some(Path::new("/checkout")));
        assert_eq!(places[0], bin.join(NAME));
        let checkout_venv = Path::new("/checkout/.venv/bin").join(NAME);
        let at = places.iter().position(|p| *p == checkout_venv);
        assert!(at.is_some_and(|i| i > 0), "{places:?}");
    }
}
