//! The one config file (`config/hubtrack.toml`), one section per stage.
//!
//! Parsing is strict: an unknown key is an error naming its full path (`capture.synthetic.fsp`),
//! and every numeric value is checked against its allowed range with an error naming the key and
//! the range. Keys left out take the defaults below, which equal the documented file
//! `config/hubtrack.toml` (a test keeps them equal).

use serde::{Deserialize, Serialize};
use std::fmt::Display;
use std::path::{Path, PathBuf};

/// Why a config could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read config file {path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error (not a `source`: the message already says it, and error chains would
        /// print it twice).
        cause: std::io::Error,
    },
    /// TOML syntax error, unknown key or wrong type.
    #[error("config {origin}: key `{key}`: {message}")]
    Invalid {
        /// File name or "override".
        origin: String,
        /// Full dotted key path.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A value outside its allowed range.
    #[error("config key `{key}` = {value} is out of range: allowed {allowed}")]
    OutOfRange {
        /// Full dotted key path.
        key: String,
        /// The value given.
        value: String,
        /// The allowed range or set.
        allowed: String,
    },
}

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Config {
    /// The launcher (`hubtrack run`).
    pub run: RunConfig,
    /// The camera stage.
    pub capture: CaptureConfig,
    /// The recorder stage.
    pub recorder: RecorderConfig,
    /// The detect stage (and `hubtrack detect` / `eval`).
    pub detect: hubtrack_detect::params::DetectConfig,
    /// The track stage (and `hubtrack track`).
    pub track: hubtrack_track::params::TrackConfig,
    /// The control stage: the approach and the MAVLink link to the autopilot.
    pub control: ControlConfig,
    /// The simulator stage (simulated ArduCopter and camera, for the demo and `hubtrack fly`).
    pub sim: hubtrack_sim::SimConfig,
}

/// Which clock control stamps MAVLink input with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ClockSource {
    /// `CLOCK_MONOTONIC`, the clock of real cameras (flight).
    Monotonic,
    /// The simulator's clock (service `clock`), so a lockstep simulation has one time base.
    Sim,
}

/// `[control]`: the approach controller and the MAVLink link to the autopilot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControlConfig {
    /// MAVLink link to the autopilot: "udpin:HOST:PORT" (listen; replies go to the sender),
    /// "udpout:HOST:PORT" (send there), or "serial:DEVICE:BAUD" (e.g. "serial:/dev/ttyAMA0:921600").
    /// Default "udpin:127.0.0.1:14550"; the simulator sends there.
    pub link: String,
    /// Our MAVLink system id, [1, 255]: the vehicle's own (ArduPilot SYSID_THISMAV, default 1).
    pub system_id: u8,
    /// Our MAVLink component id, [1, 255]: 191 = MAV_COMP_ID_ONBOARD_COMPUTER.
    pub component_id: u8,
    /// Frame of the velocity setpoints: "body_offset_ned" (MAV_FRAME_BODY_OFFSET_NED = 9, velocities
    /// along the vehicle's heading, what ArduCopter documents for body velocities) or "body_ned" (8).
    pub setpoint_frame: hubtrack_mavlink::SetpointFrame,
    /// Setpoints are sent on every new track state and at least this often while inputs are fresh, [10, 50] Hz.
    pub setpoint_rate_hz: f64,
    /// Our HEARTBEAT to the autopilot, [0.2, 10] Hz (ArduPilot expects 1 Hz).
    pub heartbeat_hz: f64,
    /// No autopilot HEARTBEAT for this long means the link is lost: stop commanding, [500, 30000] ms.
    pub link_timeout_ms: u64,
    /// Attitude and position older than this are not used, [50, 5000] ms.
    pub vehicle_timeout_ms: u64,
    /// No track state for this long (wall clock) means our inputs are stale: send nothing at all,
    /// so ArduPilot's guided-mode timeout stops the vehicle, [50, 5000] ms.
    pub input_timeout_ms: u64,
    /// Clock used to stamp autopilot messages: "monotonic" (flight) or "sim" (simulated flights,
    /// where the simulator's clock drives the pipeline).
    pub clock: ClockSource,
    /// The T1/T2/T3 approach.
    pub approach: hubtrack_approach::ApproachConfig,
}

