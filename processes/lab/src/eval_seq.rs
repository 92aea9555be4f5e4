//! `hubtrack eval --sequence`: rendered flights with per-frame truth through detect → track
//! offline (the stages' library code, no processes), the project's tracker and the thesis's
//! filter side by side.

use crate::config::LabConfig;
use crate::score::point_segment_distance;
use anyhow::Context;
use hubtrack_detect::{Detector, Hints, ImageView};
use hubtrack_render::dataset::{flight, held_out_scene, FLIGHT_FPS};
use hubtrack_render::{Camera, Distractor, Renderer};
use hubtrack_track::{BaselineTracker, Tracker};
use hubtrack_types::{Detection, PixelFormat, TrackMode, TrackState, VehicleState};

/// Distance range over which distance errors are scored, metres.
const DISTANCE_SCORED_M: (f64, f64) = (8.0, 30.0);
/// Distance bands of the approach whose errors are reported separately, metres (far to close):
/// a tower 20–40 px wide far out, the spinner's size and the parallax close in.
const DISTANCE_BANDS_M: [(f64, f64); 3] = [(20.0, 30.0), (12.0, 20.0), (5.0, 12.0)];
/// Largest |relative yaw| over which yaw errors are scored, degrees.
const YAW_SCORED_DEG: f64 = 35.0;
/// Standard deviation of the white noise on the vehicle position given to the tracker, metres
/// (an autopilot EKF's short-term relative accuracy with GPS: the parallax cue uses position
/// changes over a few seconds).
const POSITION_NOISE_M: f64 = 0.05;
/// A track (re)acquired farther than this from the truth is a false lock, fraction of height.
const FALSE_LOCK_FRAC: f64 = 0.05;
/// A valid track farther than this from the truth is off the hub, fraction of height (the
/// perception targets: off the hub in at most 2 % of the frames after first lock, never for
/// more than 1 s at a time).
const OFF_HUB_FRAC: f64 = 0.08;

/// Accumulated results of one tracker over one or more flights.
#[derive(Default, Clone)]
struct Metrics {
    frames: u64,
    raw_sq: Vec<f64>,
    filt_sq: Vec<f64>,
    after_lock: u64,
    valid_after_lock: u64,
    longest_gap: u64,
    dist_err_pct: Vec<f64>,
    /// Signed distance error, % of the truth, per [`DISTANCE_BANDS_M`] band.
    band_err_pct: [Vec<f64>; 3],
    /// Per band, the sums of the distance cues' shares (tower, spinner, parallax) over the
    /// frames that gave a distance measurement, and their count.
    band_shares: [([f64; 3], u64); 3],
    yaw_err_deg: Vec<f64>,
    false_locks: u64,
    /// Frames after first lock with a valid track more than [`OFF_HUB_FRAC`] off the hub.
    off_hub: u64,
    /// Longest run of such frames.
    longest_off_hub: u64,
    /// Where it begins: flight and frame.
    longest_off_hub_at: Option<(u64, u64)>,
}

impl Metrics {
    fn merge(&mut self, o: &Metrics) {
        self.frames += o.frames;
        self.raw_sq.extend(&o.raw_sq);
        self.filt_sq.extend(&o.filt_sq);
        self.after_lock += o.after_lock;
        self.valid_after_lock += o.valid_after_lock;
        self.longest_gap = self.longest_gap.max(o.longest_gap);
        self.dist_err_pct.extend(&o.dist_err_pct);
        for (a, b) in self.band_err_pct.iter_mut().zip(&o.band_err_pct) {
            a.extend(b);
        }
        for (a, b) in self.band_shares.iter_mut().zip(&o.band_shares) {
            for (x, y) in a.0.iter_mut().zip(b.0) {
                *x += y;
            }
            a.1 += b.1;
        }
        self.yaw_err_deg.extend(&o.yaw_err_deg);
        self.false_locks += o.false_locks;
        self.off_hub += o.off_hub;
        self.keep_longest_off_hub(o.longest_off_hub, o.longest_off_hub_at);
    }

    /// Takes a stretch of `frames` off the hub beginning `at` when it is longer than the
    /// longest so far (an equal one later does not move it).
    fn keep_longest_off_hub(&mut self, frames: u64, at: Option<(u64, u64)>) {
        if frames > self.longest_off_hub {
            self.longest_off_hub = frames;
            self.longest_off_hub_at = at;
        }
    }
}

fn rms(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        (v.iter().sum::<f64>() / v.len() as f64).sqrt()
    }
}

