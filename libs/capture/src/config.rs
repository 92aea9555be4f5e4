//! `[capture]`: which frame source the camera stage opens and how it paces it.

use hubtrack_types::params;
use hubtrack_types::params::ParamError;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

hubtrack_runtime::sections! {
    /// What the capture stage reads: its own section, and the camera and turbine the synthetic
    /// camera films when files name them.
    pub struct CaptureSections {
        capture: CaptureConfig,
        camera: hubtrack_types::setup::CameraSetup,
        turbine: hubtrack_types::setup::TurbineSetup,
    }
}

/// Which frame source the capture stage uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SourceKind {
    /// A V4L2 camera.
    V4l,
    /// A video file through OpenCV.
    Video,
    /// A folder, file or glob of still images.
    Images,
    /// The synthetic turbine renderer.
    Synthetic,
}

/// How non-camera sources are paced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Pace {
    /// At `capture.fps` (video: its own frame rate when `capture.fps` is 0).
    Realtime,
    /// As fast as possible.
    Fast,
}

params! {
    /// `[capture]`.
    pub struct CaptureConfig {
        /// Frame source.
        pub source: SourceKind = SourceKind::Synthetic;
        /// Frames per second for synthetic and images; video: 0 = the file's own rate.
        pub fps: f64 = 30.0, closed(0.0, 1000.0);
        /// Pacing of non-camera sources.
        pub pace: Pace = Pace::Realtime;
        /// Images and video: start again at the end instead of stopping.
        #[serde(rename = "loop")]
        pub looping: bool = true;
        /// Stop after this many frames (0 = never).
        pub max_frames: u64 = 0;
        /// V4L2 camera.
        pub v4l: V4lConfig = V4lConfig::default();
        /// Video file.
        pub video: VideoConfig = VideoConfig::default();
        /// Still images.
        pub images: ImagesConfig = ImagesConfig::default();
        /// Synthetic renderer.
        pub synthetic: SyntheticConfig = SyntheticConfig::default();
    }
}

impl CaptureConfig {
    /// Checks every value; errors name the key under `capture`.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("capture")?;
        if self.source != SourceKind::Video && self.fps <= 0.0 {
            return Err(ParamError {
                key: "capture.fps".into(),
                value: self.fps.to_string(),
                allowed: "(0, 1000] for this source".into(),
                problem: None,
            });
        }
        self.v4l.check_ranges("capture.v4l")?;
        self.synthetic.check_ranges("capture.synthetic")
    }
}

/// Pixel format requested from a V4L2 camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum V4lFormat {
    /// Motion JPEG (decoded with OpenCV).
    Mjpg,
    /// YUYV 4:2:2 (converted in Rust).
    Yuyv,
}

params! {
    /// `[capture.v4l]`.
    pub struct V4lConfig {
        /// Device path.
        pub device: PathBuf = PathBuf::from("/dev/video0");
        /// Requested width, px.
        pub width: u32 = 1280, closed(16, 8192);
        /// Requested height, px.
        pub height: u32 = 720, closed(16, 8192);
        /// Requested frame rate.
        pub fps: f64 = 30.0, closed(1.0, 1000.0);
        /// Requested pixel format.
        pub format: V4lFormat = V4lFormat::Mjpg;
        /// Let the camera choose exposure.
        pub auto_exposure: bool = true;
        /// Manual exposure time when `auto_exposure = false`, microseconds.
        pub exposure_us: u32 = 5000, closed(1, 1_000_000);
        /// Driver buffers to queue.
        pub buffers: u32 = 4, closed(2, 32);
    }
}

params! {
    /// `[capture.video]`.
    pub struct VideoConfig {
        /// Video file path.
        pub path: PathBuf = PathBuf::new();
    }
}

params! {
    /// `[capture.images]`.
    pub struct ImagesConfig {
        /// A folder (all images in name order), one image file, or a glob such as `dir/*.jpg`.
        pub path: String = String::new();
    }
}

/// Lens of the synthetic camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SyntheticCamera {
    /// GoPro HERO3+ wide: 1920×1080, 118°×69.5°, barrel distortion (the thesis's camera).
    Gopro,
    /// Narrow USB camera: 640×480, 60° diagonal.
    Usb,
}

params! {
    /// `[capture.synthetic]`: a scripted camera path in front of a rendered turbine.
    pub struct SyntheticConfig {
        /// Lens, unless `[camera] calibration` names one (see `synthetic::Filming`).
        pub camera: SyntheticCamera = SyntheticCamera::Gopro;
        /// Seed of the scene (sky, ground, sun, effects); the same seed gives the same frames.
        pub seed: u64 = 1;
        /// Distance to the hub at the start, m.
        pub start_distance_m: f64 = 35.0, closed(3.0, 500.0);
        /// Distance to the hub at the end of the path, m (equal to start for a fixed distance).
        pub end_distance_m: f64 = 10.0, closed(3.0, 500.0);
        /// Time to fly from start to end distance, s (the path then repeats).
        pub path_duration_s: f64 = 20.0, closed(0.1, 3600.0);
        /// Peak sideways sway, m.
        pub lateral_sway_m: f64 = 3.0, closed(0.0, 50.0);
        /// Peak relative yaw swing, degrees.
        pub yaw_swing_deg: f64 = 10.0, closed(0.0, 80.0);
        /// Camera height relative to the hub, m (negative = below).
        pub height_m: f64 = -2.0, closed(-60.0, 60.0);
        /// Peak camera roll jitter, degrees.
        pub roll_jitter_deg: f64 = 2.0, closed(0.0, 30.0);
        /// Rotor speed, revolutions per minute (0 = parked).
        pub rotor_rpm: f64 = 0.0, closed(0.0, 30.0);
        /// Sensor noise standard deviation, 8-bit levels.
        pub noise_sigma: f64 = 2.0, closed(0.0, 50.0);
        /// Render only the path's first N frames, then play them again in a loop (new seq and
        /// stamps, the same pixels and truth): a camera that costs a copy per frame, as a V4L2
        /// camera's DMA does, for benchmarks of the flight stages (rendering 1080p takes most of
        /// a core). 0: render every frame.
        pub cache_frames: u32 = 0, closed(0, 600);
    }
}
