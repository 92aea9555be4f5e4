//! Messages that cross process boundaries.
//!
//! Every type here is `#[repr(C)]`, fixed size, pointer free and `Copy`, so it can live in iceoryx2
//! shared memory (`#[derive(ZeroCopySend)]`). They also derive `serde` and `schemars` so the
//! recorder writes them as JSON with an embedded JSON schema, and replay reads them back exactly
//! (all physical quantities are `f64`, which JSON round-trips bit for bit).

use iceoryx2::prelude::ZeroCopySend;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Frame sequence number, capture time and per-stage stamps carried by every result message.
/// All times are `CLOCK_MONOTONIC` ns (see [`crate::time`]).
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::Stamps")]
pub struct Stamps {
    /// Sequence number of the camera frame this result derives from.
    pub seq: u64,
    /// When that frame was captured.
    pub capture_ns: u64,
    /// When the publishing stage received its input.
    pub recv_ns: u64,
    /// When the publishing stage published this message.
    pub publish_ns: u64,
}

/// Pixel layout of a frame's `[u8]` payload.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::PixelFormat")]
pub enum PixelFormat {
    /// 8-bit blue, green, red; `stride >= 3 * width`.
    #[default]
    Bgr8 = 1,
    /// 8-bit luminance; `stride >= width`.
    Gray8 = 2,
}

impl PixelFormat {
    /// Bytes per pixel.
    pub const fn bytes_per_pixel(self) -> usize {
        match self {
            PixelFormat::Bgr8 => 3,
            PixelFormat::Gray8 => 1,
        }
    }
}

/// Which kind of source produced a frame.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::FrameSourceKind")]
pub enum FrameSourceKind {
    /// A V4L2 camera.
    #[default]
    Camera = 1,
    /// A video file.
    Video = 2,
    /// A folder or glob of still images.
    Images = 3,
    /// The synthetic turbine renderer.
    Synthetic = 4,
    /// The flight simulator's rendered camera.
    Sim = 5,
    /// Frames replayed from a recording.
    Replay = 6,
}

/// Exact ground truth of a rendered frame (synthetic source and simulator only; `valid == false`
/// for real cameras). Pixel coordinates are in the frame's own resolution, origin top-left.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::FrameTruth")]
pub struct FrameTruth {
    /// The frame was rendered and the fields below hold its truth.
    pub valid: bool,
    /// A turbine is present and its hub lies inside the image.
    pub turbine_in_view: bool,
    /// Where the blade axes meet (rotor centre in the blade-root plane), px.
    pub hub_px: [f64; 2],
    /// Tip of the spinner nose cone, px.
    pub nose_px: [f64; 2],
    /// Tower axis at the top of the tower, px.
    pub tower_top_px: [f64; 2],
    /// Tower width in px, measured at image row `tower_width_row`.
    pub tower_width_px: f64,
    /// The image row at which `tower_width_px` is measured.
    pub tower_width_row: f64,
    /// Camera-to-hub distance, metres.
    pub distance_m: f64,
    /// Relative yaw, degrees: positive when the camera stands on the turbine's own left (the
    /// viewer's right when facing the rotor) and looks at the hub; zero when facing the rotor.
    pub relative_yaw_deg: f64,
}

/// User header of every sample on the frames service; the pixels are the sample's `[u8]` payload.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::FrameHeader")]
pub struct FrameHeader {
    /// Frame sequence number, +1 per frame the source produced (a gap means a lost frame).
    pub seq: u64,
    /// When the frame was captured (monotonic ns).
    pub capture_ns: u64,
    /// When the frame was captured (realtime, epoch ns).
    pub capture_realtime_ns: u64,
    /// When capture published the frame (monotonic ns).
    pub publish_ns: u64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bytes per row (`>= width * bytes_per_pixel`).
    pub stride: u32,
    /// Pixel layout.
    pub format: PixelFormat,
    /// What produced the frame.
    pub source: FrameSourceKind,
    /// Ground truth for rendered frames.
    pub truth: FrameTruth,
    /// Bytes of the camera's own JPEG of this frame (a V4L2 MJPG camera, a JPEG image file),
    /// carried after the pixels in the same sample so the recorder stores it without encoding
    /// again; 0: none.
    #[serde(default)]
    pub camera_jpeg_len: u32,
}

