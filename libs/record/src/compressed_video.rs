//! `foxglove.CompressedVideo` as protobuf: the schema and the message (H.264 frames on
//! `/frames`, one Annex B access unit per message). Field numbers of
//! foxglove/CompressedVideo.proto: timestamp 1, frame_id 2, data 3, format 4.

use crate::raw_image::{foxglove_descriptor_set, timestamp};
use prost::Message;
use prost_types::field_descriptor_proto::Type;

/// Schema name of the video frames channel.
pub const SCHEMA_NAME: &str = "foxglove.CompressedVideo";

/// A `foxglove.CompressedVideo`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct CompressedVideo {
    /// Capture time of the frame.
    #[prost(message, optional, tag = "1")]
    pub timestamp: Option<prost_types::Timestamp>,
    /// Frame id.
    #[prost(string, tag = "2")]
    pub frame_id: String,
    /// One access unit (Annex B for `h264`).
    #[prost(bytes = "vec", tag = "3")]
    pub data: Vec<u8>,
    /// `h264`, `h265`, `vp9` or `av1`.
    #[prost(string, tag = "4")]
    pub format: String,
}

/// The serialized `FileDescriptorSet` of `foxglove.CompressedVideo` and
/// `google.protobuf.Timestamp`.
pub fn descriptor_set() -> Vec<u8> {
    foxglove_descriptor_set(
        "CompressedVideo",
        &[
            ("frame_id", 2, Type::String),
            ("data", 3, Type::Bytes),
            ("format", 4, Type::String),
        ],
    )
}

/// Encodes a video frame into `out` (cleared first).
pub fn encode(timestamp_ns: u64, frame_id: &str, format: &str, data: Vec<u8>, out: &mut Vec<u8>) {
    let msg = CompressedVideo {
        timestamp: Some(timestamp(timestamp_ns)),
        frame_id: frame_id.into(),
        data,
        format: format.into(),
    };
    out.clear();
    msg.encode(out).expect("a Vec grows as needed");
}

#[cfg(test)]
mod tests {
    use super::*;
    use prost_types::FileDescriptorSet;

    #[test]
    fn round_trip_and_descriptor() {
        let mut out = Vec::new();
        encode(
            2_250_000_000,
            "camera",
            "h264",
            vec![0, 0, 0, 1, 0x65],
            &mut out,
        );
        let m = CompressedVideo::decode(out.as_slice()).unwrap();
        assert_eq!((m.format.as_str(), m.data.len()), ("h264", 5));
        assert_eq!(m.timestamp.unwrap().nanos, 250_000_000);
        let set = FileDescriptorSet::decode(descriptor_set().as_slice()).unwrap();
        assert_eq!(set.file[1].message_type[0].field.len(), 4);
    }
}
