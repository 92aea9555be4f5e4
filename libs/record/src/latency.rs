//! Latency per stage and per hop from the stamps in a recording (live or replayed).
//!
//! Every message carries its frame's `seq` and `capture_ns`, and its stage's `recv_ns` and
//! `publish_ns` (monotonic). So: stage time = `publish_ns - recv_ns`; hop time = consumer
//! `recv_ns` − producer `publish_ns` for the same seq; end to end = setpoint `publish_ns` −
//! `capture_ns`. Frames a stage never produced a result for count as dropped at that stage.

use crate::channels::{self, Channels};
use hubtrack_types::{Detection, Stamps};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Percentiles of one latency, microseconds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stat {
    /// Stage or hop name.
    pub name: String,
    /// Median.
    pub p50_us: f64,
    /// 90th percentile.
    pub p90_us: f64,
    /// 99th percentile.
    pub p99_us: f64,
    /// Maximum.
    pub max_us: f64,
    /// Samples.
    pub count: u64,
    /// Frames that should have produced a sample but did not (skipped or dropped).
    pub dropped: u64,
}

/// The latency report of one recording.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Report {
    /// Time inside each stage.
    pub stages: Vec<Stat>,
    /// Time between stages.
    pub hops: Vec<Stat>,
    /// Capture to the last stage's output.
    pub end_to_end: Vec<Stat>,
    /// The detect stage's own split of its time (`pyramid`, `edges`, `hough`, `geometry`), from
    /// the timings each detection carries: where to look when the detect stage is slow.
    pub detect_steps: Vec<Stat>,
    /// Messages without usable stamps (all zero), per topic.
    pub unstamped: BTreeMap<String, u64>,
    /// Messages on topics this tool does not know (ignored), per topic.
    pub unknown_topics: BTreeMap<String, u64>,
    /// Why reading stopped early, if the file is cut or damaged.
    pub read_error: Option<String>,
}

/// Why no report could be made (the recording could not be read).
pub use crate::channels::ReadError as LatencyError;

fn stat(name: &str, mut v: Vec<f64>, dropped: u64) -> Stat {
    v.sort_by(|a, b| a.total_cmp(b));
    let at = |q: f64| {
        if v.is_empty() {
            f64::NAN
        } else {
            v[((v.len() - 1) as f64 * q).round() as usize]
        }
    };
    Stat {
        name: name.into(),
        p50_us: at(0.5),
        p90_us: at(0.9),
        p99_us: at(0.99),
        max_us: v.last().copied().unwrap_or(f64::NAN),
        count: v.len() as u64,
        dropped,
    }
}

fn us(later: u64, earlier: u64) -> Option<f64> {
    (later >= earlier && earlier > 0).then(|| (later - earlier) as f64 / 1e3)
}

/// Reads `path` (complete, cut or damaged: whatever is readable) and computes the report.
pub fn analyze(path: &Path) -> Result<Report, LatencyError> {
    let Channels {
        frames,
        detections: dets,
        tracks,
        setpoints: sps,
        unstamped,
        unknown_topics,
        read_error,
        ..
    } = channels::read(path)?;
    let mut report = Report {
        unstamped,
        unknown_topics,
        read_error,
        ..Default::default()
    };
    // Frames are only counted as expected for a stage within the seq range that stage covered
    // (a stage started later, or a recording cut early, is not "dropping").
    let missing = |have: &BTreeMap<u64, Stamps>, upstream: &BTreeMap<u64, u64>| -> u64 {
        let (Some(first), Some(last)) = (have.keys().next(), have.keys().last()) else {
            return 0;
        };
        upstream
            .keys()
            .filter(|s| (*first..=*last).contains(*s) && !have.contains_key(s))
            .count() as u64
    };
    let frame_pub: BTreeMap<u64, u64> = frames.iter().map(|(s, h)| (*s, h.publish_ns)).collect();
    let det_st: BTreeMap<u64, Stamps> = dets.iter().map(|(s, d)| (*s, d.stamps)).collect();
    let trk_st: BTreeMap<u64, Stamps> = tracks.iter().map(|(s, t)| (*s, t.stamps)).collect();
    let sp_st: BTreeMap<u64, Stamps> = sps.iter().map(|(s, t)| (*s, t.stamps)).collect();
    let det_pub: BTreeMap<u64, u64> = det_st.iter().map(|(s, d)| (*s, d.publish_ns)).collect();
    let trk_pub: BTreeMap<u64, u64> = trk_st.iter().map(|(s, d)| (*s, d.publish_ns)).collect();

    if !frames.is_empty() {
        let v = frames
            .values()
            .filter_map(|h| us(h.publish_ns, h.capture_ns))
            .collect();
        let gaps = frames
            .keys()
            .zip(frames.keys().skip(1))
            .map(|(a, b)| b - a - 1)
            .sum();
        report.stages.push(stat("capture", v, gaps));
    }
    for (name, st) in [("detect", &det_st), ("track", &trk_st), ("control", &sp_st)] {
        if !st.is_empty() {
            report.stages.push(stat(
                name,
                st.values()
                    .filter_map(|s| us(s.publish_ns, s.recv_ns))
                    .collect(),
                0,
            ));
        }
    }
    let hop = |name: &str, up: &BTreeMap<u64, u64>, down: &BTreeMap<u64, Stamps>| {
        let v = down
            .iter()
            .filter_map(|(seq, s)| up.get(seq).and_then(|p| us(s.recv_ns, *p)))
            .collect();
        stat(name, v, missing(down, up))
    };
    if !det_st.is_empty() && !frame_pub.is_empty() {
        report
            .hops
            .push(hop("capture->detect", &frame_pub, &det_st));
    }
    if !trk_st.is_empty() && !det_pub.is_empty() {
        report.hops.push(hop("detect->track", &det_pub, &trk_st));
    }
    if !sp_st.is_empty() && !trk_pub.is_empty() {
        report.hops.push(hop("track->control", &trk_pub, &sp_st));
    }
    for (name, st) in [
        ("capture->detection", &det_st),
        ("capture->track", &trk_st),
        ("capture->setpoint", &sp_st),
    ] {
        if !st.is_empty() {
            let dropped = if frame_pub.is_empty() {
                0
            } else {
                missing(st, &frame_pub)
            };
            report.end_to_end.push(stat(
                name,
                st.values()
                    .filter_map(|s| us(s.publish_ns, s.capture_ns))
                    .collect(),
                dropped,
            ));
        }
    }
    if !dets.is_empty() {
        let t = |f: fn(&Detection) -> f64| {
            dets.values()
                .map(f)
                .filter(|v| *v > 0.0)
                .collect::<Vec<f64>>()
        };
        report.detect_steps = vec![
            stat("pyramid", t(|d| d.timings.pyramid_us), 0),
            stat("edges", t(|d| d.timings.edges_us), 0),
            stat("hough", t(|d| d.timings.hough_us), 0),
            stat("geometry", t(|d| d.timings.geometry_us), 0),
        ];
        report.detect_steps.retain(|s| s.count > 0);
    }
    Ok(report)
}

