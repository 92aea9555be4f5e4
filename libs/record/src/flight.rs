//! How a simulated flight's estimates compared with its truth, band by band of distance: where
//! the detector lost the hub, where the distance read long or short, where the yaw took the wrong
//! sign, and which cues were there. `hubtrack diagnose FILE` prints it; it needs frames with
//! truth (`hubtrack fly --record`, or a replay of such a recording, which keeps the headers).
//!
//! Truth comes from `/frames/header`; the estimates from `/detections` and `/track` of the same
//! `seq`; the spinner's looming ([`crate::looming`]) from the circles and `/vehicle`. A yaw "has the wrong sign" when both the truth and the estimate are valid, the truth is
//! at least [`SIGN_MIN_DEG`] from zero, and the signs differ: the failure that makes T2 fly the
//! wrong way.

use crate::channels::{self, ReadError};
use crate::looming;
use hubtrack_types::{ApproachTask, Detection, FrameHeader, TrackMode, TrackState};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A yaw's sign is judged only when the truth is at least this far from zero, degrees (closer,
/// either sign is a fraction of a degree from the truth).
pub const SIGN_MIN_DEG: f64 = 3.0;

/// Bands of truth distance reported, metres `[lo, hi)`, far to near.
pub const BANDS_M: [(f64, f64); 5] = [
    (30.0, f64::INFINITY),
    (20.0, 30.0),
    (10.0, 20.0),
    (5.0, 10.0),
    (0.0, 5.0),
];

/// Median and 90th percentile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spread {
    /// Median.
    pub p50: f64,
    /// 90th percentile.
    pub p90: f64,
}

/// One band of truth distance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Band {
    /// `"30+ m"`, `"20-30 m"`, ... or `"all"`.
    pub name: String,
    /// Frames with truth in the band (hub in view).
    pub frames: u64,
    /// Share of those with a detected hub, %.
    pub detected_pct: f64,
    /// Distance of the detected hub from the true hub, % of the image height.
    pub hub_error_pct: Option<Spread>,
    /// Share of the frames with a tower band / a spinner circle / a nacelle end, %.
    pub tower_pct: f64,
    /// See `tower_pct`.
    pub circle_pct: f64,
    /// See `tower_pct`.
    pub nacelle_pct: f64,
    /// Of the nacelle ends at a truth yaw beyond [`SIGN_MIN_DEG`], the share on the side the yaw
    /// puts the nacelle, %.
    pub nacelle_side_ok_pct: Option<f64>,
    /// Share of the frames with a valid tracked distance, %.
    pub distance_valid_pct: f64,
    /// Tracked distance over the true one (10th percentile, median, 90th percentile).
    pub distance_ratio: Option<[f64; 3]>,
    /// Share of the frames with a valid tracked yaw, %.
    pub yaw_valid_pct: f64,
    /// |tracked − true| yaw, degrees.
    pub yaw_error_deg: Option<Spread>,
    /// Of the valid yaws at a truth beyond [`SIGN_MIN_DEG`], the share with the wrong sign, %.
    pub yaw_wrong_sign_pct: Option<f64>,
    /// Share of the frames with a yaw from the detector's learned yaw network, %.
    pub net_valid_pct: f64,
    /// |network yaw − true yaw|, degrees.
    pub net_error_deg: Option<Spread>,
    /// Network yaws of the wrong sign, % of those where the true |yaw| ≥ [`SIGN_MIN_DEG`].
    pub net_wrong_sign_pct: Option<f64>,
    /// Share of the frames with a distance from the spinner's looming ([`crate::looming`]), %.
    pub looming_pct: f64,
    /// |looming distance / true distance − 1|, %.
    pub looming_error_pct: Option<Spread>,
    /// Of the frames with both a looming and a valid tracked distance, the share where they
    /// differ by more than [`crate::looming::DISAGREE_FACTOR`], % (no truth needed).
    pub looming_disagrees_pct: Option<f64>,
}

/// The truth and the track at the last frame with truth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LastFrame {
    /// Frame `seq`.
    pub seq: u64,
    /// True distance to the hub, m.
    pub distance_m: f64,
    /// True relative yaw, degrees.
    pub yaw_deg: f64,
    /// Tracked distance, m (when valid).
    pub track_distance_m: Option<f64>,
    /// Tracked yaw, degrees (when valid).
    pub track_yaw_deg: Option<f64>,
}

