//! Reading recordings, also damaged ones: the one bounded path every tool reads through.
//!
//! A damaged or hostile file must cost no more than a good one: [`messages`] checks the magic,
//! caps what any record, chunk or decompressed chunk can claim at [`MAX_RECORD_BYTES`], checks
//! each chunk's CRC before any of its messages is handed out (a bit flip is reported, never passed
//! on as data), and turns every failure into an error that names the file.

use crate::RecordError;
use mcap::sans_io::LinearReaderOptions;
use std::io::{BufReader, BufWriter, Read};
use std::path::{Path, PathBuf};

/// The most a single record, a chunk (compressed) or a chunk's content (decompressed) may
/// declare, bytes. The writer closes a chunk at `recorder.chunk_size_kib` (at most
/// [`crate::config::MAX_CHUNK_SIZE_KIB`]) or with one message that is larger alone; the largest
/// message is a frame (an 8K RGB frame is 100 MB). Anything larger is damage: reading stops with
/// an error instead of allocating what the file claims (up to 2^64 bytes).
pub const MAX_RECORD_BYTES: usize = 256 << 20;

/// Why a recording could not be read at all.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// Opening the file failed.
    #[error(transparent)]
    Record(#[from] RecordError),
    /// The file is empty or does not start with the MCAP magic.
    #[error("{path} is not an MCAP file ({why})")]
    NotMcap {
        /// The file.
        path: PathBuf,
        /// `"empty"`, `"shorter than the magic"` or `"bad magic"`.
        why: &'static str,
    },
}

/// The messages of a recording in file order, as far as it is intact. Iteration ends at the end
/// of the file or at the first damaged record; [`Messages::stopped`] then says why.
pub struct Messages {
    inner: mcap::io::MessageReader<BufReader<Box<dyn Read + Send>>>,
    path: PathBuf,
    /// Why reading stopped before the end of the file (damage, a cut, a limit), if it did.
    pub stopped: Option<String>,
    /// Messages handed out so far.
    pub count: u64,
}

impl Iterator for Messages {
    type Item = mcap::Message<'static>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.stopped.is_some() {
            return None;
        }
        match self.inner.next()? {
            Ok(m) => {
                self.count += 1;
                Some(m)
            }
            Err(e) => {
                self.stopped = Some(format!(
                    "{}: {e} (after {} messages)",
                    self.path.display(),
                    self.count
                ));
                None
            }
        }
    }
}

/// The reader options of every tool: see the module documentation.
pub fn bounded_options() -> LinearReaderOptions {
    LinearReaderOptions::default()
        // A file cut by `kill -9` or a full disk has no end magic; it is read as far as it goes.
        .with_skip_end_magic(true)
        .with_record_length_limit(MAX_RECORD_BYTES)
        // Before any message of a chunk is handed out: a flipped bit never becomes data.
        .with_prevalidate_chunk_crcs(true)
}

/// Opens `path` for reading its messages in file order through the bounded path.
pub fn messages(path: &Path) -> Result<Messages, OpenError> {
    let io = |cause| RecordError::Io {
        path: path.into(),
        cause,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let mut magic = [0u8; 8];
    let why = if len == 0 {
        Some("empty")
    } else if (len as usize) < MCAP_MAGIC.len() {
        Some("shorter than the magic")
    } else {
        file.read_exact(&mut magic).map_err(io)?;
        (&magic != MCAP_MAGIC).then_some("bad magic")
    };
    if let Some(why) = why {
        return Err(OpenError::NotMcap {
            path: path.into(),
            why,
        });
    }
    let file = std::fs::File::open(path).map_err(io)?;
    Ok(messages_from(Box::new(file), path))
}

/// [`messages`] over any byte source, the magic not checked (`name` names it in errors).
pub fn messages_from(source: Box<dyn Read + Send>, name: &Path) -> Messages {
    Messages {
        inner: mcap::io::MessageReader::new_with_options(BufReader::new(source), bounded_options()),
        path: name.into(),
        stopped: None,
        count: 0,
    }
}

/// What [`recover`] salvaged.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecoverReport {
    /// Messages copied into the new file.
    pub messages: u64,
    /// The input was read to its end without damage and was finished cleanly (footer and magic).
    pub input_complete: bool,
    /// Why reading stopped before the end of the input (damage, a cut), if it did.
    pub stopped_by: Option<String>,
    /// What is wrong with the summary section of an input read to its end, if anything: every
    /// message of its data section was copied, but the input was not complete.
    pub summary_damage: Option<String>,
}