fn pct(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(|a, b| a.total_cmp(b));
    s[((s.len() - 1) as f64 * q).round() as usize]
}

fn valid(s: &TrackState) -> bool {
    matches!(s.mode, TrackMode::Tracking | TrackMode::Coasting)
}

/// Scores one tracker output over one flight against the frame truth.
struct Scorer {
    m: Metrics,
    flight: u64,
    locked: bool,
    gap: u64,
    off_run: u64,
    was_valid: bool,
}

impl Scorer {
    fn new(flight: u64) -> Scorer {
        Scorer {
            m: Metrics::default(),
            flight,
            locked: false,
            gap: 0,
            off_run: 0,
            was_valid: false,
        }
    }

    fn add(&mut self, s: &TrackState, truth: &hubtrack_render::Truth, height: f64) {
        self.m.frames += 1;
        let (Some(hub), Some(nose)) = (truth.hub_px, truth.nose_px) else {
            return;
        };
        let err = point_segment_distance(s.hub_px, hub, nose) / height;
        let v = valid(s);
        if v && !self.was_valid && err > FALSE_LOCK_FRAC {
            self.m.false_locks += 1;
        }
        self.was_valid = v;
        if s.mode == TrackMode::Tracking {
            self.locked = true;
        }
        if !self.locked {
            return;
        }
        self.m.after_lock += 1;
        if v {
            self.m.valid_after_lock += 1;
            self.m.filt_sq.push((100.0 * err).powi(2));
            self.gap = 0;
            if err > OFF_HUB_FRAC {
                self.m.off_hub += 1;
                self.off_run += 1;
                // `frames` counts this frame: the run began `off_run − 1` frames earlier.
                let start = self.m.frames - self.off_run;
                self.m
                    .keep_longest_off_hub(self.off_run, Some((self.flight, start)));
            } else {
                self.off_run = 0;
            }
        } else {
            self.off_run = 0;
            self.gap += 1;
            self.m.longest_gap = self.m.longest_gap.max(self.gap);
        }
        let shares = [
            s.distance_share_tower,
            s.distance_share_spinner,
            s.distance_share_parallax,
        ];
        if shares.iter().sum::<f64>() > 0.0 {
            for (band, acc) in DISTANCE_BANDS_M.iter().zip(self.m.band_shares.iter_mut()) {
                if truth.distance_m > band.0 && truth.distance_m <= band.1 {
                    for (a, x) in acc.0.iter_mut().zip(shares) {
                        *a += x;
                    }
                    acc.1 += 1;
                }
            }
        }
        if s.distance_valid {
            let signed = 100.0 * (s.distance_m - truth.distance_m) / truth.distance_m;
            for (band, errs) in DISTANCE_BANDS_M.iter().zip(self.m.band_err_pct.iter_mut()) {
                if truth.distance_m > band.0 && truth.distance_m <= band.1 {
                    errs.push(signed);
                }
            }
        }
        if s.distance_valid
            && (DISTANCE_SCORED_M.0..=DISTANCE_SCORED_M.1).contains(&truth.distance_m)
        {
            self.m
                .dist_err_pct
                .push(100.0 * (s.distance_m - truth.distance_m).abs() / truth.distance_m);
        }
        if s.yaw_valid && truth.relative_yaw_deg.abs() <= YAW_SCORED_DEG {
            self.m
                .yaw_err_deg
                .push((s.yaw_deg - truth.relative_yaw_deg).abs());
        }
    }
}

/// One frame of `--trace` output.
fn trace_line(
    flight: u64,
    frame: usize,
    truth: &hubtrack_render::Truth,
    det: &Detection,
    ours: &TrackState,
    thesis: &TrackState,
) -> serde_json::Value {
    let track = |s: &TrackState| {
        serde_json::json!({
            "mode": format!("{:?}", s.mode).to_lowercase(),
            "hub": s.hub_px,
            "distance_m": s.distance_valid.then_some(s.distance_m),
            "yaw_deg": s.yaw_valid.then_some(s.yaw_deg),
            "distance_shares": [s.distance_share_tower, s.distance_share_spinner, s.distance_share_parallax],
        })
    };
    serde_json::json!({
        "flight": flight,
        "frame": frame,
        "truth": {"hub": truth.hub_px, "nose": truth.nose_px, "distance_m": truth.distance_m, "yaw_deg": truth.relative_yaw_deg, "tower_width": truth.tower_width_px, "tower_width_row": truth.tower_width_row, "tower_top": truth.tower_top_px},
        "detection": {
            "detected": det.detected,
            "hub": det.detected.then_some(det.hub_px),
            "confidence": det.confidence,
            "spinner_radius": det.circle_found.then_some(det.circle[2]),
            "tower_width": det.tower_found.then_some(det.tower_width_px),
            "tower_width_row": det.tower_found.then_some(det.tower_width_row),
            "tower_top": det.tower_found.then_some(det.tower_top_px),
        },
        "ours": track(ours),
        "thesis": track(thesis),
    })
}