impl FrameHeader {
    /// Pixel bytes the header describes (`stride * height`).
    pub fn payload_len(&self) -> usize {
        self.stride as usize * self.height as usize
    }

    /// Bytes of the whole sample: the pixels, then the camera's JPEG if any.
    pub fn sample_len(&self) -> usize {
        self.payload_len() + self.camera_jpeg_len as usize
    }

    /// The camera's own JPEG in a sample's payload, if the header announces one and it is there.
    pub fn camera_jpeg<'a>(&self, payload: &'a [u8]) -> Option<&'a [u8]> {
        if self.camera_jpeg_len == 0 {
            return None;
        }
        payload.get(self.payload_len()..self.sample_len())
    }
}

/// Maximum number of blade angles carried in a [`Detection`].
pub const MAX_BLADES: usize = 6;

/// Time spent in each step of one detection, microseconds.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::DetectTimings")]
pub struct DetectTimings {
    /// Pyramid downsampling (and colour conversion).
    pub pyramid_us: f64,
    /// Edge detection.
    pub edges_us: f64,
    /// Hough line (and circle) transforms.
    pub hough_us: f64,
    /// Tower, blade and hub geometry.
    pub geometry_us: f64,
    /// Whole detection.
    pub total_us: f64,
}

/// Result of the detect stage for one frame.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::Detection")]
pub struct Detection {
    /// Frame identity and stage stamps.
    pub stamps: Stamps,
    /// Full-resolution image width of the frame, px.
    pub image_width: u32,
    /// Full-resolution image height of the frame, px.
    pub image_height: u32,
    /// A hub was found.
    pub detected: bool,
    /// Hub position, full-resolution px (valid when `detected`).
    pub hub_px: [f64; 2],
    /// 0..1; how much the detector believes this is a turbine hub.
    pub confidence: f64,
    /// A tower was found.
    pub tower_found: bool,
    /// Tower top on its axis, px.
    pub tower_top_px: [f64; 2],
    /// Tower width, px, measured at row `tower_width_row`.
    pub tower_width_px: f64,
    /// Image row of the tower width measurement, px.
    pub tower_width_row: f64,
    /// Signed horizontal gap hub minus tower axis, px (for yaw estimation).
    pub hub_tower_gap_px: f64,
    /// A spinner circle was found.
    pub circle_found: bool,
    /// Spinner circle `[x, y, radius]`, px.
    pub circle: [f64; 3],
    /// The nacelle was seen sticking out beside the spinner on one side (needs the tracker's
    /// distance; see `hubtrack-detect`'s nacelle step).
    pub nacelle_found: bool,
    /// Signed horizontal offset from the hub to the nacelle's far end, px (positive: to the
    /// right; a camera on the turbine's left sees the nacelle to the right of the hub).
    pub nacelle_end_dx_px: f64,
    /// The learned yaw network read the view around the hub (needs the hub's distance; see
    /// `detect.default.hub_yaw`). Absent in recordings from before it: false.
    #[serde(default)]
    pub yaw_net_valid: bool,
    /// The relative yaw it read, degrees (the sign of `TrackState::yaw_deg`).
    #[serde(default)]
    pub yaw_net_deg: f64,
    /// Its standard deviation, degrees.
    #[serde(default)]
    pub yaw_net_std_deg: f64,
    /// Number of valid entries in `blade_angles_deg`.
    pub blade_count: u32,
    /// Blade angles in the image, degrees, 0 = up, clockwise.
    pub blade_angles_deg: [f64; MAX_BLADES],
    /// Camera roll used for compensation, degrees.
    pub roll_used_deg: f64,
    /// Number of Hough lines.
    pub line_count: u32,
    /// Number of edge pixels.
    pub edge_count: u32,
    /// Frames the detector skipped to stay on the newest frame, since start.
    pub frames_skipped: u64,
    /// Per-step timings.
    pub timings: DetectTimings,
}