/// The MCAP magic that starts and ends a complete file.
pub const MCAP_MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// True when the file ends with the MCAP magic, i.e. it was finished (not cut by a crash).
pub fn is_finished(path: &Path) -> std::io::Result<bool> {
    use std::io::{Seek, SeekFrom};
    let mut f = std::fs::File::open(path)?;
    if f.metadata()?.len() < 16 {
        return Ok(false);
    }
    f.seek(SeekFrom::End(-8))?;
    let mut tail = [0u8; 8];
    f.read_exact(&mut tail)?;
    Ok(&tail == MCAP_MAGIC)
}

/// Copies every intact message of `input` (e.g. a recording cut short by `kill -9` or a full
/// disk) into a new, complete and indexed `output`. Reading goes through the file linearly without
/// needing its footer and stops at the first record it cannot parse or the first chunk whose CRC
/// does not match; everything before is kept. `output` must not exist yet (it is never the input,
/// and nothing is replaced); it is written under a temporary name and renamed when finished.
pub fn recover(input: &Path, output: &Path) -> Result<RecoverReport, OpenError> {
    let mut messages = self::messages(input)?;
    let out_err = |message: String| RecordError::Mcap {
        path: output.into(),
        message,
    };
    let out_io = |cause| RecordError::Io {
        path: output.into(),
        cause,
    };
    let tmp = partial_name(output);
    let out_file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(out_io)?;
    let written = (|| {
        let mut out =
            mcap::Writer::new(BufWriter::new(out_file)).map_err(|e| out_err(e.to_string()))?;
        for m in messages.by_ref() {
            out.write(&m).map_err(|e| out_err(e.to_string()))?;
        }
        out.finish().map_err(|e| out_err(e.to_string()))?;
        // `output` is checked right before the rename: recovery never replaces a file.
        if output.exists() {
            return Err(out_io(std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "already exists",
            )));
        }
        std::fs::rename(&tmp, output).map_err(out_io)
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(e.into());
    }
    let finished = is_finished(input).map_err(|cause| RecordError::Io {
        path: input.into(),
        cause,
    })?;
    // A finished file whose summary is damaged (zeroed, overwritten) was not complete, though
    // every message of its data section was read.
    let summary_damage = (finished && messages.stopped.is_none())
        .then(|| summary_damage(input, messages.count))
        .flatten();
    Ok(RecoverReport {
        messages: messages.count,
        input_complete: finished && messages.stopped.is_none() && summary_damage.is_none(),
        stopped_by: messages.stopped,
        summary_damage,
    })
}

