//! Synthetic source: the project's turbine renderer flying a scripted camera path.
//!
//! Simulated time is `frame_index / fps`, not the wall clock, so a seed and a frame index always
//! give the same image (replayable, testable), whatever the pacing.

use crate::config::{SyntheticCamera, SyntheticConfig};
use crate::{CaptureError, FrameInfo, FrameSink, FrameSource, Step};
use hubtrack_render::{Camera, CameraPose, Renderer, Scene, Truth};
use hubtrack_types::setup::{CameraSetup, TurbineSetup};
use hubtrack_types::{FrameSourceKind, FrameTruth, PixelFormat};
use std::f64::consts::TAU;

/// Periods of the path's oscillations relative to `path_duration_s`, chosen incommensurate so
/// sway, yaw and roll do not repeat in lock-step.
const SWAY_PERIOD_FACTOR: f64 = 0.73;
const YAW_PERIOD_FACTOR: f64 = 1.31;
const ROLL_PERIOD_S: f64 = 1.7;
/// Camera pointing error amplitude (the hub wanders in the image as on a real flight), degrees.
const POINTING_JITTER_DEG: f64 = 3.0;
const POINTING_PERIOD_S: f64 = 2.3;

/// The scripted camera pose and rotor angle at simulated time `t` (seconds).
pub fn path_pose(cfg: &SyntheticConfig, t: f64) -> (CameraPose, f64) {
    let dur = cfg.path_duration_s;
    let phase = (t % dur) / dur;
    let distance = cfg.start_distance_m + (cfg.end_distance_m - cfg.start_distance_m) * phase;
    let lateral = cfg.lateral_sway_m * (TAU * t / (dur * SWAY_PERIOD_FACTOR)).sin();
    // Aim at the hub, then add the pointing error of a real flight.
    let mut pose = CameraPose::looking_at_hub(distance, lateral, cfg.height_m);
    pose.yaw_deg += POINTING_JITTER_DEG * (TAU * t / POINTING_PERIOD_S).sin();
    pose.pitch_deg += 0.5 * POINTING_JITTER_DEG * (TAU * t / (POINTING_PERIOD_S * 1.37)).cos();
    pose.roll_deg = cfg.roll_jitter_deg * (TAU * t / ROLL_PERIOD_S).sin();
    let nacelle_yaw = cfg.yaw_swing_deg * (TAU * t / (dur * YAW_PERIOD_FACTOR)).sin();
    (pose, nacelle_yaw)
}

/// Converts renderer truth into the frame header's truth.
pub fn frame_truth(t: &Truth) -> FrameTruth {
    let xy = |p: Option<[f64; 2]>| p.unwrap_or([f64::NAN, f64::NAN]);
    FrameTruth {
        valid: true,
        turbine_in_view: t.turbine_in_view,
        hub_px: xy(t.hub_px),
        nose_px: xy(t.nose_px),
        tower_top_px: xy(t.tower_top_px),
        tower_width_px: t.tower_width_px.unwrap_or(f64::NAN),
        tower_width_row: t.tower_width_row.unwrap_or(f64::NAN),
        distance_m: t.distance_m,
        relative_yaw_deg: t.relative_yaw_deg,
    }
}

/// Renders frame after frame along the scripted path.
pub struct SyntheticSource {
    cfg: SyntheticConfig,
    fps: f64,
    renderer: Renderer,
    scene: Scene,
    base_rotor_deg: f64,
    index: u64,
    /// The first `cache_frames` frames and their truth (see `SyntheticConfig::cache_frames`).
    cache: Vec<(Vec<u8>, FrameTruth)>,
}

/// What the synthetic camera films beyond its own settings: the lens of a calibration file
/// (`--camera`) instead of `capture.synthetic.camera`'s, and the turbine of a profile
/// (`--turbine`) instead of the renderer's own, so that detect and track, given the same files,
/// see what they are told they see.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Filming {
    /// The calibrated lens, when `[camera] calibration` names one.
    pub lens: Option<Camera>,
    /// The turbine, when `[turbine] profile` names one.
    pub turbine: Option<TurbineSetup>,
}

impl Filming {
    /// The calibration and the profile of `[camera]` and `[turbine]`, where files are named.
    pub fn of(camera: &CameraSetup, turbine: &TurbineSetup) -> Result<Filming, CaptureError> {
        Ok(Filming {
            lens: camera
                .calibrated()
                .map_err(|e| CaptureError::Render(format!("camera calibration: {e}")))?,
            turbine: (!turbine.profile.is_empty()).then(|| turbine.clone()),
        })
    }
}

impl SyntheticSource {
    /// The same source filming through `filming`'s lens and turbine, where it names them.
    pub fn filming(mut self, filming: &Filming) -> SyntheticSource {
        if let Some(lens) = filming.lens {
            self.renderer = Renderer::new(lens);
        }
        if let Some(t) = &filming.turbine {
            hubtrack_sim::show_turbine(&mut self.scene, t);
        }
        self
    }