/// Prints the report as a table.
pub fn print(report: &Report) {
    let section = |title: &str, rows: &[Stat]| {
        if rows.is_empty() {
            return;
        }
        println!(
            "{title:<22}{:>10}{:>10}{:>10}{:>10}{:>9}{:>9}",
            "p50 us", "p90 us", "p99 us", "max us", "count", "dropped"
        );
        for s in rows {
            println!(
                "  {:<20}{:>10.0}{:>10.0}{:>10.0}{:>10.0}{:>9}{:>9}",
                s.name, s.p50_us, s.p90_us, s.p99_us, s.max_us, s.count, s.dropped
            );
        }
    };
    section("stage", &report.stages);
    section("hop", &report.hops);
    section("end to end", &report.end_to_end);
    section("detect steps", &report.detect_steps);
    for (t, n) in &report.unstamped {
        println!("note: {n} messages on {t} lack stamps (ignored)");
    }
    for (t, n) in &report.unknown_topics {
        println!("note: {n} messages on unknown topic {t} (ignored)");
    }
    if let Some(e) = &report.read_error {
        println!("note: the file is cut or damaged; read up to: {e}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::writer::{ChannelKind, Recording, RecordingOptions};
    use hubtrack_types::FrameHeader;

    fn stamps(seq: u64, base: u64) -> Stamps {
        Stamps {
            seq,
            capture_ns: base,
            recv_ns: base + 2_000_000,
            publish_ns: base + 5_000_000,
        }
    }

    #[test]
    fn stage_hop_and_end_to_end_from_stamps() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("l.mcap");
        let mut rec = Recording::create(&path, &RecordingOptions::default()).unwrap();
        for seq in 0..10u64 {
            let base = 1_000_000_000 + seq * 33_000_000;
            let h = FrameHeader {
                seq,
                capture_ns: base,
                publish_ns: base + 1_000_000,
                ..Default::default()
            };
            rec.write_frame(&h, None, 1).unwrap();
            if seq % 2 == 0 {
                let mut d = Detection {
                    stamps: stamps(seq, base),
                    ..Default::default()
                };
                d.timings.pyramid_us = 100.0 + seq as f64;
                d.timings.hough_us = 700.0;
                rec.write_json(ChannelKind::Detection, seq, 1, 1, &d)
                    .unwrap();
            }
        }
        rec.write_json(ChannelKind::Detection, 99, 1, 1, &Detection::default())
            .unwrap();
        rec.finish().unwrap();
        let r = analyze(&path).unwrap();
        let cap = &r.stages[0];
        assert_eq!(
            (cap.name.as_str(), cap.count, cap.p50_us, cap.dropped),
            ("capture", 10, 1000.0, 0)
        );
        let det = &r.stages[1];
        assert_eq!((det.count, det.p50_us), (5, 3000.0));
        let hop = &r.hops[0];
        assert_eq!(
            (hop.p50_us, hop.count, hop.dropped),
            (1000.0, 5, 4),
            "4 frames skipped inside 0..=8"
        );
        assert_eq!(r.end_to_end[0].p50_us, 5000.0);
        assert_eq!(r.unstamped.get("/detections"), Some(&1));
        // Steps the detector did not time (zero) are left out, not reported as 0 us.
        let steps: Vec<(&str, f64, u64)> = r
            .detect_steps
            .iter()
            .map(|s| (s.name.as_str(), s.p50_us, s.count))
            .collect();
        assert_eq!(steps, vec![("pyramid", 104.0, 5), ("hough", 700.0, 5)]);
    }

    #[test]
    fn bad_files_give_clear_errors() {
        let dir = tempfile::tempdir().unwrap();
        let empty = dir.path().join("empty.mcap");
        std::fs::write(&empty, b"").unwrap();
        assert!(matches!(
            analyze(&empty),
            Err(LatencyError::Open(crate::reader::OpenError::NotMcap { .. }))
        ));
        let only_status = dir.path().join("status.mcap");
        let mut rec = Recording::create(&only_status, &RecordingOptions::default()).unwrap();
        rec.write_json(
            ChannelKind::Status,
            0,
            1,
            1,
            &hubtrack_types::StageStatus::default(),
        )
        .unwrap();
        rec.finish().unwrap();
        let e = analyze(&only_status).unwrap_err().to_string();
        assert!(e.contains("no stamped hubtrack messages"), "{e}");
    }
}