/// Track mode of the hub tracker.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::TrackMode")]
#[serde(rename_all = "snake_case")]
pub enum TrackMode {
    /// No track yet, collecting first detections.
    #[default]
    Acquiring = 0,
    /// Detections arrive and update the track.
    Tracking = 1,
    /// Recent detections missing: predicting.
    Coasting = 2,
    /// The track is lost.
    Lost = 3,
}

/// Output of the track stage.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::TrackState")]
pub struct TrackState {
    /// Frame identity and stage stamps.
    pub stamps: Stamps,
    /// Track mode.
    pub mode: TrackMode,
    /// The tracker asks for a search manoeuvre (prolonged loss).
    pub search_requested: bool,
    /// Full-resolution image width, px.
    pub image_width: u32,
    /// Full-resolution image height, px.
    pub image_height: u32,
    /// Filtered hub position, px.
    pub hub_px: [f64; 2],
    /// Filtered hub velocity, px/s.
    pub hub_velocity_px_s: [f64; 2],
    /// Position covariance `[xx, xy, yx, yy]`, px².
    pub hub_covariance: [f64; 4],
    /// Direction of the filtered hub from the camera's optical axis through the tracker's
    /// camera model, degrees: `[azimuth (right positive), elevation (up positive)]`.
    pub hub_bearing_deg: [f64; 2],
    /// Distance estimate is usable.
    pub distance_valid: bool,
    /// Distance to the hub, metres.
    pub distance_m: f64,
    /// Standard deviation of `distance_m`.
    pub distance_std_m: f64,
    /// Yaw estimate is usable.
    pub yaw_valid: bool,
    /// Relative yaw (sign as in [`FrameTruth::relative_yaw_deg`]), degrees.
    pub yaw_deg: f64,
    /// Standard deviation of `yaw_deg`.
    pub yaw_std_deg: f64,
    /// The detector's learned yaw network gave a trusted reading on this frame (taken from
    /// `track.yaw.net_fallback_min_distance_m` out, within the gates of its own filter).
    /// Absent in recordings from before it: false.
    #[serde(default)]
    pub net_yaw_valid: bool,
    /// The network's relative yaw, filtered like `yaw_deg` over its trusted readings, degrees.
    /// A separate cue from `yaw_deg` (which holds the geometric cues only, see
    /// `track.yaw.net_fuse`): the controller weighs the two
    /// (`control.approach.net_heading_weight`).
    #[serde(default)]
    pub net_yaw_deg: f64,
    /// Standard deviation of `net_yaw_deg`.
    #[serde(default)]
    pub net_yaw_std_deg: f64,
    /// Frames since the last accepted detection.
    pub frames_since_detection: u32,
    /// Seconds since the last accepted detection.
    pub time_since_detection_s: f64,
    /// Share of the tower's width in this frame's fused distance measurement, 0..1 (its
    /// inverse variance over the sum of all cues'); the three shares sum to 1 on a frame whose
    /// detection gave a distance, else all are 0. Absent in recordings from before them: 0.
    #[serde(default)]
    pub distance_share_tower: f64,
    /// Share of the spinner's size, 0..1 (see `distance_share_tower`).
    #[serde(default)]
    pub distance_share_spinner: f64,
    /// Share of the motion parallax, 0..1 (see `distance_share_tower`).
    #[serde(default)]
    pub distance_share_parallax: f64,
    /// This frame's detection put the hub where the turbine profile's hub cannot be relative to
    /// the tower it found, and was kept out of the track (`[track.profile_check]`). Absent in
    /// recordings from before it: false.
    #[serde(default)]
    pub profile_contradiction: bool,
}