    /// A source for `cfg` at `fps` frames per simulated second.
    pub fn new(cfg: &SyntheticConfig, fps: f64) -> Result<SyntheticSource, CaptureError> {
        let camera = match cfg.camera {
            SyntheticCamera::Gopro => Camera::gopro_hero3(),
            SyntheticCamera::Usb => Camera::usb_narrow(),
        };
        let mut scene = Scene::random(cfg.seed);
        scene.turbine_present = true;
        scene.noise_sigma = cfg.noise_sigma as f32;
        let base_rotor_deg = scene.rotor_angle_deg;
        Ok(SyntheticSource {
            cfg: cfg.clone(),
            fps,
            renderer: Renderer::new(camera),
            scene,
            base_rotor_deg,
            index: 0,
            cache: Vec::new(),
        })
    }

    /// Renders frame `index` of the path into `out` (also used by tests to compare pixels).
    pub fn render_index(&mut self, index: u64, out: &mut [u8]) -> Result<Truth, CaptureError> {
        let t = index as f64 / self.fps;
        let (pose, nacelle_yaw) = path_pose(&self.cfg, t);
        self.scene.nacelle_yaw_deg = nacelle_yaw;
        self.scene.rotor_angle_deg = self.base_rotor_deg + self.cfg.rotor_rpm * 6.0 * t;
        // Fresh sensor noise per frame; texture and clouds stay put. Reproducible per index.
        self.scene.frame = index;
        self.renderer
            .render(&self.scene, &pose, out)
            .map_err(|e| CaptureError::Render(e.to_string()))
    }

    /// Frame size in pixels.
    pub fn size(&self) -> (u32, u32) {
        let c = self.renderer.camera();
        (c.width, c.height)
    }
}

impl FrameSource for SyntheticSource {
    fn kind(&self) -> FrameSourceKind {
        FrameSourceKind::Synthetic
    }
    fn describe(&self) -> String {
        let (w, h) = self.size();
        format!(
            "synthetic {w}x{h} seed {} path {:.0} m -> {:.0} m over {:.0} s",
            self.cfg.seed,
            self.cfg.start_distance_m,
            self.cfg.end_distance_m,
            self.cfg.path_duration_s
        )
    }
    fn max_frame_len(&self) -> usize {
        let (w, h) = self.size();
        w as usize * h as usize * 3
    }
    fn self_paced(&self) -> bool {
        false
    }
    fn next_frame(&mut self, sink: &mut dyn FrameSink) -> Result<Step, CaptureError> {
        let (width, height) = self.size();
        let index = self.index;
        self.index += 1;
        // The truth is known only after rendering: the fill returns it for the header. The frame
        // is stamped when rendered (capture_ns: None), as a camera frame is when dequeued.
        let info = FrameInfo {
            width,
            height,
            format: PixelFormat::Bgr8,
            capture_ns: None,
            truth: FrameTruth::default(),
        };
        let cached = u64::from(self.cfg.cache_frames);
        if cached == 0 {
            sink.publish(info, &mut |out| {
                Ok(Some(frame_truth(&self.render_index(index, out)?)))
            })?;
            return Ok(Step::Frame);
        }
        let slot = (index % cached) as usize;
        if slot == self.cache.len() {
            let mut pixels = vec![0u8; info.len()];
            let truth = frame_truth(&self.render_index(index, &mut pixels)?);
            self.cache.push((pixels, truth));
        }
        let (pixels, truth) = &self.cache[slot];
        sink.publish(info, &mut |out| {
            out.copy_from_slice(pixels);
            Ok(Some(*truth))
        })?;
        Ok(Step::Frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sink::VecSink;

    #[test]
    fn a_cached_camera_plays_its_first_frames_again() {
        let cfg = SyntheticConfig {
            camera: SyntheticCamera::Usb,
            cache_frames: 2,
            ..SyntheticConfig::default()
        };
        let mut src = SyntheticSource::new(&cfg, 30.0).unwrap();
        let mut sink = VecSink::default();
        let mut frames = Vec::new();
        for _ in 0..3 {
            src.next_frame(&mut sink).unwrap();
            frames.push((sink.header, sink.pixels.clone()));
        }
        assert_eq!(
            frames.iter().map(|(h, _)| h.seq).collect::<Vec<_>>(),
            [0, 1, 2]
        );
        assert_ne!(
            frames[0].1, frames[1].1,
            "each cached frame is its own render"
        );
        assert_eq!(frames[0].1, frames[2].1, "frame 2 plays frame 0 again");
        assert_eq!(frames[0].0.truth, frames[2].0.truth);
        let mut fresh = SyntheticSource::new(
            &SyntheticConfig {
                cache_frames: 0,
                ..cfg
            },
            30.0,
        )
        .unwrap();
        let mut first = vec![0u8; frames[0].1.len()];
        fresh.render_index(0, &mut first).unwrap();
        assert_eq!(first, frames[0].1, "the cache holds the path's own frames");
    }
}
