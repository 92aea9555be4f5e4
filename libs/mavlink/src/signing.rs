//! MAVLink 2 message signing (<https://mavlink.io/en/guide/message_signing.html>), without I/O:
//! the caller passes the time, so the rules are testable.
//!
//! A signed frame carries a 13-byte trailer: link id (1 byte), timestamp (6 bytes, little
//! endian, units of 10 µs since 2015-01-01 00:00:00 UTC) and signature (6 bytes): the first 6
//! bytes of SHA-256(secret key ‖ the frame from its start byte up to and including the link id
//! and timestamp). A frame is accepted when its signature matches and its timestamp is newer than
//! the last one accepted from the same stream (link id, system id, component id); the first frame
//! of a stream is refused when it is more than a minute older than the local timestamp (the
//! highest of our clock, our last sent timestamp and any accepted timestamp). So a frame recorded
//! off the air and sent again (a replay) is refused like a forged one.

use std::collections::HashMap;
use std::time::{SystemTime, UNIX_EPOCH};

use mavlink::dialects::common::MavMessage;
use mavlink::MavHeader;
use sha2::{Digest, Sha256};

use crate::signing_key::SigningKey;

/// 2015-01-01 00:00:00 UTC in Unix seconds: the epoch of signing timestamps.
const SIGNING_EPOCH_UNIX_S: u64 = 1_420_070_400;
/// Signing timestamps count 10 µs units.
const TIMESTAMP_UNIT_NS: u128 = 10_000;
/// A new stream's first timestamp may lag the local timestamp by at most one minute (spec).
const NEW_STREAM_MAX_LAG: u64 = 60 * 100_000;
/// MAVLink 2 start byte.
const STX_V2: u8 = mavlink::MAV_STX_V2;
/// Incompatibility flag: signed frame.
const IFLAG_SIGNED: u8 = 0x01;
/// Header length including the start byte.
const HEADER_LEN: usize = 10;
/// Checksum length.
const CRC_LEN: usize = 2;
/// Link id + timestamp + signature.
const TRAILER_LEN: usize = 13;
/// Bytes of the signature value.
const SIGNATURE_LEN: usize = 6;
/// Bytes of the timestamp.
const TIMESTAMP_LEN: usize = 6;

/// The signing timestamp of a wall-clock time: 10 µs units since 2015-01-01 (0 before).
pub fn signing_timestamp(now: SystemTime) -> u64 {
    let since_unix = now.duration_since(UNIX_EPOCH).unwrap_or_default();
    let since_epoch =
        since_unix.saturating_sub(std::time::Duration::from_secs(SIGNING_EPOCH_UNIX_S));
    (since_epoch.as_nanos() / TIMESTAMP_UNIT_NS) as u64
}

/// Why a received frame was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// Not signed (also every MAVLink 1 frame, which cannot be).
    Unsigned,
    /// Signed, but not with our key (or altered on the way).
    BadSignature,
    /// Correctly signed but not newer than the stream's last frame, or a new stream more than a
    /// minute behind: a replay.
    OldTimestamp,
}

impl Refusal {
    /// Every cause, in the order of [`Refusal::index`].
    pub const ALL: [Refusal; 3] = [
        Refusal::Unsigned,
        Refusal::BadSignature,
        Refusal::OldTimestamp,
    ];

    /// Position in [`Refusal::ALL`], for per-cause counters.
    pub fn index(self) -> usize {
        self as usize
    }

    /// What the cause means, for logs.
    pub fn describe(self) -> &'static str {
        match self {
            Refusal::Unsigned => "unsigned frame",
            Refusal::BadSignature => "wrong signature (another key, or altered)",
            Refusal::OldTimestamp => "signing timestamp not newer than before (replayed)",
        }
    }
}

/// Signing state of one link: signs what we send and checks what we receive.
#[derive(Debug)]
pub struct Signing {
    key: SigningKey,
    link_id: u8,
    /// The local timestamp: the highest of the clock, our last sent and any accepted timestamp.
    timestamp: u64,
    /// Last accepted timestamp per (link id, system id, component id). Only frames signed with
    /// the key add entries, so a sender without the key cannot grow it.
    streams: HashMap<(u8, u8, u8), u64>,
}

impl Signing {
    /// Signing with `key`, our frames sent with `link_id`.
    pub fn new(key: SigningKey, link_id: u8) -> Signing {
        Signing {
            key,
            link_id,
            timestamp: 0,
            streams: HashMap::new(),
        }
    }