/// Defines a fixed-capacity UTF-8 text type of `$n` bytes (NUL padded) for shared memory.
macro_rules! fixed_text {
    ($(#[$doc:meta])* $name:ident, $n:literal, $type_name:literal) => {
        $(#[$doc])*
        #[repr(C)]
        #[derive(Clone, Copy, PartialEq, Eq, ZeroCopySend)]
        #[type_name($type_name)]
        pub struct $name(pub [u8; $n]);

        impl Default for $name {
            fn default() -> Self {
                $name([0; $n])
            }
        }

        impl $name {
            #[doc = concat!("Builds from a string, truncated at a char boundary to ", stringify!($n), " bytes.")]
            pub fn new(s: &str) -> Self {
                let mut out = [0u8; $n];
                let mut end = s.len().min($n);
                while !s.is_char_boundary(end) {
                    end -= 1;
                }
                out[..end].copy_from_slice(&s.as_bytes()[..end]);
                $name(out)
            }

            /// The text up to the first NUL.
            pub fn as_str(&self) -> &str {
                let end = self.0.iter().position(|&b| b == 0).unwrap_or($n);
                // Built only from &str, cut at a char boundary; fall back to "" for foreign bytes.
                std::str::from_utf8(&self.0[..end]).unwrap_or("")
            }
        }

        impl std::fmt::Debug for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "{:?}", self.as_str())
            }
        }

        impl Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(self.as_str())
            }
        }

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let s = String::deserialize(d)?;
                Ok($name::new(&s))
            }
        }

        impl JsonSchema for $name {
            fn schema_name() -> std::borrow::Cow<'static, str> {
                stringify!($name).into()
            }
            fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
                schemars::json_schema!({ "type": "string", "maxLength": $n })
            }
        }
    };
}

fixed_text!(
    /// A fixed-capacity text (NUL padded) for names, reasons and error messages in shared memory.
    Text64,
    64,
    "hubtrack::Text64"
);

fixed_text!(
    /// A fixed-capacity text (NUL padded) for a log line in shared memory.
    Text512,
    512,
    "hubtrack::Text512"
);

/// Severity of a [`LogLine`], numbered as `foxglove.Log.Level` numbers its values, so the
/// recorder writes it unchanged.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend)]
#[type_name("hubtrack::LogLevel")]
pub enum LogLevel {
    /// `debug!` and `trace!`.
    Debug = 1,
    /// `info!`.
    #[default]
    Info = 2,
    /// `warn!`.
    Warning = 3,
    /// `error!`.
    Error = 4,
}

/// One line a stage logged, as it printed it, for the recorder (`/log` in a recording).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("hubtrack::LogLine")]
pub struct LogLine {
    /// When it was logged, wall clock (ns since the Unix epoch).
    pub realtime_ns: u64,
    /// Severity.
    pub level: LogLevel,
    /// Source line of the log call (0: unknown).
    pub line: u32,
    /// The stage that logged it (`detect`, `control`, ...).
    pub stage: Text64,
    /// Source file of the log call, cut to 64 bytes.
    pub file: Text64,
    /// The message, cut to 512 bytes.
    pub text: Text512,
}

/// Which task of the approach produced a setpoint.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::ApproachTask")]
#[serde(rename_all = "snake_case")]
pub enum ApproachTask {
    /// Hover in place.
    #[default]
    Hold = 0,
    /// T1: keep the hub in the target box (climb/descend, yaw).
    CentreHub = 1,
    /// T2: reduce relative yaw by moving sideways.
    ReduceYaw = 2,
    /// T3: move forward to the distance target.
    Approach = 3,
    /// Rotate slowly to find the turbine.
    Search = 4,
    /// At target.
    Done = 5,
    /// Bad data or link loss.
    Abort = 6,
}

