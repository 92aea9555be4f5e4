//! Reading a recording's inputs for replay: what drives the first replayed stage, which of them
//! the live stage took, and the order it took them in relative to the vehicle states.
//!
//! The recorder does not write messages in publish order: each turn of its loop drains the
//! frames, then every result service in a fixed order, so a vehicle state published just before
//! a track state can land after it in the file. Replay restores the order the live stage saw:
//! an input that drives a stage (a frame, detection or track state) is keyed by when the live
//! stage received it (the `recv_ns` of its recorded output), a vehicle state by when it was
//! published, and the two streams are merged by key within a bounded look-ahead.

use hubtrack_record::frame_payload::{self, FrameCoding};
use hubtrack_record::writer::{ChannelKind, FRAMES_TOPIC, RAW_FRAMES_TOPIC};
use hubtrack_types::{Detection, FrameHeader, Stamps, TrackState, VehicleState};
use std::collections::{BTreeMap, VecDeque};
use std::path::Path;

/// How much later than another message one published before it can stand in the file: the
/// recorder drains every service once per loop turn (a few ms; 5 ms wait plus frame copies), so
/// this is a generous bound on one turn on a loaded machine.
const REORDER_MARGIN_NS: u64 = 200_000_000;
/// Driving inputs held back waiting for a later vehicle state, at most (8 frames at 1920x1080
/// are 50 MB). Beyond it the oldest goes out anyway: only possible when the stamps of the file
/// do not follow one clock (e.g. a replay of a replay), where no order can be restored.
const MAX_HELD_DRIVERS: usize = 8;
/// Image messages of one frame (its JPEG and a raw copy) waiting for its header, at most.
const MAX_PENDING_IMAGES: usize = 4;
/// Vehicle states held back waiting for the next driving input, at most (small messages).
const MAX_HELD_VEHICLES: usize = 4096;

/// The first replayed stage: replay publishes its recorded inputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstStage {
    /// Frames in.
    Detect,
    /// Detections in.
    Track,
    /// Track states in.
    Control,
}

impl FirstStage {
    /// The stage name.
    pub fn name(self) -> &'static str {
        match self {
            FirstStage::Detect => "detect",
            FirstStage::Track => "track",
            FirstStage::Control => "control",
        }
    }

    /// What drives it, for messages.
    pub fn drivers(self) -> &'static str {
        match self {
            FirstStage::Detect => "frames",
            FirstStage::Track => "detections",
            FirstStage::Control => "track states",
        }
    }

    /// The channel of its outputs.
    pub fn output(self) -> ChannelKind {
        match self {
            FirstStage::Detect => ChannelKind::Detection,
            FirstStage::Track => ChannelKind::Track,
            FirstStage::Control => ChannelKind::Setpoint,
        }
    }

    fn driver_channel(self) -> ChannelKind {
        match self {
            FirstStage::Detect => ChannelKind::FrameHeader,
            FirstStage::Track => ChannelKind::Detection,
            FirstStage::Control => ChannelKind::Track,
        }
    }
}

/// One recorded input.
pub enum Input {
    /// A frame: header and pixels.
    Frame(FrameHeader, Vec<u8>),
    /// A detection.
    Detection(Detection),
    /// A track state.
    Track(TrackState),
    /// A vehicle state.
    Vehicle(VehicleState),
}

impl Input {
    /// The frame seq of an input that drives a stage; `None` for a vehicle state.
    pub fn driver_seq(&self) -> Option<u64> {
        match self {
            Input::Frame(h, _) => Some(h.seq),
            Input::Detection(d) => Some(d.stamps.seq),
            Input::Track(t) => Some(t.stamps.seq),
            Input::Vehicle(_) => None,
        }
    }

    /// When it was published live (monotonic ns).
    pub fn publish_ns(&self) -> u64 {
        match self {
            Input::Frame(h, _) => h.publish_ns,
            Input::Detection(d) => d.stamps.publish_ns,
            Input::Track(t) => t.stamps.publish_ns,
            Input::Vehicle(v) => v.publish_ns,
        }
    }
}

/// What a first pass over the recording found.
#[derive(Debug, Default)]
pub struct Survey {
    /// Per seq the live first stage produced an output for: when it received that input
    /// (`recv_ns` of its first output for the seq).
    pub taken: BTreeMap<u64, u64>,
    /// Messages that drive the first stage (for frames: frame headers).
    pub drivers: u64,
    /// Readable vehicle states.
    pub vehicles: u64,
    /// Messages per topic.
    pub topics: BTreeMap<String, u64>,
    /// Why reading stopped early, if it did.
    pub stopped: Option<String>,
    /// The size of the first frame, when frames drive the first stage.
    pub frame_size: Option<(u32, u32)>,
}