    /// The signature of a frame whose bytes up to the signature are `signed_part`.
    fn signature(&self, signed_part: &[u8]) -> [u8; SIGNATURE_LEN] {
        let mut h = Sha256::new();
        h.update(self.key.bytes());
        h.update(signed_part);
        let digest = h.finalize();
        let mut sig = [0u8; SIGNATURE_LEN];
        sig.copy_from_slice(&digest[..SIGNATURE_LEN]);
        sig
    }

    /// Encodes `msg` as one signed MAVLink 2 frame at signing time `now` (see
    /// [`signing_timestamp`]). Timestamps strictly increase from frame to frame, whatever the
    /// clock does. System ids are sent as 8 bits, as in [`crate::encode_v2`].
    pub fn encode(&mut self, header: MavHeader, msg: &MavMessage, now: u64) -> Vec<u8> {
        let header = MavHeader {
            system_id: header.system_id & u32::from(u8::MAX),
            ..header
        };
        let mut raw = mavlink::MAVLinkV2MessageRaw::new();
        raw.serialize_message_for_signing(header, msg);
        self.timestamp = self.timestamp.saturating_add(1).max(now);
        *raw.signature_link_id_mut() = self.link_id;
        raw.signature_timestamp_bytes_mut()
            .copy_from_slice(&self.timestamp.to_le_bytes()[..TIMESTAMP_LEN]);
        let mut frame = raw.raw_bytes().to_vec();
        let sig_at = frame.len() - SIGNATURE_LEN;
        let sig = self.signature(&frame[..sig_at]);
        frame[sig_at..].copy_from_slice(&sig);
        frame
    }

