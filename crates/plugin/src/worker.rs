//! One Python worker process: started with the host script, spoken to over its stdin/stdout
//! (`protocol.rs`), sharing one arena file for pixels. Python runs in its own process, not in
//! ours, so a plugin that hangs can be killed at once when a cook is cancelled, a plugin that
//! crashes its interpreter takes only its worker with it, and pyrograph never links libpython.

use std::collections::VecDeque;
use std::ffi::OsString;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

use pyrograph_core::CookCtx;

use crate::arena::Arena;
use crate::protocol::{FrameError, Reply, read_frame, write_frame};

/// How long a worker may take to start Python and import numpy.
const START_TIMEOUT: Duration = Duration::from_secs(120);
/// How often a waiting cook looks at its cancel flag.
const POLL: Duration = Duration::from_millis(20);
/// How much of a worker's stderr is kept for error messages.
const STDERR_TAIL: usize = 16 << 10;

/// How to start a worker.
#[derive(Clone, Debug)]
pub struct Launch {
    /// The Python interpreter (`PYROGRAPH_PYTHON`, else `python3`).
    pub python: OsString,
    /// The folder holding the host script and the `pyrograph_plugin` module.
    pub host_dir: PathBuf,
}

/// Why a request to a worker got no reply.
#[derive(Debug)]
pub enum WorkerError {
    /// The cook was cancelled; the worker was killed.
    Cancelled,
    /// The worker is gone or broken; the text says why, with its last output.
    Broken(String),
}

/// A running worker.
pub struct Worker {
    child: Child,
    stdin: BufWriter<ChildStdin>,
    replies: Receiver<Result<Reply, FrameError>>,
    stderr: Arc<Mutex<VecDeque<u8>>>,
    /// The shared file for arrays.
    pub arena: Arena,
    broken: bool,
}

