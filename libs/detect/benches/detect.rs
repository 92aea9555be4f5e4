//! Detection speed on rendered 1920x1080 BGR frames (GoPro model), including the downsampling.
//!
//! `cargo bench -p hubtrack-detect --bench detect` (or `cargo run --release --bench detect`).
//! Prints, per mode and OpenCV thread count, median and p99 of the whole `detect` call and the
//! median of each step. `DETECT_BENCH_ROWS=default,thesis` limits the run to those rows. Rows
//! `+d` pass the tracker's distance, `+t` its predicted hub too (the detect stage's steady state).
//! The `pipeline` row runs on the frames `hubtrack bench pipeline`'s camera plays (the first 30
//! of the synthetic path at 30 fps, `capture.synthetic.cache_frames`) with the hints the detect
//! stage has there (the tracker's hub and distance, no roll: no autopilot), with the default
//! detect config. `hubtrack bench pipeline` compares the detect stage with `hubtrack bench
//! detect-alone` instead, which runs these frames with the stage's whole config (lens and
//! turbine included), paced and pinned like the stage, in the same sitting.

use std::time::Instant;

use hubtrack_capture::config::SyntheticConfig;
use hubtrack_capture::synthetic::SyntheticSource;
use hubtrack_detect::params::{DetectConfig, Mode};
use hubtrack_detect::{Detector, Hints, ImageView};
use hubtrack_render::dataset::{synth_case, CLASSES};
use hubtrack_render::{Camera, Renderer};
use hubtrack_types::PixelFormat;

const FRAMES: usize = 100;
const REPEATS: usize = 3;
/// Frames `hubtrack bench pipeline`'s camera loops over, and its rate.
const PIPELINE_FRAMES: u64 = 30;
const PIPELINE_FPS: f64 = 30.0;

/// One frame, its roll hint (radians), distance and hub in view.
type Frame = (Vec<u8>, Option<f64>, f64, Option<[f64; 2]>);

/// What a row tells the detector besides the roll.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Hinted {
    /// Nothing: frames before acquisition.
    No,
    /// The tracker's distance.
    Distance,
    /// The tracker's distance and predicted hub.
    Tracking,
}

