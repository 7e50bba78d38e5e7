//! The window (being built).
use std::path::PathBuf;
pub fn run(_files: Vec<PathBuf>) -> anyhow::Result<()> {
    anyhow::bail!("the window is not built yet")
}
