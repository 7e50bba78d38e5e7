//! One module per subcommand. Each parses its own arguments (clap `Args`) and returns
//! `anyhow::Result`, so every failure reaches the user as one line.

pub mod args;
pub mod bench;
pub mod bench_surface;
pub mod bench_volume;
pub mod mesh;
pub mod npy;
pub mod render;
pub mod voxelize;

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;

/// Writes through `PATH.tmp` and renames, so no half-written file is left under the name.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let tmp = PathBuf::from(format!("{}.tmp", path.display()));
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut out = std::io::BufWriter::new(file);
        write(&mut out)?;
        out.flush()?;
        Ok::<_, anyhow::Error>(())
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(e.context(format!("{}: cannot write", path.display())));
    }
    std::fs::rename(&tmp, path).with_context(|| format!("{}: cannot write", path.display()))
}