impl Default for ControlConfig {
    fn default() -> Self {
        ControlConfig {
            link: "udpin:127.0.0.1:14550".into(),
            system_id: 1,
            component_id: 191,
            setpoint_frame: hubtrack_mavlink::SetpointFrame::BodyOffsetNed,
            setpoint_rate_hz: 15.0,
            heartbeat_hz: 1.0,
            link_timeout_ms: 3000,
            vehicle_timeout_ms: 500,
            input_timeout_ms: 500,
            clock: ClockSource::Monotonic,
            approach: Default::default(),
        }
    }
}

/// `[run]`: which stages `hubtrack run` starts and how it stops them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    /// Stage processes to start. They start in pipeline order (recorder first, so it misses
    /// nothing) and stop in reverse (control first, recorder last), whatever the order here.
    pub stages: Vec<String>,
    /// Folder for recordings when `--record` is not given (relative to the working directory).
    pub record_dir: PathBuf,
    /// How long a stage may take to exit after SIGTERM before it is killed, ms.
    pub stop_timeout_ms: u64,
    /// How long a stage may take from start to its first heartbeat, ms.
    pub startup_timeout_ms: u64,
    /// Interval of each stage's status heartbeat, ms.
    pub status_interval_ms: u64,
    /// The stages get SIGTERM when the supervisor process dies (`kill -9`, a crash), so none
    /// is left running unsupervised. Off for `hubtrack run` by default: in flight a supervisor
    /// crash then leaves the pipeline flying rather than turning into the autopilot's guided
    /// timeout. `hubtrack fly` always sets it (simulated flights must not leave stages behind).
    pub stop_with_supervisor: bool,
    /// What the supervisor does when a stage dies or hangs.
    pub restart: RestartConfig,
    /// Scheduling niceness per stage, added to the niceness `hubtrack run` itself runs at (a
    /// systemd `Nice=` sets the base), -20 … 19. A stage not listed keeps its default: +10 for
    /// the recorder, 0 for the others (see [`RunConfig::nice_of`]). The recorder is
    /// throughput-bound (its queue absorbs delays) while detect → track → control is
    /// latency-bound, so on a 2-core computer the recorder yields the CPU to them. Going below
    /// the base needs CAP_SYS_NICE.
    pub nice: std::collections::BTreeMap<String, i32>,
}

/// When a stage is restarted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RestartPolicy {
    /// Never: a stage that ends stays down.
    Never,
    /// When it exits with an error, is killed by a signal, or stops heart-beating.
    OnFailure,
    /// Whenever it ends, also after a clean exit.
    Always,
}

/// `[run.restart]`: restart policy, back-off, crash-loop limit and liveness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RestartConfig {
    /// Policy of every stage not listed in `policy`.
    pub default_policy: RestartPolicy,
    /// Per-stage policy, e.g. `capture = "never"`.
    pub policy: std::collections::BTreeMap<String, RestartPolicy>,
    /// Delay before the first restart, ms; doubled after each restart inside the window.
    pub backoff_initial_ms: u64,
    /// Longest delay between restarts, ms.
    pub backoff_max_ms: u64,
    /// A stage restarted this many times within `window_s` is given up on (the others go on).
    pub max_restarts: u32,
    /// The crash-loop window, seconds.
    pub window_s: f64,
    /// A running stage that sends no heartbeat for this long is hung: it is killed and restarted, ms.
    pub liveness_timeout_ms: u64,
}

impl Default for RestartConfig {
    fn default() -> Self {
        RestartConfig {
            default_policy: RestartPolicy::OnFailure,
            policy: Default::default(),
            backoff_initial_ms: 100,
            backoff_max_ms: 5000,
            max_restarts: 5,
            window_s: 60.0,
            liveness_timeout_ms: 1500,
        }
    }
}

impl RestartConfig {
    /// The policy of `stage`.
    pub fn policy_of(&self, stage: &str) -> RestartPolicy {
        self.policy
            .get(stage)
            .copied()
            .unwrap_or(self.default_policy)
    }
}

/// Default niceness of the stages that do not run at 0 (see [`RunConfig::nice`]).
pub const DEFAULT_NICE: &[(&str, i32)] = &[("recorder", 10)];