/// Output of the control stage: a body-frame velocity and yaw-rate command.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::Setpoint")]
pub struct Setpoint {
    /// Frame identity and stage stamps.
    pub stamps: Stamps,
    /// Active task.
    pub task: ApproachTask,
    /// The setpoint was sent to the autopilot (armed, GUIDED, fresh inputs).
    pub sent: bool,
    /// Forward velocity, body frame, m/s.
    pub vx_m_s: f64,
    /// Right velocity, body frame, m/s.
    pub vy_m_s: f64,
    /// Down velocity, body frame, m/s.
    pub vz_m_s: f64,
    /// Yaw rate, rad/s, positive clockwise seen from above.
    pub yaw_rate_rad_s: f64,
    /// Why this task is active.
    pub reason: Text64,
}

/// The vehicle's state as reported by the autopilot (or the simulator).
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::VehicleState")]
pub struct VehicleState {
    /// When the newest autopilot message in this state was received (monotonic ns).
    pub recv_ns: u64,
    /// When this state was published (monotonic ns).
    pub publish_ns: u64,
    /// Autopilot HEARTBEAT seen recently.
    pub link_ok: bool,
    /// Motors armed.
    pub armed: bool,
    /// ArduCopter custom mode number (4 = GUIDED).
    pub custom_mode: u32,
    /// Attitude fields are valid.
    pub attitude_valid: bool,
    /// Roll, rad (right wing down positive).
    pub roll_rad: f64,
    /// Pitch, rad (nose up positive).
    pub pitch_rad: f64,
    /// Yaw, rad (clockwise from north).
    pub yaw_rad: f64,
    /// Body rates `[p, q, r]`, rad/s.
    pub body_rates_rad_s: [f64; 3],
    /// Position fields are valid.
    pub position_valid: bool,
    /// Local position north, east, down, metres.
    pub position_ned_m: [f64; 3],
    /// Local velocity north, east, down, m/s.
    pub velocity_ned_m_s: [f64; 3],
}

/// Periodic status of a stage process (its heartbeat); read by the supervisor and recorded.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::StageStatus")]
pub struct StageStatus {
    /// Stage name (`capture`, `detect`, ...).
    pub stage: Text64,
    /// Process id.
    pub pid: u32,
    /// When this status was published (monotonic ns).
    pub publish_ns: u64,
    /// Process start (monotonic ns).
    pub started_ns: u64,
    /// Inputs received since start (frames, messages).
    pub inputs: u64,
    /// Outputs published since start.
    pub outputs: u64,
    /// Inputs skipped on purpose to stay on the newest one.
    pub skipped: u64,
    /// Inputs lost (overwritten before read, dropped because a queue was full).
    pub dropped: u64,
    /// Errors since start.
    pub errors: u64,
    /// The last error, if any.
    pub last_error: Text64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text64_truncates_at_char_boundary() {
        let s = "é".repeat(40); // 80 bytes
        let t = Text64::new(&s);
        assert_eq!(t.as_str().len(), 64);
        assert_eq!(t.as_str(), &s[..64]);
    }

    /// Recordings made before a field was added still replay: the fields added later
    /// (`Detection::yaw_net_*`, `TrackState::net_yaw_*`) default when absent.
    #[test]
    fn messages_recorded_before_the_network_fields_still_read() {
        let mut track = serde_json::to_value(TrackState {
            yaw_valid: true,
            yaw_deg: 2.5,
            ..TrackState::default()
        })
        .unwrap();
        for key in ["net_yaw_valid", "net_yaw_deg", "net_yaw_std_deg"] {
            assert!(
                track.as_object_mut().unwrap().remove(key).is_some(),
                "{key}"
            );
        }
        let back: TrackState = serde_json::from_value(track).unwrap();
        assert!(back.yaw_valid && back.yaw_deg == 2.5 && !back.net_yaw_valid);
        let mut det = serde_json::to_value(Detection {
            detected: true,
            ..Detection::default()
        })
        .unwrap();
        for key in ["yaw_net_valid", "yaw_net_deg", "yaw_net_std_deg"] {
            assert!(det.as_object_mut().unwrap().remove(key).is_some(), "{key}");
        }
        let back: Detection = serde_json::from_value(det).unwrap();
        assert!(back.detected && !back.yaw_net_valid);
    }

