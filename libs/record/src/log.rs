//! The stages' log lines as `foxglove.Log` (protobuf) on `/log`, so a viewer's log panel shows
//! what each stage said (a task change, a warning) at the moment it said it, beside the video.

use crate::raw_image::{field, timestamp, timestamp_file};
use hubtrack_types::LogLine;
use prost::Message;
use prost_types::field_descriptor_proto::Type;
use prost_types::{
    DescriptorProto, EnumDescriptorProto, EnumValueDescriptorProto, FileDescriptorProto,
    FileDescriptorSet,
};

/// Schema name of the log channel.
pub const SCHEMA_NAME: &str = "foxglove.Log";

/// MCAP topic of the stages' log lines.
pub const LOG_TOPIC: &str = "/log";

/// A `foxglove.Log` (field numbers of foxglove/Log.proto).
#[derive(Clone, PartialEq, prost::Message)]
pub struct Log {
    /// When the line was logged.
    #[prost(message, optional, tag = "1")]
    pub timestamp: Option<prost_types::Timestamp>,
    /// `foxglove.Log.Level`: 1 debug, 2 info, 3 warning, 4 error, 5 fatal.
    #[prost(int32, tag = "2")]
    pub level: i32,
    /// The line.
    #[prost(string, tag = "3")]
    pub message: String,
    /// Who logged it: the stage.
    #[prost(string, tag = "4")]
    pub name: String,
    /// Source file of the log call.
    #[prost(string, tag = "5")]
    pub file: String,
    /// Source line of the log call.
    #[prost(fixed32, tag = "6")]
    pub line: u32,
}

/// The values of `foxglove.Log.Level`, as foxglove/Log.proto names them.
const LEVELS: [(&str, i32); 6] = [
    ("UNKNOWN", 0),
    ("DEBUG", 1),
    ("INFO", 2),
    ("WARNING", 3),
    ("ERROR", 4),
    ("FATAL", 5),
];

/// The `foxglove.Log` of a stage's line.
pub fn to_message(line: &LogLine) -> Log {
    Log {
        timestamp: Some(timestamp(line.realtime_ns)),
        level: line.level as i32,
        message: line.text.as_str().to_owned(),
        name: line.stage.as_str().to_owned(),
        file: line.file.as_str().to_owned(),
        line: line.line,
    }
}

/// The serialized `FileDescriptorSet` of `foxglove.Log` (with its nested `Level` enum) and
/// `google.protobuf.Timestamp`: the MCAP schema data for encoding `protobuf`.
pub fn descriptor_set() -> Vec<u8> {
    let level = EnumDescriptorProto {
        name: Some("Level".into()),
        value: LEVELS
            .iter()
            .map(|&(name, number)| EnumValueDescriptorProto {
                name: Some(name.into()),
                number: Some(number),
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    };
    let log = DescriptorProto {
        name: Some("Log".into()),
        field: vec![
            field(
                "timestamp",
                1,
                Type::Message,
                Some(".google.protobuf.Timestamp"),
            ),
            field("level", 2, Type::Enum, Some(".foxglove.Log.Level")),
            field("message", 3, Type::String, None),
            field("name", 4, Type::String, None),
            field("file", 5, Type::String, None),
            field("line", 6, Type::Fixed32, None),
        ],
        enum_type: vec![level],
        ..Default::default()
    };
    let file = FileDescriptorProto {
        name: Some("foxglove/Log.proto".into()),
        package: Some("foxglove".into()),
        dependency: vec!["google/protobuf/timestamp.proto".into()],
        message_type: vec![log],
        syntax: Some("proto3".into()),
        ..Default::default()
    };
    FileDescriptorSet {
        file: vec![timestamp_file(), file],
    }
    .encode_to_vec()
}

/// The log lines of a recording, in file order, and why reading stopped early if it did (a cut
/// or damaged file is read as far as it goes). Lines that do not decode are counted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Lines {
    /// The lines.
    pub lines: Vec<Log>,
    /// `/log` messages that did not decode as `foxglove.Log`.
    pub undecodable: u64,
    /// Why reading stopped before the end of the file.
    pub stopped: Option<String>,
}

/// Reads the `/log` lines of the recording `path`.
pub fn read(path: &std::path::Path) -> Result<Lines, crate::reader::OpenError> {
    let mut messages = crate::reader::messages(path)?;
    let mut out = Lines::default();
    for m in messages.by_ref() {
        if m.channel.topic != LOG_TOPIC {
            continue;
        }
        match Log::decode(&m.data[..]) {
            Ok(line) => out.lines.push(line),
            Err(_) => out.undecodable += 1,
        }
    }
    out.stopped = messages.stopped;
    Ok(out)
}

/// The name of a `foxglove.Log.Level` value (`LEVELS`), `UNKNOWN` for one it does not define.
pub fn level_name(level: i32) -> &'static str {
    LEVELS
        .iter()
        .find(|(_, n)| *n == level)
        .map_or("UNKNOWN", |(name, _)| name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use hubtrack_types::{LogLevel, Text512, Text64};

    #[test]
    fn a_line_becomes_a_log_message_that_decodes_back() {
        let line = LogLine {
            realtime_ns: 1_700_000_000_123_456_789,
            level: LogLevel::Warning,
            line: 42,
            stage: Text64::new("control"),
            file: Text64::new("processes/control/src/setpoint.rs"),
            text: Text512::new("done with the turbine heading in doubt"),
        };
        let bytes = to_message(&line).encode_to_vec();
        let back = Log::decode(bytes.as_slice()).unwrap();
        assert_eq!(back.level, 3);
        assert_eq!(back.name, "control");
        assert_eq!(back.line, 42);
        assert_eq!(back.message, "done with the turbine heading in doubt");
        let t = back.timestamp.unwrap();
        assert_eq!((t.seconds, t.nanos), (1_700_000_000, 123_456_789));
    }

    #[test]
    fn the_schema_names_the_level_enum_for_the_level_field() {
        let set = FileDescriptorSet::decode(descriptor_set().as_slice()).unwrap();
        let log = &set.file[1].message_type[0];
        let level = log.field.iter().find(|f| f.name() == "level").unwrap();
        assert_eq!(level.type_name(), ".foxglove.Log.Level");
        assert_eq!(log.enum_type[0].value.len(), 6);
        assert_eq!((level_name(3), level_name(9)), ("WARNING", "UNKNOWN"));
    }
}