/// The report of one recording.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlightReport {
    /// The recording.
    pub path: PathBuf,
    /// The bands of [`BANDS_M`] that had frames, then `"all"`.
    pub bands: Vec<Band>,
    /// Frames per controller task (from `/setpoints`), by task name.
    pub task_frames: BTreeMap<String, u64>,
    /// The last frame with truth.
    pub last: Option<LastFrame>,
    /// Why reading stopped early, if the file is cut or damaged.
    pub read_error: Option<String>,
}

/// Why no report could be made.
#[derive(Debug, thiserror::Error)]
pub enum FlightError {
    /// The recording could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// No frame header carries truth.
    #[error(
        "{path} has no frames with truth: record a simulated flight (`hubtrack fly --record FILE`)"
    )]
    NoTruth {
        /// The file.
        path: PathBuf,
    },
}

fn pct(n: usize, of: usize) -> f64 {
    if of == 0 {
        0.0
    } else {
        100.0 * n as f64 / of as f64
    }
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

fn spread(mut v: Vec<f64>) -> Option<Spread> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(Spread {
        p50: quantile(&v, 0.5),
        p90: quantile(&v, 0.9),
    })
}

/// One frame's truth with what the pipeline made of it.
struct Sample<'a> {
    header: &'a FrameHeader,
    detection: Option<&'a Detection>,
    track: Option<&'a TrackState>,
    /// The distance from the spinner's looming, m.
    looming_m: Option<f64>,
}

