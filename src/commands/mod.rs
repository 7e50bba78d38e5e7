//! One module per subcommand. Each parses its own arguments (clap `Args`) and returns
//! `anyhow::Result`, so every failure reaches the user as one line.

pub mod args;
pub mod bench;
pub mod bench_surface;
pub mod bench_volume;
pub mod mesh;
pub mod npy;
pub mod render;
pub mod render_compare;
pub mod video;
pub mod video_encode;
pub mod voxelize;

use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Context;
use loudscape::files::TempFile;

/// Set by `-q`: no "wrote ..." summaries.
static QUIET: AtomicBool = AtomicBool::new(false);

/// Silences the "wrote ..." summaries (`-q`).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// The one summary line every command prints per file written, on stderr (stdout stays for
/// results such as benchmark figures): `wrote PATH` or `wrote PATH (DETAIL)`.
pub fn wrote(path: &Path, detail: &str) {
    if QUIET.load(Ordering::Relaxed) {
        return;
    }
    if detail.is_empty() {
        eprintln!("wrote {}", path.display());
    } else {
        eprintln!("wrote {} ({detail})", path.display());
    }
}

/// Writes through `PATH.tmp` and renames, so no half-written file is left under the name; the
/// temporary file is removed on any error and on SIGTERM/SIGINT.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<&mut std::fs::File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let result = (|| {
        let mut tmp = TempFile::create(path, ".tmp")?;
        {
            let mut out = std::io::BufWriter::new(tmp.file());
            write(&mut out)?;
            out.flush()?;
        }
        tmp.persist(path)?;
        Ok::<_, anyhow::Error>(())
    })();
    result.with_context(|| format!("{}: cannot write", path.display()))
}
