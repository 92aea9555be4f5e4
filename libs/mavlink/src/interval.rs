//! Asking the autopilot for the messages we need, at the rates we need them.
//!
//! ArduPilot sends a link only what its stream-rate parameters (SRn_*) or a client asked for; on
//! a fresh SITL or a flight controller with SRn_* at 0 that is HEARTBEAT and STATUSTEXT alone,
//! and after a reboot any rate a client set is gone. So the companion asks for each message it
//! needs with MAV_CMD_SET_MESSAGE_INTERVAL (param1 message id, param2 interval µs), and asks
//! again whenever that message has not been heard for a while — after a reboot, a lost request,
//! or an autopilot that was not there yet. A rule that needs no knowledge of why the stream
//! stopped.
//!
//! Sans-IO: [`StreamRequests::seen`] for every message received, [`StreamRequests::poll`] on
//! every turn, send what it returns; all times are the caller's clock (ns).

use mavlink::dialects::common::{MavCmd, MavMessage, COMMAND_LONG_DATA};
use mavlink::Message;

/// One message wanted at a rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WantedStream {
    /// MAVLink message id (e.g. 30 for ATTITUDE).
    pub message_id: u32,
    /// Rate, Hz (> 0).
    pub rate_hz: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry {
    wanted: WantedStream,
    last_seen_ns: Option<u64>,
    last_request_ns: Option<u64>,
}

/// The requests for a set of streams (see the [module](self) documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct StreamRequests {
    entries: Vec<Entry>,
    /// A stream not heard for this long is asked for again.
    missing_after_ns: u64,
    /// Between two requests for the same stream.
    retry_ns: u64,
}

impl StreamRequests {
    /// Requests for `wanted`; a stream silent for `missing_after_ns` is asked for, at most once
    /// per `retry_ns`.
    pub fn new(wanted: &[WantedStream], missing_after_ns: u64, retry_ns: u64) -> Self {
        StreamRequests {
            entries: wanted
                .iter()
                .map(|&w| Entry {
                    wanted: w,
                    last_seen_ns: None,
                    last_request_ns: None,
                })
                .collect(),
            missing_after_ns,
            retry_ns,
        }
    }

    /// A message from the autopilot arrived at `now_ns`.
    pub fn seen(&mut self, now_ns: u64, msg: &MavMessage) {
        let id = msg.message_id();
        for e in self
            .entries
            .iter_mut()
            .filter(|e| e.wanted.message_id == id)
        {
            e.last_seen_ns = Some(now_ns);
        }
    }

    /// The requests due at `now_ns` for the autopilot `target` (none while it is unknown).
    pub fn poll(&mut self, now_ns: u64, target: Option<(u8, u8)>) -> Vec<MavMessage> {
        let Some(target) = target else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for e in &mut self.entries {
            let missing = e
                .last_seen_ns
                .is_none_or(|t| now_ns.saturating_sub(t) > self.missing_after_ns);
            let may_retry = e
                .last_request_ns
                .is_none_or(|t| now_ns.saturating_sub(t) >= self.retry_ns);
            if missing && may_retry {
                e.last_request_ns = Some(now_ns);
                out.push(set_message_interval(target, e.wanted));
            }
        }
        out
    }
}

/// MAV_CMD_SET_MESSAGE_INTERVAL for `stream` to `target` = (system, component).
pub fn set_message_interval(target: (u8, u8), stream: WantedStream) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: stream.message_id as f32,
        param2: (1e6 / stream.rate_hz) as f32,
        param3: 0.0,
        param4: 0.0,
        param5: 0.0,
        param6: 0.0,
        param7: 0.0,
        command: MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
        target_system: target.0,
        target_component: target.1,
        confirmation: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::ATTITUDE_DATA;

    const MS: u64 = 1_000_000;

    fn attitude() -> MavMessage {
        MavMessage::ATTITUDE(ATTITUDE_DATA::default())
    }

    fn requested_ids(msgs: &[MavMessage]) -> Vec<u32> {
        msgs.iter()
            .map(|m| match m {
                MavMessage::COMMAND_LONG(c) => {
                    assert_eq!(c.command, MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL);
                    c.param1 as u32
                }
                other => panic!("{other:?}"),
            })
            .collect()
    }

    #[test]
    fn asks_for_missing_streams_again_until_they_flow() {
        let wanted = [
            WantedStream {
                message_id: 30,
                rate_hz: 50.0,
            },
            WantedStream {
                message_id: 32,
                rate_hz: 25.0,
            },
        ];
        let mut r = StreamRequests::new(&wanted, 1000 * MS, 1000 * MS);
        assert!(r.poll(0, None).is_empty(), "nobody to ask yet");
        let first = r.poll(10 * MS, Some((1, 1)));
        assert_eq!(requested_ids(&first), vec![30, 32]);
        let MavMessage::COMMAND_LONG(c) = &first[0] else {
            unreachable!()
        };
        assert_eq!(
            (c.param2, c.target_system, c.target_component),
            (20_000.0, 1, 1)
        );
        assert!(
            r.poll(500 * MS, Some((1, 1))).is_empty(),
            "not before the retry"
        );
        // ATTITUDE flows, LOCAL_POSITION_NED does not: only the second is asked for again.
        r.seen(900 * MS, &attitude());
        assert_eq!(requested_ids(&r.poll(1100 * MS, Some((1, 1)))), vec![32]);
        // The autopilot rebooted: ATTITUDE stops and is asked for once it has been missing.
        r.seen(1500 * MS, &attitude());
        assert_eq!(requested_ids(&r.poll(2400 * MS, Some((1, 1)))), vec![32]);
        assert_eq!(requested_ids(&r.poll(2600 * MS, Some((1, 1)))), vec![30]);
    }

    /// The wire values: MAV_CMD_SET_MESSAGE_INTERVAL is command 511 with the id in param1 and
    /// the interval in µs in param2 (MAVLink common.xml).
    #[test]
    fn command_number_and_units() {
        let MavMessage::COMMAND_LONG(c) = set_message_interval(
            (1, 1),
            WantedStream {
                message_id: 30,
                rate_hz: 4.0,
            },
        ) else {
            unreachable!()
        };
        assert_eq!(c.command as u32, 511);
        assert_eq!((c.param1, c.param2), (30.0, 250_000.0));
    }
}