impl Worker {
    /// Starts a worker and waits until its Python has numpy; an error says how to fix the setup.
    pub fn start(launch: &Launch, ctx: Option<&CookCtx>) -> Result<Worker, WorkerError> {
        let mut cmd = Command::new(&launch.python);
        let mut path = OsString::from(&launch.host_dir);
        if let Some(old) = std::env::var_os("PYTHONPATH").filter(|p| !p.is_empty()) {
            path.push(":");
            path.push(old);
        }
        cmd.arg("-u")
            .arg(launch.host_dir.join(crate::host::HOST_FILE))
            .env("PYTHONPATH", path)
            .env("PYTHONDONTWRITEBYTECODE", "1")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = spawn(cmd).map_err(|e| {
            WorkerError::Broken(format!(
                "could not start Python ('{}'): {e}; install Python 3 with numpy, or set PYROGRAPH_PYTHON to one",
                launch.python.to_string_lossy()
            ))
        })?;
        let (Some(stdin), Some(stdout), Some(stderr)) = (child.stdin.take(), child.stdout.take(), child.stderr.take()) else {
            let _ = child.kill();
            return Err(WorkerError::Broken("the Python worker's pipes could not be opened".into()));
        };
        let arena = match Arena::create() {
            Ok(arena) => arena,
            Err(e) => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(WorkerError::Broken(format!("could not make the shared file for pixels: {e}")));
            }
        };
        let mut worker = Worker {
            child,
            stdin: BufWriter::new(stdin),
            replies: read_replies(stdout),
            stderr: keep_stderr(stderr),
            arena,
            broken: false,
        };
        let hello = serde_json::json!({"op": "hello", "protocol": 1, "arena": worker.arena.path().map(Path::to_path_buf)});
        match worker.request_within(&hello, ctx, START_TIMEOUT)? {
            Reply::Ready { .. } => {
                worker.arena.unlink();
                Ok(worker)
            }
            other => Err(worker.fail(format!("the Python worker did not start: {}", describe(&other)))),
        }
    }

    /// Kills the worker: it is out of step with this side (a question left unanswered).
    pub fn discard(&mut self) {
        self.kill();
    }

    /// Whether the worker may be used again.
    pub fn healthy(&self) -> bool {
        !self.broken
    }

    /// Sends `msg` and waits for the reply, killing the worker if `ctx` is cancelled meanwhile.
    pub fn request(&mut self, msg: &serde_json::Value, ctx: Option<&CookCtx>) -> Result<Reply, WorkerError> {
        self.send(msg)?;
        self.receive(ctx)
    }

    /// [`Worker::request`] with a time limit: a worker that has not answered by then is killed.
    pub fn request_within(
        &mut self,
        msg: &serde_json::Value,
        ctx: Option<&CookCtx>,
        limit: Duration,
    ) -> Result<Reply, WorkerError> {
        self.send(msg)?;
        self.receive_within(ctx, limit)
    }

    /// Sends one message (a request, or the answer to a worker's question during a cook).
    pub fn send(&mut self, msg: &serde_json::Value) -> Result<(), WorkerError> {
        if self.broken {
            return Err(WorkerError::Broken("the Python worker stopped earlier".into()));
        }
        write_frame(&mut self.stdin, msg).map_err(|e| self.fail(format!("could not send to the Python worker: {e}")))
    }

    /// Waits for the worker's next message, killing the worker if `ctx` is cancelled meanwhile.
    pub fn receive(&mut self, ctx: Option<&CookCtx>) -> Result<Reply, WorkerError> {
        self.receive_within(ctx, Duration::MAX)
    }

    fn receive_within(&mut self, ctx: Option<&CookCtx>, limit: Duration) -> Result<Reply, WorkerError> {
        let start = Instant::now();
        loop {
            match self.replies.recv_timeout(POLL) {
                Ok(Ok(Reply::Fatal { message })) => return Err(self.fail(message)),
                Ok(Ok(reply)) => return Ok(reply),
                Ok(Err(e)) => return Err(self.fail(format!("the Python worker broke the protocol: {e}"))),
                Err(RecvTimeoutError::Disconnected) => return Err(self.fail("the Python worker stopped".into())),
                Err(RecvTimeoutError::Timeout) => {}
            }
            if ctx.is_some_and(|c| c.cancel_token().is_cancelled()) {
                self.kill();
                return Err(WorkerError::Cancelled);
            }
            if start.elapsed() > limit {
                return Err(self.fail(format!("the Python worker did not answer within {:.1} s", limit.as_secs_f64())));
            }
        }
    }

    /// Marks the worker broken and says why, with how it ended and its last stderr lines.
    fn fail(&mut self, why: String) -> WorkerError {
        self.kill();
        let status = match self.child.wait() {
            Ok(s) => exit_text(s),
            Err(_) => String::new(),
        };
        let tail = self.stderr_tail(20);
        let tail = if tail.is_empty() { String::new() } else { format!("; its last output:\n{tail}") };
        WorkerError::Broken(format!("{why}{status}{tail}"))
    }

    fn kill(&mut self) {
        self.broken = true;
        let _ = self.child.kill();
    }

    /// The last `lines` lines the worker wrote to stderr.
    fn stderr_tail(&self, lines: usize) -> String {
        // Give the stderr reader a moment to drain what a dying worker wrote last.
        std::thread::sleep(Duration::from_millis(50));
        let tail = self.stderr.lock().map(|t| t.iter().copied().collect::<Vec<u8>>()).unwrap_or_default();
        let text = String::from_utf8_lossy(&tail);
        let all: Vec<&str> = text.lines().collect();
        all[all.len().saturating_sub(lines)..].join("\n")
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        if !self.broken {
            let _ = write_frame(&mut self.stdin, &serde_json::json!({"op": "bye"}));
            // A worker busy in plugin code does not read `bye`: give it a moment, then kill it.
            let deadline = Instant::now() + Duration::from_millis(500);
            while Instant::now() < deadline {
                if let Ok(Some(_)) = self.child.try_wait() {
                    return;
                }
                std::thread::sleep(Duration::from_millis(10));
            }
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// ", exited with status 1" or ", killed by signal 11 (SIGSEGV)".
fn exit_text(status: std::process::ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(code), _) => format!(" (it exited with status {code})"),
        (None, Some(sig)) => {
            let name = match sig {
                libc::SIGSEGV => " (SIGSEGV)",
                libc::SIGKILL => " (SIGKILL)",
                libc::SIGABRT => " (SIGABRT)",
                libc::SIGBUS => " (SIGBUS)",
                _ => "",
            };
            format!(" (it was killed by signal {sig}{name})")
        }
        _ => String::new(),
    }
}