fn pct(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let cam = Camera::gopro_hero3();
    let mut r = Renderer::new(cam);
    let mut frames: Vec<Frame> = Vec::new();
    // The project's evaluation set (`hubtrack eval`): every distance class, every 8th a negative.
    for k in 0..FRAMES {
        let case = synth_case(5000, k % CLASSES.len(), k as u64, k % 8 == 7);
        let (scene, pose) = (case.scene, case.pose);
        let mut buf = vec![0u8; cam.frame_bytes()];
        let truth = r.render(&scene, &pose, &mut buf)?;
        let hub = truth.hub_px.filter(|_| truth.turbine_in_view);
        frames.push((buf, Some(pose.roll_deg.to_radians()), pose.distance_m, hub));
    }
    let mut path = SyntheticSource::new(&SyntheticConfig::default(), PIPELINE_FPS)?;
    let mut pipeline_frames: Vec<Frame> = Vec::new();
    for index in 0..PIPELINE_FRAMES {
        let mut buf = vec![0u8; cam.frame_bytes()];
        let truth = path.render_index(index, &mut buf)?;
        let hub = truth.hub_px.filter(|_| truth.turbine_in_view);
        pipeline_frames.push((buf, None, truth.distance_m, hub));
    }
    let default_threads = opencv::core::get_num_threads()?;
    println!("{FRAMES} rendered 1920x1080 BGR frames x {REPEATS} repeats (`pipeline`: the {PIPELINE_FRAMES} frames of `hubtrack bench pipeline`'s camera); times in ms (wall clock of detect(), per-step medians from Detection.timings)");
    println!(
        "{:<9} {:>7} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "mode", "threads", "median", "p99", "pyramid", "edges", "hough", "geometry"
    );
    // The default mode also without the hub crop (`default.hub_crop`), its cost compared in one run.
    let no_crop = {
        let mut c = DetectConfig {
            mode: Mode::Default,
            ..DetectConfig::default()
        };
        c.default.hub_crop = false;
        c
    };
    // ... and without the yaw network (`default.hub_yaw`). Without a tracker's distance it runs
    // only where a spinner circle gives one (3.5–45 m); the `+d` rows pass the true distance as
    // the tracker's hint, as the detect stage does in flight (the network then runs on every
    // detection within 45 m; the hint also narrows the tower's width window).
    let no_yaw = {
        let mut c = DetectConfig {
            mode: Mode::Default,
            ..DetectConfig::default()
        };
        c.default.hub_yaw = false;
        c
    };
    // The `+t` row passes the tracker's prediction too (the true hub, for frames showing one),
    // as the detect stage does between acquisition and a loss: the hub crop then stays off and
    // the close spinner search only runs when nothing else is found.
    let default = DetectConfig {
        mode: Mode::Default,
        ..DetectConfig::default()
    };
    let variants = [
        (
            "thesis",
            DetectConfig {
                mode: Mode::Thesis,
                ..DetectConfig::default()
            },
            Hinted::No,
            &frames,
        ),
        ("default", default.clone(), Hinted::No, &frames),
        ("no-crop", no_crop, Hinted::No, &frames),
        ("no-yaw", no_yaw.clone(), Hinted::No, &frames),
        ("default+d", default.clone(), Hinted::Distance, &frames),
        ("no-yaw+d", no_yaw, Hinted::Distance, &frames),
        ("default+t", default.clone(), Hinted::Tracking, &frames),
        ("pipeline", default, Hinted::Tracking, &pipeline_frames),
    ];
    // `DETECT_BENCH_ROWS=default,no-crop` runs only those rows (e.g. under a profiler).
    let only: Option<Vec<String>> = std::env::var("DETECT_BENCH_ROWS")
        .ok()
        .map(|v| v.split(',').map(|s| s.trim().to_string()).collect());
    for (name, config, hinted, frames) in variants {
        if only.as_ref().is_some_and(|o| !o.iter().any(|r| r == name)) {
            continue;
        }
        for threads in [1, default_threads] {
            opencv::core::set_num_threads(threads)?;
            let mut det = Detector::new(config.clone())?;
            let (mut tot, mut py, mut ed, mut ho, mut ge) =
                (vec![], vec![], vec![], vec![], vec![]);
            // About as many calls per repeat whatever the set's size.
            let passes = (FRAMES / frames.len()).max(1);
            for rep in 0..=REPEATS {
                for (buf, roll, distance, hub) in frames.iter().cycle().take(passes * frames.len())
                {
                    let view = ImageView {
                        width: cam.width,
                        height: cam.height,
                        stride: cam.width as usize * 3,
                        format: PixelFormat::Bgr8,
                        data: buf,
                    };
                    let t = Instant::now();
                    let hints = Hints {
                        roll_rad: *roll,
                        hub_distance_m: (hinted != Hinted::No).then_some(*distance),
                        predicted_hub_px: hub.filter(|_| hinted == Hinted::Tracking),
                    };
                    let out = det.detect(&view, &hints)?;
                    let ms = t.elapsed().as_secs_f64() * 1e3;
                    if rep == 0 {
                        continue; // warm-up pass
                    }
                    let tm = out.detection.timings;
                    tot.push(ms);
                    py.push(tm.pyramid_us / 1e3);
                    ed.push(tm.edges_us / 1e3);
                    ho.push(tm.hough_us / 1e3);
                    ge.push(tm.geometry_us / 1e3);
                }
            }
            println!(
                "{:<9} {:>7} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2}",
                name,
                threads,
                pct(&mut tot, 0.5),
                pct(&mut tot, 0.99),
                pct(&mut py, 0.5),
                pct(&mut ed, 0.5),
                pct(&mut ho, 0.5),
                pct(&mut ge, 0.5)
            );
        }
    }
    opencv::core::set_num_threads(default_threads)?;
    Ok(())
}
