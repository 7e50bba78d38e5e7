//! Files the app writes, made safe: a temporary file beside the target that is renamed into place
//! when complete and deleted on every other path (an error, a panic's unwinding, SIGTERM or
//! SIGINT), child processes writing such files killed on those paths too ([`ChildGuard`]), and
//! the check that an output is not one of the inputs (the same path, or the same file through a
//! link).

use std::fs::File;
use std::io;
use std::path::{Path, PathBuf};
use std::process::{Child, ExitStatus};
use std::sync::{Arc, Mutex};

/// Temporary files in progress, deleted by the signal handler (see [`remove_temporaries_on_signal`]).
/// Created and registered under this lock, so the handler sees every file that exists.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn temporaries() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    TEMPORARIES
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// A temporary file beside its target: deleted when dropped, unless [`TempFile::persist`]
/// renamed it into place.
#[derive(Debug)]
pub struct TempFile {
    path: PathBuf,
    file: Option<File>,
}

impl TempFile {
    /// Creates `target` + `suffix` (e.g. `out.png.partial`), replacing a leftover of that name.
    pub fn create(target: &Path, suffix: &str) -> io::Result<TempFile> {
        let mut name = target.file_name().unwrap_or_default().to_os_string();
        name.push(suffix);
        let path = target.with_file_name(name);
        let mut list = temporaries();
        let file = File::create(&path)?;
        list.push(path.clone());
        Ok(TempFile {
            path,
            file: Some(file),
        })
    }

    /// The temporary file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The open file, for writing.
    pub fn file(&mut self) -> &mut File {
        self.file
            .as_mut()
            .expect("the file is open until persist or drop")
    }

    /// Flushes to disk, closes and renames the file to `target`.
    pub fn persist(mut self, target: &Path) -> io::Result<()> {
        if let Some(file) = self.file.take() {
            file.sync_all()?;
        }
        std::fs::rename(&self.path, target)?;
        forget(&self.path);
        self.path = PathBuf::new();
        Ok(())
    }
}

fn forget(path: &Path) {
    temporaries().retain(|p| p != path);
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if self.path.as_os_str().is_empty() {
            return;
        }
        self.file = None;
        let _ = std::fs::remove_file(&self.path);
        forget(&self.path);
    }
}

type SharedChild = Arc<Mutex<Child>>;

/// Child processes killed by the signal handler before it deletes the temporary files (an
/// encoder writing one must not go on writing, or recreate it).
static CHILDREN: Mutex<Vec<(u64, SharedChild)>> = Mutex::new(Vec::new());

fn children() -> std::sync::MutexGuard<'static, Vec<(u64, SharedChild)>> {
    CHILDREN
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// A child process killed (and reaped) when dropped before [`ChildGuard::wait`], and on
/// SIGTERM/SIGINT by [`remove_temporaries_on_signal`]'s handler.
pub struct ChildGuard {
    id: u64,
    child: SharedChild,
    done: bool,
}

impl ChildGuard {
    /// Takes charge of `child` (take its pipes out first).
    pub fn new(child: Child) -> Self {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let id = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let child = Arc::new(Mutex::new(child));
        children().push((id, Arc::clone(&child)));
        ChildGuard {
            id,
            child,
            done: false,
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Child> {
        self.child
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Waits for the process to end by itself (polling, so the signal handler can still kill it
    /// meanwhile).
    pub fn wait(mut self) -> io::Result<ExitStatus> {
        loop {
            let status = self.lock().try_wait()?;
            if let Some(status) = status {
                self.done = true;
                return Ok(status);
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }
}

impl Drop for ChildGuard {
    fn drop(&mut self) {
        if !self.done {
            let mut child = self.lock();
            let _ = child.kill();
            let _ = child.wait();
        }
        children().retain(|(id, _)| *id != self.id);
    }
}

/// Starts a thread that, on SIGTERM or SIGINT (SIGHUP too on Unix), kills the child processes in
/// [`ChildGuard`]s, deletes every temporary file in progress and exits with 128 + the signal number, as a shell reports it. Call once, from
/// a command-line program (the window keeps its own handling).
#[cfg(unix)]
pub fn remove_temporaries_on_signal() -> io::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGTERM, SIGINT, SIGHUP])?;
    std::thread::Builder::new()
        .name("loudscape::signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                // Held until exit: no new child or temporary file can appear after the sweep.
                let running = children();
                for (_, child) in running.iter() {
                    let mut child = child
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner);
                    let _ = child.kill();
                    let _ = child.wait();
                }
                let list = temporaries();
                for path in list.iter() {
                    let _ = std::fs::remove_file(path);
                }
                std::process::exit(128 + signal);
            }
        })?;
    Ok(())
}

