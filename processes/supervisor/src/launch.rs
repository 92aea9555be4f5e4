//! Starting, watching and stopping stage processes.

use anyhow::{bail, Context};
use std::io::{BufRead, BufReader, Write};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Poll period while waiting for a stage to exit.
const EXIT_POLL: Duration = Duration::from_millis(20);
/// Longest wait for an ended stage's last stderr lines.
const STDERR_DRAIN: Duration = Duration::from_millis(200);

/// Environment variable naming the folder of the stage binaries (default: next to `hubtrack`).
pub const STAGE_DIR_ENV: &str = "HUBTRACK_STAGE_DIR";

/// Finds the binary of stage `name` (`hubtrack-<name>`) in `$HUBTRACK_STAGE_DIR` or next to the
/// running `hubtrack`.
pub fn stage_binary(name: &str) -> anyhow::Result<PathBuf> {
    let exe = std::env::current_exe().context("locating the hubtrack executable")?;
    let dir = match std::env::var_os(STAGE_DIR_ENV) {
        Some(d) => PathBuf::from(d),
        None => exe
            .parent()
            .context("hubtrack executable has no folder")?
            .to_path_buf(),
    };
    let dir = dir.as_path();
    let bin = dir.join(format!("hubtrack-{name}"));
    if !bin.is_file() {
        bail!(
            "stage binary {} not found next to {} (build all stages: cargo build --release --workspace)",
            bin.display(),
            exe.display()
        );
    }
    Ok(bin)
}

/// A running stage process whose output is forwarded with a `[stage]` prefix.
pub struct Stage {
    /// Stage name.
    pub name: String,
    /// The process.
    pub child: Child,
    /// When it was started.
    pub started: Instant,
    /// When it was started (monotonic ns, the stamps' clock).
    pub started_ns: u64,
    /// Exit status once it ended.
    pub exited: Option<ExitStatus>,
    /// The last `error: ...` line the stage printed.
    stderr: Arc<StderrTail>,
}

/// What a stage's stderr said last, kept by the thread that forwards it.
#[derive(Default)]
struct StderrTail {
    /// The message of the last `error: ...` line.
    last_error: Mutex<Option<String>>,
    /// Set when the stream closed (the process ended).
    closed: AtomicBool,
}

impl Stage {
    /// Starts `binary args...` at niceness `nice` relative to our own (so a systemd `Nice=`
    /// sets the base), forwarding its stdout and stderr line by line to ours (its stdout to our
    /// stderr when `stdout_to_stderr`, to keep our stdout machine-readable). With
    /// `stop_with_us`, the kernel sends it SIGTERM when we die (`run.stop_with_supervisor`).
    ///
    /// Call it from the thread that lives as long as the stage should: the kernel's parent-death
    /// signal fires when the *thread* that forked exits.
    pub fn spawn(
        name: &str,
        binary: &Path,
        args: &[String],
        stdout_to_stderr: bool,
        nice: i32,
        stop_with_us: bool,
    ) -> anyhow::Result<Stage> {
        let mut cmd = Command::new(binary);
        cmd.args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let target = (own_nice()? + nice).clamp(-20, 19);
        // SAFETY: getpid(2) cannot fail.
        let parent = unsafe { libc::getpid() };
        // SAFETY: setpriority(2), prctl(2), getppid(2) and raise(3) are plain system calls, safe
        // between fork and exec. Set before exec, so every thread the stage starts inherits them.
        unsafe {
            cmd.pre_exec(move || {
                if nice != 0 && libc::setpriority(libc::PRIO_PROCESS, 0, target) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                if stop_with_us {
                    if libc::prctl(
                        libc::PR_SET_PDEATHSIG,
                        libc::SIGTERM as libc::c_ulong,
                        0,
                        0,
                        0,
                    ) != 0
                    {
                        return Err(std::io::Error::last_os_error());
                    }
                    // We may have died between fork and prctl: then nobody would signal it.
                    if libc::getppid() != parent {
                        libc::raise(libc::SIGTERM);
                    }
                }
                Ok(())
            });
        }
        let mut child = cmd.spawn().with_context(|| {
            format!(
                "starting stage {name} ({}) at nice {target} (ours {nice:+})",
                binary.display()
            )
        })?;
        let stderr = Arc::new(StderrTail::default());
        forward(
            name,
            child.stdout.take().expect("piped"),
            stdout_to_stderr,
            None,
        );
        forward(
            name,
            child.stderr.take().expect("piped"),
            true,
            Some(stderr.clone()),
        );
        Ok(Stage {
            name: name.into(),
            child,
            started: Instant::now(),
            started_ns: hubtrack_types::time::monotonic_ns(),
            exited: None,
            stderr,
        })
    }

