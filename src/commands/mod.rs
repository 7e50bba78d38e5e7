//! One module per subcommand. Each parses its own arguments (clap `Args`) and returns
//! `anyhow::Result`, so every failure reaches the user as one line.

pub mod args;
pub mod bench;
pub mod bench_surface;
pub mod bench_volume;
pub mod compare;
pub mod compare_align;
pub mod compare_multiples;
pub mod mesh;
pub mod page;
pub mod render;
pub mod render_compare;
pub mod video;
pub mod video_encode;
pub mod video_frames;
pub mod voxelize;

/// `.npy` grids: in the library (`loudscape::data::npy`), where the fuzzers reach them too.
pub use loudscape::data::npy;

use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use loudscape::files::{TempFile, is_disk_full};

/// Set by `-q`: no "wrote ..." summaries.
static QUIET: AtomicBool = AtomicBool::new(false);

/// Silences the "wrote ..." summaries (`-q`).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// Whether `-q` was given (for commands that hand it on to the extractor).
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
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
        loudscape::files::sync_parent(path);
        Ok::<_, anyhow::Error>(())
    })();
    result.map_err(|e| write_error(path, e))
}

/// The one line for a failed write of `path`: a full disk as "no space left on the device"
/// (whatever layer reported it: the OS, or an encoder that counts the bytes it could write),
/// anything else as `PATH: cannot write: CAUSE`.
pub fn write_error(path: &Path, error: anyhow::Error) -> anyhow::Error {
    let full = error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(is_disk_full)
            || cause
                .downcast_ref::<image::ImageError>()
                .is_some_and(|e| matches!(e, image::ImageError::IoError(io) if is_disk_full(io)))
    });
    if full {
        return anyhow::anyhow!(
            "{}: cannot write: no space left on the device",
            path.display()
        );
    }
    error.context(format!("{}: cannot write", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A full disk reads as such, however it was reported: ENOSPC, a short write, or the PNG
    /// encoder's I/O error (which used to read "cannot write file (N requested and M written)").
    #[test]
    fn a_full_disk_is_one_plain_line_naming_the_file() {
        let path = Path::new("out/x.png");
        for error in [
            anyhow::Error::from(std::io::Error::from(std::io::ErrorKind::StorageFull)),
            anyhow::Error::from(std::io::Error::new(
                std::io::ErrorKind::WriteZero,
                "cannot write file (868970 requested and 785814 written)",
            )),
            anyhow::Error::from(image::ImageError::IoError(std::io::Error::from(
                std::io::ErrorKind::StorageFull,
            ))),
        ] {
            let text = format!("{:#}", write_error(path, error));
            assert_eq!(text, "out/x.png: cannot write: no space left on the device");
        }
        let other = write_error(path, anyhow::anyhow!("permission denied"));
        assert_eq!(
            format!("{other:#}"),
            "out/x.png: cannot write: permission denied"
        );
    }
}
