//! `hubtrack track`: detect → track over an image sequence offline, with the same library code the
//! stages run; one JSON object per frame on stdout (a contract: keep the keys).

use crate::detect_cmd::{detector, expand, read_input, view_of, ModeArg};
use hubtrack_detect::Hints;
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_track::Tracker;
use hubtrack_types::{Detection, TrackMode};
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `hubtrack track`.
#[derive(clap::Args)]
pub struct TrackArgs {
    #[command(flatten)]
    pub config: ConfigArgs,
    /// Frame rate of the sequence: frame i is at time i / F seconds.
    #[arg(long)]
    pub fps: f64,
    /// Detection mode (default: `[detect].mode` of the config).
    #[arg(long, value_enum)]
    pub mode: Option<ModeArg>,
    /// Images in order, or folders (read in file-name order).
    #[arg(required = true, value_name = "PATH")]
    pub paths: Vec<PathBuf>,
}

/// Track mode as printed.
pub fn mode_name(m: TrackMode) -> &'static str {
    match m {
        TrackMode::Acquiring => "acquiring",
        TrackMode::Tracking => "tracking",
        TrackMode::Coasting => "coasting",
        TrackMode::Lost => "lost",
    }
}

/// Runs the command.
pub fn run(args: TrackArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.fps > 0.0 && args.fps.is_finite(),
        "--fps must be a positive number, got {}",
        args.fps
    );
    let config = crate::config::load(&args.config)?;
    let mut det = detector(&config.detect, args.mode.map(Into::into))?;
    let mut tracker = Tracker::new(config.track.clone()).map_err(|e| anyhow::anyhow!("{e}"))?;
    // As in the live pipeline, the tracker's newest state focuses the detector on the next frame.
    let mut last: Option<hubtrack_types::TrackState> = None;
    let mut unreadable = 0usize;
    let paths = expand(&args.paths)?;
    for (i, path) in paths.iter().enumerate() {
        let capture_ns = (i as f64 / args.fps * 1e9).round() as u64;
        // An unreadable frame is a frame without detection: the track predicts through it.
        let (detection, error) = match read_input(path) {
            Ok(mat) => {
                let view = view_of(&mat)?;
                // No IMU with a folder of images: no roll.
                let hints =
                    Hints::for_frame(last.as_ref(), view.width, view.height, capture_ns, None);
                let mut d = det.detect(&view, &hints)?.detection;
                d.stamps.seq = i as u64;
                d.stamps.capture_ns = capture_ns;
                (d, None)
            }
            Err(e) => {
                unreadable += 1;
                let mut d = Detection::default();
                d.stamps.seq = i as u64;
                d.stamps.capture_ns = capture_ns;
                (d, Some(format!("{e:#}")))
            }
        };
        let t = tracker.update(&detection, None);
        last = Some(t);
        let has_track =
            !matches!(t.mode, TrackMode::Acquiring | TrackMode::Lost) || detection.detected;
        let mut line = json!({
            "path": path, "detected": detection.detected,
            "hub": has_track.then_some(t.hub_px),
            "mode": mode_name(t.mode),
            "distance_m": t.distance_valid.then_some(t.distance_m),
            "yaw_deg": t.yaw_valid.then_some(t.yaw_deg),
            "raw_hub": detection.detected.then_some(detection.hub_px),
            "distance_std_m": t.distance_valid.then_some(t.distance_std_m),
            "yaw_std_deg": t.yaw_valid.then_some(t.yaw_std_deg),
            "search": t.search_requested,
        });
        if let Some(e) = error {
            line["error"] = json!(e);
        }
        println!("{line}");
    }
    // Each unreadable frame is on its own line above; a sequence of none is no track.
    anyhow::ensure!(
        unreadable < paths.len(),
        "none of the {unreadable} input(s) could be read (each error is above)"
    );
    Ok(())
}
