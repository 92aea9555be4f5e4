//! One supervisor per IPC domain: a second `hubtrack run` in the same domain would start a second
//! camera publishing into the same services (and recording into the same file).
//!
//! The supervisor holds an exclusive lock on `/tmp/hubtrack/run-DOMAIN.lock` for as long as it
//! runs; the kernel releases it when the process ends, however it ends (`kill -9` included), so a
//! stale lock never blocks a new run. Holding the lock also proves that no other supervisor owns
//! the stages still running in the domain: those are orphans of a supervisor that was killed, and
//! they are stopped before anything starts.

use anyhow::{bail, Context};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Where the lock files live.
const LOCK_DIR: &str = "/tmp/hubtrack";
/// How long an orphan gets to stop after SIGTERM before it is killed.
const ORPHAN_STOP_TIMEOUT: Duration = Duration::from_secs(3);
/// The stage binaries a supervisor starts (`hubtrack-NAME`).
const STAGE_BINARIES: [&str; 7] = [
    "capture", "sim", "detect", "track", "control", "recorder", "live",
];

/// The held lock; released when dropped or when the process ends.
#[derive(Debug)]
pub struct DomainLock {
    _file: std::fs::File,
    /// The lock file.
    pub path: PathBuf,
}

/// The current IPC domain (`HUBTRACK_DOMAIN`; empty: the default domain).
pub fn current_domain() -> String {
    std::env::var(hubtrack_runtime::ipc::DOMAIN_ENV).unwrap_or_default()
}

/// The lock file of `domain` (any character outside `[A-Za-z0-9._-]` becomes `_`).
pub fn lock_path(domain: &str) -> PathBuf {
    let name: String = if domain.is_empty() {
        "default".into()
    } else {
        domain
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "._-".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    };
    Path::new(LOCK_DIR).join(format!("run-{name}.lock"))
}

/// Takes the lock of `domain`, or says which process holds it.
pub fn acquire(domain: &str) -> anyhow::Result<DomainLock> {
    let path = lock_path(domain);
    std::fs::create_dir_all(LOCK_DIR).with_context(|| format!("creating {LOCK_DIR}"))?;
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .with_context(|| format!("opening the lock file {}", path.display()))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut holder = String::new();
            let _ = file.read_to_string(&mut holder);
            let holder = holder.trim();
            bail!(
                "another hubtrack run is active in this IPC domain ({}){}: stop it first, or set \
                 HUBTRACK_DOMAIN to run a separate pipeline (lock {})",
                if domain.is_empty() { "default" } else { domain },
                if holder.is_empty() {
                    String::new()
                } else {
                    format!(" by supervisor pid {holder}")
                },
                path.display()
            );
        }
        Err(std::fs::TryLockError::Error(e)) => {
            return Err(e).with_context(|| format!("locking {}", path.display()))
        }
    }
    file.set_len(0)?;
    file.rewind()?;
    writeln!(file, "{}", std::process::id())?;
    Ok(DomainLock { _file: file, path })
}

/// A stage process found running in the domain.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Orphan {
    /// Process id.
    pub pid: u32,
    /// Stage name.
    pub stage: String,
}

/// The hubtrack stage processes of `domain` other than our own children. Call while holding
/// the domain's lock: then none of them has a live supervisor.
pub fn find_orphans(domain: &str) -> Vec<Orphan> {
    let me = std::process::id();
    let mut out = Vec::new();
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return out;
    };
    for entry in dir.flatten() {
        let Some(pid) = entry
            .file_name()
            .to_str()
            .and_then(|s| s.parse::<u32>().ok())
        else {
            continue;
        };
        let proc_dir = entry.path();
        let Ok(cmdline) = std::fs::read(proc_dir.join("cmdline")) else {
            continue;
        };
        let argv0 = cmdline.split(|b| *b == 0).next().unwrap_or_default();
        let argv0 = String::from_utf8_lossy(argv0);
        let Some(stage) = Path::new(argv0.as_ref())
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| n.strip_prefix("hubtrack-"))
            .filter(|n| STAGE_BINARIES.contains(n))
        else {
            continue;
        };
        if parent_of(&proc_dir) == Some(me) || !is_alive(&proc_dir) {
            continue;
        }
        let Ok(environ) = std::fs::read(proc_dir.join("environ")) else {
            continue;
        };
        let key = format!("{}=", hubtrack_runtime::ipc::DOMAIN_ENV);
        let theirs = environ
            .split(|b| *b == 0)
            .find_map(|kv| kv.strip_prefix(key.as_bytes()))
            .map(|v| String::from_utf8_lossy(v).into_owned())
            .unwrap_or_default();
        if theirs == domain {
            out.push(Orphan {
                pid,
                stage: stage.to_string(),
            });
        }
    }
    out.sort_by_key(|o| o.pid);
    out
}