/// Only the stamps of a result message.
#[derive(serde::Deserialize)]
struct StampsOnly {
    stamps: Stamps,
}

/// Reads `path` once (as far as it is intact) for what replay into `first` needs to know.
pub fn survey(path: &Path, first: FirstStage) -> anyhow::Result<Survey> {
    let mut messages = hubtrack_record::reader::messages(path)?;
    let mut s = Survey::default();
    for m in messages.by_ref() {
        let topic = m.channel.topic.as_str();
        *s.topics.entry(topic.to_string()).or_insert(0) += 1;
        let kind = ChannelKind::from_topic(topic);
        if kind == Some(first.driver_channel()) {
            s.drivers += 1;
            if kind == Some(ChannelKind::FrameHeader) && s.frame_size.is_none() {
                s.frame_size = serde_json::from_slice::<FrameHeader>(&m.data)
                    .ok()
                    .map(|h| (h.width, h.height));
            }
        }
        if kind == Some(first.output()) {
            if let Ok(o) = serde_json::from_slice::<StampsOnly>(&m.data) {
                // The first output per seq is the one computed from the input (live control
                // publishes a second, silent one under the same seq when its input goes stale).
                s.taken.entry(o.stamps.seq).or_insert(o.stamps.recv_ns);
            }
        }
        if kind == Some(ChannelKind::Vehicle)
            && serde_json::from_slice::<VehicleState>(&m.data).is_ok()
        {
            s.vehicles += 1;
        }
    }
    s.stopped = messages.stopped;
    Ok(s)
}

/// The inputs of the first replayed stage and the vehicle states, streamed in file order.
pub struct Reader {
    reader: hubtrack_record::reader::Messages,
    first: FirstStage,
    /// The image messages read since the last frame header: (MCAP sequence, coding, message).
    pending_images: Vec<(u32, FrameCoding, Vec<u8>)>,
    /// Decodes the images (video frames in file order).
    images: frame_payload::FrameDecoder,
    /// Why the file ended early, if it did.
    pub stopped: Option<String>,
    /// Messages that could not be decoded.
    pub undecodable: u64,
    /// Frames fed from a lossy (JPEG) image: detect's results then differ from the live run's.
    pub frames_lossy: u64,
    /// Frames whose image did not decode (corrupt or truncated), skipped.
    pub frames_bad: u64,
}

impl Reader {
    /// Opens `path` for replay into `first`.
    pub fn open(path: &Path, first: FirstStage) -> anyhow::Result<Reader> {
        Ok(Reader {
            reader: hubtrack_record::reader::messages(path)?,
            first,
            pending_images: Vec::new(),
            images: frame_payload::FrameDecoder::default(),
            stopped: None,
            undecodable: 0,
            frames_lossy: 0,
            frames_bad: 0,
        })
    }

    fn decode<T: serde::de::DeserializeOwned>(&mut self, data: &[u8]) -> Option<T> {
        let v = serde_json::from_slice(data).ok();
        if v.is_none() {
            self.undecodable += 1;
        }
        v
    }

    /// The pixels of frame `h` from the images read before its header: the raw one if there is
    /// one (bit-exact), else the decoded JPEG or H.264 frame; `None` (counted) if none is usable.
    /// A video frame is always decoded, raw copy or not: the next video frames need it.
    fn frame_pixels(&mut self, h: &FrameHeader) -> Option<Vec<u8>> {
        let mut images = std::mem::take(&mut self.pending_images);
        images.retain(|(seq, _, _)| *seq == h.seq as u32);
        images.sort_by_key(|(_, coding, _)| *coding != FrameCoding::Raw);
        let mut failure = None;
        let mut found = None;
        for (_, coding, data) in &images {
            if found.is_some() && *coding != FrameCoding::Video {
                continue;
            }
            match self.images.pixels(*coding, data, h) {
                Ok(px) => {
                    if found.is_none() {
                        found = Some((px, *coding != FrameCoding::Raw));
                    }
                }
                Err(e) => failure = Some(e),
            }
        }
        if let Some((px, lossy)) = found {
            if lossy {
                self.frames_lossy += 1;
            }
            return Some(px);
        }
        match failure {
            Some(e) => {
                self.frames_bad += 1;
                log::warn!("frame {} skipped: {e}", h.seq);
            }
            None => self.undecodable += 1,
        }
        None
    }
}