    /// The message of the last `error: ...` line the stage printed, once it has ended (waits up
    /// to [`STDERR_DRAIN`] for its stderr to be read to the end).
    pub fn last_error(&self) -> Option<String> {
        let deadline = Instant::now() + STDERR_DRAIN;
        while !self.stderr.closed.load(Ordering::Acquire) && Instant::now() < deadline {
            std::thread::sleep(EXIT_POLL / 4);
        }
        self.stderr.last_error.lock().ok()?.clone()
    }

    /// Process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Checks (without blocking) whether the process ended.
    pub fn poll(&mut self) -> Option<ExitStatus> {
        if self.exited.is_none() {
            self.exited = self.child.try_wait().ok().flatten();
        }
        self.exited
    }

    /// Sends SIGTERM, waits up to `timeout` for a clean exit, then SIGKILL.
    pub fn stop(&mut self, timeout: Duration) -> Option<ExitStatus> {
        if self.poll().is_some() {
            return self.exited;
        }
        signal(self.pid(), libc::SIGTERM);
        // A stopped (SIGSTOP) process must run again to act on SIGTERM.
        signal(self.pid(), libc::SIGCONT);
        let deadline = Instant::now() + timeout;
        while Instant::now() < deadline {
            if self.poll().is_some() {
                return self.exited;
            }
            std::thread::sleep(EXIT_POLL);
        }
        log::warn!(
            "{} did not stop within {:?}: killing it",
            self.name,
            timeout
        );
        let _ = self.child.kill();
        self.exited = self.child.wait().ok();
        self.exited
    }
}

/// Our own niceness.
fn own_nice() -> anyhow::Result<i32> {
    // SAFETY: getpriority(2) on ourselves; -1 is also a valid niceness, so errno tells errors apart.
    unsafe {
        *libc::__errno_location() = 0;
        let n = libc::getpriority(libc::PRIO_PROCESS, 0);
        if n == -1 && *libc::__errno_location() != 0 {
            return Err(std::io::Error::last_os_error()).context("reading our own niceness");
        }
        Ok(n)
    }
}

/// Sends `sig` to `pid`.
pub fn signal(pid: u32, sig: i32) {
    // SAFETY: plain kill(2) on a child pid we own.
    unsafe {
        libc::kill(pid as libc::pid_t, sig);
    }
}

fn forward(
    name: &str,
    stream: impl std::io::Read + Send + 'static,
    to_stderr: bool,
    tail: Option<Arc<StderrTail>>,
) {
    let prefix = format!("[{name}] ");
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines() {
            let Ok(line) = line else { break };
            if let (Some(tail), Some(message)) = (&tail, line.strip_prefix("error: ")) {
                if let Ok(mut last) = tail.last_error.lock() {
                    *last = Some(message.to_string());
                }
            }
            if to_stderr {
                let _ = writeln!(std::io::stderr().lock(), "{prefix}{line}");
            } else {
                let _ = writeln!(std::io::stdout().lock(), "{prefix}{line}");
            }
        }
        if let Some(tail) = tail {
            tail.closed.store(true, Ordering::Release);
        }
    });
}