    /// Checks one complete received frame (start byte to the end of its signature) at signing
    /// time `now`; on success, the stream's timestamp advances.
    pub fn verify(&mut self, frame: &[u8], now: u64) -> Result<(), Refusal> {
        self.timestamp = self.timestamp.max(now);
        if frame.len() < HEADER_LEN || frame[0] != STX_V2 || frame[2] & IFLAG_SIGNED == 0 {
            return Err(Refusal::Unsigned);
        }
        let trailer_at = HEADER_LEN + usize::from(frame[1]) + CRC_LEN;
        if frame.len() != trailer_at + TRAILER_LEN {
            // The parser sizes frames from the same header, so this is not a frame it passes.
            return Err(Refusal::BadSignature);
        }
        let sig_at = frame.len() - SIGNATURE_LEN;
        if self.signature(&frame[..sig_at]) != frame[sig_at..] {
            return Err(Refusal::BadSignature);
        }
        let link_id = frame[trailer_at];
        let mut ts = [0u8; 8];
        ts[..TIMESTAMP_LEN].copy_from_slice(&frame[trailer_at + 1..sig_at]);
        let ts = u64::from_le_bytes(ts);
        let stream = (link_id, frame[5], frame[6]);
        let fresh = match self.streams.get(&stream) {
            Some(&last) => ts > last,
            None => ts.saturating_add(NEW_STREAM_MAX_LAG) >= self.timestamp,
        };
        if !fresh {
            return Err(Refusal::OldTimestamp);
        }
        self.streams.insert(stream, ts);
        self.timestamp = self.timestamp.max(ts);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::*;
    use crate::{encode_v2, FrameParser};
    use mavlink::Message;

    const NOW: u64 = 374_000_000_000; // 2026, in 10 µs units

    fn key(p: &str) -> SigningKey {
        SigningKey::from_passphrase(p)
    }

    #[test]
    fn timestamp_epoch_and_unit() {
        let epoch = UNIX_EPOCH + std::time::Duration::from_secs(SIGNING_EPOCH_UNIX_S);
        assert_eq!(signing_timestamp(epoch), 0);
        assert_eq!(
            signing_timestamp(epoch + std::time::Duration::from_micros(25)),
            2
        );
        assert_eq!(signing_timestamp(UNIX_EPOCH), 0);
    }

    /// The signature agrees with the mavlink crate's own implementation of the spec.
    #[test]
    fn signature_matches_the_mavlink_crate() {
        let mut s = Signing::new(key("k"), 7);
        for (h, m) in sample_messages() {
            let frame = s.encode(h, &m, NOW);
            let mut buf = [0u8; mavlink::consts::MAX_FRAME_SIZE];
            buf[..frame.len()].copy_from_slice(&frame);
            let raw = mavlink::MAVLinkV2MessageRaw::from_bytes_unparsed(buf);
            let mut sig = [0u8; 6];
            raw.calculate_signature(key("k").bytes(), &mut sig);
            assert_eq!(&frame[frame.len() - 6..], &sig);
            assert_eq!(raw.signature_link_id(), 7);
            // And the parser decodes it as the message sent.
            assert_eq!(FrameParser::new().push(&frame), vec![(h, m)]);
        }
    }

    #[test]
    fn sent_timestamps_strictly_increase_even_when_the_clock_steps_back() {
        let mut s = Signing::new(key("k"), 0);
        let (h, m) = sample_messages()[0].clone();
        let ts = |f: &[u8]| {
            let at = f.len() - 12;
            let mut b = [0u8; 8];
            b[..6].copy_from_slice(&f[at..at + 6]);
            u64::from_le_bytes(b)
        };
        let a = ts(&s.encode(h, &m, NOW));
        let b = ts(&s.encode(h, &m, NOW));
        let c = ts(&s.encode(h, &m, NOW - 1_000_000));
        let d = ts(&s.encode(h, &m, NOW + 500));
        assert_eq!((a, b, c, d), (NOW, NOW + 1, NOW + 2, NOW + 500));
    }

    #[test]
    fn verify_accepts_the_key_and_refuses_the_rest() {
        let (h, m) = sample_messages()[1].clone();
        let mut ours = Signing::new(key("shared"), 0);
        let mut theirs = Signing::new(key("shared"), 3);
        let mut stranger = Signing::new(key("guess"), 3);
        let good = theirs.encode(h, &m, NOW);
        assert_eq!(ours.verify(&good, NOW), Ok(()));
        // Replayed as is.
        assert_eq!(ours.verify(&good, NOW), Err(Refusal::OldTimestamp));
        assert_eq!(ours.verify(&encode_v2(h, &m), NOW), Err(Refusal::Unsigned));
        assert_eq!(
            ours.verify(&stranger.encode(h, &m, NOW + 10), NOW),
            Err(Refusal::BadSignature)
        );
        // A flipped payload bit (checksum fixed up by a forger) breaks the signature.
        let mut forged = theirs.encode(h, &m, NOW + 20);
        forged[12] ^= 1;
        let crc_at = forged.len() - 13 - 2;
        let extra = MavMessage::extra_crc(m.message_id());
        let crc = mavlink::calculate_crc(&forged[1..crc_at], extra);
        forged[crc_at..crc_at + 2].copy_from_slice(&crc.to_le_bytes());
        assert_eq!(ours.verify(&forged, NOW), Err(Refusal::BadSignature));
        // A forger moving the timestamp forward breaks it too.
        let mut moved = theirs.encode(h, &m, NOW + 30);
        let ts_at = moved.len() - 12;
        moved[ts_at + 3] ^= 1;
        assert_eq!(ours.verify(&moved, NOW), Err(Refusal::BadSignature));
        // Newer frames of the stream pass.
        assert_eq!(ours.verify(&theirs.encode(h, &m, NOW + 40), NOW), Ok(()));
        // MAVLink 1 cannot be signed.
        let mut v1 = Vec::new();
        mavlink::write_v1_msg(&mut v1, h, &m).unwrap();
        assert_eq!(ours.verify(&v1, NOW), Err(Refusal::Unsigned));
        assert_eq!(ours.verify(&[], NOW), Err(Refusal::Unsigned));
    }

    #[test]
    fn a_new_stream_more_than_a_minute_behind_is_refused() {
        let (h, m) = sample_messages()[1].clone();
        let mut ours = Signing::new(key("shared"), 0);
        let mut old = Signing::new(key("shared"), 1);
        let late = old.encode(h, &m, NOW - NEW_STREAM_MAX_LAG - 1);
        assert_eq!(ours.verify(&late, NOW), Err(Refusal::OldTimestamp));
        let mut recent = Signing::new(key("shared"), 2);
        let ok = recent.encode(h, &m, NOW - NEW_STREAM_MAX_LAG);
        assert_eq!(ours.verify(&ok, NOW), Ok(()));
        // Streams are told apart by link id and sender.
        let mut other_link = Signing::new(key("shared"), 9);
        assert_eq!(ours.verify(&other_link.encode(h, &m, NOW), NOW), Ok(()));
    }

    #[test]
    fn mutated_signed_frames_never_pass_or_panic() {
        let mut rng = Rng::new(45);
        let mut theirs = Signing::new(key("shared"), 1);
        let mut ours = Signing::new(key("shared"), 0);
        let frames = sample_messages();
        let mut t = NOW;
        for _ in 0..20_000 {
            let (h, m) = &frames[rng.below(frames.len())];
            t += 1;
            let mut f = theirs.encode(*h, m, t);
            let i = rng.below(f.len());
            f[i] ^= 1 + rng.below(255) as u8;
            if rng.below(4) == 0 {
                f.truncate(rng.below(f.len()));
            }
            assert!(ours.verify(&f, NOW).is_err());
        }
        assert!(ours.streams.is_empty());
    }
}
