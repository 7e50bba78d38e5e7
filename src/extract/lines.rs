//! An extractor child process read line by line: its stdout (the JSON progress protocol) comes
//! through a channel that can be polled with a timeout, so the caller can check for a cancel
//! between lines; its stderr is collected whole, for the error message when it fails.
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
    lines: mpsc::Receiver<String>,
    reader: JoinHandle<()>,
    errors: JoinHandle<String>,
}

impl LinedChild {
    /// Starts `command` with stdin closed and stdout and stderr piped.
    pub fn spawn(command: &mut Command) -> std::io::Result<Self> {
        let mut child = command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        let stdout = child.stdout.take().expect("stdout is piped");
        let mut stderr = child.stderr.take().expect("stderr is piped");
        let (lines_in, lines) = mpsc::channel();
        let reader = std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if lines_in.send(line).is_err() {
                    break;
                }
            }
        });
        let errors = std::thread::spawn(move || {
            let mut text = String::new();
            let _ = stderr.read_to_string(&mut text);
            text
        });
        Ok(Self {
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

    /// Kills the child and waits for it and its reader threads.
    pub fn kill(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = self.reader.join();
        let _ = self.errors.join();
    }

    /// Waits for the child to exit: its status and everything it wrote to stderr.
    pub fn finish(mut self) -> std::io::Result<(ExitStatus, String)> {
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
        assert_eq!(last_words(&stderr, status), "bad.wav: silent");
    }

    #[test]
    fn silence_names_the_exit_status() {
        let mut command = Command::new("sh");
        command.args(["-c", "exit 2"]);
        let (status, stderr) = LinedChild::spawn(&mut command).unwrap().finish().unwrap();
        assert!(last_words(&stderr, status).contains("said nothing"));
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