    #[test]
    fn the_cameras_jpeg_is_found_after_the_pixels_or_not_at_all() {
        let mut h = FrameHeader {
            width: 2,
            height: 2,
            stride: 6,
            ..FrameHeader::default()
        };
        let mut payload = vec![0u8; 24];
        payload[24 - 3..].copy_from_slice(&[0xFF, 0xD8, 0xFF]);
        assert_eq!(h.camera_jpeg(&payload), None, "no JPEG announced");
        h.camera_jpeg_len = 3;
        assert_eq!(h.sample_len(), 15);
        assert_eq!(h.camera_jpeg(&payload[..15]), Some(&payload[12..15]));
        h.camera_jpeg_len = 20;
        assert_eq!(h.camera_jpeg(&payload), None, "announced but cut short");
        let mut old = serde_json::to_value(h).unwrap();
        old.as_object_mut().unwrap().remove("camera_jpeg_len");
        let back: FrameHeader = serde_json::from_value(old).unwrap();
        assert_eq!(
            back.camera_jpeg_len, 0,
            "headers recorded before the field read as none"
        );
    }

    #[test]
    fn floats_round_trip_through_json_bit_for_bit() {
        // Replay feeds recorded JSON back into stages and must reproduce their outputs exactly:
        // this needs serde_json's correctly rounded parser (feature `float_roundtrip`).
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if !v.is_finite() {
                continue;
            }
            let back: f64 = serde_json::from_str(&serde_json::to_string(&v).unwrap()).unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{v:e}");
            let small = (x % 100_000_000) as f64 / 1e4 - 5_000.0;
            let back: f64 = serde_json::from_str(&serde_json::to_string(&small).unwrap()).unwrap();
            assert_eq!(back.to_bits(), small.to_bits(), "{small}");
        }
    }

    #[test]
    #[allow(clippy::field_reassign_with_default)] // fixed-size messages, filled field by field
    fn messages_round_trip_through_json_exactly() {
        let mut d = Detection::default();
        d.hub_px = [1_234.567_890_123, 0.1 + 0.2];
        d.stamps.seq = u64::MAX;
        let json = serde_json::to_string(&d).unwrap();
        let back: Detection = serde_json::from_str(&json).unwrap();
        assert_eq!(back, d);
        let mut s = Setpoint::default();
        s.reason = Text64::new("T1: hub outside target box");
        s.task = ApproachTask::CentreHub;
        let back: Setpoint = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        assert_eq!(back, s);
    }
}

/// Most lines one [`DetectOverlay`] carries.
pub const MAX_OVERLAY_LINES: usize = 128;

/// What an overlay line is.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend)]
#[type_name("hubtrack::OverlayKind")]
pub enum OverlayKind {
    /// A line the detector did not use.
    #[default]
    Other = 0,
    /// A tower edge.
    Tower = 1,
    /// A blade edge.
    Blade = 2,
    /// A line rejected by a check (voting, horizon, overlap).
    Rejected = 3,
}

/// One line segment of the overlay, full-resolution px.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("hubtrack::OverlaySegment")]
pub struct OverlaySegment {
    /// Start `[x, y]`.
    pub a: [f32; 2],
    /// End `[x, y]`.
    pub b: [f32; 2],
    /// Classification.
    pub kind: OverlayKind,
}