/// `FILE.partial` next to `path`: where a file is written before it is renamed into place.
pub fn partial_name(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::writer::{ChannelKind, Recording, RecordingOptions};
    use hubtrack_types::FrameHeader;

    fn write_sample(path: &Path, frames: u64) {
        write_sample_with(path, frames, None);
    }

    fn write_sample_with(path: &Path, frames: u64, compression: Option<mcap::Compression>) {
        let mut rec = Recording::create(
            path,
            &RecordingOptions {
                compression,
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
        // A finished file whose summary section was zeroed: every message is copied, and the
        // input is not called complete.
        let mut bytes = std::fs::read(&full).unwrap();
        let footer = bytes.len() - 8 - 29;
        let summary_start =
            u64::from_le_bytes(bytes[footer + 9..footer + 17].try_into().unwrap()) as usize;
        assert!(
            summary_start > 0 && summary_start < footer,
            "{summary_start}"
        );
        bytes[summary_start..footer].fill(0);
        let zeroed = dir.path().join("zeroed.mcap");
        std::fs::write(&zeroed, &bytes).unwrap();
        let report = recover(&zeroed, &dir.path().join("from-zeroed.mcap")).unwrap();
        assert_eq!(report.messages, 30, "{report:?}");
        assert!(!report.input_complete, "{report:?}");
        assert!(
            report
                .summary_damage
                .as_deref()
                .is_some_and(|d| d.contains("summary section")),
            "{report:?}"
        );
    }

    /// The MCAP magic, then a record header (opcode, little-endian length) and `body`.
    fn hostile(opcode: u8, len: u64, body: &[u8]) -> Vec<u8> {
        let mut b = MCAP_MAGIC.to_vec();
        b.push(opcode);
        b.extend_from_slice(&len.to_le_bytes());
        b.extend_from_slice(body);
        b
    }

    #[test]
    fn declared_lengths_beyond_the_limit_stop_reading_with_an_error() {
        let dir = tempfile::tempdir().unwrap();
        // Header (0x01), Chunk (0x06), Message (0x05) records claiming 3 GiB, 4 GiB and 2^64-1
        // bytes in a file of ~100 bytes: an error, no allocation of what they claim, no panic.
        for (i, (opcode, len)) in [
            (0x01u8, 3u64 << 30),
            (0x01, 4 << 30),
            (0x06, u64::MAX),
            (0x05, u64::MAX - 8),
            (0x01, u64::MAX),
        ]
        .into_iter()
        .enumerate()
        {
            let path = dir.path().join(format!("hostile{i}.mcap"));
            std::fs::write(&path, hostile(opcode, len, &[0xAB; 90])).unwrap();
            let mut m = messages(&path).unwrap();
            assert_eq!(m.by_ref().count(), 0);
            let why = m.stopped.expect("reading stops with a reason");
            assert!(why.contains("hostile"), "names the file: {why}");
            let e = recover(&path, &dir.path().join(format!("out{i}.mcap"))).unwrap();
            assert_eq!(e.messages, 0);
            assert!(!e.input_complete);
            assert!(e.stopped_by.is_some());
            assert!(crate::channels::read(&path).is_err());
            assert!(inspect(&path).unwrap().topic_counts.is_empty());
        }
    }

    #[test]
    fn empty_and_foreign_files_are_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        for (name, bytes, why) in [
            ("empty.mcap", &b""[..], "empty"),
            ("short.mcap", &b"\x89MC"[..], "shorter than the magic"),
            (
                "text.mcap",
                &b"hello, this is not a recording"[..],
                "bad magic",
            ),
        ] {
            let path = dir.path().join(name);
            std::fs::write(&path, bytes).unwrap();
            let out = dir.path().join(format!("{name}.out"));
            let e = recover(&path, &out).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(why), "{e}");
            assert!(!out.exists() && !partial_name(&out).exists());
        }
    }

    #[test]
    fn a_flipped_bit_in_a_chunk_is_reported_not_laundered() {
        let dir = tempfile::tempdir().unwrap();
        let full = dir.path().join("full.mcap");
        write_sample(&full, 10);
        let mut bytes = std::fs::read(&full).unwrap();
        // Inside the pixels of the 6th frame (the data section is ~10 chunks of ~3 kB).
        let i = bytes
            .windows(64)
            .position(|w| w.iter().all(|b| *b == 5))
            .unwrap();
        bytes[i + 10] ^= 0x10;
        let flipped = dir.path().join("flipped.mcap");
        std::fs::write(&flipped, &bytes).unwrap();
        let out = dir.path().join("out.mcap");
        let report = recover(&flipped, &out).unwrap();
        assert!(!report.input_complete, "{report:?}");
        let why = report.stopped_by.unwrap();
        assert!(why.contains("CRC") || why.contains("crc"), "{why}");
        // The five frames before the damaged chunk are kept, nothing of it or after it.
        assert_eq!(report.messages, 15);
        let data = std::fs::read(&out).unwrap();
        assert!(mcap::MessageStream::new(&data).unwrap().all(|m| m
            .map(|m| !m.data.contains(&5u8) || m.channel.topic != "/frames")
            .unwrap()));
    }

    #[test]
    fn recover_never_replaces_a_file() {
        let dir = tempfile::tempdir().unwrap();
        let full = dir.path().join("full.mcap");
        write_sample(&full, 2);
        let e = recover(&full, &full).unwrap_err().to_string();
        assert!(e.contains("exists"), "{e}");
        assert!(is_finished(&full).unwrap());
        assert_eq!(
            recover(&full, &dir.path().join("b.mcap")).unwrap().messages,
            6
        );
    }

    /// Mutants of real recordings (uncompressed and lz4) through every reading entry: each ends
    /// with messages or an error, never a panic; and memory stays bounded by the limit.
    #[test]
    fn mutated_recordings_never_panic() {
        use hubtrack_types::mutate::{mutate, Rng};
        let dir = tempfile::tempdir().unwrap();
        let mut seeds = Vec::new();
        for (name, c) in [("none", None), ("lz4", Some(mcap::Compression::Lz4))] {
            let path = dir.path().join(format!("{name}.mcap"));
            write_sample_with(&path, 4, c);
            seeds.push(std::fs::read(&path).unwrap());
        }
        let mut rng = Rng::new(45);
        let mut stopped = 0;
        for i in 0..2000 {
            let mut data = seeds[i % seeds.len()].clone();
            mutate(&mut rng, &mut data, 1 << 16);
            let mut m = messages_from(Box::new(std::io::Cursor::new(data)), Path::new("mutant"));
            let _ = m.by_ref().count();
            stopped += usize::from(m.stopped.is_some());
        }
        assert!(stopped > 500, "most mutants are damaged: {stopped}");
        // The path-based entries on a few hundred of them.
        for i in 0..200 {
            let mut data = seeds[i % seeds.len()].clone();
            mutate(&mut rng, &mut data, 1 << 16);
            let path = dir.path().join("mutant.mcap");
            std::fs::write(&path, &data).unwrap();
            let out = dir.path().join(format!("recovered{i}.mcap"));
            let _ = recover(&path, &out);
            let _ = inspect(&path);
            let _ = crate::channels::read(&path);
        }
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

/// The summary section of a finished file (`None` when the file has none), or why it cannot be
/// read. Maps the file instead of reading it: only the summary's pages at its end are touched (a
/// flight's recording is many GB).
fn read_summary(path: &Path) -> Result<Option<mcap::Summary>, String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    // SAFETY: the file is opened read-only; a concurrent writer would only make the summary
    // unreadable, which the callers treat as a damaged summary.
    let data = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| e.to_string())?;
    mcap::Summary::read(&data).map_err(|e| e.to_string())
}

/// Whether a finished file's summary section is intact: it reads, and its statistics count
/// `messages` (those a linear read found).
fn summary_damage(path: &Path, messages: u64) -> Option<String> {
    match read_summary(path) {
        Err(e) => Some(format!("its summary section cannot be read: {e}")),
        Ok(None) => Some("it has no summary section".into()),
        Ok(Some(summary)) => match summary.stats {
            None => Some("its summary section holds no statistics (empty or overwritten)".into()),
            Some(stats) if stats.message_count != messages => Some(format!(
                "its summary section counts {} messages, its data section holds {messages}",
                stats.message_count
            )),
            Some(_) => None,
        },
    }
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
        if let Ok(Some(summary)) = read_summary(path) {
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
    if let Ok(messages) = messages(path) {
        for m in messages {
            *topic_counts.entry(m.channel.topic.clone()).or_insert(0) += 1;
        }
    }
    Ok(FileInfo {
        size_bytes,
        finished,
        topic_counts,
    })
}
