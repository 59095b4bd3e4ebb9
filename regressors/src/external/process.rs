//! The plugin's child process: one JSON line out on its stdin, one JSON
//! line back from its stdout, each reply awaited at most a timeout; its
//! stderr kept (the last lines) for error messages. The process is always
//! reaped: on `shutdown`, on any failure (it is killed first) and on drop.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How many of the plugin's last stderr lines an error quotes.
pub const STDERR_TAIL_LINES: usize = 20;

/// How long a plugin may take to exit after `shutdown` (or its stdin
/// closing) before it is killed.
const EXIT_GRACE: Duration = Duration::from_secs(2);

/// Why talking to the plugin failed (the caller adds the regressor's label
/// and the request).
#[derive(Debug, Clone, PartialEq)]
pub enum ProcessFailure {
    /// The program could not be started.
    Spawn(String),
    /// Writing the request failed (the plugin has exited).
    Write(String),
    /// No reply within the timeout; the plugin was killed.
    Timeout(Duration),
    /// The plugin closed its stdout (exited) before replying.
    Exited(Option<ExitStatus>),
}

impl std::fmt::Display for ProcessFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Spawn(e) => write!(f, "could not start the plugin: {e}"),
            Self::Write(e) => write!(
                f,
                "could not send the request (has the plugin exited?): {e}"
            ),
            Self::Timeout(t) => write!(
                f,
                "no reply within {:.1} s (timeout_secs); the plugin was killed",
                t.as_secs_f64()
            ),
            Self::Exited(Some(status)) => {
                write!(f, "the plugin exited ({status}) before replying")
            }
            Self::Exited(None) => write!(f, "the plugin closed its stdout before replying"),
        }
    }
}

/// A running plugin.
pub struct PluginProcess {
    child: Child,
    stdin: Option<ChildStdin>,
    replies: Receiver<String>,
    stderr_tail: Arc<Mutex<VecDeque<String>>>,
    readers: Vec<JoinHandle<()>>,
    reaped: bool,
}

impl std::fmt::Debug for PluginProcess {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PluginProcess")
            .field("pid", &self.child.id())
            .field("reaped", &self.reaped)
            .finish()
    }
}

impl PluginProcess {
    /// Starts `command` (program and arguments) in `dir` with piped stdin,
    /// stdout and stderr.
    ///
    /// # Errors
    /// [`ProcessFailure::Spawn`] when the command is empty or cannot run.
    pub fn spawn(command: &[String], dir: Option<&Path>) -> Result<Self, ProcessFailure> {
        let (program, args) = command
            .split_first()
            .ok_or_else(|| ProcessFailure::Spawn("the command is empty".into()))?;
        let mut cmd = Command::new(program);
        cmd.args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        if let Some(dir) = dir {
            cmd.current_dir(dir);
        }
        let mut child = cmd
            .spawn()
            .map_err(|e| ProcessFailure::Spawn(format!("`{}`: {e}", command.join(" "))))?;
        let stdin = child.stdin.take();
        let (stdout, stderr) = (child.stdout.take(), child.stderr.take());
        let (sender, replies) = channel();
        let stderr_tail = Arc::new(Mutex::new(VecDeque::new()));
        let mut readers = Vec::new();
        if let Some(stdout) = stdout {
            readers.push(std::thread::spawn(move || {
                for line in BufReader::new(stdout).lines() {
                    let Ok(line) = line else { break };
                    if sender.send(line).is_err() {
                        break;
                    }
                }
            }));
        }
        if let Some(stderr) = stderr {
            let tail = Arc::clone(&stderr_tail);
            readers.push(std::thread::spawn(move || {
                for line in BufReader::new(stderr).lines() {
                    let Ok(line) = line else { break };
                    if let Ok(mut tail) = tail.lock() {
                        if tail.len() == STDERR_TAIL_LINES {
                            tail.pop_front();
                        }
                        tail.push_back(line);
                    }
                }
            }));
        }
        Ok(Self {
            child,
            stdin,
            replies,
            stderr_tail,
            readers,
            reaped: false,
        })
    }

