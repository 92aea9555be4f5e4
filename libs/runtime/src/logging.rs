//! Logging for stage processes: one line per event on stderr,
//! `<time> <LEVEL> <stage>: <message> key=value ...`. `RUST_LOG` overrides the level (default info).
//!
//! Every line printed is also kept for the recorder: once a [`LogForwarder`] exists (each
//! started stage has one, in its heartbeat), lines wait in a bounded queue until the stage's
//! loop hands them to the log service, from which the recorder writes `/log`. The queue is
//! drained from the loop rather than from the log call because a log call may come from any
//! thread, and an iceoryx2 publisher belongs to one.

use crate::ipc::{Ipc, IpcError, MsgPublisher};
use hubtrack_types::services::LOG;
use hubtrack_types::time::realtime_ns;
use hubtrack_types::{LogLevel, LogLine, Text512, Text64};
use iceoryx2::prelude::Node;
use std::collections::VecDeque;
use std::io::Write;
use std::sync::Mutex;

/// Lines that wait for the stage's loop at most; beyond, new lines are counted, not kept (a
/// loop stalled for that long has its own line to say so).
const MAX_WAITING: usize = 1024;

/// Lines logged since the last [`LogForwarder::forward`]; `None` while no forwarder exists (a
/// command-line tool), so nothing accumulates.
static WAITING: Mutex<Option<Waiting>> = Mutex::new(None);

#[derive(Default)]
struct Waiting {
    lines: VecDeque<LogLine>,
    /// Lines not kept because the queue was full.
    overflowed: u64,
}

/// Initialises the logger for a process named `stage`. Safe to call once per process.
/// iceoryx2's own log goes to stderr at level error unless `IOX2_LOG_LEVEL` says otherwise (its
/// warnings, e.g. "no config file loaded, defaults used", are expected here and only noise).
pub fn init(stage: &'static str) {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let env = env_logger::Env::default().default_filter_or("info");
    let _ = env_logger::Builder::from_env(env)
        .format(move |buf, record| {
            // Formatted once, for stderr and for the recording.
            let text = record.args().to_string();
            keep(record, &text);
            writeln!(
                buf,
                "{} {:5} {}: {text}",
                buf.timestamp_millis(),
                record.level(),
                stage,
            )
        })
        // iceoryx2's own logger is separate; keep third-party crates quiet unless asked.
        .filter_module("mcap", log::LevelFilter::Warn)
        .try_init();
}

/// The `foxglove.Log` level of a `log` level (trace counts as debug: Foxglove has no trace).
pub fn level(level: log::Level) -> LogLevel {
    match level {
        log::Level::Error => LogLevel::Error,
        log::Level::Warn => LogLevel::Warning,
        log::Level::Info => LogLevel::Info,
        log::Level::Debug | log::Level::Trace => LogLevel::Debug,
    }
}

/// Queues `record`, formatted as `text`, for the forwarder, if there is one (which names the
/// stage).
fn keep(record: &log::Record<'_>, text: &str) {
    let Ok(mut waiting) = WAITING.lock() else {
        return;
    };
    let Some(waiting) = waiting.as_mut() else {
        return;
    };
    if waiting.lines.len() >= MAX_WAITING {
        waiting.overflowed += 1;
        return;
    }
    waiting.lines.push_back(LogLine {
        realtime_ns: realtime_ns(),
        level: level(record.level()),
        line: record.line().unwrap_or(0),
        stage: Text64::default(),
        file: Text64::new(record.file().unwrap_or("")),
        text: Text512::new(text),
    });
}

/// Hands the lines a stage logs to the log service (see the module doc).
pub struct LogForwarder {
    publisher: MsgPublisher<LogLine>,
    stage: Text64,
    /// Lines the service refused, not yet said.
    unsent: u64,
}

impl LogForwarder {
    /// Opens the log service for `stage` (the name the recording gives its lines) and starts
    /// keeping the lines the process logs.
    pub fn new(node: &Node<Ipc>, stage: &str) -> Result<Self, IpcError> {
        let publisher = MsgPublisher::new(node, &LOG)?;
        if let Ok(mut waiting) = WAITING.lock() {
            waiting.get_or_insert_with(Waiting::default);
        }
        Ok(LogForwarder {
            publisher,
            stage: Text64::new(stage),
            unsent: 0,
        })
    }

    /// Publishes the lines logged since the last call, and a line saying how many were lost if
    /// any were. Never logs itself (that would feed the queue it drains).
    pub fn forward(&mut self) {
        let (lines, overflowed) = match WAITING.lock() {
            Ok(mut w) => match w.as_mut() {
                Some(w) if !w.lines.is_empty() || w.overflowed > 0 => (
                    std::mem::take(&mut w.lines),
                    std::mem::take(&mut w.overflowed),
                ),
                _ => return,
            },
            Err(_) => return,
        };
        for mut line in lines {
            line.stage = self.stage;
            if self.publisher.publish(line).is_err() {
                self.unsent += 1;
            }
        }
        let lost = overflowed + std::mem::take(&mut self.unsent);
        if lost > 0 {
            let line = LogLine {
                realtime_ns: realtime_ns(),
                level: LogLevel::Warning,
                line: 0,
                stage: self.stage,
                file: Text64::new(file!()),
                text: Text512::new(&format!(
                    "{lost} log line(s) of this stage are missing from the recording (more than {MAX_WAITING} waited, or the log service refused them)"
                )),
            };
            if self.publisher.publish(line).is_err() {
                self.unsent += lost;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_log_level_has_a_foxglove_level() {
        assert_eq!(level(log::Level::Error), LogLevel::Error);
        assert_eq!(level(log::Level::Warn), LogLevel::Warning);
        assert_eq!(level(log::Level::Info), LogLevel::Info);
        assert_eq!(level(log::Level::Debug), LogLevel::Debug);
        assert_eq!(level(log::Level::Trace), LogLevel::Debug);
    }
}
