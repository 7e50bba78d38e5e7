//! Files the app writes, made safe: a temporary file beside the target that is renamed into place
//! when complete and deleted on every other path (an error, a panic's unwinding, SIGTERM or
//! SIGINT), a private temporary folder deleted the same way ([`TempDir`]), the child processes
//! killed with the app on those signals ([`ChildGuard`] for a process group by id, [`OwnedChild`]
//! for a child writing one of those files, killed and reaped), and the check that an output is
//! not one of the inputs (the same path, or the same file through a link).

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

/// Child processes (each the leader of its own process group) killed by the signal handler
/// before it deletes the temporaries they may be writing.
static CHILDREN: Mutex<Vec<u32>> = Mutex::new(Vec::new());

fn children() -> std::sync::MutexGuard<'static, Vec<u32>> {
    CHILDREN
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Kills child process `pid` and every process of its group (it was started as a group leader:
/// [`own_process_group`]), so what it started goes too.
pub fn kill_process_group(pid: u32) {
    #[cfg(unix)]
    if let Ok(pid) = i32::try_from(pid)
        && pid > 0
    {
        // SAFETY: kill(2) with a negative pid signals that process group; no memory is shared.
        unsafe {
            libc::kill(-pid, libc::SIGKILL);
            libc::kill(pid, libc::SIGKILL);
        }
    }
    #[cfg(not(unix))]
    let _ = pid;
}

/// Asks `child` to stop with SIGTERM (it may clean up first); nothing if its pid does not fit
/// a `pid_t`.
#[cfg(unix)]
pub fn terminate(child: &std::process::Child) {
    if let Ok(pid) = i32::try_from(child.id())
        && pid > 0
    {
        // SAFETY: kill(2) on our own child's pid; no memory is shared.
        unsafe {
            libc::kill(pid, libc::SIGTERM);
        }
    }
}

/// Whether process `pid` runs on this machine (a zombie counts: what it uses may be in use until
/// it is reaped; one of another user's counts); `Some(false)` for a PID no process can have (it
/// does not fit a `pid_t`); None where that cannot be told (PID 0, not Unix).
#[cfg(unix)]
pub fn process_runs(pid: u32) -> Option<bool> {
    if pid == 0 {
        return None;
    }
    let Ok(pid) = i32::try_from(pid) else {
        return Some(false);
    };
    // SAFETY: kill(2) with signal 0 sends nothing; it only checks that the process exists.
    if unsafe { libc::kill(pid, 0) } == 0 {
        return Some(true);
    }
    match io::Error::last_os_error().raw_os_error() {
        Some(libc::ESRCH) => Some(false),
        // EPERM: it runs, as another user.
        Some(libc::EPERM) => Some(true),
        _ => None,
    }
}

#[cfg(not(unix))]
pub fn process_runs(_pid: u32) -> Option<bool> {
    None
}

/// Starts `command`'s child as the leader of a process group of its own, so that
/// [`kill_process_group`] reaches what it starts, and (Linux) so that it is killed if the app
/// dies without a chance to (SIGKILL).
pub fn own_process_group(command: &mut std::process::Command) -> &mut std::process::Command {
    #[cfg(unix)]
    std::os::unix::process::CommandExt::process_group(command, 0);
    die_with_parent(command);
    command
}

/// Linux: the child gets SIGKILL when the thread that started it ends (the app killed).
pub fn die_with_parent(command: &mut std::process::Command) {
    #[cfg(target_os = "linux")]
    on_parent_death(command, libc::SIGKILL);
    #[cfg(not(target_os = "linux"))]
    let _ = command;
}

/// Linux: the child gets SIGTERM when the thread that started it ends (the app killed), so
/// that it may clean up (a command that removes its temporary files on SIGTERM).
pub fn stop_with_parent(command: &mut std::process::Command) {
    #[cfg(target_os = "linux")]
    on_parent_death(command, libc::SIGTERM);
    #[cfg(not(target_os = "linux"))]
    let _ = command;
}

#[cfg(target_os = "linux")]
fn on_parent_death(command: &mut std::process::Command, signal: libc::c_int) {
    use std::os::unix::process::CommandExt;
    // SAFETY: between fork and exec the closure only calls prctl(2), which is
    // async-signal-safe and touches no memory of the parent.
    unsafe {
        command.pre_exec(move || {
            libc::prctl(libc::PR_SET_PDEATHSIG, signal);
            Ok(())
        });
    }
}

/// A running child process registered to be killed (its whole process group) when the app gets
/// SIGTERM, SIGINT or SIGHUP; unregistered when dropped.
#[derive(Debug)]
pub struct ChildGuard(u32);

impl ChildGuard {
    pub fn new(pid: u32) -> ChildGuard {
        children().push(pid);
        ChildGuard(pid)
    }
}

impl Drop for ChildGuard {
    fn drop(&mut self) {
        children().retain(|&p| p != self.0);
    }
}

/// A private temporary folder (mode 0700 on Unix), deleted with everything in it when dropped
/// and by the signal handler.
#[derive(Debug)]
pub struct TempDir {
    path: PathBuf,
}

impl TempDir {
    /// Creates a new folder `PREFIX-PID-N` in `parent`.
    pub fn create_in(parent: &Path, prefix: &str) -> io::Result<TempDir> {
        static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        loop {
            let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let path = parent.join(format!("{prefix}-{}-{n}", std::process::id()));
            let mut list = temporaries();
            #[cfg_attr(not(unix), allow(unused_mut))]
            let mut builder = std::fs::DirBuilder::new();
            #[cfg(unix)]
            std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
            match builder.create(&path) {
                Ok(()) => {
                    list.push(path.clone());
                    return Ok(TempDir { path });
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(e),
            }
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
        forget(&self.path);
    }
}

/// Deletes a temporary file or folder (the signal handler's sweep; Unix only, where signals are
/// handled).
#[cfg(unix)]
fn remove_temporary(path: &Path) {
    if path.is_dir() {
        let _ = std::fs::remove_dir_all(path);
    } else {
        let _ = std::fs::remove_file(path);
    }
}

/// Writes several files that belong together (an array and its description): each through a
/// temporary file beside it, `write(i, file)` filling the `i`th; all are fsynced before the first
/// is renamed into place, and if a rename fails the files already renamed are removed, so the
/// set appears whole or not at all (an earlier file of a name is then gone too). The folders are
/// fsynced after.
pub fn write_together<E: From<io::Error>>(
    targets: &[&Path],
    mut write: impl FnMut(usize, &mut io::BufWriter<&mut File>) -> Result<(), E>,
) -> Result<(), E> {
    let mut temporaries = Vec::with_capacity(targets.len());
    for (i, target) in targets.iter().enumerate() {
        let mut tmp = TempFile::create(target, ".tmp")?;
        {
            let mut out = io::BufWriter::new(tmp.file());
            write(i, &mut out)?;
            io::Write::flush(&mut out)?;
        }
        tmp.sync()?;
        temporaries.push(tmp);
    }
    for (i, (tmp, target)) in temporaries.into_iter().zip(targets).enumerate() {
        if let Err(e) = tmp.persist(target) {
            for done in &targets[..i] {
                let _ = std::fs::remove_file(done);
            }
            return Err(e.into());
        }
    }
    for target in targets {
        sync_parent(target);
    }
    Ok(())
}

/// Whether a write failed for want of space: ENOSPC or a quota, or a short write (`WriteZero`,
/// from a writer that could not place all its bytes).
pub fn is_disk_full(error: &io::Error) -> bool {
    matches!(
        error.kind(),
        io::ErrorKind::StorageFull | io::ErrorKind::QuotaExceeded | io::ErrorKind::WriteZero
    )
}

/// The reason of a failed write, for a message that names the file: "no space left on the
/// device" for a full disk, else the error's own words.
pub fn write_reason(error: &io::Error) -> String {
    if is_disk_full(error) {
        "no space left on the device".into()
    } else {
        error.to_string()
    }
}

/// Writes `bytes` to `target` through a temporary file beside it, fsynced before the rename,
/// and fsyncs the folder after it (so a power cut leaves the old file or the new one).
pub fn write_file_atomically(target: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut tmp = TempFile::create(target, ".tmp")?;
    io::Write::write_all(tmp.file(), bytes)?;
    tmp.persist(target)?;
    sync_parent(target);
    Ok(())
}

/// Fsyncs the folder holding `path` (best effort: not every system can open a folder).
pub fn sync_parent(path: &Path) {
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        if let Ok(dir) = File::open(dir) {
            let _ = dir.sync_all();
        }
    }
}

/// The longest file name most file systems take, in bytes.
const MAX_NAME_BYTES: usize = 255;

/// A temporary file beside its target: deleted when dropped, unless [`TempFile::persist`]
/// renamed it into place.
#[derive(Debug)]
pub struct TempFile {
    path: PathBuf,
    file: Option<File>,
}

impl TempFile {
    /// Creates `target` + `suffix` (e.g. `out.png.partial`), replacing a leftover of that name;
    /// where that name would be longer than a file name may be (255 bytes), a short hidden one,
    /// `.loudscape-PID-N` + `suffix`, in the same folder.
    pub fn create(target: &Path, suffix: &str) -> io::Result<TempFile> {
        static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let mut name = target.file_name().unwrap_or_default().to_os_string();
        name.push(suffix);
        if name.len() > MAX_NAME_BYTES {
            let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            name = format!(".loudscape-{}-{n}{suffix}", std::process::id()).into();
        }
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

    /// Flushes the file's data to disk (before a rename that makes it visible).
    pub fn sync(&mut self) -> io::Result<()> {
        self.file().sync_all()
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
static OWNED_CHILDREN: Mutex<Vec<(u64, SharedChild)>> = Mutex::new(Vec::new());

fn owned_children() -> std::sync::MutexGuard<'static, Vec<(u64, SharedChild)>> {
    OWNED_CHILDREN
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// A child process killed (and reaped) when dropped before [`OwnedChild::wait`], and on
/// SIGTERM/SIGINT by [`remove_temporaries_on_signal`]'s handler.
pub struct OwnedChild {
    id: u64,
    child: SharedChild,
    done: bool,
}

impl OwnedChild {
    /// Takes charge of `child` (take its pipes out first).
    pub fn new(child: Child) -> Self {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let id = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let child = Arc::new(Mutex::new(child));
        owned_children().push((id, Arc::clone(&child)));
        OwnedChild {
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

impl Drop for OwnedChild {
    fn drop(&mut self) {
        if !self.done {
            let mut child = self.lock();
            let _ = child.kill();
            let _ = child.wait();
        }
        owned_children().retain(|(id, _)| *id != self.id);
    }
}

/// Starts a thread that, on SIGTERM or SIGINT (SIGHUP too on Unix), kills every registered child
/// process ([`ChildGuard`]'s process groups, [`OwnedChild`]ren), deletes every temporary file and
/// folder in progress and exits with 128 + the signal number, as a shell reports it. Call once, from
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
                for &pid in running.iter() {
                    kill_process_group(pid);
                }
                for (_, child) in owned_children().iter() {
                    let mut child = child
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner);
                    let _ = child.kill();
                    let _ = child.wait();
                }
                let list = temporaries();
                for path in list.iter() {
                    remove_temporary(path);
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

/// Fails, with the reason, when `path` exists but is neither a regular file nor a folder: a FIFO
/// (reading it would wait for a writer forever), a device (`/dev/zero` never ends) or a socket.
/// Checked by every entry point before anything opens or hashes the input; `stat` does not
/// block on any of them. A path that cannot be read at all passes: opening it gives its error.
pub fn check_regular(path: &Path) -> Result<(), String> {
    let Ok(metadata) = std::fs::metadata(path) else {
        return Ok(());
    };
    let kind = metadata.file_type();
    if kind.is_file() || kind.is_dir() {
        return Ok(());
    }
    #[cfg(unix)]
    let what = {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            "a FIFO (named pipe)"
        } else if kind.is_char_device() {
            "a character device"
        } else if kind.is_block_device() {
            "a block device"
        } else if kind.is_socket() {
            "a socket"
        } else {
            "not a regular file"
        }
    };
    #[cfg(not(unix))]
    let what = "not a regular file";
    Err(format!(
        "{}: is {what}, not a file; loudscape reads regular files only",
        path.display()
    ))
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

    #[test]
    fn files_written_together_appear_together_or_not_at_all() {
        let dir = dir("together");
        // A name whose temporary would pass 255 bytes still writes.
        let long = dir.join(format!("{}.npy", "a".repeat(243)));
        let mut json = long.clone().into_os_string();
        json.push(".json");
        let json = PathBuf::from(json);
        write_together::<io::Error>(&[&long, &json], |i, out| {
            io::Write::write_all(out, if i == 0 { &b"array"[..] } else { &b"{}"[..] })
        })
        .unwrap();
        assert_eq!(std::fs::read(&long).unwrap(), b"array");
        assert_eq!(std::fs::read(&json).unwrap(), b"{}");
        // The second cannot be renamed into place (a folder has its name): neither is left.
        let (a, b) = (dir.join("b.npy"), dir.join("b.npy.json"));
        std::fs::create_dir(&b).unwrap();
        std::fs::write(b.join("x"), b"x").unwrap();
        let failed =
            write_together::<io::Error>(&[&a, &b], |_, out| io::Write::write_all(out, b"x"));
        assert!(failed.is_err());
        assert!(!a.exists());
        // A write that fails: nothing, and no temporary.
        let (c, d) = (dir.join("c.npy"), dir.join("c.npy.json"));
        let failed = write_together::<io::Error>(&[&c, &d], |i, out| {
            if i == 1 {
                return Err(io::Error::other("disk full"));
            }
            io::Write::write_all(out, b"x")
        });
        assert!(failed.is_err());
        let mut names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names.len(), 3, "{names:?}");
        assert!(names.contains(&"b.npy.json".to_string()));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn fifos_and_devices_are_refused_at_once() {
        let dir = dir("fifo");
        let fifo = dir.join("pipe.wav");
        let status = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(status.success());
        let error = check_regular(&fifo).unwrap_err();
        assert!(
            error.contains("pipe.wav") && error.contains("FIFO"),
            "{error}"
        );
        let error = check_regular(Path::new("/dev/zero")).unwrap_err();
        assert!(error.contains("character device"), "{error}");
        assert!(check_regular(&dir).is_ok());
        assert!(check_regular(&dir.join("missing.ply")).is_ok());
        std::fs::write(dir.join("a.ply"), b"ply").unwrap();
        assert!(check_regular(&dir.join("a.ply")).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_dropped_owned_child_kills_its_process_and_a_waited_one_reports_it() {
        let child = std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .unwrap();
        let pid = child.id();
        let guard = OwnedChild::new(child);
        assert!(
            owned_children()
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
            owned_children()
                .iter()
                .all(|(_, c)| c.lock().unwrap().id() != pid)
        );
        let done = std::process::Command::new("true").spawn().unwrap();
        assert!(OwnedChild::new(done).wait().unwrap().success());
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
