//! An extractor child process read line by line: its stdout (the JSON progress protocol) comes
//! through a channel that can be polled with a timeout, so the caller can check for a cancel
//! between lines; its stderr is read as it comes (a chatty child never blocks on a full pipe),
//! keeping its last [`STDERR_TAIL_BYTES`] for the error message when it fails and every
//! `warning:` line (at most [`MAX_WARNINGS`]) to pass on to the user.
//! Shared by the song extraction (src/extract/child.rs) and the timeline runs
//! (src/extract/timeline.rs).

use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::Duration;

/// How long one [`LinedChild::next_line`] waits before it returns to let the caller look at
/// its cancel flag.
const POLL: Duration = Duration::from_millis(50);

/// How much of the end of the child's stderr is kept for the reason of a failure.
pub const STDERR_TAIL_BYTES: usize = 64 * 1024;
/// Most `warning:` lines kept from the child's stderr.
pub const MAX_WARNINGS: usize = 100;

/// What the child said on stderr: the tail of it, and its warnings.
#[derive(Debug, Default)]
pub struct Stderr {
    /// The last [`STDERR_TAIL_BYTES`] or so, whole lines.
    pub tail: String,
    /// The text after `warning: ` of each line that has it (the extractor's prefix before it
    /// dropped), in order, without repeats.
    pub warnings: Vec<String>,
}

impl Stderr {
    /// Reads `stream` to its end, a line at a time, keeping the tail and the warnings.
    pub fn read_from(stream: impl Read) -> Stderr {
        let mut out = Stderr::default();
        let mut reader = BufReader::with_capacity(64 * 1024, stream);
        let mut line = Vec::new();
        loop {
            line.clear();
            // A line is cut at the tail's size, so one endless line cannot grow memory.
            match (&mut reader)
                .take(STDERR_TAIL_BYTES as u64)
                .read_until(b'\n', &mut line)
            {
                Ok(0) | Err(_) => break,
                Ok(_) => {}
            }
            let text = String::from_utf8_lossy(&line);
            out.keep(&text);
        }
        out
    }

    fn keep(&mut self, line: &str) {
        if let Some(at) = line.find("warning: ")
            && self.warnings.len() < MAX_WARNINGS
        {
            let warning = line[at + "warning: ".len()..].trim().to_string();
            if !warning.is_empty() && !self.warnings.contains(&warning) {
                self.warnings.push(warning);
            }
        }
        self.tail.push_str(line);
        if !line.ends_with('\n') {
            self.tail.push('\n');
        }
        if self.tail.len() > 2 * STDERR_TAIL_BYTES {
            let mut cut = self.tail.len() - STDERR_TAIL_BYTES;
            while !self.tail.is_char_boundary(cut) {
                cut += 1;
            }
            self.tail.drain(..cut);
        }
    }
}

/// What [`LinedChild::next_line`] saw.
pub enum Next {
    Line(String),
    /// No line within the poll time; the child still runs.
    Waiting,
    /// Stdout closed: the child has finished (or closed it).
    Closed,
}

/// A running child with its stdout read into a channel and its stderr into a string.
pub struct LinedChild {
    child: Child,
    /// Registered for the signal handler: the app's SIGINT/SIGTERM kills the child too.
    _guard: crate::files::ChildGuard,
    lines: mpsc::Receiver<String>,
    reader: JoinHandle<()>,
    errors: JoinHandle<Stderr>,
}

