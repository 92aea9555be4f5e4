//! Service names and quality of service, defined once for every process.
//!
//! Each publish-subscribe service has a companion event service (`<name>/event`) on which the
//! publisher notifies after each sample, so subscribers sleep in the kernel instead of polling.

/// Quality of service of one publish-subscribe service. Every process opens a service with the
/// same values (iceoryx2 refuses to open a service with incompatible settings).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Qos {
    /// Samples a late-joining subscriber receives on connect.
    pub history_size: usize,
    /// Largest receive buffer a subscriber may request.
    pub subscriber_max_buffer_size: usize,
    /// Samples one subscriber may hold at once.
    pub subscriber_max_borrowed_samples: usize,
    /// Subscribers at once (stages, recorder, tools such as `hubtrack status`).
    pub max_subscribers: usize,
    /// Publishers at once (a live stage and a replay may both exist).
    pub max_publishers: usize,
    /// Nodes at once.
    pub max_nodes: usize,
    /// When a subscriber's buffer is full, overwrite its oldest sample instead of blocking the
    /// publisher: the camera never waits (design rule 1).
    pub safe_overflow: bool,
}

/// One publish-subscribe service: its name and QoS.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ServiceSpec {
    /// Human-readable channel name, also the MCAP topic (with a leading `/`).
    pub channel: &'static str,
    /// iceoryx2 service name.
    pub name: &'static str,
    /// iceoryx2 service name of the companion event service.
    pub event_name: &'static str,
    /// Quality of service.
    pub qos: Qos,
}

const RESULT_QOS: Qos = Qos {
    history_size: 1,
    subscriber_max_buffer_size: 64,
    subscriber_max_borrowed_samples: 4,
    max_subscribers: 8,
    max_publishers: 4,
    max_nodes: 24,
    safe_overflow: true,
};

/// Camera frames: `[u8]` pixels with a [`crate::FrameHeader`] user header.
///
/// Every subscriber buffer holds whole frames in shared memory, so the frame QoS is small: the
/// detector keeps 1 (newest); the recorder, which encodes each frame straight from shared memory
/// at a low priority, up to `subscriber_max_buffer_size` (267 ms at 30 fps: what it may fall
/// behind in a stall of the machine without losing a frame). The camera's pool holds
/// `max_subscribers × (buffer + borrowed) + 2` frames: 52, 322 MB of shared memory at 1920x1080.
/// The subscribers: detect, recorder, live view, one tool (`hubtrack tap`), one spare
/// for a stage restarting before its dead predecessor is cleaned up.
pub const FRAMES: ServiceSpec = ServiceSpec {
    channel: "frames",
    name: "hubtrack/frames",
    event_name: "hubtrack/frames/event",
    qos: Qos {
        history_size: 0,
        subscriber_max_buffer_size: 8,
        subscriber_max_borrowed_samples: 2,
        max_subscribers: 5,
        max_publishers: 2,
        max_nodes: 24,
        safe_overflow: true,
    },
};

/// [`crate::Detection`] per processed frame.
pub const DETECTIONS: ServiceSpec = ServiceSpec {
    channel: "detections",
    name: "hubtrack/detections",
    event_name: "hubtrack/detections/event",
    qos: RESULT_QOS,
};

/// [`crate::DetectOverlay`]: what the detector saw, for the recorder.
pub const OVERLAY: ServiceSpec = ServiceSpec {
    channel: "overlay",
    name: "hubtrack/overlay",
    event_name: "hubtrack/overlay/event",
    qos: Qos {
        history_size: 0,
        subscriber_max_buffer_size: 16,
        subscriber_max_borrowed_samples: 2,
        max_subscribers: 4,
        max_publishers: 2,
        max_nodes: 24,
        safe_overflow: true,
    },
};

/// [`crate::TrackState`] per detection (and predictions).
pub const TRACK: ServiceSpec = ServiceSpec {
    channel: "track",
    name: "hubtrack/track",
    event_name: "hubtrack/track/event",
    qos: RESULT_QOS,
};

/// [`crate::Setpoint`] from control.
pub const SETPOINTS: ServiceSpec = ServiceSpec {
    channel: "setpoints",
    name: "hubtrack/setpoints",
    event_name: "hubtrack/setpoints/event",
    qos: RESULT_QOS,
};

/// [`crate::VehicleState`] from the autopilot link (control, sim or replay).
pub const VEHICLE: ServiceSpec = ServiceSpec {
    channel: "vehicle",
    name: "hubtrack/vehicle",
    event_name: "hubtrack/vehicle/event",
    qos: RESULT_QOS,
};

/// [`crate::StageStatus`] heartbeats of every stage (many publishers).
pub const STATUS: ServiceSpec = ServiceSpec {
    channel: "status",
    name: "hubtrack/status",
    event_name: "hubtrack/status/event",
    qos: Qos {
        history_size: 0,
        subscriber_max_buffer_size: 64,
        subscriber_max_borrowed_samples: 4,
        max_subscribers: 8,
        max_publishers: 16,
        max_nodes: 24,
        safe_overflow: true,
    },
};

/// [`crate::SupervisorStatus`] from `hubtrack run`, read by `hubtrack status`.
pub const SUPERVISOR: ServiceSpec = ServiceSpec {
    channel: "supervisor",
    name: "hubtrack/supervisor",
    event_name: "hubtrack/supervisor/event",
    qos: Qos {
        history_size: 1,
        subscriber_max_buffer_size: 4,
        subscriber_max_borrowed_samples: 2,
        max_subscribers: 8,
        max_publishers: 2,
        max_nodes: 24,
        safe_overflow: true,
    },
};

/// [`crate::SimClock`]: simulated time, published by the `sim` stage before everything it sends
/// for that instant (history 1: a late subscriber gets the current time at once).
pub const CLOCK: ServiceSpec = ServiceSpec {
    channel: "clock",
    name: "hubtrack/clock",
    event_name: "hubtrack/clock/event",
    qos: RESULT_QOS,
};

/// [`crate::RawWindowRequest`]s to the recorder (`hubtrack raw-window`). No history: a
/// recorder started later must not act on an old request.
pub const RAW_WINDOW: ServiceSpec = ServiceSpec {
    channel: "recorder/raw_window",
    name: "hubtrack/recorder/raw_window",
    event_name: "hubtrack/recorder/raw_window/event",
    qos: Qos {
        history_size: 0,
        subscriber_max_buffer_size: 4,
        subscriber_max_borrowed_samples: 2,
        max_subscribers: 4,
        max_publishers: 4,
        max_nodes: 24,
        safe_overflow: true,
    },
};

/// [`crate::LogLine`]s of every stage (many publishers), recorded on `/log`. A history of a
/// few dozen lines: a recorder started after a stage still records how that stage started.
pub const LOG: ServiceSpec = ServiceSpec {
    channel: "log",
    name: "hubtrack/log",
    event_name: "hubtrack/log/event",
    qos: Qos {
        history_size: 32,
        subscriber_max_buffer_size: 256,
        subscriber_max_borrowed_samples: 4,
        max_subscribers: 8,
        max_publishers: 16,
        max_nodes: 24,
        safe_overflow: true,
    },
};

/// All fixed-size result services, in pipeline order (frames excluded).
pub const RESULT_SERVICES: [ServiceSpec; 5] = [DETECTIONS, TRACK, SETPOINTS, VEHICLE, STATUS];