/// Without Unix signals there is nothing to install; errors and unwinding still clean up.
#[cfg(not(unix))]
pub fn remove_temporaries_on_signal() -> io::Result<()> {
    Ok(())
}

/// Whether `a` and `b` name the same file: the same path once made absolute, or (both existing)
/// the same device and inode on Unix, so hard and symbolic links count.
pub fn same_file(a: &Path, b: &Path) -> bool {
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    if absolute(a) == absolute(b) {
        return true;
    }
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(ma), Ok(mb)) => same_identity(&ma, &mb),
        _ => false,
    }
}

#[cfg(unix)]
fn same_identity(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    a.dev() == b.dev() && a.ino() == b.ino()
}

#[cfg(not(unix))]
fn same_identity(_: &std::fs::Metadata, _: &std::fs::Metadata) -> bool {
    false
}

/// Fails when `output` is one of `inputs`, naming both: no command writes over what it reads.
pub fn check_not_input(output: &Path, inputs: &[&Path]) -> Result<(), String> {
    match inputs.iter().find(|input| same_file(output, input)) {
        Some(input) if input == &output => Err(format!(
            "{}: the output is the input; choose another output name",
            output.display()
        )),
        Some(input) => Err(format!(
            "{}: the output is the input {} (the same file through a link); choose another \
             output name",
            output.display(),
            input.display()
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("loudscape-files-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn dropped_temporaries_vanish_and_persisted_ones_move() {
        let dir = dir("temp");
        let target = dir.join("a.png");
        let tmp = TempFile::create(&target, ".partial").unwrap();
        let tmp_path = tmp.path().to_path_buf();
        assert!(tmp_path.exists());
        drop(tmp);
        assert!(!tmp_path.exists());
        assert!(!target.exists());
        let mut tmp = TempFile::create(&target, ".partial").unwrap();
        io::Write::write_all(tmp.file(), b"png").unwrap();
        tmp.persist(&target).unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"png");
        assert!(!tmp_path.exists());
        assert!(temporaries().iter().all(|p| p != &tmp_path));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_dropped_child_guard_kills_its_process_and_a_waited_one_reports_it() {
        let child = std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .unwrap();
        let pid = child.id();
        let guard = ChildGuard::new(child);
        assert!(
            children()
                .iter()
                .any(|(_, c)| c.lock().unwrap().id() == pid)
        );
        let start = std::time::Instant::now();
        drop(guard);
        assert!(start.elapsed() < std::time::Duration::from_secs(5));
        assert!(
            !Path::new(&format!("/proc/{pid}")).exists(),
            "still running"
        );
        assert!(
            children()
                .iter()
                .all(|(_, c)| c.lock().unwrap().id() != pid)
        );
        let done = std::process::Command::new("true").spawn().unwrap();
        assert!(ChildGuard::new(done).wait().unwrap().success());
    }

    #[cfg(unix)]
    #[test]
    fn links_are_the_same_file() {
        let dir = dir("links");
        let a = dir.join("c.ply");
        std::fs::write(&a, b"ply").unwrap();
        let sym = dir.join("link.ply");
        std::os::unix::fs::symlink(&a, &sym).unwrap();
        let hard = dir.join("hard.ply");
        std::fs::hard_link(&a, &hard).unwrap();
        let other = dir.join("other.ply");
        std::fs::write(&other, b"ply").unwrap();
        assert!(same_file(&a, &a));
        assert!(same_file(&a, &dir.join(".").join("c.ply")));
        assert!(same_file(&sym, &a));
        assert!(same_file(&hard, &a));
        assert!(!same_file(&other, &a));
        assert!(!same_file(&dir.join("new.png"), &a));
        assert!(check_not_input(&a, &[&a]).is_err());
        assert!(check_not_input(&sym, &[&other, &a]).is_err());
        assert!(check_not_input(&dir.join("new.png"), &[&a]).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