impl Iterator for Reader {
    type Item = Input;
    fn next(&mut self) -> Option<Input> {
        loop {
            let Some(m) = self.reader.next() else {
                self.stopped = self.reader.stopped.clone();
                return None;
            };
            let topic = m.channel.topic.as_str();
            let frames = self.first == FirstStage::Detect;
            match (topic, ChannelKind::from_topic(topic), self.first) {
                (FRAMES_TOPIC | RAW_FRAMES_TOPIC, _, _) if frames => {
                    let coding = m
                        .channel
                        .schema
                        .as_ref()
                        .and_then(|s| FrameCoding::of_schema(&s.name));
                    match coding {
                        // Decoded when its header arrives, and only the one image used.
                        Some(c) => {
                            // Images without a header (a damaged file) must not pile up.
                            if self.pending_images.len() >= MAX_PENDING_IMAGES {
                                self.pending_images.remove(0);
                                self.undecodable += 1;
                            }
                            self.pending_images
                                .push((m.sequence, c, m.data.into_owned()));
                        }
                        None => self.undecodable += 1,
                    }
                }
                (_, Some(ChannelKind::FrameHeader), FirstStage::Detect) => {
                    let Some(h) = self.decode::<FrameHeader>(&m.data) else {
                        continue;
                    };
                    // The recorder writes each frame's images right before its header.
                    if let Some(pixels) = self.frame_pixels(&h) {
                        return Some(Input::Frame(h, pixels));
                    }
                }
                (_, Some(ChannelKind::Detection), FirstStage::Track) => {
                    if let Some(d) = self.decode(&m.data) {
                        return Some(Input::Detection(d));
                    }
                }
                (_, Some(ChannelKind::Track), FirstStage::Control) => {
                    if let Some(t) = self.decode(&m.data) {
                        return Some(Input::Track(t));
                    }
                }
                (_, Some(ChannelKind::Vehicle), _) => {
                    if let Some(v) = self.decode(&m.data) {
                        return Some(Input::Vehicle(v));
                    }
                }
                _ => {}
            }
        }
    }
}

/// An input with its place in the replay order.
pub struct Keyed {
    /// Order key (monotonic ns): when the live stage took a driving input, when a vehicle
    /// state was published.
    pub key: u64,
    /// The input.
    pub input: Input,
}

/// Merges driving inputs and vehicle states read in file order into the order of their keys.
///
/// Each stream is in order by itself (kept so: a key never goes below its predecessor's). An
/// input is released once nothing unread can come before it: the other stream already holds a
/// later key, the file holds no more vehicle states, or the newest publish stamp read is more
/// than [`REORDER_MARGIN_NS`] past its key.
pub struct Ordered<I: Iterator<Item = Keyed>> {
    source: I,
    drivers: VecDeque<Keyed>,
    vehicles: VecDeque<Keyed>,
    vehicles_unread: u64,
    frontier_ns: u64,
    last_driver_key: u64,
    last_vehicle_key: u64,
    exhausted: bool,
}

impl<I: Iterator<Item = Keyed>> Ordered<I> {
    /// Orders `source`, whose file holds `vehicles` vehicle states ([`Survey::vehicles`]).
    pub fn new(source: I, vehicles: u64) -> Self {
        Ordered {
            source,
            drivers: VecDeque::new(),
            vehicles: VecDeque::new(),
            vehicles_unread: vehicles,
            frontier_ns: 0,
            last_driver_key: 0,
            last_vehicle_key: 0,
            exhausted: false,
        }
    }

    fn push(&mut self, mut k: Keyed) {
        self.frontier_ns = self.frontier_ns.max(k.input.publish_ns());
        if matches!(k.input, Input::Vehicle(_)) {
            self.vehicles_unread = self.vehicles_unread.saturating_sub(1);
            k.key = k.key.max(self.last_vehicle_key);
            self.last_vehicle_key = k.key;
            self.vehicles.push_back(k);
        } else {
            k.key = k.key.max(self.last_driver_key);
            self.last_driver_key = k.key;
            self.drivers.push_back(k);
        }
    }