fn band(name: String, samples: &[&Sample<'_>]) -> Band {
    let n = samples.len();
    let dets: Vec<&Detection> = samples
        .iter()
        .filter_map(|s| s.detection)
        .filter(|d| d.detected)
        .collect();
    let hub_error = samples
        .iter()
        .filter_map(|s| {
            let d = s.detection.filter(|d| d.detected)?;
            let (t, h) = (&s.header.truth, f64::from(s.header.height.max(1)));
            Some(100.0 * (d.hub_px[0] - t.hub_px[0]).hypot(d.hub_px[1] - t.hub_px[1]) / h)
        })
        .collect();
    let nacelle_sides: Vec<bool> = samples
        .iter()
        .filter_map(|s| {
            let d = s.detection.filter(|d| d.detected && d.nacelle_found)?;
            let y = s.header.truth.relative_yaw_deg;
            // A camera on the turbine's left (yaw > 0) sees the nacelle to the right of the hub.
            (y.abs() >= SIGN_MIN_DEG).then_some((d.nacelle_end_dx_px > 0.0) == (y > 0.0))
        })
        .collect();
    let tracks: Vec<(&FrameHeader, &TrackState)> = samples
        .iter()
        .filter_map(|s| Some((s.header, s.track?)))
        .collect();
    let mut ratios: Vec<f64> = tracks
        .iter()
        .filter(|(h, t)| t.distance_valid && h.truth.distance_m > 0.0)
        .map(|(h, t)| t.distance_m / h.truth.distance_m)
        .collect();
    ratios.sort_by(f64::total_cmp);
    let yaws: Vec<(f64, f64)> = tracks
        .iter()
        .filter(|(_, t)| t.yaw_valid)
        .map(|(h, t)| (h.truth.relative_yaw_deg, t.yaw_deg))
        .collect();
    let signed: Vec<&(f64, f64)> = yaws
        .iter()
        .filter(|(truth, _)| truth.abs() >= SIGN_MIN_DEG)
        .collect();
    let nets: Vec<(f64, f64)> = samples
        .iter()
        .filter_map(|s| {
            s.detection
                .filter(|d| d.detected && d.yaw_net_valid)
                .map(|d| (s.header.truth.relative_yaw_deg, d.yaw_net_deg))
        })
        .collect();
    let nets_signed: Vec<&(f64, f64)> = nets
        .iter()
        .filter(|(truth, _)| truth.abs() >= SIGN_MIN_DEG)
        .collect();
    let loomings: Vec<(f64, Option<f64>)> = samples
        .iter()
        .filter_map(|s| {
            let tracked = s.track.filter(|t| t.distance_valid).map(|t| t.distance_m);
            Some((s.looming_m?, tracked))
        })
        .collect();
    let both: Vec<(f64, f64)> = loomings
        .iter()
        .filter_map(|(l, t)| Some((*l, (*t)?)))
        .collect();
    Band {
        name,
        frames: n as u64,
        detected_pct: pct(dets.len(), n),
        hub_error_pct: spread(hub_error),
        tower_pct: pct(dets.iter().filter(|d| d.tower_found).count(), n),
        circle_pct: pct(dets.iter().filter(|d| d.circle_found).count(), n),
        nacelle_pct: pct(nacelle_sides.len(), n),
        nacelle_side_ok_pct: (!nacelle_sides.is_empty()).then(|| {
            pct(
                nacelle_sides.iter().filter(|ok| **ok).count(),
                nacelle_sides.len(),
            )
        }),
        distance_valid_pct: pct(ratios.len(), n),
        distance_ratio: (!ratios.is_empty()).then(|| {
            [
                quantile(&ratios, 0.1),
                quantile(&ratios, 0.5),
                quantile(&ratios, 0.9),
            ]
        }),
        yaw_valid_pct: pct(yaws.len(), n),
        yaw_error_deg: spread(
            yaws.iter()
                .map(|(truth, est)| (est - truth).abs())
                .collect(),
        ),
        yaw_wrong_sign_pct: (!signed.is_empty()).then(|| {
            pct(
                signed
                    .iter()
                    .filter(|(truth, est)| truth * est < 0.0)
                    .count(),
                signed.len(),
            )
        }),
        net_valid_pct: pct(nets.len(), n),
        net_error_deg: spread(
            nets.iter()
                .map(|(truth, est)| (est - truth).abs())
                .collect(),
        ),
        net_wrong_sign_pct: (!nets_signed.is_empty()).then(|| {
            pct(
                nets_signed
                    .iter()
                    .filter(|(truth, est)| truth * est < 0.0)
                    .count(),
                nets_signed.len(),
            )
        }),
        looming_pct: pct(loomings.len(), n),
        looming_error_pct: spread(
            samples
                .iter()
                .filter_map(|s| {
                    let truth = s.header.truth.distance_m;
                    Some(100.0 * (s.looming_m? / truth - 1.0).abs()).filter(|_| truth > 0.0)
                })
                .collect(),
        ),
        looming_disagrees_pct: (!both.is_empty()).then(|| {
            pct(
                both.iter()
                    .filter(|(l, t)| looming::disagree(*l, *t))
                    .count(),
                both.len(),
            )
        }),
    }
}

fn task_name(t: ApproachTask) -> &'static str {
    match t {
        ApproachTask::Hold => "hold",
        ApproachTask::CentreHub => "centre_hub",
        ApproachTask::ReduceYaw => "reduce_yaw",
        ApproachTask::Approach => "approach",
        ApproachTask::Search => "search",
        ApproachTask::Done => "done",
        ApproachTask::Abort => "abort",
    }
}

/// The looming distance of every frame (see [`crate::looming`]), by `seq`: each frame's circle,
/// tracked distance and line of sight, with the newest vehicle state received by its capture.
fn looming_by_seq(c: &channels::Channels) -> BTreeMap<u64, Option<f64>> {
    let vehicles = &c.vehicles;
    let mut next = 0;
    let (seqs, sights): (Vec<u64>, Vec<looming::Sight>) = c
        .frames
        .iter()
        .map(|(seq, h)| {
            while next < vehicles.len() && vehicles[next].recv_ns <= h.capture_ns {
                next += 1;
            }
            let vehicle = next
                .checked_sub(1)
                .map(|i| &vehicles[i])
                .filter(|v| v.position_valid && v.attitude_valid);
            let track = c.tracks.get(seq);
            let sight = looming::Sight {
                position_ne_m: vehicle.map(|v| [v.position_ned_m[0], v.position_ned_m[1]]),
                line_of_sight_rad: vehicle.map_or(0.0, |v| v.yaw_rad)
                    + track.map_or(0.0, |t| t.hub_bearing_deg[0].to_radians()),
                radius_px: c
                    .detections
                    .get(seq)
                    .filter(|d| d.detected && d.circle_found)
                    .map(|d| d.circle[2]),
                tracked_m: track
                    .filter(|t| t.distance_valid && t.mode == TrackMode::Tracking)
                    .map(|t| t.distance_m),
            };
            (*seq, sight)
        })
        .unzip();
    seqs.into_iter().zip(looming::distances(&sights)).collect()
}

