//! The pipeline's messages of one recording, by frame `seq`: what the analysis tools
//! ([`crate::latency`], [`crate::flight`]) read.

use crate::reader::OpenError;
use crate::writer::ChannelKind;
use crate::RecordError;
use hubtrack_types::{Detection, FrameHeader, Setpoint, Stamps, TrackState, VehicleState};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The stamped messages of a recording, keyed by frame `seq` (the last one wins).
#[derive(Debug, Clone, Default)]
pub struct Channels {
    /// `/frames/header`: stamps and, from the simulator, the truth.
    pub frames: BTreeMap<u64, FrameHeader>,
    /// `/detections`.
    pub detections: BTreeMap<u64, Detection>,
    /// `/track`.
    pub tracks: BTreeMap<u64, TrackState>,
    /// `/setpoints`.
    pub setpoints: BTreeMap<u64, Setpoint>,
    /// `/vehicle`, by `recv_ns` (on the frames' capture clock).
    pub vehicles: Vec<VehicleState>,
    /// The last `/recorder` counters.
    pub recorder: Option<crate::writer::RecorderStats>,
    /// Messages without usable stamps (all zero) or that did not decode, per topic.
    pub unstamped: BTreeMap<String, u64>,
    /// Messages on topics not read here (neither the above nor the images), per topic.
    pub unknown_topics: BTreeMap<String, u64>,
    /// Why reading stopped early, if the file is cut or damaged.
    pub read_error: Option<String>,
    /// Messages read.
    pub messages: u64,
}

/// Why a recording could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// Opening or reading the file failed.
    #[error(transparent)]
    Record(#[from] RecordError),
    /// The file could not be opened, or is not MCAP (empty, or bad magic).
    #[error(transparent)]
    Open(#[from] OpenError),
    /// The file holds no stamped hubtrack message.
    #[error("{path} holds no stamped hubtrack messages ({messages} messages read{detail})")]
    NoStamps {
        /// The file.
        path: PathBuf,
        /// Messages read.
        messages: u64,
        /// More detail.
        detail: String,
    },
}

fn stamped(s: &Stamps) -> bool {
    s.capture_ns > 0 && s.recv_ns > 0 && s.publish_ns > 0
}

/// Reads `path` (complete, cut or damaged: whatever is readable).
pub fn read(path: &Path) -> Result<Channels, ReadError> {
    let mut messages = crate::reader::messages(path)?;
    let mut c = Channels::default();
    for m in messages.by_ref() {
        c.messages += 1;
        let topic = m.channel.topic.as_str();
        let mut unstamped = || *c.unstamped.entry(topic.to_string()).or_insert(0) += 1;
        match ChannelKind::from_topic(topic) {
            Some(ChannelKind::FrameHeader) => {
                match serde_json::from_slice::<FrameHeader>(&m.data) {
                    Ok(h) if h.capture_ns > 0 && h.publish_ns > 0 => {
                        c.frames.insert(h.seq, h);
                    }
                    _ => unstamped(),
                }
            }
            Some(ChannelKind::Detection) => match serde_json::from_slice::<Detection>(&m.data) {
                Ok(d) if stamped(&d.stamps) => {
                    c.detections.insert(d.stamps.seq, d);
                }
                _ => unstamped(),
            },
            Some(ChannelKind::Track) => match serde_json::from_slice::<TrackState>(&m.data) {
                Ok(t) if stamped(&t.stamps) => {
                    c.tracks.insert(t.stamps.seq, t);
                }
                _ => unstamped(),
            },
            Some(ChannelKind::Setpoint) => match serde_json::from_slice::<Setpoint>(&m.data) {
                Ok(s) if stamped(&s.stamps) => {
                    c.setpoints.insert(s.stamps.seq, s);
                }
                _ => unstamped(),
            },
            Some(ChannelKind::Vehicle) => match serde_json::from_slice::<VehicleState>(&m.data) {
                Ok(v) if v.recv_ns > 0 => c.vehicles.push(v),
                _ => unstamped(),
            },
            Some(ChannelKind::Recorder) => {
                if let Ok(r) = serde_json::from_slice(&m.data) {
                    c.recorder = Some(r);
                }
            }
            Some(_) => {}
            // The images (`/frames`, `/frames/raw`), the overlay and the stages' log lines.
            None if topic.starts_with("/frames") || topic == crate::log::LOG_TOPIC => {}
            None => *c.unknown_topics.entry(topic.to_string()).or_insert(0) += 1,
        }
    }
    c.read_error = messages.stopped;
    c.vehicles.sort_by_key(|v| v.recv_ns);
    if c.frames.is_empty()
        && c.detections.is_empty()
        && c.tracks.is_empty()
        && c.setpoints.is_empty()
    {
        let mut detail = String::new();
        if let Some(e) = &c.read_error {
            detail += &format!("; reading stopped: {e}");
        }
        if !c.unstamped.is_empty() {
            detail += &format!("; unstamped: {:?}", c.unstamped);
        }
        if !c.unknown_topics.is_empty() {
            detail += &format!(
                "; unknown topics: {:?}",
                c.unknown_topics.keys().collect::<Vec<_>>()
            );
        }
        return Err(ReadError::NoStamps {
            path: path.into(),
            messages: c.messages,
            detail,
        });
    }
    Ok(c)
}
