//! Logging for stage processes: one line per event on stderr,
//! `<time> <LEVEL> <stage>: <message> key=value ...`. `RUST_LOG` overrides the level (default info).

use std::io::Write;

/// Initialises the logger for a process named `stage`. Safe to call once per process.
/// iceoryx2's own log goes to stderr at level error unless `IOX2_LOG_LEVEL` says otherwise (its
/// warnings, e.g. "no config file loaded, defaults used", are expected here and only noise).
pub fn init(stage: &'static str) {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let env = env_logger::Env::default().default_filter_or("info");
    let _ = env_logger::Builder::from_env(env)
        .format(move |buf, record| {
            writeln!(
                buf,
                "{} {:5} {}: {}",
                buf.timestamp_millis(),
                record.level(),
                stage,
                record.args()
            )
        })
        // iceoryx2's own logger is separate; keep third-party crates quiet unless asked.
        .filter_module("mcap", log::LevelFilter::Warn)
        .try_init();
}