/// Reads `path` (a cut file as far as it goes) and compares the estimates with the truth.
pub fn analyze(path: &Path) -> Result<FlightReport, FlightError> {
    let c = channels::read(path)?;
    let looming = looming_by_seq(&c);
    let samples: Vec<Sample<'_>> = c
        .frames
        .iter()
        .filter(|(_, h)| h.truth.valid && h.truth.turbine_in_view)
        .map(|(seq, header)| Sample {
            header,
            detection: c.detections.get(seq),
            track: c.tracks.get(seq),
            looming_m: looming.get(seq).copied().flatten(),
        })
        .collect();
    if samples.is_empty() {
        return Err(FlightError::NoTruth { path: path.into() });
    }
    let mut bands = Vec::new();
    for (lo, hi) in BANDS_M {
        let inside: Vec<&Sample<'_>> = samples
            .iter()
            .filter(|s| (lo..hi).contains(&s.header.truth.distance_m))
            .collect();
        if !inside.is_empty() {
            let name = if hi.is_finite() {
                format!("{lo:.0}-{hi:.0} m")
            } else {
                format!("{lo:.0}+ m")
            };
            bands.push(band(name, &inside));
        }
    }
    bands.push(band("all".into(), &samples.iter().collect::<Vec<_>>()));
    let mut task_frames = BTreeMap::new();
    for s in c.setpoints.values() {
        *task_frames
            .entry(task_name(s.task).to_string())
            .or_insert(0) += 1;
    }
    let last = samples.last().map(|s| LastFrame {
        seq: s.header.seq,
        distance_m: s.header.truth.distance_m,
        yaw_deg: s.header.truth.relative_yaw_deg,
        track_distance_m: s.track.filter(|t| t.distance_valid).map(|t| t.distance_m),
        track_yaw_deg: s.track.filter(|t| t.yaw_valid).map(|t| t.yaw_deg),
    });
    Ok(FlightReport {
        path: path.into(),
        bands,
        task_frames,
        last,
        read_error: c.read_error,
    })
}