impl RunConfig {
    /// The niceness stage `name` runs at: `[run.nice]`, else its default.
    pub fn nice_of(&self, name: &str) -> i32 {
        self.nice.get(name).copied().unwrap_or_else(|| {
            DEFAULT_NICE
                .iter()
                .find(|(n, _)| *n == name)
                .map_or(0, |(_, v)| *v)
        })
    }
}

impl Default for RunConfig {
    fn default() -> Self {
        RunConfig {
            stages: vec!["capture".into(), "recorder".into()],
            record_dir: PathBuf::from("out"),
            stop_timeout_ms: 3000,
            startup_timeout_ms: 5000,
            status_interval_ms: 250,
            stop_with_supervisor: false,
            restart: RestartConfig::default(),
            nice: DEFAULT_NICE
                .iter()
                .map(|(n, v)| (n.to_string(), *v))
                .collect(),
        }
    }
}

/// The stage names `[run].stages` may contain.
pub const KNOWN_STAGES: &[&str] = &["capture", "sim", "recorder", "detect", "track", "control"];

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

/// `[capture]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CaptureConfig {
    /// Frame source.
    pub source: SourceKind,
    /// Frames per second for synthetic and images; video: 0 = the file's own rate.
    pub fps: f64,
    /// Pacing of non-camera sources.
    pub pace: Pace,
    /// Images and video: start again at the end instead of stopping.
    #[serde(rename = "loop")]
    pub looping: bool,
    /// Stop after this many frames (0 = never).
    pub max_frames: u64,
    /// V4L2 camera.
    pub v4l: V4lConfig,
    /// Video file.
    pub video: VideoConfig,
    /// Still images.
    pub images: ImagesConfig,
    /// Synthetic renderer.
    pub synthetic: SyntheticConfig,
}

impl Default for CaptureConfig {
    fn default() -> Self {
        CaptureConfig {
            source: SourceKind::Synthetic,
            fps: 30.0,
            pace: Pace::Realtime,
            looping: true,
            max_frames: 0,
            v4l: V4lConfig::default(),
            video: VideoConfig::default(),
            images: ImagesConfig::default(),
            synthetic: SyntheticConfig::default(),
        }
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

/// `[capture.v4l]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct V4lConfig {
    /// Device path.
    pub device: PathBuf,
    /// Requested width, px.
    pub width: u32,
    /// Requested height, px.
    pub height: u32,
    /// Requested frame rate.
    pub fps: f64,
    /// Requested pixel format.
    pub format: V4lFormat,
    /// Let the camera choose exposure.
    pub auto_exposure: bool,
    /// Manual exposure time when `auto_exposure = false`, microseconds.
    pub exposure_us: u32,
    /// Driver buffers to queue.
    pub buffers: u32,
}

impl Default for V4lConfig {
    fn default() -> Self {
        V4lConfig {
            device: PathBuf::from("/dev/video0"),
            width: 1280,
            height: 720,
            fps: 30.0,
            format: V4lFormat::Mjpg,
            auto_exposure: true,
            exposure_us: 5000,
            buffers: 4,
        }
    }
}

/// `[capture.video]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct VideoConfig {
    /// Video file path.
    pub path: PathBuf,
}

/// `[capture.images]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ImagesConfig {
    /// A folder (all images in name order), one image file, or a glob such as `dir/*.jpg`.
    pub path: String,
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

/// `[capture.synthetic]`: a scripted camera path in front of a rendered turbine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SyntheticConfig {
    /// Lens.
    pub camera: SyntheticCamera,
    /// Seed of the scene (sky, ground, sun, effects); the same seed gives the same frames.
    pub seed: u64,
    /// Distance to the hub at the start, m.
    pub start_distance_m: f64,
    /// Distance to the hub at the end of the path, m (equal to start for a fixed distance).
    pub end_distance_m: f64,
    /// Time to fly from start to end distance, s (the path then repeats).
    pub path_duration_s: f64,
    /// Peak sideways sway, m.
    pub lateral_sway_m: f64,
    /// Peak relative yaw swing, degrees.
    pub yaw_swing_deg: f64,
    /// Camera height relative to the hub, m (negative = below).
    pub height_m: f64,
    /// Peak camera roll jitter, degrees.
    pub roll_jitter_deg: f64,
    /// Rotor speed, revolutions per minute (0 = parked).
    pub rotor_rpm: f64,
    /// Sensor noise standard deviation, 8-bit levels.
    pub noise_sigma: f64,
}

