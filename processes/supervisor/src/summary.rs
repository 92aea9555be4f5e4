//! What `hubtrack run` prints at the end, and the default recording name.

use hubtrack_types::StageStatus;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;

/// Prints the per-stage counts and the recording files of a run.
pub fn print_summary(
    elapsed: Duration,
    statuses: &BTreeMap<String, StageStatus>,
    segments: &[PathBuf],
) {
    let secs = elapsed.as_secs_f64();
    println!("\n== hubtrack run summary ({secs:.1} s) ==");
    if let Some(c) = statuses.get("capture") {
        let up = c.publish_ns.saturating_sub(c.started_ns) as f64 / 1e9;
        println!(
            "  capture   {} frames published ({:.1} fps), {} errors{}",
            c.outputs,
            c.outputs as f64 / up.max(1e-9),
            c.errors,
            if c.errors > 0 {
                format!(" (last: {})", c.last_error.as_str())
            } else {
                String::new()
            }
        );
    }
    if let Some(s) = statuses.get("sim") {
        println!(
            "  sim       {} frames rendered, {} setpoints seen, {} errors",
            s.outputs, s.inputs, s.errors
        );
    }
    for stage in ["detect", "track", "control"] {
        if let Some(s) = statuses.get(stage) {
            println!(
                "  {stage:<9} {} in, {} out, {} skipped, {} errors",
                s.inputs, s.outputs, s.skipped, s.errors
            );
        }
    }
    if let Some(r) = statuses.get("recorder") {
        println!(
            "  recorder  {} frames received, {} recorded, {} dropped (disk behind or lost in shared memory), {} errors{}{}",
            r.inputs,
            r.outputs,
            r.dropped,
            r.errors,
            if r.errors > 0 {
                format!(" (last: {})", r.last_error.as_str())
            } else {
                String::new()
            },
            if segments.len() > 1 { " (last segment)" } else { "" }
        );
    }
    if let Some(l) = statuses.get("live") {
        println!(
            "  live      {} frames in, {} sent as video, {} skipped (no viewer, or the frame-rate or bitrate cap), {} errors",
            l.inputs, l.outputs, l.skipped, l.errors
        );
    }
    for path in segments {
        match hubtrack_record::inspect(path) {
            Ok(info) => {
                println!(
                    "  file      {} ({:.1} MB, {})",
                    path.display(),
                    info.size_bytes as f64 / 1e6,
                    if info.finished {
                        "finished"
                    } else {
                        "NOT finished: run `hubtrack recover` on it"
                    }
                );
                let channels: Vec<String> = info
                    .topic_counts
                    .iter()
                    .map(|(t, n)| format!("{t} {n}"))
                    .collect();
                println!("  channels  {}", channels.join(", "));
            }
            Err(e) => println!("  file      {} unreadable: {e}", path.display()),
        }
    }
    if let Some(path) = segments.first() {
        println!(
            "  open it   in Foxglove or Lichtblick (Open local file), or `hubtrack latency {}`",
            path.display()
        );
    }
}

/// `hubtrack-YYYYmmdd-HHMMSS.mcap` in UTC.
pub fn timestamped_name() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Civil-from-days (Howard Hinnant's algorithm), proleptic Gregorian, UTC.
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "hubtrack-{y:04}{m:02}{d:02}-{:02}{:02}{:02}.mcap",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}
