//! Reading recordings, also damaged ones.

use crate::RecordError;
use mcap::sans_io::LinearReaderOptions;
use std::io::{BufReader, BufWriter};
use std::path::Path;

/// What [`recover`] salvaged.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecoverReport {
    /// Messages copied into the new file.
    pub messages: u64,
    /// The input ended with its footer and magic (it was finished cleanly).
    pub input_complete: bool,
    /// The error that stopped reading, if any (a truncated file may also just end).
    pub stopped_by: Option<String>,
}

/// The MCAP magic that starts and ends a complete file.
pub const MCAP_MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// True when the file ends with the MCAP magic, i.e. it was finished (not cut by a crash).
pub fn is_finished(path: &Path) -> std::io::Result<bool> {
    use std::io::{Read, Seek, SeekFrom};
    let mut f = std::fs::File::open(path)?;
    if f.metadata()?.len() < 16 {
        return Ok(false);
    }
    f.seek(SeekFrom::End(-8))?;
    let mut tail = [0u8; 8];
    f.read_exact(&mut tail)?;
    Ok(&tail == MCAP_MAGIC)
}

/// Copies every readable message of `input` (e.g. a recording cut short by `kill -9` or a full
/// disk) into a new, complete and indexed `output`. Reading goes through the file linearly without
/// needing its footer and stops at the first record it cannot parse; everything before is kept.
pub fn recover(input: &Path, output: &Path) -> Result<RecoverReport, RecordError> {
    let file = std::fs::File::open(input).map_err(|cause| RecordError::Io {
        path: input.into(),
        cause,
    })?;
    let out_file = std::fs::File::create(output).map_err(|cause| RecordError::Io {
        path: output.into(),
        cause,
    })?;
    let mut out = mcap::Writer::new(BufWriter::new(out_file)).map_err(|e| RecordError::Mcap {
        path: output.into(),
        message: e.to_string(),
    })?;
    let mut messages = 0;
    let mut stopped_by = None;
    let options = LinearReaderOptions::default().with_skip_end_magic(true);
    for message in mcap::io::MessageReader::new_with_options(BufReader::new(file), options) {
        match message {
            Ok(m) => {
                out.write(&m).map_err(|e| RecordError::Mcap {
                    path: output.into(),
                    message: e.to_string(),
                })?;
                messages += 1;
            }
            Err(e) => {
                stopped_by = Some(e.to_string());
                break;
            }
        }
    }
    out.finish().map_err(|e| RecordError::Mcap {
        path: output.into(),
        message: e.to_string(),
    })?;
    let input_complete = is_finished(input).map_err(|cause| RecordError::Io {
        path: input.into(),
        cause,
    })?;
    Ok(RecoverReport {
        messages,
        input_complete,
        stopped_by,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::writer::{ChannelKind, Recording, RecordingOptions};
    use hubtrack_types::FrameHeader;

    fn write_sample(path: &Path, frames: u64) {
        let mut rec = Recording::create(
            path,
            &RecordingOptions {
                compression: None,
                chunk_size: 1024,
                ..RecordingOptions::default()
            },
        )
        .unwrap();
        for seq in 0..frames {
            // Frames large enough that the data section dominates the file, as in real recordings.
            let h = FrameHeader {
                seq,
                width: 100,
                height: 10,
                stride: 300,
                ..Default::default()
            };
            rec.write_frame(&h, Some(&[seq as u8; 3000]), 1000 + seq)
                .unwrap();
            rec.write_json(
                ChannelKind::Recorder,
                seq,
                1000 + seq,
                1000 + seq,
                &crate::writer::RecorderStats::default(),
            )
            .unwrap();
            rec.flush().unwrap();
        }
        rec.finish().unwrap();
    }

    #[test]
    fn truncated_file_recovers_complete_chunks() {
        let dir = tempfile::tempdir().unwrap();
        let full = dir.path().join("full.mcap");
        write_sample(&full, 10);
        let bytes = std::fs::read(&full).unwrap();
        let cut = dir.path().join("cut.mcap");
        std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
        let out = dir.path().join("recovered.mcap");
        let report = recover(&cut, &out).unwrap();
        assert!(!report.input_complete);
        assert!(report.messages < 30, "{report:?}");
        // Each frame is 3 messages (image, header, stats) flushed into its own chunk.
        assert!(
            report.messages >= 9 && report.messages.is_multiple_of(3),
            "{report:?}"
        );
        assert!(report.messages < 30, "{report:?}");
        // The recovered file is complete: the indexed reader accepts it.
        let data = std::fs::read(&out).unwrap();
        let n = mcap::MessageStream::new(&data).unwrap().count();
        assert_eq!(n as u64, report.messages);
        // And the complete file recovers in full.
        let report = recover(&full, &dir.path().join("again.mcap")).unwrap();
        assert_eq!(
            (report.messages, report.input_complete, report.stopped_by),
            (30, true, None)
        );
    }
}

/// What a recording holds, per topic.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FileInfo {
    /// File size, bytes.
    pub size_bytes: u64,
    /// The file was finished cleanly (footer present).
    pub finished: bool,
    /// Message count per topic.
    pub topic_counts: std::collections::BTreeMap<String, u64>,
}

/// Counts the messages of every topic. A finished file is read through its summary; a cut one
/// linearly, as far as it is readable.
pub fn inspect(path: &Path) -> Result<FileInfo, RecordError> {
    let io = |cause| RecordError::Io {
        path: path.into(),
        cause,
    };
    let size_bytes = std::fs::metadata(path).map_err(io)?.len();
    let finished = is_finished(path).map_err(io)?;
    let mut topic_counts = std::collections::BTreeMap::new();
    if finished {
        // Map, don't read: only the summary pages at the end of the file are touched (a flight's
        // recording is many GB).
        let file = std::fs::File::open(path).map_err(io)?;
        // SAFETY: the file is opened read-only; a concurrent writer would only make the summary
        // unreadable, which falls back to the linear count below.
        let data = unsafe { memmap2::Mmap::map(&file) }.map_err(io)?;
        if let Ok(Some(summary)) = mcap::Summary::read(&data) {
            if let Some(stats) = &summary.stats {
                for (id, n) in &stats.channel_message_counts {
                    if let Some(ch) = summary.channels.get(id) {
                        *topic_counts.entry(ch.topic.clone()).or_insert(0) += n;
                    }
                }
                return Ok(FileInfo {
                    size_bytes,
                    finished,
                    topic_counts,
                });
            }
        }
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let options = LinearReaderOptions::default().with_skip_end_magic(true);
    for m in mcap::io::MessageReader::new_with_options(BufReader::new(file), options) {
        match m {
            Ok(m) => *topic_counts.entry(m.channel.topic.clone()).or_insert(0) += 1,
            Err(_) => break,
        }
    }
    Ok(FileInfo {
        size_bytes,
        finished,
        topic_counts,
    })
}