impl Default for SyntheticConfig {
    fn default() -> Self {
        SyntheticConfig {
            camera: SyntheticCamera::Gopro,
            seed: 1,
            start_distance_m: 35.0,
            end_distance_m: 10.0,
            path_duration_s: 20.0,
            lateral_sway_m: 3.0,
            yaw_swing_deg: 10.0,
            height_m: -2.0,
            roll_jitter_deg: 2.0,
            rotor_rpm: 0.0,
            noise_sigma: 2.0,
        }
    }
}

/// MCAP chunk compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Compression {
    /// No compression (fastest, largest).
    None,
    /// LZ4 (fast; the default).
    Lz4,
    /// Zstandard (smaller, slower).
    Zstd,
}

/// `[recorder]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecorderConfig {
    /// Chunk compression.
    pub compression: Compression,
    /// Target chunk size, KiB. A chunk is also closed at every flush.
    pub chunk_size_kib: u64,
    /// Frames buffered between the shared-memory reader and the disk writer; when full, further
    /// frames are dropped and counted (the camera never waits for the disk).
    pub queue_frames: usize,
    /// Close the current chunk and flush to the OS at least this often, ms: after a `kill -9`
    /// everything older than this is readable.
    pub flush_interval_ms: u64,
    /// Record the pixels of every frame (false: only the frame headers).
    pub record_frames: bool,
    /// Free space the recorder leaves on the recording's file system, MiB (0: no limit). Below
    /// it, frame pixels are no longer written (headers and results still are) so that the file
    /// can always be finished; above twice the limit, pixels are written again.
    pub min_free_mib: u64,
}

impl Default for RecorderConfig {
    fn default() -> Self {
        RecorderConfig {
            compression: Compression::Lz4,
            chunk_size_kib: 4096,
            queue_frames: 16,
            flush_interval_ms: 200,
            record_frames: true,
            min_free_mib: 512,
        }
    }
}

