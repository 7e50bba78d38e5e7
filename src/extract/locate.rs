//! Finding `loudscape-extract`: `$LOUDSCAPE_EXTRACT` when set (and then only there); the project's virtual
//! environment (`.venv/bin/`, on Windows `.venv/Scripts/`) in the folder of the `loudscape`
//! binary or any folder above it (a checkout's `target/release/loudscape`) or in the current
//! folder or above; beside the binary; on `PATH`.

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
    let mut places = Vec::new();
    let exe_dir = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(Path::to_path_buf));
    if let Some(dir) = &exe_dir {
        places.extend(venv_candidates(dir));
    }
    if let Ok(cwd) = std::env::current_dir() {
        places.extend(venv_candidates(&cwd));
    }
    if let Some(dir) = &exe_dir {
        places.push(dir.join(NAME));
    }
    if let Some(path) = std::env::var_os("PATH") {
        places.extend(std::env::split_paths(&path).map(|dir| dir.join(NAME)));
    }
    places
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
    Err(
        ".venv/bin above the loudscape binary and the current folder, beside the binary, PATH"
            .into(),
    )
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
}