    /// Whether the process has exited and been reaped (after a failure).
    pub fn is_reaped(&self) -> bool {
        self.reaped
    }

    /// The operating system's id of the process.
    pub fn id(&self) -> u32 {
        self.child.id()
    }

    /// Sends one line and waits at most `timeout` for one line back. On a
    /// timeout the plugin is killed and reaped.
    ///
    /// # Errors
    /// [`ProcessFailure::Write`], [`ProcessFailure::Timeout`] or
    /// [`ProcessFailure::Exited`].
    pub fn exchange(&mut self, line: &str, timeout: Duration) -> Result<String, ProcessFailure> {
        let Some(stdin) = self.stdin.as_mut() else {
            return Err(ProcessFailure::Write("stdin is closed".into()));
        };
        let written = stdin
            .write_all(line.as_bytes())
            .and_then(|()| stdin.write_all(b"\n"))
            .and_then(|()| stdin.flush());
        if let Err(e) = written {
            // The reply channel says whether the plugin already exited.
            self.kill();
            return Err(ProcessFailure::Write(e.to_string()));
        }
        match self.replies.recv_timeout(timeout) {
            Ok(reply) => Ok(reply),
            Err(RecvTimeoutError::Timeout) => {
                self.kill();
                Err(ProcessFailure::Timeout(timeout))
            }
            Err(RecvTimeoutError::Disconnected) => {
                let status = self.wait_for_exit(EXIT_GRACE);
                Err(ProcessFailure::Exited(status))
            }
        }
    }

    /// The plugin's last stderr lines (at most [`STDERR_TAIL_LINES`]), after
    /// its stderr has been read to the end when it has exited.
    pub fn stderr_tail(&mut self) -> Vec<String> {
        if self.reaped {
            // Let the reader drain what the plugin wrote before it exited
            // (bounded: a grandchild may still hold the pipe open).
            let deadline = Instant::now() + Duration::from_millis(500);
            while self.readers.iter().any(|r| !r.is_finished()) && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(5));
            }
        }
        self.stderr_tail
            .lock()
            .map(|t| t.iter().cloned().collect())
            .unwrap_or_default()
    }

    /// The last stderr lines of a plugin that is still running, once its
    /// stderr has been quiet for a moment (at most 250 ms): a plugin writes
    /// its traceback to stderr before its error reply to stdout, and the
    /// two pipes are read by different threads.
    pub fn settled_stderr_tail(&mut self) -> Vec<String> {
        let deadline = Instant::now() + Duration::from_millis(250);
        let mut last = self.stderr_tail();
        let mut quiet_since = Instant::now();
        while Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
            let now = self.stderr_tail();
            if now != last {
                last = now;
                quiet_since = Instant::now();
            } else if quiet_since.elapsed() >= Duration::from_millis(40) {
                break;
            }
        }
        last
    }

    /// Closes the plugin's stdin and waits up to `grace` for it to exit,
    /// then kills it; always reaps it.
    pub fn close(&mut self, grace: Duration) {
        self.stdin = None;
        if self.wait_for_exit(grace).is_none() {
            self.kill();
        }
    }

    /// Kills and reaps the process (no zombie is left behind).
    pub fn kill(&mut self) {
        if !self.reaped {
            let _ = self.child.kill();
            let _ = self.child.wait();
            self.reaped = true;
        }
        self.stdin = None;
    }

    /// Polls for the process's exit for up to `grace`; reaps it when it has
    /// exited.
    fn wait_for_exit(&mut self, grace: Duration) -> Option<ExitStatus> {
        let deadline = Instant::now() + grace;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => {
                    self.reaped = true;
                    return Some(status);
                }
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(5));
                }
                _ => return None,
            }
        }
    }
}

impl Drop for PluginProcess {
    fn drop(&mut self) {
        if !self.reaped {
            self.close(EXIT_GRACE);
        }
    }
}