impl Config {
    /// Reads and validates a config file.
    pub fn load(path: &Path) -> Result<Config, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|cause| ConfigError::Io {
            path: path.to_path_buf(),
            cause,
        })?;
        Config::parse(&text, &path.display().to_string())
    }

    /// Parses and validates TOML text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Config, ConfigError> {
        let de = toml::Deserializer::parse(text).map_err(|e| ConfigError::Invalid {
            origin: origin.to_string(),
            key: "(syntax)".into(),
            message: e.to_string().trim().to_string(),
        })?;
        let config: Config = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            let inner = e.into_inner();
            ConfigError::Invalid {
                origin: origin.to_string(),
                key,
                message: inner.message().trim().to_string(),
            }
        })?;
        config.validate()?;
        Ok(config)
    }

    /// Loads `path` if given, else the defaults.
    pub fn load_or_default(path: Option<&Path>) -> Result<Config, ConfigError> {
        match path {
            Some(p) => Config::load(p),
            None => Ok(Config::default()),
        }
    }

    /// Applies `key=value` overrides (TOML values, e.g. `capture.fps=60`,
    /// `capture.source="images"`), then re-validates.
    pub fn with_overrides(&self, overrides: &[String]) -> Result<Config, ConfigError> {
        if overrides.is_empty() {
            return Ok(self.clone());
        }
        let mut doc: toml::Table =
            toml::Table::try_from(self).map_err(|e| ConfigError::Invalid {
                origin: "override".into(),
                key: "(all)".into(),
                message: e.to_string(),
            })?;
        for ov in overrides {
            let (key, value) = ov.split_once('=').ok_or_else(|| ConfigError::Invalid {
                origin: "override".into(),
                key: ov.clone(),
                message: "expected KEY=VALUE".into(),
            })?;
            let key = key.trim();
            let parsed: toml::Value = format!("v = {}", value.trim())
                .parse::<toml::Table>()
                .ok()
                .and_then(|mut t| t.remove("v"))
                // An unquoted word such as `images` is taken as a string.
                .unwrap_or_else(|| toml::Value::String(value.trim().to_string()));
            let mut table = &mut doc;
            let parts: Vec<&str> = key.split('.').collect();
            for part in &parts[..parts.len() - 1] {
                table = table
                    .entry(part.to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                    .as_table_mut()
                    .ok_or_else(|| ConfigError::Invalid {
                        origin: "override".into(),
                        key: key.to_string(),
                        message: format!("`{part}` is not a section"),
                    })?;
            }
            table.insert(parts[parts.len() - 1].to_string(), parsed);
        }
        Config::parse(&doc.to_string(), "override")
    }

    /// Checks every value against its allowed range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let r = &self.run;
        for s in &r.stages {
            if !KNOWN_STAGES.contains(&s.as_str()) {
                return Err(ConfigError::OutOfRange {
                    key: "run.stages".into(),
                    value: format!("{s:?}"),
                    allowed: format!("{KNOWN_STAGES:?}"),
                });
            }
        }
        range("run.stop_timeout_ms", r.stop_timeout_ms, 100, 60_000)?;
        range("run.startup_timeout_ms", r.startup_timeout_ms, 100, 60_000)?;
        range("run.status_interval_ms", r.status_interval_ms, 20, 10_000)?;
        let rs = &r.restart;
        for stage in rs.policy.keys() {
            if !KNOWN_STAGES.contains(&stage.as_str()) {
                return Err(out_of_range(
                    &format!("run.restart.policy.{stage}"),
                    stage,
                    format!("a stage of {KNOWN_STAGES:?}"),
                ));
            }
        }
        for (stage, nice) in &r.nice {
            if !KNOWN_STAGES.contains(&stage.as_str()) {
                return Err(out_of_range(
                    &format!("run.nice.{stage}"),
                    stage,
                    format!("a stage of {KNOWN_STAGES:?}"),
                ));
            }
            range(&format!("run.nice.{stage}"), *nice, -20, 19)?;
        }
        range(
            "run.restart.backoff_initial_ms",
            rs.backoff_initial_ms,
            0,
            60_000,
        )?;
        range(
            "run.restart.backoff_max_ms",
            rs.backoff_max_ms,
            rs.backoff_initial_ms,
            600_000,
        )?;
        range("run.restart.max_restarts", rs.max_restarts, 0, 1000)?;
        range("run.restart.window_s", rs.window_s, 1.0, 86_400.0)?;
        range(
            "run.restart.liveness_timeout_ms",
            rs.liveness_timeout_ms,
            4 * r.status_interval_ms,
            600_000,
        )?;
        let c = &self.capture;
        range("capture.fps", c.fps, 0.0, 1000.0)?;
        if c.source != SourceKind::Video && c.fps <= 0.0 {
            return Err(out_of_range(
                "capture.fps",
                c.fps,
                "(0, 1000] for this source",
            ));
        }
        range("capture.v4l.width", c.v4l.width, 16, 8192)?;
        range("capture.v4l.height", c.v4l.height, 16, 8192)?;
        range("capture.v4l.fps", c.v4l.fps, 1.0, 1000.0)?;
        range("capture.v4l.exposure_us", c.v4l.exposure_us, 1, 1_000_000)?;
        range("capture.v4l.buffers", c.v4l.buffers, 2, 32)?;
        let s = &c.synthetic;
        range(
            "capture.synthetic.start_distance_m",
            s.start_distance_m,
            3.0,
            500.0,
        )?;
        range(
            "capture.synthetic.end_distance_m",
            s.end_distance_m,
            3.0,
            500.0,
        )?;
        range(
            "capture.synthetic.path_duration_s",
            s.path_duration_s,
            0.1,
            3600.0,
        )?;
        range(
            "capture.synthetic.lateral_sway_m",
            s.lateral_sway_m,
            0.0,
            50.0,
        )?;
        range(
            "capture.synthetic.yaw_swing_deg",
            s.yaw_swing_deg,
            0.0,
            80.0,
        )?;
        range("capture.synthetic.height_m", s.height_m, -60.0, 60.0)?;
        range(
            "capture.synthetic.roll_jitter_deg",
            s.roll_jitter_deg,
            0.0,
            30.0,
        )?;
        range("capture.synthetic.rotor_rpm", s.rotor_rpm, 0.0, 30.0)?;
        range("capture.synthetic.noise_sigma", s.noise_sigma, 0.0, 50.0)?;
        let rec = &self.recorder;
        range("recorder.chunk_size_kib", rec.chunk_size_kib, 16, 1 << 20)?;
        range("recorder.queue_frames", rec.queue_frames, 1, 1024)?;
        range(
            "recorder.flush_interval_ms",
            rec.flush_interval_ms,
            10,
            60_000,
        )?;
        range("recorder.min_free_mib", rec.min_free_mib, 0, 1 << 24)?;
        self.detect
            .validate()
            .map_err(|e| ConfigError::OutOfRange {
                key: e.key,
                value: e.value,
                allowed: e.allowed,
            })?;
        self.track.validate().map_err(|e| ConfigError::OutOfRange {
            key: e.key,
            value: e.value,
            allowed: e.allowed,
        })?;
        let ctl = &self.control;
        ctl.link
            .parse::<hubtrack_mavlink::Endpoint>()
            .map_err(|e| out_of_range("control.link", format!("{:?}", ctl.link), e))?;
        range("control.system_id", ctl.system_id, 1, 255)?;
        range("control.component_id", ctl.component_id, 1, 255)?;
        range("control.setpoint_rate_hz", ctl.setpoint_rate_hz, 10.0, 50.0)?;
        range("control.heartbeat_hz", ctl.heartbeat_hz, 0.2, 10.0)?;
        range("control.link_timeout_ms", ctl.link_timeout_ms, 500, 30_000)?;
        range(
            "control.vehicle_timeout_ms",
            ctl.vehicle_timeout_ms,
            50,
            5000,
        )?;
        range("control.input_timeout_ms", ctl.input_timeout_ms, 50, 5000)?;
        ctl.approach
            .validate()
            .map_err(|e| ConfigError::OutOfRange {
                key: e.key,
                value: e.value,
                allowed: e.allowed,
            })?;
        self.sim
            .link
            .parse::<hubtrack_mavlink::Endpoint>()
            .map_err(|e| out_of_range("sim.link", format!("{:?}", self.sim.link), e))?;
        self.sim.validate().map_err(|e| ConfigError::OutOfRange {
            key: e.key,
            value: e.value,
            allowed: e.allowed,
        })?;
        if self.run.stages.iter().any(|s| s == "sim")
            && self.run.stages.iter().any(|s| s == "capture")
        {
            return Err(out_of_range(
                "run.stages",
                format!("{:?}", self.run.stages),
                "either \"capture\" or \"sim\" (both publish frames)",
            ));
        }
        // Detect and track each estimate distance and yaw: their lens and turbine must agree.
        let (dc, tc) = (&self.detect.camera, &self.track);
        for (dk, dv, tk, tv) in [
            (
                "detect.camera.hfov_deg",
                dc.hfov_deg,
                "track.camera.hfov_deg",
                tc.camera.hfov_deg,
            ),
            (
                "detect.camera.focal_length_per_width",
                dc.focal_length_per_width,
                "track.camera.focal_length_per_width",
                tc.camera.focal_length_per_width,
            ),
            (
                "detect.camera.tower_top_diameter_m",
                dc.tower_top_diameter_m,
                "track.distance.tower_diameter_m",
                tc.distance.tower_diameter_m,
            ),
            (
                "detect.camera.hub_tower_gap_m",
                dc.hub_tower_gap_m,
                "track.yaw.hub_tower_offset_m",
                tc.yaw.hub_tower_offset_m,
            ),
            (
                "detect.camera.spinner_diameter_m",
                dc.spinner_diameter_m,
                "track.distance.spinner_diameter_m",
                tc.distance.spinner_diameter_m,
            ),
        ] {
            if dv != tv {
                return Err(ConfigError::OutOfRange {
                    key: dk.into(),
                    value: dv.to_string(),
                    allowed: format!("the same value as `{tk}` ({tv})"),
                });
            }
        }
        Ok(())
    }
}