    fn pop_ready(&mut self) -> Option<Keyed> {
        // Nothing unread has a key below this: keys are never before publication, and nothing
        // unread was published more than the margin before the newest publish stamp read.
        let settled = if self.exhausted {
            u64::MAX
        } else {
            self.frontier_ns.saturating_sub(REORDER_MARGIN_NS)
        };
        let d = self.drivers.front().map(|k| k.key);
        let v = self.vehicles.front().map(|k| k.key);
        let from_drivers = match (d, v) {
            // Ties go to the vehicle state: it was there when the stage took the input.
            (Some(d), Some(v)) => d < v,
            (Some(d), None)
                if self.vehicles_unread == 0
                    || d < settled
                    || self.drivers.len() > MAX_HELD_DRIVERS =>
            {
                true
            }
            (None, Some(v)) if v < settled || self.vehicles.len() > MAX_HELD_VEHICLES => false,
            _ => return None,
        };
        if from_drivers {
            self.drivers.pop_front()
        } else {
            self.vehicles.pop_front()
        }
    }
}

impl<I: Iterator<Item = Keyed>> Iterator for Ordered<I> {
    type Item = Keyed;
    fn next(&mut self) -> Option<Keyed> {
        loop {
            if let Some(k) = self.pop_ready() {
                return Some(k);
            }
            if self.exhausted {
                return None;
            }
            match self.source.next() {
                Some(k) => self.push(k),
                None => self.exhausted = true,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    fn track(seq: u64, publish_ms: u64) -> Input {
        Input::Track(TrackState {
            stamps: Stamps {
                seq,
                capture_ns: 1,
                recv_ns: 1,
                publish_ns: publish_ms * MS,
            },
            ..Default::default()
        })
    }

    fn vehicle(publish_ms: u64) -> Input {
        Input::Vehicle(VehicleState {
            publish_ns: publish_ms * MS,
            ..Default::default()
        })
    }

    /// Keys: a track state by when the live stage took it (`taken_ms`), a vehicle by its publish time.
    fn order(file: Vec<(Input, u64)>) -> Vec<String> {
        let vehicles = file
            .iter()
            .filter(|(i, _)| matches!(i, Input::Vehicle(_)))
            .count() as u64;
        let keyed = file.into_iter().map(|(input, taken_ms)| Keyed {
            key: if input.driver_seq().is_some() {
                taken_ms * MS
            } else {
                input.publish_ns()
            },
            input,
        });
        Ordered::new(keyed, vehicles)
            .map(|k| match k.input {
                Input::Vehicle(v) => format!("v{}", v.publish_ns / MS),
                i => format!("t{}", i.driver_seq().unwrap()),
            })
            .collect()
    }

    #[test]
    fn vehicle_states_written_after_a_track_state_but_published_before_it_was_taken_go_first() {
        // The recorder's turn wrote track 1 before vehicle 12 although control took track 1
        // at 13 ms, after vehicle 12 was published.
        let file = vec![
            (vehicle(5), 0),
            (track(1, 11), 13),
            (vehicle(12), 0),
            (vehicle(20), 0),
            (track(2, 44), 45),
            (vehicle(46), 0),
        ];
        assert_eq!(order(file), ["v5", "v12", "t1", "v20", "t2", "v46"]);
    }

    #[test]
    fn without_vehicle_states_inputs_go_in_file_order_at_once() {
        let file = vec![(track(1, 10), 11), (track(2, 20), 21)];
        let mut it = Ordered::new(
            file.into_iter()
                .map(|(input, t)| Keyed { key: t * MS, input }),
            0,
        );
        // Released before the source is exhausted: nothing is held back needlessly.
        assert_eq!(it.next().and_then(|k| k.input.driver_seq()), Some(1));
        assert_eq!(it.next().and_then(|k| k.input.driver_seq()), Some(2));
        assert!(it.next().is_none());
    }

    #[test]
    fn a_driver_waits_for_the_margin_only_while_vehicle_states_are_unread() {
        // Vehicle states stop after 10 ms (the link went quiet) but one more is at the file's end.
        let mut file = vec![(vehicle(10), 0)];
        file.extend((1..=20).map(|i| (track(i, 20 + i * 33), 21 + i * 33)));
        file.push((vehicle(700), 0));
        let got = order(file);
        assert_eq!(got.len(), 22);
        assert_eq!(got[0], "v10");
        assert_eq!(got[21], "v700");
        assert!(
            got[1..21]
                .iter()
                .enumerate()
                .all(|(i, s)| *s == format!("t{}", i + 1)),
            "{got:?}"
        );
    }

    #[test]
    fn keys_that_run_backwards_keep_file_order_within_a_stream() {
        let file = vec![
            (track(1, 10), 30),
            (track(2, 20), 25),
            (vehicle(26), 0),
            (vehicle(24), 0),
        ];
        assert_eq!(order(file), ["v26", "v24", "t1", "t2"]);
    }
}