/// Prints the report as a table.
pub fn print(r: &FlightReport) {
    let opt = |v: Option<f64>, w: usize| v.map_or(format!("{:>w$}", "-"), |v| format!("{v:>w$.1}"));
    let sp = |v: Option<Spread>| {
        v.map_or(format!("{:>11}", "-"), |s| {
            format!("{:>5.1} {:>5.1}", s.p50, s.p90)
        })
    };
    println!(
        "{:<9}{:>7}{:>6} {:>11}{:>6}{:>6}{:>6}{:>6} | {:>6} {:>17} | {:>6} {:>11} {:>6} | {:>6} {:>11} {:>6} | {:>6} {:>11} {:>6}",
        "truth", "frames", "det%", "hub err %h", "tow%", "circ%", "nac%", "side%", "dist%", "dist/truth", "yaw%", "|yaw err|°", "wrong%", "net%", "|net err|°", "wrong%", "loom%", "loom err %", "≠trk%"
    );
    println!(
        "{:<9}{:>7}{:>6} {:>11}{:>6}{:>6}{:>6}{:>6} | {:>6} {:>17} | {:>6} {:>11} {:>6} | {:>6} {:>11} {:>6} | {:>6} {:>11} {:>6}",
        "", "", "", "p50   p90", "", "", "", "", "", "p10   p50   p90", "", "p50   p90", "", "", "p50   p90", "", "", "p50   p90", ""
    );
    for b in &r.bands {
        let ratio = b.distance_ratio.map_or(format!("{:>17}", "-"), |q| {
            format!("{:>5.2} {:>5.2} {:>5.2}", q[0], q[1], q[2])
        });
        println!(
            "{:<9}{:>7}{:>6.1} {}{:>6.1}{:>6.1}{:>6.1}{} | {:>6.1} {} | {:>6.1} {} {} | {:>6.1} {} {} | {:>6.1} {} {}",
            b.name,
            b.frames,
            b.detected_pct,
            sp(b.hub_error_pct),
            b.tower_pct,
            b.circle_pct,
            b.nacelle_pct,
            opt(b.nacelle_side_ok_pct, 6),
            b.distance_valid_pct,
            ratio,
            b.yaw_valid_pct,
            sp(b.yaw_error_deg),
            opt(b.yaw_wrong_sign_pct, 6),
            b.net_valid_pct,
            sp(b.net_error_deg),
            opt(b.net_wrong_sign_pct, 6),
            b.looming_pct,
            sp(b.looming_error_pct),
            opt(b.looming_disagrees_pct, 6)
        );
    }
    println!(
        "side% = nacelle ends on the side the true yaw puts the nacelle; wrong% = valid yaws (the track's, the yaw network's) of the wrong sign; both where the true |yaw| >= {SIGN_MIN_DEG:.0}°"
    );
    println!(
        "loom% = frames with a distance from the spinner circle's growth over the last {:.0} m (or {:.0} %) flown toward the hub; ≠trk% = of those with a valid tracked distance, the share more than {:.1}x apart (no truth needed)",
        looming::MIN_FLOWN_M,
        100.0 * looming::MIN_FLOWN_FRAC,
        looming::DISAGREE_FACTOR
    );
    if !r.task_frames.is_empty() {
        let tasks: Vec<String> = r
            .task_frames
            .iter()
            .map(|(t, n)| format!("{t} {n}"))
            .collect();
        println!("frames per task: {}", tasks.join(", "));
    }
    if let Some(l) = r.last {
        let est = |v: Option<f64>, unit: &str| {
            v.map_or("invalid".to_string(), |v| format!("{v:+.1}{unit}"))
        };
        println!(
            "last frame {}: truth {:.2} m, yaw {:+.1}°; track {}, yaw {}",
            l.seq,
            l.distance_m,
            l.yaw_deg,
            est(l.track_distance_m, " m").trim_start_matches('+'),
            est(l.track_yaw_deg, "°")
        );
    }
    if let Some(e) = &r.read_error {
        println!("note: the file is cut or damaged; read up to: {e}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::writer::{ChannelKind, Recording, RecordingOptions};
    use hubtrack_types::{Stamps, TrackMode};

    /// Frame `seq`'s header with the hub in view at `distance_m`.
    fn header_with_truth(seq: u64, distance_m: f64) -> FrameHeader {
        let mut h = FrameHeader {
            seq,
            capture_ns: stamps(seq).capture_ns,
            publish_ns: stamps(seq).publish_ns,
            height: 1000,
            ..Default::default()
        };
        h.truth.valid = true;
        h.truth.turbine_in_view = true;
        h.truth.distance_m = distance_m;
        h
    }

    fn stamps(seq: u64) -> Stamps {
        let base = 1_000_000_000 + seq * 50_000_000;
        Stamps {
            seq,
            capture_ns: base,
            recv_ns: base + 1_000_000,
            publish_ns: base + 2_000_000,
        }
    }

    /// A straight approach from 20 m to 6 m, 0.1 m a frame, the spinner circle 200 px / d: the
    /// tracked distance right for the first half, then twice the truth. The looming distance
    /// (from the circles and `/vehicle`) follows the truth, and disagrees with the track exactly
    /// where the track is wrong.
    #[test]
    fn the_spinner_looming_checks_the_tracked_distance_without_the_truth() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.mcap");
        let mut rec = Recording::create(&path, &RecordingOptions::default()).unwrap();
        let frames = 141u64;
        for seq in 0..frames {
            let north = 0.1 * seq as f64;
            let d = 20.0 - north;
            let wrong = seq >= frames / 2;
            rec.write_frame(&header_with_truth(seq, d), None, 1)
                .unwrap();
            let v = hubtrack_types::VehicleState {
                recv_ns: stamps(seq).capture_ns,
                attitude_valid: true,
                position_valid: true,
                position_ned_m: [north, 0.0, -80.0],
                ..Default::default()
            };
            rec.write_json(ChannelKind::Vehicle, seq, 1, 1, &v).unwrap();
            let mut det = Detection {
                stamps: stamps(seq),
                detected: true,
                ..Default::default()
            };
            det.circle_found = true;
            det.circle = [500.0, 500.0, 200.0 / d];
            rec.write_json(ChannelKind::Detection, seq, 1, 1, &det)
                .unwrap();
            let t = TrackState {
                stamps: stamps(seq),
                mode: TrackMode::Tracking,
                distance_valid: true,
                distance_m: if wrong { 2.0 * d } else { d },
                ..Default::default()
            };
            rec.write_json(ChannelKind::Track, seq, 1, 1, &t).unwrap();
        }
        rec.finish().unwrap();
        let r = analyze(&path).unwrap();
        let band = |name: &str| r.bands.iter().find(|b| b.name == name).unwrap();
        // 20–10 m: the track right (20–13 m) and wrong (13–10 m); the looming starts once 4 m
        // (20 % of 20 m) have been flown.
        let mid = band("10-20 m");
        assert!(mid.looming_pct > 30.0, "{mid:?}");
        assert!(mid.looming_error_pct.unwrap().p90 < 3.0, "{mid:?}");
        let near = band("5-10 m");
        assert_eq!(near.looming_pct, 100.0, "{near:?}");
        assert_eq!(near.looming_disagrees_pct, Some(100.0), "{near:?}");
        let all = band("all");
        let disagreeing = all.looming_disagrees_pct.unwrap();
        assert!((20.0..100.0).contains(&disagreeing), "{all:?}");
    }

    #[test]
    fn bands_compare_the_estimates_with_the_truth() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.mcap");
        let mut rec = Recording::create(&path, &RecordingOptions::default()).unwrap();
        // 20 frames at 35 m, yaw +10°: the tracker reads 70 m and −8° in the first ten (the
        // wrong sign), 35 m and +9° after; the detector's hub is 10 px off in a 1000 px image,
        // its nacelle end on the left (the wrong side) in every frame.
        for seq in 0..20u64 {
            let mut h = header_with_truth(seq, 35.0);
            h.truth.hub_px = [500.0, 500.0];
            h.truth.relative_yaw_deg = 10.0;
            rec.write_frame(&h, None, 1).unwrap();
            let mut d = Detection {
                stamps: stamps(seq),
                detected: true,
                hub_px: [510.0, 500.0],
                ..Default::default()
            };
            d.nacelle_found = true;
            d.nacelle_end_dx_px = -30.0;
            rec.write_json(ChannelKind::Detection, seq, 1, 1, &d)
                .unwrap();
            let early = seq < 10;
            let t = TrackState {
                stamps: stamps(seq),
                mode: TrackMode::Tracking,
                distance_valid: true,
                distance_m: if early { 70.0 } else { 35.0 },
                yaw_valid: true,
                yaw_deg: if early { -8.0 } else { 9.0 },
                ..Default::default()
            };
            rec.write_json(ChannelKind::Track, seq, 1, 1, &t).unwrap();
        }
        rec.finish().unwrap();
        let r = analyze(&path).unwrap();
        assert_eq!(
            r.bands.len(),
            2,
            "{:?}",
            r.bands.iter().map(|b| &b.name).collect::<Vec<_>>()
        );
        let b = &r.bands[0];
        assert_eq!((b.name.as_str(), b.frames), ("30+ m", 20));
        assert_eq!(b.detected_pct, 100.0);
        assert_eq!(b.hub_error_pct.unwrap().p50, 1.0);
        assert_eq!(b.nacelle_side_ok_pct, Some(0.0));
        let q = b.distance_ratio.unwrap();
        assert_eq!((q[0], q[2]), (1.0, 2.0));
        assert_eq!(b.yaw_wrong_sign_pct, Some(50.0));
        assert_eq!(b.yaw_error_deg.unwrap().p90, 18.0);
        assert_eq!(
            r.bands[1],
            Band {
                name: "all".into(),
                ..b.clone()
            }
        );
        let last = r.last.unwrap();
        assert_eq!(
            (last.seq, last.track_distance_m, last.track_yaw_deg),
            (19, Some(35.0), Some(9.0))
        );
    }

    #[test]
    fn a_recording_without_truth_names_the_cause() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("camera.mcap");
        let mut rec = Recording::create(&path, &RecordingOptions::default()).unwrap();
        let h = FrameHeader {
            seq: 0,
            capture_ns: 5,
            publish_ns: 6,
            ..Default::default()
        };
        rec.write_frame(&h, None, 1).unwrap();
        rec.finish().unwrap();
        let e = analyze(&path).unwrap_err();
        assert!(matches!(e, FlightError::NoTruth { .. }), "{e}");
        assert!(e.to_string().contains("hubtrack fly --record"), "{e}");
    }
}