fn out_of_range(key: &str, value: impl Display, allowed: impl Display) -> ConfigError {
    ConfigError::OutOfRange {
        key: key.into(),
        value: value.to_string(),
        allowed: allowed.to_string(),
    }
}

/// Checks `lo <= value <= hi` (NaN fails).
fn range<T: PartialOrd + Display + Copy>(
    key: &str,
    value: T,
    lo: T,
    hi: T,
) -> Result<(), ConfigError> {
    if value >= lo && value <= hi {
        Ok(())
    } else {
        Err(out_of_range(key, value, format!("[{lo}, {hi}]")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn documented_file_equals_defaults() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/hubtrack.toml");
        let from_file = Config::load(&path).expect("config/hubtrack.toml must load");
        assert_eq!(from_file, Config::default());
    }

    #[test]
    fn every_shipped_config_file_is_valid() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config");
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                Config::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                n += 1;
            }
        }
        assert!(n >= 2);
    }

    #[test]
    fn unknown_key_is_named_with_its_path() {
        let err = Config::parse("[capture.synthetic]\nfsp = 3\n", "t.toml").unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("capture.synthetic.fsp"), "{msg}");
        assert!(msg.contains("unknown field"), "{msg}");
    }

    #[test]
    fn out_of_range_names_key_and_range() {
        let err = Config::parse("[capture]\nfps = 5000\n", "t.toml").unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("capture.fps") && msg.contains("[0, 1000]"),
            "{msg}"
        );
    }

    #[test]
    fn stage_niceness_defaults_overrides_and_range() {
        let d = Config::default();
        assert_eq!(
            (d.run.nice_of("recorder"), d.run.nice_of("detect")),
            (10, 0)
        );
        // Naming one stage keeps the other stages' defaults.
        let c = Config::parse("[run.nice]\ncapture = 5\n", "t.toml").unwrap();
        assert_eq!(
            (
                c.run.nice_of("capture"),
                c.run.nice_of("recorder"),
                c.run.nice_of("track")
            ),
            (5, 10, 0)
        );
        let err = Config::parse("[run.nice]\ndetect = 25\n", "t.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("run.nice.detect") && err.contains("[-20, 19]"),
            "{err}"
        );
        let err = Config::parse("[run.nice]\ncamera = 1\n", "t.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("run.nice.camera"), "{err}");
    }

    #[test]
    fn wrong_type_names_key() {
        let err = Config::parse("[recorder]\nqueue_frames = \"many\"\n", "t.toml").unwrap_err();
        assert!(err.to_string().contains("recorder.queue_frames"), "{err}");
    }

    #[test]
    fn detect_and_track_must_share_the_lens() {
        let err = Config::parse("[track.camera]\nfocal_length_per_width = 0.5\n", "t")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("detect.camera.focal_length_per_width")
                && err.contains("track.camera.focal_length_per_width"),
            "{err}"
        );
    }

    #[test]
    fn unknown_stage_is_rejected() {
        let err = Config::parse("[run]\nstages = [\"capture\", \"detcet\"]\n", "t").unwrap_err();
        assert!(err.to_string().contains("run.stages"), "{err}");
    }

    #[test]
    fn overrides_apply_and_validate() {
        let c = Config::default()
            .with_overrides(&["capture.fps=60".into(), "capture.source=images".into()])
            .unwrap();
        assert_eq!(c.capture.fps, 60.0);
        assert_eq!(c.capture.source, SourceKind::Images);
        assert!(Config::default()
            .with_overrides(&["capture.nope=1".into()])
            .is_err());
        assert!(Config::default()
            .with_overrides(&["recorder.queue_frames=0".into()])
            .is_err());
    }
}

/// Command-line options every stage process takes: `--config FILE` and `--set KEY=VALUE`.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct ConfigArgs {
    /// Config file (TOML); default: built-in defaults, as documented in config/hubtrack.toml.
    #[arg(long, short = 'c', value_name = "FILE", env = "HUBTRACK_CONFIG")]
    pub config: Option<PathBuf>,
    /// Override one key, e.g. `--set capture.fps=60` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,
}

impl ConfigArgs {
    /// Loads the file (or defaults) and applies the overrides.
    pub fn load(&self) -> Result<Config, ConfigError> {
        Config::load_or_default(self.config.as_deref())?.with_overrides(&self.overrides)
    }
}