/// What the detector saw on one frame, for the recording (shown over the video in Foxglove).
/// The hub, tower top and spinner circle are in the [`Detection`] with the same seq.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("hubtrack::DetectOverlay")]
pub struct DetectOverlay {
    /// Frame identity and stage stamps (same as the frame's Detection).
    pub stamps: Stamps,
    /// The detection this overlay belongs to.
    pub detection: Detection,
    /// Blade search circle `[x, y, r]` (r = 0: none).
    pub search_circle: [f32; 3],
    /// Valid entries of `segments`.
    pub segment_count: u32,
    /// Hough segments with their classification.
    pub segments: [OverlaySegment; MAX_OVERLAY_LINES],
}

impl Default for DetectOverlay {
    fn default() -> Self {
        DetectOverlay {
            stamps: Stamps::default(),
            detection: Detection::default(),
            search_circle: [0.0; 3],
            segment_count: 0,
            segments: [OverlaySegment::default(); MAX_OVERLAY_LINES],
        }
    }
}

impl DetectOverlay {
    /// The valid segments.
    pub fn segments(&self) -> &[OverlaySegment] {
        &self.segments[..(self.segment_count as usize).min(MAX_OVERLAY_LINES)]
    }
}

/// Most stages one [`SupervisorStatus`] describes.
pub const MAX_STAGES: usize = 8;

/// Lifecycle state of a supervised stage.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::StageState")]
#[serde(rename_all = "snake_case")]
pub enum StageState {
    /// Started, no heartbeat yet.
    #[default]
    Starting = 0,
    /// Running and heart-beating.
    Running = 1,
    /// Ended; a restart is scheduled.
    Restarting = 2,
    /// Ended and not restarted (policy, or a clean end).
    Stopped = 3,
    /// Crashed too often: given up on.
    Failed = 4,
}

/// The supervisor's view of one stage.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::SupervisedStage")]
pub struct SupervisedStage {
    /// Stage name.
    pub name: Text64,
    /// Current process id (0 when not running).
    pub pid: u32,
    /// Lifecycle state.
    pub state: StageState,
    /// Restarts since the run began.
    pub restarts: u32,
    /// When the current process started (monotonic ns).
    pub started_ns: u64,
    /// Exit code or `-signal` of the last end, 0 if none.
    pub last_exit: i32,
    /// Why the last restart happened.
    pub last_reason: Text64,
}

/// Published by `hubtrack run` (history 1: a late subscriber gets the latest at once).
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::SupervisorStatus")]
pub struct SupervisorStatus {
    /// Supervisor process id.
    pub pid: u32,
    /// When this status was published (monotonic ns).
    pub publish_ns: u64,
    /// Valid entries of `stages`.
    pub stage_count: u32,
    /// The stages in start order.
    pub stages: [SupervisedStage; MAX_STAGES],
}

/// A request to the recorder: record the camera's frames raw as well (`/frames/raw`, bit-exact,
/// beside the compressed `/frames`) for a window of capture time starting at the next frame
/// (`hubtrack raw-window`). A request while a window is open extends it.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::RawWindowRequest")]
pub struct RawWindowRequest {
    /// Length of the window, seconds of capture time (0: the recorder's `recorder.raw_window_s`).
    pub seconds: f64,
    /// When the request was sent (monotonic ns).
    pub publish_ns: u64,
}

/// The simulator's clock (published by the `sim` stage only).
///
/// In a simulated flight the pipeline clock — the clock of every `capture_ns` — is simulated
/// time, which in lockstep runs faster or slower than the wall clock. Stages that stamp inputs
/// arriving from outside iceoryx2 (control stamps MAVLink messages) read this clock instead of
/// `CLOCK_MONOTONIC` when `control.clock = "sim"`, so that every time stamp in a simulated run
/// is on one clock (as ROS's `use_sim_time`).
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
#[type_name("hubtrack::SimClock")]
pub struct SimClock {
    /// Simulated time on the pipeline clock (sim start's `CLOCK_MONOTONIC` + simulated ns).
    pub now_ns: u64,
    /// Physics steps since the simulation started.
    pub step: u64,
    /// Wall-clock `CLOCK_MONOTONIC` when this was published.
    pub publish_ns: u64,
}