fn describe(reply: &Reply) -> String {
    match reply {
        Reply::Error(f) => f.error.render(),
        other => format!("it answered '{}' to hello", other.op()),
    }
}

/// A thread that turns the worker's stdout into replies.
fn read_replies(stdout: impl Read + Send + 'static) -> Receiver<Result<Reply, FrameError>> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut r = std::io::BufReader::new(stdout);
        loop {
            match read_frame(&mut r) {
                Ok(Some(reply)) => {
                    if tx.send(Ok(reply)).is_err() {
                        return;
                    }
                }
                Ok(None) => return,
                Err(e) => {
                    let _ = tx.send(Err(e));
                    return;
                }
            }
        }
    });
    rx
}

/// A thread that passes the worker's stderr (a plugin's `print`s, Python's warnings) on to ours
/// and keeps its tail for error messages.
fn keep_stderr(stderr: impl Read + Send + 'static) -> Arc<Mutex<VecDeque<u8>>> {
    let tail = Arc::new(Mutex::new(VecDeque::new()));
    let kept = tail.clone();
    std::thread::spawn(move || {
        let mut r = stderr;
        let mut buf = [0u8; 8192];
        while let Ok(n @ 1..) = r.read(&mut buf) {
            let _ = std::io::stderr().write_all(&buf[..n]);
            if let Ok(mut t) = kept.lock() {
                t.extend(&buf[..n]);
                let over = t.len().saturating_sub(STDERR_TAIL);
                t.drain(..over);
            }
        }
    });
    tail
}

type SpawnRequest = (Command, mpsc::Sender<std::io::Result<Child>>);

/// Starts `cmd` from one long-lived thread. On Linux a worker is told to die with the thread that
/// started it (`PR_SET_PDEATHSIG`), so a pyrograph killed outright leaves no Python behind; that
/// thread must therefore outlive every cook, which rayon's and the evaluator's threads may not.
fn spawn(cmd: Command) -> std::io::Result<Child> {
    static SPAWNER: OnceLock<Mutex<mpsc::Sender<SpawnRequest>>> = OnceLock::new();
    let spawner = SPAWNER.get_or_init(|| {
        let (tx, rx) = mpsc::channel::<SpawnRequest>();
        std::thread::Builder::new()
            .name("plugin-spawner".into())
            .spawn(move || {
                for (mut cmd, reply) in rx {
                    let _ = reply.send(die_with_parent(&mut cmd).spawn());
                }
            })
            .ok();
        Mutex::new(tx)
    });
    let (tx, rx) = mpsc::channel();
    let sent = spawner.lock().map_err(|_| std::io::Error::other("the spawner failed"))?.send((cmd, tx));
    sent.map_err(|_| std::io::Error::other("the spawner thread is gone"))?;
    rx.recv().map_err(|_| std::io::Error::other("the spawner thread is gone"))?
}

#[cfg(target_os = "linux")]
fn die_with_parent(cmd: &mut Command) -> &mut Command {
    use std::os::unix::process::CommandExt;
    let parent = std::process::id() as libc::pid_t;
    // SAFETY: the closure runs in the child between fork and exec and calls only prctl and
    // getppid, both async-signal-safe, and touches no memory of the parent.
    unsafe {
        cmd.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            // The parent may have died before prctl took effect: then nothing would kill us.
            if libc::getppid() != parent {
                return Err(std::io::Error::other("pyrograph exited while starting Python"));
            }
            Ok(())
        })
    }
}

#[cfg(not(target_os = "linux"))]
fn die_with_parent(cmd: &mut Command) -> &mut Command {
    cmd
}