impl LinedChild {
    /// Starts `command` with stdin closed and stdout and stderr piped, as the leader of its own
    /// process group, killed with everything it started when the app is stopped by a signal.
    pub fn spawn(command: &mut Command) -> std::io::Result<Self> {
        let mut child = crate::files::own_process_group(command)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        let stdout = child.stdout.take().expect("stdout is piped");
        let stderr = child.stderr.take().expect("stderr is piped");
        let (lines_in, lines) = mpsc::channel();
        let reader = std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if lines_in.send(line).is_err() {
                    break;
                }
            }
        });
        let errors = std::thread::spawn(move || Stderr::read_from(stderr));
        Ok(Self {
            _guard: crate::files::ChildGuard::new(child.id()),
            child,
            lines,
            reader,
            errors,
        })
    }

    /// The next stdout line, waiting at most the poll time for it.
    pub fn next_line(&self) -> Next {
        match self.lines.recv_timeout(POLL) {
            Ok(line) => Next::Line(line),
            Err(mpsc::RecvTimeoutError::Timeout) => Next::Waiting,
            Err(mpsc::RecvTimeoutError::Disconnected) => Next::Closed,
        }
    }

    /// Kills the child (and what it started) and waits for it and its reader threads.
    pub fn kill(mut self) {
        crate::files::kill_process_group(self.child.id());
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = self.reader.join();
        let _ = self.errors.join();
    }

    /// Waits for the child to exit: its status and what it wrote to stderr.
    pub fn finish(mut self) -> std::io::Result<(ExitStatus, Stderr)> {
        let status = self.child.wait()?;
        let _ = self.reader.join();
        let stderr = self.errors.join().unwrap_or_default();
        Ok((status, stderr))
    }
}

/// The reason to give when the child failed without an error line of the protocol: the last
/// non-empty line of its stderr, without the extractor's own prefixes.
pub fn last_words(stderr: &str, status: ExitStatus) -> String {
    match stderr.lines().rev().find(|l| !l.trim().is_empty()) {
        Some(line) => line
            .trim()
            .trim_start_matches("loudscape-extract: ")
            .trim_start_matches("error: ")
            .to_string(),
        None => format!("it exited with {status} and said nothing"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_and_stderr_come_back() {
        let mut command = Command::new("sh");
        command.args([
            "-c",
            "echo one; echo two; echo 'loudscape-extract: bad.wav: silent' >&2; exit 3",
        ]);
        let child = LinedChild::spawn(&mut command).unwrap();
        let mut seen = Vec::new();
        loop {
            match child.next_line() {
                Next::Line(line) => seen.push(line),
                Next::Waiting => {}
                Next::Closed => break,
            }
        }
        assert_eq!(seen, ["one", "two"]);
        let (status, stderr) = child.finish().unwrap();
        assert_eq!(status.code(), Some(3));
        assert_eq!(last_words(&stderr.tail, status), "bad.wav: silent");
    }

    #[test]
    fn silence_names_the_exit_status() {
        let mut command = Command::new("sh");
        command.args(["-c", "exit 2"]);
        let (status, stderr) = LinedChild::spawn(&mut command).unwrap().finish().unwrap();
        assert!(last_words(&stderr.tail, status).contains("said nothing"));
    }

    /// A child that writes megabytes to stderr before its first stdout line (more than any pipe
    /// holds) is not blocked, its warnings come through, and the tail kept stays bounded.
    #[test]
    fn a_chatty_stderr_neither_blocks_nor_grows() {
        let mut command = Command::new("sh");
        command.args([
            "-c",
            "echo 'loudscape-extract: warning: a.flac: decoded 1.49 s of 4.00 s' >&2; \
             yes 'noise noise noise noise noise noise noise noise' | head -c 8000000 >&2; \
             echo 'loudscape-extract: warning: a.flac: decoded 1.49 s of 4.00 s' >&2; \
             echo done; echo 'last words' >&2",
        ]);
        let child = LinedChild::spawn(&mut command).unwrap();
        let start = std::time::Instant::now();
        let mut seen = Vec::new();
        loop {
            match child.next_line() {
                Next::Line(line) => seen.push(line),
                Next::Waiting => assert!(start.elapsed().as_secs() < 60, "blocked"),
                Next::Closed => break,
            }
        }
        assert_eq!(seen, ["done"]);
        let (status, stderr) = child.finish().unwrap();
        assert!(status.success());
        assert_eq!(stderr.warnings, ["a.flac: decoded 1.49 s of 4.00 s"]);
        assert!(
            stderr.tail.len() <= 2 * STDERR_TAIL_BYTES,
            "{}",
            stderr.tail.len()
        );
        assert_eq!(last_words(&stderr.tail, status), "last words");
    }

    #[test]
    fn a_killed_child_is_reaped() {
        let mut command = Command::new("sh");
        command.args(["-c", "sleep 30"]);
        let child = LinedChild::spawn(&mut command).unwrap();
        assert!(matches!(child.next_line(), Next::Waiting));
        child.kill();
    }
}
