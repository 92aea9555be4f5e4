//! `foxglove.CompressedImage` as protobuf: the schema and the message (JPEG frames on `/frames`).
//! The JPEG bytes already sit in their own buffer, so prost encodes the message with one copy.

use crate::raw_image::{foxglove_descriptor_set, timestamp};
use prost::Message;
use prost_types::field_descriptor_proto::Type;

/// Schema name of the compressed frames channel.
pub const SCHEMA_NAME: &str = "foxglove.CompressedImage";

/// A `foxglove.CompressedImage` (field numbers of foxglove/CompressedImage.proto).
#[derive(Clone, PartialEq, prost::Message)]
pub struct CompressedImage {
    /// Capture time.
    #[prost(message, optional, tag = "1")]
    pub timestamp: Option<prost_types::Timestamp>,
    /// Frame id.
    #[prost(string, tag = "4")]
    pub frame_id: String,
    /// The compressed image.
    #[prost(bytes = "vec", tag = "2")]
    pub data: Vec<u8>,
    /// `jpeg`, `png`, `webp` or `avif`.
    #[prost(string, tag = "3")]
    pub format: String,
}

/// The serialized `FileDescriptorSet` of `foxglove.CompressedImage` and
/// `google.protobuf.Timestamp`.
pub fn descriptor_set() -> Vec<u8> {
    foxglove_descriptor_set(
        "CompressedImage",
        &[
            ("frame_id", 4, Type::String),
            ("data", 2, Type::Bytes),
            ("format", 3, Type::String),
        ],
    )
}

/// Encodes a compressed image into `out` (cleared first).
pub fn encode(timestamp_ns: u64, frame_id: &str, format: &str, data: Vec<u8>, out: &mut Vec<u8>) {
    let msg = CompressedImage {
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
            1_500_000_000,
            "camera",
            "jpeg",
            vec![0xff, 0xd8, 1, 2],
            &mut out,
        );
        let m = CompressedImage::decode(out.as_slice()).unwrap();
        assert_eq!((m.format.as_str(), m.data.len()), ("jpeg", 4));
        assert_eq!(m.timestamp.unwrap().seconds, 1);
        let set = FileDescriptorSet::decode(descriptor_set().as_slice()).unwrap();
        assert_eq!(set.file[1].message_type[0].field.len(), 4);
    }
}