fn stat_fields(proc_dir: &Path) -> Option<Vec<String>> {
    let stat = std::fs::read_to_string(proc_dir.join("stat")).ok()?;
    // The name (field 2) may hold spaces and parentheses: fields start after the last ')'.
    let rest = &stat[stat.rfind(')')? + 1..];
    Some(rest.split_whitespace().map(String::from).collect())
}

fn parent_of(proc_dir: &Path) -> Option<u32> {
    stat_fields(proc_dir)?.get(1)?.parse().ok()
}

fn is_alive(proc_dir: &Path) -> bool {
    stat_fields(proc_dir).is_some_and(|f| f.first().is_some_and(|s| s != "Z" && s != "X"))
}

/// Stops `orphans` (SIGTERM, then SIGKILL after [`ORPHAN_STOP_TIMEOUT`]); errors name the pids
/// still running.
pub fn stop_orphans(orphans: &[Orphan]) -> anyhow::Result<()> {
    for o in orphans {
        crate::launch::signal(o.pid, libc::SIGTERM);
    }
    let alive = |o: &&Orphan| is_alive(&Path::new("/proc").join(o.pid.to_string()));
    let t0 = Instant::now();
    while orphans.iter().any(|o| alive(&o)) && t0.elapsed() < ORPHAN_STOP_TIMEOUT {
        std::thread::sleep(Duration::from_millis(20));
    }
    for o in orphans.iter().filter(alive) {
        crate::launch::signal(o.pid, libc::SIGKILL);
    }
    std::thread::sleep(Duration::from_millis(50));
    let left: Vec<String> = orphans
        .iter()
        .filter(alive)
        .map(|o| format!("{} (pid {})", o.stage, o.pid))
        .collect();
    if !left.is_empty() {
        bail!(
            "stages of an earlier run in this IPC domain could not be stopped: {}",
            left.join(", ")
        );
    }
    Ok(())
}

/// Takes the domain's lock and stops the orphaned stages of an earlier supervisor in it.
pub fn claim_domain() -> anyhow::Result<DomainLock> {
    let domain = current_domain();
    let lock = acquire(&domain)?;
    let orphans = find_orphans(&domain);
    if !orphans.is_empty() {
        let list: Vec<String> = orphans
            .iter()
            .map(|o| format!("{} (pid {})", o.stage, o.pid))
            .collect();
        log::warn!(
            "stopping {} stage(s) left running in this IPC domain by an earlier supervisor that \
             was killed: {}",
            orphans.len(),
            list.join(", ")
        );
        stop_orphans(&orphans)?;
    }
    Ok(lock)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_in_the_same_domain_is_refused_and_names_the_holder() {
        let domain = format!("lock-test-{}", std::process::id());
        let first = acquire(&domain).unwrap();
        let e = acquire(&domain).unwrap_err().to_string();
        assert!(e.contains("another hubtrack run is active"), "{e}");
        assert!(
            e.contains(&format!("supervisor pid {}", std::process::id())),
            "{e}"
        );
        // Another domain is independent.
        let other = acquire(&format!("{domain}-other")).unwrap();
        drop(first);
        let again = acquire(&domain).unwrap();
        drop((again, other));
        let _ = std::fs::remove_file(lock_path(&domain));
        let _ = std::fs::remove_file(lock_path(&format!("{domain}-other")));
    }

    #[test]
    fn lock_names_are_file_names() {
        assert_eq!(lock_path(""), Path::new("/tmp/hubtrack/run-default.lock"));
        assert_eq!(
            lock_path("a/../b c"),
            Path::new("/tmp/hubtrack/run-a_.._b_c.lock")
        );
    }
}
