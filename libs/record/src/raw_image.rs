//! `foxglove.RawImage` as protobuf: the schema (a `FileDescriptorSet`) and a hand-written encoder
//! that writes the pixels once, straight into the output buffer (prost would need them in a `Vec`
//! first, costing a second copy of every frame).

use prost::Message;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet};

/// Schema name of the frames channel.
pub const SCHEMA_NAME: &str = "foxglove.RawImage";

// Field numbers of foxglove/RawImage.proto and google/protobuf/timestamp.proto.
const F_TIMESTAMP: u32 = 1;
const F_WIDTH: u32 = 2;
const F_HEIGHT: u32 = 3;
const F_ENCODING: u32 = 4;
const F_STEP: u32 = 5;
const F_DATA: u32 = 6;
const F_FRAME_ID: u32 = 7;
const F_SECONDS: u32 = 1;
const F_NANOS: u32 = 2;

const WIRE_VARINT: u32 = 0;
const WIRE_LEN: u32 = 2;
const WIRE_FIXED32: u32 = 5;

pub(crate) fn field(
    name: &str,
    number: i32,
    ty: Type,
    type_name: Option<&str>,
) -> FieldDescriptorProto {
    FieldDescriptorProto {
        name: Some(name.into()),
        number: Some(number),
        label: Some(Label::Optional as i32),
        r#type: Some(ty as i32),
        type_name: type_name.map(Into::into),
        json_name: Some(name.into()),
        ..Default::default()
    }
}

/// `google/protobuf/timestamp.proto`, the dependency of every Foxglove message.
pub(crate) fn timestamp_file() -> FileDescriptorProto {
    FileDescriptorProto {
        name: Some("google/protobuf/timestamp.proto".into()),
        package: Some("google.protobuf".into()),
        message_type: vec![DescriptorProto {
            name: Some("Timestamp".into()),
            field: vec![
                field("seconds", F_SECONDS as i32, Type::Int64, None),
                field("nanos", F_NANOS as i32, Type::Int32, None),
            ],
            ..Default::default()
        }],
        syntax: Some("proto3".into()),
        ..Default::default()
    }
}

/// The serialized `FileDescriptorSet` of `foxglove.<message>`, a `timestamp` (field 1) and the
/// scalar `fields` (name, number, type), with its dependency `google.protobuf.Timestamp`.
pub(crate) fn foxglove_descriptor_set(message: &str, fields: &[(&str, i32, Type)]) -> Vec<u8> {
    let mut all = vec![field(
        "timestamp",
        F_TIMESTAMP as i32,
        Type::Message,
        Some(".google.protobuf.Timestamp"),
    )];
    all.extend(fields.iter().map(|&(name, n, ty)| field(name, n, ty, None)));
    let file = FileDescriptorProto {
        name: Some(format!("foxglove/{message}.proto")),
        package: Some("foxglove".into()),
        dependency: vec!["google/protobuf/timestamp.proto".into()],
        message_type: vec![DescriptorProto {
            name: Some(message.into()),
            field: all,
            ..Default::default()
        }],
        syntax: Some("proto3".into()),
        ..Default::default()
    };
    FileDescriptorSet {
        file: vec![timestamp_file(), file],
    }
    .encode_to_vec()
}

/// A time in nanoseconds as a `google.protobuf.Timestamp`.
pub(crate) fn timestamp(ns: u64) -> prost_types::Timestamp {
    prost_types::Timestamp {
        seconds: (ns / 1_000_000_000) as i64,
        nanos: (ns % 1_000_000_000) as i32,
    }
}

/// The serialized `FileDescriptorSet` of `foxglove.RawImage` and its dependency
/// `google.protobuf.Timestamp`: the MCAP schema data for encoding `protobuf`.
pub fn descriptor_set() -> Vec<u8> {
    let timestamp = timestamp_file();
    let raw_image = FileDescriptorProto {
        name: Some("foxglove/RawImage.proto".into()),
        package: Some("foxglove".into()),
        dependency: vec!["google/protobuf/timestamp.proto".into()],
        message_type: vec![DescriptorProto {
            name: Some("RawImage".into()),
            field: vec![
                field(
                    "timestamp",
                    F_TIMESTAMP as i32,
                    Type::Message,
                    Some(".google.protobuf.Timestamp"),
                ),
                field("frame_id", F_FRAME_ID as i32, Type::String, None),
                field("width", F_WIDTH as i32, Type::Fixed32, None),
                field("height", F_HEIGHT as i32, Type::Fixed32, None),
                field("encoding", F_ENCODING as i32, Type::String, None),
                field("step", F_STEP as i32, Type::Fixed32, None),
                field("data", F_DATA as i32, Type::Bytes, None),
            ],
            ..Default::default()
        }],
        syntax: Some("proto3".into()),
        ..Default::default()
    };
    FileDescriptorSet {
        file: vec![timestamp, raw_image],
    }
    .encode_to_vec()
}

fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn put_key(out: &mut Vec<u8>, field: u32, wire: u32) {
    put_varint(out, u64::from(field << 3 | wire));
}

fn put_fixed32(out: &mut Vec<u8>, field: u32, v: u32) {
    put_key(out, field, WIRE_FIXED32);
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_bytes(out: &mut Vec<u8>, field: u32, bytes: &[u8]) {
    put_key(out, field, WIRE_LEN);
    put_varint(out, bytes.len() as u64);
    out.extend_from_slice(bytes);
}

/// One image's fields apart from the pixels.
#[derive(Debug, Clone, Copy)]
pub struct ImageMeta<'a> {
    /// Capture time, epoch ns.
    pub timestamp_ns: u64,
    /// Frame id (coordinate frame name).
    pub frame_id: &'a str,
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Foxglove encoding name (`bgr8`, `mono8`).
    pub encoding: &'a str,
    /// Bytes per row.
    pub step: u32,
}

/// Encodes a `foxglove.RawImage` into `out` (cleared first), copying `pixels` once.
pub fn encode(meta: &ImageMeta<'_>, pixels: &[u8], out: &mut Vec<u8>) {
    out.clear();
    out.reserve(pixels.len() + 64);
    let mut ts = Vec::with_capacity(16);
    let secs = meta.timestamp_ns / 1_000_000_000;
    let nanos = meta.timestamp_ns % 1_000_000_000;
    if secs != 0 {
        put_key(&mut ts, F_SECONDS, WIRE_VARINT);
        put_varint(&mut ts, secs);
    }
    if nanos != 0 {
        put_key(&mut ts, F_NANOS, WIRE_VARINT);
        put_varint(&mut ts, nanos);
    }
    // Canonical field order (by number), as protobuf encoders write it.
    put_bytes(out, F_TIMESTAMP, &ts);
    put_fixed32(out, F_WIDTH, meta.width);
    put_fixed32(out, F_HEIGHT, meta.height);
    put_bytes(out, F_ENCODING, meta.encoding.as_bytes());
    put_fixed32(out, F_STEP, meta.step);
    put_bytes(out, F_DATA, pixels);
    put_bytes(out, F_FRAME_ID, meta.frame_id.as_bytes());
}

/// A decoded `foxglove.RawImage` (for replay and tests).
#[derive(Clone, PartialEq, prost::Message)]
pub struct RawImage {
    /// Capture time.
    #[prost(message, optional, tag = "1")]
    pub timestamp: Option<prost_types::Timestamp>,
    /// Frame id.
    #[prost(string, tag = "7")]
    pub frame_id: String,
    /// Width, px.
    #[prost(fixed32, tag = "2")]
    pub width: u32,
    /// Height, px.
    #[prost(fixed32, tag = "3")]
    pub height: u32,
    /// Encoding name.
    #[prost(string, tag = "4")]
    pub encoding: String,
    /// Bytes per row.
    #[prost(fixed32, tag = "5")]
    pub step: u32,
    /// Pixels.
    #[prost(bytes = "vec", tag = "6")]
    pub data: Vec<u8>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_encoding_equals_prost() {
        let pixels: Vec<u8> = (0..300u32).map(|i| i as u8).collect();
        let meta = ImageMeta {
            timestamp_ns: 1_763_000_000_123_456_789,
            frame_id: "camera",
            width: 10,
            height: 10,
            encoding: "bgr8",
            step: 30,
        };
        let mut ours = Vec::new();
        encode(&meta, &pixels, &mut ours);
        let decoded = RawImage::decode(ours.as_slice()).unwrap();
        assert_eq!(decoded.width, 10);
        assert_eq!(decoded.step, 30);
        assert_eq!(decoded.encoding, "bgr8");
        assert_eq!(decoded.data, pixels);
        let ts = decoded.timestamp.unwrap();
        assert_eq!((ts.seconds, ts.nanos), (1_763_000_000, 123_456_789));
        assert_eq!(
            decoded.encode_to_vec(),
            ours,
            "byte-identical to prost's encoding"
        );
    }

    #[test]
    fn descriptor_set_decodes() {
        let set = FileDescriptorSet::decode(descriptor_set().as_slice()).unwrap();
        assert_eq!(set.file.len(), 2);
        assert_eq!(set.file[1].message_type[0].field.len(), 7);
    }
}