/// Optional per-frame outputs of a sequence evaluation.
pub struct Outputs<'a> {
    /// One JSON line per frame (truth, detection, both trackers) to this file.
    pub trace: Option<&'a std::path::Path>,
    /// An overlay PNG of every frame whose detection misses the truth, in this folder.
    pub misses: Option<&'a std::path::Path>,
    /// Every hub candidate of every frame (see `hubtrack eval --candidates`) to this file.
    pub candidates: Option<&'a std::path::Path>,
}

/// Which rendered flights to score.
pub struct Flights {
    /// How many.
    pub count: u64,
    /// Frames per flight.
    pub frames: u64,
    /// Flight `f` is `dataset::flight(seed + f)`.
    pub seed: u64,
    /// Filmed in the held-out scenes of `eval --cross-domain` (`dataset::held_out_scene`).
    pub held_out_scenes: bool,
}

/// Runs the flights and prints the tables, writing the optional per-frame outputs on the way.
pub fn run(config: &LabConfig, flights: &Flights, outputs: Outputs<'_>) -> anyhow::Result<()> {
    let (frames, seed) = (flights.frames, flights.seed);
    use std::io::Write as _;
    let mut trace = match outputs.trace {
        Some(p) => Some(std::io::BufWriter::new(
            std::fs::File::create(p)
                .map_err(|e| anyhow::anyhow!("creating {}: {e}", p.display()))?,
        )),
        None => None,
    };
    let mut cand_out = match outputs.candidates {
        Some(p) => Some(std::io::BufWriter::new(
            std::fs::File::create(p)
                .map_err(|e| anyhow::anyhow!("creating {}: {e}", p.display()))?,
        )),
        None => None,
    };
    let mut detector = Detector::new(config.detect.clone())?;
    // The flights are filmed through the configured camera (`--camera`), else the GoPro, and
    // show the configured turbine (`--turbine`), else the renderer's own.
    let camera = config
        .camera
        .calibrated()?
        .unwrap_or_else(Camera::gopro_hero3);
    let turbine = (!config.turbine.profile.is_empty()).then_some(&config.turbine);
    let mut renderer = Renderer::new(camera);
    let cam = *renderer.camera();
    let mut pixels = vec![0u8; cam.frame_bytes()];
    let height = cam.height as f64;
    let (mut total_ours, mut total_thesis) = (Metrics::default(), Metrics::default());
    println!(
        "\nrendered flights: {} x {frames} frames at {FLIGHT_FPS} fps (30 -> 6 m, drift, climb, yaw turn, roll jitter, dropouts){}, seed {seed}",
        flights.count,
        if flights.held_out_scenes {
            ", held-out scenes (chimneys, motion blur)"
        } else {
            ""
        }
    );
    println!(
        "{:<8}{:>9} |{:>9}{:>8}{:>8}{:>10}{:>10}{:>10}{:>7} |{:>9}{:>8}{:>8}{:>10}{:>10}{:>10}{:>7}",
        "flight", "raw RMS", "filt RMS", "valid%", "gap", "dist med", "dist p90", "yaw med", "false",
        "filt RMS", "valid%", "gap", "dist med", "dist p90", "yaw med", "false"
    );
    println!(
        "{:<17} |{:^62} |{:^62}",
        "", "hubtrack tracker", "thesis filter (no gating, no attitude)"
    );
    for f in 0..flights.count {
        let mut path = flight(seed.wrapping_add(f), frames);
        for fr in &mut path {
            if let Some(t) = turbine {
                hubtrack_sim::show_turbine(&mut fr.scene, t);
            }
            if flights.held_out_scenes {
                let scene_seed = fr.scene.seed;
                held_out_scene(&mut fr.scene, scene_seed);
            }
        }
        if let Some(fr) = path.first().filter(|_| flights.held_out_scenes) {
            eprintln!(
                "[eval] flight {f}: {}, motion blur {:.1} px",
                if fr.scene.distractor == Distractor::Chimney {
                    "a chimney"
                } else {
                    "no chimney"
                },
                fr.scene.motion_blur_frac * cam.width as f32
            );
        }
        let mut ours = Tracker::new(config.track.clone()).map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut thesis =
            BaselineTracker::new(config.track.clone()).map_err(|e| anyhow::anyhow!("{e}"))?;
        let (mut so, mut st) = (Scorer::new(f), Scorer::new(f));
        let mut raw_sq = Vec::new();
        let mut prev_heading: Option<(f64, u64)> = None;
        let mut prev_position: Option<([f64; 3], u64)> = None;
        let mut noise = hubtrack_types::mutate::Rng::new(seed.wrapping_add(f) ^ 0x005E_ED0F_9051);
        // As in the live pipeline, the tracker's newest state focuses the detector on the next
        // frame (predicted hub, expected tower and spinner sizes); the thesis filter is fed the
        // same detections, so the two columns differ by the filter alone.
        let mut last: Option<hubtrack_types::TrackState> = None;
        for (i, fr) in path.iter().enumerate() {
            let truth = renderer
                .render(&fr.scene, &fr.pose, &mut pixels)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            let view = ImageView {
                width: cam.width,
                height: cam.height,
                stride: cam.width as usize * 3,
                format: PixelFormat::Bgr8,
                data: &pixels,
            };
            let capture_ns = (i as f64 / FLIGHT_FPS * 1e9).round() as u64;
            let hints = Hints::for_frame(
                last.as_ref(),
                cam.width,
                cam.height,
                capture_ns,
                Some(fr.pose.roll_deg.to_radians()),
            );
            let output = detector.detect(&view, &hints)?;
            if outputs.misses.is_some() && !fr.dropout {
                write_sequence_miss(
                    outputs.misses,
                    &format!("f{f}_{i:03}"),
                    &pixels,
                    &cam,
                    &truth,
                    &output,
                    &hints,
                )?;
            }
            if !fr.dropout {
                let t = crate::score::Truth::of_rendered(&truth);
                crate::eval::write_candidates(
                    cand_out.as_mut(),
                    &format!("f{f}_{i:03}"),
                    &t,
                    &output,
                    cam.height,
                )?;
            }
            let mut det: Detection = output.detection;
            det.stamps.seq = i as u64;
            det.stamps.capture_ns = capture_ns;
            if fr.dropout {
                det.detected = false;
            }
            if det.detected {
                if let (Some(h), Some(n)) = (truth.hub_px, truth.nose_px) {
                    raw_sq
                        .push((100.0 * point_segment_distance(det.hub_px, h, n) / height).powi(2));
                }
            }
            let yaw_rate = prev_heading.map_or(0.0, |(h, t)| {
                (fr.heading_rad - h) / ((capture_ns - t) as f64 / 1e9)
            });
            prev_heading = Some((fr.heading_rad, capture_ns));
            // The vehicle's position in a local NED frame whose north is the approach direction
            // (toward the rotor face) and east the camera's right, origin at the hub: the frame
            // `heading_rad` is measured in.
            let position = [-fr.pose.distance_m, fr.pose.lateral_m, -fr.pose.height_m];
            let velocity = prev_position.map_or([0.0; 3], |(p, t)| {
                let dt = (capture_ns - t) as f64 / 1e9;
                [0, 1, 2].map(|k| (position[k] - p[k]) / dt)
            });
            prev_position = Some((position, capture_ns));
            let mut uniform = || (noise.next_u64() >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            // Uniform noise of the same standard deviation: width √12 σ.
            let noisy = position.map(|x| x + 12f64.sqrt() * POSITION_NOISE_M * uniform());
            let vehicle = VehicleState {
                recv_ns: capture_ns,
                publish_ns: capture_ns,
                link_ok: true,
                attitude_valid: true,
                roll_rad: fr.pose.roll_deg.to_radians(),
                pitch_rad: fr.pose.pitch_deg.to_radians(),
                yaw_rad: fr.heading_rad,
                body_rates_rad_s: [0.0, 0.0, yaw_rate],
                position_valid: true,
                position_ned_m: noisy,
                velocity_ned_m_s: velocity,
                ..Default::default()
            };
            let state = ours.update(&det, Some(&vehicle));
            so.add(&state, &truth, height);
            let thesis_state = thesis.update(&det, None);
            st.add(&thesis_state, &truth, height);
            if let Some(w) = trace.as_mut() {
                writeln!(
                    w,
                    "{}",
                    trace_line(f, i, &truth, &det, &state, &thesis_state)
                )?;
            }
            last = Some(state);
        }
        so.m.raw_sq = raw_sq.clone();
        st.m.raw_sq = raw_sq;
        let row = |m: &Metrics| {
            format!(
                "{:>9.2}{:>8.1}{:>8}{:>10.1}{:>10.1}{:>10.1}{:>7}",
                rms(&m.filt_sq),
                100.0 * m.valid_after_lock as f64 / m.after_lock.max(1) as f64,
                m.longest_gap,
                pct(&m.dist_err_pct, 0.5),
                pct(&m.dist_err_pct, 0.9),
                pct(&m.yaw_err_deg, 0.5),
                m.false_locks
            )
        };
        println!(
            "{:<8}{:>9.2} |{} |{}",
            f,
            rms(&so.m.raw_sq),
            row(&so.m),
            row(&st.m)
        );
        total_ours.merge(&so.m);
        total_thesis.merge(&st.m);
    }
    let (o, t) = (&total_ours, &total_thesis);
    println!(
        "overall: raw RMS {:.2} % of height | hubtrack: filtered RMS {:.2} %, valid {:.1} % after first lock, longest gap {} frames, \
distance error median {:.1} % p90 {:.1} % (8-30 m), yaw error median {:.1} deg p90 {:.1} deg (|yaw| <= 35), false locks {}",
        rms(&o.raw_sq), rms(&o.filt_sq), 100.0 * o.valid_after_lock as f64 / o.after_lock.max(1) as f64, o.longest_gap,
        pct(&o.dist_err_pct, 0.5), pct(&o.dist_err_pct, 0.9), pct(&o.yaw_err_deg, 0.5), pct(&o.yaw_err_deg, 0.9), o.false_locks
    );
    println!(
        "         thesis filter: filtered RMS {:.2} %, valid {:.1} %, longest gap {}, distance median {:.1} % p90 {:.1} %, yaw median {:.1} deg p90 {:.1} deg, false locks {}",
        rms(&t.filt_sq), 100.0 * t.valid_after_lock as f64 / t.after_lock.max(1) as f64, t.longest_gap,
        pct(&t.dist_err_pct, 0.5), pct(&t.dist_err_pct, 0.9), pct(&t.yaw_err_deg, 0.5), pct(&t.yaw_err_deg, 0.9), t.false_locks
    );
    for ((band, (eo, et)), (share_sum, n)) in DISTANCE_BANDS_M
        .iter()
        .zip(o.band_err_pct.iter().zip(&t.band_err_pct))
        .zip(&o.band_shares)
    {
        let abs = |v: &[f64]| v.iter().map(|e| e.abs()).collect::<Vec<f64>>();
        let share = |i: usize| 100.0 * share_sum[i] / (*n).max(1) as f64;
        println!(
            "distance {:>2}-{:>2} m: hubtrack |error| median {:.1} % p90 {:.1} %, signed median {:+.1} % ({} frames; cue shares tower {:.0} % spinner {:.0} % parallax {:.0} %) | thesis filter median {:.1} % p90 {:.1} %",
            band.1, band.0,
            pct(&abs(eo), 0.5), pct(&abs(eo), 0.9), pct(eo, 0.5), eo.len(),
            share(0), share(1), share(2),
            pct(&abs(et), 0.5), pct(&abs(et), 0.9)
        );
    }
    // Where the longest stretch begins, to replay it (`--flights 1 --seed SEED+FLIGHT`).
    let at = |m: &Metrics| {
        m.longest_off_hub_at.map_or(String::new(), |(f, frame)| {
            format!(" (flight {f} from frame {frame})")
        })
    };
    println!(
        "off the hub (> {:.0} % of height): hubtrack {:.1} % of valid frames after first lock, longest {:.1} s{} | thesis filter {:.1} %, longest {:.1} s{}",
        100.0 * OFF_HUB_FRAC,
        100.0 * o.off_hub as f64 / o.valid_after_lock.max(1) as f64,
        o.longest_off_hub as f64 / FLIGHT_FPS,
        at(o),
        100.0 * t.off_hub as f64 / t.valid_after_lock.max(1) as f64,
        t.longest_off_hub as f64 / FLIGHT_FPS,
        at(t)
    );
    println!("RMS in % of image height over frames with a valid estimate after first lock; gap = frames without one.");
    if let Some(w) = cand_out.as_mut() {
        w.flush()
            .map_err(|e| anyhow::anyhow!("writing the candidates file: {e}"))?;
    }
    Ok(())
}

/// Writes the overlay of a frame whose detection misses the truth (scored as `hubtrack eval`
/// scores photos) into `dir`.
fn write_sequence_miss(
    dir: Option<&std::path::Path>,
    name: &str,
    pixels: &[u8],
    cam: &Camera,
    truth: &hubtrack_render::Truth,
    output: &hubtrack_detect::Output,
    hints: &Hints,
) -> anyhow::Result<()> {
    use opencv::core::{Mat, MatTraitConst};
    let t = crate::score::Truth::of_rendered(truth);
    let d = &output.detection;
    let outcome = crate::score::score(&t, d.detected.then_some(d.hub_px), cam.height as f64);
    if outcome.hit || !outcome.detected {
        return Ok(());
    }
    let mat = Mat::from_slice(pixels)?
        .reshape(3, cam.height as i32)?
        .try_clone()?;
    if crate::eval::write_miss(
        dir,
        name,
        &mat,
        &t,
        std::slice::from_ref(output),
        &[outcome],
        None,
    )? {
        // The rendered input too, to re-run `hubtrack detect` on (with RUST_LOG=trace).
        let input = dir
            .unwrap_or(std::path::Path::new("."))
            .join(format!("{name}_input.png"));
        let path = input
            .to_str()
            .ok_or_else(|| anyhow::anyhow!("non-UTF-8 path {}", input.display()))?;
        anyhow::ensure!(
            opencv::imgcodecs::imwrite_def(path, &mat)?,
            "cannot write {path}"
        );
        // ... with the hints the tracker gave the detector, as `hubtrack detect` arguments
        // (detecting as the detect stage does on a video frame).
        let mut args = vec!["--as-frame".to_string()];
        if let Some([x, y]) = hints.predicted_hub_px {
            args.push(format!("--hint-hub={x:.1},{y:.1}"));
        }
        if let Some(d) = hints.hub_distance_m {
            args.push(format!("--hint-distance={d:.2}"));
        }
        if let Some(r) = hints.roll_rad {
            args.push(format!("--hint-roll={:.2}", r.to_degrees()));
        }
        let hints_path = input.with_extension("hints");
        std::fs::write(&hints_path, args.join(" ") + "\n")
            .with_context(|| format!("writing {}", hints_path.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame's truth with the hub (and its nose) at `hub`.
    fn truth(hub: [f64; 2]) -> hubtrack_render::Truth {
        hubtrack_render::Truth {
            turbine_in_view: true,
            hub_px: Some(hub),
            nose_px: Some(hub),
            tower_top_px: None,
            tower_width_px: None,
            tower_width_row: None,
            tower_width_height_m: None,
            distance_m: 20.0,
            relative_yaw_deg: 0.0,
            hub_cam_m: [0.0, 0.0, 20.0],
        }
    }

    /// A tracking state with the hub at `hub`.
    fn tracking(hub: [f64; 2]) -> TrackState {
        TrackState {
            mode: TrackMode::Tracking,
            hub_px: hub,
            ..TrackState::default()
        }
    }

    /// Scores one flight of 100 px high frames whose track is `off[i]` px below the hub.
    fn scored_flight(f: u64, off: &[f64]) -> Metrics {
        let mut s = Scorer::new(f);
        for &dy in off {
            s.add(&tracking([50.0, 50.0 + dy]), &truth([50.0, 50.0]), 100.0);
        }
        s.m
    }

    #[test]
    fn the_longest_stretch_off_the_hub_is_located() {
        // 8 % of the height is the limit: 9 px is off, 7 px on.
        let a = scored_flight(0, &[0.0, 9.0, 9.0, 0.0, 9.0, 0.0]);
        assert_eq!((a.off_hub, a.longest_off_hub), (3, 2));
        assert_eq!(a.longest_off_hub_at, Some((0, 1)));
        let b = scored_flight(1, &[0.0, 0.0, 7.0, 9.0, 9.0, 9.0]);
        assert_eq!(b.longest_off_hub_at, Some((1, 3)));
        // Merged, the longer stretch and its place win; a shorter one later does not move it.
        let mut all = Metrics::default();
        for m in [&a, &b, &scored_flight(2, &[9.0, 9.0])] {
            all.merge(m);
        }
        assert_eq!(
            (all.off_hub, all.longest_off_hub, all.longest_off_hub_at),
            (8, 3, Some((1, 3)))
        );
        // A flight that never leaves the hub names no place.
        assert_eq!(scored_flight(3, &[0.0, 7.0]).longest_off_hub_at, None);
    }
}
